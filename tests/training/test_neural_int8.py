"""int8 denoisers (training/quantize_onnx.py) and the runtime's precision choice (backend/neural/precision.py)."""
import json
import os
import shutil

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")

from omninoise.backend.errors import SettingError  # noqa: E402
from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural import precision as P  # noqa: E402
from omninoise.backend.neural.generate import generate  # noqa: E402
from omninoise.backend.neural.model import ModelError, NeuralNoiseModel, PrecisionUnavailable  # noqa: E402
from omninoise.training.quantize_onnx import INT8_FILES, calibration_feeds, quantize_folder  # noqa: E402
from tiny_run import TINY  # noqa: E402  (the export itself: the `exported` fixture of tests/training/conftest.py)


@pytest.fixture(scope="module")
def folders(exported, tmp_path_factory):
    """The tiny trained split export, and a copy of it with int8 denoisers."""
    fp32 = str(exported[1])
    int8 = tmp_path_factory.mktemp("int8")
    shutil.copytree(fp32, int8, dirs_exist_ok=True)
    section = quantize_folder(str(int8), size=32, log=lambda s: None)
    return fp32, str(int8), section


@pytest.fixture
def default_precision():
    """Restore the module default after a test changes it."""
    before = P.default_precision()
    yield
    P.set_default_precision(before)


def test_quantize_writes_int8_twins_and_keeps_the_weights_fingerprint(folders):
    fp32, int8, section = folders
    assert sorted(section["files"]) == sorted(INT8_FILES.values())
    a, b = NeuralNoiseModel(fp32, precision="fp32"), NeuralNoiseModel(int8, precision="fp32")
    assert a.fingerprint == b.fingerprint  # the fp32 files, which name the weights, are untouched
    with open(os.path.join(int8, "neural_noise.json"), encoding="utf-8") as fh:
        doc = json.load(fh)
    assert doc["int8"]["calibration"]["classes"] == list(TINY["classes"]) and doc["int8"]["calibration"]["size"] == 32
    # calibration inputs are real forward-process samples: every class at every listed timestep
    feeds = calibration_feeds(a, 16, False, timesteps=(999, 10))
    assert len(feeds) == 2 * len(TINY["classes"])
    late, early = feeds[0]["x"], feeds[1]["x"]
    assert abs(float(late.std()) - 1.0) < 0.25 and float(np.abs(early).max()) <= 1.2  # noise vs nearly x0


def test_int8_denoiser_tracks_fp32(folders):
    """ε of the int8 denoiser follows fp32 (plain and tileable), and whole images stay close."""
    _, int8, _ = folders
    f, q = NeuralNoiseModel(int8, precision="fp32"), NeuralNoiseModel(int8, precision="int8")
    assert (f.precision, q.precision) == ("fp32", "int8")
    assert q.denoiser_name(False) == "denoiser_int8.onnx" and q.denoiser_name(True) == "denoiser_tile_int8.onnx"
    feeds = calibration_feeds(f, 32, False, seed=5, timesteps=(700, 200))
    cond = C.uniform(f, ("spots", {}), 32, 32)[None]
    for tile in (False, True):
        for feed in feeds[:4]:
            a = f.eps_fn(tile)(feed["x"], feed["t"], cond)
            b = q.eps_fn(tile)(feed["x"], feed["t"], cond)
            assert np.corrcoef(a.ravel(), b.ravel())[0, 1] > 0.98
            assert float(np.abs(a - b).mean()) < 0.2 * float(np.abs(a).mean()) + 1e-3
    ia = generate(f, C.uniform(f, ("perlin", {}), 32, 32), seed=2, steps=6)
    ib = generate(q, C.uniform(q, ("perlin", {}), 32, 32), seed=2, steps=6)
    assert float(np.abs(ia - ib).mean()) < 0.05
    # deterministic: the same seed gives the same bytes
    assert np.array_equal(ib, generate(q, C.uniform(q, ("perlin", {}), 32, 32), seed=2, steps=6))


def test_precision_choice(folders, default_precision):
    fp32, int8, _ = folders
    assert NeuralNoiseModel(int8).precision == "fp32"  # float32 is the default, int8 files or not
    assert NeuralNoiseModel(int8, precision="int8").precision == "int8"
    P.set_default_precision("int8")
    assert NeuralNoiseModel(int8).precision == "int8"  # None: the module default (the CLI's --precision)
    assert NeuralNoiseModel(int8, precision="fp32").precision == "fp32"
    with pytest.raises(PrecisionUnavailable, match="quantize_onnx"):
        NeuralNoiseModel(fp32)  # int8 asked for by default, but this folder has no int8 files
    with pytest.raises(SettingError, match="precision"):
        NeuralNoiseModel(int8, precision="int4")
    with pytest.raises(SettingError, match="precision"):
        P.set_default_precision("half")


def test_cli_precision(folders, tmp_path, capsys, default_precision):
    """omninoise neural --precision int8 runs the int8 denoiser; the same command twice gives the same bytes."""
    from omninoise.cli.main import main

    _, int8, _ = folders
    outs = []
    for prec, name in (("int8", "a.npy"), ("int8", "b.npy"), ("fp32", "c.npy")):
        rc = main(["neural", "--model", int8, "--noise", "perlin", "--size", "32", "--steps", "4",
                   "--precision", prec, "-o", str(tmp_path / name), "--threads", "1"])
        assert rc == 0
        outs.append(np.load(tmp_path / name))
    assert np.array_equal(outs[0], outs[1]) and not np.array_equal(outs[0], outs[2])
    assert float(np.abs(outs[0] - outs[2]).mean()) < 0.05
    with pytest.raises(SystemExit):
        main(["neural", "--model", int8, "--noise", "perlin", "--precision", "half", "-o", str(tmp_path / "d.npy")])
    assert "invalid choice" in capsys.readouterr().err


def test_damaged_int8_file_is_refused(folders, tmp_path):
    _, int8, _ = folders
    bad = tmp_path / "bad"
    shutil.copytree(int8, bad)
    with open(bad / "denoiser_int8.onnx", "r+b") as fh:
        fh.seek(100)
        fh.write(b"\xff\xfe")
    NeuralNoiseModel(str(bad), precision="fp32")  # fp32 never reads it
    with pytest.raises(PrecisionUnavailable, match="denoiser_int8.onnx: sha256"):  # a ModelError the CLI
        NeuralNoiseModel(str(bad), precision="int8")  # reports as --precision, not as a bad --model
    os.remove(bad / "denoiser_int8.onnx")
    with pytest.raises(ModelError, match="missing"):
        NeuralNoiseModel(str(bad), precision="int8")


def test_cpu_detection_reads_the_flags():
    """int8_dot_products answers from this machine's CPU flags (VNNI), without raising anywhere."""
    P.int8_dot_products.cache_clear()
    got = P.int8_dot_products()
    flags = ""
    if os.path.isfile("/proc/cpuinfo"):
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            flags = next((ln for ln in fh if ln.startswith("flags")), "")
    assert got == (("avx512_vnni" in flags.split()) or ("avx_vnni" in flags.split()))
