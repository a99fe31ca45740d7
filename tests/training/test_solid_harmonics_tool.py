"""python -m omninoise.training.solid.harmonics: a single photo model's stored harmonic part is measured again, exactly,
from its exemplar's training region; --remove takes it out; other models are refused with one line."""
import json
import os
import shutil

import numpy as np

import pytest

torch = pytest.importorskip("torch")  # omninoise.training needs torch

from omninoise.training.solid.harmonics import main, measure

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BRICK = os.path.join(ROOT, "models", "solid", "brick_3d")


def same(a, b) -> bool:
    """JSON values equal, their numbers to 1e-9 relative (the last bits of a sum differ between CPUs' BLAS
    kernels: the stored parts were measured on one machine and are checked on others)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, (int, float)) and not isinstance(a, bool):
        return isinstance(b, (int, float)) and bool(np.isclose(a, b, rtol=1e-9, atol=1e-12))
    return a == b


def test_the_shipped_part_is_what_the_command_measures():
    with open(os.path.join(BRICK, "solid.json"), encoding="utf-8") as f:
        stored = json.load(f)["harmonics"]
    measured = json.loads(json.dumps(measure(BRICK, ROOT)))
    assert same(measured, stored)
    # the comparison sees a real change: one amplitude moved by a millionth
    moved = json.loads(json.dumps(stored))
    moved["amp"][0][0] += 1e-6
    assert not same(measured, moved)


def test_the_space_models_named_parts_are_what_the_command_measures(tmp_path, capsys):
    """The texture-space model stores a part per named code whose photo has one (metal plates, planks, ...),
    measured from the photo that names it, and the Gaussian rest its check keeps (backend/solid/gaussian_rest.py);
    the command rewrites them the same, and refuses a photo set whose photos no longer encode to the stored
    codes."""
    space = os.path.join(ROOT, "models", "solid", "space")
    with open(os.path.join(space, "solid.json"), encoding="utf-8") as f:
        doc = json.load(f)
    stored, rests = doc["code_harmonics"], doc["code_rests"]
    assert doc["spin"] == "octave"        # the rests were measured as the model draws: its octaves turned
    assert {"metal", "wood"} <= set(stored) and {"sand", "metal"} <= set(rests) and "rock" not in rests
    folder = tmp_path / "space"      # removed, then measured again from the photos: what is stored
    said = remove_and_add_back(space, folder, "code_harmonics", capsys)
    assert "metal 141 waves" in said and "Gaussian rests: brick 1.00" in said
    back = json.loads((folder / "solid.json").read_text())
    assert same(back["code_harmonics"], stored) and same(back["code_rests"], rests)
    train = os.path.join(ROOT, "data", "photos", "train")
    other = tmp_path / "other"
    (other / "data" / "photos" / "train").mkdir(parents=True)
    for f in os.listdir(train):        # the same photo set, but another photo in metal's place
        src = os.path.join(train, "wood__bridge_wood_b.jpg" if f == "metal__metal_plates.jpg" else f)
        os.symlink(src, other / "data" / "photos" / "train" / f)
    assert main([str(folder), "--root", str(other)]) == 2
    assert "does not encode to the stored code 'metal'" in capsys.readouterr().err
    # --spin measures the folder as it will be, and leaves it untouched when measuring fails
    before = (folder / "solid.json").read_text()
    assert main([str(folder), "--root", str(other), "--spin", "none"]) == 2
    assert (folder / "solid.json").read_text() == before


def remove_and_add_back(model: str, folder, key: str, capsys) -> str:
    """A copy of ``model`` in ``folder`` with its stored part(s) ``key`` removed by the command (checked gone),
    then measured again: what the command printed."""
    shutil.copytree(model, folder)
    assert main([str(folder), "--remove", "--root", ROOT]) == 0
    assert key not in json.loads((folder / "solid.json").read_text())
    assert main([str(folder), "--root", ROOT]) == 0
    return capsys.readouterr().out


def test_remove_and_add_back(tmp_path, capsys):
    folder = tmp_path / "brick_3d"
    assert "11 waves, share 0.403" in remove_and_add_back(BRICK, folder, "harmonics", capsys)
    with open(os.path.join(BRICK, "solid.json"), encoding="utf-8") as f:
        shipped = json.load(f)
    back = json.loads((folder / "solid.json").read_text())
    assert back.pop("json_sha256") and shipped.pop("json_sha256")    # each seals its own numbers' last bits
    assert same(back, shipped)


def test_a_model_without_the_photos_colour_is_refused(tmp_path, capsys):
    folder = tmp_path / "tiny"
    shutil.copytree(os.path.join(ROOT, "tests", "data", "tiny_solid", "single3"), folder)
    before = (folder / "solid.json").read_text()
    assert main([str(folder)]) == 2
    err = capsys.readouterr().err
    assert "is not a single photo model" in err and err.count("\n") == 1
    assert (folder / "solid.json").read_text() == before
