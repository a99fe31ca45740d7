"""The settings schema: exact types for every job-file key, refused before any work, named by table and key."""
from __future__ import annotations

import doctest
import math
import os
import subprocess
import sys

import pytest

from omninoise.backend import schema
from omninoise.backend.errors import SettingError
from omninoise.backend.jobs import load_job
from omninoise.backend.settings_schema import BAKE, SOURCE_TABLES
from omninoise.backend.wavenoise.settings import WaveSettings
from omninoise.cli.main import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

BASE = {"bake": 'name = "b"\noutput = "out/b.npy"\nresolution = [8, 8]\n', "source": 'kind = "wave"\ndim = 2\n'}


def job(tmp_path, bake: str = "", source: str = "", kind: str | None = None) -> str:
    src = BASE["source"] if kind is None else f'kind = "{kind}"\n'
    text = "[[bake]]\n" + BASE["bake"] + bake + "[bake.source]\n" + src + source
    (tmp_path / "job.toml").write_text(text)
    return str(tmp_path / "job.toml")


def refused(tmp_path, capsys, path: str) -> str:
    """Exit 2 with one line, nothing written, and the same line listed by --dry-run; the line."""
    assert main(["bake", path, "--quiet"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omninoise bake: error: bake 'b': "), lines
    assert main(["bake", path, "--dry-run"]) == 2
    assert lines[0].removeprefix("omninoise bake: error: ") in capsys.readouterr().out
    assert not (tmp_path / "out").exists()
    return lines[0]


# every coercion the schema refuses: (bake lines, source lines, kind, the message's end)
COERCIONS = [
    ("", 'tileable = "false"\nnoise = "perlin"\n', "neural", "source.tileable: expected true or false, got 'false'"),
    ("", "seed = 1.5\n", None, "source.seed: expected a whole number, got 1.5"),
    ("", 'seed = "7"\n', None, "source.seed: expected a whole number, got '7'"),
    ("", "directions = 2.7\n", None, "source.directions: expected a whole number, got 2.7"),
    ("", "directions = true\n", None, "source.directions: expected a whole number, got True"),
    ("", 'dim = "3"\n', "wave", "source.dim: expected one of 2, 3, 4 (did you mean 3?), got '3'"),
    ("", 'noise = "perlin"\nparams = {scale = "8"}\n', "neural", "source.params.scale: expected a number, got '8'"),
    ("", 'noise = "perlin"\nparams = 5\n', "neural", "source.params: expected a table from parameter name"),
    ("", 'noise = "perlin"\nsteps = 2.0\n', "neural", "source.steps: expected a whole number, got 2.0"),
    ("", "refine = -1\n", "solid", "source.refine: must lie in [0, 10000], got -1"),
    ("", "scale = inf\n", "solid", "source.scale: must be a finite number, got inf"),
    ("", "speed = nan\n", None, "source.speed: must be a finite number, got nan"),
    ("", "sped = 1.0\n", None, "source.sped: unknown key (did you mean speed?)"),
    ("", "spectrum = {kind = \"fractal\", fmax = 1e400}\n", None, "source.spectrum.fmax: must be a finite number"),
    ("", "lobes = [[[1, 0], inf]]\nanisotropy = \"lobes\"\n", None, "source.lobes[0][1]: must be a finite number"),
    ("", "cellular = \"polytope\"\ncell_size = 1e-300\n", None, "source.cell_size: must lie in [1e-06, 10000000]"),
    ("transfer = {preset = \"fire\", density_scale = inf}\n", "", None,
     "transfer.density_scale: must be a finite number, got inf"),
    ("transfer = {stops = [[0, [1, 0, 0, nan]]]}\n", "", None, "transfer.stops[0][1][3]: must be a finite number"),
    ("transfer = {stops = 5}\n", "", None, "transfer.stops: expected a list of 1 to 4096 items"),
    ("resolution = [true, 16]\n", "", None, "resolution[0]: expected a whole number, got True"),
    ("resolution = [\"a\", 16]\n", "", None, "resolution[0]: expected a whole number, got 'a'"),
    ("resolution = [nan, 16]\n", "", None, "resolution[0]: expected a whole number, got nan"),
    ("resolution = [8, 8, 8, 8]\n", "", None, "resolution: expected 2 to 3 items, got 4"),
    ("bounds = [[0, 0], [1, 1]]\n", "", None, "bounds[0]: expected 3 items, got 2: [0, 0]"),
    ("bounds = [[0, 0, 0], [1e38, 1, 1]]\n", "", None, "bounds[1][0]: must lie in [-10000000, 10000000]"),
    ("frames = [1, 2.5]\n", "", None, "frames[1]: expected a whole number, got 2.5"),
    ("half = 1\n", "", None, "half: expected true or false, got 1"),
    ("time = 1e308\n", "", None, "time: must lie in [-1000000000, 1000000000], got 1e+308"),
    ("colour = 1\n", "", None, "colour: unknown key; known: name, output"),
    ("outptu = \"x.npy\"\n", "", None, "outptu: unknown key (did you mean output?)"),
]


@pytest.mark.parametrize("bake, source, kind, said", COERCIONS, ids=[c[3].split(":")[0] for c in COERCIONS])
def test_coercions_are_refused_before_any_work(tmp_path, capsys, bake, source, kind, said):
    text = BASE["bake"].replace('resolution = [8, 8]\n', '') if bake.startswith("resolution") else BASE["bake"]
    src = BASE["source"] if kind is None else f'kind = "{kind}"\n'
    if kind == "solid":
        src += 'model = "gravel_3d"\n'
    (tmp_path / "job.toml").write_text("[[bake]]\n" + text + bake + "[bake.source]\n" + src + source)
    line = refused(tmp_path, capsys, str(tmp_path / "job.toml"))
    assert said in line, line


def test_kind_of_the_wrong_type_and_a_kind_misspelt(tmp_path, capsys):
    assert "source.kind: unknown source ['wave']" in refused(tmp_path, capsys, _kind(tmp_path, '["wave"]'))
    assert "(did you mean neural?)" in refused(tmp_path, capsys, _kind(tmp_path, '"nueral"'))


def _kind(tmp_path, value: str) -> str:
    (tmp_path / "job.toml").write_text("[[bake]]\n" + BASE["bake"] + f"[bake.source]\nkind = {value}\n")
    return str(tmp_path / "job.toml")


def test_whole_file_problems_are_named_by_their_table(tmp_path, capsys):
    for text, said in (("outptu_root = 'x'\n[[bake]]\n" + BASE["bake"] + "[bake.source]\n",
                        "outptu_root: unknown key (did you mean output_root?)"),
                       ("output_root = 3\n[[bake]]\n" + BASE["bake"] + "[bake.source]\n",
                        "output_root: expected a file path (relative to the job file) (a non-empty string), got 3"),
                       ("[defaults]\nbounds = 3\nresoltion = [8, 8]\n[[bake]]\n" + BASE["bake"] + "[bake.source]\n",
                        "defaults.resoltion: unknown key (did you mean resolution?)"),
                       ("bake = 5\n", "bake: expected a list of 1 to 10000 items")):
        (tmp_path / "job.toml").write_text(text)
        assert main(["bake", str(tmp_path / "job.toml"), "--quiet"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], err


def test_a_value_quoted_in_a_message_is_cut():
    with pytest.raises(SettingError) as e:
        schema.Int(0, 1).check("x" * 10_000_000, "seed")
    assert len(str(e.value)) < 120 and str(e.value).endswith("...")


def test_every_key_has_a_type_and_a_line_of_what_it_does():
    for table in (BAKE, *SOURCE_TABLES.values()):
        for key, f in table.fields.items():
            assert isinstance(f.type, schema.Type) and f.doc and f.type.describe(), key


def test_the_wave_settings_are_checked_whichever_front_end_built_them():
    """The Python API (and the panels, which build WaveSettings) meet the same table as job files."""
    for kw, said in ((dict(seed=1.5), "seed: expected a whole number"), (dict(dim=True), "dim: expected one of"),
                     (dict(directions=0), "directions: must lie in [1, 4096]"), (dict(speed=math.inf), "speed"),
                     (dict(lobes=(((1.0, 0.0), math.nan),), anisotropy="lobes"), "lobes[0][1]"),
                     (dict(output="Real"), "(did you mean real?)")):
        with pytest.raises(SettingError, match=None) as e:
            WaveSettings(**kw).validate()
        assert said in str(e.value), (kw, str(e.value))


def test_schema_doctests():
    assert doctest.testmod(schema).failed == 0


def test_the_job_reference_page_is_generated_from_the_schema():
    r = subprocess.run([sys.executable, "-m", "tools.job_reference", "--check"], cwd=ROOT, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    page = open(os.path.join(ROOT, "docs", "guide", "job-reference.md"), encoding="utf-8").read()
    for table in (BAKE, *SOURCE_TABLES.values()):
        for key in table.fields:
            assert f"| `{key}` |" in page, key


def test_a_valid_job_still_loads(tmp_path):
    entries = load_job(job(tmp_path, source='seed = 7\nspectrum = {kind = "fractal", fmin = 1, fmax = 4}\n'))
    assert [n for n, _ in entries] == ["b"] and not isinstance(entries[0][1], Exception)
