"""The colours a ramp by luminance leaves out: a tint along the photo's main colour axis, from its own noise.

A family's ramp (ramp.py) gives every point the mean colour of the photo's pixels of its luminance rank, so a
forest floor's green moss and brown leaves of one luminance come out as one olive.  The tint puts back the main
share of what that leaves out: the photo's residual r = pixel - the mean colour of its luminance group (the ramp's
colour for it), its first principal axis a (the covariance's top eigenvector, float (3,)) and the distribution of
the scores z = r . a, drawn independently of the family's value by a wave noise u of its own (the turbulence's
noise for the field's seed + SEED_OFFSET, turbulence.py) through a ramp that matches ranks (histogram matching,
Heeger & Bergen 1995, Sec. 3.2, as the colour ramp does):

    rgb(x) = ramp(s(x)) + Q(u(f x)) a,      Q: the quantiles of u -> the STOPS group means of the sorted z

Q is piecewise linear between its stops (constant beyond the ends), as the colour ramp is; its stops sit at the
quantiles of u over a block of space many of its wavelengths wide (u is stationary and read at f x, so the stops
hold for every frequency f): an artist turning the node group's Tint Frequency keeps the photo's distribution of z.
The offsets are added before the clip to [0, 1].

Shapes: photo float (H, W, 3) sRGB; points float (P, 3) in texture units -> offsets float32 (P, 3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ramp import STOPS, luminance_groups, quantile_stops
from .turbulence import turbulence

__all__ = ["Tint", "fit_tint", "colour_axis", "FREQUENCIES", "SEED_OFFSET"]

FREQUENCIES = (2.0, 4.0)         #: the tint noise's lowest frequencies a fit tries, cycles per unit
SEED_OFFSET = 5                  #: the tint noise's seed is the field's plus this (turbulence, grain, detail: +0..2)
BLOCK = 8.0                      #: the stops' block of space: [-BLOCK, BLOCK]^3 at 1 cycle per unit


@dataclass(frozen=True)
class Tint:
    """``frequency`` (cycles per unit) of the tint noise u; Q's ``positions`` (K,) strictly increasing values of u and
    ``levels`` (K,) of z; ``axis`` (3,) the unit colour axis a."""
    frequency: float
    positions: tuple
    levels: tuple
    axis: tuple

    def amount(self, points: np.ndarray, seed: int) -> np.ndarray:
        """Q(u(f x)) at points float (P, 3) of the field drawn with ``seed`` -> float64 (P,)."""
        u = turbulence(points, self.frequency, seed + SEED_OFFSET)
        return np.interp(u.astype(np.float64), self.positions, self.levels)

    def __call__(self, points: np.ndarray, seed: int) -> np.ndarray:
        """The offsets Q(u(f x)) a at points float (P, 3) of the field drawn with ``seed`` -> float32 (P, 3)."""
        return (self.amount(points, seed)[:, None] * np.asarray(self.axis)).astype(np.float32)

    def to_dict(self) -> dict:
        return dict(frequency=float(self.frequency), positions=[float(v) for v in self.positions],
                    levels=[float(v) for v in self.levels], axis=[float(v) for v in self.axis])

    @staticmethod
    def from_dict(d: dict) -> "Tint":
        return Tint(float(d["frequency"]), tuple(map(float, d["positions"])), tuple(map(float, d["levels"])),
                    tuple(map(float, d["axis"])))


def colour_axis(photo: np.ndarray, stops: int = STOPS) -> tuple:
    """(a float64 (3,), levels float64 (stops,) increasing): the first principal axis of the photo's colour less
    its luminance group's mean (ramp.luminance_groups, the groups of the ramp's colours), and the scores along it
    split into ``stops`` groups of equal size by rank, each group's mean."""
    px, groups = luminance_groups(photo, stops)
    rest = np.empty_like(px)
    for g in groups:
        rest[g] = px[g] - px[g].mean(0)
    a = np.linalg.eigh(np.cov(rest.T))[1][:, -1]
    z = np.sort(rest @ a)
    return a, np.array([g.mean() for g in np.array_split(z, stops)])


def fit_tint(photo: np.ndarray, frequency: float, seed: int) -> Tint:
    """The photo's tint (module doc) drawn at ``frequency`` by the field of ``seed``."""
    a, levels = colour_axis(photo)
    block = np.random.default_rng(seed).uniform(-BLOCK, BLOCK, (1 << 15, 3))
    stops = quantile_stops(turbulence(block, 1.0, seed + SEED_OFFSET), len(levels))
    return Tint(float(frequency), stops, tuple(float(z) for z in levels), tuple(float(v) for v in a))
