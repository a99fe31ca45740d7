"""Method "spectral" (backend/solid/spectral_solid.py: random phase noise lifted to a solid) in the command line
and job files: one request from flags, job tables and pixels; a volume and an image from `omninoise solid --method
spectral`; the same volume from a job file's bake; one-line errors for what it cannot do.  No torch; tiles of a
small period keep it to seconds."""
import os
import shutil
import warnings

import numpy as np
import pytest

import omninoise

from omninoise.backend.errors import SettingError
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.solid.spectral_solid import PX_PER_UNIT
from omninoise.backend.sources import solid_request_from_dict
from omninoise.cli.main import build_parser, main
from omninoise.cli.solid import solid_request
from omninoise.export import read_rgb

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PHOTO = os.path.join(ROOT, "data", "photos", "val", "rock__cliff_greek.jpg")


@pytest.fixture(autouse=True)
def small_tiles(monkeypatch):
    """Tiles of a 32 px period (64^3 voxels) instead of the product's 128: the same code, a fiftieth of the work."""
    from omninoise.backend.solid import spectral_solid

    monkeypatch.setattr(spectral_solid, "PERIOD", 32)


def cli(*args):
    return solid_request(build_parser().parse_args(["solid", *args, "-o", "x.png"]))


def test_flags_job_tables_and_pixels_give_one_request():
    a = cli("--method", "spectral", "--exemplar", PHOTO, "--seed", "4")
    b = solid_request_from_dict({"method": "spectral", "exemplar": PHOTO, "seed": 4})
    c = SolidRequest(exemplar=read_rgb(PHOTO), method="spectral", seed=4).check()
    assert a.key() == b.key() == c.key()
    # what it reads, nothing of a model; "marginals" marks the map onto the photo's marginals and "start" the
    # power's isotropic start, so a bake keyed before either is redone
    assert set(a.key()) == {"method", "exemplar", "seed", "periodic", "marginals", "start"}
    assert a.key()["marginals"] is True and a.key()["start"] == "isotropic"
    assert a.key() != cli("--method", "spectral", "--exemplar", PHOTO).key()
    d = cli("--method", "spectral", "--exemplar", PHOTO, "--seed", "4", "--no-periodic")
    assert d.key() != a.key() and d.key() == solid_request_from_dict({"method": "spectral", "exemplar": PHOTO,
                                                                      "seed": 4, "periodic": False}).key()
    assert a.key() != cli("--method", "synthesis", "--exemplar", PHOTO, "--seed", "4").key()


@pytest.mark.parametrize("flags, table, field, why", [
    (["--exemplar", "gravel"], {"exemplar": "gravel"}, "exemplar", "spectral works from an image"),
    (["--exemplar", "no/such.png"], {"exemplar": "no/such.png"}, "exemplar", "there is no file 'no/such.png'"),
    (["--to", "grass"], {"to": "grass"}, "to", "interpolation needs the neural texture"),
    (["--refine", "3"], {"refine": 3}, "refine", "spectral has none"),
])
def test_what_spectral_cannot_do_is_named(flags, table, field, why):
    with pytest.raises(SettingError) as e1:
        cli("--method", "spectral", "--exemplar", PHOTO, *flags)
    with pytest.raises(SettingError) as e2:
        solid_request_from_dict(dict({"method": "spectral", "exemplar": PHOTO}, **table))
    assert e1.value.setting == "--" + field and e2.value.setting == "source." + field
    assert why in str(e1.value) and why in str(e2.value)


def test_a_volume_from_the_command_line_and_from_a_job_file_agree(tmp_path, capsys):
    """A 3D .npy from the command line (linear colours) is the job file's bake of the same box, and it has the
    photo's colours: mean within 0.03 and a spread within 30 % of the photo's (linear)."""
    cli_out = str(tmp_path / "cli.npy")
    assert main(["solid", "--quiet", "--method", "spectral", "--exemplar", PHOTO, "--dim", "3", "--size", "24",
                 "--seed", "1", "-o", cli_out]) == 0
    vol = np.load(cli_out)
    assert vol.shape == (24, 24, 24, 3) and np.isfinite(vol).all()
    from omninoise.backend.colour import srgb_to_linear

    photo = srgb_to_linear(read_rgb(PHOTO)).reshape(-1, 3)
    assert np.abs(vol.reshape(-1, 3).mean(0) - photo.mean(0)).max() < 0.03
    ratio = vol.reshape(-1, 3).std(0) / photo.std(0)
    assert np.all((ratio > 0.7) & (ratio < 1.3)), ratio

    e = 24 / PX_PER_UNIT
    shutil.copy(PHOTO, tmp_path / "rock.jpg")
    job = tmp_path / "job.toml"
    job.write_text(f"""
[[bake]]
name = "rock"
output = "job.npy"
resolution = [24, 24, 24]
bounds = [[0, 0, 0], [{e!r}, {e!r}, {e!r}]]
[bake.source]
kind = "solid"
method = "spectral"
exemplar = "rock.jpg"
seed = 1
""")
    assert main(["bake", str(job), "--quiet"]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "job.npy"), vol, atol=2e-5)
    from omninoise.backend.jobs import run_job

    job.write_text(job.read_text().replace('output = "job.npy"', 'output = "job.vdb"'))   # .npy carry no key
    assert [o.status for o in run_job(str(job))] == ["baked"]
    assert [o.status for o in run_job(str(job))] == ["up to date"]


def test_an_image_and_one_line_errors(tmp_path, capsys):
    """A 2D image is the front view (x right, z up), as a 3D model's 2D image and the panel's preview are."""
    out = str(tmp_path / "a.npy")
    assert main(["solid", "--quiet", "--method", "spectral", "--exemplar", PHOTO, "--size", "64", "--scale", "2",
                 "-o", out]) == 0
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.backend.solid.model import slice_points

    req = SolidRequest(exemplar=PHOTO, method="spectral").check()
    front = req.spectral_field().evaluate(slice_points(64, 2 * PX_PER_UNIT, "y")).reshape(64, 64, 3)
    np.testing.assert_allclose(np.load(out), srgb_to_linear(front), atol=1e-5)
    small = str(tmp_path / "small.png")
    from omninoise.export.images import write_png

    write_png(small, np.zeros((20, 30, 3), np.uint8))
    for args, msg in ((["--exemplar", small], "--exemplar: the photo is 30 x 20 px"),
                      (["--exemplar", os.path.join(ROOT, "README.md")], "--exemplar: "),
                      (["--exemplar", PHOTO, "--dim", "3"], "-o: a 3D result is written as .vdb, .npy")):
        assert main(["solid", "--quiet", "--method", "spectral", *args, "-o", str(tmp_path / "b.png")]) == 2
        err = capsys.readouterr().err.strip()
        assert msg in err and len(err.splitlines()) == 1
    assert not os.path.exists(tmp_path / "b.png")


def test_a_photo_brighter_than_white_or_darker_than_black_is_said_to_be(tmp_path, capsys):
    """A float photo whose pixels pass 1 is read as white there (an HDR photo, an overexposed one), and one whose
    pixels fall below 0 as black (all of a photo offset below black came out black without a word): the command says
    how much of it, before any work, and ``omninoise.solid`` warns so; a photo within [0, 1], values under black by
    less than an 8-bit step, and a quiet command say nothing."""
    from omninoise.export import write_exr
    from omninoise.export.images import BLACK_TOLERANCE, outside_unit

    hot = np.full((40, 40, 3), 0.5, np.float32)
    hot[:10] = 4.5                                              # a quarter of the pixels past white
    hot[10:14, :, 2] = -0.2                                     # a tenth under black in blue
    hot[14:, :, 1] = -0.9 * BLACK_TOLERANCE                     # the rest black within the tolerance
    write_exr(str(tmp_path / "hot.exr"), hot)
    write_exr(str(tmp_path / "cool.exr"), np.full((40, 40, 3), 0.5, np.float32))
    assert outside_unit(str(tmp_path / "hot.exr")) == (0.25, 0.1)
    assert outside_unit(str(tmp_path / "cool.exr")) == (0.0, 0.0)
    for name, value, said in (("hot", 4.5, "brighter than white (above 1) and are read as white"),
                              ("dark", -0.5, "darker than black (below 0) and are read as black"), ("cool", 0.5, "")):
        write_exr(str(tmp_path / "p.exr"), np.full((40, 40, 3), value, np.float32))
        for quiet in ([], ["-q"]):
            assert main(["solid", "--exemplar", str(tmp_path / "p.exr"), "--method", "spectral", "--size", "16",
                         "-o", str(tmp_path / f"{name}.png")] + quiet) == 0
            err = capsys.readouterr().err
            notes = [line for line in err.splitlines() if line.startswith("note:")]
            assert len(notes) == (1 if said and not quiet else 0), err
            assert not notes or notes[0].startswith(f"note: 100 % of the photo's pixels are {said}"), err
        with warnings.catch_warnings(record=True) as caught:          # the Python API warns the same
            warnings.simplefilter("always")
            assert omninoise.solid(str(tmp_path / "p.exr"), 16, method="spectral").shape == (16, 16, 3)
        told = [str(w.message) for w in caught]
        assert len(told) == (1 if said else 0) and all(t.startswith(f"100 % of the photo's pixels are {said}")
                                                      for t in told), told
