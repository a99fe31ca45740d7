"""Strict settings schemas: exact types, ranges and known keys, checked in one place before any work.

A schema is a tree of small types. ``check(value, where)`` returns the value (ints given for floats become
floats, lists become tuples) or raises :class:`~backend.errors.SettingError` naming the setting by its dotted
path (``source.spectrum.fmax``). Nothing is coerced: a bool is not a number, ``1.5`` is not a whole number,
``"7"`` is not a number and ``"false"`` is not a boolean. ``describe()`` gives each type's rule in words, from
which the job-file reference (``docs/guide/job-reference.md``) is generated.

>>> Int(0, 10).check(3, "seed")
3
>>> Float(0.0, 1.0).check(1, "mix")
1.0
>>> def said(t, value, where):
...     try:
...         t.check(value, where)
...     except SettingError as exc:
...         print(exc)
>>> said(Int(0, 10), 1.5, "seed")
seed: expected a whole number, got 1.5
>>> said(Bool(), "false", "tileable")
tileable: expected true or false, got 'false'
>>> said(Table({"seed": Field(Int(0, 9), "the seed")}), {"sead": 1}, "source")
source.sead: unknown key (did you mean seed?); known: seed
"""
from __future__ import annotations

import difflib
import math
import numbers
from dataclasses import dataclass

from .errors import SettingError

__all__ = ["Type", "Int", "Float", "Bool", "Text", "Choice", "ListOf", "Items", "Table", "Field", "AnyOf", "MapOf",
           "shown_value", "did_you_mean"]

SHOWN_CHARS = 60  # a value quoted in a message is cut to this many characters


def shown_value(value) -> str:
    """``repr(value)`` cut to :data:`SHOWN_CHARS` (a 10 MB string is not echoed whole)."""
    text = repr(value)
    return text if len(text) <= SHOWN_CHARS else text[:SHOWN_CHARS - 3] + "..."


def did_you_mean(word: str, known) -> str:
    """`` (did you mean X?)`` for the closest known word, or nothing."""
    names = {str(k).lower(): str(k) for k in known}
    close = difflib.get_close_matches(str(word).lower(), list(names), n=1, cutoff=0.6)
    return f" (did you mean {names[close[0]]}?)" if close else ""


def _join(where: str, key) -> str:
    return f"{where}.{key}" if where else str(key)


class Type:
    """One rule; subclasses define :meth:`check` and :meth:`describe`."""

    def check(self, value, where: str):
        raise NotImplementedError

    def describe(self) -> str:
        raise NotImplementedError

    def fail(self, where: str, value, what: str | None = None):
        raise SettingError(where or "value", f"expected {what or self.describe()}, got {shown_value(value)}")


def _is_int(v) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _is_number(v) -> bool:
    return isinstance(v, (numbers.Integral, float)) and not isinstance(v, bool)


def _num(v: float) -> str:
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e15 else f"{v:g}"


@dataclass(frozen=True)
class Int(Type):
    """A whole number in [lo, hi]."""

    lo: int
    hi: int

    def check(self, value, where):
        if not _is_int(value):
            self.fail(where, value, "a whole number")
        if not self.lo <= value <= self.hi:
            raise SettingError(where, f"must lie in [{self.lo}, {self.hi}], got {shown_value(value)}")
        return int(value)

    def describe(self):
        return f"a whole number in [{self.lo}, {self.hi}]"


@dataclass(frozen=True)
class Float(Type):
    """A finite number in [lo, hi] (``above``: strictly greater than lo); whole numbers are taken."""

    lo: float = -math.inf
    hi: float = math.inf
    above: bool = False

    def check(self, value, where):
        if not _is_number(value):
            self.fail(where, value, "a number")
        try:
            v = float(value)
        except OverflowError:  # a whole number past the float range
            raise SettingError(where, f"must be a finite number, got {shown_value(value)}") from None
        if not math.isfinite(v):
            raise SettingError(where, f"must be a finite number, got {shown_value(value)}")
        if (v <= self.lo if self.above else v < self.lo) or v > self.hi:
            raise SettingError(where, f"must lie in {self._range()}, got {v:g}")
        return v

    def _range(self):
        lo = "(-inf" if self.lo == -math.inf else ("(" if self.above else "[") + _num(self.lo)
        hi = "inf)" if self.hi == math.inf else _num(self.hi) + "]"
        return f"{lo}, {hi}"

    def describe(self):
        if self.lo == -math.inf and self.hi == math.inf:
            return "a finite number"
        if self.above and self.lo == 0 and self.hi == math.inf:
            return "a positive number"
        return f"a number in {self._range()}"


@dataclass(frozen=True)
class Bool(Type):
    def check(self, value, where):
        if not isinstance(value, bool):
            self.fail(where, value)
        return value

    def describe(self):
        return "true or false"


@dataclass(frozen=True)
class Text(Type):
    """A non-empty string of at most ``max_len`` characters (a name, a path, a class spec)."""

    what: str = "text"
    max_len: int = 4096

    def check(self, value, where):
        if not isinstance(value, str) or not value.strip():
            self.fail(where, value, f"{self.what} (a non-empty string)")
        if len(value) > self.max_len or "\x00" in value:
            raise SettingError(where, f"expected {self.what} of at most {self.max_len} characters without NUL, "
                                      f"got {shown_value(value)}")
        return value

    def describe(self):
        return self.what


@dataclass(frozen=True)
class Choice(Type):
    """One of a fixed set of strings (or of whole numbers)."""

    options: tuple

    def check(self, value, where):
        same_kind = all(_is_int(o) for o in self.options) == _is_int(value) and isinstance(value, (str, int)) \
            and not isinstance(value, bool)
        if same_kind and value in self.options:
            return value
        hint = did_you_mean(value, self.options) if isinstance(value, str) else ""
        raise SettingError(where, f"expected one of {', '.join(map(str, self.options))}{hint}, got "
                                  f"{shown_value(value)}")

    def describe(self):
        return "one of " + ", ".join(f'"{o}"' if isinstance(o, str) else str(o) for o in self.options)


@dataclass(frozen=True)
class ListOf(Type):
    """A list of ``lo`` to ``hi`` items of one type."""

    item: Type
    lo: int = 0
    hi: int = 1 << 16

    def check(self, value, where):
        if not isinstance(value, (list, tuple)):
            self.fail(where, value)
        if not self.lo <= len(value) <= self.hi:
            raise SettingError(where, f"expected {self._count()}, got {len(value)}: {shown_value(value)}")
        return [self.item.check(v, f"{where}[{i}]") for i, v in enumerate(value)]

    def _count(self):
        n = f"{self.lo}" if self.lo == self.hi else f"{self.lo} to {self.hi}"
        return f"{n} item{'s' if self.hi != 1 else ''}"

    def describe(self):
        return f"a list of {self._count()}, each {self.item.describe()}"


@dataclass(frozen=True)
class Items(Type):
    """A list of fixed length whose items have their own types (``[[x, y, z], weight]``)."""

    types: tuple
    what: str = ""

    def check(self, value, where):
        if not isinstance(value, (list, tuple)) or len(value) != len(self.types):
            self.fail(where, value)
        return [t.check(v, f"{where}[{i}]") for i, (t, v) in enumerate(zip(self.types, value))]

    def describe(self):
        return self.what or "[" + ", ".join(t.describe() for t in self.types) + "]"


@dataclass(frozen=True)
class MapOf(Type):
    """A table of up to ``hi`` entries from names to values of one type."""

    value: Type
    key: str = "name"
    hi: int = 256

    def check(self, value, where):
        if not isinstance(value, dict):
            self.fail(where, value)
        if len(value) > self.hi:
            raise SettingError(where, f"expected at most {self.hi} entries, got {len(value)}")
        return {k: self.value.check(v, _join(where, k)) for k, v in value.items()}

    def describe(self):
        return f"a table from {self.key} to {self.value.describe()}"


@dataclass(frozen=True)
class AnyOf(Type):
    """The first alternative whose kind of value matches (a string, a number, a list or a table)."""

    options: tuple

    def check(self, value, where):
        for opt in self.options:
            if _accepts_kind(opt, value):
                return opt.check(value, where)
        self.fail(where, value)

    def describe(self):
        return " or ".join(o.describe() for o in self.options)


def _accepts_kind(t: Type, value) -> bool:
    if isinstance(t, (Int, Float)):
        return _is_number(value)
    if isinstance(t, Bool):
        return isinstance(value, bool)
    if isinstance(t, (Text, Choice)):
        return isinstance(value, str)
    if isinstance(t, (ListOf, Items)):
        return isinstance(value, (list, tuple))
    if isinstance(t, (Table, MapOf)):
        return isinstance(value, dict)
    return isinstance(t, AnyOf) and any(_accepts_kind(o, value) for o in t.options)


@dataclass(frozen=True)
class Field:
    """A key of a :class:`Table`: its type, what it does (one line), and whether it must be given."""

    type: Type
    doc: str
    required: bool = False
    default: str = ""  # the default in words, for the reference


@dataclass(frozen=True)
class Table(Type):
    """A table with known keys (an unknown one fails with the nearest known name); ``fields`` None: any keys
    (a table whose keys another schema checks)."""

    fields: dict | None = None
    what: str = "a table"

    def check(self, value, where):
        if not isinstance(value, dict):
            self.fail(where, value)
        if self.fields is None:
            return value
        for k in value:
            if k not in self.fields:
                raise SettingError(_join(where, k), f"unknown key{did_you_mean(k, self.fields)}; known: "
                                                    f"{', '.join(self.fields)}")
        for k, f in self.fields.items():
            if f.required and k not in value:
                raise SettingError(_join(where, k), f"missing ({f.doc})")
        return {k: self.fields[k].type.check(v, _join(where, k)) for k, v in value.items()}

    def describe(self):
        return self.what
