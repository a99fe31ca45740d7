"""What ``--list`` prints: a table to read, or with ``--json`` the same as JSON for scripts.

>>> print(classes_text({"perlin": dict(doc="one octave of Perlin noise", params=[
...     dict(name="scale", min=2, max=16, unit="cells per 128 px", integer=False)])}))
perlin  one octave of Perlin noise
        scale 2 to 16 (cells per 128 px)
<BLANKLINE>
1 class: --noise CLASS, --param NAME=VALUE; --list --json prints this as JSON.
"""
from __future__ import annotations

import json
import textwrap

__all__ = ["show", "classes_text", "textures_text", "presets_text"]

WIDTH = 100     #: the tables' lines are wrapped at this many characters


def show(data, text: str, as_json: bool) -> None:
    """Print ``data`` as indented JSON, or ``text``."""
    print(json.dumps(data, indent=2) if as_json else text)


def _number(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _param(p: dict) -> str:
    unit = ", ".join(u for u in (p.get("unit"), "whole numbers" if p.get("integer") else "") if u)
    return f"{p['name']} {_number(p['min'])} to {_number(p['max'])}" + (f" ({unit})" if unit else "")


def classes_text(classes: dict, untrained=()) -> str:
    """Noise classes ({name: {doc, params: [{name, min, max, unit, integer}]}}) as a table: each name and what it
    draws, and under it its parameters' ranges and units; then the ``untrained`` classes a model also takes (they
    draw, but not as their class looks)."""
    width = max(map(len, classes)) + 2
    lines = []
    for name, c in classes.items():
        lines.append(f"{name:<{width}}{c['doc']}")
        if c["params"]:
            params = ", ".join(_param(p).replace(" ", "\xa0") for p in c["params"])   # lines break between them
            lines.append(textwrap.fill(params, WIDTH, initial_indent=" " * width, subsequent_indent=" " * width,
                                       break_on_hyphens=False).replace("\xa0", " "))
    n = len(classes)
    lines += ["", f"{n} class{'es' if n != 1 else ''}: --noise CLASS, --param NAME=VALUE; --list --json prints this "
              "as JSON."]
    if untrained:
        lines.append(textwrap.fill(f"The model was not trained on {', '.join(untrained)}.", WIDTH))
    return "\n".join(lines)


def textures_text(textures: dict) -> str:
    """The shipped solid textures ({name: {mode, dim, exemplars, codes}}) as a table: each name, what it gives and
    from what photo; then the kinds of photo a texture-space model (mode "space") names, and that any photo will do."""
    singles = {name: t for name, t in textures.items() if t["mode"] != "space"}
    width = max(map(len, singles), default=0) + 2
    lines = [f"{name:<{width}}{t['dim']}D {'image' if t['dim'] == 2 else 'solid'} from "
             + ", ".join(e.rsplit("/", 1)[-1] for e in t["exemplars"]) for name, t in singles.items()]
    for name, t in textures.items():
        if t["mode"] == "space":
            lines += ["", textwrap.fill(f"3D solids of kinds of photo, by name (the {name} model): "
                                        + ", ".join(t["codes"]) + ".", WIDTH)]
    return "\n".join(lines + ["", "--exemplar NAME, or any photo's file; --list --json prints this as JSON."])


def presets_text(notes: dict) -> str:
    """Presets ({name: what it looks like}) a line each, the name first (what a script reads: ``cut -d' ' -f1``)."""
    width = max(map(len, notes)) + 2
    return "\n".join(f"{name:<{width}}{note}" for name, note in notes.items())
