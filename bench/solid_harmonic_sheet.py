"""Held-out photos and their solid textures with and without the harmonic part:
``python bench/solid_harmonic_sheet.py [-o JPG] [PREFIX ...]``.

One row per photo of ``data/photos/val`` whose name starts with a PREFIX (default: the brick, wood, concrete,
soil and fabric photos): photo (top-left 128²) | the texture-space model alone (front view, plane y) | with the
photo's harmonic part (backend/solid/harmonic.py): front (y), side (x), floor (z), front at seed 1 | a cube whose
visible faces are sampled from the 3D texture | random phase noise.  The slices are those of
``bench/eval_solid_photos.py``.
"""
from __future__ import annotations

import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from backend.solid.model import SolidTextureModel  # noqa: E402
from bench.eval_solid_photos import cube, photos, read, slice_image  # noqa: E402
from export.atomic import atomic_path  # noqa: E402
from training.solid import photo_eval as pe  # noqa: E402

DEFAULT = ("brick", "wood", "concrete", "soil__farmland", "fabric__karts", "paving__aegean_anatolia_paving")


def main(argv=None) -> int:
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("prefixes", nargs="*", default=list(DEFAULT))
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "docs", "img", "solid_harmonic.jpg"))
    a = ap.parse_args(argv)
    m = SolidTextureModel(a.model)
    rows = []
    for path in photos():
        if not os.path.basename(path).startswith(tuple(a.prefixes)):
            continue
        photo = read(path)
        alone, with_h = m.photo_code(photo, periodic=False), m.photo_code(photo)
        cb = cube(m, with_h)
        cb = np.asarray(Image.fromarray((cb * 255).astype(np.uint8)).resize((128, 128)), np.float32) / 255
        cells = [photo[:128, :128], slice_image(m, alone, "y", 0), slice_image(m, with_h, "y", 0),
                 slice_image(m, with_h, "x", 0), slice_image(m, with_h, "z", 0), slice_image(m, with_h, "y", 1), cb,
                 pe.random_phase(photo, 128, np.random.default_rng(0))]
        rows.append(np.concatenate([np.pad(c, ((2, 2), (2, 2), (0, 0)), constant_values=1.0) for c in cells], 1))
        print(os.path.basename(path), flush=True)
    if not rows:
        raise SystemExit(f"no held-out photo starts with {', '.join(a.prefixes)}")
    img = (np.clip(np.concatenate(rows, 0), 0, 1) * 255 + 0.5).astype(np.uint8)
    with atomic_path(a.out) as tmp:
        Image.fromarray(img).save(tmp, format="JPEG", quality=90)
    print("wrote", a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
