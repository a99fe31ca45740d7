"""Diagonal strokes of the texture-space model: ``python bench/solid_strokes.py [--every 6] MODEL_DIR [MODEL_DIR ...]``.

For every ``every``-th held-out photo (``data/photos/val``) each model encodes the photo (decoder alone: no
harmonic part, no Gaussian rest, so that only the decoder's own structure is measured) and renders 128² slices
normal to y (fronts: x right, z up) and to z (floors) at the photo's resolution, two seeds each.  Per slice:

- ``diag``: the ratio of luminance power at +45 degrees to power at -45 degrees (orientation within 22.5 degrees of
  each diagonal, 0.05 to 0.35 cycles per pixel, mean removed, Hann window).  1 when neither diagonal dominates;
  the photos' own ratios say how far from 1 a real texture lies.  A decoder that draws strokes along a fixed
  direction shows the same ratio away from 1 on every photo;
- ``T`` anisotropy: per octave, the largest singular value of the encoded transform over the middle one, and the
  major axis; a translator that stretches every photo's octaves along the same direction has a cosine near 1
  between photos' major axes.

Prints, per model: the median and range of log2 diag on fronts and floors (0 is no preference), the photos'
own, and the octaves' median stretch ratio and agreement of major axes between photos.  ``--sheet JPG``: a
picture, one row per photo named by ``--photos`` (file-name prefixes): the photo, then per model a front and a
floor (192² px, seed 1, as an artist's preview).
"""
from __future__ import annotations

import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from omninoise.backend.solid.model import SolidTextureModel, slice_points  # noqa: E402
from omninoise.export import read_rgb  # noqa: E402
from omninoise.training.solid.photo_set import photo_set  # noqa: E402

SIZE = 128


def diagonal_ratio(rgb: np.ndarray) -> float:
    """Power at +45 over power at -45 degrees of an image float (H, W, 3) (see module doc)."""
    lum = rgb.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    lum = lum - lum.mean()
    h, w = lum.shape
    win = np.outer(np.hanning(h), np.hanning(w))
    P = np.abs(np.fft.fft2(lum * win)) ** 2
    fy = np.fft.fftfreq(h)[:, None] * np.ones((1, w))
    fx = np.ones((h, 1)) * np.fft.fftfreq(w)[None, :]
    r = np.hypot(fx, fy)
    band = (r >= 0.05) & (r <= 0.35)
    # image rows grow downwards: a stroke rising to the right (+45 degrees on screen) has its wave vector
    # along (1, 1) in (fx, fy-with-rows-down) coordinates
    ang = np.degrees(np.arctan2(fy, fx)) % 180.0
    plus = band & (np.abs(ang - 45.0) < 22.5)
    minus = band & (np.abs(ang - 135.0) < 22.5)
    return float(P[plus].sum() / max(P[minus].sum(), 1e-12))


def transform_axes(T: np.ndarray) -> tuple:
    """Per octave (m, 3, 3): largest over middle singular value (m,), unit major axis in world space (m, 3)."""
    _, s, vt = np.linalg.svd(T.astype(np.float64))
    return s[:, 0] / s[:, 1], vt[:, 0, :]


def measure(model_dir: str, photos: list, images: list) -> dict:
    m = SolidTextureModel(model_dir)
    fronts, floors, ratios, axes = [], [], [], []
    for img in images:
        code = m.photo_code(img, periodic=False, gaussian=False)
        for seed in (0, 1):
            for axis, out in (("y", fronts), ("z", floors)):
                pts = slice_points(SIZE, m.px_per_unit, axis, (0.37 * seed, 0.61 * seed, 0.29 * seed))
                out.append(diagonal_ratio(m.evaluate(pts, code, seed=seed).reshape(SIZE, SIZE, 3)))
        r, a = transform_axes(np.asarray(code.T))
        ratios.append(r)
        axes.append(a)
    axes = np.stack(axes)                                           # (P, m, 3)
    cos = np.abs(np.einsum("pmi,qmi->mpq", axes, axes))            # per octave, photo against photo
    P = axes.shape[0]
    agree = (cos.sum(axis=(1, 2)) - P) / (P * (P - 1))              # mean off-diagonal |cos|, per octave
    return dict(front=np.log2(fronts), floor=np.log2(floors), stretch=np.median(np.stack(ratios), axis=0),
                agree=agree, spin=m.spin)


def sheet(path: str, models: list, photos: list, size: int = 192) -> None:
    """Photo | per model: front, floor (slices through (0.3, 0.3, 0.3), seed 1), one row per photo."""
    from PIL import Image

    from omninoise.export.atomic import atomic_path

    ms = [SolidTextureModel(d) for d in models]
    rows = []
    for p in photos:
        img = read_rgb(p)
        cells = [img[:size, :size]]
        for m in ms:
            code = m.photo_code(img, periodic=False, gaussian=False)
            for axis in ("y", "z"):
                pts = slice_points(size, m.px_per_unit, axis, (0.3, 0.3, 0.3))
                cells.append(m.evaluate(pts, code, seed=1).reshape(size, size, 3))
        rows.append(np.concatenate([np.pad(c, ((2, 2), (2, 2), (0, 0)), constant_values=1.0) for c in cells], 1))
    pic = (np.clip(np.concatenate(rows, 0), 0, 1) * 255 + 0.5).astype(np.uint8)
    with atomic_path(path) as tmp:
        Image.fromarray(pic).save(tmp, format="JPEG", quality=90)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="+")
    ap.add_argument("--every", type=int, default=6, help="every N-th held-out photo (default 6: 15 of 87)")
    ap.add_argument("--sheet", help="write a picture (JPEG) of the photos named by --photos")
    ap.add_argument("--photos", nargs="+", default=["grass__grass_field_dry", "rock__cliff_rocky",
                                                    "sand__desert_plants_b_persia", "soil__dirt_flaky"])
    args = ap.parse_args(argv)
    if args.sheet:
        val = photo_set("val")
        picked = [next((p for p in val if os.path.basename(p).startswith(k)), None) for k in args.photos]
        if None in picked:
            ap.error(f"no held-out photo starts with {args.photos[picked.index(None)]!r}")
        sheet(args.sheet, args.models, picked)
        print(args.sheet)
    photos = photo_set("val")[::args.every]
    images = [read_rgb(p) for p in photos]
    own = np.log2([diagonal_ratio(img[:SIZE, :SIZE]) for img in images])
    print(f"{len(photos)} held-out photos; log2(+45/-45 power) of the photos themselves: median {np.median(own):+.2f}, "
          f"range {own.min():+.2f} .. {own.max():+.2f}")
    for d in args.models:
        r = measure(d, photos, images)
        print(f"{d} (spin {r['spin'] or 'none'}):")
        for k in ("front", "floor"):
            v = r[k]
            print(f"  {k:5s} log2 diag: median {np.median(v):+.2f}, range {v.min():+.2f} .. {v.max():+.2f}, "
                  f"same sign on {max((v > 0).sum(), (v < 0).sum())} of {len(v)} slices")
        print("  stretch (s1/s2) per octave: " + " ".join(f"{x:.2f}" for x in r["stretch"]))
        print("  the translator's major axes (before any spin): agreement between photos (mean |cos|, 0.5 for random): "
              + " ".join(f"{x:.2f}" for x in r["agree"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
