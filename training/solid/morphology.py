"""Morphology of a texture's level sets: a structure measure that patch statistics miss.

The patch distance of :mod:`training.solid.photo_eval` compares 7 x 7
neighbourhoods; it scored a speckle of the right colours nearer to a photo of
paving stones than random phase noise, which draws blobs of the stones' size
(docs/decisions/solid.md).  Stones, cobbles and brick
courses are shapes: regions of a size, with outlines of a length, connected
or apart.  Minkowski functionals of thresholded images measure exactly that
(Mecke, Buchert, Wagner 1994; for textures Mantz, Jacobs, Mecke 2008): for
the excursion set B_q = {luminance > its own q-quantile} of each image

    P(q)    boundary length per pixel (pixel edges between B_q and its complement)
    chi(q)  Euler characteristic per pixel (components minus holes, 8-connected
            foreground), from 2 x 2 quad counts (Gray 1971):
            chi = (Q1 - Q3 - 2 Q_D) / 4

at q = 0.1 ... 0.9 and on three levels of a Gaussian pyramid (pixels, 1/2, 1/4),
so shapes up to tens of pixels count.  Each image is thresholded at its own
quantiles: the area is then equal by construction, and colour or contrast
errors (measured by the colour error) do not enter.

distance = mean over levels of  mean_q |P - P_ref| / mean_q P_ref
                              + mean_q |chi - chi_ref| / mean_q |chi_ref|

0 for the same morphology; a field with blobs of the wrong size, or speckle
for stones, is far.  Images are float (H, W, 3) or (H, W) in [0, 1], numpy only.
"""
from __future__ import annotations

import numpy as np

__all__ = ["QUANTILES", "LEVELS", "minkowski_curves", "morphology_distance"]

QUANTILES = np.linspace(0.1, 0.9, 9)
LEVELS = 3
_K = np.array([1.0, 4.0, 6.0, 4.0, 1.0]) / 16.0


def _luminance(img) -> np.ndarray:
    a = np.asarray(img, np.float64)
    return a if a.ndim == 2 else a[..., :3] @ np.array([0.2126, 0.7152, 0.0722])


def _down(a: np.ndarray) -> np.ndarray:
    """5-tap binomial blur (reflected borders), then every second pixel: (H, W) -> (H/2, W/2)."""
    p = np.pad(a, 2, mode="reflect")
    h = sum(_K[i] * p[:, i:i + a.shape[1]] for i in range(5))
    return sum(_K[i] * h[i:i + a.shape[0]] for i in range(5))[::2, ::2]


def _functionals(b: np.ndarray) -> tuple[float, float]:
    """Boundary length and Euler characteristic (8-connected foreground) per pixel of a binary image."""
    b = b.astype(np.int8)
    perim = np.count_nonzero(b[1:] != b[:-1]) + np.count_nonzero(b[:, 1:] != b[:, :-1])
    q = b[:-1, :-1] + b[:-1, 1:] + b[1:, :-1] + b[1:, 1:]
    diag = (q == 2) & (b[:-1, :-1] == b[1:, 1:])
    chi = (np.count_nonzero(q == 1) - np.count_nonzero(q == 3) - 2 * np.count_nonzero(diag)) / 4.0
    return perim / b.size, chi / b.size


def minkowski_curves(img, levels: int = LEVELS) -> np.ndarray:
    """P(q) and chi(q) on each pyramid level: float64 (levels, 2, len(QUANTILES)); chi scaled by 100."""
    g = _luminance(img)
    out = np.empty((levels, 2, len(QUANTILES)))
    for lvl in range(levels):
        thr = np.quantile(g, QUANTILES)
        for j, t in enumerate(thr):
            p, chi = _functionals(g > t)
            out[lvl, :, j] = p, 100.0 * chi
        g = _down(g)
    return out


def morphology_distance(images, reference) -> float:
    """Distance of the level-set morphology of ``images`` (one image or a list, curves averaged) to
    ``reference``'s (see module doc); lower is better, 0 for the same curves."""
    if isinstance(images, np.ndarray):
        images = [images]
    ref = minkowski_curves(reference)
    cur = np.mean([minkowski_curves(im) for im in images], axis=0)
    p = np.abs(cur[:, 0] - ref[:, 0]).mean(1) / (ref[:, 0].mean(1) + 1e-9)
    c = np.abs(cur[:, 1] - ref[:, 1]).mean(1) / (np.abs(ref[:, 1]).mean(1) + 1e-9)
    return float((p + c).mean())
