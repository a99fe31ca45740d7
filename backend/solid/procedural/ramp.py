"""The photo's colours along a procedural solid's value: a colour ramp fitted by ranks.

A family's value s (rings' phase, a layer's height, a cell's random number) says which of the photo's colours a
point takes.  The ramp puts its stops at the quantiles of s and gives each the mean colour of the photo's pixels of
the same luminance rank, so that the solid's colours are distributed as the photo's (histogram matching through
the luminance order, Heeger & Bergen 1995, Sec. 3.2) and bright stays bright: the order of s is the order of the
photo's luminance, reversed where ``flip``.  Between stops the colours are linear in s, as Blender's Color Ramp
node reads them (linear interpolation, constant beyond the ends), so the node group reproduces it exactly.

Shapes: values float (P,); colours float32 (P, 3) sRGB in [0, 1].
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Ramp", "fit_ramp", "photo_colours", "luminance_groups", "quantile_stops", "STOPS", "luminance"]

STOPS = 16    #: stops per ramp (Blender's Color Ramp holds at most 32)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luma of sRGB values (..., 3) -> (...)."""
    return np.asarray(rgb, np.float64)[..., :3] @ np.array([0.2126, 0.7152, 0.0722])


@dataclass(frozen=True)
class Ramp:
    """``positions`` (K,) strictly increasing values of s and ``colours`` (K, 3) sRGB: linear between, constant
    beyond the ends."""
    positions: tuple
    colours: tuple

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """values float (P,) -> float32 (P, 3)."""
        x, c = np.asarray(self.positions, np.float64), np.asarray(self.colours, np.float64)
        s = np.asarray(s, np.float64)
        return np.stack([np.interp(s, x, c[:, k]) for k in range(3)], axis=-1).astype(np.float32)

    def to_dict(self) -> dict:
        return dict(positions=[float(p) for p in self.positions], colours=[[float(v) for v in c] for c in self.colours])

    @staticmethod
    def from_dict(d: dict) -> "Ramp":
        return Ramp(tuple(float(p) for p in d["positions"]), tuple(tuple(float(v) for v in c) for c in d["colours"]))


def luminance_groups(photo: np.ndarray, stops: int = STOPS) -> tuple:
    """(the photo's pixels float64 (N, 3), ``stops`` arrays of their indices): groups of equal size by luminance
    rank, darkest first."""
    px = np.asarray(photo, np.float64)[..., :3].reshape(-1, 3)
    return px, np.array_split(np.argsort(luminance(px), kind="stable"), stops)


def photo_colours(photo: np.ndarray, stops: int = STOPS) -> np.ndarray:
    """The mean colour of each of the photo's :func:`luminance_groups`, darkest first: float64 (stops, 3)."""
    px, groups = luminance_groups(photo, stops)
    return np.stack([px[g].mean(0) for g in groups])


def fit_ramp(values: np.ndarray, colours: np.ndarray, flip: bool = False) -> Ramp:
    """A ramp whose stops sit at the quantiles of ``values`` (K group centres, K = len(colours)) and carry
    ``colours`` (darkest first: :func:`photo_colours`), reversed where ``flip`` (:func:`quantile_stops`)."""
    c = np.asarray(colours, np.float64)[::-1] if flip else np.asarray(colours, np.float64)
    return Ramp(quantile_stops(values, len(c)), tuple(tuple(float(v) for v in row) for row in np.clip(c, 0.0, 1.0)))


def quantile_stops(values: np.ndarray, k: int) -> tuple:
    """``k`` strictly increasing stops at the quantiles (i + 1/2) / k of ``values``: ties (a value many points
    share, such as a joint's) spread by a hair."""
    q = np.quantile(np.asarray(values, np.float64), (np.arange(k) + 0.5) / k)
    span = max(float(q[-1] - q[0]), 1e-6)
    return tuple(float(v) for v in q + np.arange(k) * span * 1e-6)
