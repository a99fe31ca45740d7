"""One command trains the neural noise model's whole line of stages (training/line.py): each stage from the export
of the one before, resumable, the last export with its int8 denoisers; and the line file is the shipped line."""
import dataclasses
import json
import os

import pytest

from tiny_run import TINY

pytest.importorskip("torch")
pytest.importorskip("onnx")

from omninoise.backend.neural.model import NeuralNoiseModel  # noqa: E402
from omninoise.training import line  # noqa: E402
from omninoise.training.config import load_config  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHIPPED = os.path.join(ROOT, "configs", "neural_noise_line.json")


def _line(tmp_path, stages):
    for name, cfg in stages:
        (tmp_path / f"{name}.json").write_text(json.dumps(cfg))
    path = tmp_path / "line.json"
    path.write_text(json.dumps({"model": "neural_noise", "stages": [
        {"name": name, "config": f"{name}.json", "steps": cfg["steps"]} for name, cfg in stages]}))
    return str(path)


def test_the_line_trains_each_stage_from_the_export_before_and_goes_on_where_it_stopped(tmp_path):
    first = dict(TINY, classes=["perlin", "spots"])                 # the second stage grows the class table
    second = dict(TINY, steps=2, init_onnx="nowhere", init_sha256="0" * 64)   # the line's start replaces these
    path = _line(tmp_path, [("a", first), ("b", second)])
    logs = []
    model = line.run_line(line.load_line(path), str(tmp_path / "out"), log=logs.append)
    assert model == str(tmp_path / "out" / "b" / "export")
    a_doc = json.loads((tmp_path / "out" / "a" / "export" / "neural_noise.json").read_text())
    doc = json.loads((tmp_path / "out" / "b" / "export" / "neural_noise.json").read_text())
    assert a_doc["step"] == 3 and a_doc["trained_classes"] == ["perlin", "spots"]
    assert doc["step"] == 2 and doc["config"]["init_onnx"] == str(tmp_path / "out" / "a" / "export")
    assert any("started from " + str(tmp_path / "out" / "a" / "export") in ln for ln in logs)
    assert "int8" in doc and "int8" not in a_doc              # the line's model only gains the int8 denoisers
    assert NeuralNoiseModel(model).class_params                # the runtime loads it
    logs.clear()
    assert line.run_line(line.load_line(path), str(tmp_path / "out"), log=logs.append) == model
    assert logs == ["[1/2] a: done (%s)" % (tmp_path / "out" / "a" / "export"),
                    "[2/2] b: done (%s)" % (tmp_path / "out" / "b" / "export")]


def test_a_stage_stopped_partway_resumes_and_max_steps_caps_every_stage(tmp_path):
    path = _line(tmp_path, [("a", dict(TINY, steps=3))])
    out = tmp_path / "out"
    assert line.run_line(line.load_line(path), str(out), max_steps=1, log=lambda s: None)
    assert json.loads((out / "a" / "export" / "neural_noise.json").read_text())["step"] == 1
    logs = []                                                   # the whole stage: on from step 1
    line.run_line(line.load_line(path), str(out), log=logs.append)
    assert any("resumed at step 1" in ln for ln in logs)
    assert json.loads((out / "a" / "export" / "neural_noise.json").read_text())["step"] == 3


@pytest.mark.parametrize("entry, message", [
    ({"name": "A", "config": "a.json", "steps": 1}, "name must be a new name"),
    ({"name": "a", "config": "a.json", "steps": 0}, "steps must be a whole number >= 1"),
    ({"name": "a", "config": "a.json", "steps": 4}, "steps 4 is past its config's 3"),
    ({"name": "a", "config": "missing.json", "steps": 1}, "config missing.json"),
    ({"name": "a", "config": "a.json"}, "needs exactly name, config and steps"),
])
def test_a_bad_line_is_one_line_before_any_work(tmp_path, capsys, entry, message):
    (tmp_path / "a.json").write_text(json.dumps(dict(TINY, steps=3)))
    (tmp_path / "line.json").write_text(json.dumps({"stages": [entry]}))
    assert line.main([str(tmp_path / "line.json"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "out").exists()


def test_the_line_file_is_the_shipped_line():
    """Its last stage is the config and step the shipped weights record; every config reads."""
    stages = line.load_line(SHIPPED)
    shipped = json.loads(open(os.path.join(ROOT, "models", "neural_noise", "neural_noise.json")).read())
    last = stages[-1]
    assert shipped["step"] == last.steps
    strip = ("init_onnx", "init_sha256", "steps")
    ours = {k: v for k, v in dataclasses.asdict(load_config(last.config)).items() if k not in strip}
    theirs = {k: v for k, v in shipped["config"].items() if k not in strip}
    assert json.loads(json.dumps(ours)) == theirs
    assert [s.name for s in stages][:2] == ["classes8", "zoo"] and len(stages) == 10


def test_a_stage_whose_start_changed_trains_again(tmp_path):
    """A quick run (`--steps 1`) then the real one: the second stage's checkpoint began from the quick first stage,
    so it is trained again from the new export, not resumed."""
    path = _line(tmp_path, [("a", dict(TINY, steps=3)), ("b", dict(TINY, steps=2))])
    out = str(tmp_path / "out")
    line.run_line(line.load_line(path), out, max_steps=1, log=lambda s: None)
    logs = []
    line.run_line(line.load_line(path), out, log=logs.append)
    assert any("began from other weights than the stage before's export" in ln for ln in logs)
    assert not any("resumed" in ln for ln in logs if "b" in ln) and sum("resumed at step 1" in ln for ln in logs) == 1
    assert json.loads((tmp_path / "out" / "b" / "export" / "neural_noise.json").read_text())["step"] == 2
