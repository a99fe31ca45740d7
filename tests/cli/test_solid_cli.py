"""The `omninoise solid` command-line contract, without torch (tiny committed models and the shipped space model)."""
import os
import re

import numpy as np
import pytest

from omninoise.cli.main import main
from omninoise.backend.paths import solid_models
from omninoise.backend.errors import SettingError
from omninoise.backend.solid.request import SolidRequest

TINY = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "tiny_solid")


@pytest.fixture(scope="module")
def models():
    """Tiny single-exemplar models (tools/make_tiny_model.py) and the shipped texture-space model: no torch."""
    return dict(single3=os.path.join(TINY, "single3"), single2=os.path.join(TINY, "single2"),
                space3=os.path.join(solid_models(), "space"))


def write_job(path, extent: float, model: str, source: str) -> None:
    """A job file baking one 8³ solid volume over [0, extent]³ into job.npy; ``source``: more source lines."""
    e = repr(extent)
    path.write_text(f"""
[[bake]]
name = "solid"
output = "job.npy"
resolution = [8, 8, 8]
bounds = [[0, 0, 0], [{e}, {e}, {e}]]
[bake.source]
kind = "solid"
model = "{model}"
{source}
""")


def run(capsys, *args):
    rc = main(["solid", "--quiet", *args])
    return rc, capsys.readouterr().err


def test_image_outputs(models, tmp_path, capsys):
    png, exr, npy = (str(tmp_path / f"a.{e}") for e in ("png", "exr", "npy"))
    assert run(capsys, "--model", models["single3"], "--exemplar", "gravel", "--size", "24", "-o", png)[0] == 0
    with open(png, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    assert run(capsys, "--model", models["single2"], "--exemplar", "gravel", "--size", "24", "-o", npy)[0] == 0
    a = np.load(npy)
    assert a.shape == (24, 24, 3) and a.dtype == np.float32 and 0.0 <= a.min() and a.max() <= 1.0
    # the .npy is scene-linear: the runtime's sRGB values, decoded
    from omninoise.backend.solid.bake import srgb_to_linear
    from omninoise.backend.solid.model import SolidTextureModel
    m = SolidTextureModel(models["single2"])
    np.testing.assert_allclose(a, srgb_to_linear(m.image(24, m.default_code(), 0)), atol=1e-6)
    assert run(capsys, "--model", models["single2"], "--exemplar", "gravel", "--size", "24", "--seed", "3",
               "-o", exr)[0] == 0
    from omninoise.export.images import read_image
    assert read_image(exr).shape == (24, 24)


def test_volume_outputs(models, tmp_path, capsys):
    npy, vdb = str(tmp_path / "v.npy"), str(tmp_path / "v.vdb")
    assert run(capsys, "--model", models["single3"], "--exemplar", "gravel", "--dim", "3", "--size", "12",
               "-o", npy)[0] == 0
    a = np.load(npy)
    assert a.shape == (12, 12, 12, 3)
    assert run(capsys, "--model", models["single3"], "--exemplar", "gravel", "--dim", "3", "--size", "12",
               "-o", vdb)[0] == 0
    from omninoise.export.vdb import read_volume
    col = read_volume(vdb, "color", (12, 12, 12))
    np.testing.assert_allclose(col, a, atol=1e-6)
    np.testing.assert_array_equal(read_volume(vdb, "density", (12, 12, 12)), 1.0)


def test_space_model_encode_and_interpolate(models, tmp_path, capsys):
    from PIL import Image
    img = tmp_path / "ex.png"
    Image.fromarray((np.random.default_rng(0).random((140, 150, 3)) * 255).astype(np.uint8)).save(img)
    outs = []
    for extra in ([], ["--to", "grass", "--mix", "0.0"], ["--to", "grass", "--mix", "1.0"]):
        p = str(tmp_path / f"s{len(outs)}.npy")
        assert run(capsys, "--model", models["space3"], "--exemplar", "gravel", "--size", "16", *extra, "-o", p)[0] == 0
        outs.append(np.load(p))
    np.testing.assert_allclose(outs[1], outs[0], atol=1e-6)      # mix 0 is the first exemplar
    assert np.abs(outs[2] - outs[0]).max() > 0                    # mix 1 is another texture
    p = str(tmp_path / "enc.png")
    assert run(capsys, "--model", models["space3"], "--exemplar", str(img), "--size", "16", "-o", p)[0] == 0


@pytest.mark.parametrize("args, msg", [
    (["--exemplar", "gravel"], "give --exemplar"),
    (["--exemplar", "gravel", "--size", "0", "-o", "x.png"], "--size: must be >= 1"),
    (["--exemplar", "gravel", "--to", "grass", "--mix", "2", "-o", "x.png"], "--mix: must lie in [0, 1]"),
    (["--exemplar", "gravel", "--mix", "0.2", "-o", "x.png"], "--mix: weighs the texture of --to"),
    (["--exemplar", "gravel", "--dim", "3", "-o", "x.png"], "a 3D result is written as .vdb, .npy"),
    (["--exemplar", "gravel", "--to", "grass", "-o", "x.png"], "interpolation needs the space model"),
])
def test_errors_single(models, capsys, args, msg):
    rc, err = run(capsys, "--model", models["single3"], *args)
    assert rc == 2 and msg in err and err.count("\n") == 1


def test_errors_models(models, tmp_path, capsys):
    rc, err = run(capsys, "--model", models["single2"], "--exemplar", "g", "--dim", "3", "-o", str(tmp_path / "a.npy"))
    assert rc == 2 and "is 2D; it cannot fill a volume" in err
    rc, err = run(capsys, "--model", models["space3"], "--exemplar", "nothing.png", "-o", str(tmp_path / "a.png"))
    assert rc == 2 and "neither an image file nor an exemplar the model knows (brick, concrete," in err
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not an image")
    rc, err = run(capsys, "--model", models["space3"], "--exemplar", str(bad), "-o", str(tmp_path / "a.png"))
    assert rc == 2 and "not an image file this reader knows" in err
    rc, err = run(capsys, "--model", str(tmp_path), "--exemplar", "x", "-o", str(tmp_path / "a.png"))
    assert rc == 2 and "no solid.json" in err
    assert not os.path.exists(tmp_path / "a.png")


def test_refine_option(models, tmp_path, capsys):
    from PIL import Image
    img = tmp_path / "ex.png"
    Image.fromarray((np.random.default_rng(1).random((130, 130, 3)) * 255).astype(np.uint8)).save(img)
    p = str(tmp_path / "r.npy")
    rc = main(["solid", "--model", models["space3"], "--exemplar", str(img), "--refine", "3", "--size", "8", "-o", p])
    err = capsys.readouterr().err
    assert rc == 0 and "neighbourhood distance" in err and np.load(p).shape == (8, 8, 3)
    rc, err = run(capsys, "--model", models["single3"], "--exemplar", "gravel", "--refine", "3", "-o", p)
    assert rc == 2 and "--refine: refinement fits the code to a photo; 'gravel' is a shipped texture" in err
    with pytest.raises(SettingError, match="refine: refinement fits the code to a photo; the model's one texture is "
                                           "drawn from the model's own code: it would change nothing"):
        SolidRequest(models["single3"], None, refine=3).check().check_reads(["refine"])


def test_a_job_file_interpolates_as_the_command_line(models, tmp_path, capsys):
    """`to` and `mix` in a job file (job files take everything the command line does) give the volume
    `omninoise solid --to --mix` writes."""
    from omninoise.backend.solid.model import SolidTextureModel

    space = SolidTextureModel(models["space3"])
    cli = str(tmp_path / "cli.npy")
    assert run(capsys, "--model", models["space3"], "--exemplar", "gravel", "--to", "wood", "--mix", "0.3", "--dim", "3",
               "--size", "8", "--seed", "2", "-o", cli)[0] == 0
    write_job(tmp_path / "job.toml", 8 / space.px_per_unit, models["space3"], 'exemplar = "gravel"\nto = "wood"\nmix = 0.3\nseed = 2')
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "job.npy"), np.load(cli))
    (tmp_path / "job.toml").write_text((tmp_path / "job.toml").read_text().replace("mix = 0.3", "mix = 1.5"))
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 2
    assert "source.mix: must lie in [0, 1], got 1.5" in capsys.readouterr().err


@pytest.mark.long
def test_texture_codes_are_made_in_one_place(models, tmp_path):
    """A file, the same pixels (the panel's input) and a training exemplar's name all go through texture_code."""
    from PIL import Image

    from omninoise.backend.errors import SettingError
    from omninoise.backend.solid.model import SolidTextureModel
    from omninoise.backend.solid.pipeline import texture_code
    from omninoise.export.images import read_rgb

    space, single = SolidTextureModel(models["space3"]), SolidTextureModel(models["single3"])
    img = tmp_path / "ex.png"
    Image.fromarray((np.random.default_rng(2).random((130, 140, 3)) * 255).astype(np.uint8)).save(img)
    a, sha_a = texture_code(space, str(img))
    b, sha_b = texture_code(space, read_rgb(str(img)))
    np.testing.assert_array_equal(a.e, b.e)
    assert sha_a == sha_b is not None
    named, sha = texture_code(space, "grass")
    np.testing.assert_array_equal(named.e, space.code("grass").e)
    assert sha is None
    assert texture_code(single, "gravel")[0].e is not None  # its own exemplar's name
    for kw, msg in [(dict(exemplar="grass"), "holds one texture; another exemplar needs the space model"),
                    (dict(exemplar=None, to="grass"), "interpolation needs the space model"),
                    (dict(exemplar=None, mix=float("nan")), r"mix: must be in \[0, 1\]")]:
        with pytest.raises(SettingError, match=msg):
            texture_code(single, **kw)
    with pytest.raises(SettingError, match="needs an exemplar"):
        texture_code(space)


@pytest.mark.long
def test_the_periodic_part_is_on_by_default_and_can_be_left_out(models, tmp_path, capsys):
    """An encoded brick photo keeps its courses (backend/solid/harmonic.py) unless --no-periodic; a job file's
    `periodic = false` gives the volume `--no-periodic` writes."""
    from omninoise.backend.solid.model import SolidTextureModel
    from omninoise.export.images import read_rgb

    photo = os.path.join(os.path.dirname(TINY), "..", "..", "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
    on, off = str(tmp_path / "on.npy"), str(tmp_path / "off.npy")
    assert run(capsys, "--model", models["space3"], "--exemplar", photo, "--size", "64", "-o", on)[0] == 0
    assert run(capsys, "--model", models["space3"], "--exemplar", photo, "--size", "64", "--no-periodic", "-o", off)[0] == 0
    rc = main(["solid", "--model", models["space3"], "--exemplar", photo, "--size", "8", "-o", str(tmp_path / "x.npy")])
    assert rc == 0 and "periodic part: 73 waves at spectral peaks, 85 % of the photo's variance" in capsys.readouterr().err
    lum = read_rgb(photo)[:64, :64].mean(2).ravel()
    r_on = np.corrcoef(np.load(on).mean(2).ravel(), lum)[0, 1]
    r_off = np.corrcoef(np.load(off).mean(2).ravel(), lum)[0, 1]
    assert r_on > 0.5 and abs(r_off) < 0.2
    space = SolidTextureModel(models["space3"])
    cli = str(tmp_path / "cli.npy")
    assert run(capsys, "--model", models["space3"], "--exemplar", photo, "--no-periodic", "--dim", "3", "--size", "8",
               "-o", cli)[0] == 0
    write_job(tmp_path / "job.toml", 8 / space.px_per_unit, models["space3"], f'exemplar = "{photo}"\nperiodic = false')
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "job.npy"), np.load(cli))


@pytest.mark.long
def test_the_gaussian_rest_is_said_and_can_be_left_out(models, tmp_path, capsys):
    """A held-out rock face the decoder draws too coarse gets its Gaussian rest (backend/solid/gaussian_rest.py), and
    the command says so; --no-gaussian and a job file's `gaussian = false` leave it out alike."""
    from omninoise.backend.solid.model import SolidTextureModel

    photo = os.path.join(os.path.dirname(TINY), "..", "..", "data", "photos", "val", "rock__rock_grey.jpg")
    rc = main(["solid", "--model", models["space3"], "--exemplar", photo, "--size", "8", "-o", str(tmp_path / "x.npy")])
    assert rc == 0 and re.search(r"gaussian rest: \d+ % of the rest's variance drawn as an? (isotropic|upright) "
                                 "Gaussian solid", capsys.readouterr().err)
    rc = main(["solid", "--model", models["space3"], "--exemplar", photo, "--size", "8", "--rest", "isotropic",
               "-o", str(tmp_path / "x.npy")])
    assert rc == 0 and "drawn as an isotropic Gaussian solid" in capsys.readouterr().err
    on, off = str(tmp_path / "on.npy"), str(tmp_path / "off.npy")
    assert run(capsys, "--model", models["space3"], "--exemplar", photo, "--dim", "3", "--size", "8", "-o", on)[0] == 0
    assert run(capsys, "--model", models["space3"], "--exemplar", photo, "--dim", "3", "--size", "8", "--no-gaussian",
               "-o", off)[0] == 0
    assert np.abs(np.load(on) - np.load(off)).mean() > 0.01
    space = SolidTextureModel(models["space3"])
    write_job(tmp_path / "job.toml", 8 / space.px_per_unit, models["space3"], f'exemplar = "{photo}"\ngaussian = false')
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "job.npy"), np.load(off))


def test_a_job_encodes_its_photo_when_it_bakes_its_file_only(models, tmp_path, monkeypatch, capsys):
    """A neural solid of a photo in a job file: reading the job, a dry run and an up-to-date bake encode nothing;
    the bake encodes once and writes the volume the command line writes; a setting the encoding reads (periodic)
    makes the bake due again."""
    from PIL import Image

    from omninoise.backend.jobs import load_job
    from omninoise.backend.solid.model import SolidTextureModel
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.backend.sources import EncodedSource

    encoded = []
    real_code = SolidRequest.code
    monkeypatch.setattr(SolidRequest, "code", lambda self, *a, **k: encoded.append(1) or real_code(self, *a, **k))
    Image.fromarray((np.random.default_rng(4).random((70, 90, 3)) * 255).astype(np.uint8)).save(tmp_path / "p.png")
    space = SolidTextureModel(models["space3"])
    write_job(tmp_path / "job.toml", 8 / space.px_per_unit, models["space3"], 'exemplar = "p.png"\nseed = 2')
    src = dict(load_job(str(tmp_path / "job.toml")))["solid"].source
    assert isinstance(src, EncodedSource) and not src.ready and encoded == []
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 0 and encoded == []
    assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 0 and encoded == [1]
    cli = str(tmp_path / "cli.npy")
    assert run(capsys, "--model", models["space3"], "--exemplar", str(tmp_path / "p.png"), "--dim", "3", "--size", "8",
               "--seed", "2", "-o", cli)[0] == 0
    np.testing.assert_array_equal(np.load(tmp_path / "job.npy"), np.load(cli))
    job = tmp_path / "job.toml"
    job.write_text(job.read_text().replace('"job.npy"', '"job.exr"').replace("[8, 8, 8]", "[8, 8]"))
    encoded.clear()
    assert main(["bake", str(job), "--quiet"]) == 0 and encoded == [1]      # .npy files carry no key; .exr do
    encoded.clear()
    capsys.readouterr()
    assert main(["bake", str(job)]) == 0 and encoded == []
    assert "up to date" in "".join(capsys.readouterr())
    job.write_text(job.read_text() + "periodic = false\n")
    assert main(["bake", str(job), "--dry-run"]) == 0 and encoded == []
    assert "to bake" in capsys.readouterr().out


@pytest.mark.parametrize("shape", [(1, 600), (600, 2), (1, 1), (16, 600)])
def test_a_photo_under_16_px_a_side_is_refused_and_a_strip_of_16_encodes(models, tmp_path, capsys, shape):
    """Every method reads its texture from a photo at least 16 px a side: a line or a pixel is refused in one line
    naming the flag, before any work, as the image methods refuse it; a strip 16 px across (too thin for a lattice
    or line of the harmonic part to read) gives a texture."""
    from PIL import Image

    Image.fromarray((np.random.default_rng(1).random(shape + (3,)) * 255).astype(np.uint8)).save(tmp_path / "p.png")
    out = str(tmp_path / "o.npy")
    rc, err = run(capsys, "--model", models["space3"], "--exemplar", str(tmp_path / "p.png"), "--size", "8", "-o", out)
    if min(shape) < 16:
        assert rc == 2 and err.strip().endswith(f"--exemplar: the photo is {shape[1]} x {shape[0]} px; a texture is "
                                                "read from a photo of at least 16 px a side"), err
        assert not os.path.exists(out)
        return
    assert rc == 0, err
    assert np.isfinite(np.load(out)).all()


@pytest.mark.parametrize("flag", ["--exemplar", "--to"])
def test_a_photo_the_encoder_cannot_read_is_named_before_its_note(models, tmp_path, capsys, flag):
    """Without --quiet the neural method says "encoding PHOTO ..." before it encodes: a photo it cannot read (here
    one holding NaN, and one with transparent pixels) is refused in one line naming the flag, not glued to the note;
    a job file names the same setting when it is read."""
    import OpenEXR
    from PIL import Image

    good = tmp_path / "good.png"
    Image.fromarray((np.random.default_rng(0).random((40, 40, 3)) * 255).astype(np.uint8)).save(good)
    nan = np.full((40, 40, 3), 0.5, np.float32)
    nan[3, 4] = np.nan
    with OpenEXR.File({"type": OpenEXR.scanlineimage}, {"RGB": nan}) as f:
        f.write(str(tmp_path / "nan.exr"))
    Image.fromarray(np.zeros((40, 40, 4), np.uint8)).save(tmp_path / "clear.png")
    for bad, why in (("nan.exr", "holds NaN"), ("clear.png", "partly transparent")):
        args = ["--exemplar", str(tmp_path / bad)] if flag == "--exemplar" else \
            ["--exemplar", str(good), "--to", str(tmp_path / bad)]
        rc = main(["solid", "--model", models["space3"], *args, "--size", "8", "-o", str(tmp_path / "o.png")])
        err = capsys.readouterr().err
        assert rc == 2 and err.startswith(f"omninoise solid: error: {flag}: ") and why in err, err
        assert err.count("\n") == 1 and not (tmp_path / "o.png").exists()
    source = f'exemplar = "{good.name}"\nto = "nan.exr"' if flag == "--to" else 'exemplar = "nan.exr"'
    write_job(tmp_path / "job.toml", 1.0, models["space3"], source)
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 2
    assert f"bake 'solid': source.{flag[2:]}: " in capsys.readouterr().out


def test_encoding_a_photo_shows_its_bar(models, tmp_path, capsys):
    """Without --quiet, a photo's encoding (its stages and the Gaussian rest's check: seconds) moves a bar of its
    own, a line per tenth in a log, before the drawing's; a shipped exemplar's stored code needs none."""
    from PIL import Image

    photo = str(tmp_path / "p.png")
    Image.fromarray((np.random.default_rng(3).random((64, 64, 3)) * 255).astype(np.uint8)).save(photo)
    assert main(["solid", "--model", models["space3"], "--exemplar", photo, "--size", "8",
                 "-o", str(tmp_path / "o.png")]) == 0
    lines = capsys.readouterr().err.splitlines()
    bar = [ln for ln in lines if ln.startswith("encoding [")]
    assert len(bar) >= 5 and "100.0%" in bar[-1], lines
    assert lines.index(bar[-1]) < max(i for i, ln in enumerate(lines) if ln.startswith("drawing ["))
    assert main(["solid", "--model", models["space3"], "--exemplar", "gravel", "--size", "8",
                 "-o", str(tmp_path / "o.png")]) == 0
    assert "encoding" not in capsys.readouterr().err


def test_the_neural_method_decodes_a_photo_once(models, tmp_path, capsys, monkeypatch):
    """The command line's check of the photos (``--exemplar``, ``--to``) and the encoding share one decoding of each
    file (a 12 MP photo takes 0.7 s to decode)."""
    from PIL import Image

    from omninoise import export

    photo = str(tmp_path / "p.png")
    Image.fromarray((np.random.default_rng(3).random((48, 48, 3)) * 255).astype(np.uint8)).save(photo)
    reads, real = [], export.read_rgb
    monkeypatch.setattr(export, "read_rgb", lambda path: reads.append(path) or real(path))
    rc, err = run(capsys, "--model", models["space3"], "--exemplar", photo, "--size", "8",
                  "-o", str(tmp_path / "o.png"))
    assert rc == 0, err
    assert reads == [photo]
    other = str(tmp_path / "q.png")                     # with --to, each file once
    Image.fromarray((np.random.default_rng(4).random((48, 48, 3)) * 255).astype(np.uint8)).save(other)
    reads.clear()
    rc, err = run(capsys, "--model", models["space3"], "--exemplar", photo, "--to", other, "--mix", "0.5",
                  "--size", "8", "-o", str(tmp_path / "o.png"))
    assert rc == 0, err
    assert sorted(reads) == [photo, other]
