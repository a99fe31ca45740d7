"""A procedural solid saved as a JSON file: fitted once, edited as text or as the node group's inputs, and drawn
again anywhere (the command line, job files, Python, Blender) without fitting.

The file is the field's JSON (:meth:`~.field.ProceduralField.to_dict`) with a ``format`` line first::

    {"format": "omninoise procedural solid 1",
     "family": "layers",
     "params": {"spacing": 0.5, "tilt": 1.57, "azimuth": 0.0, "profile": "saw", "flip": false,
                "turbulence": 0.4, "turb_freq": 1.2, "detail": 0.1},
     "ramp": {"positions": [-1.0, 0.0, 1.0], "colours": [[0.2, 0.1, 0.1], [0.5, 0.3, 0.2], [0.8, 0.6, 0.5]]},
     "seed": 0, "px_per_unit": 128.0}

``ramp``: the value s's stops (strictly increasing) and their sRGB colours in [0, 1]; ``tint`` (where the fit kept
one): its noise's frequency (cycles per unit), its levels' stops and levels and its colour axis (tint.py);
``px_per_unit``: the photo's pixels per texture unit (what a scale of 1 draws).  :func:`read` refuses anything
else with one line naming the key.
"""
from __future__ import annotations

import json
import os
import re

import numpy as np

from ...errors import SettingError
from ...schema import shown_value
from .family import MAX_PARAM
from .field import ProceduralField
from .ramp import Ramp
from .tint import Tint

__all__ = ["FORMAT", "document", "save", "read", "from_document", "is_saved"]

FORMAT = "omninoise procedural solid 1"     #: the ``format`` line of a saved solid
MAX_STOPS = 256                             #: the most stops a ramp or a tint's levels may have
MAX_BYTES = 1 << 20                         #: a saved solid is a few kB; a larger file is not one
_KEYS = ("format", "family", "params", "ramp", "seed", "px_per_unit", "tint")
_MAX_SEED = 2 ** 32 - 1


def is_saved(x) -> bool:
    """Whether an exemplar is a saved procedural solid: a ProceduralField, or a path ending in ``.json``."""
    return isinstance(x, ProceduralField) or isinstance(x, str) and x.lower().endswith(".json")


def document(field: ProceduralField) -> dict:
    """The saved solid of ``field``: its JSON with the ``format`` line first."""
    return {"format": FORMAT, **field.to_dict()}


def save(path: str, field: ProceduralField) -> None:
    """Write ``field`` to ``path`` as a saved solid (atomically: a failed write leaves any earlier file), a key or
    parameter a line and each list of numbers on one."""
    from ....export.atomic import write_text

    text = json.dumps(document(field), indent=1, allow_nan=False)
    text = re.sub(r"\[\s*([-+0-9.eE,\s]+?)\s*\]", lambda m: "[" + ", ".join(x.strip() for x in m.group(1).split(","))
                  + "]", text)
    write_text(path, text + "\n")


def read(path: str, setting: str = "exemplar") -> ProceduralField:
    """The solid saved at ``path``; SettingError naming ``setting`` and what is wrong where it is not one."""
    try:
        size = os.path.getsize(path)
        if size <= MAX_BYTES:
            with open(path, encoding="utf-8-sig") as fh:      # a byte-order mark (Windows editors) left out
                doc = json.load(fh, parse_constant=_no_constant)
    except OSError as exc:
        raise SettingError(setting, f"cannot read {path}: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise SettingError(setting, f"{path} is not JSON: {exc}") from None
    except RecursionError:
        raise SettingError(setting, f"{path} is not a saved procedural solid: its JSON is nested too deep") from None
    if size > MAX_BYTES:
        raise SettingError(setting, f"{path}: over {MAX_BYTES >> 20} MiB, not a saved procedural solid")
    try:
        return from_document(doc)
    except SettingError as exc:
        raise SettingError(setting, f"{path}: {exc.setting}: {exc.message}") from None


def _no_constant(name: str):
    raise ValueError(f"{name} is no number a saved solid holds")


def from_document(doc) -> ProceduralField:
    """The field of a saved solid's parsed JSON; SettingError naming the key that is wrong."""
    if not isinstance(doc, dict):
        raise SettingError("format", f"expected a JSON object, got {type(doc).__name__}")
    if doc.get("format") != FORMAT:
        raise SettingError("format", f"expected \"format\": \"{FORMAT}\", got {shown_value(doc.get('format'))}")
    unknown = sorted(set(doc) - set(_KEYS))
    if unknown:
        raise SettingError(shown_value(unknown[0]).strip("'"), f"unknown key; a saved procedural solid has "
                                                          f"{', '.join(_KEYS)}")
    for key in ("family", "params", "ramp"):
        if key not in doc:
            raise SettingError(key, "missing")
    if not isinstance(doc["family"], str):
        raise SettingError("family", f"expected a name, got {shown_value(doc['family'])}")
    params = doc["params"]
    if not isinstance(params, dict):
        raise SettingError("params", f"expected an object of the family's parameters, got {shown_value(params)}")
    _known_params(doc["family"], params)
    seed = doc.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= _MAX_SEED:
        raise SettingError("seed", f"expected a whole number in [0, {_MAX_SEED}], got {shown_value(seed)}")
    ppu = _number(doc.get("px_per_unit", 128.0), "px_per_unit")
    if not ppu > 0:
        raise SettingError("px_per_unit", f"must be above 0, got {ppu!r}")
    ramp = _ramp(doc["ramp"])
    tint = None if doc.get("tint") is None else _tint(doc["tint"])
    return ProceduralField(doc["family"], params, ramp, seed, ppu, tint)


def _known_params(family: str, params: dict) -> None:
    """SettingError naming a key of ``params`` that ``family`` does not read, or ``flip`` that is no boolean (the
    family's numbers, ``profile`` and ``pattern`` are checked by :class:`~.field.ProceduralField`)."""
    from .field import FAMILIES

    if family not in FAMILIES:
        return                       # ProceduralField names the families
    known = {q.name for q in FAMILIES[family].params()} | {"flip"}
    known |= {"layers": {"profile"}, "bonds": {"pattern"}}.get(family, set())
    unknown = sorted(set(params) - known)
    if unknown:
        raise SettingError("params", f"{family} have no parameter {shown_value(unknown[0])}; theirs: "
                                     f"{', '.join(sorted(known))}")
    if not isinstance(params.get("flip", False), bool):
        raise SettingError("params", f"flip must be true or false, got {shown_value(params['flip'])}")


def _number(v, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise SettingError(where, f"expected a finite number, got {shown_value(v)}")
    if abs(v) > MAX_PARAM:          # drawn in float32: past it a value turns infinite and the solid NaN
        raise SettingError(where, f"must lie within +-{MAX_PARAM:g}, got {shown_value(v)}")
    return float(v)


def _numbers(v, where: str, low: float = -np.inf, high: float = np.inf) -> list:
    if not isinstance(v, list):
        raise SettingError(where, f"expected a list of numbers, got {shown_value(v)}")
    out = [_number(x, where) for x in v]
    if any(not low <= x <= high for x in out):
        raise SettingError(where, f"values must lie in [{low}, {high}]")
    return out


def _stops(v, where: str) -> tuple:
    x = _numbers(v, where)
    if not 2 <= len(x) <= MAX_STOPS:
        raise SettingError(where, f"expected 2 to {MAX_STOPS} stops, got {len(x)}")
    if any(b <= a for a, b in zip(x, x[1:])):
        raise SettingError(where, "stops must increase strictly")
    return tuple(x)


def _ramp(d) -> Ramp:
    if not isinstance(d, dict) or set(d) != {"positions", "colours"}:
        raise SettingError("ramp", f"expected {{\"positions\": [...], \"colours\": [[r, g, b], ...]}}, "
                                   f"got {shown_value(d)}")
    x = _stops(d["positions"], "ramp.positions")
    c = d["colours"]
    if not isinstance(c, list) or len(c) != len(x):
        raise SettingError("ramp.colours", f"expected {len(x)} colours, one per position")
    cols = []
    for rgb in c:
        v = _numbers(rgb, "ramp.colours", 0.0, 1.0)
        if len(v) != 3:
            raise SettingError("ramp.colours", f"expected [r, g, b] in [0, 1], got {shown_value(rgb)}")
        cols.append(tuple(v))
    return Ramp(x, tuple(cols))


def _tint(d) -> Tint:
    keys = {"frequency", "positions", "levels", "axis"}
    if not isinstance(d, dict) or set(d) != keys:
        raise SettingError("tint", f"expected an object of {', '.join(sorted(keys))}, or null, got {shown_value(d)}")
    f = _number(d["frequency"], "tint.frequency")
    if not f > 0:
        raise SettingError("tint.frequency", f"must be above 0, got {f!r}")
    x = _stops(d["positions"], "tint.positions")
    levels = _numbers(d["levels"], "tint.levels", -1.0, 1.0)
    if len(levels) != len(x):
        raise SettingError("tint.levels", f"expected {len(x)} levels, one per position")
    axis = _numbers(d["axis"], "tint.axis", -1.0, 1.0)
    if len(axis) != 3 or not np.linalg.norm(axis) > 0:
        raise SettingError("tint.axis", f"expected a colour direction [r, g, b], got {shown_value(d['axis'])}")
    return Tint(f, x, tuple(levels), tuple(axis))
