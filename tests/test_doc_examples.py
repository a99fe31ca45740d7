"""The Python examples of the README and the API guide run as written, in a folder holding the files they name
(a photo, a job file), with the package installed or from this checkout."""
import os
import re
import shutil

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
JOB = """[[bake]]
name = "clouds"
output = "out/clouds.exr"
resolution = [32, 32]
transfer = "clouds"
[bake.source]
kind = "wave"
"""


def blocks(path: str) -> list:
    with open(os.path.join(ROOT, path), encoding="utf-8") as fh:
        return re.findall(r"```python\n(.*?)```", fh.read(), re.S)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    shutil.copy(os.path.join(ROOT, "data", "photos", "val", "brick__beige_bricks.jpg"), tmp_path / "photo.jpg")
    (tmp_path / "job.toml").write_text(JOB)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("path", ["README.md", "docs/guide/api.md"])
def test_the_python_examples_run(path, folder, capsys):
    code = blocks(path)
    assert code, f"{path} holds no Python example"
    env = {"points": np.random.default_rng(0).uniform(-1, 1, (64, 3))}
    for block in code:
        exec(compile(block, f"{path} example", "exec"), env)
    for f in ("marble.exr",) if path == "README.md" else ("clouds.npy", "marble.exr", "damascus.exr", "rock.npy"):
        assert (folder / f).is_file(), f
    if path == "README.md":
        assert env["img"].shape == (512, 512) and env["vol"].shape == (128, 128, 128)
        assert env["cells"].shape == (256, 256) and env["rgb"].shape == (256, 256, 3)
        assert [(o.name, o.status) for o in env["outcomes"]] == [("clouds", "baked")]
    else:
        assert env["values"].shape == (64,) and np.isfinite(env["values"]).all()
        assert env["blend"].shape == (128, 128) and np.isfinite(env["blend"]).all()
        assert env["vol"].shape == (64, 64, 64, 3)
