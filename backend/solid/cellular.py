"""Cellular (Worley) octave features for neural solid textures.

Value-noise octaves (:mod:`backend.solid.value_noise`, Henzler et al. 2020, Eq. 5)
have no closed outlines, straight edges or per-region constants, so a
pointwise decoder over them draws speckle where a photo has stones or
cobbles (docs/decisions/solid.md).  These
features add what a threshold can turn into a stone: for the first K octaves,
at the same transformed position as the value noise,

    p = 2^i T_i x                                                  (Eq. 5's argument)

Worley's cellular basis (Worley 1996, "A Cellular Texture Basis Function"):
one feature point per integer lattice cell at k + j(k), jitter j(k) in [0, 1)^D
from a hash of the cell, and

    F1(p) = min_k |p - k - j(k)|,   F2(p) = the second smallest,
    v(p)  = a random value in [-1, 1] of the cell whose point is nearest.

The decoder reads three values per cellular octave, (2 F1 - 1, 2 (F2 - F1) - 1, v):
distance to the cell centre (rounded stones), distance to the border (mortar
lines, cracks; F2 - F1 is 0 on the Voronoi edges) and a per-cell constant
(each stone its own shade).  Points are searched in the 3^D cells around p's
cell (the usual approximation: a point two cells away is rarely nearer).

The hash is the lattice's ``lowbias32`` chained over the cell coordinates from
a seed derived from the octave's seed, computed in int64 with 32-bit masks, so
this module and its torch twin (``training.solid.cellular``) find the same
cells.  The jitter takes 10 bits per axis of the cell hash, the cell value 10
bits of one more ``lowbias32`` of it.

Shapes: points (N, D) float, D in {2, 3}; transforms (m, D, D) float32 with
m >= K; result float32 (N, 3 K), octave-major (octave i, feature f at 3 i + f).
"""
from __future__ import annotations

import itertools

import numpy as np

from .value_noise import BITS, MASK32, check_feature_octaves, lowbias32, numba, octave_position, salted_seeds

__all__ = ["FEATURES", "CELL_SALT", "cell_seeds", "cellular_features", "cellular_features_numpy"]

FEATURES = 3                 #: values per cellular octave: 2 F1 - 1, 2 (F2 - F1) - 1, cell value
CELL_SALT = 0x68E31DA4       #: separates the cells' hash stream from the value noise's
_LEVELS = (1 << BITS) - 1


def cell_seeds(seed: int, octaves: int) -> np.ndarray:
    """Per-octave seeds of the feature-point lattices: int64 (octaves,)."""
    return salted_seeds(seed, octaves, CELL_SALT)


def offsets(dim: int) -> list:
    """The 3^D neighbour cell offsets, in the order both implementations search them."""
    return list(itertools.product((-1, 0, 1), repeat=dim))


def cellular_features_numpy(points, transforms, seed: int, octaves: int) -> np.ndarray:
    """Reference numpy implementation of the features (see module doc): float32 (N, 3 octaves)."""
    points, transforms = check_feature_octaves(points, transforms, octaves, "cellular")
    N, D = points.shape
    seeds = cell_seeds(seed, transforms.shape[0])
    x = points.astype(np.float64)
    out = np.empty((N, FEATURES * octaves), np.float32)
    for i in range(octaves):
        p = octave_position(x, transforms, i)
        fl = np.floor(p)
        f = p - fl
        k = fl.astype(np.int64)
        f1 = np.full(N, np.inf)
        f2 = np.full(N, np.inf)
        val = np.zeros(N)
        for off in offsets(D):
            h = np.full(N, seeds[i], np.int64)
            for d in range(D):
                h = lowbias32((h + ((k[:, d] + off[d]) & MASK32)) & MASK32)
            d2 = np.zeros(N)
            for d in range(D):
                j = ((h >> (BITS * d)) & _LEVELS).astype(np.float64) * (1.0 / (_LEVELS + 1))
                d2 += (off[d] + j - f[:, d]) ** 2
            v = (lowbias32(h) & _LEVELS).astype(np.float64) * (2.0 / _LEVELS) - 1.0
            nearer = d2 < f1
            f2 = np.where(nearer, f1, np.minimum(f2, d2))
            f1 = np.where(nearer, d2, f1)
            val = np.where(nearer, v, val)
        F1, F2 = np.sqrt(f1), np.sqrt(f2)
        out[:, 3 * i] = 2.0 * F1 - 1.0
        out[:, 3 * i + 1] = 2.0 * (F2 - F1) - 1.0
        out[:, 3 * i + 2] = val
    return out


if numba is not None:
    from .value_noise import lowbias32_jit, octave_coord

    @numba.njit(parallel=True, cache=True, nogil=True)
    def _cell_kernel(x, T, seeds, K, offs, out):
        N, D = x.shape
        for n in numba.prange(N):
            p = np.empty(3)
            k = np.empty(3, np.int64)
            for i in range(K):
                for a in range(D):
                    pa = octave_coord(T, x, n, i, a)
                    fa = np.floor(pa)
                    p[a] = pa - fa
                    k[a] = np.int64(fa)
                f1 = np.inf
                f2 = np.inf
                val = 0.0
                for o in range(offs.shape[0]):
                    h = seeds[i]
                    for a in range(D):
                        h = lowbias32_jit((h + ((k[a] + offs[o, a]) & 0xFFFFFFFF)) & 0xFFFFFFFF)
                    d2 = 0.0
                    for a in range(D):
                        j = ((h >> (10 * a)) & 1023) * (1.0 / 1024.0)
                        t = offs[o, a] + j - p[a]
                        d2 += t * t
                    if d2 < f1:
                        f2 = f1
                        f1 = d2
                        val = (lowbias32_jit(h) & 1023) * (2.0 / 1023.0) - 1.0
                    elif d2 < f2:
                        f2 = d2
                F1 = np.sqrt(f1)
                out[n, 3 * i] = 2.0 * F1 - 1.0
                out[n, 3 * i + 1] = 2.0 * (np.sqrt(f2) - F1) - 1.0
                out[n, 3 * i + 2] = val


def cellular_features(points, transforms, seed: int, octaves: int) -> np.ndarray:
    """Cellular features of the first ``octaves`` octaves (see module doc): float32 (N, 3 octaves).

    The compiled kernel when numba is importable (it releases the GIL), else
    :func:`cellular_features_numpy`; both give the same values to float32 rounding.
    """
    points, transforms = check_feature_octaves(points, transforms, octaves, "cellular")
    if numba is None:
        return cellular_features_numpy(points, transforms, seed, octaves)
    out = np.empty((points.shape[0], FEATURES * octaves), np.float32)
    _cell_kernel(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(transforms),
                 cell_seeds(seed, transforms.shape[0]), octaves,
                 np.array(offsets(points.shape[1]), np.int64), out)
    return out
