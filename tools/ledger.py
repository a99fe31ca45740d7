"""Print a model's training ledger: ``python tools/ledger.py models/neural_noise`` (or ``models/solid``).

The ledger (``MODEL_FOLDER/ledger.json``: ``columns`` and ``rows``, oldest stage first) records every training
stage of a model's line: its config, start, steps, time, hardware, evaluation and whether it shipped.  The model
card links here instead of repeating it.  ``--markdown`` prints a Markdown table; the default is one block of
``column: value`` lines per stage, readable in a terminal.
"""
from __future__ import annotations

import argparse
import json
import os
import sys


def load(folder: str) -> dict:
    """The ledger document of a model folder (or a ledger file itself)."""
    path = folder if folder.endswith(".json") else os.path.join(folder, "ledger.json")
    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    cols, rows = doc.get("columns"), doc.get("rows")
    if not isinstance(cols, list) or not isinstance(rows, list) or any(len(r) != len(cols) for r in rows):
        raise ValueError(f"{path}: a ledger needs 'columns' and 'rows' of as many cells")
    return doc


def markdown(doc: dict) -> str:
    lines = ["| " + " | ".join(doc["columns"]) + " |", "|" + "---|" * len(doc["columns"])]
    lines += ["| " + " | ".join(str(c).replace("|", "\\|") for c in row) + " |" for row in doc["rows"]]
    return "\n".join(lines)


def blocks(doc: dict) -> str:
    width = max(len(c) for c in doc["columns"])
    out = []
    for i, row in enumerate(doc["rows"], 1):
        out.append(f"[{i}/{len(doc['rows'])}]")
        out += [f"  {c:<{width}}  {v}" for c, v in zip(doc["columns"], row)]
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model", help="a model folder holding ledger.json (models/neural_noise, models/solid)")
    ap.add_argument("--markdown", action="store_true", help="a Markdown table instead of one block per stage")
    a = ap.parse_args(argv)
    try:
        doc = load(a.model)
    except (OSError, ValueError) as exc:
        print(f"ledger: error: {exc}", file=sys.stderr)
        return 2
    print(doc.get("description", ""))
    print(markdown(doc) if a.markdown else blocks(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
