"""Staggered-lattice (brick) octave features for neural solid textures.

Value noise and Worley cells (:mod:`backend.solid.value_noise`,
:mod:`backend.solid.cellular`) have no courses: rows of regions of one height
with joints offset from row to row, as in brick and block walls, plank floors,
ashlar and setts laid in courses.  Blender's Brick Texture node draws such a
lattice; here it is a feature the decoder reads, at the same transformed
position as octave i's value noise,

    p = 2^i T_i x                                                  (Eq. 5's argument)

rows r = floor(p_1) (the second axis); along the others the lattice is shifted
by half a cell in odd rows, q_a = p_a + (r mod 2) / 2 for a != 1.  Per octave
three values:

    2 d_row - 1     d_row = 2 min(fract p_1, 1 - fract p_1): 0 on a bed joint, 1 mid-row
    2 d_joint - 1   d_joint = min over a != 1 of 2 min(fract q_a, 1 - fract q_a): 0 on a head joint
    v               a random value in [-1, 1] of the brick (r, floor q_a), from the lattice's hash

The transform T_i sets the bricks' size, proportions and orientation (a
learned T stretches cells into bricks or planks).  The hash is ``lowbias32``
chained over (r, floor q_a) from a seed derived from the octave's seed, in
int64 with 32-bit masks, as the torch twin ``training.solid.brick`` computes it.

Shapes: points (N, D) float, D in {2, 3}; transforms (m, D, D) float32 with
m >= K; result float32 (N, 3 K), octave-major (octave i, feature f at 3 i + f).
"""
from __future__ import annotations

import numpy as np

from .value_noise import BITS, MASK32, check_feature_octaves, lowbias32, octave_position, salted_seeds

__all__ = ["FEATURES", "BRICK_SALT", "brick_seeds", "brick_features"]

FEATURES = 3                 #: values per brick octave: bed joint distance, head joint distance, brick value
BRICK_SALT = 0x2C1B3C6D      #: separates the bricks' hash stream from the value noise's and the cells'
_LEVELS = (1 << BITS) - 1


def brick_seeds(seed: int, octaves: int) -> np.ndarray:
    """Per-octave seeds of the brick lattices: int64 (octaves,)."""
    return salted_seeds(seed, octaves, BRICK_SALT)


def _tri(t: np.ndarray) -> np.ndarray:
    """2 min(fract t, 1 - fract t): 0 at integers, 1 half-way."""
    f = t - np.floor(t)
    return 2.0 * np.minimum(f, 1.0 - f)


def brick_features(points, transforms, seed: int, octaves: int) -> np.ndarray:
    """Brick features of the first ``octaves`` octaves (see module doc): float32 (N, 3 octaves)."""
    points, transforms = check_feature_octaves(points, transforms, octaves, "brick")
    N, D = points.shape
    seeds = brick_seeds(seed, transforms.shape[0])
    x = points.astype(np.float64)
    out = np.empty((N, FEATURES * octaves), np.float32)
    others = [a for a in range(D) if a != 1]
    for i in range(octaves):
        p = octave_position(x, transforms, i)
        r = np.floor(p[:, 1])
        shift = 0.5 * (r.astype(np.int64) & 1)
        h = lowbias32((seeds[i] + (r.astype(np.int64) & MASK32)) & MASK32)
        joint = np.full(N, np.inf)
        for a in others:
            q = p[:, a] + shift
            h = lowbias32((h + (np.floor(q).astype(np.int64) & MASK32)) & MASK32)
            joint = np.minimum(joint, _tri(q))
        out[:, 3 * i] = 2.0 * _tri(p[:, 1]) - 1.0
        out[:, 3 * i + 1] = 2.0 * joint - 1.0
        out[:, 3 * i + 2] = (h & _LEVELS).astype(np.float64) * (2.0 / _LEVELS) - 1.0
    return out
