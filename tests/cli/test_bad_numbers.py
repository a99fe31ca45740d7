"""Bad numbers never reach the kernels: NaN/inf time and speed, zero extent and period, absurd
directions, table sizes and grid sizes each give a one-line error naming the setting, exit 2, nothing written."""
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from omninoise.backend import limits
from omninoise.cli.main import main
from omninoise.backend.errors import SettingError
from omninoise.backend.jobs import run_job

from test_jobs import JOB, RAMP


@pytest.mark.parametrize("args,setting", [
    (["--time", "nan"], "--time"),                           # was a segmentation fault in the row kernel
    (["--dim", "3", "--speed", "inf"], "speed"),             # likewise
    (["--directions", "100000000"], "--directions"),         # was a hang
    (["--extent", "0"], "--extent"),                         # was ZeroDivisionError
    (["--period", "0"], "--period"),
    (["--size", "100000000"], "--size"),                     # was MemoryError
    (["--table-size", "1000000000"], "--table-size"),
    (["--slice-width", "-1"], "--slice-width"),
    (["--stit-probability", "2"], "--stit-probability"),
    (["--spread", "nan"], "--spread"),
])
def test_bad_wave_numbers_fail_with_one_line(tmp_path, capsys, args, setting):
    out = tmp_path / "x.npy"
    rc = main(["wave", "--size", "16", "--quiet", *args, "-o", str(out)])
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(lines) == 1 and setting in lines[0], lines
    assert not out.exists()


@pytest.mark.parametrize("args, message", [
    (["--anisotropy", "axes"], "--axis-spectrum: per-axis anisotropy needs 2 spectra, one per axis, got 0"),
    (["--anisotropy", "axes", "--axis-spectrum", "gaussian:1:2", "--axis-spectrum", "gaussian:3:1"],
     "--axis-spectrum: 3 is greater than fmax 1"),
    (["--anisotropy", "lobes", "--lobe", "1,0,0:1"], "--lobe: lobe axis (1.0, 0.0, 0.0) must be a non-zero 2-vector"),
    (["--transition", "gaussian:2:1"], "--transition: 2 is greater than fmax 1"),
    (["--transition", "gaussian:1:2", "--transition-length", "0"], "--transition-length: must lie in [1e-06"),
    (["--transfer", "fire", "--range", "nan", "1"], "--range: must be a finite number, got nan"),
    (["--transfer", "fire", "--range", "1", "1"], "--range: needs two different values"),
    # past these the ramp's positions were infinite and the file was refused after the work as NaN (exit 1)
    (["--transfer", "fire", "--range", "-1e308", "1e308"], "--range: must lie in [-1000000, 1000000], got -1e+308"),
    (["--transfer", "fire", "--range", "0", "1e-9"], "--range: needs two different values, at least 1e-06 apart"),
    (["--period", "1e-6"], "--spectrum: the band holds no table harmonic; widen [fmin, fmax] or raise the period"),
    (["--anisotropy", "lobes", "--lobe", "1,0:0"], "--lobe: lobe weights must not all be zero"),
    (["--cellular", "stit", "--stit-depth", "9"], "--stit-depth: must lie in [0, 8], got 9"),
    # a negative number in scientific notation is a value (argparse took it for an unknown flag)
    (["--time", "-1e-3"], "--time: is read only with --speed"),
    (["--time", "2"], "--time: is read only with --speed (animated noise) or --dim 4 (its fourth coordinate)"),
])
def test_settings_that_join_flags_are_named_by_the_flag(tmp_path, capsys, args, message):
    """A rule over several wave settings (a spectrum per axis, a lobe's axis, the transition's band, a ramp's
    range) is checked before any work and named by the flag the user typed; a transition length of 0 is refused,
    not read as "not given" (the extent)."""
    out = tmp_path / "x.png"
    rc = main(["wave", "--size", "16", "--quiet", *args, "-o", str(out)])
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(lines) == 1 and lines[0].startswith(f"omninoise wave: error: {message}"), lines
    assert not out.exists()


def test_a_custom_spectrum_is_no_flag_s_kind(capsys):
    """A custom spectrum's amplitudes cannot be flags: KIND:FMIN:FMAX took it, then refused it for amplitudes no
    flag gives."""
    with pytest.raises(SystemExit) as e:
        main(["wave", "--size", "8", "--transition", "custom:1:2", "-o", "x.png"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "argument --transition: expected a kind of gaussian, white, blue, brown, fractal, " \
        "bandpass, twolevel, got 'custom' (a custom spectrum's amplitudes are given in a job file" in err, err


@pytest.mark.parametrize("args,setting", [
    (["--steps", "0"], "--steps: must be a whole number"),
    (["--sampler", "bogus"], "--sampler: unknown sampler"),
    (["--spacing", "bogus"], "--spacing: unknown spacing"),
    (["--eta", "2"], "--eta: must lie in [0, 1]"),
    (["--sampler", "heun", "--eta", "0.5"], "--eta: eta > 0 is a DDIM"),
])
def test_bad_sampler_settings_name_their_flag(tmp_path, capsys, args, setting):
    out = tmp_path / "x.npy"
    rc = main(["neural", "--noise", "perlin", "--size", "16", "--quiet", *args, "-o", str(out)])
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(lines) == 1 and setting in lines[0], lines
    assert not out.exists()


def test_memory_error_says_how_much(monkeypatch):
    monkeypatch.setenv("OMNINOISE_MEMORY_LIMIT", "1M")
    assert limits.memory_limit() == 1 << 20
    with pytest.raises(SettingError, match=r"size: a grid needs 2\.0 MiB, above the limit of 1\.0 MiB \(set "):
        limits.check_memory("size", 2 << 20, "a grid")
    monkeypatch.setenv("OMNINOISE_MEMORY_LIMIT", "16G")
    with pytest.raises(SettingError, match=r"needs 20\.0 GiB, above the limit of 16\.0 GiB"):
        limits.check_memory("size", 20 << 30, "a grid")


@pytest.mark.parametrize("given, limit", [("8G", 8 << 30), ("8g", 8 << 30), ("8GB", 8 << 30), ("8 GiB", 8 << 30),
                                          ("512M", 512 << 20), ("1.5T", 3 << 39), ("2e9", 2_000_000_000),
                                          ("100", 100), (" 4K ", 4096), ("", 16 << 30)])
def test_the_memory_limit_reads_bytes_with_a_unit(monkeypatch, given, limit):
    monkeypatch.setenv("OMNINOISE_MEMORY_LIMIT", given)
    monkeypatch.setattr(limits, "physical_memory", lambda: 64 << 30)
    assert limits.memory_limit() == limit


@pytest.mark.parametrize("ram, limit", [(64 << 30, 16 << 30), (32 << 30, 16 << 30), (24 << 30, 12 << 30),
                                        (8 << 30, 4 << 30), (None, 16 << 30)])
def test_the_default_memory_limit_is_at_most_half_the_machine_s_memory(monkeypatch, capsys, tmp_path, ram, limit):
    """16 GiB let a machine of 16 GB or less take a result its memory cannot hold (a 512^3 cloud volume peaks at
    4.2 GiB), and the system kills such a process, in Blender with the unsaved file: the default is half the
    machine's (or its container's) memory where that is less, and the message says so."""
    monkeypatch.delenv("OMNINOISE_MEMORY_LIMIT", raising=False)
    monkeypatch.setattr(limits, "physical_memory", lambda: ram)
    assert limits.memory_limit() == limit
    assert main(["wave", "--size", "1500", "--dim", "3", "--quiet", "-o", str(tmp_path / "w.npy")]) == 2
    err = capsys.readouterr().err.strip()
    half = ", half this machine's memory" if limit < 16 << 30 else ""
    assert err.startswith("omninoise wave: error: ") and "\n" not in err and err.endswith(
        f"GiB, above the limit of {limit / 2 ** 30:.1f} GiB{half} (set OMNINOISE_MEMORY_LIMIT to raise it)"), err
    assert os.listdir(tmp_path) == []


_PEAK = """import re, sys
from omninoise.cli.main import main
assert main(sys.argv[1:] + ["--quiet"]) == 0
print(re.search(r"VmHWM:\\s*(\\d+) kB", open("/proc/self/status").read())[1])"""


@pytest.mark.long          # eight whole commands at sizes where the bake sets the peak
@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="the peak resident memory read from /proc")
@pytest.mark.parametrize("args, sizes, ext, holds", [
    (["--transfer", "fire"], (2048, 4096), ".exr", "ramp"),
    (["--transfer", "fire"], (2048, 4096), ".png", "ramp"),
    (["--transfer", "clouds", "--dim", "3"], (128, 192), ".vdb", "ramp"),
    ([], (2048, 4096), ".png", "values"),
])
def test_a_bake_s_memory_estimate_is_not_below_its_peak(tmp_path, args, sizes, ext, holds):
    """What a result is refused by is what it holds at its peak: the growth of a bake's peak resident memory from
    one size to the next, per sample, stays within :data:`backend.bake.PEAK_BYTES` and near it (an estimate of the
    values alone let a ramp's EXR take 36 bytes a pixel against the 20 allowed for, and its PNG 87)."""
    from omninoise.backend.bake import PEAK_BYTES, require_vdb

    if ext == ".vdb":
        try:
            require_vdb("-o")
        except SettingError:
            pytest.skip("this Python has no OpenVDB module")
    peaks, samples = [], []
    for n in sizes:     # VmHWM: this process's own peak (ru_maxrss keeps the forking test process's across exec)
        out = str(tmp_path / f"w{n}{ext}")
        run = subprocess.run([sys.executable, "-c", _PEAK, "wave", "--size", str(n), *args, "-o", out],
                             capture_output=True, text=True, check=True)
        peaks.append(int(run.stdout.split()[-1]) * 1024)
        samples.append(n ** (3 if "--dim" in args else 2))
    per_sample = (peaks[1] - peaks[0]) / (samples[1] - samples[0])
    assert 0.6 * PEAK_BYTES[ext][holds] <= per_sample <= PEAK_BYTES[ext][holds], (per_sample, peaks)


def test_the_machine_s_memory_is_read():
    """Where the system says (Linux, macOS): a positive number of bytes, at most what the machine has."""
    ram = limits.physical_memory()
    if hasattr(os, "sysconf") and "SC_PHYS_PAGES" in os.sysconf_names:
        assert ram is not None and 0 < ram <= os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


@pytest.mark.parametrize("given", ["lots", "-5", "0", "0.5", "nan", "inf", "1e400", "1e18G", "8X", "8 G B"])
def test_a_memory_limit_of_no_positive_bytes_is_refused_naming_it(monkeypatch, capsys, tmp_path, given):
    """A negative or zero limit refused every result as needing more than "-0.0 GiB"; an infinite one ended the
    command with an internal OverflowError."""
    monkeypatch.setenv("OMNINOISE_MEMORY_LIMIT", given)
    with pytest.raises(SettingError, match=f"OMNINOISE_MEMORY_LIMIT: expected a positive number of bytes like 8G "
                                           rf"\(a K, M, G or T suffix\), got '{given}'"):
        limits.memory_limit()
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "w.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("omninoise wave: error: OMNINOISE_MEMORY_LIMIT: ") and "\n" not in err, err
    assert not (tmp_path / "w.png").exists()


def test_a_neural_image_is_refused_by_what_it_takes_drawn_whole_or_in_tiles(monkeypatch, capsys, tmp_path):
    """Up to 1024 px an image is drawn whole (the U-Net's activations over every pixel), larger ones in 512 px
    tiles: what a size takes grows by the piece drawn at once plus a little per pixel."""
    from omninoise.backend.neural import generate as G

    monkeypatch.delenv("OMNINOISE_MEMORY_LIMIT", raising=False)
    monkeypatch.setattr(limits, "physical_memory", lambda: 64 << 30)     # the 16 GiB default, whatever this machine
    assert G.peak_bytes(1024, 1024) == 1024 ** 2 * (G.PIECE_BYTES + G.IMAGE_BYTES)
    assert G.peak_bytes(4096, 4096) == 512 ** 2 * G.PIECE_BYTES + 4096 ** 2 * G.IMAGE_BYTES
    assert G.peak_bytes(2048, 2048, tile=0) == 2048 ** 2 * (G.PIECE_BYTES + G.IMAGE_BYTES)
    G.check_memory("size", 4096, 4096)                      # about 5 GiB: drawn in tiles under 16 GiB
    with pytest.raises(SettingError, match=r"size: a 9000 x 9000 neural image needs 20\.1 GiB, above the limit"):
        G.check_memory("size", 9000, 9000)
    monkeypatch.setenv("OMNINOISE_MEMORY_LIMIT", "2G")
    with pytest.raises(SettingError, match=r"a 1024 x 1024 neural image needs 3\.6 GiB"):
        G.check_memory("size", 1024, 1024)                  # drawn whole
    G.check_memory("size", 1024, 1024, tile=512)            # in tiles it fits
    out = tmp_path / "n.png"
    assert main(["neural", "--noise", "perlin", "--size", "1024", "-o", str(out)]) == 2
    assert main(["neural", "--noise", "perlin", "--size", "1024", "--tile", "0", "-o", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 2 and all(ln.startswith("omninoise neural: error: --size: a 1024 x 1024 neural image needs")
                                 for ln in err), err
    assert not out.exists()


@pytest.mark.parametrize("edit, match", [
    (("time_step = 0.5", "time_step = nan"), "time_step: must be a finite number"),   # was a segfault
    (("time_step = 0.5", 'time_step = "x"'), "time_step: expected a number"),
    (("time_step = 0.5", 'time_step = 0.5\ntime = "x"'), "time: expected a number"),       # was a ValueError
    (("frames = [1, 2]", 'frames = ["a", "b"]'), r"frames\[0\]: expected a whole number, got 'a'"),
    (('output = "out/clouds_##.vdb"', 'output = "out/clouds_##.npy"'),
     r"bake 'clouds': transfer: .npy holds the raw values, which a ramp does not colour"),   # was left out unsaid
    (("seed = 4", 'seed = 4\ntransition_to = {kind = "gaussian", fmin = 1, fmax = 3}\ntransition_axis = [0, 0, 0]'),
     r"source.transition_axis: transition axis \(0.0, 0.0, 0.0\) must be a non-zero 3-vector"),  # was all NaN
    (("seed = 4", 'seed = 4\nanisotropy = "lobes"\nlobes = [[[1, 0], 1]]'),
     r"source.lobes\[0\]: lobe axis \(1.0, 0.0\) must be a non-zero 3-vector"),
    (("half = true", 'half = "no"'), "half: expected true or false"),                 # "no" was taken as true
    # the tables' own rules: found while baking (exit 1, the bakes before it written), now when the job is read
    (("seed = 4", 'seed = 4\nanisotropy = "lobes"\nlobes = [[[1, 0, 0], 0]]'),
     "source.lobes: lobe weights must not all be zero"),
    (("seed = 4", "seed = 4\ntable_period = 1e-6"), "source.spectrum: the band holds no table harmonic"),
    (("seed = 4", "seed = 4\ntable_period = 1e6"),
     "source.fmax: 4 cycles/unit is at or above the wave table's Nyquist"),
    (("resolution = [32, 16]", "resolution = [100000000, 100000]"), "resolution"),
    (("bounds = [[-1, -1, 0], [1, 1, 1]]", "bounds = [[-1, -1, 0], [inf, 1, 1]]"), r"bounds\[1\]\[0\]: must be a finite number, got inf"),
    (('[[bake]]\nname = "marble"', '[[bake]]\nname = "first"\noutput = "out/../out/marble.exr"\n'
      'resolution = [8, 8]\n[bake.source]\ndim = 2\n\n[[bake]]\nname = "marble"'),
     "bake 'marble': output .* is also written by bake 'first'"),              # was a silent overwrite
])
def test_bad_job_numbers_are_named(tmp_path, edit, match):
    (tmp_path / "out").mkdir()
    (tmp_path / "ramp.json").write_text(RAMP)
    job = tmp_path / "job.toml"
    job.write_text(JOB.replace(*edit))
    res = run_job(str(job))
    failed = [r for r in res if r.status == "invalid"]
    assert failed and re.search(match, failed[0].message), [r.message for r in res]
    assert os.listdir(tmp_path / "out") == []


def test_atomic_writes_refuse_folders_and_clean_stale_temporaries(tmp_path, capsys):
    import time

    from omninoise.export.atomic import STALE_SECONDS, atomic_path

    old = tmp_path / ".omninoise-dead.npy"          # left by a killed process
    old.write_bytes(b"x")
    past = time.time() - STALE_SECONDS - 60
    os.utime(old, (past, past))
    fresh = tmp_path / ".omninoise-live.npy"        # another process's write in progress
    fresh.write_bytes(b"x")
    with atomic_path(str(tmp_path / "a.txt")) as tmp:
        with open(tmp, "w") as fh:
            fh.write("ok")
    assert (tmp_path / "a.txt").read_text() == "ok"
    assert not old.exists() and fresh.exists()
    (tmp_path / "dir.npy").mkdir()
    with pytest.raises(IsADirectoryError, match="is a folder"):
        with atomic_path(str(tmp_path / "dir.npy")):
            pass
    rc = main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "dir.npy")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and "is a folder" in err[0]


def test_model_without_hashes_is_refused(tmp_path):
    import json

    from omninoise.backend.onnx_models import ModelError, load_model_json, sealed

    (tmp_path / "solid.json").write_text(json.dumps(sealed({"model": "neural_solid_texture"})))
    with pytest.raises(ModelError, match="lists no files with their sha256"):
        load_model_json(str(tmp_path), "solid.json")


@pytest.mark.parametrize("args, setting", [
    (["neural", "--noise", "perlin", "--seed", "-1", "-o", "{d}/n.png"], "--seed"),
    (["neural", "--noise", "perlin", "--size", "100000000", "-o", "{d}/n.png"], "--size"),
    (["solid", "--exemplar", "gravel", "--scale", "inf", "-o", "{d}/s.png"], "--scale"),
    (["solid", "--exemplar", "gravel", "--size", "100000000", "-o", "{d}/s.png"], "--size"),
    (["zoo", "--noise", "perlin", "-o", "{d}/o.txt"], "-o"),
    (["neural", "--noise", "perlin", "--param", "=3", "-o", "{d}/n.png"], "--param: expected NAME=VALUE"),
    (["neural", "--noise", "perlin", "--param", "scale=3", "--param", "scale=4", "-o", "{d}/n.png"],
     "--param: scale is given twice"),
    (["neural", "--noise", "perlin", "--param", "scale=300", "-o", "{d}/n.png"], "--param: scale=300 is outside"),
    (["neural", "--corners", "perlin", "gabor", "spots", "noise:Scale=99", "-o", "{d}/n.png"],
     "--corners: Scale=99 is outside"),
    (["neural", "--noise", "perlin", "--latent", "slerp", "-o", "{d}/n.png"], "--latent: moves the starting noise"),
    (["neural", "--noise", "perlin", "--drift", "1", "-o", "{d}/n.png"], "--drift: moves the starting noise"),
    (["neural", "--fit", "{d}/none.png", "--fit-size", "4", "-o", "{d}/n.png"], "--fit-size: must be a multiple"),
    (["solid", "--exemplar", "grass", "--mix", "0.3", "-o", "{d}/s.png"], "--mix: weighs the texture of --to"),
    (["neural", "--noise", "perlin", "--width", "8", "-o", "{d}/n.png"], "--width: shapes the transitions"),
    (["transfer", "fire", "-o", "{d}/ramp.txt"], "-o: a ramp is written as .json"),
    (["transfer", "-o", "{d}/ramp.json"], "-o: saves a preset: give its name"),
    (["transfer", "--list", "fire"], "--list: lists the presets"),
    (["bake", "{d}/job.toml", "--retries", "5"], "--retries: applies to a farm bake"),
    (["bake", "{d}/job.toml", "--brick-voxels", "64"], "--brick-voxels: applies to a farm bake"),
    (["bake", "{d}/job.toml", "--tls-cert", "c.pem"], "--tls-cert: applies to a farm bake"),
    (["bake", "{d}/job.toml", "--cluster", "http://host:8786"],
     "--cluster: expected a Dask scheduler's address, tcp://HOST:PORT"),
    (["neural", "--corners", "perlin", "gabor", "spots", "noise", "--sharpness", "2", "-o", "{d}/n.png"],
     "--sharpness: shapes the transitions"),
    # flags the image's layout does not read (each was ignored): a map's regions, a class beside the corners
    (["neural", "--noise", "perlin", "--region", "0=spots", "-o", "{d}/n.png"],
     "--region: names the colours of --map; without --map, it would change nothing"),
    (["neural", "--corners", "perlin", "gabor", "spots", "noise", "--param", "scale=4", "-o", "{d}/n.png"],
     "--param: sets the parameters of --noise; with --corners, it would change nothing"),
    (["neural", "--corners", "perlin", "gabor", "spots", "noise", "--noise", "perlin", "-o", "{d}/n.png"],
     "--noise: is the class of the whole image, or of a blend's unmasked part; with --corners"),
    (["neural", "--noise", "perlin", "--fit-size", "32", "-o", "{d}/n.png"],
     "--fit-size: a fit window size needs --fit"),
    # half an animation is named by the half given (it was told that --noise changes nothing with --keys)
    (["neural", "--noise", "perlin", "--frames", "1", "3", "-o", "{d}/n_#.png"],
     "--frames: an animation needs both --keys KEYS.toml and --frames FIRST LAST"),
    (["neural", "--keys", "{d}/keys.toml", "-o", "{d}/n_#.png"],
     "--keys: an animation needs both --keys KEYS.toml and --frames FIRST LAST"),
    # a photo's settings for a shipped texture, a rest's orientation without the rest (each was ignored)
    (["solid", "--exemplar", "grass", "--refine", "2", "-o", "{d}/s.png"],
     "--refine: refinement fits the code to a photo; 'grass' is a shipped texture, drawn from the model's own code"),
    (["solid", "--exemplar", "grass", "--no-periodic", "-o", "{d}/s.png"],
     "--no-periodic: the periodic part is read off a photo; 'grass' is a shipped texture"),
    (["solid", "--exemplar", "grass", "--rest", "upright", "--no-gaussian", "-o", "{d}/s.png"],
     "--rest: orients the Gaussian rest, which --no-gaussian leaves out: it would change nothing"),
    # options beside --list, which only prints (each was passed over: -o wrote nothing and said nothing)
    (["solid", "--list", "-o", "{d}/s.png"],
     "-o: --list only prints the shipped textures: leave out -o, which would change nothing"),
    (["solid", "--list", "--no-periodic"], "--no-periodic: --list only prints the shipped textures"),
    (["neural", "--list", "--noise", "perlin", "--size", "64"], "--noise: --list only prints the classes"),
])
def test_bad_neural_solid_zoo_input(tmp_path, capsys, args, setting):
    rc = main([x.format(d=tmp_path) for x in args])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and setting in err[0], err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("content, name", [("0 1 banana 2\n", "p.txt"), ("", "p.txt"), ("0 nan 1\n", "p.txt"),
                                           ("\x93NUMPY broken", "p.npy"), ("1 1 1 1\n", "p.txt"),
                                           ("0 1\n2 3\n", "p.txt")])
def test_bad_custom_profiles(tmp_path, capsys, content, name):
    (tmp_path / name).write_text(content)
    rc = main(["wave", "--size", "8", "--quiet", "--waveform", "custom", "--profile", str(tmp_path / name),
               "-o", str(tmp_path / "o.npy")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and "--profile" in err[0], err
    assert not (tmp_path / "o.npy").exists()


def test_an_internal_error_is_one_line_without_debug_and_a_traceback_with_it(tmp_path, capsys, monkeypatch):
    """Exit 1 and one line naming the exception for a bug; `omninoise --debug ...` re-raises it."""
    import omninoise.cli.main as cli
    from omninoise.cli import zoo

    def broken(a):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(zoo, "run", broken)
    assert cli.main(["zoo", "--noise", "perlin", "-o", str(tmp_path / "z.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "internal error: ZeroDivisionError: float division by zero" in err[0]
    assert "--debug" in err[0]
    with pytest.raises(ZeroDivisionError):
        cli.main(["--debug", "zoo", "--noise", "perlin", "-o", str(tmp_path / "z.png")])


@pytest.mark.parametrize("source, match", [
    ('exemplar = "gravel"\nscale = "big"', "source.scale: expected a number"),      # was an internal TypeError
    ('exemplar = "gravel"\nscale = inf', "source.scale: must be a finite number"),  # was baked
    ('exemplar = "gravel"\ndensity = -1', r"source.density: must lie in \[0, 1000000\], got -1"),
    ('method = "synthesis"\nexemplar = "ex.png"\nscale = "big"', "source.scale: expected a number"),
    ('method = "synthesis"\nexemplar = "ex.png"\nscale = 0', r"source.scale: must lie in \[0.0001, 10000\]"),
])
def test_bad_solid_source_numbers_are_named(tmp_path, source, match):
    from omninoise.export.images import write_png
    import numpy as np

    write_png(str(tmp_path / "ex.png"), np.random.default_rng(0).integers(0, 256, (64, 64, 3)).astype(np.uint8))
    job = tmp_path / "job.toml"
    job.write_text(f'[[bake]]\nname = "s"\noutput = "s.png"\nresolution = [8, 8]\nbounds = [[0, 0, 0], [1, 1, 0]]\n'
                   f'[bake.source]\nkind = "solid"\n{source}\n')
    res = run_job(str(job))
    assert res[0].status == "invalid" and re.search(match, res[0].message), [r.message for r in res]
    assert not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("flag, value", [("--sharpness", "inf"), ("--width", "-1")])
def test_a_blend_setting_is_named_by_its_flag(tmp_path, capsys, flag, value):
    from PIL import Image

    Image.fromarray(np.tile(np.arange(16, dtype=np.uint8) * 16, (16, 1))).save(tmp_path / "m.png")
    rc = main(["neural", "--noise", "perlin", "--size", "16", "--blend", str(tmp_path / "m.png"), flag, value,
               "-o", str(tmp_path / "n.png")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and f"error: {flag}: " in err[0], err
    assert os.listdir(tmp_path) == ["m.png"]


@pytest.mark.parametrize("source, why", [
    ('kind = "neural"\nnoise = "perlin"', "frames: this source does not change over time (give keys: keyframes "
                                          "of its classes)"),
    ('kind = "wave"', "frames: this source does not change over time (set speed, or dim = 4)"),
    ('kind = "solid"\nexemplar = "grass"', "frames: this source does not change over time"),
])
def test_a_frame_range_of_a_still_source_says_what_would_animate_it(tmp_path, source, why):
    """A still source's frame range is refused with the setting that animates its kind (a neural source's is its
    keyframes, not a wave's speed)."""
    job = tmp_path / "job.toml"
    job.write_text(f'[[bake]]\nname = "still"\noutput = "s_##.png"\nresolution = [16, 16]\nframes = [1, 2]\n'
                   f'[bake.source]\n{source}\n')
    res = run_job(str(job))
    assert [r.status for r in res] == ["invalid"] and res[0].message.endswith(why), res[0].message
    assert os.listdir(tmp_path) == ["job.toml"]


@pytest.mark.parametrize("command", [["neural", "--noise", "perlin", "--size", "16", "--steps", "1"], ["bake"]])
def test_threads_are_at_most_the_machine_s_cpus(tmp_path, capsys, monkeypatch, command):
    """More threads than CPUs wait on each other: neural noise took 265 s with --threads 1000 on 2 CPUs, 1.1 s with
    2. Past the CPUs this machine gives the command is refused naming them, before any work; 0 (all of them) and
    the count itself draw."""
    monkeypatch.setattr(limits, "cpus", lambda: 2)
    out = tmp_path / "n.npy"
    if command == ["bake"]:
        job = tmp_path / "job.toml"
        job.write_text('[[bake]]\nname = "w"\noutput = "w.png"\nresolution = [8, 8]\n[bake.source]\nkind = "wave"\n')
        argv = ["bake", str(job), "--quiet", "--force"]
    else:
        argv = command + ["--quiet", "-o", str(out)]
    assert main(argv + ["--threads", "3"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"omninoise {argv[0]}: error: --threads: 3 threads is more than the 2 CPUs this machine gives "
                     "it; ask for at most 2 (0: all of them)"], lines
    assert os.listdir(tmp_path) == ([] if command != ["bake"] else ["job.toml"])
    for n in ("0", "2"):
        assert main(argv + ["--threads", n]) == 0
    assert limits.threads("threads", 0) == 0 and limits.cpus() == 2
