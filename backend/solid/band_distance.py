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

__all__ = ["band_distance", "laplacian_bands", "central_crop", "PATCH", "LEVELS", "SAMPLES", "DIRECTIONS", "REFERENCE_SIDE"]

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


def _neighbourhoods(level: np.ndarray, n: int, rng: np.random.Generator, k: int) -> np.ndarray:
    """n random k x k neighbourhoods of level (H, W, 3), k <= H, W: float64 (n, k^2, 3)."""
    H, W, _ = level.shape
    ys, xs = rng.integers(0, H - k + 1, n), rng.integers(0, W - k + 1, n)
    dy, dx = np.mgrid[0:k, 0:k]
    return level[ys[:, None, None] + dy, xs[:, None, None] + dx].reshape(n, k * k, 3)


def central_crop(photo: np.ndarray, side: int) -> np.ndarray:
    """The central side x side crop of a photo (H, W, C) (the whole photo where it is smaller)."""
    H, W = photo.shape[:2]
    y, x = max(0, (H - side) // 2), max(0, (W - side) // 2)
    return photo[y:y + side, x:x + side]


def band_distance(images: list, photo: np.ndarray, seed: int = 0) -> float:
    """The distance (module doc) of ``images`` (a list of (h, w, 3), pooled) from ``photo`` (H, W, 3), >= 0,
    0 for the same distributions; ``seed`` draws the neighbourhoods and directions."""
    if not images:
        raise ValueError("band_distance needs at least one image")
    rng = np.random.default_rng(seed)
    ref = laplacian_bands(central_crop(np.asarray(photo, np.float64), REFERENCE_SIDE))
    pyrs = [laplacian_bands(im) for im in images]
    per = -(-SAMPLES // len(pyrs))
    total = 0.0
    for lvl in range(LEVELS):
        k = min([PATCH, *ref[lvl].shape[:2]] + [d for p in pyrs for d in p[lvl].shape[:2]])   # a tiny photo's
        r = _neighbourhoods(ref[lvl], SAMPLES, rng, k)
        o = np.concatenate([_neighbourhoods(p[lvl], per, rng, k) for p in pyrs])[:SAMPLES]
        mu, sd = r.mean(axis=(0, 1)), r.std(axis=(0, 1)) + 1e-8
        r, o = ((r - mu) / sd).reshape(len(r), -1), ((o - mu) / sd).reshape(len(o), -1)
        v = rng.standard_normal((r.shape[1], DIRECTIONS))
        v /= np.linalg.norm(v, axis=0, keepdims=True)
        total += float(np.abs(np.sort(r @ v, axis=0) - np.sort(o @ v, axis=0)).mean())
    return 1000.0 * total / LEVELS
