"""Methods "procedural" and "auto" (backend/solid/procedural, backend/solid/choose.py) in the command line, job files
and the Python API: one request from flags, job tables and pixels; the same image and volume from each; one-line
errors for what they cannot do.  A short fit (small slices, a short search) keeps it to seconds: the same stages."""
import functools
import os
import shutil

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.solid.procedural import fit
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.sources import solid_request_from_dict
from omninoise.cli.main import build_parser, main
from omninoise.cli.solid import solid_request
from omninoise.export import read_rgb

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PHOTO = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")


@pytest.fixture(autouse=True)
def small_fit(monkeypatch):
    monkeypatch.setattr(fit, "ProceduralConfig", functools.partial(fit.ProceduralConfig, side=32, budget=6,
                                                                   finalists=1, fit_side=64))


def cli(*args):
    return solid_request(build_parser().parse_args(["solid", *args, "-o", "x.png"]))


def test_flags_job_tables_and_pixels_give_one_request():
    a = cli("--method", "procedural", "--exemplar", PHOTO, "--seed", "4")
    b = solid_request_from_dict({"method": "procedural", "exemplar": PHOTO, "seed": 4})
    c = SolidRequest(exemplar=read_rgb(PHOTO), method="procedural", seed=4).check()
    assert a.key() == b.key() == c.key()
    assert set(a.key()) == {"method", "exemplar", "seed", "families"}
    assert a.key() != cli("--method", "procedural", "--exemplar", PHOTO).key()
    auto = cli("--method", "auto", "--exemplar", PHOTO, "--seed", "4")
    assert auto.key()["procedural"] == a.key() and auto.key()["neural"]["model"] == "space"
    assert auto.key() == solid_request_from_dict({"method": "auto", "exemplar": PHOTO, "seed": 4}).key()
    assert a.key()["families"] == ["rings", "layers", "cells", "bonds"]        # herringbones only where asked
    kinds = cli("--method", "procedural", "--exemplar", PHOTO, "--seed", "4", "--families", "bonds,herringbone")
    assert kinds.key() == solid_request_from_dict({"method": "procedural", "exemplar": PHOTO, "seed": 4,
                                                   "families": ["bonds", "herringbone"]}).key() != a.key()
    assert kinds.key()["families"] == ["bonds", "herringbone"]


@pytest.mark.parametrize("method, flags, table, field, why", [
    ("procedural", ["--exemplar", "gravel"], {"exemplar": "gravel"}, "exemplar", "procedural works from an image"),
    ("procedural", ["--to", "grass"], {"to": "grass"}, "to", "interpolation needs the neural texture"),
    ("procedural", ["--refine", "3"], {"refine": 3}, "refine", "procedural has none"),
    ("auto", ["--exemplar", "gravel"], {"exemplar": "gravel"}, "exemplar", "auto chooses for a photo"),
    ("auto", ["--to", "grass"], {"to": "grass"}, "to", "auto draws one texture"),
    ("procedural", ["--families", "cells,tiles"], {"families": ["cells", "tiles"]}, "families[1]",
     "expected one of rings, layers, cells, bonds, herringbone, got 'tiles'"),
    ("auto", ["--families", "bonds,bonds"], {"families": ["bonds", "bonds"]}, "families", "names bonds more than once"),
])
def test_what_they_cannot_do_is_named(method, flags, table, field, why):
    with pytest.raises(SettingError) as e1:
        cli("--method", method, "--exemplar", PHOTO, *flags)
    with pytest.raises(SettingError) as e2:
        solid_request_from_dict(dict({"method": method, "exemplar": PHOTO}, **table))
    assert e1.value.setting == "--" + field and e2.value.setting == "source." + field
    assert why in str(e1.value) and why in str(e2.value)


def test_an_image_and_a_volume_from_the_command_line_a_job_file_and_the_api(tmp_path):
    from omninoise import api
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.backend.solid.model import slice_points
    from omninoise.backend.solid.procedural.field import PX_PER_UNIT

    out = str(tmp_path / "a.npy")
    assert main(["solid", "--quiet", "--method", "procedural", "--exemplar", PHOTO, "--size", "48", "--seed", "1",
                 "-o", out]) == 0
    field = SolidRequest(exemplar=PHOTO, method="procedural", seed=1).check().procedural_field()
    front = field.evaluate(slice_points(48, PX_PER_UNIT, "y")).reshape(48, 48, 3)
    np.testing.assert_allclose(np.load(out), srgb_to_linear(front), atol=1e-5)
    np.testing.assert_allclose(api.solid(PHOTO, 48, method="procedural", seed=1), np.load(out), atol=1e-6)
    herring = api.solid(PHOTO, 16, method="procedural", seed=1, families=["herringbone"])
    field = SolidRequest(exemplar=PHOTO, method="procedural", seed=1, families=("herringbone",)).check() \
        .procedural_field()
    assert field.params["pattern"] in ("herringbone", "herringbone45")
    np.testing.assert_allclose(herring, srgb_to_linear(field.image(16)), atol=1e-6)
    with pytest.raises(SettingError, match="families"):
        api.solid(PHOTO, 16, method="procedural", families="bonds")

    vol_out = str(tmp_path / "cli.npy")
    assert main(["solid", "--quiet", "--method", "procedural", "--exemplar", PHOTO, "--dim", "3", "--size", "16",
                 "--seed", "1", "-o", vol_out]) == 0
    vol = np.load(vol_out)
    assert vol.shape == (16, 16, 16, 3) and np.isfinite(vol).all() and vol.std() > 0.01
    e = 16 / PX_PER_UNIT
    shutil.copy(PHOTO, tmp_path / "bricks.jpg")
    job = tmp_path / "job.toml"
    job.write_text(f"""
[[bake]]
name = "wall"
output = "job.npy"
resolution = [16, 16, 16]
bounds = [[0, 0, 0], [{e!r}, {e!r}, {e!r}]]
[bake.source]
kind = "solid"
method = "procedural"
exemplar = "bricks.jpg"
seed = 1
""")
    assert main(["bake", str(job), "--quiet"]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "job.npy"), vol, atol=2e-5)


@pytest.mark.long       # a whole auto choice twice: 25 s
def test_auto_keeps_what_its_check_finds_closer(tmp_path, capsys):
    """Auto keeps the procedural solid where its planes find it closer by the margin on both the axis and the oblique
    cuts and its walls hold the photo's structure about as well; its image is that texture's."""
    from omninoise.backend.solid.choose import PLANES, SHARES, STRUCTURE_TOLERANCE
    from omninoise.backend.solid.gaussian_rest import MARGIN

    from omninoise import export

    req = SolidRequest(exemplar=PHOTO, method="auto", seed=2).check()
    reads, seen = [], []
    with pytest.MonkeyPatch.context() as mp:       # the fit, the encoding and the check share one read of the file
        mp.setattr(export, "read_rgb", lambda path: reads.append(path) or read_rgb(path))
        c = req.choose(progress=seen.append)
    assert reads == [PHOTO]
    fitted, encoded = SHARES["fit"], SHARES["fit"] + SHARES["encode"]     # progress runs on through the three stages
    assert seen == sorted(seen) and seen[-1] == 1.0 and fitted in seen and encoded in seen
    assert sum(encoded < f < 1.0 for f in seen) >= len(PLANES)           # the check's planes move it on
    d = c.distances
    assert set(d) == {"procedural", "neural"}
    assert all(set(d[m]) == {"axes", "oblique", "structure"} for m in d)
    closer = (all(d["procedural"][f] <= MARGIN * d["neural"][f] for f in ("axes", "oblique"))
              and d["procedural"]["structure"] <= d["neural"]["structure"] + STRUCTURE_TOLERANCE)
    assert c.method == ("procedural" if closer else "neural")
    assert c.request.method == c.method
    img = req.front_image(32)
    if c.method == "procedural":
        np.testing.assert_allclose(img, c.field.image(32), atol=1e-6)
    else:
        np.testing.assert_allclose(img, c.model.image(32, c.code, 2), atol=1e-6)
    out = str(tmp_path / "auto.png")
    capsys.readouterr()
    assert main(["solid", "--method", "auto", "--exemplar", PHOTO, "--seed", "2", "--size", "32", "-o", out]) == 0
    assert os.path.getsize(out) > 0
    err = capsys.readouterr().err           # the command says what it kept and the figures that kept it
    assert c.summary() in err.splitlines(), err
    assert c.summary().startswith(f"auto: kept the {'procedural ' + c.field.family if closer else 'neural texture'} "
                                  f"(distance on axis and oblique cuts, structure error: procedural {c.field.family} "
                                  f"{d['procedural']['axes']:.1f}, ")
    assert " done (" not in err         # "done" follows the neural method's "encoding PHOTO ...", not auto's fit
    assert "auto: fit, encoding, check [" in err


def test_auto_stops_between_its_stages_when_cancelled():
    """A cancel asked for during the fit stops auto before the encoding starts (the Blender panel's Esc)."""
    from omninoise.backend.grid import Cancelled

    req = SolidRequest(exemplar=PHOTO, method="auto", seed=2).check()
    field = req.replace(method="procedural").procedural_field()
    seen, loads = [], []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(SolidRequest, "load", lambda self, where="": loads.append(self) or pytest.fail("encoded"))
        with pytest.raises(Cancelled):
            req.choose(progress=seen.append, field=field, cancel=lambda: bool(seen))
    assert seen == [0.7] and loads == []


@pytest.mark.parametrize("args, note", [(["--method", "procedural"], True), (["--method", "auto"], True),
                                        (["--method", "procedural", "--families", "bonds"], False),
                                        (["--method", "procedural", "--quiet"], False),
                                        (["--method", "spectral"], False)])
def test_a_brick_wall_s_fit_suggests_bonds(tmp_path, monkeypatch, capsys, args, note):
    """The brick wall repeats as a grid: a procedural fit that tries other kinds says, before fitting, that bonds
    lay it in courses (the result itself is not what is tested: the texture is stubbed)."""
    monkeypatch.setattr(SolidRequest, "front_image", lambda self, size, *a, **k: np.full((size, size, 3), 0.5))
    assert main(["solid", "--exemplar", PHOTO, "--size", "8", "-o", str(tmp_path / "a.png"), *args]) == 0
    assert ("--families bonds lays it in courses" in capsys.readouterr().err) == note


def solid_job(folder, methods, side: int, exemplar: str = "bricks.jpg", extra: str = ""):
    """A job file in ``folder`` of one side x side EXR bake named after each method of ``methods``, each a solid of
    that method from ``exemplar`` (``extra``: more lines of its source table) -> its path."""
    job = folder / "job.toml"
    job.write_text("".join(f"""
[[bake]]
name = "{m}"
output = "{m}.exr"
resolution = [{side}, {side}]
[bake.source]
kind = "solid"
method = "{m}"
exemplar = "{exemplar}"
{extra}
""" for m in methods))
    return job


def test_a_job_fits_a_procedural_solid_when_it_bakes_its_file_only(tmp_path, monkeypatch, capsys):
    """Reading a job, a dry run, another bake of the job and a bake that is up to date fit and choose nothing; the
    fit runs once, when its file is baked, and again when the kinds tried change; auto's choice likewise; a photo
    too small for the fit is refused when the job is read, before any bake."""
    made = []
    real_field = SolidRequest.solid_field

    def counted_field(self, *a, **k):
        made.append(self.method)
        return real_field(self, *a, **k)

    monkeypatch.setattr(SolidRequest, "solid_field", counted_field)
    monkeypatch.setattr(SolidRequest, "choose", lambda *a, **k: made.append("auto") or pytest.fail("auto chose"))
    shutil.copy(PHOTO, tmp_path / "bricks.jpg")

    def write(exemplar="bricks.jpg", kinds=""):
        return solid_job(tmp_path, ("procedural", "auto"), 8, exemplar, kinds)

    job = write()

    assert main(["bake", str(job), "--dry-run"]) == 0 and made == []
    assert main(["bake", str(job), "--quiet", "--only", "procedural"]) == 0 and made == ["procedural"]
    img = read_rgb(str(tmp_path / "procedural.exr"))
    assert img.shape == (8, 8, 3) and np.isfinite(img).all()
    capsys.readouterr()
    assert main(["bake", str(job), "--only", "procedural"]) == 0 and made == ["procedural"]
    text = capsys.readouterr()
    assert "procedural: up to date" in text.out + text.err
    write(kinds='families = ["bonds"]')
    assert main(["bake", str(job), "--dry-run"]) == 0 and made == ["procedural"]
    assert capsys.readouterr().out.count("to bake") == 2        # the kinds are in both bakes' keys
    assert main(["bake", str(job), "--quiet", "--only", "procedural"]) == 0 and made == ["procedural"] * 2
    from omninoise.export.images import write_unit_image

    write_unit_image(str(tmp_path / "small.png"), np.random.default_rng(0).random((12, 40, 3)))
    write(exemplar="small.png")
    assert main(["bake", str(job), "--dry-run"]) == 2 and made == ["procedural"] * 2
    out = capsys.readouterr().out
    assert out.count("a procedural solid is fitted to a photo of at least 16 x 16 px, got 40 x 12") == 2, out


def test_a_fit_stopped_early_is_not_kept_by_its_source():
    """A cancelled fit returns its best so far (the panel's preview draws it); a bake source does not keep it: it
    stops with Cancelled and fits again at its next use."""
    from omninoise.backend.grid import Cancelled
    from omninoise.backend.sources import SpectralSource

    src = SpectralSource(SolidRequest(exemplar=PHOTO, method="procedural").check())
    assert not src.ready
    with pytest.raises(Cancelled):
        src.prepare(cancel=lambda: True)
    assert not src.ready
    assert src.evaluate((4, 4), np.zeros(3), np.full(2, 0.1), 0.0).shape == (4, 4, 3) and src.ready


def test_a_job_holds_no_photo_s_pixels_until_it_makes_the_texture(tmp_path):
    """A job's sources read their photo when the job is read (checks, key) and again when a texture is made, and
    keep neither: a job of many large photos holds none of them between its bakes."""
    from omninoise.backend.jobs import load_job
    from omninoise.backend.sources import AutoSource, EncodedSource, SpectralSource

    shutil.copy(PHOTO, tmp_path / "bricks.jpg")
    job = solid_job(tmp_path, ("procedural", "spectral", "auto", "neural"), 4)

    def holds_pixels(obj, seen=None) -> bool:
        seen = set() if seen is None else seen
        if id(obj) in seen:
            return False
        seen.add(id(obj))
        if isinstance(obj, np.ndarray):
            return obj.size >= 64 * 64 * 3
        if isinstance(obj, dict):
            return any(holds_pixels(v, seen) for v in obj.values())
        if isinstance(obj, (list, tuple)):
            return any(holds_pixels(v, seen) for v in obj)
        return hasattr(obj, "__dict__") and holds_pixels(vars(obj), seen)

    specs = dict(load_job(str(job)))
    assert isinstance(specs["auto"].source, AutoSource) and isinstance(specs["spectral"].source, SpectralSource)
    assert isinstance(specs["neural"].source, EncodedSource)
    for name, spec in specs.items():
        assert not spec.source.ready and not holds_pixels(spec.source.request), name
    src = specs["procedural"].source
    assert src.evaluate((2, 2), np.zeros(3), np.full(2, 0.1), 0.0).shape == (2, 2, 3) and src.ready
    assert not holds_pixels(src.request)


@pytest.mark.parametrize("dim, size", [(2, 32), (3, 8)])
def test_the_api_s_progress_runs_over_the_fit_and_then_the_drawing(dim, size):
    """``omninoise.solid(..., progress=)`` hears the fit over the first PREPARE_SHARE of the work and the drawing
    over the rest, up to 1 (the fit's seconds were silent)."""
    import omninoise
    from omninoise.backend.bake import PREPARE_SHARE

    seen = []
    omninoise.solid(PHOTO, size, dim=dim, method="procedural", seed=2, progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == 1.0
    assert sum(0 < f < PREPARE_SHARE for f in seen) >= 3 and any(PREPARE_SHARE < f for f in seen), seen
