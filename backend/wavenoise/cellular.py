"""Cellular wave noise (Guehl et al. 2025, Sec. 6.3, Algorithm 2, Fig. 11).

Each stratum k contributes two families of parallel hyperplanes (Alg. 2's
``k = 0`` slices and ``k = 1`` waves): normals s_k (the slicing direction) and
omega_k (the stratum's wave direction).  Plane j of a family sits at
``j + slpos_j`` (slpos_j in [0.3, 0.7]) in units of the cell size C along the
normal.  Replacing the sum of waves by a min gives

* ``polytope``  distance to the nearest plane, min over families (world units):
                random-hyperplane polytopes with thin borders (Fig. 11a);
* ``code``      the slab index in every family, chained through the hash into a
                grey level in [0, 1]: a binary-code polytope id (Fig. 11c);
* ``stit``      STIT-like recursion (Fig. 11d): a cell splits with probability P
                (drawn from its code) by a new, finer set of families with random
                directions, up to ``depth`` levels.

All random numbers come from Blender's White Noise hash (see backend.wavenoise.hashing).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .directions import DirectionSet, map_directions
from ..errors import SettingError, check_points
from .hashing import MAX_EXACT_ID, white_noise4

__all__ = ["CellularNoise", "CELLULAR_MODES"]

_F = np.float32
CELLULAR_MODES = ("none", "polytope", "code", "stit")
_STREAM_NORMAL, _STREAM_OFFSET, _STREAM_PLANE, _STREAM_CODE, _STREAM_SPLIT, _STREAM_SUBDIR = 20, 24, 25, 26, 27, 28


@dataclass
class CellularResult:
    """distance: float32 (P,) to the nearest border, world units; cell: float32 (P,) grey id in [0, 1]."""

    distance: np.ndarray
    cell: np.ndarray


class CellularNoise:
    """Random-hyperplane cells from the strata of a DirectionSet.

    cell_size     C, world units between planes of one family
    probability   STIT split probability per cell and level
    depth         STIT levels (0 = plain polytopes)
    """

    def __init__(self, directions: DirectionSet, seed: int, cell_size: float,
                 probability: float = 0.5, depth: int = 0):
        if not 0 <= int(seed) < MAX_EXACT_ID:
            raise SettingError("seed", f"must lie in [0, {MAX_EXACT_ID}), got {seed}")
        if not cell_size > 0:
            raise SettingError("cell size", f"must be positive, got {cell_size}")
        if not 0.0 <= probability <= 1.0:
            raise SettingError("stit probability", f"must lie in [0, 1], got {probability}")
        if not 0 <= int(depth) <= 8:
            raise SettingError("stit depth", f"must lie in [0, 8], got {depth}")
        self.dirs = directions
        self.dim = directions.domains[0].dim
        self.seed = _F(int(seed))
        self.cell_size = float(cell_size)
        self.probability = _F(probability)
        self.depth = int(depth)
        r = directions.hashed_normals(self.seed, _STREAM_NORMAL)
        centres = directions.centres()
        #: family normals, two per stratum (slicing, wave): float32 (2K, D)
        self.normals = np.concatenate([r, centres]).astype(_F)

    @staticmethod
    def _nearest_plane(p, fam, stream, key, spacing):
        """Planes at j + slpos_j (slpos_j = 0.3 + 0.4 hash(fam, j, stream, key)) along p.

        Returns the distance to the nearest plane (world units) and the slab index.
        """
        j = np.floor(p)
        o = p - j
        j = j + _F(0.0)

        def pos(idx):
            return _F(0.3) + _F(0.4) * white_noise4(fam, idx, stream, key)

        here = pos(j)
        above = o >= here
        other = np.where(above, _F(1.0) + pos(j + _F(1.0)) - o, o + _F(1.0) - pos(j - _F(1.0)))
        dist = np.minimum(np.abs(o - here), other) * _F(spacing)
        return dist, np.where(above, j, j - _F(1.0))

    def _family(self, x, normal, fam: float, level: float, spacing: float):
        """Distance (world units) to the nearest plane and slab index for one family."""
        off = white_noise4(_F(fam), level, _F(_STREAM_OFFSET), self.seed)
        p = (x @ normal) * _F(1.0 / spacing) + off
        return self._nearest_plane(p, _F(fam), _F(_STREAM_PLANE) + level, self.seed, spacing)

    def evaluate(self, x: np.ndarray) -> CellularResult:
        """x: float32 (P, dim) -> CellularResult."""
        x = check_points(x, (self.dim,), _F)
        dist = np.full(len(x), np.inf, _F)
        code = np.zeros(len(x), _F)
        for f, normal in enumerate(self.normals):
            d, slab = self._family(x, normal, f, _F(0), self.cell_size)
            dist = np.minimum(dist, d)
            code = white_noise4(slab, code, _F(_STREAM_CODE), self.seed)
        # STIT-like recursion: split some cells by finer random families
        K = self.dirs.count
        for level in range(1, self.depth + 1):
            lv = _F(level)
            split = white_noise4(code, lv, _F(_STREAM_SPLIT), self.seed) < self.probability
            spacing = self.cell_size / (2.0 ** level)
            new_code = code.copy()
            for k in range(K):
                dom = self.dirs.domains[self.dirs.domain[k]]
                u = np.stack([white_noise4(code, lv, _F(_STREAM_SUBDIR + 8 * k + i), self.seed)
                              for i in range(self.dim - 1)], 1)
                normal = map_directions(self.dirs.lo[k] + (self.dirs.hi[k] - self.dirs.lo[k]) * u, dom)
                fam = _F(1000 * level + k)
                off = white_noise4(fam, code, _F(_STREAM_OFFSET), self.seed)
                p = np.sum(x * normal, axis=1) * _F(1.0 / spacing) + off
                d, slab = self._nearest_plane(p, fam, _F(_STREAM_PLANE) + lv, code, spacing)
                dist = np.where(split, np.minimum(dist, d), dist)
                new_code = np.where(split, white_noise4(slab, new_code, _F(_STREAM_CODE) + lv, self.seed), new_code)
            code = new_code
        return CellularResult(dist.astype(_F), code.astype(_F))
