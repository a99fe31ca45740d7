"""The Python API (omninoise.wave, neural, solid) refuses a bad argument with a SettingError naming it, before any
work: never a TypeError, ValueError or AttributeError from deep inside, never a file opened by a number."""
import numpy as np
import pytest

import omninoise
from omninoise.backend.errors import SettingError

CASES = [
    (lambda: omninoise.wave(8, seed=None), "seed", "expected a value, got None"),
    (lambda: omninoise.wave(8, spectrum=None), "spectrum", "expected a value, got None"),
    (lambda: omninoise.neural("perlin", 16, model=3), "model", "expected a model folder's path, got 3"),  # TypeError
    # a tuple of another length: fmax was taken as 8 unsaid, a fifth number as a split bandpass does not read
    (lambda: omninoise.wave(8, spectrum=("bandpass", 4)), "spectrum", r"\(kind, fmin, fmax\[, exponent\]\) tuple"),
    (lambda: omninoise.wave(8, spectrum=("bandpass", 4, 8, 1, 5)), "spectrum", r"tuple, got \('bandpass', 4, 8"),
    (lambda: omninoise.wave(8, directions=None), "directions", "expected a value, got None"),
    (lambda: omninoise.wave(8, extent=1e300), "extent", r"must lie in \[1e-06, 1e\+07\]"),
    (lambda: omninoise.wave(8, extent=0), "extent", "must lie in"),
    (lambda: omninoise.wave(8, out=3), "out", "expected a file path, got 3"),
    (lambda: omninoise.wave(8, out="/"), "out", "output path is a folder, not a file: /"),    # not "written as"
    (lambda: omninoise.solid("grass", 8, out="/"), "out", "output path is a folder, not a file: /"),
    (lambda: omninoise.wave(8, transfer=3, out="x.png"), "transfer", "expected a preset name or a ramp .json file"),
    (lambda: omninoise.neural("perlin", 16, steps=1, params={"scale": "x"}), "param", "scale: expected a number"),
    (lambda: omninoise.neural("perlin", 16, steps=1, params=[1]), "param", "expected a table of parameter values"),
    (lambda: omninoise.neural("perlin", 16, steps=1, params={"scale": True}), "param", "expected a number"),
    (lambda: omninoise.solid("grass", 8, out=3), "out", "expected a file path"),
    (lambda: omninoise.solid(np.full((8, 8, 3), 200, np.uint8), 8), "exemplar", "divide 8-bit pixels by 255"),
    (lambda: omninoise.solid("grass", 8, model=3), "model", "expected a model folder or a shipped model's name"),
    (lambda: omninoise.solid("grass", 8, progress=3), "progress", "expected a function of the fraction done"),
    (lambda: omninoise.wave(8, progress="bar"), "progress", "expected a function"),
    (lambda: omninoise.neural("perlin", 16, steps=1, progress=1), "progress", "expected a function"),
    (lambda: omninoise.bake("job.toml", progress=1), "progress", "expected a function"),
    (lambda: omninoise.bake("job.toml", only="clouds"), "only", "expected a list of bake names"),
    (lambda: omninoise.bake(3), "job", "expected a job file's path, got 3"),
    (lambda: omninoise.bake("job.toml", only=[]), "only", "names no bake: leave it out to run every bake"),
    (lambda: omninoise.bake("job.toml", force="no"), "force", "expected True or False, got 'no'"),
    (lambda: omninoise.bake("job.toml", keep_going=1), "keep_going", "expected True or False, got 1"),
    (lambda: omninoise.wave(8, half="no", out="x.exr"), "half", "expected True or False, got 'no'"),
    (lambda: omninoise.wave(8, half=True), "half", "give out= too"),
    (lambda: omninoise.wave(8, half=True, out="x.npy"), "half", "into .exr and .vdb only"),
    (lambda: omninoise.wave(8, transfer="fire", out="x.npy"), "transfer", ".npy holds the raw values"),
    (lambda: omninoise.wave(8, time=1.0), "time", "is read only with speed"),
    (lambda: omninoise.wave(8, waveform="custom", profile=np.zeros((2, 2))), "profile[0]",
     r"expected a number, got \[0.0, 0.0\]"),
    (lambda: omninoise.wave(8, profile=[0.0, 1.0, 0.0]), "profile", "is read only with waveform='custom'"),
    (lambda: omninoise.wave(8, anisotropy="lobes", lobes=5), "lobes", "expected a list of 1 to 64 items"),
    (lambda: omninoise.wave(8, seed=1 << 24), "seed", r"must lie in \[0, 16777215\]"),
    (lambda: omninoise.wave(8, transition_to=("gaussian", 1, 2), transition_axis=(0, 0)), "transition_axis",
     "must be a non-zero 2-vector"),
    (lambda: omninoise.wave(8, anisotropy="axes", axis_spectra=[("gaussian", 1, 2)]), "axis_spectra",
     "needs 2 spectra, one per axis, got 1"),
    (lambda: omninoise.wave(8, waveform="custom", profile=[1.0, 1.0]), "profile", "samples that vary"),
    (lambda: omninoise.solid("photo.png", 64, method="procedural", out="wall.json"), "size",
     "a .json output holds the fitted solid"),
    (lambda: omninoise.solid("photo.png", dim=3, method="procedural", out="wall.json"), "dim",
     "a .json output holds the fitted solid"),
]


def test_a_tuple_setting_may_be_a_list_or_an_array():
    """Python users hand over lists and numpy arrays where the settings hold tuples: the noise is the same."""
    profile = np.sin(np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)) ** 3
    ref = omninoise.wave(8, waveform="custom", profile=tuple(profile.tolist()), seed=3)
    np.testing.assert_array_equal(omninoise.wave(8, waveform="custom", profile=profile, seed=3), ref)
    np.testing.assert_array_equal(omninoise.wave(8, waveform="custom", profile=list(profile), seed=3), ref)
    lobes = omninoise.wave(8, dim=3, anisotropy="lobes", lobes=[[[0, 0, 1], 1.0]], seed=3)
    np.testing.assert_array_equal(lobes, omninoise.wave(8, dim=3, anisotropy="lobes", lobes=(((0, 0, 1), 1.0),),
                                                        seed=3))


def test_every_spectrum_setting_takes_the_spectrum_forms():
    """The transition's and the axes' spectra take the forms ``spectrum`` takes (a Spectrum, a dict, a tuple), as
    their job-file tables are read; they crashed with an AttributeError as dicts or tuples."""
    from omninoise.backend.wavenoise.spectra import Spectrum

    a, b = Spectrum("gaussian", 1.0, 2.0), Spectrum("bandpass", 2.0, 4.0)
    ref = omninoise.wave(8, transition_to=a, seed=2)
    assert np.isfinite(ref).all() and ref.std() > 0.1
    for form in (("gaussian", 1, 2), {"kind": "gaussian", "fmin": 1, "fmax": 2}):
        np.testing.assert_array_equal(omninoise.wave(8, transition_to=form, seed=2), ref)
    ref = omninoise.wave(8, anisotropy="axes", axis_spectra=(a, b), seed=2)
    np.testing.assert_array_equal(omninoise.wave(8, anisotropy="axes", axis_spectra=[
        ("gaussian", 1, 2), {"kind": "bandpass", "fmin": 2, "fmax": 4}], seed=2), ref)
    np.testing.assert_array_equal(omninoise.wave(8, spectrum="bandpass", seed=2),
                                  omninoise.wave(8, spectrum=Spectrum("bandpass"), seed=2))


@pytest.mark.parametrize("call, setting, why", CASES)
def test_a_bad_argument_is_a_setting_error_naming_it(call, setting, why, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SettingError, match=why) as exc:
        call()
    assert exc.value.setting == setting
    assert list(tmp_path.iterdir()) == []


def test_a_transfer_path_may_be_a_path_object(tmp_path):
    """A pathlib.Path is a path like a str (out and transfer)."""
    import json

    ramp = tmp_path / "ramp.json"
    ramp.write_text(json.dumps({"range": [-1, 1], "stops": [[0, [0, 0, 0, 0]], [1, [1, 1, 1, 1]]]}))
    assert str(omninoise.wave(8, out=tmp_path / "o.png", transfer=ramp)) == str(tmp_path / "o.png")
    assert (tmp_path / "o.png").stat().st_size > 0



def test_a_photo_may_be_a_path_object(tmp_path):
    """solid's exemplar, a file, as a pathlib.Path: the same texture as its str; out and a model folder as Paths."""
    from omninoise.export.images import write_unit_image

    photo = tmp_path / "photo.png"
    write_unit_image(str(photo), np.random.default_rng(1).random((40, 40, 3)))
    by_path = omninoise.solid(photo, 8, seed=2)
    np.testing.assert_array_equal(by_path, omninoise.solid(str(photo), 8, seed=2))
    assert str(omninoise.solid(photo, 8, out=tmp_path / "s.png")) == str(tmp_path / "s.png")
    from omninoise.backend.paths import solid_models
    from pathlib import Path

    folder = Path(solid_models()) / "gravel_3d"                 # a model folder as a Path
    np.testing.assert_array_equal(omninoise.solid("gravel_3d", 8, model=folder), omninoise.solid("gravel_3d", 8))


def test_grey_and_rgba_pixels_are_read_as_their_files_are():
    """A photo's pixels as grey (H, W) or (H, W, 1), or with an opaque alpha (H, W, 4): the texture of their RGB
    (H, W, 3), as a grey or RGBA image file is read; a transparent pixel is refused as in a file."""
    grey = np.random.default_rng(2).random((40, 40)).astype(np.float32)
    rgb = np.repeat(grey[..., None], 3, axis=2)
    ref = omninoise.solid(rgb, 8, method="neural", seed=1)
    rgba = np.concatenate([rgb, np.ones((40, 40, 1), np.float32)], axis=2)
    for pixels in (grey, grey[..., None], rgba, grey.astype(np.float64)):
        np.testing.assert_array_equal(omninoise.solid(pixels, 8, method="neural", seed=1), ref)
    rgba[3, 4, 3] = 0.5
    with pytest.raises(SettingError, match=r"^exemplar: the image is partly transparent \(alpha below 1 on 0.0625 %"):
        omninoise.solid(rgba, 8, method="neural")


def test_a_photo_of_one_colour_draws_that_colour():
    """Nothing varies in a photo of one colour: the neural texture draws the colour alone, as the spectral and
    procedural solids do. It drew a mottle of its own (up to 0.03 off in sRGB) with a tint: the colour covariance
    its decoder is scaled by is floored (1e-4) as the model was trained. The spectral solid has no power to lift
    and the procedural fit nothing to search: neither spends its usual seconds on it."""
    from omninoise.export.images import linear_to_srgb

    colour = np.array([0.5, 0.3, 0.2], np.float32)
    photo = np.broadcast_to(colour, (48, 48, 3)).copy()
    for method, dim, size in (("neural", 2, 32), ("neural", 3, 12), ("spectral", 3, 12), ("procedural", 2, 32),
                              ("auto", 3, 12)):
        out = omninoise.solid(photo, size, dim=dim, method=method, seed=2)
        assert out.shape == (size,) * dim + (3,)
        np.testing.assert_allclose(linear_to_srgb(out).reshape(-1, 3), np.broadcast_to(colour, (size ** dim, 3)),
                                   atol=2e-6, err_msg=method)


def test_an_unknown_wave_setting_is_a_type_error_naming_wave_and_its_settings():
    """As for any Python function, an unknown keyword is a TypeError, from ``wave`` itself (not from the settings
    class behind it), listing the settings it takes."""
    with pytest.raises(TypeError, match=r"^wave\(\) got an unexpected keyword argument 'colour'; its settings are "
                                        r"dim, .*spectrum") as exc:
        omninoise.wave(8, colour=3)
    assert "WaveSettings" not in str(exc.value)
