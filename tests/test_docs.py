"""The documents stay a user's documents: the project speaks of itself only (no rounds of work, issue numbers,
borrowed machines or dates of work in any tracked file), the README stays short and its links resolve, the
model cards keep their hub shape, and the licence ships."""
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

_ORDINAL = (r"(first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|twelfth|\w+teenth|"
            r"twentieth|thirtieth|fortieth|(twenty|thirty|forty)-(first|second|third|fourth|fifth|sixth|seventh|"
            r"eighth|ninth)|\d+(st|nd|rd|th))")
#: what a line about how the project was made looks like; dates only outside measurement data (benchmarks state
#: when they were measured)
HISTORY = {
    "an issue number": re.compile(r"\bissues? ?#?\d+\b|\bissue\d+", re.I),
    "a round of work": re.compile(r"\b(session|sprint)s? \d+\b|\b" + _ORDINAL + r" (session|sprint)\b"
                                  r"|\brounds? of (work|development)\b", re.I),
    "a borrowed machine": re.compile(r"\b(lent|borrowed|loaned)( an?| the| one)?( NVIDIA)? (GPU|H100|H200|machine|"
                                     r"device|accelerator)s?\b|\bdevice tool\b|\b(GPU|H100|H200|machine|device|"
                                     r"accelerator)s? (has|have|was|were|is|are)( not)?( been)? (lent|borrowed|"
                                     r"loaned)\b", re.I),
    "a date of work": re.compile(r"\b(January|February|March|April|May|June|July|August|September|October|November|"
                                 r"December) \d{1,2}(, \d{4})?\b|\b(January|February|March|April|May|June|July|"
                                 r"August|September|October|November|December) 20\d\d\b"),
}
BINARY = (".onnx", ".npz", ".png", ".jpg", ".jpeg", ".gif", ".exr", ".vdb", ".weights", ".npy", ".zip", ".whl")
MEASUREMENTS = ("docs/benchmarks.md",)
#: third-party text quoted whole, and this test, which names the kinds of line it looks for
NOT_SCANNED = ("LICENSE", "tests/test_docs.py")


def history_lines(path: str, text: str) -> list:
    """(line number, what it speaks of, line) of every line of ``text`` that tells how the project was made."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for what, pat in HISTORY.items():
            if what == "a date of work" and (path.endswith(".json") or path in MEASUREMENTS):
                continue
            if pat.search(line):
                out.append((n, what, line.strip()[:160]))
    return out


def tracked() -> list:
    r = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip("not a git checkout")
    return [f for f in r.stdout.splitlines() if os.path.isfile(os.path.join(ROOT, f))]


def test_no_tracked_file_speaks_of_how_the_project_was_made():
    bad = []
    for f in tracked():
        if HISTORY["an issue number"].search(f):
            bad.append(f"{f}: its name carries an issue number")
        if f.lower().endswith(BINARY) or f in NOT_SCANNED:
            continue
        try:
            with open(os.path.join(ROOT, f), encoding="utf-8") as fh:
                text = fh.read()
        except UnicodeDecodeError:
            continue
        bad += [f"{f}:{n}: {what}: {line}" for n, what, line in history_lines(f, text)]
    assert not bad, "\n".join(bad[:60]) + (f"\n... {len(bad)} lines in all" if len(bad) > 60 else "")


#: lines the check must catch, assembled here so that this file holds none of them whole
CAUGHT = [(" ".join(words), what) for words, what in (
    (("Fixed in", "issue", "22."), "an issue number"),
    (("as the", "twenty-third", "session", "found"), "a round of work"),
    (("the second", "round of", "work on it"), "a round of work"),
    (("trained on a", "lent", "H200"), "a borrowed machine"),
    (("on the CPU (no GPU", "was lent)"), "a borrowed machine"),
    (("measured on", "November", "27, 2026"), "a date of work"),
)]


@pytest.mark.parametrize("line, what", CAUGHT)
def test_the_history_check_finds_each_kind(line, what):
    assert [w for _, w, _ in history_lines("x.py", line)] == [what]


@pytest.mark.parametrize("line", [
    "Frequencies are in cycles per unit.", "Round the value to the nearest texel.", "the session's preferences",
    "an H200 machine", "dask==2026.8.0", "the first round of the sampler", "released under GPL-3.0-or-later"])
def test_the_history_check_leaves_ordinary_lines_alone(line):
    assert history_lines("x.py", line) == []


def test_the_readme_is_short_and_its_links_and_pictures_resolve():
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as fh:
        text = fh.read()
    assert len(text.splitlines()) <= 300 and len(text.encode()) <= 30_000
    for heading in ("## Install into Blender", "## A tour", "## Command line", "## Python API", "## Develop and test",
                    "## Licence and credits"):
        assert heading in text, heading
    for cmd in ("make demo", "make test", "make dist"):
        assert cmd in text, cmd
    links = re.findall(r"\]\(([^)#\s]+)\)", text)
    local = [x for x in links if not x.startswith(("http://", "https://"))]
    assert len(local) >= 10
    missing = [x for x in local if not os.path.exists(os.path.join(ROOT, x))]
    assert not missing, missing


def test_every_guide_page_link_resolves():
    bad = []
    for folder, _, files in os.walk(os.path.join(ROOT, "docs")):
        for f in files:
            if not f.endswith(".md"):
                continue
            path = os.path.join(folder, f)
            with open(path, encoding="utf-8") as fh:
                for x in re.findall(r"\]\(([^)#\s]+)\)", fh.read()):
                    if not x.startswith(("http://", "https://")) and \
                            not os.path.exists(os.path.normpath(os.path.join(folder, x))):
                        bad.append(f"{os.path.relpath(path, ROOT)}: {x}")
    assert not bad, bad


@pytest.mark.parametrize("card", ["models/neural_noise/MODEL_CARD.md", "models/solid/MODEL_CARD.md"])
def test_model_cards_have_the_hub_shape(card):
    with open(os.path.join(ROOT, card), encoding="utf-8") as fh:
        text = fh.read()
    assert len(text.splitlines()) <= 150
    for heading in ("## Model details", "## Intended use", "## Training data and licence", "## Evaluation",
                    "## Limitations"):
        assert heading in text, (card, heading)
    assert re.search(r"^## How to train", text, re.M)
    assert "tools/ledger.py" in text     # the stage-by-stage ledger is data, printed by a command


def test_the_licence_is_the_gpl_the_manifest_names():
    import tomllib

    with open(os.path.join(ROOT, "LICENSE"), encoding="utf-8") as fh:
        head = fh.read(200)
    assert "GNU GENERAL PUBLIC LICENSE" in head and "Version 3" in head
    with open(os.path.join(ROOT, "blender_manifest.toml"), "rb") as fh:
        assert tomllib.load(fh)["license"] == ["SPDX:GPL-3.0-or-later"]


@pytest.fixture(scope="module")
def ledger():
    """tools/ledger.py as a module (tools are scripts, not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("ledger", os.path.join(ROOT, "tools", "ledger.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("model, columns", [("models/neural_noise", ["stage", "config", "steps", "shipped"]),
                                            ("models/solid", ["stage", "steps", "median swd", "shipped"])])
def test_the_ledger_prints_every_stage(model, columns, ledger, capsys):
    doc = ledger.load(os.path.join(ROOT, model))
    assert all(c in doc["columns"] for c in columns) and len(doc["rows"]) >= 10
    assert ledger.main([os.path.join(ROOT, model), "--markdown"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n| ") == len(doc["rows"]) + 1       # the header and one row per stage


def test_a_broken_ledger_is_one_line_and_exit_2(tmp_path, ledger, capsys):
    (tmp_path / "ledger.json").write_text('{"columns": ["a", "b"], "rows": [["only one"]]}')
    assert ledger.main([str(tmp_path)]) == 2
    assert "ledger needs" in capsys.readouterr().err


def test_the_command_line_guide_sets_each_solid_preset_as_the_panel_does():
    """The command-line guide's table of solid flags by kind of photo is the Solid Texture panel's shipped presets:
    the same method and procedural kinds, a row for each preset."""
    def key(words: str) -> str:     # "a brick wall or tiles", "brick_wall_or_tiles" -> "brick wall or tiles"
        return " ".join(w for w in re.split(r"[ _,]+", words) if w not in ("a", "and", ""))

    every = ["bonds", "cells", "layers", "rings"]   # the procedural kinds a preset of another method leaves set
    folder = os.path.join(ROOT, "blender_addon", "presets", "omninoise", "solid")
    presets = {}
    for name in os.listdir(folder):
        text = open(os.path.join(folder, name), encoding="utf-8").read()
        method = re.search(r"p\.method = '(\w+)'", text).group(1).lower()
        families = sorted(f.lower() for f in re.findall(r"'(\w+)'", re.search(r"p\.families = \{(.*)\}", text)[1]))
        presets[key(name[:-3])] = (method, families)
    guide = open(os.path.join(ROOT, "docs", "guide", "cli.md"), encoding="utf-8").read()
    table = guide.split("**By kind of photo**")[1].split("\n\n")[1]
    rows = {}
    for photo, flags in re.findall(r"^\| ([a-z, ]+) \| (.+) \|$", table, re.M)[1:]:    # after the header
        method = re.search(r"--method (\w+)", flags)
        families = re.search(r"--families ([\w,]+)", flags)
        rows[key(photo)] = (method.group(1) if method else "neural",
                            sorted(families.group(1).split(",")) if families else every)
    assert rows == presets
