"""Refine a texture code against its exemplar without torch (Henzler et al. 2020, Sec. 3 encoder, refined).

The encoder g gives a code z in one pass; this module then improves z for the
given exemplar by a derivative-free search, since the runtime has no
gradients: a (1+1) evolution strategy with the 1/5th success rule (Rechenberg)
over the learned part of z, each candidate rendered through the translator and
sampler at 128² px and compared with the exemplar by the sliced Wasserstein
distance of 5 x 5 colour neighbourhoods on three levels of a 2 x 2 box pyramid
(Heitz et al. 2021: the neighbourhood term of the training loss, here in numpy
with 64 fixed random directions per level).

Checked on planes the search does not see.  A candidate replaces z only when it
is closer on the two planes the search renders (front, seeds 0 and 1) *and* on
two others (a side and a floor plane, seeds 2 and 3), and the refined code is
kept only when it is also closer than the encoder's on six fresh planes (x, y
and z at seeds 6 and 7); otherwise the encoder's code is returned.  A search on
one small render finds codes that fit that render's chance: the classical
statistics this module searched with before (colour quantiles, a radial power
spectrum and gradient energies of 64² renders) lowered their own distance while
the patch distance of ``python -m bench solid-photos`` (x, y and z slices pooled)
grew by more than 5 % on 39 of 80 training photos and fell on 11; this search,
40 steps: 5 farther, 7 closer (on the walls, x and y slices: 6 and 15; before 33
and 17).  ``python -m bench solid-photos --split train --limit 80 --refine
40 --against ENCODER.json``; ``docs/evaluations/solid_refine_train_*.json``.

Photo models carry the exemplar's measured colour (mean and covariance) after
the latent: the search moves only the latent, so refinement never changes the
colours.

Shapes: images float32 (H, W, 3) sRGB values in [0, 1].
"""
from __future__ import annotations

import numpy as np

from ..grid import Cancelled
from .pixels import resize_rgb

__all__ = ["SlicedTarget", "sliced_target", "sliced_distance", "refine_code", "RENDER_SIZE",
           "SEARCH_PLANES", "CHECK_PLANES", "FINAL_PLANES"]

RENDER_SIZE = 128   #: px per rendered plane
PATCH = 5           #: neighbourhood side, px
LEVELS = 3          #: box-pyramid levels (1, 2 and 4 px per sample)
SAMPLES = 1024      #: neighbourhoods per level
DIRECTIONS = 64     #: random projection directions per level
#: (seed, axis, offset) of the planes rendered: the search's, the check's on each accepted candidate, the final one's
SEARCH_PLANES = ((0, "y", (0.0, 0.0, 0.0)), (1, "y", (7.0, 3.0, 1.0)))
CHECK_PLANES = ((2, "x", (12.0, 11.0, 4.0)), (3, "z", (17.0, 11.0, 4.0)))
FINAL_PLANES = tuple((s, a, (13.0 + s, 17.0, 19.0)) for s in (6, 7) for a in "xyz")


def _pyramid(img: np.ndarray, levels: int = LEVELS) -> list:
    """[img, img at 1/2, ...]: float64 (H / 2^l, W / 2^l, 3) means of 2 x 2 blocks."""
    out = [np.asarray(img, np.float64)[..., :3]]
    for _ in range(levels - 1):
        a = out[-1]
        h, w = a.shape[0] // 2 * 2, a.shape[1] // 2 * 2
        out.append(a[:h, :w].reshape(h // 2, 2, w // 2, 2, 3).mean(axis=(1, 3)))
    return out


def _neighbourhoods(img: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """n random PATCH x PATCH colour neighbourhoods of img (H, W, 3): float64 (n, 3 PATCH^2)."""
    H, W, _ = img.shape
    k = min(PATCH, H, W)
    ys, xs = rng.integers(0, H - k + 1, n), rng.integers(0, W - k + 1, n)
    dy, dx = np.mgrid[0:k, 0:k]
    return img[ys[:, None, None] + dy, xs[:, None, None] + dx].reshape(n, -1)


class SlicedTarget:
    """An exemplar's sorted projections: per level the directions float64 (3 PATCH^2, DIRECTIONS) and the sorted
    projections of SAMPLES of its neighbourhoods (SAMPLES, DIRECTIONS)."""

    def __init__(self, dirs: list, sorted_proj: list):
        self.dirs, self.sorted_proj = dirs, sorted_proj


def _pooled(images: list, level: int, rng: np.random.Generator) -> np.ndarray:
    pyrs = [_pyramid(i) for i in images]
    per = -(-SAMPLES // len(pyrs))
    return np.concatenate([_neighbourhoods(p[level], per, rng) for p in pyrs])[:SAMPLES]


def sliced_target(images: list, seed: int = 0) -> SlicedTarget:
    """The target of :func:`sliced_distance`: neighbourhoods of ``images`` (the exemplar's crops) pooled."""
    rng = np.random.default_rng(seed)
    dirs, proj = [], []
    for level in range(LEVELS):
        d = _pooled(images, level, rng)
        v = rng.standard_normal((d.shape[1], DIRECTIONS))
        v /= np.linalg.norm(v, axis=0, keepdims=True)
        dirs.append(v)
        proj.append(np.sort(d @ v, axis=0))
    return SlicedTarget(dirs, proj)


def sliced_distance(images: list, target: SlicedTarget, seed: int = 1) -> float:
    """Sliced Wasserstein-1 distance between the neighbourhoods of ``images`` (pooled) and the target's, the mean
    over levels and directions of |sorted projections - sorted target projections| (0: the same distribution)."""
    rng = np.random.default_rng(seed)
    total = 0.0
    for level in range(LEVELS):
        p = np.sort(_pooled(images, level, rng) @ target.dirs[level], axis=0)
        total += float(np.abs(p - target.sorted_proj[level]).mean())
    return total / LEVELS


def _exemplar_crops(exemplar: np.ndarray, scale: float, n: int = 4) -> list:
    """The exemplar resampled to the model's training resolution, cut into up to n square crops."""
    img = np.asarray(exemplar, np.float32)
    if scale != 1.0:
        img = resize_rgb(img, max(PATCH, round(img.shape[0] * scale)), max(PATCH, round(img.shape[1] * scale)))
    H, W, _ = img.shape
    S = min(H, W, RENDER_SIZE)
    ys = np.linspace(0, H - S, 2).astype(int)
    xs = np.linspace(0, W - S, 2).astype(int)
    return [img[y:y + S, x:x + S] for y in ys for x in xs][:n]


def refine_code(model, z0, exemplar: np.ndarray, steps: int = 40, seed: int = 0, sigma: float = 0.3,
                progress=None, cancel=None, harmonics=None):
    """(z, distances): z float32 (z_dim,) after ``steps`` candidates; distances[i] the best search distance after
    candidate i (distances[0]: the start).  When the final check keeps the encoder's code (module doc), z is
    ``z0`` and distances ends with distances[0] once more.  ``model`` is a space :class:`SolidTextureModel`;
    candidates are rendered with the exemplar's ``harmonics`` (:meth:`SolidTextureModel.harmonics`) when given,
    as the texture will be."""
    rng = np.random.default_rng(seed)
    scale = float(model.config.get("exemplar_scale", 1.0))
    target = sliced_target(_exemplar_crops(exemplar, scale))

    def cost(z, planes):
        code = model.translate(z, harmonics)
        return sliced_distance([model.image(RENDER_SIZE, code, s, scale=scale, axis=ax, offset=off)
                                for s, ax, off in planes], target)

    z0 = np.asarray(z0, np.float32).copy()
    z = z0.copy()
    if steps <= 0:
        return z, [cost(z, SEARCH_PLANES)]
    best, best_check = cost(z, SEARCH_PLANES), cost(z, CHECK_PLANES)
    hist = [best]
    k = int(getattr(model, "z_dim", z.shape[0]))       # the latent; photo models' colour statistics stay
    step = float(sigma) * max(float(np.std(z[:k])), 1e-3)
    for i in range(int(steps)):
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        cand = z.copy()
        cand[:k] = (z[:k] + rng.normal(0.0, step, k)).astype(np.float32)
        c = cost(cand, SEARCH_PLANES)
        c_check = cost(cand, CHECK_PLANES) if c < best else np.inf
        if c_check < best_check:
            z, best, best_check = cand, c, c_check
            step *= 1.5          # 1/5th rule: grow on success ...
        else:
            step *= 1.5 ** -0.25  # ... shrink on failure (balance at one success in five)
        hist.append(best)
        if progress is not None:
            progress((i + 1) / steps)
    if not np.array_equal(z, z0) and cost(z, FINAL_PLANES) >= cost(z0, FINAL_PLANES):
        return z0, hist + [hist[0]]
    return z, hist
