"""The neural-noise training zoo: classes, parameters, Halton sets, conditioning, CLI."""
import json
import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from omninoise.cli.main import main  # noqa: E402
from omninoise.training import zoo  # noqa: E402
from omninoise.training.evaluate import gradient_direction  # noqa: E402


def centroid(img: np.ndarray) -> float:
    """Power-weighted mean radial frequency, cycles per pixel."""
    F = np.abs(np.fft.fft2(img - img.mean())) ** 2
    f = np.fft.fftfreq(img.shape[0])
    r = np.hypot(*np.meshgrid(f, f, indexing="ij"))
    return float((F * r).sum() / F.sum())


def test_at_least_18_classes_with_documented_params():
    assert len(zoo.CLASS_NAMES) >= 18
    for c in zoo.CLASSES.values():
        assert 1 <= len(c.params) <= 5 and c.doc
        for p in c.params:
            assert p.hi > p.lo and isinstance(p.unit, str)
    assert {"noise", "voronoi_f1", "wave_bands", "gabor", "phasor", "wave_bandpass", "wave_cellular"} <= set(zoo.CLASS_NAMES)
    assert len(set(zoo.PARAM_NAMES)) == len(zoo.PARAM_NAMES)


@pytest.mark.parametrize("name", zoo.CLASS_NAMES)
def test_every_class_is_deterministic_and_seeded(name):
    p = zoo.sample_params(name, np.array([3, 3]))
    a = zoo.generate(name, p, torch.tensor([11, 12]), 64)
    b = zoo.generate(name, p, torch.tensor([11, 12]), 64)
    assert a.shape == (2, 64, 64) and a.dtype == torch.float32
    assert torch.isfinite(a).all() and a.min() >= 0 and a.max() <= 1
    assert torch.equal(a, b)
    assert (a[0] - a[1]).abs().mean() > 0.02  # another seed, another patch
    assert a.std(dim=(1, 2)).min() > 0.05


@pytest.mark.parametrize("name, key, lo, hi", [
    ("cells_f1", "scale", 5, 18), ("perlin", "scale", 3, 14), ("damascus", "frequency", 4, 18),
    ("gabor", "frequency", 0.025, 0.075), ("noise", "Scale", 2, 9), ("wave_bandpass", "frequency", 3, 11),
    ("phasor", "frequency", 5, 15), ("voronoi_f1", "Scale", 3, 14),
])
def test_scale_parameters_move_the_spectrum(name, key, lo, hi):
    base = zoo.default_params(name)
    if name == "gabor":
        base["bandwidth"] = 0.02
    cents = []
    for v in (lo, hi):
        p = dict(base, **{key: v})
        imgs = zoo.generate(name, p, torch.arange(4), 128).numpy()
        cents.append(np.mean([centroid(i) for i in imgs]))
    assert cents[1] > 1.3 * cents[0], cents


def test_features_keep_their_pixel_size_at_any_size():
    p = zoo.default_params("cells_f1")
    small = np.mean([centroid(i) for i in zoo.generate("cells_f1", p, torch.arange(4), 64).numpy()])
    large = np.mean([centroid(i) for i in zoo.generate("cells_f1", p, torch.arange(4), 256).numpy()])
    assert abs(large / small - 1) < 0.25


def test_halton_and_condition_vectors():
    h = zoo.halton(4, 2)
    np.testing.assert_allclose(h[:, 0], [0.5, 0.25, 0.75, 0.125])
    np.testing.assert_allclose(h[:, 1], [1 / 3, 2 / 3, 1 / 9, 4 / 9])
    pts = zoo.halton(256, 3)
    counts = np.histogramdd(pts, bins=(4, 4, 4))[0]
    assert counts.min() >= 2  # low discrepancy: every one of 64 boxes is visited
    p = zoo.sample_params("clouds", np.arange(8))
    assert set(np.unique(p["detail"])) <= set(range(2, 9))
    c = zoo.condition_vector("clouds", p)
    assert c.shape == (8, len(zoo.PARAM_NAMES)) and c.min() >= 0 and c.max() <= 1
    used = [zoo.PARAM_NAMES.index(n) for n in ("scale", "roughness", "detail")]
    assert torch.count_nonzero(c[:, [i for i in range(c.shape[1]) if i not in used]]) == 0
    np.testing.assert_allclose(c[:, zoo.PARAM_NAMES.index("roughness")], (p["roughness"] - 0.3) / 0.5, atol=1e-6)


def test_sampler_batches():
    s = zoo.ZooSampler(32, classes=("perlin", "spots", "gabor"), rng=np.random.default_rng(4))
    imgs, ids, cond = s.batch(6)
    assert imgs.shape == (6, 1, 32, 32) and ids.shape == (6,) and cond.shape == (6, len(zoo.PARAM_NAMES))
    assert set(ids.tolist()) <= {zoo.CLASS_NAMES.index(n) for n in ("perlin", "spots", "gabor")}
    again = zoo.ZooSampler(32, classes=("perlin", "spots", "gabor"), rng=np.random.default_rng(4)).batch(6)
    assert torch.equal(imgs, again[0]) and torch.equal(cond, again[2])


def test_sampler_class_weights():
    classes = ("perlin", "spots", "gabor")
    np.testing.assert_allclose(zoo.class_probabilities(classes, {"gabor": 2}), [0.25, 0.25, 0.5])
    s = zoo.ZooSampler(16, classes=classes, rng=np.random.default_rng(5), class_weights={"perlin": 6})
    _, ids, _ = s.batch(160)
    share = float((ids == zoo.CLASS_NAMES.index("perlin")).float().mean())
    assert 0.62 < share < 0.88  # 0.75 expected; equal weights give 1/3
    assert zoo.ZooSampler(16, classes=classes).p is None  # no weights: the draw of older runs
    with pytest.raises(ValueError, match="'clouds', which is not among"):
        zoo.class_probabilities(classes, {"clouds": 2})
    with pytest.raises(ValueError, match=r"class_weights\['gabor'\] must be a positive number"):
        zoo.class_probabilities(classes, {"gabor": 0})


def test_config_class_weights():
    from omninoise.training.config import TrainConfig

    cfg = TrainConfig.from_dict({"class_weights": {"fibers": 2.0}})
    assert cfg.class_weights == {"fibers": 2.0}
    with pytest.raises(ValueError, match="not among the trained classes"):
        TrainConfig.from_dict({"classes": ["perlin"], "class_weights": {"fibers": 2.0}})
    with pytest.raises(ValueError, match="must map class names"):
        TrainConfig.from_dict({"class_weights": [2.0]})


def test_zoo_cli(tmp_path, capsys):
    out = str(tmp_path / "z.npy")
    assert main(["zoo", "--noise", "spots", "--param", "coverage=0.7", "--size", "48", "--seed", "3", "-o", out]) == 0
    ref = zoo.generate("spots", dict(zoo.default_params("spots"), coverage=0.7), [3], 48)[0].numpy()
    np.testing.assert_array_equal(np.load(out), ref)
    assert main(["zoo", "--list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["gabor"]["params"][0] == dict(name="frequency", min=0.02, max=0.08, unit="cycles per px", integer=False)
    for args, msg in [(["--noise", "lava"], "unknown noise class 'lava'"),
                      (["--noise", "spots", "--param", "coverage=2"], "outside [0.2, 0.8]"),
                      (["--noise", "spots", "--param", "size=2"], "no parameter 'size'")]:
        assert main(["zoo", *args, "-o", out]) == 2
        assert msg in capsys.readouterr().err


@pytest.mark.parametrize("name, extra", [("fibers", {"scale": 12.0, "length": 6.0}),
                                         ("phasor", {"frequency": 8.0, "spread": 0.1})])
def test_orientation_is_a_parameter_every_seed_follows(name, extra):
    """Fibres and phasor waves once took their direction from the seed: a variable hidden from the model that a
    whole image shares. Now the parameter sets it, for every seed, so the conditioning carries it."""
    assert zoo.CLASSES[name].param("orientation").hi == pytest.approx(np.pi)
    for deg in (0.0, 30.0, 90.0, 135.0):
        imgs = zoo.generate(name, dict(extra, orientation=np.radians(deg)), torch.arange(3) + 40, 128).numpy()
        got = gradient_direction(imgs)
        err = np.abs((got - deg + 90.0) % 180.0 - 90.0)
        assert err.max() < 8.0, (name, deg, got)  # a random direction: uniform over ±90
    c = zoo.condition_vector(name, dict(extra, orientation=np.pi / 4))
    assert c[0, zoo.PARAM_NAMES.index("orientation")] == pytest.approx(0.25)


def test_parameter_slots_and_class_ids_are_append_only():
    """A trained model's conditioning slots are fixed: the zoo's names start with every shipped model's."""
    from omninoise.backend.onnx_models import load_model_json
    from omninoise.backend.paths import neural_model

    doc = load_model_json(neural_model(), "neural_noise.json")
    assert zoo.PARAM_NAMES[: len(doc["params"])] == tuple(doc["params"])
    assert zoo.CLASS_NAMES[: len(doc["classes"])] == tuple(doc["classes"])


def test_galvanic_has_no_nan_where_its_ridge_noise_is_strongest():
    """The sample that turned a 128² GPU stage's weights into NaN (seed and parameters from the replayed data
    stream, step 980): |fbm| > 0.5 made the ridge negative and its fractional power NaN."""
    p = {"scale": torch.tensor([4.338623046875]), "contrast": torch.tensor([0.5051059289742417])}
    img = zoo.generate("galvanic", p, torch.tensor([110020244]), 128)
    assert torch.isfinite(img).all() and float(img.min()) >= 0.0 and float(img.max()) <= 1.0


def test_gabor_orientation_is_conditioned_modulo_its_half_turn_period():
    """gabor's images are the same at θ and θ + π (its kernel is a cosine): the conditioning gives both the same
    input, turning once per π like fibres and phasor, and the exported description carries the period."""
    p = {"frequency": torch.tensor([0.05, 0.05]), "bandwidth": torch.tensor([0.1, 0.1]),
         "orientation": torch.tensor([0.7, 0.7 + math.pi])}
    img = zoo.generate("gabor", p, torch.tensor([5, 5]), 64)
    assert torch.allclose(img[0], img[1], atol=1e-5)
    c = zoo.condition_vector("gabor", p)[:, zoo.PARAM_NAMES.index("orientation")]
    assert torch.allclose(c, torch.tensor([0.7 / math.pi] * 2), atol=1e-6)
    spec = {q["name"]: q for q in zoo.describe()["gabor"]["params"]}
    assert spec["orientation"]["period"] == pytest.approx(math.pi) and "period" not in spec["frequency"]
    fib = zoo.condition_vector("fibers", {**zoo.default_params("fibers"), "orientation": torch.tensor([2.0])})
    assert float(fib[0, zoo.PARAM_NAMES.index("orientation")]) == pytest.approx(2.0 / math.pi, abs=1e-6)
