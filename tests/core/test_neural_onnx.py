"""The neural noise runtime without torch: conditioning grids, sampling, tiles, the CLI, job files and animation,
on the committed tiny model (tests/data/tiny_neural, made by tools/make_tiny_model.py) and the shipped one."""
import json
import os

import numpy as np
import pytest

from omninoise.cli.main import main
from omninoise.backend.errors import SettingError
from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.neural.sampler import ddim_sample, initial_noise

TINY_MODEL = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "tiny_neural")


KEYS = """
[[key]]
frame = 1
noise = "perlin"
params = {scale = 4}
seed = 2

[[key]]
frame = 7
noise = "cells_f1"
seed = 9
"""


@pytest.fixture(scope="module")
def tiny():
    """The committed tiny model (three classes, 16² crops, 3 training steps): for properties, not pictures."""
    return TINY_MODEL


def test_tiled_generation(tiny):
    """Tiles: one tile covering the image is the one-piece path; smaller tiles give the same statistics,
    stay seeded, and tileable output still wraps."""
    out = tiny
    model = NeuralNoiseModel(str(out))
    cond = C.uniform(model, ("cells_f1", {}), 96, 128)
    whole = generate(model, cond, seed=2, steps=3, tile=0)
    np.testing.assert_array_equal(whole, generate(model, cond, seed=2, steps=3, tile=128))
    tiled = generate(model, cond, seed=2, steps=3, tile=64, overlap=16)
    np.testing.assert_array_equal(tiled, generate(model, cond, seed=2, steps=3, tile=64, overlap=16))
    assert abs(tiled.mean() - whole.mean()) < 0.05 and abs(tiled.std() - whole.std()) < 0.05
    assert np.corrcoef(tiled.ravel(), whole.ravel())[0, 1] > 0.9
    wrap = generate(model, C.uniform(model, ("perlin", {}), 64, 96), seed=4, steps=3, tileable=True, tile=32,
                    overlap=8)
    inner_x, inner_y = np.abs(np.diff(wrap, axis=1)).mean(), np.abs(np.diff(wrap, axis=0)).mean()
    assert np.abs(wrap[:, 0] - wrap[:, -1]).mean() < 1.5 * inner_x
    assert np.abs(wrap[0] - wrap[-1]).mean() < 1.5 * inner_y
    for tile, overlap, msg in ((60, 8, "multiple of 8"), (16, 0, "at least 32"), (64, 40, "too small for their 40 px overlap")):
        with pytest.raises(SettingError, match=msg):
            generate(model, cond, steps=2, tile=tile, overlap=overlap)


def test_the_default_step_noise_is_seeded_and_shared_by_tiles(tiny):
    """The default sampler's step noise (η = 0.3) comes from the seed: the same seed gives the same bytes, the
    default equals an explicit η = 0.3 and differs from η = 0, and a tile covering the image is the one piece."""
    model = NeuralNoiseModel(str(tiny))
    cond = C.uniform(model, ("perlin", {}), 64, 64)
    a = generate(model, cond, seed=5, steps=4)
    np.testing.assert_array_equal(a, generate(model, cond, seed=5, steps=4))
    np.testing.assert_array_equal(a, generate(model, cond, seed=5, steps=4, eta=0.3))
    np.testing.assert_array_equal(a, generate(model, cond, seed=5, steps=4, tile=64, overlap=16))
    assert np.abs(a - generate(model, cond, seed=5, steps=4, eta=0.0)).max() > 1e-3
    assert np.abs(a - generate(model, cond, seed=6, steps=4)).max() > 1e-3


def test_tileable_sampling_wraps(tiny):
    out = tiny
    model = NeuralNoiseModel(str(out))
    cond = C.uniform(model, ("cells_f1", {}), 32, 32)[None]
    xT = initial_noise(2, (1, 1, 32, 32))
    a = ddim_sample(model.eps_fn(True), np.roll(xT, (8, 16), (2, 3)), cond, steps=3)
    b = np.roll(ddim_sample(model.eps_fn(True), xT, cond, steps=3), (8, 16), (2, 3))
    np.testing.assert_allclose(a, b, atol=1e-4)  # the image lives on a torus: it tiles without a seam


def test_conditioning_grids(tiny):
    out = tiny
    model = NeuralNoiseModel(str(out))
    E, P = model.embedding.shape[1], len(model.params)
    a, b = ("spots", {"coverage": 0.3}), ("perlin", {"scale": 12})
    ua, ub = C.uniform(model, a, 8, 8), C.uniform(model, b, 8, 8)
    np.testing.assert_allclose(C.blend(model, a, b, np.zeros((8, 8))), ua, atol=1e-6)
    np.testing.assert_allclose(C.blend(model, a, b, np.ones((8, 8))), ub, atol=1e-6)
    mid = C.blend(model, a, b, np.full((8, 8), 0.5))[:E, 0, 0]
    ea, eb = model.embedding[model.class_id("spots")], model.embedding[model.class_id("perlin")]
    assert np.linalg.norm(mid) > 0.98 * np.linalg.norm(0.5 * (ea + eb))
    same = C.slerp(ea, ea, np.array([0.3, 0.7]))
    assert np.isfinite(same).all() and np.allclose(same, ea)  # slerp of a class with itself is safe
    u = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    np.testing.assert_allclose(np.linalg.norm(C.slerp(*u, np.linspace(0, 1, 7)), axis=1), 1.0, atol=1e-6)
    g4 = C.four_corner(model, [a, b, ("cells_f1", {}), a], 9, 11)
    np.testing.assert_allclose(g4[:, 0, 0], ua[:, 0, 0], atol=1e-5)
    np.testing.assert_allclose(g4[:, 0, -1], ub[:, 0, 0], atol=1e-5)
    assert g4.shape == (E + P, 9, 11)
    with pytest.raises(SettingError, match="no parameter 'size'"):
        C.uniform(model, ("spots", {"size": 1}), 4, 4)
    with pytest.raises(SettingError, match="unknown class 'lava'"):
        C.uniform(model, ("lava", {}), 4, 4)


def test_distance_transform_and_mask_weights():
    rng = np.random.default_rng(3)
    m = rng.random((23, 31)) < 0.03
    d = C.distance_transform(m)
    ys, xs = np.nonzero(m)
    yy, xx = np.mgrid[:23, :31]
    brute = np.sqrt(((yy[..., None] - ys) ** 2 + (xx[..., None] - xs) ** 2).min(-1))
    np.testing.assert_allclose(d, brute, atol=1e-5)
    half = np.zeros((16, 64), bool)
    half[:, 32:] = True
    soft, hard = C.mask_weight(half, 24, 1.0), C.mask_weight(half, 24, 4.0)
    assert np.all(np.diff(soft[0]) >= -1e-7) and soft[0, 0] == 0 and soft[0, -1] == 1
    assert abs(hard[0, 28] - 0.5) > abs(soft[0, 28] - 0.5)  # a larger exponent is a harder edge


def test_painted_maps(tiny):
    out = tiny
    model = NeuralNoiseModel(str(out))
    img = np.zeros((16, 24, 3), np.uint8)
    img[:, 12:] = (255, 0, 0)
    g = C.painted(model, img, {(0, 0, 0): ("spots", {}), (255, 0, 0): ("perlin", {})}, width=4)
    np.testing.assert_allclose(g[:, 0, 0], C.uniform(model, ("spots", {}), 1, 1)[:, 0, 0], atol=1e-5)
    np.testing.assert_allclose(g[:, 0, -1], C.uniform(model, ("perlin", {}), 1, 1)[:, 0, 0], atol=1e-5)
    with pytest.raises(SettingError, match=r"uses \(255, 0, 0\) but no spec"):
        C.painted(model, img, {(0, 0, 0): ("spots", {})})
    idx = np.zeros((8, 8), int)
    idx[4:] = 3
    assert C.painted(model, idx, {0: ("spots", {}), 3: ("cells_f1", {})}).shape[1:] == (8, 8)


@pytest.mark.long
def test_neural_cli(tiny, tmp_path, capsys):
    out = tiny
    png = str(tmp_path / "n.png")
    base = ["neural", "--model", str(out), "--quiet", "--steps", "3"]
    assert main(base + ["--noise", "spots", "--param", "coverage=0.5", "--size", "24", "-o", png]) == 0
    assert main(base + ["--noise", "spots", "--size", "32", "--tileable", "-o", str(tmp_path / "t.npy")]) == 0
    assert np.load(tmp_path / "t.npy").shape == (32, 32)
    mask = np.zeros((32, 32), np.uint8)
    mask[:, 16:] = 255
    from omninoise.export.images import write_png

    write_png(str(tmp_path / "m.png"), mask)
    write_png(str(tmp_path / "wide.png"), mask[:16])
    assert main(base + ["--noise", "spots", "--noise2", "perlin", "--param2", "scale=10", "--blend",
                        str(tmp_path / "m.png"), "--size", "32", "-o", png]) == 0
    assert main(base + ["--corners", "spots:coverage=0.3", "perlin", "cells_f1:scale=10,jitter=0.5", "spots",
                        "--size", "24", "-o", png]) == 0
    cmap = np.zeros((32, 32, 3), np.uint8)
    cmap[:, 16:] = (255, 0, 0)
    write_png(str(tmp_path / "map.png"), cmap)
    assert main(base + ["--map", str(tmp_path / "map.png"), "--region", "#000000=spots", "--region",
                        "#ff0000=perlin:scale=9", "--size", "32", "-o", str(tmp_path / "m.npy")]) == 0
    assert np.load(tmp_path / "m.npy").shape == (32, 32)
    assert main(base + ["--map", str(tmp_path / "map.png"), "--region", "#000000=spots", "--size", "32",
                        "-o", png]) == 2
    assert "uses (255, 0, 0) but no spec" in capsys.readouterr().err
    assert main(["neural", "--model", str(out), "--list", "--json"]) == 0          # the listing reads the model alone
    assert "spots" in json.loads(capsys.readouterr().out)["classes"]
    wide = str(tmp_path / "wide.png")
    for args, msg in [(["--noise", "lava", "-o", png], "--noise: unknown class 'lava'"),
                      (["--noise", "spots", "--blend", wide, "--noise2", "lava", "-o", png],
                       "--noise2: unknown class 'lava'"),           # each class named by the flag that gave it
                      (["--noise", "spots", "--blend", wide, "--param2", "coverage=9", "-o", png],
                       "--param2: coverage=9 is outside"),
                      (["--corners", "spots", "spots", "lava", "spots", "-o", png], "--corners: unknown class 'lava'"),
                      (["--map", str(tmp_path / "map.png"), "--region", "#000000=spots", "--region", "#ff0000=lava",
                        "-o", png], "--region: unknown class 'lava'"),
                      (["--noise", "spots", "--param", "coverage=9", "-o", png], "outside [0.2, 0.8]"),
                      (["--noise", "spots", "--blend", str(tmp_path / "wide.png"), "--size", "16", "-o", png],
                       "--blend: mask is 32x16 but the image is 16x16"),
                      (["--noise", "spots", "--noise2", "perlin", "-o", png],
                       "--noise2: is the class of a blend's masked part; without --blend")]:
        assert main(base + args) == 2
        assert msg in capsys.readouterr().err
    assert main(["neural", "--model", str(tmp_path / "none"), "--noise", "spots", "-o", png]) == 2
    assert "no neural_noise.json" in capsys.readouterr().err
    # sampler settings: the CLI's output equals generate() with the same settings; bad ones: one line, exit 2
    npy = str(tmp_path / "s.npy")
    model = NeuralNoiseModel(str(out))
    cond = C.uniform(model, ("spots", {}), 24, 24)
    for extra, kw in ((["--sampler", "ddim", "--eta", "0.5"], dict(sampler="ddim", eta=0.5)),
                      (["--sampler", "heun", "--spacing", "karras"], dict(sampler="heun", spacing="karras")),
                      (["--tile", "0", "--threads", "1"], {})):
        assert main(base + ["--noise", "spots", "--size", "24", "-o", npy] + extra) == 0
        np.testing.assert_array_equal(np.load(npy), generate(model, cond, seed=0, steps=3, **kw))
    for extra, msg in ((["--sampler", "euler"], "unknown sampler 'euler'"), (["--steps", "0"], "steps: must be"),
                       (["--threads", "-1"], "--threads: must lie in [0, 1024]"), (["--tile", "20"], "multiple of 8"),
                       (["--eta", "2"], "eta: must lie in [0, 1]"), (["--spacing", "odd"], "unknown spacing")):
        assert main(base + ["--noise", "spots", "--size", "24", "-o", npy] + extra) == 2
        err = capsys.readouterr().err
        assert msg in err and len(err.strip().splitlines()) == 1, err


def test_neural_bake_source_in_jobs(tiny, tmp_path):
    """kind = "neural" in a job file: a mask blend baked to PNG/npy, equal to generate() on the same grid."""
    from omninoise.backend.bake import BakeSpec, Cancelled, run_bake
    from omninoise.backend.jobs import run_job
    from omninoise.backend.sources import BoxGrid, NeuralSource
    from omninoise.export.images import write_png

    out = tiny
    mask = np.zeros((24, 40), np.uint8)
    mask[:, 20:] = 255
    write_png(str(tmp_path / "mask.png"), mask)
    (tmp_path / "job.toml").write_text(f"""
[[bake]]
name = "blend"
output = "n.npy"
resolution = [40, 24]
[bake.source]
kind = "neural"
model = "{out}"
noise = "spots"
params = {{coverage = 0.6}}
blend = "mask.png"
noise2 = "perlin"
steps = 3
seed = 4
sampler = "ddim"
""")
    assert [o.status for o in run_job(str(tmp_path / "job.toml"))] == ["baked"]
    got = np.load(tmp_path / "n.npy")[::-1]  # .npy rows run by +y; image rows top-down
    model = NeuralNoiseModel(str(out))
    ref = generate(model, C.blend(model, ("spots", {"coverage": 0.6}), ("perlin", {}),
                                  C.mask_weight(mask > 127, 32.0, 1.0)), seed=4, steps=3, sampler="ddim")
    np.testing.assert_allclose(got, ref, atol=1e-6)
    with pytest.raises(SettingError, match="source.sampler: unknown sampler 'fast'"):
        NeuralSource(str(out), "spots", sampler="fast")
    src = NeuralSource(str(out), "spots", steps=5)
    calls = []
    with pytest.raises(Cancelled):
        run_bake(BakeSpec("c", src, BoxGrid((16, 16)), str(tmp_path / "c.png")), cancel=lambda: len(calls) > 1
                 or calls.append(1))
    assert not (tmp_path / "c.png").exists()
    with pytest.raises(SettingError, match="no parameter 'size'"):
        NeuralSource(str(out), "spots", {"size": 3})
    (tmp_path / "job.toml").write_text((tmp_path / "job.toml").read_text().replace("resolution = [40, 24]",
                                                                                  "resolution = [32, 24]"))
    out2 = run_job(str(tmp_path / "job.toml"), force=True)  # refused before anything runs (was a failure, exit 1)
    assert out2[0].status == "invalid" and "mask is 40x24 but the resolution is 32x24" in out2[0].message
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 2


def test_the_shipped_model_loads_and_generates():
    """models/neural_noise: the committed ONNX passes its hash check and samples every trained class."""
    from omninoise.backend.paths import neural_model

    assert neural_model() == os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "models",
                                          "neural_noise")  # the repository's own models
    model = NeuralNoiseModel(neural_model())
    assert set(model.config["trained_classes"]) <= set(model.classes) and model.config["step"] > 0
    for name in model.config["trained_classes"][:2]:
        img = generate(model, C.uniform(model, (name, {}), 32, 32), seed=1, steps=3)
        assert img.shape == (32, 32) and img.std() > 0.01
    # one denoiser per padding, sharing one weights file; the tileable one wraps without a seam
    assert {"denoiser.onnx", "denoiser_tile.onnx", "denoiser.weights"} <= set(model.config["files"])
    wrap = generate(model, C.uniform(model, ("cells_f1", {}), 32, 32), seed=1, steps=3, tileable=True)
    assert np.abs(wrap[:, 0] - wrap[:, -1]).mean() < 1.5 * np.abs(np.diff(wrap, axis=1)).mean()


def test_an_export_with_one_tile_input_denoiser_still_loads(tiny):
    """tests/data/tiny_neural is in the older split form (one denoiser with a tile input): plain and tileable
    sampling still work and differ only at the borders' padding."""
    model = NeuralNoiseModel(tiny)
    assert "denoiser_tile.onnx" not in model.config["files"]
    assert "tile" in {i.name for i in model.session("denoiser.onnx").get_inputs()}
    cond = C.uniform(model, ("perlin", {}), 32, 32)
    plain, wrap = (generate(model, cond, seed=2, steps=3, tileable=t) for t in (False, True))
    assert plain.shape == wrap.shape == (32, 32) and np.abs(plain - wrap).max() > 0


def test_animation_hits_its_keyframes_and_moves_smoothly_between_them(tiny, tmp_path):
    """Animation: frames at keyframes equal plain generation; frames between move in small, even steps."""
    from omninoise.backend.neural.animate import animate, frame_cond, frame_latent, parse_keys, temporal_coherence
    import tomllib

    out = tiny
    m = NeuralNoiseModel(str(out))
    keys = parse_keys(tomllib.loads(KEYS))
    assert [k.frame for k in keys] == [1, 7] and keys[0].params == {"scale": 4.0}
    frames = dict(animate(m, keys, (0, 8), 16, 16, latent="fixed", steps=4))
    assert sorted(frames) == list(range(0, 9))
    # keyframes: the plain image of the key's spec from the first key's seed, made with the deterministic
    # sampler (animation always is; a still's default has step noise)
    np.testing.assert_array_equal(frames[1], generate(m, C.uniform(m, ("perlin", {"scale": 4.0}), 16, 16), seed=2,
                                                       steps=4, eta=0.0))
    np.testing.assert_array_equal(frames[7], generate(m, C.uniform(m, ("cells_f1", {}), 16, 16), seed=2, steps=4,
                                                      eta=0.0))
    assert np.abs(frames[1] - generate(m, C.uniform(m, ("perlin", {"scale": 4.0}), 16, 16), seed=2,
                                       steps=4)).max() > 1e-3
    np.testing.assert_array_equal(frames[0], frames[1])  # held before the first key and after the last
    np.testing.assert_array_equal(frames[8], frames[7])
    # halfway: the conditioning is the w = 1/2 blend
    half = frame_cond(m, keys, 4, 16, 16)
    np.testing.assert_allclose(half, C.blend(m, keys[0].spec, keys[1].spec, np.full((16, 16), 0.5)), atol=1e-6)
    seq = [frames[f] for f in range(1, 8)]
    other = generate(m, C.uniform(m, ("perlin", {"scale": 4.0}), 16, 16), seed=77, steps=4, eta=0.0)
    coh = temporal_coherence(seq, float(np.abs(other - frames[1]).mean()))
    assert coh["step_over_independent"] < 0.5, coh  # far from flicker
    # latents: slerp goes from one key's seed to the other's, keeping the norm; drift circles
    a, b = frame_latent(keys, 1, (16, 16), "slerp"), frame_latent(keys, 7, (16, 16), "slerp")
    mid = frame_latent(keys, 4, (16, 16), "slerp")
    assert np.linalg.norm(mid) == pytest.approx((np.linalg.norm(a) + np.linalg.norm(b)) / 2, rel=0.05)
    assert np.abs(mid - a).mean() > 0.1 and np.abs(mid - b).mean() > 0.1
    d0, d1 = frame_latent(keys, 1, (16, 16), "drift", 0.1), frame_latent(keys, 2, (16, 16), "drift", 0.1)
    assert 0 < np.abs(d1 - d0).mean() < 0.2 * np.abs(d0).mean()


def test_animation_cli_writes_numbered_frames_and_refuses_bad_input(tiny, tmp_path, capsys):
    out = tiny
    keys = tmp_path / "keys.toml"
    keys.write_text(KEYS)
    base = ["neural", "--model", str(out), "--size", "16", "--steps", "2", "--quiet"]
    assert main(base + ["--keys", str(keys), "--frames", "1", "3", "-o", str(tmp_path / "a_###.png")]) == 0
    assert sorted(p.name for p in tmp_path.glob("a_*.png")) == ["a_001.png", "a_002.png", "a_003.png"]
    bad = [
        (["--keys", str(keys), "--frames", "3", "1", "-o", str(tmp_path / "b_#.png")], "--frames"),
        (["--keys", str(keys), "--frames", "1", "2", "-o", str(tmp_path / "b.png")], "'#'"),
        (["--keys", str(tmp_path / "none.toml"), "--frames", "1", "2", "-o", str(tmp_path / "b_#.png")], "not found"),
        (["--frames", "1", "2", "-o", str(tmp_path / "b_#.png")], "--keys"),
        (["--keys", str(keys), "--frames", "1", "2", "--noise", "perlin", "-o", str(tmp_path / "b_#.png")], "--keys"),
    ]
    for extra, what in bad:
        assert main(base + extra) == 2, extra
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and what in err[0], (extra, err)
    for text, what in (("[[key]]\nframe = 1\n", "noise"), ('[[key]]\nframe = "a"\nnoise = "perlin"\n', "frame"),
                       ('[[key]]\nframe = 1\nnoise = "bogus"\n', "bogus"), ("x = 1\n", "unknown top-level"),
                       ('[[key]]\nframe = 1\nnoise = "perlin"\n[[key]]\nframe = 1\nnoise = "perlin"\n', "two keyframes"),
                       ('[[key]]\nframe = 1\nnoise = "perlin"\nparams = {scale = nan}\n', "params")):
        keys.write_text(text)
        assert main(base + ["--keys", str(keys), "--frames", "1", "2", "-o", str(tmp_path / "c_#.png")]) == 2, text
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and what in err[0], (text, err)
    assert not list(tmp_path.glob("b_*")) and not list(tmp_path.glob("c_*"))


def test_animation_in_a_job_file_equals_the_cli_frames(tiny, tmp_path):
    """A job with keys and frames bakes the same frames as `neural --keys --frames` (the job's time is the
    frame number); the keys enter the bake key, and blend with keys is refused."""
    from omninoise.backend.jobs import load_job, run_job

    out = tiny
    (tmp_path / "keys.toml").write_text(KEYS)
    job = tmp_path / "job.toml"
    job.write_text(f"""
[[bake]]
name = "morph"
output = "seq/m_##.npy"
resolution = [16, 16]
frames = [1, 3]
[bake.source]
kind = "neural"
model = "{out}"
keys = "keys.toml"
latent = "slerp"
steps = 2
""")
    assert [o.status for o in run_job(str(job))] == ["baked"]
    assert main(["neural", "--model", str(out), "--size", "16", "--steps", "2", "--quiet", "--keys",
                 str(tmp_path / "keys.toml"), "--frames", "1", "3", "--latent", "slerp", "-o",
                 str(tmp_path / "cli_#.npy")]) == 0
    for f in (1, 2, 3):
        np.testing.assert_allclose(np.load(tmp_path / "seq" / f"m_0{f}.npy")[::-1],  # bakes index rows by +y
                                   np.load(tmp_path / f"cli_{f}.npy"), atol=1e-6)
    assert not np.allclose(np.load(tmp_path / "seq" / "m_01.npy"), np.load(tmp_path / "seq" / "m_03.npy"))
    inline = job.read_text().replace('keys = "keys.toml"', 'keys = [{frame = 1, noise = "perlin"}, '
                                                              '{frame = 3, noise = "spots"}]')
    job.write_text(inline)
    (spec,) = [s for _, s in load_job(str(job))]
    assert spec.source.animated and spec.time == 1.0 and spec.time_step == 1.0
    from omninoise.backend.sources import describe
    from omninoise.export.images import write_png

    assert '"spots"' in describe(spec.source) and '"latent":"slerp"' in describe(spec.source)  # in the bake key
    write_png(str(tmp_path / "mask.png"), np.zeros((16, 16), np.uint8))
    job.write_text(inline.replace('latent = "slerp"', 'latent = "slerp"\nblend = "mask.png"'))
    (_, bad), = load_job(str(job))
    assert "source.keys: keyframes set the classes of the whole image; leave out blend" in str(bad)


def test_a_periodic_parameter_maps_one_turn_of_its_pattern_to_one_turn_of_the_input(tiny):
    """gabor's orientation spans 0-2π but its images repeat every π (a cosine kernel): a model whose JSON gives the
    period gets ((v - min) mod period) / period, as the zoo conditioned it; a JSON without one keeps the range."""
    import copy
    import math

    m = NeuralNoiseModel(tiny)
    slot = m.params.index("orientation")
    assert "period" not in {k for p in m.class_params["gabor"]["params"] for k in p}
    assert m.param_vector("gabor", {"orientation": math.pi})[slot] == pytest.approx(0.5)  # the range: 0-2π
    m.class_params = copy.deepcopy(m.class_params)
    for p in m.class_params["gabor"]["params"]:
        if p["name"] == "orientation":
            p["period"] = math.pi
    for v, want in ((0.0, 0.0), (math.pi / 2, 0.5), (math.pi + 0.3, 0.3 / math.pi), (2 * math.pi, 0.0)):
        assert m.param_vector("gabor", {"orientation": v})[slot] == pytest.approx(want, abs=1e-6)
    with pytest.raises(SettingError, match="outside"):
        m.param_vector("gabor", {"orientation": 7.0})
