"""python -m training.solid.harmonics: a single photo model's stored harmonic part is measured again, exactly,
from its exemplar's training region; --remove takes it out; other models are refused with one line."""
import json
import os
import shutil

from training.solid.harmonics import main, measure

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BRICK = os.path.join(ROOT, "models", "solid", "brick_3d")


def test_the_shipped_part_is_what_the_command_measures():
    with open(os.path.join(BRICK, "solid.json"), encoding="utf-8") as f:
        stored = json.load(f)["harmonics"]
    assert json.loads(json.dumps(measure(BRICK, ROOT))) == stored


def test_remove_and_add_back(tmp_path, capsys):
    folder = tmp_path / "brick_3d"
    shutil.copytree(BRICK, folder)
    assert main([str(folder), "--remove", "--root", ROOT]) == 0
    assert "harmonics" not in json.loads((folder / "solid.json").read_text())
    assert main([str(folder), "--root", ROOT]) == 0
    assert "38 waves, share 0.374" in capsys.readouterr().out
    with open(os.path.join(BRICK, "solid.json"), encoding="utf-8") as f:
        assert json.loads((folder / "solid.json").read_text()) == json.load(f)


def test_a_model_without_the_photos_colour_is_refused(tmp_path, capsys):
    folder = tmp_path / "tiny"
    shutil.copytree(os.path.join(ROOT, "tests", "data", "tiny_solid", "single3"), folder)
    before = (folder / "solid.json").read_text()
    assert main([str(folder)]) == 2
    err = capsys.readouterr().err
    assert "is not a single photo model" in err and err.count("\n") == 1
    assert (folder / "solid.json").read_text() == before
