"""Write docs/guide/job-reference.md from the settings schema (backend/settings_schema.py).

    python -m tools.job_reference            # rewrite the page
    python -m tools.job_reference --check    # exit 1 when the page is out of date
"""
from __future__ import annotations

import argparse
import os
import sys

from omninoise.backend.schema import Table
from omninoise.backend.settings_schema import BAKE, JOB, SOURCE_TABLES
from omninoise.backend.transfer import TRANSFER
from omninoise.backend.wavenoise.schema import SPECTRUM

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGE = os.path.join(ROOT, "docs", "guide", "job-reference.md")

INTRO = """# Job-file reference

Every key a job file takes, with its exact type and range. This page is generated from the schema the
checks use (`backend/settings_schema.py`, `backend/wavenoise/schema.py`, `backend/transfer.py`) by
`python -m tools.job_reference`; [Job files](jobs.md) shows them in use.

Types are exact: a whole number is not written `2.0`, `true` is not a number, `"7"` is not a number and
`"false"` is not a boolean. Numbers are finite. An unknown key is refused with the nearest known one
(`source.sped: unknown key (did you mean speed?)`). Every bake is checked before any bake runs; a problem is
reported as `bake 'NAME': KEY: what is wrong` with exit status 2.
"""


def table_md(title: str, table: Table, note: str = "") -> str:
    rows = ["| key | type | default | what it does |", "|---|---|---|---|"]
    for key, f in table.fields.items():
        default = "required" if f.required else (f.default or "—")
        rows.append(f"| `{key}` | {f.type.describe()} | {default} | {f.doc} |")
    return f"## {title}\n\n" + (note + "\n\n" if note else "") + "\n".join(rows) + "\n"


def _reads() -> str:
    """Which methods read which keys of a solid source (backend.solid.methods.READS), as a sentence."""
    from omninoise.backend.solid.methods import READS

    keys = dict.fromkeys(k for ks in READS.values() for k in ks)
    said = "; ".join(f"`{k}` {', '.join(m for m, ks in READS.items() if k in ks)}" for k in keys)
    return f"Each method reads its exemplar and seed and some of the other keys ({said}); one it does not read is " \
           "refused."


def page() -> str:
    parts = [INTRO,
             table_md("The file", JOB, "Top-level keys of the job file."),
             table_md("`[[bake]]`", BAKE, "One table per bake; `[defaults]` takes the same keys and is merged "
                                          "into every bake (a bake's own keys win, tables merge key by key)."),
             table_md('`[bake.source]` with `kind = "wave"`', SOURCE_TABLES["wave"],
                      "Wave noise; the same settings as `omninoise wave` and the Wave Noise node."),
             table_md("Spectrum tables", SPECTRUM, "`spectrum`, `transition_to` and each of `axis_spectra`."),
             table_md('`[bake.source]` with `kind = "neural"`', SOURCE_TABLES["neural"],
                      "Neural noise: one class (`noise`), a mask blend (`blend`), two from left to right "
                      "(`gradient`), four `corners` or a painted `map` with `regions`; `keys` animates."),
             table_md('`[bake.source]` with `kind = "solid"`', SOURCE_TABLES["solid"],
                      "A solid texture from a photo. " + _reads()),
             table_md("Ramp tables (`transfer = {...}` or a ramp .json file)", TRANSFER)]
    return "\n".join(parts)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when the page is out of date")
    a = ap.parse_args(argv)
    text = page()
    if a.check:
        with open(PAGE, encoding="utf-8") as fh:
            same = fh.read() == text
        print("docs/guide/job-reference.md is " + ("up to date" if same else "out of date: python -m tools.job_reference"))
        return 0 if same else 1
    with open(PAGE + ".tmp", "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(PAGE + ".tmp", PAGE)
    print(f"wrote {os.path.relpath(PAGE, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
