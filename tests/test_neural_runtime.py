"""Neural noise runtime: ONNX export (split and one-piece) vs torch, hash check, samplers, conditioning grids,
any size, tiling, CLI."""
import json
import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from backend.cli import main  # noqa: E402
from backend.errors import SettingError  # noqa: E402
from backend.neural import conditioning as C  # noqa: E402
from backend.neural.generate import generate  # noqa: E402
from backend.neural.model import ModelError, NeuralNoiseModel  # noqa: E402
from backend.neural.sampler import ddim_sample, initial_noise  # noqa: E402
from backend.onnx_models import fingerprint  # noqa: E402
from backend.training.export_onnx import export, reexport  # noqa: E402
from backend.training.train import TrainConfig, build_model, train  # noqa: E402
from backend.training.unet import set_circular  # noqa: E402

TINY = dict(size=16, batch=4, steps=3, widths=(8, 16, 16), emb_dim=8, log_every=1, checkpoint_every=3, sample_every=0,
            classes=("perlin", "spots", "cells_f1"))


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """A tiny trained run and its export in the default (split) form."""
    run = tmp_path_factory.mktemp("run")
    out = tmp_path_factory.mktemp("model")
    train(TrainConfig.from_dict(TINY), str(run), log=lambda s: None)
    export(str(run), str(out))
    return run, out


@pytest.fixture(scope="module")
def one_piece(exported, tmp_path_factory):
    """The same weights as one eps.onnx (the form of exports made before the split)."""
    out = tmp_path_factory.mktemp("one_piece")
    export(str(exported[0]), str(out), one_piece=True)
    return out


def test_split_export_equals_the_one_piece_network(exported, one_piece):
    """encoder + denoiser = the one-piece ε-network within 1e-4, plain and circular padding, any batch and size."""
    _, out = exported
    split, whole = NeuralNoiseModel(str(out)), NeuralNoiseModel(str(one_piece))
    assert split.form == "split" and whole.form == "one-piece"
    assert sorted(split.config["files"]) == ["denoiser.onnx", "encoder.onnx"]
    assert split.config["blocks"]["names"][0] == "m00" and len(split.config["blocks"]["levels"]) == 15
    rng = np.random.default_rng(1)
    for shape in ((2, 24, 40), (1, 16, 16)):
        B, H, W = shape
        x = rng.standard_normal((B, 1, H, W)).astype(np.float32)
        t = rng.uniform(0, 999, B).astype(np.float32)
        cond = rng.standard_normal((B, split.embedding.shape[1] + len(split.params), H, W)).astype(np.float32)
        for tile in (False, True):
            np.testing.assert_allclose(split.eps_fn(tile)(x, t, cond), whole.eps_fn(tile)(x, t, cond), atol=1e-4)
    # the encoder runs once per conditioning array: same cond object, cached maps; a new array, new maps
    calls = []
    enc = split.encode
    split.encode = lambda c, tileable=False: calls.append(1) or enc(c, tileable)
    f = split.eps_fn(False)
    cond = C.uniform(split, ("perlin", {}), 16, 16)[None]
    a = f(x[:1, :, :16, :16], t[:1], cond)
    f(x[:1, :, :16, :16], t[:1], cond)
    b = f(x[:1, :, :16, :16], t[:1], C.uniform(split, ("spots", {}), 16, 16)[None])
    assert len(calls) == 2 and np.abs(a - b).max() > 1e-4


def test_reexport_from_an_export_keeps_the_weights(exported, one_piece, tmp_path):
    """An older one-piece export is re-exported to the split form from its own weights (no checkpoint)."""
    doc = reexport(str(one_piece), str(tmp_path / "split"))
    assert doc["form"] == "split" and doc["reexported_from"]["files"] == NeuralNoiseModel(str(one_piece)).config["files"]
    a, b = NeuralNoiseModel(str(one_piece)), NeuralNoiseModel(str(tmp_path / "split"))
    assert a.config["step"] == b.config["step"] and a.classes == b.classes
    cond = C.uniform(a, ("cells_f1", {}), 24, 24)
    np.testing.assert_allclose(generate(a, cond, seed=3, steps=4), generate(b, cond, seed=3, steps=4), atol=1e-4)


def test_model_json_must_declare_what_the_runtime_runs(exported, tmp_path):
    _, out = exported
    for f in os.listdir(out):
        (tmp_path / f).write_bytes((out / f).read_bytes())
    doc = json.loads((tmp_path / "neural_noise.json").read_text())
    for change, msg in ((dict(form="sideways"), "unknown model form"), (dict(prediction="v"), "epsilon only"),
                        (dict(schedule=dict(kind="linear")), "unsupported noise schedule"),
                        (dict(files={"encoder.onnx": doc["files"]["encoder.onnx"]}), "no sha256 for denoiser.onnx")):
        (tmp_path / "neural_noise.json").write_text(json.dumps(dict(doc, **change)))
        with pytest.raises(ModelError, match=msg):
            NeuralNoiseModel(str(tmp_path))


def _torch_model(run, circular=False):
    state = torch.load(os.path.join(run, "ckpt.pt"), weights_only=False)
    m = build_model(TrainConfig.from_dict(state["config"]), state["ema"])
    m.load_state_dict(state["ema"])
    return set_circular(m.eval(), circular)


def test_onnx_matches_torch(exported):
    run, out = exported
    model = NeuralNoiseModel(str(out))
    rng = np.random.default_rng(0)
    x = rng.standard_normal((2, 1, 24, 40)).astype(np.float32)
    t = np.array([10.0, 700.0], np.float32)
    cond = rng.standard_normal((2, model.embedding.shape[1] + len(model.params), 24, 40)).astype(np.float32)
    for circular in (False, True):
        ref = _torch_model(run, circular)(torch.from_numpy(x), torch.from_numpy(t), torch.from_numpy(cond))
        got = model.eps_fn(circular)(x, t, cond)
        np.testing.assert_allclose(got, ref.detach().numpy(), atol=1e-4)
    tm = _torch_model(run)
    np.testing.assert_allclose(model.embedding, tm.class_emb.weight.detach().numpy(), atol=1e-6)


@pytest.mark.parametrize("form", ["split", "one-piece"])
def test_hash_is_checked(exported, one_piece, tmp_path, form):
    out = exported[1] if form == "split" else one_piece
    for f in os.listdir(out):
        (tmp_path / f).write_bytes((out / f).read_bytes())
    for name in NeuralNoiseModel(str(out)).config["files"]:
        with open(tmp_path / name, "ab") as fh:
            fh.write(b"\0")
        with pytest.raises(ModelError, match="sha256 does not match"):
            NeuralNoiseModel(str(tmp_path))
        (tmp_path / name).write_bytes((out / name).read_bytes())
        NeuralNoiseModel(str(tmp_path))  # restored: loads again
        os.remove(tmp_path / name)
        with pytest.raises(ModelError, match="missing"):
            NeuralNoiseModel(str(tmp_path))
        (tmp_path / name).write_bytes((out / name).read_bytes())


def test_generate_any_size_seeded_and_sampler_equals_torch(exported):
    run, out = exported
    model = NeuralNoiseModel(str(out))
    cond = C.uniform(model, ("spots", {"coverage": 0.4}), 20, 36)
    a = generate(model, cond, seed=5, steps=4)
    assert a.shape == (20, 36) and a.dtype == np.float32 and 0 <= a.min() and a.max() <= 1
    np.testing.assert_array_equal(a, generate(model, cond, seed=5, steps=4))
    assert np.abs(a - generate(model, cond, seed=6, steps=4)).mean() > 1e-3
    tm = _torch_model(run)
    cond16 = C.uniform(model, ("perlin", {}), 16, 16)[None]

    def torch_eps(x, t, c):
        with torch.no_grad():
            return tm(torch.from_numpy(x), torch.from_numpy(t), torch.from_numpy(c)).numpy()

    xT = initial_noise(1, (1, 1, 16, 16))
    np.testing.assert_allclose(ddim_sample(model.eps_fn(), xT, cond16, steps=5),
                               ddim_sample(torch_eps, xT, cond16, steps=5), atol=1e-3)
    with pytest.raises(SettingError, match="multiples of 8"):
        generate(model, cond, tileable=True)


def test_tiled_generation(exported):
    """Tiles: one tile covering the image is the one-piece path; smaller tiles give the same statistics,
    stay seeded, and tileable output still wraps."""
    _, out = exported
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
    for tile, overlap, msg in ((60, 8, "multiple of 8"), (16, 0, "at least 32"), (64, 40, "half the tile")):
        with pytest.raises(SettingError, match=msg):
            generate(model, cond, steps=2, tile=tile, overlap=overlap)


def test_tileable_sampling_wraps(exported):
    _, out = exported
    model = NeuralNoiseModel(str(out))
    cond = C.uniform(model, ("cells_f1", {}), 32, 32)[None]
    xT = initial_noise(2, (1, 1, 32, 32))
    a = ddim_sample(model.eps_fn(True), np.roll(xT, (8, 16), (2, 3)), cond, steps=3)
    b = np.roll(ddim_sample(model.eps_fn(True), xT, cond, steps=3), (8, 16), (2, 3))
    np.testing.assert_allclose(a, b, atol=1e-4)  # the image lives on a torus: it tiles without a seam


def test_conditioning_grids(exported):
    _, out = exported
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


def test_painted_maps(exported):
    _, out = exported
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


def test_neural_cli(exported, tmp_path, capsys):
    _, out = exported
    png = str(tmp_path / "n.png")
    base = ["neural", "--model", str(out), "--quiet", "--steps", "3"]
    assert main(base + ["--noise", "spots", "--param", "coverage=0.5", "--size", "24", "-o", png]) == 0
    assert main(base + ["--noise", "spots", "--size", "32", "--tileable", "-o", str(tmp_path / "t.npy")]) == 0
    assert np.load(tmp_path / "t.npy").shape == (32, 32)
    mask = np.zeros((32, 32), np.uint8)
    mask[:, 16:] = 255
    from export.images import write_png

    write_png(str(tmp_path / "m.png"), mask)
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
    assert main(base + ["--list"]) == 0
    assert "spots" in json.loads(capsys.readouterr().out)["classes"]
    for args, msg in [(["--noise", "lava", "-o", png], "unknown class 'lava'"),
                      (["--noise", "spots", "--param", "coverage=9", "-o", png], "outside [0.2, 0.8]"),
                      (["--noise", "spots", "--blend", str(tmp_path / "m.png"), "--size", "16", "-o", png],
                       "mask is 32x32 but --size is 16"),
                      (["--noise", "spots", "--noise2", "perlin", "-o", png], "needs --blend")]:
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
                       (["--threads", "-1"], "--threads: must be >= 0"), (["--tile", "20"], "multiple of 8"),
                       (["--eta", "2"], "eta: must lie in [0, 1]"), (["--spacing", "odd"], "unknown spacing")):
        assert main(base + ["--noise", "spots", "--size", "24", "-o", npy] + extra) == 2
        err = capsys.readouterr().err
        assert msg in err and len(err.strip().splitlines()) == 1, err


# an evaluation document as bench/eval_neural.py writes it, one class, for the card tests
EVAL = dict(classes={"spots": dict(fd=1.5, acc=0.5, psd=0.2, response=0.1, param="scale")}, zoo_accuracy=0.9,
            seam_tileable=1.1, seam_plain=3.0, locality=0.75, model=dict(n=4, steps=5),
            timing=dict(size=64, onnxruntime_s=0.1, torch_s=0.2, ratio=2.0, max_eps_difference=1e-6))


def test_model_card_reads_the_run_export_and_evaluation(exported, tmp_path):
    from backend.training.model_card import card, wall_seconds

    run, out = exported
    log = tmp_path / "log.jsonl"
    log.write_text("\n".join(json.dumps(dict(step=i, seconds=s, mse=0.1)) for i, s in enumerate([5, 10, 3, 7])))
    assert wall_seconds(str(log)) == 17  # two segments: 10 s, then a resume for 7 s
    ev = EVAL
    text = card(str(run), str(out), ev, dict(ev, locality=0.5), "python -m backend.training.train ...", "test CPU")
    meta = json.loads((out / "neural_noise.json").read_text())
    assert all(digest in text for digest in meta["files"].values()) and "| spots | 1.5 | 0.5 | 0.2 | 0.1 (scale) |" in text
    assert "| without CutMix | 0.5 |" in text and "test CPU" in text
    worse = dict(ev, classes={"spots": dict(fd=3.0, acc=0.25, psd=0.4, response=0.2, param="scale")}, locality=0.5)
    text = card(str(run), str(out), ev, None, "train", "test CPU", previous=worse, previous_label="3000-step model")
    assert "3000-step model" in text and "| mean FD ↓ | 3.0 | 1.5 |" in text and "| blend locality ↑ | 0.5 | 0.75 |" in text
    text = card(str(run), str(out), ev, dict(ev, locality=0.25), "train", "test CPU", ablation_reference=worse)
    assert "| with CutMix | 0.5 | 3.0 | 0.25 |" in text and "| without CutMix | 0.25 |" in text
    # a model with more classes compares with its predecessor on the predecessor's classes only
    wide = dict(ev, classes=dict(ev["classes"], perlin=dict(fd=99.0, acc=0.0, psd=0.9, response=0.9, param="scale")))
    text = card(str(run), str(out), wide, None, "train", "test CPU", previous=worse, compare=ev, kept="## Old\nkept",
                note="Why: more classes.")
    assert "| mean FD ↓ | 3.0 | 1.5 |" in text and "| spots | 3.0 / 1.5 | 0.25 / 0.5 | 0.4 / 0.2 |" in text
    assert "on its 1 classes (spots)" in text and "| perlin | 99.0 |" in text and "## Old\nkept\n" in text
    assert "| spots | 3.0 / 1.5 | 0.25 / 0.5 | 0.4 / 0.2 |\n\nWhy: more classes.\n" in text


def test_model_card_without_the_run(exported, tmp_path):
    """Runs are not kept: the export records the log's wall time and loss, and the card reads them from there."""
    import shutil

    from backend.training.model_card import main as card_main, run_figures, wall_seconds

    run, out = exported
    meta = json.loads((out / "neural_noise.json").read_text())
    last = json.loads((run / "log.jsonl").read_text().splitlines()[-1])
    rec = meta["training"]
    assert rec["final_mse"] == round(last["mse"], 5) and rec["log_step"] == meta["step"] == last["step"]
    assert rec["wall_seconds"] == round(wall_seconds(str(run / "log.jsonl")), 1)
    wall, mse, source = run_figures(None, meta)
    assert (wall, mse) == (rec["wall_seconds"] / 60, rec["final_mse"]) and "export's JSON" in source
    # an export from before the record: the figures must be given, and the card says where they come from
    old = tmp_path / "old"
    shutil.copytree(out, old)
    doc = json.loads((old / "neural_noise.json").read_text())
    del doc["training"]
    (old / "neural_noise.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="give --wall-minutes and --final-mse"):
        run_figures(None, doc)
    ev = tmp_path / "ev.json"
    ev.write_text(json.dumps(EVAL))
    card_out = tmp_path / "CARD.md"
    base = ["--model", str(old), "--eval", str(ev), "--train-command", "train", "-o", str(card_out)]
    with pytest.raises(SystemExit):
        card_main(base)
    assert not card_out.exists()
    assert card_main(base + ["--wall-minutes", "88.0", "--final-mse", "0.1011"]) == 0
    text = card_out.read_text()
    assert "**Wall time:** 88.0 min" in text and "0.1011" in text and "the run folder is not kept" in text


def test_model_card_carries_sections_of_the_earlier_card():
    from backend.training.model_card import kept_sections

    old = "# Card\n\nintro\n\n## A\n\nfirst | table\n\n## B (Fig. 13)\n\nsecond\n\n## C\n\nthird\n"
    assert kept_sections(old, ["B (Fig. 13)", "A"]) == "## B (Fig. 13)\n\nsecond\n\n## A\n\nfirst | table"
    with pytest.raises(ValueError, match="no section '## D'"):
        kept_sections(old, ["D"])


def test_neural_bake_source_in_jobs(exported, tmp_path):
    """kind = "neural" in a job file: a mask blend baked to PNG/npy, equal to generate() on the same grid."""
    from backend.bake import BakeSpec, Cancelled, run_bake
    from backend.jobs import run_job
    from backend.sources import BoxGrid, NeuralSource
    from export.images import write_png

    _, out = exported
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
    from backend.paths import neural_model

    assert neural_model() == os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "models",
                                          "neural_noise")  # the repository's own models
    model = NeuralNoiseModel(neural_model())
    assert set(model.config["trained_classes"]) <= set(model.classes) and model.config["step"] > 0
    for name in model.config["trained_classes"][:2]:
        img = generate(model, C.uniform(model, (name, {}), 32, 32), seed=1, steps=3)
        assert img.shape == (32, 32) and img.std() > 0.01


@pytest.mark.parametrize("form", ["split", "one-piece"])
def test_warm_start_reads_an_export_back_exactly(exported, one_piece, tmp_path, form):
    """A run started from an export (init_onnx) begins with the exported EMA weights, GroupNorm affines included."""
    from backend.neural.model import sha256_file
    from backend.training.train import main as train_main

    run, out = exported
    if form == "one-piece":
        out = one_piece
        assert fingerprint(NeuralNoiseModel(str(out)).config["files"]) == sha256_file(str(out / "eps.onnx"))
    sha = NeuralNoiseModel(str(out)).fingerprint
    ref = torch.load(os.path.join(run, "ckpt.pt"), weights_only=False)["ema"]
    assert any(".norm1.weight" in k for k in ref)
    cfg = TrainConfig.from_dict(dict(TINY, steps=1, lr=0.0, init_onnx=str(out), init_sha256=sha))
    train(cfg, str(tmp_path / "warm"), log=lambda s: None)
    got = torch.load(tmp_path / "warm" / "ckpt.pt", weights_only=False)
    for k, v in ref.items():
        tol = 1e-6 if k == "class_emb.weight" else 0.0  # the JSON table is rounded to 7 decimals
        assert torch.allclose(got["model"][k], v, atol=tol, rtol=0), k
    # a pinned hash that does not match: one line, exit 2, no run folder written
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(dict(TINY, init_onnx=str(out), init_sha256="0" * 64)))
    rc = train_main(["--config", str(bad), "--out", str(tmp_path / "never")])
    assert rc == 2 and not (tmp_path / "never").exists()
    with pytest.raises(ValueError, match="init_onnx needs init_sha256"):
        TrainConfig.from_dict(dict(TINY, init_onnx=str(out)))


@pytest.mark.parametrize("form", ["split", "one-piece"])
def test_torch_is_rebuilt_from_the_export_alone(exported, one_piece, form):
    """The step timing needs no checkpoint: torch runs the export's own weights, as onnxruntime does."""
    from backend.training.evaluate import step_seconds
    from backend.training.warm_start import torch_from_export

    run, out = exported
    out = out if form == "split" else one_piece
    ref = _torch_model(run).state_dict()
    got = torch_from_export(str(out)).state_dict()
    assert set(got) == set(ref)
    for k, v in ref.items():
        assert torch.allclose(got[k], v, atol=1e-6 if k == "class_emb.weight" else 0.0, rtol=0), k
    t = step_seconds(str(out), size=16, reps=1)
    assert t["max_eps_difference"] < 1e-4 and t["onnxruntime_s"] > 0 and t["torch_s"] > 0 and t["size"] == 16


def test_warm_start_grows_the_class_table_and_parameter_slots():
    """New classes keep their fresh embeddings; new parameter slots get zero MLP input columns."""
    from backend.training.unet import UNet
    from backend.training.warm_start import warm_start

    torch.manual_seed(0)
    small = UNet(3, 2, emb_dim=4, widths=(8, 16, 16))
    big = UNet(5, 4, emb_dim=4, widths=(8, 16, 16))
    fresh = big.class_emb.weight.detach().clone()
    warm_start(big, {k: v.numpy() for k, v in small.state_dict().items()})
    assert torch.equal(big.class_emb.weight[:3], small.class_emb.weight)
    assert torch.equal(big.class_emb.weight[3:], fresh[3:])
    w_big, w_small = big.cond_mlp[0].weight, small.cond_mlp[0].weight
    assert torch.equal(w_big[:, :6], w_small) and not w_big[:, 6:].any()
    # same output for the old classes with the new slots at any value
    x, t = torch.randn(1, 1, 16, 16), torch.tensor([300.0])
    ids = torch.full((1, 16, 16), 2)
    p_small = torch.rand(1, 2, 16, 16)
    p_big = torch.cat([p_small, torch.rand(1, 2, 16, 16)], 1)
    with torch.no_grad():
        a = small(x, t, small.embed(ids, p_small))
        b = big(x, t, big.embed(ids, p_big))
    assert torch.allclose(a, b, atol=1e-5)
    with pytest.raises(ValueError, match="init_onnx: init.weight has shape"):
        warm_start(UNet(3, 2, emb_dim=4, widths=(16, 16, 16)), {k: v.numpy() for k, v in small.state_dict().items()})


def test_evaluation_at_a_chosen_size_batches_each_sample_with_its_own_seed(exported, tmp_path):
    """bench/eval_neural.py's evaluate(): at --eval-size (not the training size), with the structure measures;
    a class's samples, generated as one batch, equal the same seeds generated one by one."""
    from backend.neural.sampler import sample
    from backend.training.evaluate import evaluate

    _, out = exported
    m = NeuralNoiseModel(str(out))
    res = evaluate(m, ("perlin", "spots"), n=3, steps=2, clf_steps=3, log=lambda s: None, size=24,
                   classifier_cache=str(tmp_path), clf_stages=3, clf_threads=1)
    assert res["size"] == 24 and res["classifier"] == dict(steps=3, stages=3, threads=1)
    for r in res["classes"].values():
        assert set(r) >= {"fd", "acc", "psd", "psd_low", "coherence", "coherence_zoo", "response"}
        assert 0.0 <= r["coherence"] <= 1.0 and np.isfinite(r["psd_low"])
    assert list(tmp_path.glob("classifier_*.pt"))  # the 3-stage instrument is cached for the next model
    eps = m.eps_fn(False)
    cond = np.stack([C.uniform(m, ("spots", {"scale": v}), 24, 24) for v in (4.0, 9.0)])
    x0 = np.concatenate([initial_noise(1000 + i, (1, 1, 24, 24)) for i in range(2)])
    both = sample("dpmpp_2m", eps, x0, cond, 3, alphas_cumprod=m.alphas_cumprod)
    one = sample("dpmpp_2m", eps, x0[1:], cond[1:].copy(), 3, alphas_cumprod=m.alphas_cumprod)
    np.testing.assert_allclose(both[1:], one, atol=1e-4)


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


def test_animation_hits_its_keyframes_and_moves_smoothly_between_them(exported, tmp_path):
    """Issue 26: frames at keyframes equal plain generation; frames between move in small, even steps."""
    from backend.neural.animate import animate, frame_cond, frame_latent, parse_keys, temporal_coherence
    import tomllib

    _, out = exported
    m = NeuralNoiseModel(str(out))
    keys = parse_keys(tomllib.loads(KEYS))
    assert [k.frame for k in keys] == [1, 7] and keys[0].params == {"scale": 4.0}
    frames = dict(animate(m, keys, (0, 8), 16, 16, latent="fixed", steps=4))
    assert sorted(frames) == list(range(0, 9))
    # keyframes: the plain image of the key's spec from the first key's seed
    np.testing.assert_array_equal(frames[1], generate(m, C.uniform(m, ("perlin", {"scale": 4.0}), 16, 16), seed=2,
                                                       steps=4))
    np.testing.assert_array_equal(frames[7], generate(m, C.uniform(m, ("cells_f1", {}), 16, 16), seed=2, steps=4))
    np.testing.assert_array_equal(frames[0], frames[1])  # held before the first key and after the last
    np.testing.assert_array_equal(frames[8], frames[7])
    # halfway: the conditioning is the w = 1/2 blend
    half = frame_cond(m, keys, 4, 16, 16)
    np.testing.assert_allclose(half, C.blend(m, keys[0].spec, keys[1].spec, np.full((16, 16), 0.5)), atol=1e-6)
    seq = [frames[f] for f in range(1, 8)]
    other = generate(m, C.uniform(m, ("perlin", {"scale": 4.0}), 16, 16), seed=77, steps=4)
    coh = temporal_coherence(seq, float(np.abs(other - frames[1]).mean()))
    assert coh["step_over_independent"] < 0.5, coh  # far from flicker
    # latents: slerp goes from one key's seed to the other's, keeping the norm; drift circles
    a, b = frame_latent(keys, 1, (16, 16), "slerp"), frame_latent(keys, 7, (16, 16), "slerp")
    mid = frame_latent(keys, 4, (16, 16), "slerp")
    assert np.linalg.norm(mid) == pytest.approx((np.linalg.norm(a) + np.linalg.norm(b)) / 2, rel=0.05)
    assert np.abs(mid - a).mean() > 0.1 and np.abs(mid - b).mean() > 0.1
    d0, d1 = frame_latent(keys, 1, (16, 16), "drift", 0.1), frame_latent(keys, 2, (16, 16), "drift", 0.1)
    assert 0 < np.abs(d1 - d0).mean() < 0.2 * np.abs(d0).mean()


def test_animation_cli_writes_numbered_frames_and_refuses_bad_input(exported, tmp_path, capsys):
    _, out = exported
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


def test_animation_in_a_job_file_equals_the_cli_frames(exported, tmp_path):
    """A job with keys and frames bakes the same frames as `neural --keys --frames` (the job's time is the
    frame number); the keys enter the bake key, and blend with keys is refused."""
    from backend.jobs import load_job, run_job

    _, out = exported
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
    from backend.sources import describe
    from export.images import write_png

    assert '"spots"' in describe(spec.source) and '"latent":"slerp"' in describe(spec.source)  # in the bake key
    write_png(str(tmp_path / "mask.png"), np.zeros((16, 16), np.uint8))
    job.write_text(inline.replace('latent = "slerp"', 'latent = "slerp"\nblend = "mask.png"'))
    (_, bad), = load_job(str(job))
    assert "source.keys: keyframes set the classes of the whole image; leave out blend" in str(bad)

