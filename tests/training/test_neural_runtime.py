"""Neural noise runtime: ONNX export (split and one-piece) vs torch, hash check, samplers, conditioning grids,
any size, tiling, CLI."""
import json
import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.generate import generate  # noqa: E402
from omninoise.backend.neural.model import ModelError, NeuralNoiseModel  # noqa: E402
from omninoise.backend.neural.sampler import ddim_sample, initial_noise  # noqa: E402
from omninoise.backend.onnx_models import fingerprint  # noqa: E402
from omninoise.training.export_onnx import export, reexport  # noqa: E402
from omninoise.training.train import TrainConfig, build_model, train  # noqa: E402
from omninoise.training.unet import set_circular  # noqa: E402
from omninoise.backend.onnx_models import sealed

from tiny_run import TINY  # noqa: E402  (the run itself: the `exported` fixture of tests/training/conftest.py)


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
    assert sorted(split.config["files"]) == ["denoiser.onnx", "denoiser.weights", "denoiser_tile.onnx", "encoder.onnx"]
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
        (tmp_path / "neural_noise.json").write_text(json.dumps(sealed(dict(doc, **change))))
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


# an evaluation document as python -m bench neural-eval writes it, one class, for the card tests
EVAL = dict(classes={"spots": dict(fd=1.5, acc=0.5, psd=0.2, response=0.1, param="scale")}, zoo_accuracy=0.9,
            seam_tileable=1.1, seam_plain=3.0, locality=0.75, model=dict(n=4, steps=5),
            timing=dict(size=64, onnxruntime_s=0.1, torch_s=0.2, ratio=2.0, max_eps_difference=1e-6))


def test_model_card_reads_the_run_export_and_evaluation(exported, tmp_path):
    from omninoise.training.model_card import card, wall_seconds

    run, out = exported
    log = tmp_path / "log.jsonl"
    log.write_text("\n".join(json.dumps(dict(step=i, seconds=s, mse=0.1)) for i, s in enumerate([5, 10, 3, 7])))
    assert wall_seconds(str(log)) == 17  # two segments: 10 s, then a resume for 7 s
    ev = EVAL
    text = card(str(run), str(out), ev, dict(ev, locality=0.5), "python -m omninoise.training.train ...", "test CPU")
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

    from omninoise.training.model_card import main as card_main, run_figures, wall_seconds

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
    (old / "neural_noise.json").write_text(json.dumps(sealed(doc)))
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
    from omninoise.training.model_card import kept_sections

    old = "# Card\n\nintro\n\n## A\n\nfirst | table\n\n## B (Fig. 13)\n\nsecond\n\n## C\n\nthird\n"
    assert kept_sections(old, ["B (Fig. 13)", "A"]) == "## B (Fig. 13)\n\nsecond\n\n## A\n\nfirst | table"
    with pytest.raises(ValueError, match="no section '## D'"):
        kept_sections(old, ["D"])


@pytest.mark.parametrize("form", ["split", "one-piece"])
def test_warm_start_reads_an_export_back_exactly(exported, one_piece, tmp_path, form):
    """A run started from an export (init_onnx) begins with the exported EMA weights, GroupNorm affines included."""
    from omninoise.backend.neural.model import sha256_file
    from omninoise.training.train import main as train_main

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
    from omninoise.training.evaluate import step_seconds
    from omninoise.training.warm_start import torch_from_export

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
    from omninoise.training.unet import UNet
    from omninoise.training.warm_start import warm_start

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
    """python -m bench neural-eval's evaluate(): at --eval-size (not the training size), with the structure measures;
    a class's samples, generated as one batch, equal the same seeds generated one by one."""
    from omninoise.backend.neural.sampler import sample
    from omninoise.training.evaluate import evaluate

    _, out = exported
    m = NeuralNoiseModel(str(out))
    res = evaluate(m, ("perlin", "spots", "fibers"), n=3, steps=2, clf_steps=3, log=lambda s: None, size=24,
                   classifier_cache=str(tmp_path), clf_stages=3, clf_threads=1)
    assert res["size"] == 24 and res["classifier"] == dict(steps=3, stages=3, threads=1)
    for r in res["classes"].values():
        assert set(r) >= {"fd", "acc", "psd", "psd_low", "coherence", "coherence_zoo", "response"}
        assert 0.0 <= r["coherence"] <= 1.0 and np.isfinite(r["psd_low"])
    # the oriented class alone is asked for directions, on its own parameter
    assert [n for n, r in res["classes"].items() if "direction_error" in r] == ["fibers"]
    assert res["classes"]["fibers"]["direction_param"] == "orientation"
    assert 0.0 <= res["classes"]["fibers"]["direction_error"] <= 90.0
    assert list(tmp_path.glob("classifier_*.pt"))  # the 3-stage instrument is cached for the next model
    eps = m.eps_fn(False)
    cond = np.stack([C.uniform(m, ("spots", {"scale": v}), 24, 24) for v in (4.0, 9.0)])
    x0 = np.concatenate([initial_noise(1000 + i, (1, 1, 24, 24)) for i in range(2)])
    both = sample("dpmpp_2m", eps, x0, cond, 3, alphas_cumprod=m.alphas_cumprod)
    one = sample("dpmpp_2m", eps, x0[1:], cond[1:].copy(), 3, alphas_cumprod=m.alphas_cumprod)
    np.testing.assert_allclose(both[1:], one, atol=1e-4)
    # --only: the rows of a full run for those classes (same classifier and samples), without seams or locality
    part = evaluate(m, ("perlin", "spots", "fibers"), n=3, steps=2, clf_steps=3, log=lambda s: None, size=24,
                    classifier_cache=str(tmp_path), clf_stages=3, clf_threads=1, only=("spots",))
    assert list(part["classes"]) == ["spots"] and part["classes"]["spots"] == res["classes"]["spots"]
    assert part["locality"] is None and part["seam_tileable"] is None




def test_constant_grids_are_encoded_small_and_expanded_exactly(exported, monkeypatch):
    """A one-class grid is encoded on a small grid and expanded: the maps equal the full encoder's (plain and
    circular padding, non-square sizes); any other grid runs the full encoder."""
    _, out = exported
    m = NeuralNoiseModel(str(out))
    side = (2 * m.EDGE + 2) << max(m.config["blocks"]["levels"])
    for H, W in ((side + 8, side + 24), (side + 40, side + 8)):
        cond = C.uniform(m, ("spots", {"scale": 6.0}), H, W)[None]
        assert m._small_grid(cond) == side
        for tile in (False, True):
            full, fast = m._encode(np.ascontiguousarray(cond), tile), m.encode(cond, tile)
            assert list(full) == list(fast)
            for k in full:
                assert fast[k].shape == full[k].shape and fast[k].dtype == np.float32
                np.testing.assert_allclose(fast[k], full[k], atol=1e-6)
    mixed = C.blend(m, ("spots", {}), ("perlin", {}), np.linspace(0, 1, side + 8)[None].repeat(side + 8, 0))[None]
    assert m._small_grid(mixed) is None
    small = C.uniform(m, ("spots", {}), side, side)[None]
    assert m._small_grid(small) is None  # no smaller grid to encode
    monkeypatch.setattr(m, "_expand", lambda *a: pytest.fail("a blend is not constant"))
    m.encode(mixed)


def test_denoiser_graph_does_no_per_step_copies(exported):
    """The per-step graph reads 1 + γ and β as inputs of their own (no Slice of the maps) and the plain denoiser
    pads inside its convolutions (no Pad op): both were copies of full tensors at every step."""
    import onnx

    _, out = exported
    doc = NeuralNoiseModel(str(out)).config["blocks"]
    assert doc["tensors"][:2] == ["m00g", "m00b"] and len(doc["tensors"]) == 2 * len(doc["names"])
    g = onnx.load(str(out / "denoiser.onnx"), load_external_data=False).graph
    assert "Pad" not in [n.op_type for n in g.node]
    assert [i.name for i in g.input] == ["x", "t"] + doc["tensors"]
    for path in ("denoiser.onnx", "denoiser_tile.onnx"):  # the time embedding's tiny vectors are still sliced
        nodes = onnx.load(str(out / path), load_external_data=False).graph.node
        assert not [n.name for n in nodes if n.op_type == "Slice" and n.input[0] in doc["tensors"]]
        assert sum(n.op_type == "Slice" for n in nodes) >= 2  # the check above looks at real Slice nodes


def test_exported_denoiser_is_folded(exported):
    """The per-step graphs are the folded form (training.unet): no transpose of a pixel unshuffle, and no
    multiply by one or add of zero (what the exporter writes for a norm without an affine); torch rebuilt from
    the export has the unfolded 1x1 downsampling weights back."""
    import onnx
    from onnx import numpy_helper

    _, out = exported
    for path in ("denoiser.onnx", "denoiser_tile.onnx"):
        g = onnx.load(str(out / path), load_external_data=False).graph
        ops = [n.op_type for n in g.node]
        assert "Transpose" not in ops and ops.count("Conv") >= 3
        consts = {n.output[0]: numpy_helper.to_array(n.attribute[0].t) for n in g.node if n.op_type == "Constant"}
        for n in g.node:
            if n.op_type in ("Mul", "Add"):
                for i in n.input:
                    v = consts.get(i)
                    assert v is None or v.size != 1 or float(v.reshape(())) != (n.op_type == "Mul"), n.name
    from omninoise.training.warm_start import torch_from_export

    m = torch_from_export(str(out))
    assert tuple(m.downsample[0][1].weight.shape[2:]) == (1, 1)


def test_drop_identity_arithmetic_keeps_what_changes_values_or_shapes(tmp_path):
    """Mul by 1 and Add of 0 go; a multiply by 2 stays, and so does a multiply by a one of higher rank
    than the other operand (it broadcasts the shape up); the function is unchanged."""
    import onnx
    import onnxruntime as ort
    from onnx import TensorProto, helper

    from omninoise.training.export_onnx import drop_identity_arithmetic

    def const(name, value, shape):
        return helper.make_node("Constant", [], [name], value=helper.make_tensor(name + "_v", TensorProto.FLOAT, shape,
                                                                                [value] * int(np.prod(shape))))
    nodes = [const("one", 1.0, [1, 1, 1]), const("zero", 0.0, [1]), const("two", 2.0, [1]),
             const("one5", 1.0, [1, 1, 1, 1, 1]),
             helper.make_node("Mul", ["x", "one"], ["a"]), helper.make_node("Add", ["zero", "a"], ["b"]),
             helper.make_node("Mul", ["b", "two"], ["c"]), helper.make_node("Mul", ["c", "one5"], ["y"])]
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 2, 3, 4])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, None)])
    path = str(tmp_path / "g.onnx")
    onnx.save(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)], ir_version=8), path)
    x = np.random.default_rng(0).standard_normal((1, 2, 3, 4)).astype(np.float32)
    before = ort.InferenceSession(path, providers=["CPUExecutionProvider"]).run(None, {"x": x})[0]
    assert drop_identity_arithmetic(path) == 2
    ops = [n.op_type for n in onnx.load(path).graph.node]
    assert ops.count("Mul") == 2 and "Add" not in ops and ops.count("Constant") == 2
    after = ort.InferenceSession(path, providers=["CPUExecutionProvider"]).run(None, {"x": x})[0]
    assert after.shape == before.shape == (1, 1, 2, 3, 4) and np.array_equal(after, before)
