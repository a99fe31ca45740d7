"""Lattice value noise for neural solid textures (Henzler et al. 2020, Sec. 4, Eq. 5).

The sampler reads m = 8 octaves of a random field at transformed positions

    n_i = noise(T_i 2^(i-1) x | xi_i),   i = 1..m                     (Eq. 5)

where ``noise(. | xi)`` holds one random value per integer lattice point for
seed ``xi``.  Here each lattice point carries C <= 3 independent values (three
10-bit fields of one 32-bit hash, so the extra channels cost nothing) and the
values are blended with the smoothstep fade 3t^2 - 2t^3 along each axis (C1
across cell borders, unlike the paper's code, which blends linearly).  The
decoder never sees x itself, only these values.

The hash is ``lowbias32`` (Chris Wellons' 32-bit integer hash) chained over
the lattice coordinates, computed in int64 with 32-bit masks, so numpy, numba
and the torch training code (``training.solid.value_noise``) produce the
same lattice values bit for bit.

Shapes: points (N, D) float, D in {2, 3}; transforms (m, D, D) float32;
result (N, m*C) float32 in [-1, 1], octave-major (octave i, channel c at i*C + c).
"""
from __future__ import annotations

import numpy as np

__all__ = ["MASK32", "BITS", "MAX_CHANNELS", "lowbias32", "octave_seeds", "salted_seeds", "value_noise",
           "lattice_noise_numpy", "fast_available", "check_points", "check_feature_octaves", "octave_position"]

MASK32 = 0xFFFFFFFF
BITS = 10                 #: bits per channel value
MAX_CHANNELS = 3          #: 3 * 10 bits fit one 32-bit hash
_LEVELS = (1 << BITS) - 1

try:  # optional compiled path; Blender's Python has no numba and uses the numpy path
    import numba
except ImportError:  # pragma: no cover - exercised inside Blender
    numba = None


def fast_available() -> bool:
    return numba is not None


def lowbias32(x):
    """32-bit integer hash (xor-shift-multiply) of int64 values in [0, 2^32); int64 out, same range."""
    x = x ^ (x >> 16)
    x = (x * 0x7FEB352D) & MASK32
    x = x ^ (x >> 15)
    x = (x * 0x846CA68B) & MASK32
    return x ^ (x >> 16)


def octave_seeds(seed: int, octaves: int) -> np.ndarray:
    """The per-octave seeds xi_i of Eq. 5 for a user seed: int64 (octaves,)."""
    base = lowbias32(int(seed) & MASK32)          # Python ints: exact, no overflow
    return np.array([lowbias32((base + (i + 1) * 0x9E3779B9) & MASK32) for i in range(octaves)], dtype=np.int64)


def salted_seeds(seed: int, octaves: int, salt: int) -> np.ndarray:
    """Per-octave seeds of another hash stream (cellular, brick features): int64 (octaves,),
    lowbias32(xi_i ^ salt), so each stream is independent of the value noise's."""
    return lowbias32((octave_seeds(seed, octaves) ^ salt) & MASK32)


def check_points(points, transforms, channels):
    points = np.asarray(points)
    transforms = np.asarray(transforms, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError(f"points must have shape (N, 2) or (N, 3), got {points.shape}")
    D = points.shape[1]
    if transforms.ndim != 3 or transforms.shape[1:] != (D, D):
        raise ValueError(f"transforms must have shape (octaves, {D}, {D}) for {D}D points, got {transforms.shape}")
    if not 1 <= channels <= MAX_CHANNELS:
        raise ValueError(f"channels must be 1..{MAX_CHANNELS}, got {channels}")
    return points, transforms


def check_feature_octaves(points, transforms, octaves: int, family: str):
    """:func:`check_points` for a feature family read at the first ``octaves`` octaves; ValueError names the family."""
    points, transforms = check_points(points, transforms, 1)
    if not 0 <= octaves <= transforms.shape[0]:
        raise ValueError(f"{family} octaves must be 0..{transforms.shape[0]}, got {octaves}")
    return points, transforms


def octave_position(x: np.ndarray, transforms: np.ndarray, i: int) -> np.ndarray:
    """p = T_i 2^(i-1) x (Eq. 5; octave index i from 0 here): x float64 (N, D) -> float64 (N, D)."""
    return (x @ transforms[i].astype(np.float64).T) * float(2 ** i)


def lattice_noise_numpy(points, transforms, seed: int, channels: int = 3) -> np.ndarray:
    """Reference numpy implementation of the octave noise n (see module doc): float32 (N, m*C)."""
    points, transforms = check_points(points, transforms, channels)
    N, D = points.shape
    m = transforms.shape[0]
    seeds = octave_seeds(seed, m)
    x = points.astype(np.float64)
    out = np.empty((N, m * channels), np.float32)
    for i in range(m):
        p = octave_position(x, transforms, i)
        fl = np.floor(p)
        t = p - fl
        w1 = t * t * (3.0 - 2.0 * t)
        k = fl.astype(np.int64)
        acc = np.zeros((N, channels))
        for corner in range(1 << D):
            h = np.full(N, seeds[i], np.int64)
            wt = np.ones(N)
            for d in range(D):
                bit = (corner >> d) & 1
                h = lowbias32((h + ((k[:, d] + bit) & MASK32)) & MASK32)
                wt = wt * (w1[:, d] if bit else 1.0 - w1[:, d])
            for c in range(channels):
                v = ((h >> (BITS * c)) & _LEVELS).astype(np.float64) * (2.0 / _LEVELS) - 1.0
                acc[:, c] += wt * v
        out[:, i * channels:(i + 1) * channels] = acc
    return out


if numba is not None:
    @numba.njit(cache=True, inline="always")
    def lowbias32_jit(x):
        x = x ^ (x >> 16)
        x = (x * 0x7FEB352D) & 0xFFFFFFFF
        x = x ^ (x >> 15)
        x = (x * 0x846CA68B) & 0xFFFFFFFF
        return x ^ (x >> 16)

    @numba.njit(cache=True, inline="always")
    def octave_coord(T, x, n, i, a):
        """Coordinate a of 2^i T_i x_n in float64, as :func:`octave_position` computes it."""
        acc = 0.0
        for b in range(x.shape[1]):
            acc += np.float64(T[i, a, b]) * x[n, b]
        return acc * (1 << i)

    @numba.njit(parallel=True, cache=True, nogil=True)
    def _noise_kernel(x, T, seeds, C, out):
        N, D = x.shape
        m = T.shape[0]
        for n in numba.prange(N):
            w = np.empty(3)
            k = np.empty(3, np.int64)
            for i in range(m):
                for a in range(D):
                    pa = octave_coord(T, x, n, i, a)
                    f = np.floor(pa)
                    t = pa - f
                    w[a] = t * t * (3.0 - 2.0 * t)
                    k[a] = np.int64(f)
                v0 = 0.0
                v1 = 0.0
                v2 = 0.0
                for corner in range(1 << D):
                    h = seeds[i]
                    wt = 1.0
                    for a in range(D):
                        bit = (corner >> a) & 1
                        h = lowbias32_jit((h + ((k[a] + bit) & 0xFFFFFFFF)) & 0xFFFFFFFF)
                        wt *= w[a] if bit else 1.0 - w[a]
                    v0 += wt * ((h & 1023) * (2.0 / 1023.0) - 1.0)
                    v1 += wt * (((h >> 10) & 1023) * (2.0 / 1023.0) - 1.0)
                    v2 += wt * (((h >> 20) & 1023) * (2.0 / 1023.0) - 1.0)
                out[n, i * C] = v0
                if C > 1:
                    out[n, i * C + 1] = v1
                if C > 2:
                    out[n, i * C + 2] = v2


def value_noise(points, transforms, seed: int, channels: int = 3) -> np.ndarray:
    """Octave noise n of Eq. 5: points (N, D), transforms (m, D, D) -> float32 (N, m*C).

    Uses the compiled kernel when numba is importable (it releases the GIL, so a
    worker thread leaves Blender's UI responsive), else :func:`lattice_noise_numpy`;
    both give the same values to float32 rounding.
    """
    points, transforms = check_points(points, transforms, channels)
    if numba is None:
        return lattice_noise_numpy(points, transforms, seed, channels)
    out = np.empty((points.shape[0], transforms.shape[0] * channels), np.float32)
    _noise_kernel(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(transforms),
                  octave_seeds(seed, transforms.shape[0]), channels, out)
    return out
