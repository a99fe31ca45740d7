"""RGBA transfer functions: noise value -> colour, density and temperature.

The volumetric bakes of Guehl et al. 2025 (Sec. 7.1) map the scalar noise
through a 1D transfer function.  A :class:`TransferFunction` is a colour ramp
like Blender's Color Ramp node:

    t        = clamp((v - range[0]) / (range[1] - range[0]), 0, 1)
    rgba(t)  = ramp through ``stops`` (constant, linear or ease interpolation)
    density  = density_scale * alpha(t)
    T(t)     = piecewise-linear ``temperature`` stops (Kelvin), optional

Colours are scene-linear RGB.  A ramp edited in Blender arrives as a dense
list of stops sampled with ``ColorRamp.evaluate`` (any of Blender's modes).
JSON form (``--transfer RAMP.json``, job files)::

    {"range": [-1.5, 1.5], "interpolation": "linear", "density_scale": 1.0,
     "stops": [[0.0, [0, 0, 0, 0]], [1.0, [1, 1, 1, 1]]],
     "temperature": [[0.5, 0.0], [1.0, 1500.0]]}
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from .errors import SettingError
from .schema import AnyOf, Choice, Field, Float, Items, ListOf, Table

__all__ = ["TransferFunction", "PRESETS", "PRESET_NOTES", "preset", "load_transfer", "transfer_from_dict"]

_F = np.float32
_BLOCK = 1 << 14
INTERPOLATIONS = ("constant", "linear", "ease")


@dataclass(frozen=True)
class TransferFunction:
    """A colour-and-alpha ramp over a value range.

    stops          ((position in [0, 1], (r, g, b, a)), ...) sorted by position
    range          (v0, v1): noise values mapped to ramp positions 0 and 1
    interpolation  constant | linear | ease (Blender's Color Ramp modes of those names)
    density_scale  density = density_scale * alpha
    temperature    ((position, kelvin), ...) or () for no temperature grid
    """

    stops: tuple
    range: tuple = (-1.5, 1.5)
    interpolation: str = "linear"
    density_scale: float = 1.0
    temperature: tuple = field(default=())

    def validate(self) -> "TransferFunction":
        """The ramp's values against :data:`TRANSFER` (finite numbers, known modes), then its own rules."""
        try:
            TRANSFER.check(self.to_dict(), "")
        except (TypeError, ValueError) as exc:
            if isinstance(exc, SettingError):
                raise
            raise SettingError("transfer", f"expected numbers in range, stops and temperature ({exc})") from None
        pos = [p for p, _ in self.stops]
        if any(b < a for a, b in zip(pos, pos[1:])):
            raise SettingError("stops", f"positions must be sorted, got {pos}")
        for p, c in self.stops:
            if len(c) != 4:
                raise SettingError("stops", f"colour at {p:g} needs 4 values (r, g, b, a), got {len(c)}")
            if c[3] > 1.0:
                raise SettingError("stops", f"the alpha of the stop at {p:g} must lie in [0, 1] (density_scale "
                                            f"scales a volume's density), got {c[3]:g}")
        v0, v1 = self.range
        if abs(v1 - v0) < MIN_SPAN:
            raise SettingError("range", f"needs two different values, at least {MIN_SPAN:g} apart, got "
                                        f"{tuple(self.range)}")
        tp = [p for p, _ in self.temperature]
        if any(b < a for a, b in zip(tp, tp[1:])):
            raise SettingError("temperature", f"positions must be sorted, got {tp}")
        return self

    @property
    def has_temperature(self) -> bool:
        return len(self.temperature) > 0

    def position(self, values: np.ndarray) -> np.ndarray:
        """Ramp position t in [0, 1]: float32, same shape as ``values``."""
        v0, v1 = (float(r) for r in self.range)
        t = (np.asarray(values, _F) - _F(v0)) * _F(1.0 / (v1 - v0))
        return np.clip(t, _F(0.0), _F(1.0))

    def rgba(self, values: np.ndarray) -> np.ndarray:
        """Noise values float32 (...) -> colour and alpha float32 (..., 4).

        Works through blocks of ``_BLOCK`` values so temporaries stay small
        whatever the slab size (bakes call this on whole slabs).
        """
        v = np.asarray(values, _F)
        out = np.empty(v.shape + (4,), _F)
        flat_v, flat_o = v.reshape(-1), out.reshape(-1, 4)
        pos = np.array([p for p, _ in self.stops], _F)
        cols = np.array([c for _, c in self.stops], _F)
        if len(pos) == 1:
            out[...] = cols[0]
            return out
        width = pos[1:] - pos[:-1]
        inv = np.where(width > 0, _F(1.0) / np.where(width > 0, width, _F(1.0)), _F(0.0)).astype(_F)
        dcol = cols[1:] - cols[:-1]
        for a in range(0, flat_v.size, _BLOCK):
            t = self.position(flat_v[a: a + _BLOCK])
            # segment i covers [pos[i], pos[i+1]); beyond the end stops the ramp is flat
            i = np.searchsorted(pos, t, side="right").astype(np.int32)
            i -= 1
            np.clip(i, 0, len(pos) - 2, out=i)
            f = t - pos[i]
            f *= inv[i]
            f[inv[i] == 0] = 1.0  # zero-width segment: a hard step
            np.clip(f, _F(0.0), _F(1.0), out=f)
            if self.interpolation == "constant":
                f = (f >= 1.0).astype(_F)  # Blender: hold the left stop's colour until the next stop
            elif self.interpolation == "ease":
                f = f * f * (_F(3.0) - _F(2.0) * f)
            o = flat_o[a: a + _BLOCK]
            np.multiply(dcol[i], f[:, None], out=o)
            o += cols[i]
        return out

    def largest(self, volume: bool) -> float:
        """The largest value the ramp writes: its stops' colours and alpha (an image), and for a volume the density
        (density_scale x alpha) and temperature too; every interpolation stays within its stops."""
        top = max(max(c) for _, c in self.stops)
        if volume:
            top = max(top, self.density_scale * max(c[3] for _, c in self.stops),
                      max((k for _, k in self.temperature), default=0.0))
        return float(top)

    def density(self, rgba: np.ndarray) -> np.ndarray:
        """Density from :meth:`rgba`'s alpha: float32 (...)."""
        return rgba[..., 3] * _F(self.density_scale)

    def kelvin(self, values: np.ndarray) -> np.ndarray:
        """Temperature in Kelvin float32 (...), piecewise linear over ``temperature`` stops."""
        if not self.has_temperature:
            raise SettingError("temperature", "this ramp has no temperature stops")
        tp = np.array([p for p, _ in self.temperature], np.float64)
        tk = np.array([k for _, k in self.temperature], np.float64)
        return np.interp(self.position(values), tp, tk).astype(_F)

    def to_dict(self) -> dict:
        return dict(range=[float(r) for r in self.range], interpolation=self.interpolation,
                    density_scale=float(self.density_scale),
                    stops=[[float(p), [float(c) for c in col]] for p, col in self.stops],
                    temperature=[[float(p), float(k)] for p, k in self.temperature])

    def with_range(self, v0: float, v1: float) -> "TransferFunction":
        from dataclasses import replace

        return replace(self, range=(float(v0), float(v1))).validate()


def _stop(item, where: str) -> tuple:
    if isinstance(item, dict):
        try:
            item = (item["position"], item["color"])
        except KeyError as exc:
            raise SettingError(where, f"a stop table needs position and color, missing {exc.args[0]}") from None
    try:
        p, c = item
        c = tuple(float(v) for v in c)
        if len(c) == 3:
            c = c + (1.0,)
        return float(p), c
    except (TypeError, ValueError):
        raise SettingError(where, f"expected [position, [r, g, b(, a)]], got {item!r}") from None


def transfer_from_dict(d: dict, where: str = "transfer") -> TransferFunction:
    """A ramp from a plain dict (JSON file, job file table), checked against :data:`TRANSFER`.

    ``preset = "clouds"`` starts from a preset; any other key overrides it.
    """
    d = TRANSFER.check(d, where)
    base = preset(d["preset"]).to_dict() if "preset" in d else {}
    base.update({k: v for k, v in d.items() if k != "preset"})
    if "stops" not in base:
        raise SettingError(where, "needs stops (or a preset)")
    tf = TransferFunction(
        stops=tuple(_stop(s, f"{where}.stops") for s in base["stops"]), range=tuple(base.get("range", (-1.5, 1.5))),
        interpolation=base.get("interpolation", "linear"), density_scale=float(base.get("density_scale", 1.0)),
        temperature=tuple((float(p), float(k)) for p, k in base.get("temperature") or ()))
    try:
        return tf.validate()
    except SettingError as exc:        # the ramp's own rules, named as the schema names its keys
        raise exc.under(where) from None


def load_transfer(spec: str, where: str = "transfer") -> TransferFunction:
    """A preset name or a JSON ramp file; ``where`` names the setting in errors (a flag, a job's key)."""
    if not isinstance(spec, (str, os.PathLike)):      # an int would be opened as a file descriptor
        raise SettingError(where, f"expected a preset name or a ramp .json file, got {spec!r}")
    spec = os.fspath(spec)
    if spec in PRESETS:
        return preset(spec)
    if not os.path.exists(spec):
        raise SettingError(where, f"{spec!r} is neither a preset ({', '.join(PRESETS)}) nor a file")
    from .documents import read_document

    d = read_document(spec, where, "json")
    return transfer_from_dict(d, f"{where}: {os.path.basename(spec)}")


#: presets for the wave noise's real output (mean 0, std ~0.7); ``range`` adapts them to others; each one's look
#: in :data:`PRESET_NOTES`
PRESETS = {
    "clouds": dict(range=(0.1, 1.8), interpolation="ease", density_scale=3.0,
                   stops=((0.0, (1.0, 1.0, 1.0, 0.0)), (0.25, (0.95, 0.96, 1.0, 0.15)),
                          (1.0, (1.0, 1.0, 1.0, 1.0)))),
    "smoke": dict(range=(-0.5, 1.8), interpolation="linear", density_scale=2.0,
                  stops=((0.0, (0.4, 0.4, 0.42, 0.0)), (0.4, (0.25, 0.25, 0.26, 0.2)),
                         (1.0, (0.05, 0.05, 0.05, 1.0)))),
    "fire": dict(range=(0.0, 1.8), interpolation="linear", density_scale=3.0,
                 stops=((0.0, (0.1, 0.0, 0.0, 0.0)), (0.3, (0.8, 0.1, 0.0, 0.3)),
                        (0.7, (1.0, 0.5, 0.05, 0.7)), (1.0, (1.0, 0.95, 0.7, 1.0))),
                 temperature=((0.2, 0.0), (1.0, 1800.0))),
    "marble": dict(range=(-1.2, 1.2), interpolation="ease", density_scale=10.0,
                   stops=((0.0, (0.92, 0.9, 0.86, 1.0)), (0.46, (0.85, 0.83, 0.8, 1.0)),
                          (0.5, (0.15, 0.14, 0.14, 1.0)), (0.54, (0.85, 0.83, 0.8, 1.0)),
                          (1.0, (0.95, 0.94, 0.92, 1.0)))),
    "crystal": dict(range=(-1.2, 1.2), interpolation="constant", density_scale=6.0,
                    stops=((0.0, (0.0, 0.0, 0.0, 0.0)), (0.45, (0.2, 0.5, 0.7, 0.4)),
                           (0.6, (0.4, 0.8, 0.9, 0.8)), (0.8, (0.8, 0.95, 1.0, 1.0)))),
}


#: what each preset draws, in a line (``omninoise transfer --list``)
PRESET_NOTES = {
    "clouds": "white puffs with soft edges, empty where the noise is low",
    "smoke": "thin grey smoke with dark cores",
    "fire": "dark red to yellow-white, with a blackbody temperature rising to 1800 K",
    "marble": "dense stone with thin dark veins at the zero crossings of the noise's real output",
    "crystal": "hard-edged blue-green facets in constant steps, for crystal waveforms and cellular noise",
}


def preset(name: str) -> TransferFunction:
    if name not in PRESETS:
        raise SettingError("transfer preset", f"unknown {name!r}; choose one of {', '.join(PRESETS)}")
    p = PRESETS[name]
    return TransferFunction(stops=p["stops"], range=p["range"], interpolation=p["interpolation"],
                            density_scale=p["density_scale"], temperature=p.get("temperature", ())).validate()


#: a ramp's range: its ends lie within +-RANGE_LIMIT and at least MIN_SPAN apart (the noise's float32 values are
#: mapped as (v - v0) / (v1 - v0): past these the positions turn infinite or NaN)
RANGE_LIMIT, MIN_SPAN = 1e6, 1e-6

#: the keys of a ramp table (a job file's ``transfer = {...}``, a ramp .json file)
COLOR = ListOf(Float(0.0, 1e6), 3, 4)     #: scene-linear r, g, b (above 1 for a glow) and alpha
TRANSFER = Table({
    "preset": Field(Choice(tuple(PRESETS)), "start from a preset; other keys override it"),
    "range": Field(Items((Float(-RANGE_LIMIT, RANGE_LIMIT),) * 2, "[v0, v1]"),
                   "noise values mapped to ramp positions 0 and 1 (each in [-1e6, 1e6], at least 1e-6 apart)",
                   default="[-1.5, 1.5]"),
    "interpolation": Field(Choice(INTERPOLATIONS), "how colours blend between stops", default="linear"),
    "density_scale": Field(Float(0.0, 1e6), "a volume's density is density_scale times alpha", default="1"),
    "stops": Field(ListOf(AnyOf((Items((Float(0.0, 1.0), COLOR), "[position, [r, g, b(, a)]]"),
                                 Table({"position": Field(Float(0.0, 1.0), "0 to 1", True),
                                        "color": Field(COLOR, "[r, g, b(, a)]", True)},
                                       "{position = P, color = [r, g, b(, a)]}"))), 1, 4096),
                   "the ramp's colour stops, sorted by position"),
    "temperature": Field(ListOf(Items((Float(0.0, 1.0), Float(0.0, 1e5)), "[position, kelvin]"), 0, 256),
                         "a volume's temperature grid over the ramp, kelvin"),
}, "a ramp table")
