"""Random rotations of the octaves, one per octave seed ("spin").

Octave i's noise is read at a position turned by a rotation Q_i drawn from the
octave's seed xi_i (Eq. 5 of Henzler et al. 2020 with Q_i inserted), in one of
two places:

- ``"lattice"``: n_i = noise(Q_i T_i 2^(i-1) x).  The transform's stretch stays
  in world space and the lattice beneath it turns with every seed, so no
  stretch can line up with the lattice's diagonals.  A training option
  (``spin`` in a solid config); models must be trained with it.
- ``"octave"``: n_i = noise(T_i Q_i^T 2^(i-1) x).  Each octave's field, stretch
  and lattice together, is turned rigidly about the origin: the field of an
  octave looks as before, but its direction is the seed's.  The decoder reads
  every point's octave values, whose joint distribution a rotation does not
  change, so a model trained without spin draws with it what it learned,
  without the fixed direction that all octaves shared.  The space model's
  translator stretches octaves 3 and 6 along the same world diagonal for every
  photo (1.45 : 1): unturned, every front slice then leans one way and every
  floor the other (measured by the diagonal power of x, y and z slices).

Q_i is uniform on SO(D): in 3D from three hash uniforms by Shoemake's
quaternion construction (Graphics Gems III, 1992: q = (sqrt(1-u1) sin 2 pi u2,
sqrt(1-u1) cos 2 pi u2, sqrt(u1) sin 2 pi u3, sqrt(u1) cos 2 pi u3)); in 2D the
angle 2 pi u1.  The uniforms are lowbias32 chained from xi_i ^ SALT, computed
in float64 and rounded once to float32, so numpy and the torch training code
(which calls this function) give the same matrices.

Shapes: seeds int64 (..., m); result float32 (..., m, D, D).
"""
from __future__ import annotations

import numpy as np

from .value_noise import MASK32, lowbias32

__all__ = ["SALT", "MODES", "octave_spins", "spun", "check_mode"]

SALT = 0x2545F491   #: separates the spin's hash stream from the lattice values'
MODES = ("", "lattice", "octave")   #: no spin, spun lattices, turned octaves


def check_mode(mode) -> str:
    """``mode`` if it is one of :data:`MODES`, else ValueError naming the choices."""
    if mode not in MODES:
        raise ValueError(f"spin must be one of {', '.join(repr(m) for m in MODES)}, got {mode!r}")
    return mode


def _uniforms(seeds: np.ndarray, k: int) -> list:
    """k float64 uniforms in [0, 1) per seed, each array shaped like ``seeds``."""
    h = lowbias32((np.asarray(seeds, np.int64) ^ SALT) & MASK32)
    out = []
    for _ in range(k):
        out.append(h.astype(np.float64) / 2.0 ** 32)
        h = lowbias32((h + 0x9E3779B9) & MASK32)
    return out


def octave_spins(seeds, dim: int) -> np.ndarray:
    """Q_i per octave seed: seeds int64 (..., m) -> float32 (..., m, dim, dim), rotations (det +1)."""
    seeds = np.asarray(seeds, np.int64)
    if dim == 2:
        (u,) = _uniforms(seeds, 1)
        c, s = np.cos(2 * np.pi * u), np.sin(2 * np.pi * u)
        Q = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
        return Q.astype(np.float32)
    if dim != 3:
        raise ValueError(f"octave spins need 2 or 3 dimensions, got {dim}")
    u1, u2, u3 = _uniforms(seeds, 3)
    a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
    x, y, z, w = a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2), b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)
    Q = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], -2)
    return Q.astype(np.float32)


def spun(transforms: np.ndarray, seeds, mode: str = "lattice") -> np.ndarray:
    """The octaves' transforms with their spin: Q_i T_i (``"lattice"``) or T_i Q_i^T (``"octave"``), T_i for "";
    transforms float32 (m, D, D), octave seeds int64 (m,) -> float32 (m, D, D), the product in float64 rounded once."""
    T = np.asarray(transforms, np.float32)
    if not check_mode(mode):
        return T
    Q = octave_spins(seeds, T.shape[-1]).astype(np.float64)
    T64 = T.astype(np.float64)
    return (Q @ T64 if mode == "lattice" else T64 @ np.swapaxes(Q, -1, -2)).astype(np.float32)
