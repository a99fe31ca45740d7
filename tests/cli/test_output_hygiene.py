"""What a command leaves behind and prints: temporaries that fit any legal name and are removed by their own
writers only, no NaN written, SIGTERM and SIGHUP handled as Ctrl+C, control characters escaped."""
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from omninoise import export
from omninoise.export.images import write_unit_image
from omninoise.cli.common import shown
from omninoise.cli.main import main
from omninoise.backend.onnx_models import sealed
from conftest import needs_openvdb


def wave_job(folder, name: str, output: str, bake: str = "", source: str = "", resolution: str = "[4, 4]"):
    """A job file of one wave bake: ``bake`` and ``source`` are extra TOML lines of its two tables."""
    job = folder / "job.toml"
    job.write_text(f'[[bake]]\nname = "{name}"\noutput = "{output}"\nresolution = {resolution}\n{bake}'
                   f'[bake.source]\nkind = "wave"\n{source}')
    return job


def test_every_legal_output_name_gets_a_temporary_within_the_name_limit(tmp_path):
    for n in (1, 200, 251):                               # 251 + ".npy": the longest legal name
        out = tmp_path / ("w" * n + ".npy")
        assert main(["wave", "--size", "8", "--quiet", "-o", str(out)]) == 0
        assert np.load(out).shape == (8, 8)
    a, b = (export.partial_prefix(str(tmp_path / (s * 250 + ".exr")), "farm-0123456789ab") for s in "xy")
    assert a != b and max(len(a), len(b)) + 8 + export.atomic.SUFFIX_PART <= 160
    assert export.partial_prefix("x" * 90 + "a.png") != export.partial_prefix("x" * 90 + "b.png")


def test_a_tagged_writer_removes_its_own_temporaries_and_no_one_elses(tmp_path):
    out = str(tmp_path / "cloud.vdb")
    with export.tagged("farm-1"):
        with pytest.raises(RuntimeError):
            with export.atomic_path(out) as tmp:
                assert os.path.basename(tmp).startswith(export.partial_prefix(out, "farm-1"))
                raise RuntimeError("stop")
        assert not os.path.exists(tmp)                    # its own failed write leaves nothing
    mine = tmp_path / (export.partial_prefix(out, "farm-1") + "dead.vdb")          # a killed worker's
    theirs = tmp_path / (export.partial_prefix(out) + "live.vdb")                  # another process's, writing now
    other_farm = tmp_path / (export.partial_prefix(out, "farm-2") + "live.vdb")
    for p in (mine, theirs, other_farm):
        p.write_bytes(b"half")
    assert export.remove_partials(out, "farm-1") == [mine.name]
    assert theirs.exists() and other_farm.exists()
    with pytest.raises(ValueError, match="tag"):
        export.remove_partials(out, "")
    with pytest.raises(ValueError, match="tag"):
        with export.tagged("../x"):
            pass


@pytest.mark.parametrize("ext", [".npy", ".exr", ".png"])
def test_no_writer_writes_nan_or_infinity(tmp_path, ext):
    out = str(tmp_path / ("x" + ext))
    bad = np.zeros((4, 4, 3), np.float32)
    bad[1, 2, 0] = np.nan
    with pytest.raises(export.NonFiniteError, match="1 of 48 values are NaN or infinite"):
        export.write_image(out, bad)
    write = {".png": write_unit_image, ".npy": export.write_npy, ".exr": export.write_exr}[ext]
    with pytest.raises(export.NonFiniteError):
        write(out, np.full((4, 4), np.inf, np.float32))
    assert os.listdir(tmp_path) == []


def test_half_floats_refuse_values_they_would_write_as_infinite(tmp_path, capsys):
    """A 16-bit half holds up to 65504: past it the file held infinities unsaid (a ramp colour of 1e5 with
    --half). The writers refuse such values; a bake whose ramp reaches past it is refused before any work."""
    out = str(tmp_path / "x.exr")
    big = np.zeros((4, 4), np.float32)
    big[0, 0], big[1, 1] = 65504.0, -7e4
    with pytest.raises(export.NonFiniteError, match="1 of 16 values lie past 65504, the largest 16-bit half"):
        export.write_exr(out, big, half=True)
    assert os.listdir(tmp_path) == []
    export.write_exr(out, big)                          # 32-bit floats hold them
    try:
        w = export.VolumeWriter((1, 1, 1), (0, 0, 0), {"density": "float"}, half=True)
    except RuntimeError:
        w = None
    if w is not None:
        with pytest.raises(export.NonFiniteError, match="grid 'density'.*past 65504"):
            w.add("density", 0, big[None] * 2)
    (tmp_path / "hot.json").write_text('{"stops": [[0, [0, 0, 0, 1]], [1, [100000, 1, 1, 1]]]}')
    (tmp_path / "dense.json").write_text('{"density_scale": 1e5, "stops": [[0, [0, 0, 0, 1]], [1, [1, 1, 1, 1]]]}')
    cases = [("hot.json", "h.exr", [])] + ([("dense.json", "d.vdb", ["--dim", "3"])] if w is not None else [])
    for ramp, name, extra in cases:         # the colours of an image, the density of a volume
        target = str(tmp_path / name)
        assert main(["wave", "--quiet", "--size", "8", "--transfer", str(tmp_path / ramp), "--half", "-o", target,
                     *extra]) == 2
        err = capsys.readouterr().err
        assert "--half: the ramp writes values up to 100000" in err and not os.path.exists(target), err
    # an image writes the ramp's colours and alpha, not its density: a density_scale past 65504 is no matter there
    assert main(["wave", "--quiet", "--size", "8", "--transfer", str(tmp_path / "dense.json"), "--half", "-o",
                 str(tmp_path / "d.exr")]) == 0


def test_a_volume_writer_refuses_nan_slabs():
    try:
        w = export.VolumeWriter((1, 1, 1), (0, 0, 0), {"density": "float"})
    except RuntimeError:
        pytest.skip("no OpenVDB module")
    slab = np.zeros((2, 3, 4), np.float32)
    slab[0, 0, 0] = -np.inf
    with pytest.raises(export.NonFiniteError, match="density"):
        w.add("density", 0, slab)


def test_times_and_speeds_whose_product_overflows_are_refused_before_any_work(tmp_path, capsys):
    """A time, speed or frame step that would overflow the waves' phases (NaN images before) is refused, named."""
    out = tmp_path / "t.npy"
    for args, said in ((["--time", "1e308", "--speed", "1"], "--time: must lie in [-1e+09, 1e+09]"),
                       (["--time", "1", "--speed", "1e300"], "--speed: must lie in [-1000000, 1000000], got 1e+300")):
        assert main(["wave", "--size", "16", "--quiet", "-o", str(out), *args]) == 2
        assert said in capsys.readouterr().err
    job = wave_job(tmp_path, "t", "f_#.npy", 'frames = [1, 3]\ntime_step = 1e308\n', 'speed = 1.0\n')
    assert main(["bake", str(job)]) == 2
    assert "time_step: must lie in (0, 1000000000], got 1e+308" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["job.toml"]


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_sigterm_and_sighup_during_a_write_remove_the_temporary(tmp_path, monkeypatch, capsys, sig, code):
    """The signal arrives while the output's temporary is half written: the command stops as Ctrl+C stops it,
    exits 128 + the signal's number, and leaves no file; the handlers before it are restored."""
    before = signal.getsignal(sig)
    real = np.save

    def save_then_signal(fh, arr, *a, **k):
        fh.write(b"\x93NUMPY half")
        fh.flush()
        assert any(n.startswith(".omninoise-") for n in os.listdir(tmp_path))     # the temporary is there
        os.kill(os.getpid(), sig)
        real(fh, arr, *a, **k)

    monkeypatch.setattr(np, "save", save_then_signal)
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "w.npy")]) == code
    assert os.listdir(tmp_path) == []
    assert "terminated; no partial file was left" in capsys.readouterr().err
    assert signal.getsignal(sig) == before


def test_sigterm_stops_a_running_command_with_143(tmp_path):
    """A real process: SIGTERM while it computes ends it with 143 and nothing in its folder."""
    code = "import sys; from omninoise.cli.main import main; sys.exit(main())"
    p = subprocess.Popen([sys.executable, "-c", code, "wave", "--dim", "3", "--size", "512", "--directions", "64",
                          "--quiet", "-o", str(tmp_path / "v.npy")], stderr=subprocess.PIPE, text=True)
    try:
        p.wait(timeout=3)
        pytest.fail("the command ended before it could be stopped")
    except subprocess.TimeoutExpired:
        p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=120) == 143, p.stderr.read()
    assert "terminated" in p.stderr.read() and os.listdir(tmp_path) == []


def test_names_and_messages_are_printed_with_control_characters_escaped_and_cut(tmp_path, capsys):
    assert shown("a\x1b]0;owned\x07b\nc") == "a\\x1b]0;owned\\x07b\\nc"
    assert len(shown("x" * 10_000)) == 400 and shown("x" * 10_000).endswith("…")
    job = wave_job(tmp_path, "evil\\u001b]0;title\\u0007", "o.npy")
    assert main(["bake", str(job), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "evil\\x1b]0;title\\x07" in out


def test_counts_are_capped_before_any_work(tmp_path, capsys):
    """A job's frames, --threads and --refine have caps: past them, one line naming the setting and exit 2."""
    job = wave_job(tmp_path, "long", "f_#.npy", "frames = [1, 30000000]\n", "speed = 1.0\n")
    assert main(["bake", str(job), "--dry-run"]) == 2
    assert "30000000 frames is more than the 100000 one bake may write" in capsys.readouterr().out
    assert main(["neural", "--noise", "perlin", "--threads", "100000", "-o", str(tmp_path / "n.png")]) == 2
    assert "--threads: must lie in [0, 1024]" in capsys.readouterr().err
    assert main(["solid", "--exemplar", "grass", "--refine", "1000000000", "-o", str(tmp_path / "s.png")]) == 2
    assert "--refine: must lie in [0, 10000]" in capsys.readouterr().err
    assert os.listdir(tmp_path) == ["job.toml"]


@pytest.mark.parametrize("damage", ['{"files": {"decoder.onnx": "0"}, "dim": ', b'\xff\xfe not text',
                                    "[" * 100_000, '{"model": "neural_solid_texture", "files": {}, "dim": "x"}'])
def test_a_damaged_model_folder_is_left_out_and_the_others_listed(tmp_path, monkeypatch, capsys, damage):
    import json
    import shutil

    from omninoise.backend.paths import solid_models

    root = tmp_path / "models"
    shutil.copytree(os.path.join(solid_models(), "gravel_3d"), root / "solid" / "gravel_3d")
    (root / "solid" / "broken").mkdir()
    (root / "solid" / "broken" / "solid.json").write_bytes(damage if isinstance(damage, bytes) else damage.encode())
    if "dim" in str(damage) and "files" in str(damage) and '"x"' in str(damage):    # hashes fine, a field wrong
        doc = json.loads(damage)
        src = root / "solid" / "gravel_3d"
        doc["files"] = json.loads((src / "solid.json").read_text())["files"]
        for name in doc["files"]:
            shutil.copy(src / name, root / "solid" / "broken" / name)
        (root / "solid" / "broken" / "solid.json").write_text(json.dumps(sealed(doc)))
    monkeypatch.setenv("OMNINOISE_MODELS", str(root))
    assert main(["solid", "--list", "--json"]) == 0
    assert list(json.loads(capsys.readouterr().out)) == ["gravel_3d"]
    assert main(["solid", "--model", str(root / "solid" / "broken"), "--exemplar", "x", "-o",
                 str(tmp_path / "s.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "broken" in err[0] and "internal error" not in err[0]


def test_a_model_description_is_inside_the_sha256_check(tmp_path, capsys):
    """Zeroing a class embedding in neural_noise.json (weights untouched) is refused, in one line naming the
    file; so is a description without its seal. Every shipped description carries a seal that verifies."""
    import json
    import shutil

    from omninoise.backend.onnx_models import SEAL, json_seal

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    folder = tmp_path / "tiny"
    shutil.copytree(os.path.join(root, "tests", "data", "tiny_neural"), folder)
    doc = json.loads((folder / "neural_noise.json").read_text())
    doc["class_embedding"][0] = [0.0] * len(doc["class_embedding"][0])
    out = tmp_path / "n.png"
    for text, said in ((json.dumps(doc), f"{SEAL} does not match its contents"),
                       (json.dumps({k: v for k, v in doc.items() if k != SEAL}), f"has no {SEAL} seal")):
        (folder / "neural_noise.json").write_text(text)
        assert main(["neural", "--model", str(folder), "--noise", doc["classes"][0], "--size", "16", "--steps", "1",
                     "--quiet", "-o", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0] and "neural_noise.json" in err[0], err
        assert not out.exists()
    (folder / "neural_noise.json").write_text(json.dumps(sealed(doc)))     # sealed again: loads (and differs)
    assert main(["neural", "--model", str(folder), "--noise", doc["classes"][0], "--size", "16", "--steps", "1",
                 "--quiet", "-o", str(out)]) == 0
    shipped = [os.path.join(d, f) for d, _, fs in os.walk(os.path.join(root, "models")) for f in fs
               if f in ("neural_noise.json", "solid.json", "fit_bank.json")]
    assert len(shipped) >= 3
    for path in shipped:
        with open(path, encoding="utf-8") as fh:
            d = json.load(fh)
        assert d[SEAL] == json_seal(d), path


def test_a_damaged_earlier_volume_is_out_of_date_and_read_within_bounds(tmp_path, capsys):
    """An earlier .vdb at a job's output whose header lies (counts, lengths), is cut short or is noise: its
    metadata reads as {} at once (bounded bytes, no OpenVDB), so the bake is 'to bake', not a hang."""
    import struct
    import time

    from omninoise.export.vdb import read_vdb_metadata

    head = struct.pack("<qIIIB", 0x56444220, 224, 12, 0, 1) + b"0" * 36
    entry = b"".join(struct.pack("<I", len(x)) + x for x in (b"omninoise_key", b"string", b"abc"))
    good = head + struct.pack("<I", 1) + entry
    assert read_vdb_metadata_bytes(tmp_path, good) == {"omninoise_key": "abc"}
    for bad in (head + struct.pack("<I", 2 ** 31), head + struct.pack("<I", 1) + struct.pack("<I", 2 ** 31),
                good[:-2], np.random.default_rng(0).bytes(4096), b""):
        t = time.perf_counter()
        assert read_vdb_metadata_bytes(tmp_path, bad) == {}
        assert time.perf_counter() - t < 1.0
    job = wave_job(tmp_path, "v", "v.vdb", "", "dim = 3\n", "[4, 4, 4]")
    (tmp_path / "v.vdb").write_bytes(head + struct.pack("<I", 2 ** 31))
    assert main(["bake", str(job), "--dry-run"]) == 0
    assert "to bake" in capsys.readouterr().out
    assert read_vdb_metadata(str(tmp_path / "missing.vdb")) == {}


def read_vdb_metadata_bytes(folder, data: bytes) -> dict:
    from omninoise.export.vdb import read_vdb_metadata

    p = folder / "x.vdb"
    p.write_bytes(data)
    return read_vdb_metadata(str(p))


def test_two_bakes_writing_one_file_are_refused_through_links_and_overlapping_frames(tmp_path, capsys):
    """The same file reached through a symlinked folder, or two frame patterns that share frames, are found
    before anything runs."""
    (tmp_path / "out").mkdir()
    os.symlink(tmp_path / "out", tmp_path / "alias")
    wave = '[bake.source]\nkind = "wave"\nspeed = 1.0\n'
    job = tmp_path / "job.toml"
    job.write_text(f'[[bake]]\nname = "a"\noutput = "out/a.npy"\nresolution = [4, 4]\n{wave}'
                   f'[[bake]]\nname = "b"\noutput = "alias/a.npy"\nresolution = [4, 4]\n{wave}'
                   f'[[bake]]\nname = "c"\noutput = "out/f_#.npy"\nresolution = [4, 4]\nframes = [1, 12]\n{wave}'
                   f'[[bake]]\nname = "d"\noutput = "out/f_##.npy"\nresolution = [4, 4]\nframes = [10, 12]\n{wave}'
                   f'[[bake]]\nname = "e"\noutput = "out/f_##.npy"\nresolution = [4, 4]\nframes = [13, 14]\n{wave}')
    assert main(["bake", str(job), "--dry-run"]) == 2
    out = capsys.readouterr().out
    assert "bake 'b': output a.npy is also written by bake 'a'" in out
    assert "bake 'd': output f_10.npy is also written by bake 'c'" in out
    assert "invalid" not in [ln for ln in out.splitlines() if " e:" in ln][0]


@pytest.mark.parametrize("args, flag", [
    (["wave", "--seed", "-1", "--size", "8", "-o", "{d}/a.npy"], "--seed: must lie in [0, 16777215], got -1"),
    (["wave", "--spectrum", "fractal", "--exponent", "nan", "--size", "8", "-o", "{d}/a.npy"],
     "--exponent: must be a finite number"),
    (["zoo", "--noise", "perlin", "--seed", "-1", "--size", "8", "-o", "{d}/z.png"], "--seed: must lie in [0, 2^32)"),
    (["neural", "--map", "{d}/m.png", "--region", "0=perlin", "--region", "0=spots", "--size", "8", "-o",
      "{d}/n.png"], "--region: '0' is given twice"),
])
def test_bad_values_are_named_by_their_flag_before_any_work(tmp_path, capsys, args, flag):
    from omninoise.export.images import write_png

    write_png(str(tmp_path / "m.png"), np.zeros((8, 8), np.uint8))
    assert main([x.format(d=tmp_path) for x in args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and flag in err[0], err
    assert sorted(os.listdir(tmp_path)) == ["m.png"]


def test_neural_tiles_and_a_fits_report_folder_are_checked_before_any_work(tmp_path, capsys):
    assert main(["neural", "--noise", "perlin", "--tile", "32", "--size", "64", "--steps", "1", "--quiet", "-o",
                 str(tmp_path / "n.png")]) == 2
    err = capsys.readouterr().err
    assert "--tile: 32 px tiles are too small for their 64 px overlap" in err and "use tiles of at least 128 px" in err
    img = tmp_path / "photo.png"
    from omninoise.export.images import write_png

    write_png(str(img), (np.random.default_rng(0).random((64, 64)) * 255).astype(np.uint8))
    assert main(["neural", "--fit", str(img), "--report", str(tmp_path / "nodir" / "r.json"), "--quiet", "-o",
                 str(tmp_path / "f.png")]) == 2
    assert "--report: output folder does not exist" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["photo.png"]


def test_half_floats_for_a_format_without_them_are_refused_in_a_job_as_on_the_command_line(tmp_path, capsys):
    job = wave_job(tmp_path, "h", "h.npy", "half = true\n")
    assert main(["bake", str(job), "--dry-run"]) == 2
    assert "half: writes 16-bit floats into .exr and .vdb only, not h.npy" in capsys.readouterr().out
    assert main(["wave", "--size", "4", "--half", "-o", str(tmp_path / "h.npy")]) == 2
    assert "--half: writes 16-bit floats into .exr and .vdb only" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["bake", "{f}"], ["neural", "--keys", "{f}", "--frames", "1", "2", "--size", "16",
                                                     "-o", "{d}/k_#.png"],
                                  ["wave", "--size", "8", "--transfer", "{f}", "-o", "{d}/w.png"]])
def test_documents_are_read_within_bounds(tmp_path, capsys, argv):
    """A job, keyframe or ramp file that is a FIFO, a device, not UTF-8 or nested past the parser's depth is
    refused in one line before any work (a FIFO blocked forever, /dev/zero grew until MemoryError)."""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    toml = argv[0] != "wave"
    cases = {str(fifo): "is not a regular file", "/dev/zero": "is not a regular file",
             "bad": "not UTF-8 text", "u16": "UTF-16 text; save it as UTF-8", "deep": "nested too deeply to read"}
    (tmp_path / "bad").write_bytes(b'a = "\xff"\n' if toml else b'{"stops": "\xff"}')
    (tmp_path / "u16").write_text('a = 1\n' if toml else '{"stops": 1}', encoding="utf-16")
    (tmp_path / "deep").write_text("a = " + "[" * 100_000 if toml else '{"a":' * 100_000)
    for name, said in cases.items():
        path = name if name.startswith("/") else str(tmp_path / name)
        assert main([x.format(f=path, d=tmp_path) for x in argv] + ["--quiet"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], (name, err)
    assert sorted(os.listdir(tmp_path)) == ["bad", "deep", "fifo", "u16"]


def test_a_document_saved_with_a_byte_order_mark_is_read(tmp_path):
    """Windows editors may begin UTF-8 text with a byte-order mark (and end lines with CR LF): a job file and a
    ramp so saved are read as without it."""
    job = tmp_path / "job.toml"
    job.write_bytes(b"\xef\xbb\xbf" + b'[[bake]]\r\nname = "w"\r\noutput = "w.png"\r\nresolution = [8, 8]\r\n'
                    b'transfer = "r.json"\r\n[bake.source]\r\nkind = "wave"\r\n')
    assert main(["transfer", "fire", "-o", str(tmp_path / "r.json")]) == 0
    (tmp_path / "r.json").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "r.json").read_bytes())
    assert main(["bake", str(job), "--quiet"]) == 0 and (tmp_path / "w.png").is_file()
    assert main(["wave", "--size", "8", "--quiet", "--transfer", str(tmp_path / "r.json"), "-o",
                 str(tmp_path / "c.png")]) == 0


def test_outputs_that_cannot_be_written_are_refused_before_any_work(tmp_path, capsys):
    """A name past the file system's limit, or a folder where a file (or one frame of a sequence) goes: exit 2
    in one line, before any work, on the command line and in a job file; the longest legal name is written."""
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / ("a" * 252 + ".npy"))]) == 2
    assert "-o: output name is 256 bytes, more than the 255" in capsys.readouterr().err
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / ("a" * 251 + ".npy"))]) == 0
    (tmp_path / "d.npy").mkdir()
    assert main(["neural", "--noise", "perlin", "--size", "16", "--steps", "1", "--quiet", "-o",
                 str(tmp_path / "d.npy")]) == 2
    assert "-o: output path is a folder, not a file" in capsys.readouterr().err
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "f_2.npy").mkdir()
    (tmp_path / "out" / "v.npy").mkdir()
    for output in ("out/v.npy", "out/f_#.npy"):
        job = wave_job(tmp_path, "j", output, 'frames = [1, 3]\n' if "#" in output else "", "speed = 1.0\n")
        for dry in ([], ["--dry-run"]):
            assert main(["bake", str(job), "--quiet", *dry]) == 2
            text = capsys.readouterr()
            assert "output path is a folder, not a file" in text.err + text.out, text
        assert sorted(os.listdir(tmp_path / "out")) == ["f_2.npy", "v.npy"]


@pytest.mark.parametrize("args", [
    ["wave", "--size", "8"],
    ["neural", "--noise", "perlin", "--size", "16", "--steps", "1"],
    ["solid", "--method", "procedural", "--exemplar", "{photo}", "--size", "8"],
    ["solid", "--method", "auto", "--exemplar", "{photo}", "--dim", "3", "--size", "8"],
    ["transfer", "fire"],
])
def test_an_output_folder_that_is_missing_or_read_only_is_refused_before_any_work(tmp_path, capsys, monkeypatch,
                                                                                 args):
    """The fit of a procedural solid takes seconds: the folder is checked first, not when the result is written."""
    from omninoise.backend.solid.procedural import fit

    def no_fit(*_a, **_k):
        raise AssertionError("the fit ran")

    monkeypatch.setattr(fit, "fit_procedural", no_fit)
    photo = tmp_path / "photo.png"
    write_unit_image(str(photo), np.random.default_rng(0).random((32, 32, 3)))
    argv = [x.format(photo=photo) for x in args] + (["-o"] if args[0] == "transfer" else ["--quiet", "-o"])
    ext = ".vdb" if "3" in args else ".json" if args[0] == "transfer" else ".png"
    assert main(argv + [str(tmp_path / "nowhere" / ("out" + ext))]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-o: output folder does not exist" in err[0], err
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if not os.access(locked, os.W_OK):              # root writes anywhere
            assert main(argv + [str(locked / ("out" + ext))]) == 2
            assert "-o: output folder is not writable" in capsys.readouterr().err
    finally:
        locked.chmod(0o700)
    assert sorted(os.listdir(tmp_path)) == ["locked", "photo.png"]


def test_an_output_written_over_a_file_the_command_reads_is_refused_and_the_file_kept(tmp_path, capsys):
    """`-o photo.png` beside `--exemplar photo.png` (or through a link to it), a job bake whose output is its own
    photo, the API's ``out`` equal to its exemplar, and a report written over the image: exit 2 in one line naming
    the flag, before any work; the photo is the same bytes after."""
    import omninoise
    from omninoise.backend.errors import SettingError

    photo, ramp = tmp_path / "photo.png", tmp_path / "ramp.json"
    write_unit_image(str(photo), np.random.default_rng(0).random((32, 32, 3)))
    assert main(["transfer", "fire", "-o", str(ramp)]) == 0
    os.symlink(photo, tmp_path / "link.png")
    before = photo.read_bytes(), ramp.read_bytes()
    for argv, said in (
            (["solid", "--exemplar", str(photo), "-o", str(photo)], "-o: photo.png is the file --exemplar reads"),
            (["solid", "--exemplar", str(tmp_path / "link.png"), "-o", str(photo)], "--exemplar reads"),
            (["solid", "--exemplar", str(photo), "-o", str(tmp_path / "link.png")], "--exemplar reads"),
            (["wave", "--example", str(photo), "-o", str(photo)], "-o: photo.png is the file --example reads"),
            (["wave", "--transfer", str(ramp), "-o", str(ramp)], "-o: ramp.json is the file --transfer reads"),
            (["neural", "--fit", str(photo), "-o", str(photo)], "-o: photo.png is the file --fit reads"),
            (["neural", "--fit", str(photo), "-o", str(tmp_path / "f.png"), "--report", str(tmp_path / "f.png")],
             "--report: f.png is also -o: write it to another file"),
            (["wave", "-o", str(tmp_path / "w.toml"), "--save-job", str(tmp_path / "w.toml")],
             "--save-job: w.toml is also -o"),
            (["neural", "--noise", "perlin", "-o", str(tmp_path / "n.png"), "--save-job", str(tmp_path / "n.png")],
             "--save-job: n.png is also -o"),
            (["solid", "--exemplar", "gravel_3d", "--dim", "3", "-o", str(tmp_path / "s.npy"), "--save-job",
              str(tmp_path / "s.npy")], "--save-job: s.npy is also -o: write it to another file"),
            (["solid", "--exemplar", str(photo), "--dim", "3", "-o", str(tmp_path / "s.npy"), "--save-job",
              str(photo)], "--save-job: photo.png is the file --exemplar reads")):
        assert main(argv + ["--quiet"]) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], (argv, err)
    job = tmp_path / "job.toml"
    job.write_text('[[bake]]\nname = "s"\noutput = "photo.png"\nresolution = [8, 8]\n[bake.source]\n'
                   'kind = "solid"\nexemplar = "photo.png"\n')
    assert main(["bake", str(job), "--quiet"]) == 2
    assert "bake 's': output: photo.png is the file source.exemplar reads: write to another file" in \
        capsys.readouterr().err
    with pytest.raises(SettingError, match="out: photo.png is the file exemplar reads"):
        omninoise.solid(str(photo), 8, out=str(photo))
    with pytest.raises(SettingError, match="out: ramp.json is the file transfer reads"):
        omninoise.wave(8, transfer=str(ramp), out=str(ramp))
    assert (photo.read_bytes(), ramp.read_bytes()) == before
    assert sorted(os.listdir(tmp_path)) == ["job.toml", "link.png", "photo.png", "ramp.json"]


def test_an_output_through_a_missing_folder_and_back_is_refused_before_any_work(tmp_path, capsys):
    """`sub/../x.png` names a folder only where sub is one (the system resolves it so): refused in one line, not
    an error of the final rename after the work."""
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "sub" / ".." / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-o: output folder does not exist: " in err[0] and err[0].endswith("sub/.."), err
    (tmp_path / "sub").mkdir()
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "sub" / ".." / "x.png")]) == 0
    assert (tmp_path / "x.png").is_file()


def test_a_bake_reading_what_an_earlier_bake_writes_says_so(tmp_path, capsys):
    """A job is checked before any bake runs: a bake whose photo an earlier bake writes is invalid until that file
    exists, and its message says which bake writes it; baked first with --only, the job then runs whole."""
    job = tmp_path / "job.toml"
    job.write_text('[[bake]]\nname = "mask"\noutput = "m.png"\nresolution = [64, 64]\n[bake.source]\nkind = "wave"\n'
                   '[[bake]]\nname = "like"\noutput = "l.png"\nresolution = [8, 8]\n[bake.source]\nkind = "wave"\n'
                   'example = "m.png"\n')
    assert main(["bake", str(job), "--dry-run"]) == 2
    out = capsys.readouterr().out
    assert "bake 'like': " in out and "(bake 'mask' writes it: a job is checked before any bake runs; bake that one " \
           "first, on its own or with --only)" in out, out
    assert main(["bake", str(job), "--only", "mask", "--quiet"]) == 0
    assert main(["bake", str(job), "--quiet"]) == 0 and (tmp_path / "l.png").is_file()


@pytest.mark.parametrize("args, said", [
    (["wave", "--size", "4"], "wave noise is written as .npy, .exr, .png, .vdb"),
    (["neural", "--noise", "perlin"], "a neural noise image is written as .png, .exr, .npy"),
    (["neural", "--keys", "k.toml", "--frames", "1", "2"], "a neural noise image is written as .png, .exr, .npy"),
    (["neural", "--fit", "photo.png"], "a neural noise image is written as .png, .exr, .npy"),
    (["solid", "--exemplar", "grass"], "a 2D result is written as .png, .exr, .npy"),
    (["solid", "--exemplar", "grass", "--dim", "3"], "a 3D result is written as .vdb, .npy"),
    (["transfer", "fire"], "a ramp is written as .json"),
])
def test_every_command_names_the_types_its_output_is_written_as(tmp_path, capsys, monkeypatch, args, said):
    """An output of a type the command does not write is refused in one line of one form on every command, saying
    what it writes; the keyframed and fitted neural noise's too (they each checked it in their own words)."""
    monkeypatch.chdir(tmp_path)
    out = "x_#.jpg" if "--keys" in args else "x.jpg"
    assert main(args + ["-o", out]) == 2
    assert capsys.readouterr().err.strip().endswith(f"-o: {said}, not '.jpg'")
    assert os.listdir(tmp_path) == []
    if "--keys" in args:        # an animation's name needs its '#' first
        return
    assert main(args + ["-o", "x"]) == 2
    assert capsys.readouterr().err.strip().endswith(f"-o: 'x' is a name without a type: {said}")
    hidden = said.split(" is written as ")[1].split(",")[0]           # '.png': a name with no type (was 'not .png')
    assert main(args + ["-o", hidden]) == 2
    assert capsys.readouterr().err.strip().endswith(f"-o: '{hidden}' is a name without a type: give the file a "
                                                    f"name before {hidden}")


def _fill_disk(monkeypatch, fail):
    """The folder's disk as full: ``fail(path)`` is how the writer fails (each writer's own words) and
    ``export.atomic.disk_full`` says so from then on."""
    from omninoise.export import atomic

    full = []
    monkeypatch.setattr(atomic, "disk_full", lambda folder: bool(full))

    def failing(path):
        full.append(path)
        fail(path)
    return failing


def _no_space_exr(path):
    raise RuntimeError(f'Failed to write pixel data to image file "{path}". No space left on device.')


def _no_space_npy(path):
    raise OSError("262144 requested and 51168 written")       # numpy's tofile: no errno


@pytest.mark.parametrize("ext", [".exr", ".npy", ".png"])
def test_a_full_disk_is_named_in_one_line_and_the_earlier_file_kept(tmp_path, capsys, monkeypatch, ext):
    """Each writer fails on a full disk in words of its own (OpenEXR's RuntimeError naming the temporary, numpy's
    OSError without an errno, an ENOSPC when the file is flushed): one line naming the output and the system's
    reason, exit 1, the earlier file as it was and no temporary left (an internal error said 'a bug: please report
    it')."""
    import errno as errnos

    out = tmp_path / f"w{ext}"
    assert main(["wave", "--size", "8", "--quiet", "-o", str(out)]) == 0
    before = out.read_bytes()
    if ext == ".exr":
        import OpenEXR

        real = OpenEXR.File.write
        fail = _fill_disk(monkeypatch, _no_space_exr)
        monkeypatch.setattr(OpenEXR.File, "write", lambda self, path: (real(self, path), fail(path)))
    elif ext == ".npy":
        fail = _fill_disk(monkeypatch, _no_space_npy)
        monkeypatch.setattr(np, "save", lambda fh, *a, **k: fail(fh))
    else:                   # a file system that says so when the file is flushed (NFS, delayed allocation)
        from omninoise.export import atomic

        def enospc(path):
            raise OSError(errnos.ENOSPC, os.strerror(errnos.ENOSPC))
        monkeypatch.setattr(atomic, "_fsync", enospc)
    assert main(["wave", "--size", "16", "--quiet", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err == f"omninoise wave: error: cannot write w{ext}: No space left on device", err
    assert out.read_bytes() == before and os.listdir(tmp_path) == [out.name]


def test_a_folder_that_takes_no_file_is_said_so_not_a_full_disk(tmp_path, capsys, monkeypatch):
    """A folder that refuses the new file where its permissions said yes (/proc, a pseudo file system of no blocks,
    even for root; a folder made read-only or removed while the work ran): one line naming the folder and the
    system's reason, exit 2, nothing written. /proc's 0 free blocks of 0 were read as a full disk ("No space left
    on device")."""
    import errno as errnos
    import tempfile

    from omninoise.export import atomic

    if sys.platform.startswith("linux") and os.path.isdir("/proc"):
        assert not atomic.disk_full("/proc")
        assert main(["wave", "--size", "8", "--quiet", "-o", "/proc/omninoise_w.png"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("omninoise wave: error: output folder takes no new file: /proc (") and "space" not in err
    monkeypatch.setattr(atomic, "disk_full", lambda folder: True)       # whatever the disk: not its reason

    def refused(**kw):
        raise PermissionError(errnos.EACCES, os.strerror(errnos.EACCES), os.path.join(kw["dir"], "tmpx"))
    monkeypatch.setattr(tempfile, "mkstemp", refused)
    assert main(["wave", "--size", "8", "--quiet", "-o", str(tmp_path / "w.png")]) == 2
    assert capsys.readouterr().err.strip() == (f"omninoise wave: error: output folder takes no new file: {tmp_path} "
                                               "(Permission denied)")
    assert os.listdir(tmp_path) == []


@needs_openvdb
def test_a_volume_that_reads_back_cut_is_not_written(tmp_path, capsys, monkeypatch):
    """OpenVDB writes a cut file on a full disk and says nothing: the file is read back before it takes the
    output's name, and a cut one is refused naming the output (the reason the disk's, where it is full)."""
    from omninoise.export import atomic, vdb

    module = vdb.openvdb_module()

    class Cutting:
        def __getattr__(self, name):
            return getattr(module, name)

        def write(self, path, **kw):
            module.write(path, **kw)
            with open(path, "r+b") as fh:
                fh.truncate(os.path.getsize(path) * 2 // 3)

    monkeypatch.setattr(vdb, "openvdb_module", lambda: Cutting())
    out = tmp_path / "v.vdb"
    for full, reason in ((False, "the file read back is not the volume written (a failing disk or a full quota?)"),
                         (True, "No space left on device")):
        monkeypatch.setattr(atomic, "disk_full", lambda folder: full)
        assert main(["wave", "--size", "24", "--dim", "3", "--quiet", "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip()
        assert err == f"omninoise wave: error: cannot write v.vdb: {reason}", err
        assert os.listdir(tmp_path) == []


@pytest.fixture
def small_disk(tmp_path):
    """A 256 KiB file system of its own (tmpfs; needs root on Linux, else the test skips)."""
    folder = tmp_path / "small"
    folder.mkdir()
    if not sys.platform.startswith("linux") or os.geteuid() != 0 or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(folder)], capture_output=True).returncode:
        pytest.skip("mounting a small tmpfs needs root on Linux")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=True)


@pytest.mark.parametrize("args, ext", [(["--size", "512"], ".exr"), (["--size", "512"], ".npy"),
                                       (["--size", "1024"], ".png"),
                                       pytest.param(["--size", "96", "--dim", "3"], ".vdb", marks=needs_openvdb)])
def test_a_really_full_disk_is_named_and_leaves_nothing(small_disk, capsys, args, ext):
    """On a disk too small for the result, every writer's failure is one line (OpenVDB wrote a cut file and exit
    status 0; OpenEXR, numpy and Python ended in an internal error) and nothing is left there."""
    rc = main(["wave", *args, "--quiet", "-o", str(small_disk / f"w{ext}")])
    err = capsys.readouterr().err.strip()
    assert (rc, err) == (1, f"omninoise wave: error: cannot write w{ext}: No space left on device")
    assert os.listdir(small_disk) == []
