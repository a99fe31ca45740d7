"""Held-out photo evaluation of solid textures: a patch-statistics distance that sees structure, and baselines.

Distance: the sliced Wasserstein distance of 7 x 7 colour neighbourhoods on
each level of a Laplacian pyramid, as Karras et al. (ICLR 2018, Sec. 5)
evaluate GANs.  Per level, descriptors (147-D) are drawn at random positions
of both images, normalised by the *reference's* per-colour-channel mean and
spread (so colour and contrast errors count, unlike GAN practice, which
normalises each set by itself), projected on ``dirs`` random unit
directions, and the sorted projections are compared (mean absolute
difference); the result is the mean over levels, x 1000.  It shares nothing
with the training losses (those use 5 x 5 Gaussian-pyramid neighbourhoods and
random ReLU filters): the evaluation's own measure.

Baselines built from the same photo (what an artist could do without a model):

pixel shuffle   the photo's pixels in random order: the exact colour histogram, no structure;
random phase    Galerne, Gousseau, Morel 2011 (random phase noise): the photo's Fourier
                amplitudes with one random phase shared by the colour channels: the exact
                power spectrum and colour correlations, Gaussian statistics;
perlin_hist     fBm of the solid textures' own lattice noise, mapped through the photo's
                luminance-sorted colours: the histogram and a generic 1/f structure;
photo_crop      random crops of the photo itself: how far real pieces of it lie (the floor).

Compare at equal image counts (:func:`grouped_swd`).  The distance falls as the compared images grow in number:
a pooled sample of neighbourhoods from six 128² images covers more of a photo than one from two.  On the 87
held-out photos (256² photos, 128² images, medians): the photo's own random crops score 98.6 as two images and
61.5 as six, random phase noise 112.3 and 79.8.  So a model's six pooled slices must meet six baseline draws, not
two.

The last level, the low-pass residue, is a 16² picture of a 128² image's local mean colours; its 7 x 7
neighbourhoods sample a photo's large-scale layout so thinly that on 22 held-out photos (every fourth) the photo's
own six crops score worst there (median 219.6, the shipped texture 209.9, random phase noise 137.9), while on the
three band-pass levels they score best (medians per level, averaged: 41.0 against 53.9 and 47.6).  :func:`band_swd` is the distance without
it: the structure from fine grain to the middle scales, where a photo's own crops are the floor.

Images are float32 (H, W, 3) in [0, 1], numpy only (no torch).
"""
from __future__ import annotations

import numpy as np

from omninoise.backend.solid.band_distance import laplacian_bands
from omninoise.backend.solid.cellular import cellular_features_numpy
from omninoise.backend.solid.value_noise import value_noise
from omninoise.backend.solid.model import plane_points
from omninoise import export as _ex

__all__ = ["laplacian_pyramid", "patch_swd", "mean_colour_error", "pixel_shuffle", "random_phase", "gaussian_noise",
           "perlin_hist",
           "photo_crop", "colour_by_rank", "voronoi_pavement", "grouped_swd", "level_distances", "band_swd",
           "rounded_swds", "BASELINES", "SLICE_OFFSETS", "OBLIQUE_NORMALS", "OBLIQUE_OFFSETS", "oblique_points",
           "oblique_slices", "tile_sheet", "axis_imbalance"]

#: where the held-out evaluations cut a 3D texture: a slice normal to each axis through these points (units)
SLICE_OFFSETS = {"z": (3.1, -2.7, 0.37), "y": (-1.3, 0.41, 2.2), "x": (0.53, 1.9, -3.3)}
#: and six cuts at random orientations (:func:`oblique_slices`): unit normals, and a point of each plane (units).
#: A mesh's faces are seldom square to the axes, and a solid fitted to its axis cuts can be farther on others.
OBLIQUE_NORMALS = np.random.default_rng(7).standard_normal((6, 3))
OBLIQUE_NORMALS /= np.linalg.norm(OBLIQUE_NORMALS, axis=1, keepdims=True)
OBLIQUE_OFFSETS = np.random.default_rng(11).uniform(-4.0, 4.0, (len(OBLIQUE_NORMALS), 3))


def oblique_points(size: int, px_per_unit: float, normal, offset) -> np.ndarray:
    """Pixel centres float64 (size*size, 3) in units of a size x size image of the plane through ``offset`` normal
    to ``normal``: rows along the plane's steepest upward direction (row 0 at the top), columns along its
    horizontal direction (along x for a horizontal plane), one photo px apart. Square to an axis, the plane of
    ``backend.solid.model.slice_points``."""
    n = np.asarray(normal, np.float64) / np.linalg.norm(normal)
    u = np.cross([0.0, 0.0, 1.0], n)
    u = u / np.linalg.norm(u) if np.linalg.norm(u) > 1e-6 else np.array([1.0, 0.0, 0.0])
    v = np.cross(n, u)
    plane = plane_points(size, px_per_unit)         # (P, 2): x right, y up
    return plane[:, :1] * u + plane[:, 1:2] * v + np.asarray(offset, np.float64)


def oblique_slices(evaluate, px_per_unit: float, size: int = 128) -> list:
    """One (size, size, 3) cut per plane of OBLIQUE_NORMALS through OBLIQUE_OFFSETS of a 3D texture whose
    ``evaluate`` maps points float64 (P, 3) in units (``px_per_unit`` photo px each) to colours (P, 3)."""
    return [np.asarray(evaluate(oblique_points(size, px_per_unit, nrm, o)), np.float32).reshape(size, size, 3)
            for nrm, o in zip(OBLIQUE_NORMALS, OBLIQUE_OFFSETS)]


def laplacian_pyramid(img: np.ndarray, levels: int) -> list:
    """Band-pass levels of an image (H, W, 3), finest first; the last level is the low-pass residue (the
    runtime's :func:`backend.solid.band_distance.laplacian_bands`)."""
    return laplacian_bands(img, levels)


def _descriptors(level: np.ndarray, n: int, rng: np.random.Generator, size: int = 7) -> np.ndarray:
    H, W, C = level.shape
    ys = rng.integers(0, H - size + 1, n)
    xs = rng.integers(0, W - size + 1, n)
    dy, dx = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    return level[ys[:, None, None] + dy, xs[:, None, None] + dx].reshape(n, size * size * C)


def level_distances(images, reference: np.ndarray, levels: int = 4, n: int = 4096, dirs: int = 256,
                    seed: int = 0) -> list:
    """:func:`patch_swd` level by level, finest first (the last is the low-pass residue), not scaled: float per
    level."""
    rng = np.random.default_rng(seed)
    if isinstance(images, np.ndarray) and images.ndim == 3:
        images = [images]
    pyr_ref = laplacian_pyramid(reference, levels)
    pyrs = [laplacian_pyramid(im, levels) for im in images]
    out = []
    for lvl in range(levels):
        r = _descriptors(pyr_ref[lvl], n, rng)
        per = -(-n // len(pyrs))
        o = np.concatenate([_descriptors(p[lvl], per, rng) for p in pyrs])[:n]
        # normalise by the reference's per-colour-channel statistics (descriptor = 49 pixels x 3 channels)
        rc = r.reshape(n, -1, 3)
        mu, sd = rc.mean(axis=(0, 1)), rc.std(axis=(0, 1)) + 1e-8
        r = ((rc - mu) / sd).reshape(n, -1)
        o = ((o.reshape(o.shape[0], -1, 3) - mu) / sd).reshape(o.shape[0], -1)
        v = rng.standard_normal((r.shape[1], dirs))
        v /= np.linalg.norm(v, axis=0, keepdims=True)
        pr, po = np.sort(r @ v, axis=0), np.sort(o @ v, axis=0)
        out.append(float(np.abs(pr - po).mean()))
    return out


def patch_swd(images, reference: np.ndarray, levels: int = 4, n: int = 4096, dirs: int = 256,
              seed: int = 0) -> float:
    """Sliced Wasserstein distance (x 1000) of 7 x 7 Laplacian-pyramid neighbourhoods between ``images``
    (one (H, W, 3) image or a list of them, pooled) and ``reference`` (H', W', 3); lower is better."""
    return _scaled(level_distances(images, reference, levels, n, dirs, seed))


def _scaled(per_level: list) -> float:
    return 1000.0 * sum(per_level) / len(per_level)


def band_swd(per_level: list) -> float:
    """The band-pass part of :func:`patch_swd` (x 1000): the mean over its levels without the low-pass residue.
    The residue of a 128² image is a 16² picture of local mean colours, and its 7 x 7 neighbourhoods sample a
    photo's large-scale layout so thinly that the photo's own crops score worst there (module doc)."""
    return _scaled(per_level[:-1])


def rounded_swds(per_level: list) -> tuple:
    """(:func:`patch_swd`, :func:`band_swd`) of one set of images from its :func:`level_distances`, each rounded
    to 0.1: the two figures a report gives per group of images."""
    return round(_scaled(per_level), 1), round(band_swd(per_level), 1)


def mean_colour_error(img: np.ndarray, reference: np.ndarray) -> float:
    """Mean over R, G, B of |mean colour of img - mean colour of reference| (0-1 scale)."""
    return float(np.abs(np.asarray(img, np.float64).reshape(-1, 3).mean(0)
                        - np.asarray(reference, np.float64).reshape(-1, 3).mean(0)).mean())


def axis_imbalance(photo: np.ndarray) -> float:
    """How far a photo's vertical-frequency spectrum lies from its horizontal one, in [0, 1]: the total variation
    distance between R(k), the power at row frequency |k| (summed over column frequencies), and C(k), the power at
    column frequency |k| (summed over row frequencies), on the photo's central square (mean removed, Hann window,
    R, G and B powers summed).  0 for an isotropic texture, 1 for stripes across one axis only.

    Why it matters for 3D (the slices of a stationary solid with power spectrum S(kx, ky, kz)): a slice normal to x
    has the spectrum of S integrated over kx, so the power of every slice family at one frequency along an axis is
    S's marginal on that axis.  If the slices normal to x and to y have the photo's spectrum (rows along z), the
    marginals on y and on x are both C, so the slices normal to z have C along their rows too, where the photo
    has R: no solid, Gaussian or not, gives all three slice families the photo's spectrum unless R = C, and the
    floors' row spectrum is off by exactly this distance when the walls are right.  Random phase noise drawn as a
    2D image per slice, the evaluation's baseline, has the photo's spectrum on every slice, so on an oriented photo
    it is a bound no solid can reach."""
    u = np.asarray(photo, np.float64)
    n = min(u.shape[:2])
    y0, x0 = (u.shape[0] - n) // 2, (u.shape[1] - n) // 2
    u = u[y0:y0 + n, x0:x0 + n].reshape(n, n, -1)
    w = np.hanning(n)
    P = sum(np.abs(np.fft.fft2((u[..., c] - u[..., c].mean()) * np.outer(w, w))) ** 2 for c in range(u.shape[2]))
    k = np.minimum(np.arange(n), n - np.arange(n))          # |frequency| index of each FFT row / column
    R = np.bincount(k, P.sum(1), n // 2 + 1)
    C = np.bincount(k, P.sum(0), n // 2 + 1)
    total = R.sum()
    return 0.0 if total <= 1e-12 else float(0.5 * np.abs(R - C).sum() / total)    # a flat photo: 0


def pixel_shuffle(photo: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    flat = np.asarray(photo, np.float32).reshape(-1, 3)
    return flat[rng.permutation(flat.shape[0])[:size * size]].reshape(size, size, 3)


def random_phase(photo: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """Random phase noise (Galerne et al. 2011, Sec. 3): |F(u - m)| with the phase of a white noise's spectrum,
    shared by the channels (keeps colour correlations); the photo's size, cropped to ``size``."""
    u = np.asarray(photo, np.float64)
    m = u.reshape(-1, 3).mean(0)
    phase = np.exp(1j * np.angle(np.fft.fft2(rng.standard_normal(u.shape[:2]))))
    out = np.stack([np.real(np.fft.ifft2(np.fft.fft2(u[..., c] - m[c]) * phase)) for c in range(3)], -1) + m
    return np.clip(out[:size, :size], 0.0, 1.0).astype(np.float32)


def gaussian_noise(photo: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """Asymptotic discrete spot noise (Galerne et al. 2011, Sec. 2.3, Eq. 5): the photo's periodic component
    (Moisan 2011) less its mean, convolved with white Gaussian noise of variance 1 / (H W) shared by the channels:
    the Gaussian texture whose expected spectrum and colour correlations are the photo's.  Its Fourier amplitudes
    vary from draw to draw (random phase noise keeps the photo's), as those of a Gaussian solid's slices do, so it is
    the 2D draw a Gaussian solid can be compared with on an unoriented photo.  The photo's size, cropped to
    ``size``."""
    from omninoise.backend.periodic import periodic_component

    u = np.asarray(photo, np.float64)[..., :3]
    m = u.reshape(-1, 3).mean(0)
    F = np.fft.fft2(periodic_component((u - m).transpose(2, 0, 1)))
    w = np.fft.fft2(rng.standard_normal(u.shape[:2])) / np.sqrt(u.shape[0] * u.shape[1])
    out = np.real(np.fft.ifft2(F * w)).transpose(1, 2, 0) + m
    return np.clip(out[:size, :size], 0.0, 1.0).astype(np.float32)


def photo_crop(photo: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """A size x size crop of the photo at a random place (the whole photo's width where it is narrower)."""
    u = np.asarray(photo, np.float32)
    H, W = u.shape[:2]
    y, x = rng.integers(0, max(H - size, 0) + 1), rng.integers(0, max(W - size, 0) + 1)
    return u[y:y + size, x:x + size]


def grouped_swd(groups: dict, reference: np.ndarray) -> dict:
    """Patch distances of images grouped by slice axis, ``{"x": [...], "y": [...], "z": [...]}`` (any names; the
    walls are "x" and "y" where present): each group alone, ``axes`` (their mean), ``walls`` (x and y pooled) and
    ``pooled`` (all), rounded to 0.1; and the same of :func:`band_swd` with the suffix ``_band``.  A model's
    slices and a baseline's draws grouped alike are compared with the reference at equal image counts (module
    doc)."""
    sets = dict(groups)
    walls = [im for k in ("x", "y") for im in groups.get(k, [])]
    if walls:
        sets["walls"] = walls
    sets["pooled"] = [im for v in groups.values() for im in v]
    out = {}
    for k, ims in sets.items():
        lv = level_distances(ims, reference)
        out[k], out[k + "_band"] = rounded_swds(lv)
    for sfx in ("", "_band"):
        out["axes" + sfx] = round(float(np.mean([out[k + sfx] for k in groups])), 1)
    return out


def perlin_hist(photo: np.ndarray, size: int, rng: np.random.Generator, octaves: int = 6,
                cell_px: float = 32.0) -> np.ndarray:
    """fBm of lattice value noise (octave i: cells of cell_px / 2^i px, weight 2^-i), coloured by rank through
    the photo's luminance-sorted pixels."""
    u = (np.arange(size) + 0.5) / cell_px
    vv, uu = np.meshgrid(u, u, indexing="ij")
    pts = np.stack([uu.ravel(), vv.ravel()], 1) + rng.uniform(0, 1000, 2)
    T = np.stack([np.eye(2, dtype=np.float32)] * octaves)
    n = value_noise(pts, T, int(rng.integers(0, 2 ** 31 - 1)), 1)
    return colour_by_rank((n * (0.5 ** np.arange(octaves))).sum(1).reshape(size, size), photo)


def colour_by_rank(field: np.ndarray, photo: np.ndarray) -> np.ndarray:
    """A scalar field (H, W) coloured by rank through the photo's pixels sorted by mean value: (H, W, 3) float32
    with the photo's colour histogram and the field's arrangement."""
    f = np.asarray(field).ravel()
    flat = np.asarray(photo, np.float32).reshape(-1, 3)
    cols = flat[np.argsort(flat.mean(1), kind="stable")]
    idx = (np.argsort(np.argsort(f, kind="stable")) * (cols.shape[0] / f.shape[0])).astype(int)
    return cols[np.clip(idx, 0, cols.shape[0] - 1)].reshape(*np.shape(field), 3)


def voronoi_pavement(size: int, cell: float, rng: np.random.Generator, joint: float = 2.0,
                     noise: float = 0.01) -> np.ndarray:
    """A synthetic stone pavement (size, size) float32 in [0, 1], a probe for structure measures: Voronoi cells
    of about ``cell`` px (Worley features, :mod:`backend.solid.cellular`), one grey per stone, dark joints where
    F2 - F1 < ``joint`` px, plus Gaussian pixel noise."""
    u = (np.arange(size) + 0.5) / cell
    vv, uu = np.meshgrid(u, u, indexing="ij")
    pts = np.stack([uu.ravel(), vv.ravel()], 1) + rng.uniform(0, 1000, 2)
    f = cellular_features_numpy(pts, np.eye(2, dtype=np.float32)[None], int(rng.integers(0, 2 ** 31 - 1)), 1)
    grey = np.where((f[:, 1] + 1) / 2 * cell < joint, 0.12, 0.45 + 0.25 * f[:, 2])
    return np.clip(grey.reshape(size, size) + noise * rng.standard_normal((size, size)), 0, 1).astype(np.float32)


BASELINES = {"pixel_shuffle": pixel_shuffle, "random_phase": random_phase, "perlin_hist": perlin_hist,
             "photo_crop": photo_crop}


def tile_sheet(rows, path: str) -> None:
    """Save a sheet atomically, PNG (JPEG, quality 90, where ``path`` ends in .jpg): one row per list of (H, W, 3)
    images in [0, 1], each in a square cell of the largest side, white where a row is shorter or an image
    smaller."""
    from PIL import Image
    cell = max(max(t.shape[:2]) for row in rows for t in row)
    canvas = Image.new("RGB", (max(map(len, rows)) * cell, len(rows) * cell), "white")
    for i, row in enumerate(rows):
        for j, t in enumerate(row):
            canvas.paste(Image.fromarray((np.clip(t, 0, 1) * 255 + 0.5).astype(np.uint8)), (j * cell, i * cell))
    jpeg = path.lower().endswith((".jpg", ".jpeg"))
    with _ex.atomic_path(path) as tmp:
        canvas.save(tmp, format="JPEG" if jpeg else "PNG", **({"quality": 90} if jpeg else {}))
