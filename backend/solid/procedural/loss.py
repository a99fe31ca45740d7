"""The fit's distance: how far slices of a solid are from the photo, cheap enough to call a hundred times.

The runtime's band distance (band_distance.py: sliced Wasserstein between 5 x 5 colour neighbourhoods on each band
of a Laplacian pyramid, normalised by the photo's spread per band) with fewer neighbourhoods and directions, taken
per group of slices (the cuts across x, across y, across z, oblique) and averaged, and with its random draws fixed
once per photo (common random numbers): the same slices always score the same, so the
search compares parameters, not draws.

Shapes: photo float (H, W, 3) sRGB; slices a list of float (side, side, 3), one per entry of ``groups``.
"""
from __future__ import annotations

import numpy as np

from ..band_distance import LEVELS, PATCH, REFERENCE_SIDE, central_crop, laplacian_bands

__all__ = ["SliceLoss", "SAMPLES", "DIRECTIONS"]

SAMPLES = 768      #: neighbourhoods per level and group
DIRECTIONS = 32    #: projections per level
#: the largest matrix product m n k that OpenBLAS runs on one thread (interface/gemm.c: 65536 x
#: GEMM_MULTITHREAD_THRESHOLD 4).  The loss projects its neighbourhoods in pieces of rows that stay within it
#: (768 x 75 x 32 would not): the BLAS threads a larger product wakes keep the cores from the wave-noise kernel's
#: threads, and a fit without numba took longer.  The pieces give the same bits as one product.
ONE_THREAD_MNK = 1 << 18


class SliceLoss:
    """``loss(slices)``: the distance of the slices from the photo, x 1000 (0 for the same distributions).  Every
    slice has the side ``side``; ``groups`` names each slice's group (one name per slice: the axis it is cut across,
    or "oblique"), and the loss is the mean over the groups of each group's pooled distance, as the held-out
    evaluation weighs the x, y and z cuts alike (a solid whose walls match and whose floor does not is no match)."""

    def __init__(self, photo: np.ndarray, side: int, groups, seed: int = 0):
        rng = np.random.default_rng(seed)
        ref = laplacian_bands(central_crop(np.asarray(photo, np.float64)[..., :3], REFERENCE_SIDE))
        self.side, self.groups = int(side), tuple(groups)
        names = sorted(set(self.groups))
        self.members = [[i for i, g in enumerate(self.groups) if g == name] for name in names]
        probe = laplacian_bands(np.zeros((side, side, 3)))
        self.levels = []
        for lvl in range(LEVELS):
            k = min(PATCH, *ref[lvl].shape[:2], *probe[lvl].shape[:2])
            dy, dx = np.mgrid[0:k, 0:k]
            H, W = ref[lvl].shape[:2]
            ys, xs = rng.integers(0, H - k + 1, SAMPLES), rng.integers(0, W - k + 1, SAMPLES)
            r = ref[lvl][ys[:, None, None] + dy, xs[:, None, None] + dx].reshape(SAMPLES, -1, 3)
            mu, sd = r.mean(axis=(0, 1)), r.std(axis=(0, 1)) + 1e-8
            v = rng.standard_normal((k * k * 3, DIRECTIONS))
            v /= np.linalg.norm(v, axis=0, keepdims=True)
            h, w = probe[lvl].shape[:2]
            where = [None] * len(self.groups)
            for m in self.members:
                per = -(-SAMPLES // len(m))
                for i in m:
                    where[i] = (rng.integers(0, h - k + 1, per), rng.integers(0, w - k + 1, per))
            ref_sorted = np.sort(((r - mu) / sd).reshape(SAMPLES, -1) @ v, axis=0)
            self.levels.append((k, dy, dx, mu, sd, v, where, ref_sorted))

    def __call__(self, slices: list) -> float:
        if len(slices) != len(self.groups):
            raise ValueError(f"expected {len(self.groups)} slices, got {len(slices)}")
        pyrs = [laplacian_bands(s) for s in slices]
        total = 0.0
        for lvl, (k, dy, dx, mu, sd, v, where, ref_sorted) in enumerate(self.levels):
            for m in self.members:
                o = np.concatenate([pyrs[i][lvl][where[i][0][:, None, None] + dy, where[i][1][:, None, None] + dx]
                                    .reshape(len(where[i][0]), -1, 3) for i in m])[:SAMPLES]
                a = ((o - mu) / sd).reshape(len(o), -1)
                rows = max(1, ONE_THREAD_MNK // (a.shape[1] * v.shape[1]))
                proj = np.sort(np.concatenate([a[i:i + rows] @ v for i in range(0, len(a), rows)]), axis=0)
                total += float(np.abs(ref_sorted - proj).mean())
        return 1000.0 * total / (LEVELS * len(self.members))
