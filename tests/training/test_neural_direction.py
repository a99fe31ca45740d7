"""The direction benches on the committed tiny model. bench/neural_direction_sheet.py: a row per oriented class, the
zoo's column follows the asked direction, every model gets a direction and an error per asked direction.
bench/neural_direction_gain.py: the ideal gain of knowing the direction grows from the noisy end, and a model's
errors with the right and the turned direction are measured on the same noise."""
import json
import os
import subprocess
import sys

import pytest

pytest.importorskip("torch")  # the zoo's ground truth

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_direction_sheet_measures_each_asked_direction(tmp_path):
    out = tmp_path / "dir.png"
    tiny = os.path.join(ROOT, "tests", "data", "tiny_neural")
    cmd = [sys.executable, os.path.join(ROOT, "bench", "neural_direction_sheet.py"), str(out), "--model", tiny,
           "--label", "tiny", "--size", "64", "--threads", "1"]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    rep = json.loads((tmp_path / "dir.json").read_text())
    assert rep["columns"] == ["zoo", "tiny"] and rep["directions"] == [0.0, 45.0, 90.0, 135.0]
    assert set(rep["classes"]) == {"fibers", "phasor", "gabor", "gabor_texture"}
    fibers = rep["classes"]["fibers"]
    assert fibers["param"] == "orientation" and rep["classes"]["gabor_texture"]["param"] == "Orientation"
    assert max(fibers["zoo"]["error"]) == 0.0  # the zoo is its own reference
    # the zoo's direction follows the asked one (gradients lie across the fibres: modulo 180 either way)
    steps = [(b - a) % 180 for a, b in zip(fibers["zoo"]["direction"], fibers["zoo"]["direction"][1:])]
    assert all(abs(s - 45) < 12 for s in steps), fibers["zoo"]["direction"]
    assert len(fibers["tiny"]["error"]) == 4 and 0 <= fibers["tiny"]["mean_error"] <= 90
    from PIL import Image

    assert Image.open(out).size == (4 * (2 * (64 + 4) + 8), 4 * (64 + 4))
    bad = subprocess.run(cmd + ["--label", "extra"], capture_output=True, text=True, cwd=ROOT)
    assert bad.returncode != 0 and "one --label per --model" in bad.stderr


def test_direction_gain_bench(tmp_path):
    out = tmp_path / "gain.json"
    tiny = os.path.join(ROOT, "tests", "data", "tiny_neural")
    cmd = [sys.executable, os.path.join(ROOT, "bench", "neural_direction_gain.py"), "--model", tiny, "--size", "32",
           "--n", "6", "--threads", "1", "-o", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    rep = json.loads(out.read_text())
    ideal = rep["ideal"]
    assert [row["t"] for row in ideal] == sorted((row["t"] for row in ideal), reverse=True)
    gains = [row["mixture"] / row["known"] - 1 for row in ideal]
    assert all(g >= -1e-9 for g in gains) and gains[-1] > gains[0] and gains[-1] > 0.1  # the known direction helps more
    rows = rep["models"][tiny]
    assert len(rows) == len(ideal) and all(row["right"] > 0 and row["turned"] > 0 for row in rows)
    bad = subprocess.run(cmd[:-2] + ["--noise", "perlin"], capture_output=True, text=True, cwd=ROOT)
    assert bad.returncode != 0 and "--noise must be one of" in bad.stderr
