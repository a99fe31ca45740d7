"""The `omninoise wave` command-line contract."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import omninoise
from omninoise.backend.errors import SettingError
from omninoise.cli.main import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(capsys, *args):
    rc = main(["wave", *args])
    err = capsys.readouterr().err
    return rc, err


def test_npy_shapes(tmp_path, capsys):
    out = str(tmp_path / "a.npy")
    assert run(capsys, "--size", "32", "--quiet", "-o", out)[0] == 0
    a = np.load(out)
    assert a.shape == (32, 32) and a.dtype == np.float32
    assert run(capsys, "--dim", "3", "--size", "16", "--quiet", "-o", out)[0] == 0
    assert np.load(out).shape == (16, 16, 16)
    assert run(capsys, "--dim", "4", "--time", "0.5", "--size", "12", "--quiet", "-o", out)[0] == 0
    assert np.load(out).shape == (12, 12, 12)


def test_png_and_exr(tmp_path, capsys):
    png, exr = str(tmp_path / "a.png"), str(tmp_path / "a.exr")
    assert run(capsys, "--size", "40", "--quiet", "--cellular", "stit", "-o", png)[0] == 0
    with open(png, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    assert run(capsys, "--size", "40", "--quiet", "--output", "phase", "-o", exr)[0] == 0
    from omninoise.export.images import read_image

    img = read_image(exr)
    assert img.shape == (40, 40) and img.min() >= -np.pi - 1e-6 and img.max() <= np.pi + 1e-6


@pytest.mark.parametrize("args,setting", [
    (["--fmin", "9", "--fmax", "8"], "--fmin"),
    (["--directions", "0"], "--directions"),
    (["--period", "100"], "Nyquist"),
    (["--example", "/no/such/image.png"], "--example"),
    (["--waveform", "custom"], "--profile"),
    (["--transfer", "nope"], "--transfer: 'nope' is neither a preset"),
])
def test_bad_settings_fail_with_one_line(tmp_path, capsys, args, setting):
    out = tmp_path / "x.png"
    rc, err = run(capsys, "--size", "16", "--quiet", *args, "-o", str(out))
    lines = [l for l in err.splitlines() if l.strip()]
    assert rc != 0 and len(lines) == 1 and setting in lines[0], err
    assert not out.exists()


def test_a_ramp_on_raw_values_is_refused_in_the_words_of_a_job(tmp_path, capsys):
    from omninoise.backend.bake import NPY_RAMP

    out = tmp_path / "x.npy"
    rc, err = run(capsys, "--size", "16", "--quiet", "--transfer", "fire", "-o", str(out))
    assert (rc, err.strip()) == (2, f"omninoise wave: error: --transfer: {NPY_RAMP}") and not out.exists()
    assert "remove the ramp" in NPY_RAMP


def test_existing_output_survives_failure(tmp_path, capsys):
    out = tmp_path / "keep.npy"
    np.save(out, np.arange(3, dtype=np.float32))
    rc, _ = run(capsys, "--size", "16", "--quiet", "--fmin", "9", "--fmax", "8", "-o", str(out))
    assert rc != 0 and np.array_equal(np.load(out), np.arange(3, dtype=np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.npy"]


def test_python_dash_m_backend(tmp_path):
    out = str(tmp_path / "m.npy")
    r = subprocess.run([sys.executable, "-m", "omninoise", "wave", "--size", "8", "--quiet", "-o", out],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert np.load(out).shape == (8, 8)


@pytest.mark.parametrize("argv", [["wave", "--dim", "3", "--size", "8"], ["solid", "--exemplar", "gravel_3d", "--dim", "3",
                                                                          "--size", "8"]])
def test_vdb_without_openvdb_is_bad_input_before_any_work(argv, tmp_path, monkeypatch, capsys):
    """Where no OpenVDB module can write .vdb (a pip install without bpy), the command says so in one line and
    exits 2 before any work, as every front end does (the bake's validation)."""
    import omninoise.export.vdb as vdb
    from omninoise.cli.main import main

    def missing():
        raise RuntimeError("writing .vdb needs the OpenVDB Python module (test)")

    monkeypatch.setattr(vdb, "openvdb_module", missing)
    out = tmp_path / "v.vdb"
    assert main(argv + ["--quiet", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-o: writing .vdb needs the OpenVDB Python module" in err[0], err
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv", [
    ["wave", "--size", "8", "-o", "{d}/w_##.npy"],
    ["solid", "--exemplar", "grass", "--size", "8", "-o", "{d}/s_##.png"],
    ["neural", "--noise", "perlin", "--size", "16", "-o", "{d}/n_####.png"],
    ["bake", "{d}/job.toml"],
])
def test_a_frame_number_in_the_name_of_one_file_is_refused(tmp_path, capsys, argv):
    """'#' is the frame number of a sequence (job files, neural --frames, Blender): in the name of one file it is a
    mistake, refused in one line before any work, not written as a file named 'w_##.npy'."""
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "a"\noutput = "j_##.exr"\nresolution = [8, 8]\n'
                                       '[bake.source]\nkind = "wave"\n')
    rc = main([x.format(d=tmp_path) for x in argv] + ["--quiet"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and "'#' stands for the frame number of a sequence" in err[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["job.toml"]
    with pytest.raises(SettingError, match="'#' stands for the frame number"):
        omninoise.wave(8, out=str(tmp_path / "w#.npy"))


@pytest.mark.parametrize("argv", [["transfer", "fire"], ["neural", "--list"], ["--version"]])
def test_a_reader_that_leaves_the_pipe_ends_the_command_quietly(argv):
    """`omninoise neural --list | head -1`: when the reader of standard output has left, the command ends with
    128 + SIGPIPE and no traceback or 'internal error' (it reported a BrokenPipeError as a bug)."""
    read, write = os.pipe()
    os.close(read)                      # the reader is gone before the first write
    try:
        r = subprocess.run([sys.executable, "-m", "omninoise", *argv], cwd=ROOT, stdout=write,
                           stderr=subprocess.PIPE, text=True)
    finally:
        os.close(write)
    assert r.returncode == 141 and r.stderr == "", r.stderr


@pytest.mark.parametrize("flag, value, needs", [
    ("--exponent", "2", ["--spectrum", "fractal"]), ("--profile", "{d}/p.txt", ["--waveform", "custom"]),
    ("--cell-size", "0.5", ["--cellular", "polytope"]), ("--stit-probability", "0.3", ["--cellular", "stit"]),
    ("--stit-depth", "2", ["--cellular", "stit"]), ("--axis-spectrum", "bandpass:1:2", None),
    ("--lobe", "1,0:1", ["--anisotropy", "lobes"]), ("--spread", "10", ["--anisotropy", "lobes", "--lobe", "1,0:1"]),
    ("--example-plane", "xz", None), ("--example-extent", "2", None), ("--sectors", "4", None),
    ("--transition-length", "2", ["--transition", "bandpass:1:2"]),
])
def test_a_flag_read_only_beside_another_is_refused_alone(tmp_path, capsys, flag, value, needs):
    """A wave flag that changes the noise only beside another setting (the fractal exponent, a cell size, a lobe)
    is refused without it, naming both, as the solid command refuses a flag its method does not read: the noise
    would not be the one asked for. With the setting it needs, the command runs."""
    (tmp_path / "p.txt").write_text("0 1 0.5 0.2\n")
    out, value = str(tmp_path / "o.npy"), value.format(d=tmp_path)
    rc, err = run(capsys, "--size", "8", "--quiet", flag, value, "-o", out)
    assert rc == 2 and err.startswith(f"omninoise wave: error: {flag}: is read only with ") and \
        err.count("\n") == 1, err
    assert not os.path.exists(out)
    if needs is not None:
        rc, err = run(capsys, "--size", "8", "--quiet", flag, value, *needs, "-o", out)
        assert rc == 0, err


def test_a_by_example_plane_is_read_in_3d_only(tmp_path, capsys):
    """A 2D by-example noise lies in its image's plane: --example-plane and --spread (the band's half-angle around
    that plane) are read by 3D by-example noise only."""
    from omninoise.export.images import write_png

    write_png(str(tmp_path / "e.png"), (np.random.default_rng(0).random((32, 32)) * 255).astype(np.uint8))
    out, ex = str(tmp_path / "o.npy"), str(tmp_path / "e.png")
    for flag, value in (("--example-plane", "xz"), ("--spread", "10")):
        rc, err = run(capsys, "--size", "8", "--quiet", "--example", ex, flag, value, "-o", out)
        assert rc == 2 and f"{flag}: is read only with " in err and "--example with --dim 3" in err, err
        rc, err = run(capsys, "--size", "8", "--quiet", "--dim", "3", "--example", ex, flag, value, "-o", out)
        assert rc == 0, err


@pytest.mark.parametrize("argv", [
    ["wave", "--size", "16", "-o", "{d}/w.npy"],
    ["neural", "--noise", "perlin", "--size", "16", "--steps", "1", "-o", "{d}/n.npy"],
    ["solid", "--exemplar", "wood_3d", "--size", "16", "-o", "{d}/s.npy"],
    ["bake", "{d}/job.toml"],
])
def test_q_is_quiet(tmp_path, capsys, argv):
    """`-q` is `--quiet`, as in most command-line tools: the command writes its file and nothing to stderr."""
    (tmp_path / "job.toml").write_text('[[bake]]\nname = "a"\noutput = "j.npy"\nresolution = [8, 8]\n'
                                       '[bake.source]\nkind = "wave"\n')
    assert main([x.format(d=tmp_path) for x in argv] + ["-q"]) == 0
    assert capsys.readouterr().err == ""
    assert len(list(tmp_path.glob("*.npy"))) == 1


def test_list_prints_a_table_to_read_and_json_with_json(capsys):
    """`--list` is read by people: one row per noise class or shipped texture, with the parameters' ranges and units;
    `--list --json` gives scripts the same as JSON. `--json` alone would change nothing and is refused."""
    import doctest

    from omninoise.cli import listing
    assert doctest.testmod(listing).failed == 0
    assert main(["neural", "--list"]) == 0
    text = capsys.readouterr().out
    assert main(["neural", "--list", "--json"]) == 0
    classes = json.loads(capsys.readouterr().out)["classes"]
    rows = [ln for ln in text.splitlines() if ln and not ln.startswith(" ")]
    assert [r.split()[0] for r in rows[:-1]] == list(classes) and rows[-1].startswith(f"{len(classes)} classes")
    assert "scale 4 to 20 (cells per 128 px), jitter 0.2 to 1 (cell jitter)" in text
    assert "detail 2 to 8 (octaves, whole numbers)" in text and max(map(len, text.splitlines())) <= listing.WIDTH
    assert main(["solid", "--list"]) == 0
    text = capsys.readouterr().out
    assert main(["solid", "--list", "--json"]) == 0
    textures = json.loads(capsys.readouterr().out)
    singles = [name for name, t in textures.items() if t["mode"] == "single"]
    assert [ln.split()[0] for ln in text.splitlines()[:len(singles)]] == singles
    assert "wood_3d     3D solid from wood__oldwood.jpg" in text and "by name (the space model): brick, concrete" in text
    tiny = os.path.join(ROOT, "tests", "data", "tiny_neural")     # trained on three of the classes
    assert main(["neural", "--model", tiny, "--list"]) == 0
    text = capsys.readouterr().out
    assert [ln.split()[0] for ln in text.splitlines()[:6:2]] == ["perlin", "spots", "cells_f1"]
    assert "3 classes:" in text and "The model was not trained on cells_borders," in text
    for command in ("neural", "solid"):
        assert main([command, "--json"]) == 2
        assert "--json: prints --list as JSON: give --list too" in capsys.readouterr().err


def test_wave_notes_the_kernel_only_when_no_compiled_one_runs(tmp_path, capsys, monkeypatch):
    """Which kernel runs is `--version`'s to say; `omninoise wave` notes it only where numpy runs, several times
    slower, with what brings a compiled one."""
    from omninoise.backend.wavenoise import fast
    out = str(tmp_path / "w.npy")
    monkeypatch.setattr(fast, "compiled", lambda: True)
    rc, err = run(capsys, "--size", "16", "-o", out)
    assert rc == 0 and "kernel" not in err and "numpy" not in err
    monkeypatch.setattr(fast, "compiled", lambda: False)
    rc, err = run(capsys, "--size", "16", "-o", out)
    assert rc == 0 and "omninoise wave: note: wave noise runs on " in err
    assert "kernel" not in run(capsys, "--size", "16", "--quiet", "-o", out)[1]


def test_transfer_list_names_each_preset_and_its_look(capsys):
    """`omninoise transfer --list`: a line per preset, its name first (what scripts read) and what it looks like."""
    from omninoise.backend.transfer import PRESET_NOTES, PRESETS
    assert main(["transfer", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in lines] == list(PRESETS) and set(PRESET_NOTES) == set(PRESETS)
    assert all(ln.endswith(PRESET_NOTES[ln.split()[0]]) for ln in lines)
