"""What a procedural solid family is: named parameters with their ranges, starts read off the photo, and a value
s at every point of space that the fitted ramp (ramp.py) turns into the photo's colours.

Every family takes the same shared settings: ``turbulence`` (amplitude, in the family's own units of s) and
``turb_freq`` (cycles per unit) of the wave noise that bends it (turbulence.py), ``detail`` (the amplitude of a
fine wave noise from DETAIL_FREQ cycles per unit added to s: a photo's grain within stones, bricks and rings) and
``flip`` (the ramp's order).
The search (search.py) moves each parameter within its range, scale parameters on a log axis.

Shapes: points float (P, 3) in texture units (x right, y back, z up; the photo stands on the walls, x right and
z up); values float64 (P,).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...limits import MAX_COORD
from ...schema import shown_value
from ...wavenoise.hashing import white_noise4
from .turbulence import turbulence

__all__ = ["Param", "Family", "cell_random", "axis_vector", "axis_angles", "dot3", "gapped", "inside", "SHARED",
           "DETAIL_FREQ", "MAX_PARAM"]

DETAIL_FREQ = 16.0    #: the detail noise's lowest frequency, cycles per unit (8 photo px at 128 px per unit)
#: the largest magnitude of any parameter a drawn solid takes (a length, a frequency, an angle, the rings' centre):
#: the value is drawn in float32, where 1e300 turns infinite and the solid NaN (limits.MAX_COORD)
MAX_PARAM = MAX_COORD


@dataclass(frozen=True)
class Param:
    """A parameter ``name`` searched in [lo, hi] (``log``: on a log axis); ``doc`` says what it is and its unit.
    A solid drawn with edited parameters (the node group's inputs, a saved solid) keeps ``lo`` as its least value
    where ``floor`` (a length, size or frequency above 0, an amplitude at least 0; not an angle or an offset) and
    ``hi`` as its greatest where ``cap`` (a share of a unit, a cube or a course), and every one within
    +-:data:`MAX_PARAM`: :meth:`check`."""
    name: str
    lo: float
    hi: float
    log: bool = False
    doc: str = ""
    floor: bool = True
    cap: bool = False

    def check(self, v) -> float:
        """``v`` as a float where a drawn solid can take it (``floor``, ``cap``); ValueError naming it where not."""
        ok = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))
        v = float(v) if ok else v
        if not ok or not np.isfinite(v):
            raise ValueError(f"{self.name} must be a finite number, got {shown_value(v)}")
        if abs(v) > MAX_PARAM:
            raise ValueError(f"{self.name} must lie within +-{MAX_PARAM:g}, got {v!r}")
        if self.cap and not self.lo <= v <= self.hi:
            raise ValueError(f"{self.name} must be in [{self.lo}, {self.hi}], got {v!r}")
        if self.floor and v < self.lo:
            raise ValueError(f"{self.name} must be at least {self.lo}, got {v!r}")
        return v

    def to_unit(self, v: float) -> float:
        """The value as a search coordinate in [0, 1]."""
        if self.log:
            return float(np.log(v / self.lo) / np.log(self.hi / self.lo))
        return float((v - self.lo) / (self.hi - self.lo))

    def from_unit(self, u: float) -> float:
        """A search coordinate (clipped to [0, 1]) as the value."""
        u = min(max(float(u), 0.0), 1.0)
        return float(self.lo * (self.hi / self.lo) ** u) if self.log else float(self.lo + u * (self.hi - self.lo))


#: the settings every family shares
SHARED = (Param("turbulence", 0.0, 2.0, doc="how far the wave noise moves the value (the family's units of s)"),
          Param("turb_freq", 0.25, 16.0, log=True, doc="the wave noise's lowest frequency, cycles per unit"),
          Param("detail", 0.0, 1.0, doc="the fine noise's amplitude (the family's units of s)"))


class Family:
    """A procedural solid family: ``name``, ``PARAMS`` (its own, then :data:`SHARED`), ``starts(est)`` (a few
    parameter dicts read off the photo's :class:`~.estimate.Estimates`) and ``shape(params, points, seed)``, the family's value before the detail noise."""
    name = ""
    PARAMS: tuple = ()
    doc = ""
    GAPPED = False      #: whether its cells or units have gaps between them (:meth:`gaps`)

    def params(self) -> tuple:
        return tuple(self.PARAMS) + SHARED

    def starts(self, est) -> list:
        raise NotImplementedError

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        raise NotImplementedError

    def gaps(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        """The gap mask at points float (P, 3) -> float64 (P,): 1 in a gap or joint, 0 inside a cell or unit,
        1 - :func:`inside` between; only for the families with gaps (``GAPPED``)."""
        raise NotImplementedError(f"{self.name} has no gaps")

    def values(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        """The value s at points float (P, 3) -> float64 (P,): the family's shape plus the detail noise."""
        s = self.shape(p, points, seed)
        if p.get("detail", 0.0) > 0:
            s = s + p["detail"] * turbulence(points, DETAIL_FREQ, seed + 2)
        return s

    def check(self, p: dict) -> dict:
        """``p``'s parameters, each present and one a drawn solid can take (:meth:`Param.check`: a fit's are within
        their search ranges, an artist's edits may leave them), as floats; ValueError naming one that is not."""
        out = {}
        for q in self.params():
            if q.name not in p:
                raise ValueError(f"{self.name}: parameter {q.name!r} is missing")
            try:
                out[q.name] = q.check(p[q.name])
            except ValueError as exc:
                raise ValueError(f"{self.name}: {exc}") from None
        return out


def inside(dist: np.ndarray, half: float) -> np.ndarray:
    """How far a point lies inside its cell or unit, float64 in [0, 1]: 0 in a gap (``dist`` < ``half`` from its
    edge), 1 beyond 2 ``half``, linear between: e = clip(dist / half - 1, 0, 1)."""
    return np.clip(np.asarray(dist, np.float64) / max(half, 1e-9) - 1.0, 0.0, 1.0)


def gapped(dist: np.ndarray, half: float, r: np.ndarray, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
    """The value of cells and units with gaps between them: -1 in a gap, the unit's own 1 + r + turbulence where
    :func:`inside` is 1, linear between:

        e = inside(dist, half),    s = e (1 + r + turbulence * T(p)) - 1
    """
    e = inside(dist, half)
    inner = 1.0 + r
    if p["turbulence"] > 0:
        inner = inner + p["turbulence"] * turbulence(points, p["turb_freq"], seed)
    return e * inner - 1.0


def cell_random(i, j, k, seed: int) -> np.ndarray:
    """A number in [0, 1] per integer cell (i, j, k) and seed: Blender's White Noise of (i, j, k, seed), so the node
    group draws the same (wavenoise/hashing.py)."""
    return white_noise4(np.asarray(i, np.float32), np.asarray(j, np.float32), np.asarray(k, np.float32),
                        np.float32(int(seed) % (1 << 24))).astype(np.float64)


def axis_vector(tilt: float, azimuth: float) -> np.ndarray:
    """The unit vector ``tilt`` radians from +z, turned ``azimuth`` radians about z from +x: float64 (3,)."""
    return np.array([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), np.cos(tilt)])


def axis_angles(v) -> tuple:
    """(tilt, azimuth) of the direction of ``v`` (3,), not 0: :func:`axis_vector`'s inverse (azimuth in (-pi, pi];
    0 along z); ValueError for a vector of no length or not finite."""
    v = np.asarray(v, np.float64)
    n = float(np.linalg.norm(v))
    if not (np.isfinite(n) and n > 1e-12):
        raise ValueError(f"a direction must have a length, got {tuple(float(x) for x in v)}")
    d = v / n
    return float(np.arccos(np.clip(d[2], -1.0, 1.0))), float(np.arctan2(d[1], d[0]))


def dot3(points: np.ndarray, v: np.ndarray) -> np.ndarray:
    """points float (P, 3) . v (3,) -> float64 (P,), as three products and two sums in numpy rather than a matrix
    product: OpenBLAS runs a product of P rows on all its threads, which then wait, spinning, for the next, and
    keep a core from the wave-noise kernel's threads (a board's fit without numba: 13.0 s with the matrix product,
    11.4 s with this; medians of three)."""
    pts = np.asarray(points, np.float64)
    return pts[:, 0] * v[0] + pts[:, 1] * v[1] + pts[:, 2] * v[2]
