"""The zoo's Blender-named classes against Blender's own texture nodes (power spectrum and histogram).

Blender's nodes are evaluated through Geometry Nodes on the zoo's pixel grid
(1 unit = 128 px, the node's Scale applied to that), at random offsets; both
sides go through the zoo's per-sample normalisation.  Compared: the power-
weighted mean radial frequency, the total-variation distance of the normalised
radially averaged power spectra, and of the 32-bin value histograms.
"""
import numpy as np
import pytest

torch = pytest.importorskip("torch")
bpy = pytest.importorskip("bpy")

from omninoise.training import noise_ops as ops  # noqa: E402
from omninoise.training import zoo  # noqa: E402
from omninoise.training.evaluate import radial_psd  # noqa: E402
from omninoise.blender_addon.field_eval import evaluate_field  # noqa: E402

S = 128


def blender_images(node_type, settings, inputs, count=4):
    rng = np.random.default_rng(0)
    c = (np.arange(S) + 0.5) / 128.0
    y, x = np.meshgrid(c, c, indexing="ij")
    out = []
    for _ in range(count):
        o = rng.uniform(0, 50, 3)
        pts = np.stack([x + o[0], y + o[1], np.full_like(x, o[2])], -1).reshape(-1, 3)

        def build(tree, pos):
            n = tree.nodes.new(node_type)
            for k, v in settings.items():
                setattr(n, k, v)
            for k, v in inputs.items():
                n.inputs[k].default_value = v
            tree.links.new(pos, n.inputs["Vector"])
            return n.outputs[0]

        out.append(evaluate_field(pts, build).reshape(S, S))
    return np.stack(out)


def stats(imgs):
    imgs = ops.normalise(torch.from_numpy(np.asarray(imgs, np.float32))).numpy()
    p = radial_psd(imgs)
    p = p / p.sum()
    h = np.mean([np.histogram(i, 32, (0, 1))[0] / i.size for i in imgs], 0)
    return p, h, float((p * np.arange(1, len(p) + 1)).sum())


def distances(a, b):
    pa, ha, ca = stats(a)
    pb, hb, cb = stats(b)
    return abs(cb / ca - 1.0), 0.5 * np.abs(pa - pb).sum(), 0.5 * np.abs(ha - hb).sum()


CASES = [
    ("noise", "ShaderNodeTexNoise", {}, dict(Scale=3.0, Detail=2.0, Roughness=0.5, Distortion=0.0)),
    ("noise", "ShaderNodeTexNoise", {}, dict(Scale=8.0, Detail=4.0, Roughness=0.6, Distortion=0.0)),
    ("voronoi_f1", "ShaderNodeTexVoronoi", dict(voronoi_dimensions="2D"), dict(Scale=3.0, Randomness=1.0)),
    ("voronoi_f1", "ShaderNodeTexVoronoi", dict(voronoi_dimensions="2D"), dict(Scale=10.0, Randomness=0.6)),
    ("wave_bands", "ShaderNodeTexWave", {}, dict(Scale=2.0, Distortion=0.0, Detail=2.0)),
    ("wave_bands", "ShaderNodeTexWave", {}, dict(Scale=2.0, Distortion=3.0, Detail=2.0)),
    ("gabor_texture", "ShaderNodeTexGabor", {}, dict(Scale=4.0, Frequency=2.0, Anisotropy=1.0, Orientation=0.6)),
    ("gabor_texture", "ShaderNodeTexGabor", {}, dict(Scale=3.0, Frequency=3.0, Anisotropy=0.0, Orientation=0.6)),
]


@pytest.mark.parametrize("name, node, settings, inputs", CASES)
def test_blender_named_classes_match_the_nodes(name, node, settings, inputs):
    from omninoise.blender_addon.compat import has_gabor_node

    if node == "ShaderNodeTexGabor" and not has_gabor_node():
        pytest.skip("Blender's Gabor Texture node needs Blender 4.3")
    ours = zoo.generate(name, inputs, torch.arange(4), S).numpy()
    theirs = blender_images(node, settings, inputs)
    centroid, psd, hist = distances(theirs, ours)
    assert centroid < 0.2 and psd < 0.25 and hist < 0.15, (centroid, psd, hist)


def test_the_comparison_tells_classes_apart():
    """A negative control: the zoo's Noise against Blender's Voronoi fails the same thresholds."""
    ours = zoo.generate("noise", dict(Scale=3.0, Detail=2.0, Roughness=0.5, Distortion=0.0), torch.arange(4), S).numpy()
    theirs = blender_images("ShaderNodeTexVoronoi", dict(voronoi_dimensions="2D"), dict(Scale=8.0, Randomness=1.0))
    centroid, psd, hist = distances(theirs, ours)
    assert not (centroid < 0.2 and psd < 0.25 and hist < 0.15)
