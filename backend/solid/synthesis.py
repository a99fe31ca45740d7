"""Textures from a photo by optimisation (Kopf et al. 2007, "Solid Texture Synthesis from 2D Exemplars"; in 2D
Kwatra et al. 2005, "Texture Optimization for Example-based Synthesis"), numpy only.

In 2D this is what ``method = "synthesis"`` draws (:class:`backend.solid.request.SolidRequest`: ``omninoise solid
--method synthesis``, job files, the panel's Tileable Image): a periodic image that copies the photo's structure
(courses, planks, stones), closer than random phase noise on most structured held-out photos.  In 3D it stays a
research baseline measured by ``python -m bench solid-methods`` (its slices disagree and settle into blocks; docs/decisions/solid.md).

The neural path (``backend/solid/model.py``) draws a texture from a code in one pass; this module instead
optimises a periodic tile of voxels so that its slices look like the photo, neighbourhood by neighbourhood
(Kwatra et al. 2005's texture optimisation, carried to solids by Kopf et al.):

- **Search** (Kopf Sec. 3.1): for query neighbourhoods n x n on a jittered grid of every slice through the tile
  (normal to x, y and z; or only the vertical walls, ``planes`` "walls"), the nearest neighbourhood of the
  photo, found exactly over the principal components of the photo's neighbourhoods (Sec. 3.3 uses PCA and an
  approximate search).
- **Optimise** (Kopf Eq. 2-3): each voxel becomes the weighted mean of the colours the matched neighbourhoods
  covering it propose, w = ||s - e||^((r - 2) k), r = 0.8.  Kopf's weights are k = 1 (iteratively reweighted
  least squares for the robust energy sum ||s - e||^r); here k = ``sharpness``, per level (10 by default), which
  makes the mean nearly the best-matching vote's colour: at k = 1 the photos' tiles came out blurred, though on
  synthetic stripes k = 1 at the coarse level is what brings every slice to one phase (measurements in
  models/solid/MODEL_CARD.md).  The coarse levels get many iterations: the slices through a voxel agree only
  slowly, and the coarse levels are cheap.
- **Histogram matching** (Kopf Sec. 3.2): after each iteration the voxels' colours take the photo's values at
  the same ranks, channel by channel along the photo's principal colour axes (a projection, where Kopf
  reweights).
- **Multi-resolution** (Sec. 3.4): coarse to fine over ``levels`` octaves of the photo and the tile.  A finer
  level starts from the photo pixels under each voxel's best vote of the coarser level, doubled (coordinate
  upsampling, Lefebvre and Hoppe 2005); starting from upsampled colours gave blurred tiles.

The tile is periodic (neighbourhoods wrap around), so it can be sampled anywhere in space
(:class:`TileField`, trilinear).

Conventions.  A 3D tile is float32 (N, N, N, 3) indexed (z, y, x), z up; a 2D tile (N, N, 3) is indexed
(y, x), y up.  The slices normal to x and y run their rows along z and show the photo upright (the photo's top
row at the largest z); the slice normal to z runs its rows along y (the photo's top row at the largest y), as
:func:`backend.solid.model.slice_points` renders them.  Colours are sRGB values in [0, 1].
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import SettingError, check_points
from ..grid import Cancelled
from .model import plane_image
from .pixels import one_colour, resize_rgb

__all__ = ["SynthesisSettings", "synthesise", "TileField", "image_settings", "PLANES", "PX_PER_UNIT", "MIN_TILE",
           "MAX_TILE", "TILE_STEP", "COARSE_SHARPNESS", "FINE_SHARPNESS", "MIN_LEVELS", "COARSEST_PATCHES",
           "image_levels"]

_F = np.float32
#: which slices must look like the photo: "all" (x, y and z: Kopf's isotropic case) or "walls" (x and y only,
#: the photo upright on vertical planes; floors are left free, as for layered rock or brick walls)
PLANES = ("all", "walls")
R = 0.8          #: Kopf's robust exponent r (Eq. 2)
_CHUNK = 4096    #: query neighbourhoods per nearest-neighbour block
#: a photo pixel per 1/PX_PER_UNIT texture units: the shipped texture-space model's scale, so the same photo gives
#: textures of the same size by either method
PX_PER_UNIT = 128.0
#: the tile sizes a request may ask for (px a side, 2D): multiples of TILE_STEP (the coarsest of the default three
#: levels has a quarter of the pixels), at least MIN_TILE (8 x 8 neighbourhoods fit that level)
MIN_TILE, MAX_TILE, TILE_STEP = 32, 1024, 4
#: the 2D product's weights, coarse to fine (:func:`image_settings`): soft on every level but the finest, where the
#: copied pieces must agree on a phase (with k = 10 there, stripes broke into offset pieces on most seeds and a
#: paving photo into blotches), sharp on the finest, which keeps the copied detail crisp.  Chosen on 22 training
#: photos (docs/decisions/solid.md)
COARSE_SHARPNESS, FINE_SHARPNESS = 3.0, 10.0
#: the fewest levels the product draws; it draws more where the tile and the photo allow (:func:`image_levels`)
MIN_LEVELS = 3
#: neighbourhoods across the tile and the photo's short side at the product's coarsest level (:func:`image_levels`)
COARSEST_PATCHES = 4


@dataclasses.dataclass(frozen=True)
class SynthesisSettings:
    """How a tile is synthesised.  ``size``: voxels (px) per side of the periodic tile at the photo's
    resolution, a multiple of 2^(levels - 1) and at least ``patch`` at the coarsest level; ``dim``: 2 or 3;
    ``patch``: neighbourhood side n; ``levels``: resolutions; ``iterations``: search/optimise rounds per level,
    coarse to fine; ``stride``: query spacing on each slice (voxels; every slice along its normal is queried);
    ``components``: principal components of the search; ``candidates``: most photo neighbourhoods searched
    (a random subset above it); ``sharpness``: k in the weights (module doc); ``planes``: see :data:`PLANES`;
    ``seed``: the random start, grids and subsets."""

    size: int = 128
    dim: int = 3
    patch: int = 8
    levels: int = 3
    iterations: tuple = (16, 6, 2)
    stride: int = 2
    components: int = 24
    candidates: int = 12000
    sharpness: tuple = (10.0, 10.0, 10.0)
    planes: str = "all"
    seed: int = 0

    def __post_init__(self):
        if self.dim not in (2, 3):
            raise SettingError("dim", f"synthesis is 2D or 3D, got dim {self.dim}")
        if self.planes not in PLANES:
            raise SettingError("planes", f"planes must be one of {', '.join(PLANES)}, got {self.planes!r}")
        if self.levels < 1 or len(self.iterations) != self.levels or min(self.iterations) < 1:
            raise SettingError("iterations", f"iterations needs one count >= 1 per level ({self.levels}), "
                                             f"got {self.iterations}")
        step = 2 ** (self.levels - 1)
        if self.patch < 2 or self.size % step or self.size // step < self.patch:
            raise SettingError("size", f"size must be a multiple of {step} with at least {self.patch} voxels at the "
                                       f"coarsest of {self.levels} levels, got {self.size}")
        if not 1 <= self.stride <= self.patch:
            raise SettingError("stride", f"stride must lie in 1..{self.patch} (the patch), got {self.stride}")
        if self.components < 1 or self.candidates < 1:
            raise SettingError("components", "components and candidates must be at least 1")
        if len(self.sharpness) != self.levels or not min(self.sharpness) > 0:
            raise SettingError("sharpness", f"sharpness needs one value > 0 per level ({self.levels}), "
                                            f"got {self.sharpness}")


def image_levels(tile: int, photo_shape, patch: int = SynthesisSettings.patch) -> int:
    """How many levels the 2D product draws a ``tile`` px tile from a photo of ``photo_shape`` (H, W, ...) with:
    as many as keep :data:`COARSEST_PATCHES` neighbourhoods (``patch`` px each) across both the tile and the
    photo's short side at the coarsest level (the tile a multiple of 2^(levels - 1)), at least :data:`MIN_LEVELS`.
    The coarsest level's neighbourhoods then span a quarter of the photo, so large structures (bricks, planks,
    slabs) are laid out whole there and the finer levels refine them: with three levels, a 256 px photo's bricks and
    planks came out as offset pieces with straight seams; with neighbourhoods spanning half the photo the tiles
    copied such large pieces that a 128 px part of one was as far from the photo as a 128 px crop of it
    (docs/decisions/solid.md)."""
    side = min(photo_shape[:2]) if len(photo_shape) >= 2 else 0     # not an image: synthesise says so
    least = COARSEST_PATCHES * patch
    levels = MIN_LEVELS
    while True:
        f = 2 ** levels          # the next level's factor
        if tile % f or tile // f < least or side // f < least:
            return levels
        levels += 1


def image_settings(tile: int, photo_shape, seed: int = 0) -> SynthesisSettings:
    """What ``method = "synthesis"`` draws from a photo of ``photo_shape`` (H, W, ...): a 2D tile of ``tile`` px on
    :func:`image_levels` levels, 16 iterations on each but the last two (6 and 2), weights' sharpness
    :data:`COARSE_SHARPNESS` on each but the finest (:data:`FINE_SHARPNESS`)."""
    levels = image_levels(int(tile), photo_shape)
    return SynthesisSettings(size=int(tile), dim=2, levels=levels, iterations=(16,) * (levels - 2) + (6, 2),
                             sharpness=(COARSE_SHARPNESS,) * (levels - 1) + (FINE_SHARPNESS,), seed=int(seed))


def _families(dim: int, planes: str) -> list:
    """The (row axis, column axis) pairs of the slice families, in tile index order (z, y, x) / (y, x)."""
    if dim == 2:
        return [(0, 1)]
    return [(0, 1), (0, 2)] if planes == "walls" else [(0, 1), (0, 2), (1, 2)]


def _colour_axes(colours: np.ndarray) -> tuple:
    """Mean (3,) and principal axes (3, 3) (columns) of colours (K, 3)."""
    m = colours.mean(0)
    _, U = np.linalg.eigh(np.cov((colours - m).T) + 1e-9 * np.eye(3))
    return m, U


def _match_histogram(tile: np.ndarray, ref: np.ndarray, m: np.ndarray, U: np.ndarray,
                     rng: np.random.Generator) -> np.ndarray:
    """Kopf Sec. 3.2, as a projection: each of the tile's decorrelated colour channels takes the photo's values at
    the same ranks (exact histogram matching along the photo's principal colour axes; ``ref`` (K, 3): the photo's
    colours in those axes, each column sorted).  Equal values are ranked at random: ranked in index order, a flat
    region would become a ramp."""
    flat = (tile.reshape(-1, 3) - m) @ U
    q = (np.arange(flat.shape[0]) + 0.5) / flat.shape[0] * ref.shape[0] - 0.5
    out = np.empty_like(flat)
    ties = rng.random(flat.shape[0])
    for c in range(3):
        order = np.lexsort((ties, flat[:, c]))
        out[order, c] = np.interp(q, np.arange(ref.shape[0]), ref[:, c])
    return np.clip(out @ U.T + m, 0.0, 1.0).astype(_F).reshape(tile.shape)


class _Searcher:
    """Exact nearest photo neighbourhood in the principal-component space of the photo's neighbourhoods."""

    def __init__(self, photo: np.ndarray, n: int, components: int, candidates: int, rng: np.random.Generator):
        w = photo.shape[1] - n + 1
        total = (photo.shape[0] - n + 1) * w
        keep = np.arange(total)
        if total > candidates:       # chosen before any is cut out: a large photo's every patch would not fit
            keep = np.sort(rng.choice(total, candidates, replace=False))
        d = np.arange(n)
        X = photo[(keep // w)[:, None, None] + d[:, None], (keep % w)[:, None, None] + d]   # (M, n, n, 3)
        X = np.ascontiguousarray(X, _F).reshape(keep.shape[0], n * n * 3)
        self.X = X
        self.pos = np.stack([keep // w, keep % w], -1).astype(np.int32)   # (M, 2) top-left (row, col)
        self.mean = X.mean(0)
        k = min(components, X.shape[1], X.shape[0])
        sub = X[rng.choice(X.shape[0], min(X.shape[0], 4096), replace=False)] - self.mean
        _, _, vt = np.linalg.svd(sub, full_matrices=False)
        self.basis = np.ascontiguousarray(vt[:k].T, _F)               # (n*n*3, k)
        self.C = (X - self.mean) @ self.basis                         # (M, k)
        self.c2 = np.einsum("ij,ij->i", self.C, self.C)

    def nearest(self, Q: np.ndarray) -> tuple:
        """Query neighbourhoods (q, n*n*3) -> (matched neighbourhoods (q, n*n*3), mean squared differences (q,),
        their top-left photo positions (q, 2))."""
        P = (Q - self.mean) @ self.basis
        idx = np.empty(Q.shape[0], np.int64)
        for a in range(0, Q.shape[0], _CHUNK):
            p = P[a:a + _CHUNK]
            idx[a:a + _CHUNK] = np.argmin(self.c2[None, :] - 2.0 * (p @ self.C.T), axis=1)
        E = self.X[idx]
        d2 = np.einsum("ij,ij->i", Q - E, Q - E) / Q.shape[1]
        return E, d2, self.pos[idx]


def _level(tile: np.ndarray, photo: np.ndarray, s: SynthesisSettings, iterations: int, sharpness: float,
           rng: np.random.Generator, tick) -> tuple:
    """Iterations of search and optimisation on one level: tile (N,)*dim + (3,) against photo (h, w, 3) ->
    (tile, sources): sources int32 (N,)*dim + (3,) is, per voxel, the photo pixel (row, col) its heaviest vote
    came from and that vote's slice family (what the next level starts from, :func:`_inherit`)."""
    n, N = s.patch, tile.shape[0]
    search = _Searcher(photo, n, s.components, s.candidates, rng)
    colours = photo.reshape(-1, 3).astype(np.float64)
    m, U = _colour_axes(colours)
    ref = np.sort((colours - m) @ U, axis=0)     # once per level: a large photo has millions of colours
    fams = _families(s.dim, s.planes)
    offs = np.arange(n)
    sources = None
    p = (R - 2.0) / 2.0 * sharpness     # the IRLS weight's exponent on squared distances
    scale = None
    for _ in range(iterations):
        acc = np.zeros(tile.shape, np.float64)
        wsum = np.zeros(tile.shape[:-1], np.float64)
        best = np.zeros(tile.shape[:-1], np.float64)
        sources = np.zeros(tile.shape[:-1] + (3,), np.int32)
        for fam, (ra, ca) in enumerate(fams):
            other = [a for a in range(s.dim) if a not in (ra, ca)]
            order = other + [ra, ca]
            W = tile.transpose(order + [s.dim])          # (No..., N, N, 3), normal axis first in 3D
            views = [acc.transpose(order + [s.dim]), wsum.transpose(order), best.transpose(order),
                     sources.transpose(order + [s.dim])]
            g = (np.arange(0, N, s.stride) + rng.integers(0, s.stride, 2)[:, None]) % N   # jittered grid (2, G)
            ir = (g[0][:, None] + offs[None, :]) % N                                         # (G, n)
            ic = (g[1][:, None] + offs[None, :]) % N
            G0, G1 = ir.shape[0], ic.shape[0]
            slab = max(1, (1 << 17) // (G0 * G1))       # normal-axis slices per block
            lead = W.shape[0] if s.dim == 3 else 1
            for a in range(0, lead, slab):
                blk = W[a:a + slab] if s.dim == 3 else W[None]
                b = blk.shape[0]
                Q = blk[:, ir[:, :, None, None], ic[None, None, :, :]]        # (b, G, n, G, n, 3)
                Q = Q.transpose(0, 1, 3, 2, 4, 5).reshape(-1, n * n * 3)
                E, d2, pos = search.nearest(Q)
                if scale is None:
                    scale = float(np.median(d2)) + 1e-6
                w = (d2.astype(np.float64) / scale + 1e-3) ** p
                E = E.reshape(b, G0, G1, n, n, 3) * w.reshape(b, G0, G1, 1, 1, 1)
                w = w.reshape(b, G0, G1)
                # (row, col, family) of each match's top-left pixel; a vote at offset (dr, dc) adds (dr, dc, 0)
                at = np.concatenate([pos.reshape(b, G0, G1, 2), np.full((b, G0, G1, 1), fam, np.int32)], -1)
                tacc, tsum, tbest, tsrc = (v[a:a + slab] if s.dim == 3 else v[None] for v in views)
                for dr in range(n):
                    for dc in range(n):
                        rr, cc = ir[:, dr][:, None], ic[:, dc][None, :]
                        tacc[:, rr, cc] += E[:, :, :, dr, dc]
                        tsum[:, rr, cc] += w
                        heavier = w > tbest[:, rr, cc]
                        tbest[:, rr, cc] = np.where(heavier, w, tbest[:, rr, cc])
                        src = at + np.array([dr, dc, 0], np.int32)
                        tsrc[:, rr, cc] = np.where(heavier[..., None], src, tsrc[:, rr, cc])
            if tick():
                raise Cancelled("cancelled")
        # the weights are relative and may all be tiny: at k = 10 a weight is (d2 / scale)^-6, and where exact
        # copies are among the photo's neighbourhoods (a photo of 128 px or less) the scale, their median, is ~0,
        # so a voxel whose votes are all inexact sums to 1e-30 or less.  Dividing by a floor of 1e-12 turned such
        # voxels black, and histogram matching painted them as flat blotches (a 128 px photo: patch distance 333,
        # the same photo at 256 px 97); a voxel without any vote keeps its colour
        mean = acc / np.where(wsum > 0, wsum, 1.0)[..., None]
        tile = _match_histogram(np.where((wsum > 0)[..., None], mean, tile).astype(_F), ref, m, U, rng)
    return tile, sources


def _inherit(sources: np.ndarray, photo: np.ndarray, fams: list) -> np.ndarray:
    """Kopf Sec. 3.4 / Lefebvre and Hoppe 2005's coordinate upsampling: the next level's tile (2N,)*dim + (3,)
    takes, in every child voxel, the finer photo's pixel under its parent's source (row, col) x 2 plus the child's
    offset along that source's slice axes; ``photo`` is the finer level's."""
    dim = sources.ndim - 1
    up = sources
    for ax in range(dim):
        up = np.repeat(up, 2, axis=ax)
    child = np.indices(up.shape[:-1]) % 2                       # (dim, 2N...)
    ra = np.array([f[0] for f in fams])[up[..., 2]]
    ca = np.array([f[1] for f in fams])[up[..., 2]]
    r = 2 * up[..., 0] + np.take_along_axis(child, ra[None], 0)[0]
    c = 2 * up[..., 1] + np.take_along_axis(child, ca[None], 0)[0]
    return photo[np.clip(r, 0, photo.shape[0] - 1), np.clip(c, 0, photo.shape[1] - 1)].astype(_F)


def check_photo(photo, settings: SynthesisSettings = SynthesisSettings()) -> np.ndarray:
    """``photo`` as float32 (H, W, 3); SettingError naming what is wrong with it for a synthesis with ``settings``
    (checked before any work)."""
    img = np.asarray(photo, _F)
    if img.ndim != 3 or img.shape[2] != 3:
        raise SettingError("photo", f"the photo must be an RGB image (H, W, 3), got shape {img.shape}")
    if not np.isfinite(img).all():
        raise SettingError("photo", "the photo has non-finite values")
    step = 2 ** (settings.levels - 1)
    if min(img.shape[:2]) // step < settings.patch + 1:
        raise SettingError("photo", f"the photo is {img.shape[1]} x {img.shape[0]} px; {settings.levels} levels of "
                                    f"{settings.patch} px neighbourhoods need at least "
                                    f"{(settings.patch + 1) * step} px a side")
    return img


def synthesise(photo: np.ndarray, settings: SynthesisSettings = SynthesisSettings(), progress=None,
               cancel=None) -> np.ndarray:
    """A periodic tile whose slices look like ``photo`` float (H, W, 3) sRGB in [0, 1] (module doc): float32
    (N, N, 3) in 2D, (N, N, N, 3) in 3D (N = ``settings.size``), at the photo's resolution.

    ``progress(fraction)`` after each slice family of each iteration (the fraction of the work, by voxels);
    ``cancel()`` returning True stops with :class:`~backend.grid.Cancelled`.  The photo must be at least ``settings.patch`` px on its short side at the
    coarsest level."""
    s = settings
    img = check_photo(photo, s)
    img = np.clip(img[::-1], 0.0, 1.0)      # row 0 at the bottom: rows run up the tile (module doc)
    if one_colour(img):                     # every neighbourhood alike: the tile is the colour
        if progress is not None:
            progress(1.0)
        return np.broadcast_to(img[0, 0], (s.size,) * s.dim + (3,)).copy()
    rng = np.random.default_rng(s.seed)
    fams = _families(s.dim, s.planes)
    # progress in work done: a slice family's pass over a level costs about its voxel count
    cost = [(s.size // 2 ** (s.levels - 1 - lvl)) ** s.dim for lvl in range(s.levels)]
    total, done, level = len(fams) * sum(i * c for i, c in zip(s.iterations, cost)), [0], [0]

    def tick() -> bool:
        done[0] += cost[level[0]]
        if progress is not None:
            progress(min(1.0, done[0] / total))
        return cancel is not None and cancel()

    tile = sources = None
    for lvl in range(s.levels):
        f = 2 ** (s.levels - 1 - lvl)
        ex = img if f == 1 else resize_rgb(img, img.shape[0] // f, img.shape[1] // f)
        N = s.size // f
        if tile is None:     # Kopf: start from the photo's colours at random
            flat = ex.reshape(-1, 3)
            tile = flat[rng.integers(0, flat.shape[0], N ** s.dim)].reshape((N,) * s.dim + (3,))
        else:
            tile = _inherit(sources, ex, fams)
        level[0] = lvl
        tile, sources = _level(tile, ex, s, s.iterations[lvl], s.sharpness[lvl], rng, tick)
    return tile


class TileField:
    """A periodic tile as a colour field over texture space: ``evaluate(points)`` samples it trilinearly
    (bilinearly in 2D) with wrap-around, ``px_per_unit`` voxels per texture unit (the photo's resolution), voxel
    centres at (i + 1/2) / px_per_unit.  2D points on a 3D tile lie on z = 0.  ``settings``: the
    :class:`SynthesisSettings` the tile was synthesised with, where known (a bake's key records them)."""

    def __init__(self, tile: np.ndarray, px_per_unit: float, settings: SynthesisSettings | None = None):
        t = np.asarray(tile, _F)
        if t.ndim not in (3, 4) or t.shape[-1] != 3 or len(set(t.shape[:-1])) != 1:
            raise SettingError("tile", f"a tile is (N, N, 3) or (N, N, N, 3), got shape {t.shape}")
        if not px_per_unit > 0:
            raise SettingError("px_per_unit", f"px_per_unit must be positive, got {px_per_unit}")
        self.tile, self.dim, self.px_per_unit, self.settings = t, t.ndim - 1, float(px_per_unit), settings

    def image(self, size: int, scale: float = 1.0) -> np.ndarray:
        """A (size, size, 3) float32 image of the plane z = 0 (x right, y up; row 0 at the top) at ``scale`` output
        pixels per tile pixel: at scale 1 the tile's own pixels, repeated beyond its size."""
        return plane_image(lambda pts, rows: self.evaluate(pts), size, self.px_per_unit * scale, None)

    def evaluate(self, points: np.ndarray, chunk: int = 1 << 18) -> np.ndarray:
        """points float (P, 2 or 3) in texture units (x, y[, z]) -> float32 (P, 3)."""
        pts = check_points(points, (2, 3) if self.dim == 3 else (2,), np.float64)
        if pts.shape[1] < self.dim:
            pts = np.concatenate([pts, np.zeros((pts.shape[0], 1))], axis=1)
        N = self.tile.shape[0]
        out = np.empty((pts.shape[0], 3), _F)
        for a in range(0, pts.shape[0], chunk):
            # index order of the tile is (z, y, x) / (y, x): reverse the coordinates
            u = pts[a:a + chunk, ::-1] * self.px_per_unit - 0.5
            i0 = np.floor(u)
            f = (u - i0).astype(_F)
            i0 = i0.astype(np.int64) % N
            i1 = (i0 + 1) % N
            acc = np.zeros((u.shape[0], 3), _F)
            for corner in range(1 << self.dim):
                idx, w = [], np.ones(u.shape[0], _F)
                for ax in range(self.dim):
                    hi = (corner >> ax) & 1
                    idx.append(i1[:, ax] if hi else i0[:, ax])
                    w = w * (f[:, ax] if hi else 1.0 - f[:, ax])
                acc += w[:, None] * self.tile[tuple(idx)]
            out[a:a + chunk] = acc
        return out
