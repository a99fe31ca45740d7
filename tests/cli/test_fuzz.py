"""Property-based fuzzing of every entry point: CLI arguments and job-file documents.

Hypothesis builds argument lists from each subcommand's real flags with hostile values (NaN, infinities,
negative and huge numbers, text where a number belongs, empty strings, paths that are folders or do not
exist, broken image files from ``tests/data/broken``) and job files with unknown keys, wrong types and bad
numbers. Every run must end in one of two ways:

- exit 0 and the output file exists and is not empty, or
- exit 2 with a one-line error (the last line of stderr, starting ``omninoise``) and no traceback;

never a traceback, a signal or a hang (each example is stopped after ``LIMIT_S`` seconds). A sweep over the
settings schema (``backend/settings_schema.py``) gives every key of a job file the values its type refuses
(wrong kinds, NaN and infinities, numbers past its range, lists past their counts) and expects exit 2 naming
that key. Sizes are drawn
from tiny valid values and absurd ones, never from the slow middle, so a valid run takes milliseconds and the
whole file stays within about a minute on 2 cores. ``derandomize`` keeps CI reproducible: the same examples
every run (set ``OMNINOISE_FUZZ_SEED`` to explore others locally).
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import os
import signal

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

from omninoise.cli.main import main  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BROKEN = os.path.join(ROOT, "tests", "data", "broken")
ODD = os.path.join(ROOT, "tests", "data", "odd")
PHOTO = os.path.join(ROOT, "data", "photos", "val", "rock__cliff_greek.jpg")
LIMIT_S = 30
_seed = os.environ.get("OMNINOISE_FUZZ_SEED")
FUZZ = settings(deadline=None, database=None, derandomize=_seed is None, print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.filter_too_much])
if _seed is not None:
    FUZZ = settings(FUZZ, derandomize=False)

# about half of every pool is valid, so that runs also reach the writers, not only the first check
NUMBERS = ["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-320", "abc", "", "99999999999999999999", "0x10",
           "1", "2", "0.5", "3", "4", "1.5", "6", "0.25", "2.5", "5", "8", "-0"]
SMALL_SIZES = ["0", "-4", "7", "100000000", "nan", "x", "8", "16", "8", "16", "24", "32", "8", "16"]


def broken_files() -> list:
    return sorted(os.path.join(BROKEN, f) for f in os.listdir(BROKEN))


def num():
    return st.sampled_from(NUMBERS)


def flag(name: str, values):
    return st.tuples(st.just(name), values)


def run(argv: list, out: str | None) -> None:
    """Run the CLI in-process and check the contract above."""
    err = io.StringIO()

    def timeout(*_):
        raise TimeoutError(f"omninoise {' '.join(argv)} ran past {LIMIT_S} s")

    old = signal.signal(signal.SIGALRM, timeout)
    signal.alarm(LIMIT_S)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                rc = main(argv)
            except SystemExit as exc:  # argparse: one error line, exit 2
                rc = exc.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    text = err.getvalue()
    assert "Traceback" not in text, (argv, text)
    if rc == 0:
        if out is not None:
            assert os.path.isfile(out) and os.path.getsize(out) > 0, (argv, "exit 0 without an output")
        return
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    assert rc == 2, (argv, rc, text)
    assert lines and lines[-1].startswith("omninoise") and "error" in lines[-1], (argv, text)


def output_path(tmp: str, ext: str) -> str:
    if ext == "folder":
        os.makedirs(os.path.join(tmp, "folder.png"), exist_ok=True)
        return os.path.join(tmp, "folder.png")
    if ext == "missing":
        return os.path.join(tmp, "no", "such", "dir", "x.png")
    return os.path.join(tmp, "out" + ext)


def _argv(cmd: str, flags: list) -> list:
    argv = [cmd]
    for name, value in flags:
        argv += [name] if value is None else [name, *value] if isinstance(value, list) else [name, value]
    return argv


@contextlib.contextmanager
def _fresh(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    yield str(d)


WAVE_FLAGS = st.lists(st.one_of(
    flag("--dim", st.sampled_from(["2", "3", "4", "5", "x"])), flag("--extent", num()), flag("--time", num()),
    flag("--speed", num()), flag("--fmin", num()), flag("--fmax", num()), flag("--exponent", num()),
    flag("--directions", st.sampled_from(["1", "4", "0", "-2", "100000000", "x"])),
    flag("--spectrum", st.sampled_from(["gaussian", "fractal", "band", "bogus"])),
    flag("--waveform", st.sampled_from(["gaussian", "sine", "custom", "bogus"])),
    flag("--profile", st.sampled_from(broken_files() + ["/no/such/profile.npy"])),
    flag("--cellular", st.sampled_from(["none", "stit", "bogus"])), flag("--cell-size", num()),
    flag("--stit-probability", num()), flag("--stit-depth", st.sampled_from(["0", "3", "-1", "64", "x"])),
    flag("--spread", num()), flag("--table-size", st.sampled_from(["16", "15", "0", "1048577", "x"])),
    flag("--period", num()), flag("--seed", st.sampled_from(["0", "-1", "4294967296", "x"])),
    flag("--example", st.sampled_from(broken_files() + ["/no/such.png"])), flag("--example-extent", num()),
    flag("--sectors", st.sampled_from(["0", "8", "-1", "100000"])),
    flag("--transfer", st.sampled_from(["clouds", "fire", "bogus", "/no/ramp.json"])),
    flag("--half", st.none()), flag("--output", st.sampled_from(["real", "modulus", "bogus"]))), max_size=5)


@settings(FUZZ, max_examples=70)
@given(flags=WAVE_FLAGS, size=st.sampled_from(SMALL_SIZES),
       ext=st.sampled_from([".npy", ".exr", ".png", ".vdb", ".txt", "folder", "missing"]))
def test_fuzz_wave(tmp_path_factory, flags, size, ext):
    with _fresh(tmp_path_factory) as tmp:
        out = output_path(tmp, ext)
        run(_argv("wave", flags) + ["--size", size, "--quiet", "-o", out], out)


@settings(FUZZ, max_examples=40)
@given(flags=WAVE_FLAGS, size=st.sampled_from(SMALL_SIZES), ext=st.sampled_from([".npy", ".exr", ".png", ".vdb"]),
       job=st.sampled_from(["job.toml", "job.json", "no/such/job.toml", "folder.toml", ""]))
def test_fuzz_wave_save_job(tmp_path_factory, flags, size, ext, job):
    """``wave --save-job``: exit 0 with a job that ``bake --dry-run`` takes, or one line, exit 2."""
    with _fresh(tmp_path_factory) as tmp:
        os.makedirs(os.path.join(tmp, "folder.toml"))
        path = os.path.join(tmp, job)
        run(_argv("wave", flags) + ["--size", size, "--quiet", "-o", output_path(tmp, ext), "--save-job", path],
            path)
        if os.path.isfile(path):
            run(["bake", path, "--quiet", "--dry-run"], None)
            assert not os.path.exists(output_path(tmp, ext)), "--save-job baked the file too"


NEURAL_FLAGS = st.lists(st.one_of(
    flag("--noise", st.sampled_from(["perlin", "spots", "bogus", ""])),
    flag("--param", st.sampled_from(["scale=8", "scale=nan", "scale=1e9", "bogus=1", "scale", "=3"])),
    flag("--steps", st.sampled_from(["1", "2", "0", "-1", "1001", "x"])),
    flag("--sampler", st.sampled_from(["ddim", "dpmpp_2m", "heun", "bogus"])),
    flag("--spacing", st.sampled_from(["uniform", "logsnr", "bogus"])), flag("--eta", num()),
    flag("--tile", st.sampled_from(["32", "8", "0", "-8", "x"])), flag("--threads", st.sampled_from(["1", "-1", "x"])),
    flag("--seed", st.sampled_from(["0", "-1", "4294967296", "x"])), flag("--tileable", st.none()),
    flag("--blend", st.sampled_from(broken_files() + ["/no/mask.png"])), flag("--noise2", st.sampled_from(["cells_f1", "x"])),
    flag("--width", num()), flag("--sharpness", num()),
    flag("--map", st.sampled_from(broken_files())), flag("--model", st.sampled_from(["/no/model", BROKEN])),
    flag("--gradient", st.sampled_from([["perlin", "spots"], ["perlin", "bogus"], ["perlin:scale=nan", "spots"],
                                        ["perlin"]]))),
    max_size=2)


@settings(FUZZ, max_examples=30)
@given(flags=NEURAL_FLAGS, size=st.sampled_from(["8", "16", "0", "-8", "7", "100000000", "x"]),
       ext=st.sampled_from([".npy", ".exr", ".png", ".txt", "folder", "missing"]))
@pytest.mark.long
def test_fuzz_neural(tmp_path_factory, flags, size, ext):
    with _fresh(tmp_path_factory) as tmp:
        out = output_path(tmp, ext)
        argv = _argv("neural", flags)
        if "--noise" not in argv and "--gradient" not in argv:
            argv += ["--noise", "perlin"]
        if "--steps" not in argv:
            argv += ["--steps", "2"]
        run(argv + ["--size", size, "--quiet", "-o", out], out)


@settings(FUZZ, max_examples=30)
@given(flags=NEURAL_FLAGS, ext=st.sampled_from([".npy", ".exr", ".png"]),
       job=st.sampled_from(["job.toml", "job.json", "no/such/job.toml", "folder.toml", ""]))
@pytest.mark.long
def test_fuzz_neural_save_job(tmp_path_factory, flags, ext, job):
    """``neural --save-job``: exit 0 with a job that ``bake --dry-run`` takes, or one line, exit 2."""
    with _fresh(tmp_path_factory) as tmp:
        os.makedirs(os.path.join(tmp, "folder.toml"))
        path = os.path.join(tmp, job)
        argv = _argv("neural", flags)
        if "--noise" not in argv and "--gradient" not in argv:
            argv += ["--noise", "perlin"]
        if "--steps" not in argv:
            argv += ["--steps", "2"]
        run(argv + ["--size", "16", "--quiet", "-o", output_path(tmp, ext), "--save-job", path], path)
        if os.path.isfile(path):
            run(["bake", path, "--quiet", "--dry-run"], None)
            assert not os.path.exists(output_path(tmp, ext)), "--save-job drew the image too"


SOLID_FLAGS = st.lists(st.one_of(
    flag("--exemplar", st.sampled_from(["gravel_3d", "grass", "bogus", ""] + broken_files())),
    flag("--to", st.sampled_from(["rock", "bogus"])), flag("--mix", num()), flag("--scale", num()),
    flag("--dim", st.sampled_from(["2", "3", "4"])), flag("--seed", st.sampled_from(["0", "-1", "x"])),
    flag("--refine", st.sampled_from(["0", "1", "-1", "x"])), flag("--model", st.sampled_from(["/no/model", BROKEN]))),
    max_size=2)


@settings(FUZZ, max_examples=30)
@given(flags=SOLID_FLAGS, size=st.sampled_from(["8", "16", "0", "-8", "100000000", "x"]),
       ext=st.sampled_from([".npy", ".exr", ".png", ".vdb", ".txt", "folder", "missing"]))
def test_fuzz_solid(tmp_path_factory, flags, size, ext):
    with _fresh(tmp_path_factory) as tmp:
        out = output_path(tmp, ext)
        argv = _argv("solid", flags)
        if "--exemplar" not in argv:
            argv += ["--exemplar", "gravel_3d"]
        run(argv + ["--size", size, "--quiet", "-o", out], out)


@settings(FUZZ, max_examples=60)
@given(flags=SOLID_FLAGS, method=st.sampled_from([[], ["--method", "spectral"], ["--method", "synthesis"],
                                                  ["--method", "procedural"], ["--method", "auto"]]),
       dim=st.sampled_from([[], ["--dim", "3"], ["--dim", "3"]]),
       ext=st.sampled_from([".npy", ".vdb", ".npy", ".vdb", ".exr", ".png", ".json"]),
       job=st.sampled_from(["job.toml", "job.toml", "job.toml", "job.json", "no/such/job.toml", "folder.toml", ""]))
def test_fuzz_solid_save_job(tmp_path_factory, flags, method, dim, ext, job):
    """``solid --save-job``: exit 0 with a job that ``bake --dry-run`` takes, or one line, exit 2; never a drawing."""
    with _fresh(tmp_path_factory) as tmp:
        os.makedirs(os.path.join(tmp, "folder.toml"))
        path, out = os.path.join(tmp, job), output_path(tmp, ext)
        argv = _argv("solid", flags) + method + (dim if "--dim" not in _argv("solid", flags) else [])
        if "--exemplar" not in argv:
            argv += ["--exemplar", "gravel_3d" if not method else PHOTO]
        run(argv + ["--size", "8", "--quiet", "-o", out, "--save-job", path], path)
        if os.path.isfile(path):
            run(["bake", path, "--quiet", "--dry-run"], None)
            assert not os.path.exists(out), "--save-job drew the texture too"


@settings(FUZZ, max_examples=20)
@given(noise=st.sampled_from(["perlin", "damascus", "cells_f1", "bogus"]), size=st.sampled_from(SMALL_SIZES),
       param=st.sampled_from([[], [], ["--param", "scale=4"], ["--param", "scale=nan"], ["--param", "x=1"]]),
       ext=st.sampled_from([".npy", ".exr", ".png", ".npy", ".png", ".txt", "folder", "missing"]))
def test_fuzz_zoo(tmp_path_factory, noise, size, param, ext):
    with _fresh(tmp_path_factory) as tmp:
        out = output_path(tmp, ext)
        run(["zoo", "--noise", noise, "--size", size, "-o", out] + param, out)


# -- job files ------------------------------------------------------------------------------------------

def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


SCALARS = st.sampled_from([0, 1, -1, 2, 3, 0.5, math.nan, math.inf, -math.inf, 1e308, 10 ** 12, True, False,
                           "", "x", "nan", "clouds"])
VALID_SOURCES = st.sampled_from([{"dim": 2, "directions": 2}, {"dim": 3, "directions": 2, "seed": 3},
                                 {"kind": "neural", "noise": "perlin", "steps": 1},
                                 {"kind": "solid", "model": "gravel_3d"}, {"dim": 4, "directions": 2}])
HOSTILE_SOURCES = st.fixed_dictionaries({"kind": st.sampled_from(["wave", "neural", "solid", "bogus", 3])}, optional={
    "dim": st.sampled_from([2, 3, 4, 5, "x", math.nan]), "directions": st.sampled_from([2, 0, -1, 10 ** 8, "x"]),
    "seed": st.sampled_from([0, -1, 2 ** 40, "x"]), "speed": SCALARS, "spectrum": st.sampled_from(
        [{"kind": "fractal", "fmin": 1, "fmax": 4}, {"kind": "bogus"}, {"fmin": math.nan}, "x"]),
    "noise": st.sampled_from(["perlin", "bogus", 3]), "steps": st.sampled_from([1, 2, 0, -1, 10 ** 6, "x"]),
    "params": st.sampled_from([{"scale": 8}, {"scale": math.nan}, {"bogus": 1}, "x"]),
    "model": st.sampled_from(["gravel_3d", "/no/model", 3]), "scale": SCALARS, "density": SCALARS,
    "blend": st.sampled_from(["missing.png", "broken.png"]), "bogus": SCALARS,
    "gradient": st.sampled_from([["perlin", "spots"], ["perlin"], ["perlin", "perlin:scale=x"], "perlin"]),
    "corners": st.sampled_from([["perlin"] * 4, ["perlin"] * 3, ["perlin:scale=x"] * 4, [{"noise": 3}] * 4, [3] * 4,
                                "perlin", [{"noise": "perlin", "params": {"scale": math.nan}}] * 4]),
    "map": st.sampled_from(["missing.png", "broken.png", 3, ""]),
    "regions": st.sampled_from([{"#ff0000": "perlin"}, {"#ff00": "perlin"}, {"300": "perlin"}, {"0": 3}, {}, "x"])})
VALID = {"output": st.sampled_from(["out/a.npy", "out/a.exr", "out/a.png", "out/a.vdb", "out/b_####.npy"]),
         "resolution": st.sampled_from([[8, 8], [16, 8], [8, 8, 8]]), "source": VALID_SOURCES}
HOSTILE = {
    "name": st.sampled_from(["a", "b", "", 3]), "output": st.sampled_from(
        ["../../x.npy", "/abs/x.npy", "out/a.txt", "", 3, "out"]),
    "resolution": st.sampled_from([[0, 8], [-1, 2], [10 ** 9, 2], ["a", 8], [8], [8, 8, 8, 8], [8.5, 8], 3, "8x8"]),
    "bounds": st.sampled_from(
        [[[0, 0, 0], [1, 1, 1]], [[0, 0, 0], [0, 0, 0]], [[1, 1, 1], [0, 0, 0]], [[0, 0], [1, 1]], "x",
         [[math.nan, 0, 0], [1, 1, 1]], [[0, 0, 0], [math.inf, 1, 1]]]),
    "transfer": st.sampled_from(["clouds", "bogus", {"preset": "fire"}, {"bogus": 1}, 3]),
    "frames": st.sampled_from([[1, 2], [2, 1], [1, 10 ** 9], ["a", "b"], [1.5, 2], 3]),
    "time": SCALARS, "time_step": SCALARS, "half": SCALARS, "source": st.one_of(HOSTILE_SOURCES, SCALARS),
    "bogus": SCALARS}


@st.composite
def bakes(draw):
    """A valid bake, then zero to two keys replaced or added from the hostile pools."""
    d = {k: draw(v) for k, v in VALID.items()}
    for key in draw(st.lists(st.sampled_from(sorted(HOSTILE)), max_size=2, unique=True)):
        d[key] = draw(HOSTILE[key])
    return d


JOBS = st.fixed_dictionaries({"bake": st.one_of(st.lists(bakes(), min_size=1, max_size=2),
                                                st.sampled_from([[], 0, "x"]))}, optional={
    "output_root": st.sampled_from([".", "out", "..", "", 3]),
    "defaults": st.one_of(st.just({}), st.just({"bounds": [[-1, -1, -1], [1, 1, 1]]}), st.just({"half": True}),
                          st.fixed_dictionaries({}, optional=HOSTILE), SCALARS)})


def job_text(doc: dict) -> str:
    lines = [f"{k} = {toml_value(v)}" for k, v in doc.items() if k != "bake"]
    bakes = doc["bake"]
    if not isinstance(bakes, list):
        return "\n".join(lines + [f"bake = {toml_value(bakes)}"]) + "\n"
    for b in bakes:
        lines.append("[[bake]]")
        lines += [f"{k} = {toml_value(v)}" for k, v in b.items()]
    return "\n".join(lines) + "\n"


@settings(FUZZ, max_examples=60)
@given(doc=JOBS, dry=st.booleans())
def test_fuzz_job_files(tmp_path_factory, doc, dry):
    with _fresh(tmp_path_factory) as tmp:
        with open(os.path.join(tmp, "broken.png"), "wb") as fh:
            fh.write(b"\x89PNG\r\n\x1a\n truncated")
        job = os.path.join(tmp, "job.toml")
        with open(job, "w", encoding="utf-8") as fh:
            fh.write(job_text(doc))
        run(["bake", job, "--quiet"] + (["--dry-run"] if dry else []), None)


def test_the_broken_file_corpus_is_refused_by_every_image_input(tmp_path):
    """Each file of tests/data/broken given to each image input: exit 2, one line naming the file."""
    out = str(tmp_path / "o.png")
    for path in broken_files():
        for argv in (["wave", "--size", "8", "--example", path], ["neural", "--noise", "perlin", "--size", "8",
                     "--steps", "1", "--blend", path], ["neural", "--size", "8", "--steps", "1", "--map", path, "--region", "0=perlin"],
                     ["solid", "--exemplar", path, "--size", "8"], ["wave", "--size", "8", "--waveform", "custom",
                                                                    "--profile", path]):
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                rc = main(argv + ["--quiet", "-o", out] if argv[0] != "zoo" else argv + ["-o", out])
            lines = err.getvalue().strip().splitlines()
            assert rc == 2 and len(lines) == 1 and os.path.basename(path) in lines[0], (argv, err.getvalue())
            assert not os.path.exists(out)


ODD_INPUTS = {
    "wave example": ["wave", "--size", "8", "--example"],
    "neural blend": ["neural", "--noise", "perlin", "--noise2", "cells_f1", "--size", "8", "--steps", "1", "--blend"],
    "neural map": ["neural", "--size", "8", "--steps", "1", "--region", "0=perlin", "--map"],
    **{f"solid {m}": ["solid", "--method", m, "--size", "8", "--exemplar"]
       for m in ("neural", "spectral", "synthesis", "procedural", "auto")},
}


@pytest.mark.parametrize("name", sorted(f for f in os.listdir(ODD) if f.endswith(".png")))
def test_odd_images_are_drawn_or_refused_in_one_line_by_every_image_input(tmp_path, name):
    """Each valid but unusual image of tests/data/odd (a line, a column two px wide, one pixel, a cut-out, one
    grey) given to each image input: a finite result, or exit 2 with one line; never an internal error."""
    for argv in ODD_INPUTS.values():
        out = str(tmp_path / "o.npy")
        run(argv + [os.path.join(ODD, name), "--quiet", "-o", out], out)
        if os.path.exists(out):
            import numpy as np

            assert np.isfinite(np.load(out)).all(), argv
            os.remove(out)


def test_a_strip_photo_is_drawn_or_refused_in_one_line(tmp_path):
    """A 20 x 20000 px strip: the neural texture reads its central window (its periodic part and Gaussian rest are
    read at 256 px a side, where the whole strip would be no pixels wide); the spectral solid refuses it."""
    import numpy as np
    from PIL import Image

    strip = str(tmp_path / "strip.png")
    Image.fromarray((np.random.default_rng(0).random((20000, 20, 3)) * 255).astype(np.uint8)).save(strip)
    out = str(tmp_path / "o.png")
    assert main(["solid", "--exemplar", strip, "--size", "8", "--quiet", "-o", out]) == 0 and os.path.isfile(out)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["solid", "--exemplar", strip, "--method", "spectral", "--size", "8", "--quiet", "-o", str(tmp_path / "s.png")])
    assert rc == 2 and err.getvalue().count("\n") == 1 and "20 x 20000 px" in err.getvalue()


# -- every key of the settings schema, each with the values its type refuses ---------------------------------

def wrong_values(t) -> list:
    """Values of the wrong kind, non-finite, past the range or past the count of schema type ``t``."""
    from omninoise.backend import schema as S

    if isinstance(t, S.AnyOf):
        return [5 if not any(isinstance(o, (S.Int, S.Float)) for o in t.options) else None, True]
    if isinstance(t, S.Int):
        return [1.5, True, "7", t.lo - 1, t.hi + 1, 10 ** 30]
    if isinstance(t, S.Float):
        return [math.nan, math.inf, "1", True] + ([t.hi * 10 + 1] if math.isfinite(t.hi) else []) + \
            ([t.lo - 1 if t.lo <= 0 else t.lo / 10] if math.isfinite(t.lo) else [])
    if isinstance(t, S.Bool):
        return ["false", 1, 0]
    if isinstance(t, S.Text):
        return [3, "", ["x"]]
    if isinstance(t, S.Choice):
        return ["bogus", [t.options[0]]] + ([str(t.options[0])] if isinstance(t.options[0], int) else [3])
    if isinstance(t, S.ListOf):
        return [5, "x"] + ([[]] if t.lo > 0 else [])
    if isinstance(t, S.Items):
        return [5, []]
    if isinstance(t, (S.Table, S.MapOf)):
        return [5, "x"]
    raise TypeError(t)


def schema_cases() -> list:
    """(id, bake table) for every key of the [[bake]] table and of each source kind's table."""
    from omninoise.backend.settings_schema import BAKE, SOURCE_TABLES

    base = {"name": "b", "output": "out/b.npy", "resolution": [8, 8]}
    sources = {"wave": {"kind": "wave"}, "neural": {"kind": "neural", "noise": "perlin", "steps": 1},
               "solid": {"kind": "solid", "model": "gravel_3d"}}
    cases = []
    for key, f in BAKE.fields.items():
        if key in ("name", "source"):
            continue
        for v in filter(lambda v: v is not None, wrong_values(f.type)):
            cases.append((f"{key}={v!r}", key, dict(base, source=sources["wave"], **{key: v})))
    for kind, table in SOURCE_TABLES.items():
        for key, f in table.fields.items():
            if key == "kind":
                continue
            for v in filter(lambda v: v is not None, wrong_values(f.type)):
                cases.append((f"{kind}.{key}={v!r}", f"source.{key}", dict(base, source=dict(sources[kind], **{key: v}))))
    return cases


SCHEMA_CASES = schema_cases()


def test_the_schema_sweep_covers_every_key():
    from omninoise.backend.settings_schema import BAKE, SOURCE_TABLES

    named = {c[1] for c in SCHEMA_CASES}
    assert {k for k in BAKE.fields if k not in ("name", "source")} <= named
    for table in SOURCE_TABLES.values():
        assert {f"source.{k}" for k in table.fields if k != "kind"} <= named
    assert len(SCHEMA_CASES) > 250


@pytest.mark.parametrize("label, key, bake", SCHEMA_CASES, ids=[c[0][:60] for c in SCHEMA_CASES])
def test_every_key_refuses_wrong_types_non_finite_numbers_and_values_past_its_caps(tmp_path, label, key, bake):
    """Exit 2 before any work, one line naming the bake and the key (``bake 'b': source.seed: ...``)."""
    job = tmp_path / "job.toml"
    job.write_text(job_text({"bake": [bake]}))
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["bake", str(job), "--quiet"])
    lines = err.getvalue().strip().splitlines()
    assert rc == 2 and len(lines) == 1, (label, rc, lines)
    assert lines[0].startswith(f"omninoise bake: error: bake 'b': {key}"), (label, lines)
    assert not (tmp_path / "out").exists()
