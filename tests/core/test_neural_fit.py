"""Inverse design without torch: the texture statistic, input checks, the zoo bank, the search and the CLI."""
import json
import os
import shutil

import numpy as np
import pytest

from omninoise.cli.main import main
from omninoise.backend.errors import SettingError
from omninoise.backend.grid import Cancelled
from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.fit import (bank_nearest, describe, distance, fit, fitted_conditioning, load_bank,
                                prepare_target)
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.onnx_models import ModelError
from omninoise.backend.paths import fit_bank, neural_model


@pytest.fixture(scope="module")
def model():
    return NeuralNoiseModel(neural_model(), threads=2)


def _stripes(f, n=64, angle=0.0):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    return (0.5 + 0.5 * np.sin(2 * np.pi * f * (np.cos(angle) * x + np.sin(angle) * y))).astype(np.float32)


def test_the_statistic_sees_feature_size_orientation_and_levels():
    coarse, fine = describe(_stripes(2 / 64)), describe(_stripes(16 / 64))
    assert np.argmax(coarse["spectrum"]) < np.argmax(fine["spectrum"])  # finer features: higher bands
    assert abs(np.sum(coarse["spectrum"] ** 2) - 1) < 1e-9  # shares of the power
    white = describe(np.random.default_rng(0).random((64, 64)).astype(np.float32))
    assert coarse["coherence"][0] > 0.9 > 0.5 > white["coherence"][0]  # stripes are oriented, white noise is not
    turned = describe(_stripes(4 / 64, angle=np.pi / 2))
    assert distance(turned, describe(_stripes(4 / 64))) < 0.05  # rotation does not matter
    binary = describe((_stripes(4 / 64) > 0.5).astype(np.float32))
    assert np.ptp(binary["levels"]) == 1.0 and distance(binary, binary) == 0.0
    assert distance(coarse, fine) == distance(fine, coarse) > 0.5


def test_targets_are_checked_and_converted_with_a_note():
    ramp = np.linspace(0, 1, 480, dtype=np.float32).reshape(20, 24)
    grey, notes = prepare_target(ramp[..., None] * [0.5, 1.0, 1.5], 8, "photo.png")
    assert grey.shape == (20, 24) and np.allclose(grey, np.clip((ramp - 0.01) / 0.98, 0, 1), atol=1e-5)
    assert notes == ["photo.png: colour converted to grey (the mean of its 3 channels)"]  # full range: no stretch
    pale, notes = prepare_target(0.6 + 0.1 * ramp, 8)
    assert pale.min() == 0 and pale.max() == 1 and "stretched from [0.601, 0.699]" in notes[0]
    for img, msg in [(np.zeros((12, 40)), "40x12 px; fitting needs at least 16x16"), (np.full((20, 20), np.nan), "NaN"),
                     (np.zeros((4, 4, 4, 4)), "expected an image"), (np.full((20, 20), 0.3), "flat")]:
        with pytest.raises(SettingError, match=msg):
            prepare_target(img, 8)


def test_the_shipped_bank_is_checked_and_finds_its_own_images(model, tmp_path):
    bank = load_bank(fit_bank())
    assert set(bank["classes"]) == set(model.config["trained_classes"]) and bank["size"] == 64
    for row in (0, len(bank["cls"]) // 2, len(bank["cls"]) - 1):
        own = {k: bank[k][row].astype(np.float64) for k in ("spectrum", "levels", "edges", "coherence")}
        name = bank["classes"][bank["cls"][row]]
        d, u = bank_nearest(bank, own)[name]
        assert d < 1e-5 and np.array_equal(u, bank["u"][row])
    copy = tmp_path / "bank"
    shutil.copytree(fit_bank(), copy)
    with open(copy / "bank.npz", "r+b") as fh:
        fh.seek(100)
        fh.write(b"\x00" * 8)
    with pytest.raises(ModelError, match="sha256 does not match"):
        load_bank(str(copy))


@pytest.mark.long
def test_the_fit_improves_on_its_start_and_the_cli_gives_the_same(model, tmp_path, capsys):
    target = generate(model, C.uniform(model, ("spots", {"scale": 12.0}), 32, 32), seed=3, steps=6)
    res = fit(model, target, seed=0)  # 32 px: smaller than the bank's 64, so every class is tried
    first = res.trace[0]
    assert first["stage"] == "classes" and len(first["distances"]) == len(model.config["trained_classes"])
    assert res.distance <= min(first["distances"].values()) + 1e-4 and res.fit_size == 32  # trace rounds to 1e-4
    assert abs(sum(res.classes.values()) - 1) < 1e-6 and 1 <= len(res.classes) <= 2
    for name, values in res.params.items():
        spec = {q["name"]: q for q in model.class_params[name]["params"]}
        assert set(values) == set(spec) and all(spec[k]["min"] <= v <= spec[k]["max"] for k, v in values.items())
    assert fitted_conditioning(model, res, 16, 24).shape == (model.embedding.shape[1] + len(model.params), 16, 24)
    np.save(tmp_path / "t.npy", target)
    assert main(["neural", "--fit", str(tmp_path / "t.npy"), "--fit-size", "32", "--size", "32", "-o",
                 str(tmp_path / "f.png"), "--report", str(tmp_path / "f.json"), "--quiet"]) == 0
    rep = json.load(open(tmp_path / "f.json"))
    assert rep["classes"] == res.classes and rep["seed"] == res.seed and rep["params"] == res.params
    assert rep["command"].startswith("omninoise neural --noise ") and os.path.isfile(tmp_path / "f.png")
    np.save(tmp_path / "c.npy", np.repeat(target[..., None], 3, axis=2) * 0.5 + 0.25)   # colour, low contrast
    capsys.readouterr()
    assert main(["neural", "--fit", str(tmp_path / "c.npy"), "--fit-size", "32", "--size", "32", "-o",
                 str(tmp_path / "c.png"), "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")                  # --quiet: no bar, no notes (grey, stretched), no summary
    with pytest.raises(Cancelled):
        fit(model, target, cancel=lambda: True)


@pytest.mark.parametrize("args, msg", [
    (["--report", "r.json", "--noise", "perlin", "-o", "o.png"], "a fit report needs --fit IMAGE"),
    (["--fit", "missing.png", "-o", "o.png"], "image not found"),
    (["--fit", "small.png", "-o", "o.png"], "small.png: 10x10 px"),
    (["--fit", "small.png", "--noise", "perlin", "-o", "o.png"],
     "--noise: is the class of the whole image, or of a blend's unmasked part; with --fit, it would change nothing"),
    (["--fit", "small.png", "--blend", "small.png", "-o", "o.png"], "leave out --noise, --gradient, --corners, --map and --blend"),
    (["--fit", "small.png", "--param", "scale=4", "-o", "o.png"],
     "--param: sets the parameters of --noise; with --fit"),
    (["--noise", "perlin", "--fit-size", "32", "-o", "o.png"], "--fit-size: a fit window size needs --fit IMAGE"),
    (["--fit", "small.png", "-o", "o.vdb"], "-o: a neural noise image is written as .png, .exr, .npy, not '.vdb'"),
])
def test_fit_errors_name_what_is_wrong(args, msg, tmp_path, capsys, monkeypatch):
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    Image.fromarray(np.zeros((10, 10, 3), np.uint8)).save("small.png")
    assert main(["neural"] + args) == 2
    assert msg in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["small.png"]
