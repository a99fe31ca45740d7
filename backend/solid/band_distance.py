"""How far renders are from a photo, band by band: the runtime's check of a texture against its exemplar.

A sliced Wasserstein distance (Rabin, Peyré, Delon & Bernot 2011; Heitz et al. 2021) between the PATCH x PATCH
colour neighbourhoods of the renders (pooled) and of the photo, on each band of a Laplacian pyramid (Burt &
Adelson 1983; 5-tap binomial blur), each band's neighbourhoods normalised by the photo's per-channel mean and
spread in that band, so that every scale counts alike and colour and contrast errors count.  The mean over bands
and DIRECTIONS random directions of the mean absolute difference of sorted projections, x 1000.

It is a cousin of the held-out evaluation's distance (``training/solid/photo_eval.py``: 7 x 7 neighbourhoods,
4096 of them, 256 directions), smaller and cheaper (5 x 5, SAMPLES, DIRECTIONS): the band-pass levels are
where structure lives.  The box pyramid of ``refine.py``'s search distance is dominated by colour and the
coarsest level, and picking the Gaussian rest's mix (``gaussian_rest.py``) by it made as many training photos farther
as closer.

Shapes: images float (H, W, 3) sRGB in [0, 1]; numpy only.
"""
from __future__ import annotations

import numpy as np

__all__ = ["band_distance", "BandReference", "laplacian_bands", "central_crop", "PATCH", "LEVELS", "SAMPLES",
           "DIRECTIONS", "REFERENCE_SIDE"]

PATCH = 5             #: neighbourhood side, px
LEVELS = 4            #: Laplacian levels (three bands and the low-pass residue)
SAMPLES = 2048        #: neighbourhoods per level and image set
DIRECTIONS = 128      #: random projection directions per level
REFERENCE_SIDE = 512  #: a larger photo is read through its central crop of this side

_K = np.array([1.0, 4.0, 6.0, 4.0, 1.0]) / 16.0


def _blur(a: np.ndarray) -> np.ndarray:
    """Separable 5-tap binomial blur with reflected borders: (H, W, C) -> (H, W, C)."""
    p = np.pad(a, ((2, 2), (2, 2), (0, 0)), mode="reflect")
    h = sum(_K[i] * p[:, i:i + a.shape[1]] for i in range(5))
    return sum(_K[i] * h[i:i + a.shape[0]] for i in range(5))


def laplacian_bands(img: np.ndarray, levels: int = LEVELS) -> list:
    """Band-pass levels of an image (H, W, 3), finest first, then the low-pass residue: float64 arrays."""
    g = np.asarray(img, np.float64)[..., :3]
    out = []
    for _ in range(levels - 1):
        low = _blur(g)[::2, ::2]
        up = np.repeat(np.repeat(low, 2, 0), 2, 1)[:g.shape[0], :g.shape[1]]
        out.append(g - _blur(up))
        g = low
    out.append(g)
    return out


def _corners(shape: tuple, n: int, rng: np.random.Generator, k: int) -> tuple:
    """n random top-left corners (ys, xs) of k x k neighbourhoods in a level of ``shape`` (H, W, 3), k <= H, W."""
    H, W = shape[:2]
    return rng.integers(0, H - k + 1, n), rng.integers(0, W - k + 1, n)


def _gather(level: np.ndarray, corners: tuple, k: int) -> np.ndarray:
    """The k x k neighbourhoods of level (H, W, 3) at ``corners`` (:func:`_corners`): float64 (n, k^2, 3)."""
    ys, xs = corners
    dy, dx = np.mgrid[0:k, 0:k]
    return level[ys[:, None, None] + dy, xs[:, None, None] + dx].reshape(len(ys), k * k, 3)


def central_crop(photo: np.ndarray, side: int) -> np.ndarray:
    """The central side x side crop of a photo (H, W, C) (the whole photo where it is smaller)."""
    H, W = photo.shape[:2]
    y, x = max(0, (H - side) // 2), max(0, (W - side) // 2)
    return photo[y:y + side, x:x + side]


class BandReference:
    """A photo (H, W, 3) prepared for :func:`band_distance` with ``seed``: its pyramid once, and for each layout of
    images measured against it (their count and shapes) the draws and the photo's sorted projections once, so that
    the renders of a check (the Gaussian rest's five to nine, auto's eight) cost their own side alone.  Each
    :meth:`distance` is :func:`band_distance`'s, to the bit."""

    def __init__(self, photo: np.ndarray, seed: int = 0):
        self.seed = seed
        self.bands = laplacian_bands(central_crop(np.asarray(photo, np.float64), REFERENCE_SIDE))
        self._layouts = {}

    def _layout(self, pyrs: list) -> list:
        """Per level (k, the renders' corners, mu, sd, directions v, the photo's sorted projections), drawn from
        ``seed`` in band_distance's order: the photo's corners, the renders', then the directions."""
        key = tuple(p[lvl].shape for p in pyrs for lvl in range(LEVELS))
        if key not in self._layouts:
            rng = np.random.default_rng(self.seed)
            per = -(-SAMPLES // len(pyrs))
            levels = []
            for lvl, ref in enumerate(self.bands):
                k = min([PATCH, *ref.shape[:2]] + [d for p in pyrs for d in p[lvl].shape[:2]])   # a tiny photo's
                r = _gather(ref, _corners(ref.shape, SAMPLES, rng, k), k)
                corners = [_corners(p[lvl].shape, per, rng, k) for p in pyrs]
                mu, sd = r.mean(axis=(0, 1)), r.std(axis=(0, 1)) + 1e-8
                r = ((r - mu) / sd).reshape(len(r), -1)
                v = rng.standard_normal((r.shape[1], DIRECTIONS))
                v /= np.linalg.norm(v, axis=0, keepdims=True)
                levels.append((k, corners, mu, sd, v, np.sort(r @ v, axis=0)))
            self._layouts[key] = levels
        return self._layouts[key]

    def distance(self, images: list) -> float:
        """The distance (module doc) of ``images`` (a list of (h, w, 3), pooled) from the photo."""
        if not len(images):
            raise ValueError("band_distance needs at least one image")
        pyrs = [laplacian_bands(im) for im in images]
        total = 0.0
        for lvl, (k, corners, mu, sd, v, ref_sorted) in enumerate(self._layout(pyrs)):
            o = np.concatenate([_gather(p[lvl], c, k) for p, c in zip(pyrs, corners)])[:SAMPLES]
            o = ((o - mu) / sd).reshape(len(o), -1)
            total += float(np.abs(ref_sorted - np.sort(o @ v, axis=0)).mean())
        return 1000.0 * total / LEVELS


def band_distance(images: list, photo, seed: int = 0) -> float:
    """The distance (module doc) of ``images`` (a list of (h, w, 3), pooled) from ``photo`` (H, W, 3, or its
    :class:`BandReference`, whose own seed stands), >= 0, 0 for the same distributions; ``seed`` draws the
    neighbourhoods and directions."""
    ref = photo if isinstance(photo, BandReference) else BandReference(photo, seed)
    return ref.distance(images)
