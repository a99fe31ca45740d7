"""One solid-texture request for every front-end: the command line's flags and a job file's source
table give equal requests for equal settings, and the same errors, named in each front-end's own terms."""
import os

import numpy as np
import pytest

from omninoise.backend.errors import SettingError
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.sources import solid_request_from_dict
from omninoise.cli.main import build_parser
from omninoise.cli.solid import solid_request
from omninoise.export import read_rgb

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PHOTO = os.path.join(ROOT, "data", "photos", "val", "soil__farmland_a.jpg")


def cli(*args):
    return solid_request(build_parser().parse_args(["solid", *args, "-o", "x.png"]))


@pytest.mark.parametrize("flags, table", [
    (["--exemplar", "gravel"], {"exemplar": "gravel"}),
    (["--exemplar", "gravel", "--seed", "7"], {"exemplar": "gravel", "seed": 7}),
    (["--exemplar", PHOTO, "--refine", "3"], {"exemplar": PHOTO, "refine": 3}),
    (["--exemplar", "grass", "--to", PHOTO, "--mix", "0.25"], {"exemplar": "grass", "to": PHOTO, "mix": 0.25}),
    (["--exemplar", "grass", "--to", "gravel"], {"exemplar": "grass", "to": "gravel"}),
    (["--exemplar", "gravel", "--model", "space"], {"exemplar": "gravel", "model": "space"}),
    (["--exemplar", PHOTO, "--no-periodic"], {"exemplar": PHOTO, "periodic": False}),
    (["--exemplar", PHOTO, "--no-gaussian"], {"exemplar": PHOTO, "gaussian": False}),
    (["--exemplar", PHOTO, "--rest", "upright"], {"exemplar": PHOTO, "rest": "upright"}),
])
def test_flags_and_job_tables_give_equal_requests(flags, table):
    a, b = cli(*flags), solid_request_from_dict(dict(table))
    assert a.key() == b.key() and a.folder() == b.folder()


def test_a_file_and_its_pixels_are_one_exemplar():
    """The panel hands over pixels, the command line a file: the same image is the same request."""
    by_file = SolidRequest(exemplar=PHOTO, refine=2)
    by_pixels = SolidRequest(exemplar=read_rgb(PHOTO), refine=2)
    assert by_file.key() == by_pixels.key()
    assert by_file.key() != SolidRequest(exemplar=PHOTO, refine=2, seed=1).key()
    assert by_file.key() != SolidRequest(exemplar=PHOTO, refine=2, periodic=False).key()
    assert by_file.key() != SolidRequest(exemplar=PHOTO, refine=2, gaussian=False).key()
    assert by_file.key() != SolidRequest(exemplar=PHOTO, refine=2, rest="isotropic").key()
    # without a Gaussian rest its kind changes nothing: the same texture, the same key
    assert SolidRequest(exemplar=PHOTO, gaussian=False, rest="upright").key() == \
        SolidRequest(exemplar=PHOTO, gaussian=False).key()


def test_a_file_is_decoded_once_per_request(tmp_path, monkeypatch):
    """The grid note and the fit read one decoding of the photo: again only where the file changed on disk; the
    pixels are read-only, the request keeps the path (its model and key), and a pickled request carries no pixels."""
    import pickle

    from PIL import Image

    from omninoise import export

    calls = []
    real = export.read_rgb
    monkeypatch.setattr(export, "read_rgb", lambda path: calls.append(path) or real(path))
    photo = str(tmp_path / "photo.png")
    Image.fromarray(np.full((24, 24, 3), 90, np.uint8)).save(photo)
    req = SolidRequest(exemplar=photo, method="procedural").check()
    first = req.exemplar_pixels()
    assert req.exemplar_pixels() is first and len(calls) == 1
    assert not req.repeats_as_grid() and len(calls) == 1
    with pytest.raises(ValueError, match="read-only"):
        first[0, 0, 0] = 1.0
    assert req.exemplar == photo and req.key() == SolidRequest(exemplar=real(photo), method="procedural").key()
    auto = req.replace(method="auto")            # method auto's stages and key share the decoding, and one hash
    from omninoise.backend.solid import request as request_module

    hashed = []
    real_sha = request_module._pixels_sha
    monkeypatch.setattr(request_module, "_pixels_sha", lambda x: hashed.append(1) or real_sha(x))
    assert auto.exemplar_pixels() is first and auto.key()["procedural"] == req.key() and len(calls) == 1
    assert len(hashed) == 2                      # auto's key, then the procedural request's own
    Image.fromarray(np.full((32, 32, 3), 200, np.uint8)).save(photo)    # changed on disk: read again
    again = req.exemplar_pixels()
    assert len(calls) == 2 and again.shape == (32, 32, 3) and np.allclose(again, 200 / 255)
    copy = pickle.loads(pickle.dumps(req))
    assert "_decoded" not in copy.__dict__ and copy.exemplar == photo
    assert copy.exemplar_pixels().shape == (32, 32, 3) and len(calls) == 3
    assert SolidRequest(exemplar=first).exemplar_pixels() is first       # pixels handed over are returned as they are


def test_periodic_and_gaussian_must_be_a_yes_or_no():
    with pytest.raises(SettingError, match="source.periodic: expected true or false"):
        solid_request_from_dict(dict(exemplar=PHOTO, periodic="yes"))
    with pytest.raises(SettingError, match="source.gaussian: expected true or false"):
        solid_request_from_dict(dict(exemplar=PHOTO, gaussian=1))
    with pytest.raises(SettingError, match="source.rest: expected one of auto, isotropic, upright, got 'sideways'"):
        solid_request_from_dict(dict(exemplar=PHOTO, rest="sideways"))
    with pytest.raises(SettingError, match="rest: expected one of"):
        SolidRequest(exemplar=PHOTO, rest=None).check()


def test_the_model_is_chosen_as_the_command_line_always_did():
    assert os.path.basename(SolidRequest(exemplar="gravel_3d").folder()) == "gravel_3d"   # its own model
    assert os.path.basename(SolidRequest(exemplar=PHOTO).folder()) == "space"           # an image: encoded
    assert os.path.basename(SolidRequest(exemplar="gravel_3d", to="x").folder()) == "space"


@pytest.mark.parametrize("flags, table, field, why", [
    (["--mix", "1.5", "--to", "grass"], {"mix": 1.5, "to": "grass"}, "mix", "must lie in [0, 1]"),
    (["--refine", "-1"], {"refine": -1}, "refine", "must lie in [0, 10000]"),
    (["--seed", "-3"], {"seed": -3}, "seed", "must lie in [0, 4294967295]"),
    (["--seed", str(2 ** 32)], {"seed": 2 ** 32}, "seed", "must lie in [0, 4294967295]"),
])
def test_the_same_errors_in_each_front_ends_terms(flags, table, field, why):
    with pytest.raises(SettingError) as e1:
        cli("--exemplar", "gravel", *flags)
    with pytest.raises(SettingError) as e2:
        solid_request_from_dict(dict(table, exemplar="gravel"))
    assert e1.value.setting == "--" + field and e2.value.setting == "source." + field
    assert why in str(e1.value) and why in str(e2.value)


def test_job_refine_must_be_a_whole_number():
    with pytest.raises(SettingError, match="source.refine"):
        solid_request_from_dict({"exemplar": "gravel", "refine": 2.5})
    assert np.isclose(solid_request_from_dict({"exemplar": "gravel"}).mix, 0.5)


CHANGES = dict(model="gravel_3d", to="gravel", mix=0.3, refine=3, periodic=False, gaussian=False, rest="upright",
               tile=128, families=("bonds",))


@pytest.mark.parametrize("method", ["neural", "synthesis", "spectral", "procedural", "auto"])
def test_what_each_method_reads_is_what_its_key_holds(method):
    """methods.READS, which the front ends check settings against, is what the request's key holds: a setting
    changes a method's key where the method reads it (mix where there is a ``to``), and a setting it does not read
    is refused by its check or leaves the key alone."""
    from omninoise.backend.solid.methods import READS

    base = SolidRequest(exemplar=PHOTO, method=method)
    for key, value in CHANGES.items():
        a = base.replace(to="grass") if key == "mix" and method == "neural" else base
        b = a.replace(**{key: value})
        try:
            b.check()
        except SettingError:
            assert key not in READS[method], key
            continue
        assert (b.key() != a.key()) == (key in READS[method]), key


@pytest.mark.parametrize("flags, table, api, name", [
    (["--method", "procedural", "--tile", "128"], {"method": "procedural", "tile": 128}, None, "tile"),
    (["--families", "bonds"], {"families": ["bonds"]}, dict(families=["bonds"]), "families"),
    (["--method", "spectral", "--no-gaussian"], {"method": "spectral", "gaussian": False}, None, "gaussian"),
    (["--method", "synthesis", "--no-periodic"], {"method": "synthesis", "periodic": False},
     dict(method="synthesis", periodic=False), "periodic"),
    (["--method", "procedural", "--model", "space"], {"method": "procedural", "model": "space"},
     dict(method="procedural", model="space"), "model"),
])
def test_a_setting_the_method_does_not_read_is_refused_by_each_front_end(tmp_path, flags, table, api, name):
    """A setting the method would ignore is named with the methods that read it, on the command line, in a job
    file and in the Python API, before any work."""
    import omninoise

    flag = {"periodic": "--no-periodic", "gaussian": "--no-gaussian"}.get(name, f"--{name}")
    with pytest.raises(SettingError, match=f"^{flag}: method .* does not read it; .* do(es)?$"):
        cli("--exemplar", PHOTO, *flags)
    with pytest.raises(SettingError, match=f"^source.{name}: method .* does not read it"):
        solid_request_from_dict(dict(table, exemplar=PHOTO))
    if api is not None:
        with pytest.raises(SettingError, match=f"^{name}: method .* does not read it"):
            omninoise.solid(PHOTO, 8, **api)
    assert cli("--exemplar", PHOTO, "--method", "auto", "--families", "bonds", "--no-gaussian").method == "auto"


@pytest.mark.parametrize("pixels, why", [
    (np.full((8, 8, 3), 128, np.uint8), r"floats in \[0, 1\], got uint8 \(divide 8-bit pixels by 255\)"),
    (np.full((8, 8, 3), 128.0), r"in \[0, 1\], got values in \[128, 128\]"),
    (np.full((8, 8, 3), -0.5), r"in \[0, 1\], got values in \[-0.5, -0.5\]"),
    (np.full((8, 8), 0.5), r"\(H, W, 3\), got shape \(8, 8\)"),
    (np.full((8, 8, 4), 0.5), r"\(H, W, 3\), got shape \(8, 8, 4\)"),
    (np.zeros((0, 8, 3)), r"got shape \(0, 8, 3\)"),
    (np.full((8, 8, 3), np.nan), "NaN or infinite"),
    (np.full((8, 8, 3), 0.5) + 0j, "got complex128"),
    (np.full((8, 8, 3), True), "got bool"),
    ([[[0.5] * 3] * 8] * 8, "got list"),
    (np.full((8, 8, 3), 0.5), r"the photo is 8 x 8 px; a texture is read from a photo of at least 16 px a side"),
    (np.full((40, 15, 3), 0.5), r"the photo is 15 x 40 px"),
])
@pytest.mark.parametrize("method", ["neural", "spectral", "synthesis", "procedural", "auto"])
def test_pixels_are_checked_alike_for_every_method(pixels, why, method):
    """Pixels handed over (the Python API, Blender's images) are sRGB floats (H, W, 3) in [0, 1] for every method:
    8-bit values, a grey or RGBA array, NaN, an empty array were read differently by each method (a white
    procedural solid from 0..255 floats, an IndexError from an empty array) and are now one error naming them."""
    with pytest.raises(SettingError, match=why) as exc:
        SolidRequest(exemplar=pixels, method=method).check("source.")
    assert exc.value.setting == "source.exemplar"
    if method == "neural":
        with pytest.raises(SettingError, match=why) as exc:
            SolidRequest(exemplar="grass", to=pixels, mix=0.5).check()
        assert exc.value.setting == "to"
    SolidRequest(exemplar=np.full((16, 16, 3), 0.5, np.float32), method=method).check()


@pytest.mark.parametrize("method", ["neural", "spectral", "procedural"])
def test_python_refuses_a_photo_file_under_16_px_a_side_before_any_work(tmp_path, method):
    """``omninoise.solid`` checks a photo file's pixels as the command line does, before the model is loaded or
    the output written: the neural texture encoded a 12 px photo where the other methods refuse it."""
    import omninoise
    from PIL import Image

    Image.fromarray(np.full((12, 40, 3), 90, np.uint8)).save(tmp_path / "small.png")
    with pytest.raises(SettingError, match=r"^exemplar: .*12"):
        omninoise.solid(str(tmp_path / "small.png"), 8, method=method, out=str(tmp_path / "o.png"))
    assert not (tmp_path / "o.png").exists()
