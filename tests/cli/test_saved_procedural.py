"""A fitted procedural solid saved as JSON (backend/solid/procedural/saved.py): written by ``-o X.json`` (command
line, Python), drawn again without fitting from that file as the exemplar (command line, job files, Python), the
same as the fit it holds; edited by hand within what the engine draws; anything else refused in one line before
any work.  A short fit (small slices, a short search) keeps it to seconds: the same stages."""
import functools
import json
import os
import shutil

import numpy as np
import pytest

from omninoise import api
from omninoise.backend.errors import SettingError
from omninoise.backend.solid.procedural import fit, saved
from omninoise.backend.solid.procedural.field import FAMILIES, ProceduralField
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.sources import solid_request_from_dict
from omninoise.cli.main import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PHOTO = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")


def small(mp):
    mp.setattr(fit, "ProceduralConfig", functools.partial(fit.ProceduralConfig, side=32, budget=6, finalists=1,
                                                          fit_side=64))


@pytest.fixture(autouse=True)
def small_fit(monkeypatch):
    small(monkeypatch)


@pytest.fixture(scope="module")
def fitted_once(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("fit") / "wall.json")
    with pytest.MonkeyPatch.context() as mp:
        small(mp)
        assert main(["solid", "--quiet", "--method", "procedural", "--exemplar", PHOTO, "--seed", "3", "-o",
                     out]) == 0
        return out, SolidRequest(exemplar=PHOTO, method="procedural", seed=3).check().procedural_field()


@pytest.fixture()
def fitted(fitted_once, tmp_path):
    """(a copy of the saved solid's path, the field a fit of the photo with seed 3 gives)."""
    path = str(tmp_path / "wall.json")
    shutil.copy(fitted_once[0], path)
    return path, fitted_once[1]


def no_fit(monkeypatch):
    monkeypatch.setattr(fit, "fit_procedural", lambda *a, **k: pytest.fail("a saved solid was fitted again"))


def test_the_saved_file_is_the_fit_and_draws_as_the_fit_from_every_front_end(fitted, tmp_path, monkeypatch, capsys):
    path, field = fitted
    doc = json.load(open(path))
    assert doc["format"] == saved.FORMAT and doc["family"] == field.family and doc["seed"] == 3
    assert saved.read(path).to_dict() == field.to_dict()
    assert api.solid(PHOTO, method="procedural", seed=3, out=str(tmp_path / "api.json")) == str(tmp_path / "api.json")
    assert json.load(open(tmp_path / "api.json")) == doc
    direct = str(tmp_path / "direct.npy")
    assert main(["solid", "--quiet", "--method", "procedural", "--exemplar", PHOTO, "--seed", "3", "--size", "32",
                 "--dim", "3", "-o", direct]) == 0

    no_fit(monkeypatch)
    drawn = str(tmp_path / "drawn.npy")
    assert main(["solid", "--quiet", "--method", "procedural", "--exemplar", path, "--size", "32", "--dim", "3",
                 "-o", drawn]) == 0
    np.testing.assert_array_equal(np.load(drawn), np.load(direct))
    np.testing.assert_array_equal(api.solid(path, 32, dim=3, method="procedural"), np.load(direct))
    np.testing.assert_array_equal(api.solid(saved.read(path), 32, dim=3, method="procedural"), np.load(direct))
    # no method: a saved solid is drawn by the one method that draws it (it was refused as not neural)
    unnamed = str(tmp_path / "unnamed.npy")
    assert main(["solid", "--quiet", "--exemplar", path, "--size", "32", "--dim", "3", "-o", unnamed]) == 0
    np.testing.assert_array_equal(np.load(unnamed), np.load(direct))
    np.testing.assert_array_equal(api.solid(path, 32, dim=3), np.load(direct))
    copy = str(tmp_path / "copy.json")        # a .json from a saved solid is a copy of it, and says so
    capsys.readouterr()
    assert main(["solid", "--exemplar", path, "-o", copy]) == 0
    assert json.load(open(copy)) == doc and "wrote a copy of the saved" in capsys.readouterr().err

    shutil.copy(path, tmp_path / "kept.json")
    shutil.copy(PHOTO, tmp_path / "bricks.jpg")
    job = tmp_path / "job.toml"
    job.write_text("".join(f"""
[[bake]]
name = "{name}"
output = "{name}.exr"
resolution = [32, 32]
[bake.source]
kind = "solid"
exemplar = "{exemplar}"
{more}
""" for name, exemplar, more in (("saved", "kept.json", ""),          # drawn by method procedural, unnamed
                                 ("photo", "bricks.jpg", 'method = "procedural"\nseed = 3'))))
    monkeypatch.undo()
    small(monkeypatch)
    assert main(["bake", str(job), "--quiet"]) == 0
    from omninoise.export import read_rgb

    np.testing.assert_array_equal(read_rgb(str(tmp_path / "saved.exr")), read_rgb(str(tmp_path / "photo.exr")))
    stamp = os.stat(tmp_path / "saved.exr").st_mtime_ns
    no_fit(monkeypatch)
    assert main(["bake", str(job), "--quiet", "--only", "saved"]) == 0
    assert os.stat(tmp_path / "saved.exr").st_mtime_ns == stamp        # up to date

    keys = {SolidRequest(exemplar=path, method="procedural").check().key()["exemplar"],
            solid_request_from_dict({"method": "procedural", "exemplar": "kept.json"}, str(tmp_path)).key()["exemplar"],
            SolidRequest(exemplar=saved.read(path), method="procedural").check().key()["exemplar"]}
    assert len(keys) == 1 and keys.pop().startswith("procedural:")


def test_an_edited_file_draws_its_edits(fitted, tmp_path, monkeypatch):
    """What the engine draws beyond the fit's search ranges (a longer unit, more turbulence) is drawn; the key
    follows the edit, so a job bakes again."""
    path, field = fitted
    no_fit(monkeypatch)
    doc = json.load(open(path))
    key = SolidRequest(exemplar=path, method="procedural").check().key()
    p = doc["params"]
    name = {"rings": "spacing", "layers": "spacing", "cells": "size", "bonds": "length"}[doc["family"]]
    top = {q.name: q.hi for q in FAMILIES[doc["family"]].params()}[name]
    p[name], p["turbulence"] = 1.5 * top, 3.0
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    req = SolidRequest(exemplar=str(edited), method="procedural").check()
    assert req.key() != key
    expected = ProceduralField(doc["family"], p, field.ramp, 3, field.px_per_unit, field.tint).image(24)
    np.testing.assert_array_equal(req.front_image(24), expected)
    assert np.abs(expected - field.image(24)).max() > 0.1


def bad_docs():
    """(what is changed, the error's words)."""
    return [
        (lambda d: d.update(format="omninoise procedural solid 2"),
         'expected "format": "omninoise procedural solid 1"'),
        (lambda d: d.update(colour="red"), "colour: unknown key"),
        (lambda d: d.pop("ramp"), "ramp: missing"),
        (lambda d: d.update(family="tiles"), "unknown procedural family 'tiles'"),
        (lambda d: d["params"].update(width=0.2), "have no parameter 'width'"),
        (lambda d: d["params"].pop("turbulence"), "parameter 'turbulence' is missing"),
        (lambda d: d["params"].update(turb_freq=0.0), "turb_freq must be at least 0.25, got 0.0"),
        (lambda d: d["params"].update(detail=-0.5), "detail must be at least 0.0"),
        (lambda d: d["params"].update(turbulence="strong"), "turbulence must be a finite number"),
        (lambda d: d["params"].update(turbulence=True), "turbulence must be a finite number"),
        (lambda d: d["params"].update(flip="yes"), "flip must be true or false"),
        (lambda d: d.update(seed=-1), "seed: expected a whole number in [0, 4294967295]"),
        (lambda d: d.update(seed=2.5), "seed: expected a whole number"),
        (lambda d: d.update(px_per_unit=0), "px_per_unit: must be above 0"),
        (lambda d: d["ramp"]["positions"].reverse(), "ramp.positions: stops must increase strictly"),
        (lambda d: d["ramp"]["colours"].pop(), "ramp.colours: expected 16 colours, one per position"),
        (lambda d: d["ramp"]["colours"][0].append(1.0), "ramp.colours: expected [r, g, b]"),
        (lambda d: d["ramp"]["colours"][2].__setitem__(1, 1.5), "ramp.colours: values must lie in [0.0, 1.0]"),
        (lambda d: d["ramp"].update(positions=[0.0]), "ramp.positions: expected 2 to 256 stops, got 1"),
        (lambda d: d.update(tint={"frequency": 2.0}), "tint: expected an object of axis, frequency, levels, positions"),
        (lambda d: d.update(tint=dict(frequency=-2.0, positions=[0, 1], levels=[0, 0.1], axis=[1, 0, 0])),
         "tint.frequency: must be above 0"),
        (lambda d: d.update(tint=dict(frequency=2.0, positions=[0, 1], levels=[0, 0.1], axis=[0, 0, 0])),
         "tint.axis: expected a colour direction"),
        (lambda d: d.update(tint=dict(frequency=2.0, positions=[0, 1], levels=[0.1], axis=[1, 0, 0])),
         "tint.levels: expected 2 levels"),
    ]


@pytest.mark.parametrize("change, words", bad_docs())
def test_a_file_that_is_not_a_saved_solid_is_refused_in_one_line(fitted, tmp_path, capsys, change, words):
    path, _ = fitted
    doc = json.load(open(path))
    change(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(SettingError) as e:
        SolidRequest(exemplar=str(bad), method="procedural").check()
    assert e.value.setting == "exemplar" and words in e.value.message and str(bad) in e.value.message
    capsys.readouterr()
    assert main(["solid", "--method", "procedural", "--exemplar", str(bad), "--size", "8",
                 "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and err[0].startswith("omninoise solid: error: --exemplar:")
    assert not os.path.exists(tmp_path / "x.png")


@pytest.mark.parametrize("text, words", [("", "is not JSON"), ('{"format": NaN}', "NaN is no number"),
                                         ("[1, 2]", "expected a JSON object, got list"),
                                         ("\xff\xfe", "is not JSON"), ("[" * 200000, "nested too deep"),
                                         ('{"format": "' + "x" * (1 << 20) + '"}', "over 1 MiB"),
                                         ('{"format": "' + "x" * 5000 + '"}', "got 'xxxx")])
def test_a_file_that_is_not_json_is_refused_in_one_line(tmp_path, text, words):
    bad = tmp_path / "bad.json"
    bad.write_bytes(text.encode("latin-1"))
    with pytest.raises(SettingError, match=words) as e:
        SolidRequest(exemplar=str(bad), method="procedural").check()
    assert len(str(e.value)) < 300 + len(str(bad))          # one short line, whatever the file holds



def test_a_file_saved_with_a_byte_order_mark_is_the_same_solid(fitted, tmp_path):
    """An edit in a Windows editor may begin the file with a UTF-8 byte-order mark."""
    path, field = fitted
    marked = tmp_path / "marked.json"
    marked.write_bytes(b"\xef\xbb\xbf" + open(path, "rb").read())
    assert saved.read(str(marked)).to_dict() == field.to_dict()

@pytest.mark.parametrize("args, flag, words", [
    (["--method", "neural"], "--exemplar", "drawn by method procedural, not neural"),
    (["--method", "auto"], "--exemplar", "drawn by method procedural, not auto"),
    (["--method", "procedural", "--seed", "2"], "--seed", 'edit its "seed" to draw another'),
    (["--method", "procedural", "--families", "cells"], "--families", "nothing is fitted"),
    (["--method", "procedural", "--refine", "2"], "--refine", "nothing is fitted"),
])
def test_what_a_saved_solid_cannot_take_is_named(fitted, tmp_path, capsys, args, flag, words):
    path, _ = fitted
    capsys.readouterr()
    assert main(["solid", "--exemplar", path, *args, "--size", "8", "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"omninoise solid: error: {flag}:") and words in err


@pytest.mark.parametrize("args, flag, words", [
    (["--method", "spectral"], "-o", "give --method procedural"),
    (["--method", "procedural", "--size", "64"], "--size", "leave --size out"),
    (["--method", "procedural", "--dim", "3"], "--dim", "leave --dim out"),
])
def test_a_json_output_is_a_fit_only(tmp_path, capsys, args, flag, words, monkeypatch):
    monkeypatch.setattr(fit, "fit_procedural", lambda *a, **k: pytest.fail("fitted before the flags were checked"))
    out = tmp_path / "x.json"
    assert main(["solid", "--exemplar", PHOTO, *args, "-o", str(out)]) == 2
    assert f"error: {flag}:" in capsys.readouterr().err and not out.exists()
    with pytest.raises(SettingError, match="not '.json'"):
        api.solid(PHOTO, 8, method="spectral", out=str(out))
