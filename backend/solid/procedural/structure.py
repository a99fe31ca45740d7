"""What a photo's structure is, read as two numbers a solid's wall cuts can be held to: which way it runs and
whether it repeats as a grid.

Patch statistics (band_distance.py) compare neighbourhoods a few pixels wide; they do not see that a photo's planks
all run one way or that its tiles repeat across and up, and a solid of stones or blotches can be closer by them
than a texture that keeps the planks and the grid.  The fit's check (fit.py) and auto (choose.py) read these too:

- **Orientation**: the structure tensor of the luminance's gradient summed over the image (Bigün & Granlund 1987),
  J = [[Jxx, Jxz], [Jxz, Jzz]], as the vector ((Jxx - Jzz) / tr J, 2 Jxz / tr J): its length is the coherence
  (0 for no preferred direction, 1 for straight parallel stripes) and its angle twice the direction across them,
  so planks standing up and planks lying down read as opposite vectors.
- **Lattice**: the band-passed autocorrelation one repeat across and one repeat up (the repeats the photo's own
  autocorrelation reads, estimate.py), the lower of the two: near 1 where the image is itself shifted by a tile
  either way, near 0 for stones, blotches and grain.  It is read with the mean over the overlap (the image padded
  with zeros), so that a cut holding only two or three tiles reads its repeats as the photo does.

A solid's walls are its cuts across x and across y (the photo stands upright on both).  The structure error of a
set of cuts is |orientation - the photo's| + |lattice - the photo's|; one texture holds the photo's structure
better than another where its error is lower by more than :data:`TOLERANCE`.

Shapes: images float (H, W, 3) sRGB, top row first; lags in px.
"""
from __future__ import annotations

import numpy as np

from ..band_distance import central_crop
from .estimate import at_lag, band_transfer, repeats
from .ramp import luminance

__all__ = ["orientation", "lattice", "readings", "structure_error", "photo_readings", "photo_structure", "TOLERANCE"]

#: a difference of structure errors that counts: the fit's check and auto keep a texture whose walls hold the photo's
#: structure worse than another's only by less than this
TOLERANCE = 0.15


def orientation(image: np.ndarray) -> np.ndarray:
    """The orientation vector of an image (module doc) -> float64 (2,), length in [0, 1]."""
    lum = luminance(np.asarray(image, np.float64))
    gz, gx = -np.gradient(lum, axis=0), np.gradient(lum, axis=1)          # z up
    xx, zz, xz = np.sum(gx * gx), np.sum(gz * gz), np.sum(gx * gz)
    tr = xx + zz
    return np.zeros(2) if tr <= 1e-12 else np.array([(xx - zz) / tr, 2.0 * xz / tr])


def lattice(image: np.ndarray, across: float, up: float) -> float:
    """The lattice reading of an image (module doc) at repeats ``across`` and ``up`` px (read at most 3/4 of its
    sides away: farther, the overlap is a strip)."""
    lum = luminance(np.asarray(image, np.float64))
    H, W = lum.shape
    padded = np.zeros((2 * H, 2 * W))
    padded[:H, :W] = lum - lum.mean()
    ac = np.real(np.fft.ifft2(np.abs(np.fft.fft2(padded) * band_transfer(2 * H, 2 * W)) ** 2))
    ones = np.zeros((2 * H, 2 * W))
    ones[:H, :W] = 1.0
    overlap = np.real(np.fft.ifft2(np.abs(np.fft.fft2(ones)) ** 2))
    ac = ac / np.maximum(overlap, 1.0)
    if ac[0, 0] <= 1e-12:
        return 0.0
    ac = ac / ac[0, 0]
    return float(min(at_lag(ac, min(across, 0.75 * W), 0.0), at_lag(ac, 0.0, min(up, 0.75 * H))))


def readings(images: list, across: float, up: float) -> np.ndarray:
    """(orientation x, orientation z, lattice) of a set of images, each the mean over them -> float64 (3,)."""
    o = np.mean([orientation(im) for im in images], axis=0)
    return np.array([o[0], o[1], np.mean([lattice(im, across, up) for im in images])])


def photo_readings(photo: np.ndarray, longest: float) -> tuple:
    """(the photo's :func:`readings`, (across, up)): its repeats in px as estimate reads them, at most ``longest``
    (3/4 of the side of the cuts that will be read at them, so that the photo and the cuts are read at one lag)."""
    lags = tuple(min(float(r), float(longest)) for r in repeats(photo))
    return readings([photo], *lags), lags


def photo_structure(photo: np.ndarray, side: int) -> tuple:
    """:func:`photo_readings` of the photo's central crop of twice ``side`` px at its own scale, at lags that cuts
    of ``side`` px can hold (3/4 of it): what walls drawn ``side`` px a side at the photo's px per unit are held to."""
    return photo_readings(central_crop(np.asarray(photo, np.float64), 2 * side), 0.75 * side)


def structure_error(images: list, photo: np.ndarray, lags: tuple) -> float:
    """How far a set of cuts' structure is from the photo's: the distance between their orientation vectors plus the
    difference of their lattice readings (``photo``: the photo's :func:`readings`; ``lags``: its repeats, px)."""
    r = readings(images, *lags)
    return float(np.hypot(*(r[:2] - photo[:2])) + abs(r[2] - photo[2]))
