"""bench/neural_solver_error.py on the committed tiny model: the reference against itself is 0, fewer steps are not."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_solver_error_bench_measures_distance_to_its_reference(tmp_path):
    out = tmp_path / "err.json"
    cmd = [sys.executable, os.path.join(ROOT, "bench", "neural_solver_error.py"), "--model",
           os.path.join(ROOT, "tests", "data", "tiny_neural"), "--size", "16", "--batch", "2", "--classes",
           "cells_f1,perlin", "--ref-steps", "12", "--threads", "1", "--cache", str(tmp_path / "cache"), "-o", str(out),
           "dpmpp_2m:12:logsnr", "ddim:2:uniform", "dpmpp_2m:4:truncated"]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads(out.read_text())["results"]
    assert res["dpmpp_2m:12:logsnr"]["max"] == 0.0  # the reference's own settings reproduce it exactly
    assert res["ddim:2:uniform"]["mean"] > 0 and res["dpmpp_2m:4:truncated"]["mean"] > 0
    assert res["dpmpp_2m:4:truncated"]["evaluations"] == 4 and res["ddim:2:uniform"]["evaluations"] == 2
    assert set(res["ddim:2:uniform"]["classes"]) == {"cells_f1", "perlin"}
    assert len(os.listdir(tmp_path / "cache")) == 1  # the reference is cached for the next run
    bad = subprocess.run(cmd[:-3] + ["dpmpp_2m-10"], capture_output=True, text=True, cwd=ROOT)
    assert bad.returncode != 0 and "write sampler:steps:spacing" in bad.stderr
