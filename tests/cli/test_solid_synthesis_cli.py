"""Method "synthesis" (backend/solid/synthesis.py) in every front-end but the panel (tests/blender covers it): one
request from flags and job tables, a seamless 2D image from `omninoise solid --method synthesis` and from a job
file's bake, and one-line errors for what it cannot do.  No torch; small photos and tiles keep it to seconds."""
import os

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.solid.synthesis import PX_PER_UNIT
from omninoise.backend.sources import solid_request_from_dict
from omninoise.cli.main import build_parser, main
from omninoise.cli.solid import solid_request
from omninoise.export import read_rgb
from omninoise.export.images import write_png

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PHOTO = os.path.join(ROOT, "data", "photos", "val", "brick__beige_bricks.jpg")


def cli(*args):
    return solid_request(build_parser().parse_args(["solid", *args, "-o", "x.png"]))


@pytest.fixture(scope="module")
def stripes(tmp_path_factory) -> str:
    """A 128² PNG of vertical stripes 16 px apart, two colours."""
    x = np.arange(128)
    rgb = (0.2 + 0.6 * (x % 16 < 8))[None, :, None] * np.array([1.0, 0.8, 0.5])
    path = str(tmp_path_factory.mktemp("synthesis") / "stripes.png")
    write_png(path, np.round(np.broadcast_to(rgb, (128, 128, 3)) * 255).astype(np.uint8))
    return path


def test_flags_job_tables_and_pixels_give_one_request(stripes):
    a = cli("--method", "synthesis", "--exemplar", stripes, "--tile", "64", "--seed", "4")
    b = solid_request_from_dict({"method": "synthesis", "exemplar": stripes, "tile": 64, "seed": 4})
    c = SolidRequest(exemplar=read_rgb(stripes), method="synthesis", tile=64, seed=4).check()
    assert a.key() == b.key() == c.key()
    assert set(a.key()) == {"method", "exemplar", "seed", "tile"}      # what it reads, nothing of a model
    assert a.key() != cli("--method", "synthesis", "--exemplar", stripes, "--tile", "68", "--seed", "4").key()
    assert a.key() != cli("--method", "synthesis", "--exemplar", stripes, "--tile", "64").key()
    assert "method" not in cli("--exemplar", stripes).key()       # the neural texture's keys are as they were


@pytest.mark.parametrize("flags, table, field, why", [
    (["--exemplar", "gravel"], {"exemplar": "gravel"}, "exemplar", "works from an image"),
    (["--exemplar", "no/such.png"], {"exemplar": "no/such.png"}, "exemplar", "there is no file 'no/such.png'"),
    (["--to", "grass"], {"to": "grass"}, "to", "interpolation needs the neural texture"),
    (["--refine", "3"], {"refine": 3}, "refine", "synthesis has none"),
    (["--tile", "30"], {"tile": 30}, "tile", "multiple of 4 in [32, 1024], got 30"),
    (["--tile", "2048"], {"tile": 2048}, "tile", "multiple of 4 in [32, 1024], got 2048"),
    (["--tile", "66"], {"tile": 66}, "tile", "multiple of 4"),
])
def test_what_synthesis_cannot_do_is_named(stripes, flags, table, field, why):
    with pytest.raises(SettingError) as e1:
        cli("--method", "synthesis", "--exemplar", stripes, *flags)
    with pytest.raises(SettingError) as e2:
        solid_request_from_dict(dict({"method": "synthesis", "exemplar": stripes}, **table))
    assert e1.value.setting == "--" + field and e2.value.setting == "source." + field
    assert why in str(e1.value) and why in str(e2.value)
    with pytest.raises(SettingError, match="source.method: expected one of neural, synthesis, spectral, procedural, auto, got 'quilt'"):
        solid_request_from_dict({"method": "quilt", "exemplar": stripes})
    with pytest.raises(SettingError, match="source.tile"):
        solid_request_from_dict({"method": "synthesis", "exemplar": stripes, "tile": True})


@pytest.mark.long
def test_command_line_writes_the_tile_seamlessly_repeated(stripes, tmp_path, capsys):
    """At scale 1 the image is the tile's own pixels (top row first), repeated beyond its size: it tiles without a
    seam; the stripes keep their direction."""
    out = str(tmp_path / "t.npy")
    assert main(["solid", "--quiet", "--method", "synthesis", "--exemplar", stripes, "--tile", "64", "--size", "128",
                 "--seed", "2", "-o", out]) == 0
    from omninoise.backend.colour import srgb_to_linear

    img = np.load(out)      # linear
    tile = SolidRequest(exemplar=stripes, method="synthesis", tile=64, seed=2).synthesis_field().tile
    np.testing.assert_allclose(img[:64, :64], srgb_to_linear(tile[::-1]), atol=2e-5)
    np.testing.assert_allclose(img[:64, 64:], img[:64, :64], atol=2e-5)     # periodic in x
    np.testing.assert_allclose(img[64:, :64], img[:64, :64], atol=2e-5)     # and in y
    g = img.mean(2)
    assert np.abs(np.diff(g, axis=1)).mean() > 3.0 * np.abs(np.diff(g, axis=0)).mean()
    png = str(tmp_path / "t.png")
    assert main(["solid", "--quiet", "--method", "synthesis", "--exemplar", stripes, "--tile", "64", "--size", "96",
                 "-o", png]) == 0
    assert read_rgb(png).shape == (96, 96, 3)


def test_command_line_errors_are_one_line(stripes, tmp_path, capsys):
    for args, msg in ((["--dim", "3", "-o", str(tmp_path / "v.vdb")], "--method: synthesis makes 2D images"),
                      (["--tile", "30", "-o", str(tmp_path / "a.png")], "--tile: must be a multiple of 4"),
                      (["--exemplar", os.path.join(ROOT, "README.md"), "-o", str(tmp_path / "a.png")],
                       "--exemplar: ")):
        argv = ["solid", "--quiet", "--method", "synthesis", "--exemplar", stripes, *args]
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert msg in err and len(err.splitlines()) == 1
    small = str(tmp_path / "small.png")
    write_png(small, np.zeros((20, 30, 3), np.uint8))
    assert main(["solid", "--quiet", "--method", "synthesis", "--exemplar", small, "-o", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--exemplar: the photo is 30 x 20 px" in err and len(err.splitlines()) == 1
    assert not os.path.exists(tmp_path / "a.png")


def test_a_job_file_bakes_what_the_command_line_writes(stripes, tmp_path, capsys):
    cli_out = str(tmp_path / "cli.npy")
    assert main(["solid", "--quiet", "--method", "synthesis", "--exemplar", stripes, "--tile", "64", "--size", "96",
                 "--seed", "1", "-o", cli_out]) == 0
    e = 96 / PX_PER_UNIT
    job = tmp_path / "job.toml"
    job.write_text(f"""
[[bake]]
name = "tile"
output = "job.npy"
resolution = [96, 96]
bounds = [[0, {-e!r}, 0], [{e!r}, 0, 0]]
[bake.source]
kind = "solid"
method = "synthesis"
exemplar = "{os.path.basename(stripes)}"
tile = 64
seed = 1
""")
    import shutil

    shutil.copy(stripes, tmp_path / os.path.basename(stripes))
    assert main(["bake", str(job), "--quiet"]) == 0
    got = np.load(tmp_path / "job.npy")
    assert got.shape == (96, 96, 3)
    # the bake's rows run up the grid (y from -e to 0), the command line's image top row first
    np.testing.assert_allclose(got[::-1], np.load(cli_out), atol=2e-5)
    job.write_text(job.read_text().replace("resolution = [96, 96]", "resolution = [8, 8, 8]")
                   .replace(f"bounds = [[0, {-e!r}, 0], [{e!r}, 0, 0]]", "bounds = [[0, 0, 0], [1, 1, 1]]"))
    assert main(["bake", str(job), "--quiet"]) == 2
    assert "source.method: synthesis makes 2D images" in capsys.readouterr().err


def test_a_job_file_png_is_redone_only_when_the_synthesis_changes(stripes, tmp_path):
    import shutil

    from omninoise.backend.jobs import run_job

    shutil.copy(stripes, tmp_path / "stripes.png")
    job = tmp_path / "job.toml"
    job.write_text("""
[[bake]]
name = "tile"
output = "tile.png"
resolution = [64, 64]
bounds = [[0, -0.5, 0], [0.5, 0, 0]]
[bake.source]
kind = "solid"
method = "synthesis"
exemplar = "stripes.png"
tile = 64
""")
    assert [o.status for o in run_job(str(job))] == ["baked"]
    assert [o.status for o in run_job(str(job))] == ["up to date"]
    job.write_text(job.read_text().replace("tile = 64", "tile = 32"))
    assert [o.status for o in run_job(str(job))] == ["baked"]
    assert read_rgb(str(tmp_path / "tile.png")).shape == (64, 64, 3)


@pytest.mark.long
def test_the_bake_key_records_the_levels_the_photo_was_drawn_with(monkeypatch):
    """The levels depend on the photo (image_levels): the field keeps the settings it was synthesised with and a job
    file's source writes them into its bake key, so a bake is redone when they change.  The photo file is decoded
    once, and its key is the request's."""
    from omninoise import export
    from omninoise.backend.solid.synthesis import image_settings
    from omninoise.backend.sources import SynthesisSource

    req = SolidRequest(exemplar=PHOTO, method="synthesis", tile=256, seed=2).check()
    decoded, read = [], export.read_rgb
    monkeypatch.setattr(export, "read_rgb", lambda path: decoded.append(path) or read(path))
    src = SynthesisSource(req)
    assert decoded == [PHOTO]
    monkeypatch.undo()
    assert src.input_sha256 == req.key()["exemplar"]
    assert src.field.settings == image_settings(256, read_rgb(PHOTO).shape, 2) and src.field.settings.levels == 4
    d = src.to_dict()
    assert d["settings"]["levels"] == 4 and d["settings"]["sharpness"] == [3.0, 3.0, 3.0, 10.0]
    assert d["settings"]["seed"] == 2 and d["tile"] == 256
