"""One command trains a model's whole line of stages (training/line.py): each stage from the export of the one
before, resumable, the last export finished (int8 denoisers, turned octaves); and the line files are the shipped
lines."""
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
SHIPPED = os.path.join(ROOT, "configs", "lines", "neural_noise.json")
SOLID = os.path.join(ROOT, "configs", "lines", "solid_space.json")
SINGLES = os.path.join(ROOT, "configs", "lines", "solid_singles.json")
#: a tiny solid texture config (tests/training/test_solid_model.py's)
TINY_SOLID = dict(name="tiny", mode="single", dim=3, crop=32, batch=2, steps=4, width=32, log_every=2,
                  checkpoint_every=2, threads=1, exemplars=["gravel"])
#: what a config that continues an export holds (a line puts the export of the stage before in their place)
CONTINUES = dict(init_onnx="nowhere", init_sha256="0" * 64)


def _line(tmp_path, stages, model="neural_noise", finish="int8", extra=()):
    for name, cfg in stages:
        (tmp_path / f"{name}.json").write_text(json.dumps(cfg))
    path = tmp_path / "line.json"
    path.write_text(json.dumps({"model": model, "finish": finish, "stages": [
        {"name": name, "config": f"{name}.json", "steps": cfg["steps"]} for name, cfg in stages] + list(extra)}))
    return str(path)


def test_the_line_trains_each_stage_from_the_export_before_and_goes_on_where_it_stopped(tmp_path):
    first = dict(TINY, classes=["perlin", "spots"])                 # the second stage grows the class table
    second = dict(TINY, steps=2, **CONTINUES)                       # the line's start replaces these
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
    path = _line(tmp_path, [("a", dict(TINY, steps=3))], finish="")
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
    ({"name": "a", "config": "a.json"}, "needs exactly name, config, steps"),
    ({"name": "a", "average": ["a", "b"]}, "needs exactly name, config, steps"),   # solid lines only
    ({"name": "a", "config": "a.json", "steps": 1, "finish": "harmonics"}, "finish must be one of int8"),
])
def test_a_bad_line_is_one_line_before_any_work(tmp_path, capsys, entry, message):
    (tmp_path / "a.json").write_text(json.dumps(dict(TINY, steps=3)))
    (tmp_path / "line.json").write_text(json.dumps({"model": "neural_noise", "stages": [entry]}))
    assert line.main([str(tmp_path / "line.json"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "out").exists()


def test_the_line_file_is_the_shipped_line():
    """Its last stage is the config and step the shipped weights record; every config reads."""
    _, stages, finish = line.load_line(SHIPPED)
    assert finish == "int8"
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
    path = _line(tmp_path, [("a", dict(TINY, steps=3)), ("b", dict(TINY, steps=2, **CONTINUES))], finish="")
    out = str(tmp_path / "out")
    line.run_line(line.load_line(path), out, max_steps=1, log=lambda s: None)
    logs = []
    line.run_line(line.load_line(path), out, log=logs.append)
    assert any("began from other weights than the stage before's export" in ln for ln in logs)
    assert not any("resumed" in ln for ln in logs if "b" in ln) and sum("resumed at step 1" in ln for ln in logs) == 1
    assert json.loads((tmp_path / "out" / "b" / "export" / "neural_noise.json").read_text())["step"] == 2


def test_a_solid_line_goes_on_from_each_export_s_step_and_averages_two_stages(tmp_path):
    """Solid texture stages count on from their start's step under their own schedule; an average stage exports the
    mean of two stages' weights at the last one's step."""
    import torch

    path = _line(tmp_path, [("a", dict(TINY_SOLID, steps=4)), ("b", dict(TINY_SOLID, steps=8, **CONTINUES))],
                 model="solid", finish="", extra=[{"name": "mean", "average": ["a", "b"]}])
    logs = []
    model = line.run_line(line.load_line(path), str(tmp_path / "out"), max_steps=2, log=logs.append)
    steps = {n: json.loads((tmp_path / "out" / n / "export" / "solid.json").read_text())["step"] for n in "ab"}
    assert steps == {"a": 2, "b": 4} and any("started from " + str(tmp_path / "out" / "a" / "export") + " (" in ln
                                             and ln.endswith("at step 2") for ln in logs)
    assert json.loads((tmp_path / "out" / "mean" / "export" / "solid.json").read_text())["step"] == 4
    runs = [torch.load(tmp_path / "out" / n / "ckpt.pt", weights_only=False)["model"] for n in ("a", "b", "mean")]
    k = next(k for k, v in runs[0].items() if v.is_floating_point() and not torch.equal(v, runs[1][k]))
    assert torch.allclose(runs[2][k], (runs[0][k] + runs[1][k]) / 2, atol=1e-6)
    assert model == str(tmp_path / "out" / "mean" / "export")
    logs.clear()
    line.run_line(line.load_line(path), str(tmp_path / "out"), max_steps=2, log=logs.append)
    assert all(ln.endswith("export)") and ": done (" in ln for ln in logs)


def test_the_solid_line_file_is_the_shipped_space_line():
    """Its last training stage is the config and step the shipped space model records, its finish the shipped
    model's spin, and a GPU stage is refused here without --device, before any work."""
    import torch

    model, stages, finish = line.load_line(SOLID)
    shipped = json.loads(open(os.path.join(ROOT, "models", "solid", "space", "solid.json")).read())
    last = [s for s in stages if s.kind == "train"][-1]
    assert shipped["step"] == last.steps and shipped["name"] == model.config(last.config).name
    assert finish == "spin " + shipped["spin"] and stages[-1].average == ("cont", "cont2")
    assert [s.kind for s in stages[:2]] == ["structure_net", "train"] and not model.config(stages[1].config).init_onnx
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="stage cont trains on cuda .* give --device cpu"):
            line._check_devices((model, stages, finish))


def test_a_line_of_configs_that_start_afresh_trains_models_side_by_side(tmp_path, capsys):
    """A stage whose config continues no export begins a model of its own (the single-photo solid models' line):
    it does not start from the stage before; a stage's own finish runs on its export; the command names each
    model."""
    photo = "data/photos/train/brick__tex_buildings_wall_brick01.jpg"      # a path from the repository's root
    single = dict(TINY_SOLID, name="single", exemplars=[photo], colour="affine", hold_out=True, steps=2)
    path = _line(tmp_path, [("a", dict(TINY_SOLID, steps=2)), ("b", single)], model="solid", finish="")
    doc = json.loads(open(path).read())
    doc["stages"][1]["finish"] = "harmonics"
    open(path, "w").write(json.dumps(doc))
    stages = line.load_line(path)[1]
    assert [s.name for s in line.line_models(stages)] == ["a", "b"] and not any(s.continues for s in stages)
    out = tmp_path / "out"
    assert line.main([path, "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "b: " + os.path.relpath(str(tmp_path / "b.json")) + ", to step 2, from a fresh network" in said
    assert said.strip().splitlines()[-1] == f"line: the models are {out / 'a' / 'export'}, {out / 'b' / 'export'}"
    a_doc, b_doc = (json.loads((out / n / "export" / "solid.json").read_text()) for n in "ab")
    assert b_doc["config"]["init_onnx"] == "" and b_doc["step"] == 2 and b_doc["name"] == "single"
    assert "harmonics" in b_doc and "harmonics" not in a_doc
    assert line.main([path, "--out", str(out)]) == 0                  # done: nothing trained or finished again
    assert all(": done (" in ln for ln in capsys.readouterr().out.splitlines()[:-1])


def test_a_line_of_several_models_takes_no_line_finish(tmp_path, capsys):
    (tmp_path / "a.json").write_text(json.dumps(dict(TINY, steps=3)))
    (tmp_path / "line.json").write_text(json.dumps({"model": "neural_noise", "finish": "int8", "stages": [
        {"name": "a", "config": "a.json", "steps": 3}, {"name": "b", "config": "a.json", "steps": 3}]}))
    assert line.main([str(tmp_path / "line.json"), "--out", str(tmp_path / "out")]) == 2
    assert "several models gives a finish to each stage" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_singles_line_file_trains_every_shipped_single_photo_model():
    """Each shipped single-photo model is a stage of its own: its config (every key but the structure network's
    path) and step as the model records them, from a fresh network, with the harmonic part where the model stores
    one."""
    model, stages, finish = line.load_line(SINGLES)
    folder = os.path.join(ROOT, "models", "solid")
    shipped = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name, "solid.json")
        if os.path.isfile(path) and json.loads(open(path).read())["mode"] == "single":
            shipped[name] = json.loads(open(path).read())
    assert not finish and stages[0].kind == "structure_net"
    models = line.line_models(stages)
    assert sorted(s.name for s in models) == sorted(shipped)
    for s in models:
        doc = shipped[s.name]
        ours = json.loads(json.dumps({k: v for k, v in dataclasses.asdict(s.cfg).items() if k != "structure_net"}))
        theirs = {k: v for k, v in doc["config"].items() if k != "structure_net"}
        assert {k: ours[k] for k in theirs} == theirs, s.name
        defaults = json.loads(json.dumps(dataclasses.asdict(type(s.cfg)())))     # keys added since: their default
        assert {k: v for k, v in ours.items() if k not in theirs} == {k: defaults[k] for k in ours if k not in theirs}
        assert s.steps == doc["step"] and (s.finish == "harmonics") == ("harmonics" in doc), s.name
        k = stages.index(s)
        if s.continues:        # the run it continued is the stage before: its config, stopped at its own steps
            before = line._start(stages, k)
            assert os.path.basename(s.cfg.init_from) == before.cfg.name and before.steps == before.cfg.steps
        else:
            assert line._start(stages, k) is None
    assert [s.name for s in stages if s.continues] == ["granite_3d"]
