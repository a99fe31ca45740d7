"""A bake written as a job file (backend/job_file.py, the Bake Noise panel's Save as Job File) bakes the same files
again through ``omninoise bake``: the same values, frames and ramps; settings that change nothing are left out, as
the job reader refuses them; what cannot be a job is refused in one line, before anything is written."""
import doctest
import functools
import os

import numpy as np
import pytest

from omninoise.backend import Spectrum, WaveSettings
from omninoise.backend.bake import BakeSpec, frame_path, run_bake
from omninoise.backend.errors import SettingError
from omninoise.backend.jobs import load_job, run_job
from omninoise.backend.sources import BoxGrid, WaveSource, source_from_dict
from omninoise.backend.transfer import TransferFunction, preset
from omninoise.backend import job_file
from omninoise.cli.main import main
from omninoise.export import read_volume
from omninoise.export.images import decode

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BOX = ((-1.0, -0.5, 0.0), (1.0, 0.5, 1.25))


def _spec(tmp_path, output, settings, resolution=(12, 10, 6), **kw):
    return BakeSpec("noise", WaveSource(settings, kw.pop("w_offset", 0.0)), BoxGrid(resolution, BOX),
                    str(tmp_path / output), make_folders=True, **kw).validate()


def _read(spec, frame):
    path = frame_path(spec.output, frame)
    ext = os.path.splitext(path)[1]
    if ext == ".vdb":        # every grid a fire ramp writes
        grids = [read_volume(path, name, spec.grid.shape) for name in ("density", "color", "temperature")]
        return np.concatenate([g.reshape(g.shape[:3] + (-1,)) for g in grids], axis=3)
    return np.load(path) if ext == ".npy" else decode(path)


def _baked(spec) -> list:
    run_bake(spec)
    out = [_read(spec, f) for f in spec.frame_list()]
    for f in spec.frame_list():
        os.remove(frame_path(spec.output, f))
    return out


RAMP = TransferFunction(stops=tuple((i / 256, (i / 256, (i / 256) ** 2, 0.3 + i / 1000, 1.0 - i / 300))
                                    for i in range(257)), range=(-0.7, 0.9)).validate()   # a sampled B-spline's 257

CASES = {
    "animated volume through fire": dict(
        output="vol/fire_###.vdb", frames=(3, 4), time=0.25, time_step=0.125, transfer=preset("fire"),
        settings=WaveSettings(dim=3, spectrum=Spectrum("fractal", 0.5, 12.0, 1.2), speed=0.7, seed=11)),
    "4D image, half EXR, a sampled ramp": dict(
        output="img/w.exr", resolution=(16, 12), time=0.6, half=True, transfer=RAMP, w_offset=0.3,
        settings=WaveSettings(dim=4, spectrum=Spectrum("bandpass", 2.0, 5.0), directions=24, seed=3)),
    "STIT cells, raw": dict(
        output="cells.npy", settings=WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2.0, 6.0),
                                                  cellular="stit", stit_probability=0.3, stit_depth=2, seed=5)),
    "lobes, crystal waves": dict(
        output="lobes.npy", settings=WaveSettings(dim=3, waveform="crystal", anisotropy="lobes",
                                                  lobes=(((0.0, 0.6, 0.8), 1.0),), spread=12.0, output="modulus")),
    "per-axis spectra, a transition": dict(
        output="axes.npy", settings=WaveSettings(dim=3, anisotropy="axes", axis_spectra=(
            Spectrum("bandpass", 1, 2), Spectrum("bandpass", 4, 6), Spectrum("fractal", 2, 8, 1.5)),
            transition_to=Spectrum("gaussian", 6, 9), transition_origin=(0.0, 0.0, 0.0),
            transition_axis=(1.0, 0.0, 0.0), transition_length=1.5)),
}


@pytest.mark.parametrize("case", CASES)
def test_a_saved_job_bakes_the_same_files(tmp_path, case):
    kw = dict(CASES[case])
    spec = _spec(tmp_path, kw.pop("output"), kw.pop("settings"), **kw)
    expected = _baked(spec)
    job = tmp_path / "job.toml"
    text = job_file.write_job(str(job), [spec])
    assert job.read_text() == text and text.startswith(job_file.HEADER)
    (name, parsed), = load_job(str(job))
    assert name == "noise" and parsed.frame_list() == spec.frame_list()
    assert [o.status for o in run_job(str(job))] == ["baked"]
    for f, want in zip(spec.frame_list(), expected):
        got = _read(spec, f)
        assert got.dtype == want.dtype and np.array_equal(got, want), case
    assert all(parsed.key(f) == spec.key(f) for f in spec.frame_list())    # its files are up to date for both


def test_settings_that_change_nothing_are_left_out(tmp_path):
    """A band-pass spectrum's exponent, a cell size without cells, a lobe spread without lobes and the time of still
    noise change no value; the job reader refuses each, so the job leaves them out and bakes the same values."""
    settings = WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5, exponent=2.5), cell_size=0.3, spread=40.0,
                            stit_depth=5, seed=2)
    spec = _spec(tmp_path, "still.npy", settings, time=0.5)
    expected = _baked(spec)
    text = job_file.write_job(str(tmp_path / "job.toml"), [spec])
    for key in ("exponent", "cell_size", "spread", "stit_depth", "time"):
        assert f"{key} =" not in text, key
    assert run_job(str(tmp_path / "job.toml"))[0].status == "baked"
    assert np.array_equal(np.load(spec.output), expected[0])


def test_outputs_outside_the_job_folder_get_an_output_root(tmp_path):
    spec = _spec(tmp_path, "renders/a.npy", WaveSettings(dim=3))
    (tmp_path / "jobs").mkdir()
    text = job_file.write_job(str(tmp_path / "jobs" / "a.toml"), [spec])
    assert 'output_root = "../renders"' in text and 'output = "../renders/a.npy"' in text
    assert main(["bake", str(tmp_path / "jobs" / "a.toml"), "-q"]) == 0
    assert np.load(spec.output).shape == (6, 10, 12)


def test_what_a_job_cannot_hold_is_refused_before_anything_is_written(tmp_path):
    spec = _spec(tmp_path, "a.npy", WaveSettings(dim=3))
    with pytest.raises(SettingError, match="a job file is a .toml file"):
        job_file.write_job(str(tmp_path / "job.json"), [spec])
    example = np.random.default_rng(0).random((32, 32)).astype(np.float32)
    by_example = _spec(tmp_path, "b.npy", WaveSettings(dim=2, example=example), resolution=(8, 8))
    with pytest.raises(SettingError, match="a job reads a by-example noise's image from a file"):
        job_file.write_job(str(tmp_path / "job.toml"), [by_example])
    assert sorted(os.listdir(tmp_path)) == []


@pytest.mark.parametrize("held", ["8-bit photo", "16-bit photo", "procedural solid", "neural photo"])
def test_a_solid_exemplar_held_in_memory_is_written_beside_its_job(tmp_path, monkeypatch, held):
    """A photo's pixels (a Blender image) or a procedural solid (a node group's) are written beside the job, as a
    PNG of the pixels' own depth or saved JSON, and the job bakes what the spec bakes."""
    from omninoise.backend.solid import spectral_solid
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.backend.sources import solid_source
    from omninoise.export.images import read_rgb

    monkeypatch.setattr(spectral_solid, "PERIOD", 32)
    photo = read_rgb(os.path.join(ROOT, "data", "photos", "val", "rock__cliff_greek.jpg"))[:160, :160]
    photo = photo if held != "16-bit photo" else np.clip(photo + np.float32(0.3 / 255), 0, 1)  # off the 8-bit grid
    exemplar = photo
    if held == "procedural solid":     # a wall of bricks with a turbulent tint ramp
        from omninoise.backend.solid.procedural.field import ProceduralField
        from omninoise.backend.solid.procedural.ramp import Ramp

        exemplar = ProceduralField("bonds", dict(length=0.4, height=0.1, offset=0.5, joint=0.2, turbulence=0.3,
                                                 turb_freq=2.0, detail=0.1),
                                   Ramp((-1.0, 0.5, 2.0), ((0.8, 0.8, 0.7), (0.5, 0.2, 0.1), (0.7, 0.3, 0.2))), seed=4)
    method = {"procedural solid": "procedural", "neural photo": "neural"}.get(held, "spectral")
    model = os.path.join(ROOT, "models", "solid", "space") if method == "neural" else None
    req = SolidRequest(model, exemplar, method=method, seed=0 if method == "procedural" else 2,
                       gaussian=False).check()      # a saved solid keeps its seed
    grid = BoxGrid((9, 8, 7), BOX)
    direct = BakeSpec("rock", solid_source(req, 1.5, 0.7), grid, str(tmp_path / "direct.npy")).validate()
    run_bake(direct, force=True)
    spec = BakeSpec("rock", solid_source(req, 1.5, 0.7), grid, str(tmp_path / "job.npy")).validate()
    text = job_file.write_job(str(tmp_path / "job.toml"), [spec])
    side = "job_solid.json" if held == "procedural solid" else "job_photo.png"
    assert f'exemplar = "{side}"' in text and "scale = 1.5" in text and "density = 0.7" in text
    if held != "procedural solid":
        depth = (tmp_path / side).read_bytes()[24]          # the PNG header's bit depth
        assert depth == (16 if held == "16-bit photo" else 8)
        assert np.abs(read_rgb(str(tmp_path / side)) - photo).max() < (1e-6 if depth == 8 else 1 / 131070 + 1e-7)
    assert [o.status for o in run_job(str(tmp_path / "job.toml"))] == ["baked"]
    np.testing.assert_allclose(np.load(tmp_path / "job.npy"), np.load(tmp_path / "direct.npy"), atol=2e-5)


def test_the_module_example_runs():
    res = doctest.testmod(job_file, optionflags=doctest.ELLIPSIS)
    assert res.attempted > 0 and res.failed == 0


def test_a_bakes_key_holds_what_determines_its_file_only(tmp_path):
    """Settings the noise does not read (a band-pass exponent, the time of still noise) leave a bake's key as it is,
    so a file baked with them is up to date for its job; a setting it reads changes the key."""
    base = _spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5)))
    same = [_spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5, exponent=3.0))),
            _spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5)), time=0.7),
            _spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5), cell_size=0.2))]
    other = [_spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 6))),
             _spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("fractal", 2, 5, exponent=3.0))),
             _spec(tmp_path, "a.npy", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 2, 5), speed=0.1), time=0.7)]
    assert all(s.key(None) == base.key(None) for s in same)
    assert len({s.key(None) for s in other} | {base.key(None)}) == 4


def test_names_and_paths_of_any_characters_survive_the_job(tmp_path):
    """Quotes, backslashes, tabs, DEL and characters past the BMP in a bake's name and file name: TOML's basic
    strings take them escaped, and the job names the same bake and file."""
    name = 'wall "A"\\\t\x7f \U0001f9f1 é'
    folder = tmp_path / "ü \U0001f9f1"
    spec = BakeSpec(name, WaveSource(WaveSettings(dim=3)), BoxGrid((4, 4, 2), BOX), str(folder / "v\x7fol.npy"),
                    make_folders=True).validate()
    job_file.write_job(str(tmp_path / "job.toml"), [spec])
    (got, parsed), = load_job(str(tmp_path / "job.toml"))
    assert got == name and parsed.output == spec.output


hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, assume, given, settings, strategies as st  # noqa: E402

SPECTRA = st.builds(Spectrum, kind=st.sampled_from(["gaussian", "white", "blue", "brown", "fractal", "bandpass",
                                                    "twolevel", "custom"]),
                    fmin=st.sampled_from([0.5, 1.0, 2.0, 3.3]), fmax=st.sampled_from([4.0, 6.5, 9.0]),
                    exponent=st.sampled_from([1.0, 0.5, 2.25]), split=st.sampled_from([0.25, 0.6]),
                    ratio=st.sampled_from([0.35, 0.8]), samples=st.sampled_from([(), (1.0, 0.5, 0.2)]))
WAVES = st.fixed_dictionaries({"dim": st.sampled_from([2, 3, 4]), "spectrum": SPECTRA}, optional={
    "directions": st.sampled_from([1, 5, 24]), "seed": st.sampled_from([0, 9, 2 ** 24 - 1]),
    "output": st.sampled_from(["real", "imag", "modulus", "phase"]), "speed": st.sampled_from([0.0, 0.4, -1.5]),
    "slice_width": st.sampled_from([None, 0.8]), "waveform": st.sampled_from(["gaussian", "crystal", "wired"]),
    "cellular": st.sampled_from(["none", "polytope", "code", "stit"]), "cell_size": st.sampled_from([None, 0.3]),
    "stit_probability": st.sampled_from([0.5, 0.2]), "stit_depth": st.sampled_from([3, 1]),
    "anisotropy": st.sampled_from(["none", "axes", "lobes"]), "spread": st.sampled_from([20.0, 7.5]),
    "transition_to": st.sampled_from([None, Spectrum("bandpass", 5, 7)]),
    "transition_length": st.sampled_from([1.0, 2.5]), "table_size": st.sampled_from([1024, 64]),
    "table_period": st.sampled_from([None, 30.0])})


@settings(deadline=None, database=None, derandomize=True, max_examples=120,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much])
@given(kw=WAVES, volume=st.booleans(), frames=st.booleans(), ramp=st.sampled_from([None, "fire", "marble", "RAMP"]),
       half=st.booleans(), time=st.sampled_from([0.0, 0.75]))
def test_any_wave_bake_is_written_as_a_job_that_reads_back_the_same(tmp_path_factory, kw, volume, frames, ramp, half,
                                                                     time):
    """Wave settings of every kind (spectra, waveforms, cellular modes, anisotropy, transitions, tables), volumes and
    images, sequences, ramps and half floats: each bake a spec takes is written, and write_job's own read-back finds
    the same keys and files (it raises otherwise)."""
    dim = kw["dim"]
    if kw.get("anisotropy") == "axes":
        kw["axis_spectra"] = tuple(Spectrum("bandpass", 1 + a, 3 + a) for a in range(dim))
    if kw.get("anisotropy") == "lobes":
        kw["lobes"] = ((tuple([0.6, 0.8, 0.0, 0.0][:dim]), 1.0),)
    if kw.get("transition_to") is not None:
        kw.update(transition_origin=(0.0,) * dim, transition_axis=(1.0,) + (0.0,) * (dim - 1))
    tmp = tmp_path_factory.mktemp("job")
    ext = (".vdb" if ramp else ".npy") if volume else (".exr" if half else ".png" if ramp else ".npy")
    try:
        s = WaveSettings(**kw).validate()
        spec = BakeSpec("b", WaveSource(s), BoxGrid((4, 3, 2) if volume else (4, 3), BOX),
                        str(tmp / ("out" + ("_##" if frames else "") + ext)), make_folders=True,
                        transfer={None: None, "RAMP": RAMP}.get(ramp, preset(ramp) if ramp else None),
                        frames=(1, 2) if frames else None, time=time, half=half).validate()
    except SettingError:
        assume(False)
    text = job_file.write_job(str(tmp / "job.toml"), [spec])
    (name, parsed), = load_job(str(tmp / "job.toml"))
    assert name == "b" and all(parsed.key(f) == spec.key(f) for f in spec.frame_list()), text


def test_omninoise_wave_saves_its_bake_as_a_job(tmp_path, capsys, monkeypatch):
    """`omninoise wave ... --save-job JOB.toml` writes the job instead of the file; `omninoise bake JOB.toml` then
    writes what `omninoise wave` writes."""
    flags = ["--dim", "3", "--size", "12", "--spectrum", "fractal", "--fmin", "1", "--fmax", "5", "--exponent",
             "1.4", "--speed", "0.3", "--time", "0.5", "--transfer", "marble", "--seed", "4"]
    monkeypatch.chdir(tmp_path)
    assert main(["wave", *flags, "-o", "direct.vdb", "-q"]) == 0
    assert main(["wave", *flags, "-o", "jobbed.vdb", "--save-job", "jobs.toml"]) == 0
    assert "wrote jobs.toml: omninoise bake jobs.toml bakes jobbed.vdb" in capsys.readouterr().err
    assert not os.path.exists("jobbed.vdb")
    assert main(["bake", "jobs.toml", "-q"]) == 0
    for grid, shape in (("density", (12, 12, 12)), ("color", (12, 12, 12))):
        np.testing.assert_array_equal(read_volume("jobbed.vdb", grid, shape), read_volume("direct.vdb", grid, shape))


@pytest.mark.parametrize("extra, message", [
    (["--save-job", "job.json"], "--save-job: a job file is a .toml file"),
    (["--save-job", "job.toml", "--example", "photo.png"], "--save-job: a job reads --example's image from a file"),
    (["--save-job", "no/such/job.toml"], "--save-job: output folder does not exist"),
])
def test_omninoise_wave_refuses_a_job_it_cannot_save_before_any_work(tmp_path, capsys, monkeypatch, extra, message):
    monkeypatch.chdir(tmp_path)
    from PIL import Image
    Image.new("L", (16, 16), 128).save("photo.png")
    assert main(["wave", "--size", "8", "-o", "a.png", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert message in err[-1] and sorted(os.listdir(tmp_path)) == ["photo.png"]


def test_the_python_api_saves_a_wave_bake_as_a_job(tmp_path):
    """omninoise.wave(..., out=, save_job=) writes the job, not the file; its bake is the file out= alone writes."""
    import omninoise

    kw = dict(dim=3, spectrum=("fractal", 1, 5, 1.3), speed=0.2, time=0.4, transfer="fire")
    assert omninoise.wave(10, out=str(tmp_path / "direct.vdb"), **kw) == str(tmp_path / "direct.vdb")
    job = tmp_path / "j.toml"
    assert omninoise.wave(10, out=str(tmp_path / "later.vdb"), save_job=str(job), **kw) == str(job)
    assert not (tmp_path / "later.vdb").exists() and run_job(str(job))[0].status == "baked"
    np.testing.assert_array_equal(read_volume(str(tmp_path / "later.vdb"), "temperature", (10, 10, 10)),
                                  read_volume(str(tmp_path / "direct.vdb"), "temperature", (10, 10, 10)))
    for bad, message in ((dict(save_job=str(job)), "save_job: applies to a written file; give out= too"),
                         (dict(out=str(tmp_path / "a.npy"), save_job="j.json"), "a job file is a .toml file"),
                         (dict(out=str(tmp_path / "a.npy"), save_job=str(tmp_path / "no" / "j.toml")),
                          "folder does not exist"),
                         (dict(out=str(tmp_path / "a.npy"), save_job=str(job), dim=2,
                               example=np.random.default_rng(0).random((16, 16)).astype(np.float32)),
                          "a job reads the example's image from a file")):
        with pytest.raises(SettingError, match=message):
            omninoise.wave(8, **bad)
    assert sorted(os.listdir(tmp_path)) == ["direct.vdb", "j.toml", "later.vdb"]


# -- neural noise: the Neural Noise panel's bakes ------------------------------------------------------------------

@functools.lru_cache(maxsize=1)
def _neural_model():
    from omninoise.backend.neural.model import NeuralNoiseModel
    from omninoise.backend.paths import neural_model

    return NeuralNoiseModel(neural_model())


_REGIONS = np.zeros((24, 24), np.int64)
_REGIONS[5:15, 3:22], _REGIONS[:, 19:] = 1, 2
NEURAL = {   # layout -> the request's settings; the painted map's first two colours are alike (the third black)
    "uniform": dict(specs=[("perlin", {"scale": 6.0})], seed=4, sampler="ddim"),
    "gradient": dict(specs=[("spots", {"coverage": 0.3}), ("cells_f1", {})], tileable=True),
    "corners": dict(specs=[("spots", {}), ("perlin", {}), ("cells_f1", {"scale": 10.0}), ("spots", {})], seed=9),
    "painted": dict(specs=[("spots", {}), ("perlin", {}), ("cells_f1", {})], regions=_REGIONS, transition=5.5,
                    sharpness=2.0, colours=[(255, 0, 0), (255, 0, 0), (0, 0, 0)]),
    "blend": dict(specs=[("spots", {}), ("perlin", {"scale": 4.0})], mask=_REGIONS > 0, transition=3.0),
}


@pytest.mark.parametrize("layout, ext", [("uniform", ".exr"), ("gradient", ".png"), ("corners", ".exr"),
                                         ("painted", ".png"), ("blend", ".exr")])
def test_a_saved_neural_job_bakes_the_panels_image(tmp_path, layout, ext):
    """Each layout of the Neural Noise panel (and a mask blend) as a job: `omninoise bake` writes the request's own
    image (a PNG's grey levels, an EXR's half floats), its key is the spec's; a painted map and a mask are written
    beside the job, the map in the given colours where they are distinct."""
    from omninoise.backend.neural.request import NeuralRequest, generate_request
    from omninoise.backend.paths import neural_model
    from omninoise.backend.sources import NeuralSource
    from omninoise.export.images import preview_8bit

    kw = dict(NEURAL[layout])
    colours = kw.pop("colours", None)
    req = NeuralRequest(layout, kw.pop("specs"), 24, 24, steps=2, **kw).check(_neural_model())
    spec = BakeSpec(layout, NeuralSource.from_request(neural_model(), req, colours), BoxGrid((24, 24)),
                    str(tmp_path / "out" / f"n{ext}"), half=ext == ".exr", make_folders=True).validate()
    text = job_file.write_job(str(tmp_path / "job.toml"), [spec])
    assert "model =" not in text and "time" not in text
    assert main(["bake", str(tmp_path / "job.toml"), "-q"]) == 0
    img = generate_request(_neural_model(), req)
    want = preview_8bit(img, 0.0, 1.0) / 255.0 if ext == ".png" else img.astype(np.float16).astype(np.float32)
    got = decode(spec.output)
    assert np.array_equal(got.reshape(want.shape), want.astype(got.dtype)), layout
    (_, parsed), = load_job(str(tmp_path / "job.toml"))
    assert parsed.key(None) == spec.key(None)
    side = sorted(f for f in os.listdir(tmp_path) if f.endswith(".png"))
    assert side == {"painted": ["job_map.png"], "blend": ["job_mask.png"]}.get(layout, [])
    if layout == "painted":
        px = decode(str(tmp_path / "job_map.png"))
        first, second, third = (tuple(np.rint(px[y, x, :3] * 255)) for y, x in ((0, 0), (7, 5), (0, 23)))
        assert first == (255, 0, 0) and third == (0, 0, 0) and second not in (first, third)   # region 1's is taken
        assert '"#ff0000" = "spots"' in text and '"#000000" = "cells_f1"' in text
        assert "width = 5.5" in text and "sharpness = 2.0" in text


def test_a_saved_neural_sequence_bakes_the_panels_frames(tmp_path):
    """Keyframes as the panel spreads its swatches (seeds, parameters), a drifting latent: the job's frames are the
    ones the panel's animate() draws; the frame numbers are the bake's times, so no time is written."""
    from omninoise.backend.neural.animate import animate, even_keys
    from omninoise.backend.paths import neural_model
    from omninoise.backend.sources import NeuralSource

    m = _neural_model()
    keys = even_keys([("perlin", {"scale": 5.0}), ("cells_f1", {}), ("spots", {"coverage": 0.4})], 3, 6, seed=7)
    src = NeuralSource(neural_model(), keys[0].noise, keys[0].params, steps=2, keys=keys, latent="drift", drift=0.2)
    spec = BakeSpec("morph", src, BoxGrid((16, 16)), str(tmp_path / "m_##.exr"), frames=(3, 6), time=3.0,
                    time_step=1.0).validate()
    text = job_file.write_job(str(tmp_path / "seq.toml"), [spec])
    assert "time" not in text and 'latent = "drift"' in text and "drift = 0.2" in text and "seed = 9" in text
    assert main(["bake", str(tmp_path / "seq.toml"), "-q"]) == 0
    for f, img in animate(m, keys, (3, 6), 16, 16, latent="drift", speed=0.2, steps=2):
        np.testing.assert_array_equal(decode(frame_path(spec.output, f))[..., 0], img)
    assert sorted(os.listdir(tmp_path)) == ["m_03.exr", "m_04.exr", "m_05.exr", "m_06.exr", "seq.toml"]


def test_a_neural_job_the_writer_cannot_hold_is_refused(tmp_path):
    """A map named as a bake's output, a sampler setting no job has: one line, nothing written."""
    from omninoise.backend.neural.request import NeuralRequest
    from omninoise.backend.paths import neural_model
    from omninoise.backend.sources import NeuralSource

    m = _neural_model()
    req = NeuralRequest("painted", NEURAL["painted"]["specs"], 24, 24, regions=_REGIONS, steps=2).check(m)
    spec = BakeSpec("p", NeuralSource.from_request(neural_model(), req), BoxGrid((24, 24)),
                    str(tmp_path / "job_map.png")).validate()
    with pytest.raises(SettingError, match="job_map.png is a bake's output"):
        job_file.write_job(str(tmp_path / "job.toml"), [spec])
    spaced = NeuralRequest("uniform", [("perlin", {})], 24, 24, steps=2, spacing="logsnr").check(m)
    with pytest.raises(SettingError, match="spacing: a bake source"):
        NeuralSource.from_request(neural_model(), spaced)
    assert os.listdir(tmp_path) == []


NEURAL_FLAGS = {     # -o's type -> the flags of `omninoise neural`
    "map.exr": ["--map", "paint.png", "--region", "#ff0000=spots", "--region", "#0000ff=perlin:scale=5",
                "--region", "0=cells_f1", "--width", "4", "--sharpness", "1.5"],
    "grad.png": ["--gradient", "spots:coverage=0.3", "cells_f1", "--tileable", "--seed", "3", "--sampler", "ddim"],
    "blend.exr": ["--noise", "spots", "--blend", "mask.png", "--noise2", "perlin", "--param2", "scale=4"],
    "m_##.png": ["--keys", "keys.toml", "--frames", "2", "4", "--latent", "drift", "--drift", "0.3"],
}


@pytest.fixture
def neural_inputs(tmp_path, monkeypatch):
    from omninoise.export.images import write_png

    monkeypatch.chdir(tmp_path)
    paint = np.zeros((32, 32, 3), np.uint8)
    paint[6:20, 4:28], paint[:, 26:] = (255, 0, 0), (0, 0, 255)
    write_png("paint.png", paint)
    write_png("mask.png", np.where(np.arange(32)[None, :] > 13, 255, 0).astype(np.uint8).repeat(32, 0))
    (tmp_path / "keys.toml").write_text('[[key]]\nframe = 2\nnoise = "perlin"\nparams = {scale = 4}\n'
                                        '[[key]]\nframe = 4\nnoise = "cells_f1"\nseed = 2\n')
    return tmp_path


@pytest.mark.parametrize("out", NEURAL_FLAGS)
def test_omninoise_neural_saves_its_image_as_a_job(neural_inputs, capsys, out):
    """`omninoise neural ... --save-job JOB.toml` writes the job (a map or mask beside it, a painted map in the
    --region colours) instead of the image; `omninoise bake JOB.toml` then writes what `omninoise neural` writes."""
    flags = NEURAL_FLAGS[out] + ["--size", "32", "--steps", "2"]
    assert main(["neural", *flags, "-o", "direct_" + out, "-q"]) == 0
    assert main(["neural", *flags, "-o", out, "--save-job", "job.toml"]) == 0
    assert f"wrote job.toml: omninoise bake job.toml draws {out}" in capsys.readouterr().err
    frames = [2, 3, 4] if "#" in out else [None]
    assert not any(os.path.exists(frame_path(out, f)) for f in frames)
    assert main(["bake", "job.toml", "-q"]) == 0
    for f in frames:
        np.testing.assert_array_equal(decode(frame_path(out, f)), decode(frame_path("direct_" + out, f)))
    if out == "map.exr":
        px = np.rint(decode("job_map.png") * 255)
        assert tuple(px[10, 10]) == (255, 0, 0) and tuple(px[0, 30]) == (0, 0, 255) and tuple(px[0, 0]) == (0, 0, 0)
    assert os.path.exists("job_mask.png") == (out == "blend.exr")


@pytest.mark.parametrize("extra, message", [
    (["--noise", "perlin", "-o", "a.png", "--save-job", "job.json"], "--save-job: a job file is a .toml file"),
    (["--fit", "paint.png", "-o", "a.png", "--save-job", "job.toml"], "--save-job: a job draws the classes it is"),
    (["--noise", "perlin", "--spacing", "logsnr", "-o", "a.png", "--save-job", "job.toml"],
     "--spacing: a job file has no such setting"),
    (["--noise", "perlin", "--tile", "16", "-o", "a.png", "--save-job", "job.toml"], "--tile: a job file has no"),
    (["--noise", "perlin", "--precision", "int8", "-o", "a.png", "--save-job", "job.toml"],
     "--precision: sets this run's arithmetic, not the job's"),
    (["--noise", "perlin", "-o", "a.npy", "--save-job", "job.toml"], "--save-job: a job's .npy holds an image's rows"),
    (["--map", "paint.png", "--region", "#ff0000=spots", "--region", "#0000ff=perlin", "--region", "0=spots",
      "-o", "a.png", "--save-job", "paint.toml"], "--save-job: the job writes its map to paint_map.png, the file"),
])
def test_omninoise_neural_refuses_a_job_it_cannot_save_before_any_work(neural_inputs, capsys, extra, message):
    if "paint_map.png" in message:
        os.rename("paint.png", "paint_map.png")
        extra = [e.replace("paint.png", "paint_map.png") for e in extra]
    before = sorted(os.listdir("."))
    assert main(["neural", "--size", "16", "--steps", "2", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and sorted(os.listdir(".")) == before


def test_the_python_api_saves_a_neural_image_as_a_job(tmp_path):
    """omninoise.neural(..., out=, save_job=) writes the job, not the image; its bake is the image out= writes."""
    import omninoise

    kw = dict(params={"scale": 5.0}, seed=2, steps=2, tileable=True)
    omninoise.neural("perlin", 24, out=str(tmp_path / "direct.png"), **kw)
    job = tmp_path / "n.toml"
    assert omninoise.neural("perlin", 24, out=str(tmp_path / "later.png"), save_job=str(job), **kw) == str(job)
    assert not (tmp_path / "later.png").exists() and run_job(str(job))[0].status == "baked"
    np.testing.assert_array_equal(decode(str(tmp_path / "later.png")), decode(str(tmp_path / "direct.png")))
    for bad, message in ((dict(save_job=str(job)), "save_job: applies to a written file; give out= too"),
                         (dict(out=str(tmp_path / "a.png"), save_job="n.json"), "a job file is a .toml file"),
                         (dict(out=str(tmp_path / "a.npy"), save_job=str(job)), "a job's .npy holds")):
        with pytest.raises(SettingError, match=message):
            omninoise.neural("perlin", 16, steps=2, **bad)
    assert sorted(os.listdir(tmp_path)) == ["direct.png", "later.png", "n.toml"]


@pytest.mark.parametrize("output, source", [("w.png", "wave"), ("w.exr", "wave"), ("n.png", "neural"),
                                            ("r.exr", "ramp"), ("s.png", "solid")])
def test_values_drawn_elsewhere_are_written_as_a_bake_writes_them(tmp_path, output, source):
    """write_values (a front end drawing the image itself: the Neural Noise panel) writes the file run_bake writes,
    key and all, so it is up to date for the spec's job; a volume is refused in one line."""
    from omninoise.backend.bake import evaluate_values, write_values
    from omninoise.export import read_metadata

    src = {"wave": {"kind": "wave", "dim": 2, "seed": 3}, "ramp": {"kind": "wave", "dim": 2},
           "neural": {"kind": "neural", "noise": "perlin", "steps": 2},
           "solid": {"kind": "solid", "model": "gravel_3d"}}[source]
    spec = BakeSpec("b", source_from_dict(src), BoxGrid((16, 12)), str(tmp_path / output),
                    preset("fire") if source == "ramp" else None).validate()
    run_bake(spec)
    baked, meta = decode(spec.output), read_metadata(spec.output)
    os.remove(spec.output)
    assert write_values(spec, None, evaluate_values(spec.source, spec.grid)) == spec.output
    np.testing.assert_array_equal(decode(spec.output), baked)
    assert read_metadata(spec.output) == meta and spec.is_up_to_date(None)
    vol = BakeSpec("v", source_from_dict({"kind": "wave", "dim": 3}), BoxGrid((4, 4, 4)), str(tmp_path / "v.vdb"))
    with pytest.raises(SettingError, match="write_values writes images and arrays, not v.vdb"):
        write_values(vol, None, np.zeros((4, 4, 4), np.float32))


def test_a_map_of_many_grey_levels_is_written_in_its_own_greys(tmp_path):
    """A job's painted map of 256 grey levels (an indexed map) written again: each region in its own grey, the
    same regions read back; without colours of their own, 300 regions get 300 distinct colours."""
    from omninoise.backend.paths import neural_model
    from omninoise.backend.sources import NeuralSource
    from omninoise.export.images import write_png

    write_png(str(tmp_path / "idx.png"), np.arange(256, dtype=np.uint8).reshape(16, 16))
    src = source_from_dict({"kind": "neural", "map": "idx.png", "steps": 2,
                            "regions": {str(k): "spots" if k % 2 else "perlin" for k in range(256)}}, str(tmp_path))
    (tmp_path / "out").mkdir()
    spec = BakeSpec("idx", src, BoxGrid((16, 16)), str(tmp_path / "out" / "idx.exr")).validate()
    job_file.write_job(str(tmp_path / "out" / "job.toml"), [spec])
    np.testing.assert_array_equal(decode(str(tmp_path / "out" / "job_map.png"))[..., 0],
                                  decode(str(tmp_path / "idx.png"))[..., 0])
    (_, parsed), = load_job(str(tmp_path / "out" / "job.toml"))
    np.testing.assert_array_equal(parsed.source.regions, src.regions)
    many = NeuralSource(neural_model(), "spots", steps=2, regions=np.arange(300).reshape(15, 20),
                        region_specs=[("spots", {})] * 300)
    assert len(set(job_file._region_colours(many))) == 300


def test_a_job_that_would_bake_otherwise_is_not_written_and_its_maps_are_put_back(tmp_path, monkeypatch):
    """The written-back check failing (a writer's fault, drawn here by a check that always fails): no job, the
    map written for it removed, and a map saved with an earlier job put back byte for byte."""
    from omninoise.backend.neural.request import NeuralRequest
    from omninoise.backend.paths import neural_model
    from omninoise.backend.sources import NeuralSource

    req = NeuralRequest("painted", NEURAL["painted"]["specs"], 24, 24, regions=_REGIONS, steps=2).check(_neural_model())
    mask = NeuralRequest("blend", NEURAL["blend"]["specs"], 24, 24, mask=_REGIONS > 0, steps=2).check(_neural_model())
    specs = [BakeSpec(n, NeuralSource.from_request(neural_model(), r), BoxGrid((24, 24)),
                      str(tmp_path / f"{n}.exr")).validate() for n, r in (("p", req), ("b", mask))]
    (tmp_path / "job_map.png").write_bytes(b"an earlier map")
    monkeypatch.setattr(job_file, "_same", lambda a, b: False)
    with pytest.raises(RuntimeError, match="the job file would bake 'p' otherwise than asked"):
        job_file.write_job(str(tmp_path / "job.toml"), specs)
    assert sorted(os.listdir(tmp_path)) == ["job_map.png"]
    assert (tmp_path / "job_map.png").read_bytes() == b"an earlier map"


SOLID_FLAGS = {     # -o -> the flags of `omninoise solid` (photos/p.jpg: a photo; the job is saved in jobs/)
    "ship.vdb": ["--exemplar", "gravel_3d", "--seed", "2", "--dim", "3"],
    "photo.npy": ["--exemplar", "photos/p.jpg", "--no-gaussian", "--seed", "3", "--dim", "3"],
    "mix.npy": ["--exemplar", "gravel", "--to", "photos/p.jpg", "--mix", "0.3", "--dim", "3"],
    "spectral.npy": ["--method", "spectral", "--exemplar", "photos/p.jpg", "--scale", "2", "--dim", "3"],
    "layers.npy": ["--method", "procedural", "--families", "layers", "--exemplar", "photos/p.jpg", "--dim", "3"],
    "saved.npy": ["--exemplar", "wall.json", "--scale", "0.5", "--dim", "3"],
    "auto.npy": ["--method", "auto", "--families", "cells", "--exemplar", "photos/p.jpg", "--dim", "3"],
    "brick.png": ["--exemplar", "brick_2d", "--seed", "1"],
    "tile.exr": ["--method", "synthesis", "--exemplar", "photos/p.jpg", "--tile", "32", "--seed", "2"],
}


@pytest.fixture
def solid_inputs(tmp_path, monkeypatch):
    """A photo in photos/, a folder for jobs, small spectral tiles and procedural fits (the same code, a fraction
    of the work)."""
    import shutil

    from omninoise.backend.solid import spectral_solid
    from omninoise.backend.solid.procedural import fit

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(spectral_solid, "PERIOD", 32)
    monkeypatch.setattr(fit, "ProceduralConfig", functools.partial(fit.ProceduralConfig, side=32, budget=6,
                                                                   finalists=1, fit_side=64))
    os.mkdir("photos")
    os.mkdir("jobs")
    shutil.copy(os.path.join(ROOT, "data", "photos", "val", "rock__cliff_greek.jpg"), "photos/p.jpg")
    return tmp_path



@pytest.mark.parametrize("out", [pytest.param(o, marks=pytest.mark.long) if o in ("mix.npy", "auto.npy") else o
                                 for o in SOLID_FLAGS])      # those two encode a photo with the space model
def test_omninoise_solid_saves_its_volume_or_image_as_a_job(solid_inputs, capsys, out):
    """`omninoise solid ... --save-job jobs/JOB.toml` writes the job (the photo named from the job's folder)
    instead of the volume or image; `omninoise bake` then writes what `omninoise solid` writes, value for value."""
    if out == "saved.npy":
        assert main(["solid", "--method", "procedural", "--families", "cells", "--exemplar", "photos/p.jpg", "-o",
                     "wall.json", "-q"]) == 0
    flags = SOLID_FLAGS[out] + ["--size", "12" if "--dim" in SOLID_FLAGS[out] else "24"]
    assert main(["solid", *flags, "-o", "direct_" + out, "-q"]) == 0
    assert main(["solid", *flags, "-o", out, "--save-job", "jobs/job.toml"]) == 0
    assert f"wrote jobs/job.toml: omninoise bake jobs/job.toml draws {out}" in capsys.readouterr().err
    assert not os.path.exists(out)
    text = open("jobs/job.toml").read()
    assert ("../photos/p.jpg" in text) == ("photos/p.jpg" in flags) and str(solid_inputs) not in text
    assert main(["bake", "jobs/job.toml", "-q"]) == 0
    if out.endswith(".vdb"):
        got, want = (read_volume(f, "color", (12, 12, 12)) for f in (out, "direct_" + out))
    elif out.endswith(".npy"):
        got, want = np.load(out), np.load("direct_" + out)
    else:
        got, want = decode(out), decode("direct_" + out)
    assert got.shape == want.shape and got.std() > 0
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("extra, message", [
    (["--exemplar", "gravel_3d", "--dim", "3", "-o", "a.npy", "--save-job", "job.json"],
     "--save-job: a job file is a .toml file"),
    (["--method", "procedural", "--exemplar", "photos/p.jpg", "-o", "a.json", "--save-job", "job.toml"],
     "--save-job: a .json -o is the fitted solid itself, which no job writes"),
    (["--exemplar", "gravel_3d", "-o", "a.png", "--save-job", "job.toml"],
     "--save-job: -o's image is a solid's front view (the plane y = 0), a job's 2D bake its plane z = 0"),
    (["--method", "spectral", "--exemplar", "photos/p.jpg", "-o", "a.exr", "--save-job", "job.toml"],
     "--save-job: -o's image is a solid's front view"),
    (["--exemplar", "brick_2d", "-o", "a.npy", "--save-job", "job.toml"],
     "--save-job: a job's .npy holds an image's rows from the bottom up"),
    (["--exemplar", "gravel_3d", "--dim", "3", "-o", "a.npy", "--save-job", "no/job.toml"],
     "--save-job: output folder does not exist"),
])
def test_omninoise_solid_refuses_a_job_it_cannot_save_before_any_work(solid_inputs, capsys, extra, message):
    before = sorted(os.listdir("."))
    assert main(["solid", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and sorted(os.listdir(".")) == before


def test_the_python_api_saves_a_solid_volume_as_a_job(solid_inputs):
    """omninoise.solid(..., out=, save_job=) writes the job, not the volume; its bake is the volume out= writes."""
    import omninoise
    from omninoise.export.images import read_rgb

    kw = dict(dim=3, method="spectral", seed=4, scale=1.5)
    omninoise.solid("photos/p.jpg", 10, out="direct.npy", **kw)
    assert omninoise.solid("photos/p.jpg", 10, out="later.npy", save_job="jobs/s.toml", **kw) == "jobs/s.toml"
    assert not os.path.exists("later.npy") and run_job("jobs/s.toml")[0].status == "baked"
    np.testing.assert_array_equal(np.load("later.npy"), np.load("direct.npy"))
    for exemplar, bad, message in (
            ("gravel_3d", dict(save_job="jobs/s.toml"), "save_job: applies to a written file; give out= too"),
            ("gravel_3d", dict(out="a.npy", dim=3, save_job="s.json"), "a job file is a .toml file"),
            ("gravel_3d", dict(out="a.png", save_job="jobs/s.toml"), "save_job: out's image is a solid's front view"),
            (read_rgb("photos/p.jpg"), dict(out="a.npy", dim=3, method="spectral", save_job="jobs/s.toml"),
             "exemplar: a job reads its image or saved solid from a file")):
        with pytest.raises(SettingError, match=message):
            omninoise.solid(exemplar, 16, **bad)
    assert sorted(os.listdir("jobs")) == ["s.toml"] and not os.path.exists("a.npy")
