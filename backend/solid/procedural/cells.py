"""Cells: stones, pebbles, flakes and spots as the cells of a jittered grid (Worley 1996, "A cellular texture
basis function": F1 and F2, the distances to the nearest and second nearest feature point), hashed by Blender's
White Noise Texture (4D), so the node group draws them from White Noise nodes exactly (Blender's Voronoi node
changed its hash in 5.0 and cannot be matched on every version).

Space is cut into cubes of side ``size`` (``stretch`` times as tall along z); cube c holds one feature point at
c + ``jitter`` x h, h the Color of the White Noise of (c, W = 4 seed' + 0) (three hashes, wavenoise.wave
.white_color4), seed' = seed mod 2^22 (W stays an exact float32); a point belongs to its nearest feature point's
cell, whose value h3, the White Noise of (c, W = 4 seed' + 1), picks its colour.  Where F2 - F1 < gap (in
cube sides) a point is in the gap between cells and takes the gap's value, -1; the cell's own value is reached at
twice that:

    e = clip((F2 - F1) / gap - 1, 0, 1),    s = e (1 + h3 + turbulence * T(p)) - 1
"""
from __future__ import annotations

import numpy as np

from ...wavenoise import ckernel
from ...wavenoise.hashing import white_noise4
from ...wavenoise.wave import white_color4
from .family import Family, Param, gapped, inside

__all__ = ["Cells", "voronoi", "cell_w", "NEIGHBOURS"]

#: the 27 cubes around a point's, x fastest
NEIGHBOURS = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), -1).reshape(-1, 3)[:, ::-1]


HASH_BATCH = 1 << 16    #: cubes hashed per call (Python's overhead per call against arrays that stay in cache)


def cell_w(seed: int, k: int) -> np.float32:
    """The White Noise W of hash k (0: the feature point's offset, three channels of the Color; 1: the cell's
    value)."""
    return np.float32(4 * (int(seed) % (1 << 22)) + k)


def _unique_cubes(base: np.ndarray) -> tuple:
    """The distinct rows of ``base`` (float32 (P, 3), P > 0, whole numbers) and each row's index among them: as
    np.unique(axis=0, return_inverse=True), through one int64 key per row (several times faster)."""
    b = base.astype(np.int64)
    lo = b.min(axis=0)
    span = b.max(axis=0) - lo + 1
    if float(span[0]) * float(span[1]) * float(span[2]) >= 2.0 ** 62:
        cubes, back = np.unique(base, axis=0, return_inverse=True)
        return cubes, back.reshape(-1)
    key = (b[:, 0] - lo[0]) + span[0] * ((b[:, 1] - lo[1]) + span[1] * (b[:, 2] - lo[2]))
    keys, back = np.unique(key, return_inverse=True)
    cubes = np.stack([keys % span[0], keys // span[0] % span[1], keys // (span[0] * span[1])], 1) + lo
    return cubes.astype(np.float32), back.reshape(-1)


def voronoi(q: np.ndarray, jitter: float, seed: int) -> tuple:
    """F1 and F2 (float32 (P,)) at points q (P, 3) in cube units, and the nearest cell's cube (float32 (P, 3));
    computed in float32, as the node group does: the loop over the 27 cubes in the C kernel where it is built
    (:func:`~backend.wavenoise.ckernel.cells`, the same bits), else in numpy."""
    q = np.asarray(q, np.float32)
    base = np.floor(q)
    local = q - base
    f1 = np.full(len(q), 8.0, np.float32)
    f2 = np.full(len(q), 8.0, np.float32)
    best = np.zeros_like(base)
    rnd = np.float32(jitter)
    if not len(q):
        return f1, f2, best
    cubes, back = _unique_cubes(base)        # points share cubes: hash each cube once
    near = NEIGHBOURS.astype(np.float32)
    mine = cubes[back]
    step = max(1, HASH_BATCH // len(cubes))      # neighbours hashed per call: few calls, arrays that stay in cache
    compiled = ckernel.available()
    if compiled:            # the C kernel's loop (the same bits); it keeps which neighbour is nearest
        which = np.zeros(len(q), np.int64)
        local, back = np.ascontiguousarray(local), np.ascontiguousarray(back, np.int64)
    for a in range(0, len(near), step):
        c = (cubes[None, :, :] + near[a:a + step, None, :]).reshape(-1, 3)
        hashes = np.stack([white_color4(c[:, 0], c[:, 1], c[:, 2], cell_w(seed, 0), k) for k in range(3)],
                          -1).astype(np.float32).reshape(-1, len(cubes), 3)
        if compiled:
            ckernel.cells(local, back, np.ascontiguousarray(near[a:a + step]), hashes, a, rnd, f1, f2, which)
            continue
        for n, h in zip(near[a:a + step], hashes):
            d = np.sqrt(np.sum(np.square(n + h[back] * rnd - local), axis=1, dtype=np.float32))
            nearer = d < f1
            f2 = np.where(nearer, f1, np.minimum(f2, d))
            best = np.where(nearer[:, None], mine + n, best)
            f1 = np.minimum(f1, d)
    return f1, f2, (mine + near[which] if compiled else best)


class Cells(Family):
    name = "cells"
    doc = "cells of a jittered grid with their own colours and gaps: stones, pebbles, flakes, spots"
    PARAMS = (Param("size", 0.01, 1.5, log=True, doc="a cell's side, units"),
              Param("stretch", 0.3, 3.0, log=True, doc="a cell's height over its width (along z)"),
              Param("jitter", 0.0, 1.0, doc="how far feature points move within their cube, in sides",
                    cap=True),
              Param("gap", 0.0, 0.45, doc="the gap between cells, in cell sides", cap=True))

    GAPPED = True

    def cells(self, p: dict, points: np.ndarray, seed: int) -> tuple:
        """(F2 - F1 in cube sides float64 (P,), the nearest cell's value r float64 (P,)) at points (P, 3)."""
        q = np.asarray(points, np.float64) / (p["size"] * np.array([1.0, 1.0, p["stretch"]]))
        f1, f2, cell = voronoi(q, p["jitter"], seed)
        r = white_noise4(cell[:, 0], cell[:, 1], cell[:, 2], cell_w(seed, 1)).astype(np.float64)
        return f2.astype(np.float64) - f1, r

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        dist, r = self.cells(p, points, seed)
        return gapped(dist, p["gap"], r, p, np.asarray(points, np.float64), seed)

    def gaps(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        return 1.0 - inside(self.cells(p, points, seed)[0], p["gap"])

    def starts(self, est) -> list:
        """Cells the size of the photo's repeats (along its wave, across, up), thin and wide gaps, dark or pale as
        the photo's are (``est.dark_gaps``); as tall as the photo's spacings up over across, and round too where
        those differ: stones' repeats are weak peaks of the autocorrelation (a photo of round stones read 0.41 as
        high as wide), the fit's loss scores flat and round cells alike, and the search stays near its start."""
        flat = float(np.clip(est.spacing_z / max(est.spacing_x, 1e-6), 0.31, 2.9))
        out = []
        sizes = {round(float(np.clip(s, 0.012, 1.4)), 4) for s in (est.spacing, est.spacing_x, est.spacing_z)}
        for size in sorted(sizes):
            for stretch in ((flat, 1.0) if abs(np.log(flat)) > 0.2 else (flat,)):
                for gap in (0.04, 0.15):
                    out.append(dict(size=size, stretch=stretch, jitter=0.9, gap=gap, turbulence=0.2, detail=0.1,
                                    turb_freq=float(np.clip(1.0 / size, 0.3, 15.0)), flip=not est.dark_gaps))
        return out
