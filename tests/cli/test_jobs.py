"""``omninoise bake JOB.toml``: parsing, errors naming the bake, skipping, keep-going, CLI."""
import os
import subprocess
import sys

import numpy as np
import pytest

from omninoise.cli.main import main
from omninoise.backend.jobs import JobError, load_job, run_job
from omninoise.export import read_volume

JOB = """
[defaults]
bounds = [[-1, -1, 0], [1, 1, 1]]

[[bake]]
name = "clouds"
output = "out/clouds_##.vdb"
resolution = [16, 16, 8]
transfer = "clouds"
frames = [1, 2]
time_step = 0.5
[bake.source]
dim = 3
speed = 1.0
spectrum = {kind = "fractal", fmin = 1, fmax = 6}

[[bake]]
name = "marble"
output = "out/marble.exr"
resolution = [32, 16]
transfer = "ramp.json"
half = true
[bake.source]
dim = 3
seed = 4
spectrum = "bandpass"
fmin = 2
fmax = 4
"""

RAMP = '{"range": [-1, 1], "stops": [[0, [0, 0, 0, 1]], [1, [1, 1, 1, 1]]]}'


@pytest.fixture
def job(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "ramp.json").write_text(RAMP)
    p = tmp_path / "job.toml"
    p.write_text(JOB)
    return p


def test_job_bakes_then_skips(job):
    fractions, bakes = [], []
    out = run_job(str(job), progress=fractions.append, on_bake=lambda *b: bakes.append(b))
    assert [(o.name, o.status) for o in out] == [("clouds", "baked"), ("marble", "baked")]
    # the core's one progress contract: the job's fraction, rising to 1; each bake announced as it starts
    assert bakes == [("clouds", 0, 2), ("marble", 1, 2)]
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0) and 0.5 in fractions
    files = sorted(os.listdir(job.parent / "out"))
    assert files == ["clouds_01.vdb", "clouds_02.vdb", "marble.exr"]
    again = run_job(str(job))
    assert [o.status for o in again] == ["up to date", "up to date"]
    assert [o.status for o in run_job(str(job), force=True, only=["marble"])] == ["baked"]
    d = read_volume(str(job.parent / "out" / "clouds_01.vdb"), "density", (8, 16, 16))
    assert 0 < (d > 0).mean() < 1


def test_job_paths_are_relative_to_the_job_file(job, tmp_path, monkeypatch):
    monkeypatch.chdir("/")
    specs = load_job(str(job))
    assert specs[0][1].output == str(tmp_path / "out" / "clouds_##.vdb")
    job.write_text(JOB.replace("out/marble.exr", "new/deeper/marble.exr"))
    assert [o.status for o in run_job(str(job), only=["marble"])] == ["baked"]
    assert os.listdir(tmp_path / "new" / "deeper") == ["marble.exr"]  # folders made for the job


@pytest.mark.parametrize("edit, match", [
    (("fmax = 6}", "fmax = 6, bogus = 1}"), r"bake 'clouds': source.spectrum.bogus: unknown key; known: kind, fmin"),
    (('resolution = [32, 16]', 'resolution = [32, 0]'), "bake 'marble': resolution"),
    (('output = "out/marble.exr"', 'output = "out/marble.vdb"'), "bake 'marble': .*needs a 3D grid"),
    (('transfer = "ramp.json"', 'transfer = "lava"'), "bake 'marble': .*neither a preset"),
    (('seed = 4', 'seed = 4\nsped = 2'), r"bake 'marble': source.sped: unknown key \(did you mean speed\?\)"),
    (('name = "marble"', 'name = "clouds"'), "bake 'clouds': the name is used twice"),
    (('time_step = 0.5', 'time_step = 0.5\ncolour = 1'), "bake 'clouds': colour: unknown key"),
    (("fmin = 1, fmax = 6}", "fmin = 7, fmax = 6}"), "bake 'clouds': source.spectrum.fmin: 7 is greater than fmax 6"),
    (("fmin = 2\nfmax = 4", "fmin = 5\nfmax = 4"), "bake 'marble': source.spectrum.fmin: 5 is greater than fmax 4"),
    # settings that change nothing: a still source's time, a time step without frames
    (("half = true", "half = true\ntime = 2.0"), r"bake 'marble': time: this source does not change over time \(set "
                                                 r"speed, or dim = 4\); its time changes nothing"),
    (("frames = [1, 2]\n", ""), "bake 'clouds': time_step: sets the time between the frames of a sequence; without "
                                "frames it changes nothing"),
])
def test_bad_bakes_are_named_and_nothing_is_baked(job, edit, match):
    job.write_text(JOB.replace(*edit))
    out = run_job(str(job))
    assert out[-1].status == "invalid"
    assert __import__("re").search(match, out[-1].message), out[-1].message
    assert os.listdir(job.parent / "out") == []  # invalid bakes fail before any work


def test_defaults_may_time_still_and_animated_bakes_alike(job):
    job.write_text(JOB.replace("[defaults]", "[defaults]\ntime = 2.0\ntime_step = 0.25"))
    specs = dict(load_job(str(job)))
    assert (specs["clouds"].time, specs["clouds"].time_step, specs["marble"].time) == (2.0, 0.5, 2.0)


def test_keep_going_bakes_the_others(job):
    job.write_text(JOB.replace("fmax = 6}", "fmax = 6, bogus = 1}"))
    out = run_job(str(job), keep_going=True)
    assert [o.status for o in out] == ["invalid", "baked"]
    assert os.listdir(job.parent / "out") == ["marble.exr"]


def test_whole_file_errors(tmp_path):
    p = tmp_path / "j.toml"
    with pytest.raises(JobError, match="not found"):
        load_job(str(p))
    p.write_text("[[bake]\nname=")
    with pytest.raises(JobError, match="not valid TOML"):
        load_job(str(p))
    p.write_text("[defaults]\nbounds = []\n")
    with pytest.raises(JobError, match=r"no \[\[bake\]\] tables"):
        load_job(str(p))
    p.write_text("[[bakes]]\nname = 'x'\n")
    with pytest.raises(JobError, match=r"bakes: unknown key \(did you mean bake\?\)"):
        load_job(str(p))


def test_cli_exit_codes_and_messages(job, capsys):
    assert main(["bake", str(job), "--quiet"]) == 0
    assert main(["bake", str(job), "--dry-run"]) == 0
    assert "up to date clouds" in capsys.readouterr().out
    job.write_text(JOB.replace("fmax = 6}", "fmax = 6, bogus = 1}"))
    assert main(["bake", str(job), "--quiet"]) == 2          # bad settings: exit 2, as for every bad input
    err = capsys.readouterr().err
    assert "omninoise bake: error: bake 'clouds': source.spectrum.bogus: unknown key; known:" in err
    assert main(["bake", str(job), "--only", "nope"]) == 2
    assert "no bake named 'nope'" in capsys.readouterr().err
    assert main(["bake", str(job), "--dry-run"]) == 2
    # a dry run says what the run would do: the bakes --only names (the run of marble alone bakes it), and with
    # --force the up-to-date ones baked again (it listed every bake, and the invalid clouds failed it)
    capsys.readouterr()
    assert main(["bake", str(job), "--dry-run", "--only", "marble"]) == 0
    assert capsys.readouterr().out.splitlines() == [f"  up to date marble: [32, 16] -> {job.parent}/out/marble.exr"]
    assert main(["bake", str(job), "--dry-run", "--only", "marble", "--force"]) == 0
    assert capsys.readouterr().out.startswith("  to bake    marble")
    assert main(["bake", str(job), "--quiet", "--only", "marble"]) == 0
    # a failure while running (the output folder is a file) exits 1
    job.write_text(JOB.replace('output = "out/marble.exr"', 'output = "blocker/marble.exr"'))
    (job.parent / "blocker").write_text("a file where a folder belongs")
    assert main(["bake", str(job), "--quiet", "--only", "marble"]) == 1


def test_console_script_bakes(job):
    exe = os.path.join(os.path.dirname(sys.executable), "omninoise")
    r = subprocess.run([exe, "bake", str(job)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "clouds: baked (2 written, 0 up to date)" in r.stderr


def test_wave_cli_vdb_and_transfer(tmp_path, capsys):
    vdb = str(tmp_path / "w.vdb")
    assert main(["wave", "--dim", "3", "--size", "16", "--fmin", "1", "--fmax", "3", "--seed", "5", "--quiet",
                 "-o", vdb]) == 0
    from omninoise.backend import WaveSettings, compile_noise, evaluate_points
    from omninoise.backend.wavenoise.spectra import Spectrum

    d = read_volume(vdb, "density", (16, 16, 16))
    c = (np.arange(16) + 0.5) * 4.0 / 16
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    noise = compile_noise(WaveSettings(dim=3, spectrum=Spectrum("gaussian", 1.0, 3.0), seed=5))
    ref = evaluate_points(noise, np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32), "real")
    np.testing.assert_allclose(d.ravel(), ref, atol=1e-3)
    assert main(["wave", "--dim", "3", "--size", "16", "--quiet", "--transfer", "smoke", "-o", vdb]) == 0
    assert read_volume(vdb, "color", (16, 16, 16)).max() > 0
    assert main(["wave", "--dim", "2", "--size", "16", "--quiet", "-o", vdb]) == 2
    assert "needs --dim 3 or 4" in capsys.readouterr().err
    assert main(["wave", "--size", "16", "--quiet", "--range", "0", "1", "-o", str(tmp_path / "a.png")]) == 2
    assert "give --transfer too" in capsys.readouterr().err


def test_outputs_stay_inside_the_output_root(tmp_path):
    """A job writes only inside its own folder unless it names output_root (output = "../../x")."""
    jobdir = tmp_path / "jobs" / "a"
    jobdir.mkdir(parents=True)
    body = ('[[bake]]\nname = "w"\noutput = "{out}"\nresolution = [8, 8]\n'
            '[bake.source]\ndim = 2\ndirections = 2\n')
    job = jobdir / "job.toml"
    for out in ("../../x.npy", str(tmp_path / "elsewhere.npy"), "sub/../../y.npy"):
        job.write_text(body.format(out=out))
        (entry,) = load_job(str(job))
        assert isinstance(entry[1], JobError) and "outside the output root" in str(entry[1]), entry
        assert "output_root" in str(entry[1])
    job.write_text(body.format(out="sub/ok.npy"))
    assert not isinstance(load_job(str(job))[0][1], JobError)
    job.write_text('output_root = "../.."\n' + body.format(out="../../x.npy"))
    assert [o.status for o in run_job(str(job))] == ["baked"] and (tmp_path / "x.npy").is_file()
    job.write_text(f'output_root = "{tmp_path}"\n' + body.format(out=str(tmp_path / "elsewhere.npy")))
    assert not isinstance(load_job(str(job))[0][1], JobError)
    for bad in ("3", '""'):
        job.write_text(f"output_root = {bad}\n" + body.format(out="ok.npy"))
        with pytest.raises(JobError, match="output_root"):
            load_job(str(job))


def test_a_symlink_does_not_lead_outside_the_output_root(tmp_path):
    jobdir = tmp_path / "job"
    jobdir.mkdir()
    (jobdir / "link").symlink_to(tmp_path)
    (jobdir / "job.toml").write_text('[[bake]]\nname = "w"\noutput = "link/x.npy"\nresolution = [8, 8]\n'
                                     '[bake.source]\ndim = 2\ndirections = 2\n')
    (entry,) = load_job(str(jobdir / "job.toml"))
    assert isinstance(entry[1], JobError) and "outside the output root" in str(entry[1])


def test_a_tilde_is_the_home_folder(tmp_path, monkeypatch):
    """'~/renders/x.exr' in a job writes in the home folder, not in a folder named '~' beside the job; files the
    job reads (a ramp) are found there too."""
    home, jobdir = tmp_path / "home", tmp_path / "jobs"
    (home / "ramps").mkdir(parents=True)
    jobdir.mkdir()
    monkeypatch.setenv("HOME", str(home))
    (home / "ramps" / "grey.json").write_text(RAMP)
    (jobdir / "job.toml").write_text('output_root = "~/renders"\n[[bake]]\nname = "w"\n'
                                     'output = "~/renders/w.exr"\nresolution = [8, 8]\n'
                                     'transfer = "~/ramps/grey.json"\n[bake.source]\ndim = 2\ndirections = 2\n')
    assert [o.status for o in run_job(str(jobdir / "job.toml"))] == ["baked"]
    assert os.listdir(home / "renders") == ["w.exr"] and os.listdir(jobdir) == ["job.toml"]


def test_a_new_source_kind_is_one_class_and_one_registration(tmp_path, monkeypatch):
    """Sources by registry: a registered kind bakes from a job file through the whole pipeline
    (validation, slabs, writers, keys) with no edit to the CLI, jobs or bake code."""
    from omninoise.backend import sources

    class Ramp:
        kind, dim, animated, chunkable = "ramp", 3, False, True

        def __init__(self, slope):
            self.slope = float(slope)

        def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None):
            z0 = 0 if start is None else start[-1]
            z = first[2] + (np.arange(shape[0]) + z0) * step[2]
            return np.broadcast_to((self.slope * z)[:, None, None], shape).astype(np.float32)

        def to_dict(self):
            return dict(kind=self.kind, slope=self.slope)

    monkeypatch.setitem(sources.SOURCES, "ramp", lambda d, base: Ramp(d.get("slope", 1.0)))
    job = tmp_path / "job.toml"
    job.write_text('[[bake]]\nname = "r"\noutput = "r.npy"\nresolution = [4, 3, 5]\nbounds = [[0, 0, 0], [1, 1, 1]]\n'
                   '[bake.source]\nkind = "ramp"\nslope = 2.0\n')
    assert [o.status for o in run_job(str(job))] == ["baked"]
    got = np.load(tmp_path / "r.npy")
    assert got.shape == (5, 3, 4)
    np.testing.assert_allclose(got[:, 0, 0], 2.0 * (np.arange(5) + 0.5) / 5, atol=1e-6)
    job.write_text(job.read_text().replace('kind = "ramp"', 'kind = "nope"'))
    (entry,) = load_job(str(job))
    assert "unknown source 'nope'; choose one of wave, neural, solid, ramp" in str(entry[1])


@pytest.mark.parametrize("key, why", [('params = {scale = 100}', "key at frame 3: scale=100 is outside [2, 16]"),
                                      ('params = {zz = 1}', "key at frame 3: perlin has no parameter 'zz'")])
def test_a_bad_keyframe_is_named_by_its_frame_and_its_file(tmp_path, capsys, key, why):
    """A keyframe's class or parameter the model refuses names the keyframe file's setting and the key's frame,
    on the command line and in a job file, before any frame is drawn (it was reported as a bare 'param')."""
    (tmp_path / "k.toml").write_text(f'[[key]]\nframe = 1\nnoise = "spots"\n[[key]]\nframe = 3\nnoise = "perlin"\n'
                                     f'{key}\n')
    rc = main(["neural", "--keys", str(tmp_path / "k.toml"), "--frames", "1", "3", "--size", "16", "--quiet",
               "-o", str(tmp_path / "f_##.png")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and err.startswith(f"omninoise neural: error: --keys: {why}"), err
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "a"\noutput = "n_##.png"\nresolution = [16, 16]\n'
                                       'frames = [1, 3]\n[bake.source]\nkind = "neural"\nkeys = "k.toml"\n')
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 2
    assert f"bake 'a': source.keys: {why}" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["job.toml", "k.toml"]


def test_a_solid_mix_without_to_is_refused(tmp_path, capsys):
    """``mix`` weighs the texture of ``to``: alone it would change nothing, and the texture would not be the one
    asked for."""
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "s"\noutput = "s.png"\nresolution = [8, 8]\n'
                                       'bounds = [[0, 0, 0], [1, 0, 1]]\n[bake.source]\nkind = "solid"\n'
                                       'exemplar = "grass"\nmix = 0.2\n')
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 2
    assert "bake 's': source.mix: weighs the texture of to" in capsys.readouterr().out


def test_a_solid_photo_is_read_beside_the_job_not_where_it_runs(tmp_path, monkeypatch, capsys):
    """A job's photo lies in the job's folder: one of the same name in the folder the command runs in is not read;
    a shipped texture's name still names the shipped texture."""
    from PIL import Image

    (tmp_path / "jobs").mkdir()
    Image.fromarray(np.full((32, 32, 3), 200, np.uint8)).save(tmp_path / "photo.png")
    job = tmp_path / "jobs" / "job.toml"
    head = ('[[bake]]\nname = "s"\noutput = "s.png"\nresolution = [8, 8]\n'
            '[bake.source]\nkind = "solid"\n')
    job.write_text(head + 'exemplar = "photo.png"\nmethod = "spectral"\n')
    monkeypatch.chdir(tmp_path)
    assert main(["bake", str(job), "--dry-run"]) == 2
    out = capsys.readouterr().out
    assert f"source.exemplar: spectral works from an image file; there is no file {str(job.parent / 'photo.png')!r}" \
        in out
    job.write_text(head + 'exemplar = "grass"\n')
    assert main(["bake", str(job), "--dry-run"]) == 0
    job.write_text(head + 'exemplar = "IMG_0001"\nmethod = "procedural"\n')     # a photo's file: no name
    assert main(["bake", str(job), "--dry-run"]) == 2
    assert f"there is no file {str(job.parent / 'IMG_0001')!r}" in capsys.readouterr().out


@pytest.mark.parametrize("source, key, needs", [
    ('cell_size = 2', "cell_size", "cellular"),
    ('spectrum = {kind = "bandpass", fmin = 1, fmax = 4, exponent = 2}', "exponent", 'spectrum = "fractal"'),
    ('stit_depth = 2\ncellular = "polytope"', "stit_depth", 'cellular = "stit"'),
    ('spread = 10', "spread", 'anisotropy = "lobes" or example with dim = 3'),
    ('sectors = 4', "sectors", "example"),
])
def test_a_wave_key_that_changes_nothing_is_refused(tmp_path, capsys, source, key, needs):
    """As on the command line: a wave key read only beside another setting is refused without it, naming both."""
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "a"\noutput = "w.npy"\nresolution = [8, 8]\n'
                                       f'[bake.source]\nkind = "wave"\n{source}\n')
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 2
    assert f"bake 'a': source.{key}: is read only with {needs};" in capsys.readouterr().out


@pytest.mark.parametrize("key", ["width = 8", "sharpness = 2"])
def test_a_neural_transition_without_a_blend_or_map_is_refused(tmp_path, capsys, key):
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "a"\noutput = "n.png"\nresolution = [16, 16]\n'
                                       f'[bake.source]\nkind = "neural"\nnoise = "perlin"\n{key}\n')
    assert main(["bake", str(tmp_path / "job.toml"), "--dry-run"]) == 2
    assert f"source.{key.split()[0]}: shapes the transitions of blend and map" in capsys.readouterr().out


NEURAL_BAKE = """
[[bake]]
name = "spots"
output = "out/spots.png"
resolution = [16, 16]
[bake.source]
kind = "neural"
noise = "spots"
steps = 1
"""


def test_int8_beside_a_job_without_neural_noise_is_refused(job, capsys):
    """--precision int8 sets the denoiser's arithmetic: a job (or the bakes --only names) with no neural noise bake
    would write what fp32 writes, so it is refused, naming the flag, before any work; beside a neural bake it
    stands."""
    assert main(["bake", str(job), "--precision", "int8", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["omninoise bake: error: --precision: sets the neural noise's arithmetic, and no bake of the job is "
                   "neural noise: it would change nothing"]
    assert os.listdir(job.parent / "out") == []
    job.write_text(JOB + NEURAL_BAKE)
    assert main(["bake", str(job), "--precision", "int8", "--dry-run"]) == 0
    assert main(["bake", str(job), "--precision", "int8", "--dry-run", "--only", "marble"]) == 2
    assert "--precision: sets the neural noise's arithmetic" in capsys.readouterr().err
    assert main(["bake", str(job), "--precision", "fp32", "--dry-run", "--only", "marble"]) == 0


def test_a_bad_key_from_defaults_says_it_came_from_there(tmp_path):
    """[defaults] is merged into every bake: a wave setting there is unknown to a neural bake, and the message
    said so without saying where the key came from (the bake's own table does not hold it)."""
    (tmp_path / "job.toml").write_text("""
[defaults]
resolution = [8, 8]
[defaults.source]
kind = "wave"
fmax = 4

[[bake]]
name = "wave"
output = "w.exr"

[[bake]]
name = "own"
output = "o.exr"
[bake.source]
fmax = -1
""" + NEURAL_BAKE.replace("out/spots.png", "n.png"))
    res = {n: s for n, s in load_job(str(tmp_path / "job.toml"))}
    assert not isinstance(res["wave"], JobError)
    assert str(res["spots"]).startswith("bake 'spots': source.fmax: unknown key;")
    assert str(res["spots"]).endswith("(set in [defaults], which every bake takes)")
    assert str(res["own"]) == "bake 'own': source.fmax: must lie in (0, 100000], got -1"     # its own key
