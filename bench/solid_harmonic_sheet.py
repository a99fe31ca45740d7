"""Held-out photos and their solid textures with and without the harmonic part (or the Gaussian rest, or its
upright kind): ``python bench/solid_harmonic_sheet.py [--part harmonic|gaussian|upright] [-o JPG] [PREFIX ...]``.

One row per photo of ``data/photos/val`` whose name starts with a PREFIX (default: the brick, wood, concrete,
soil and fabric photos): photo (top-left 128²) | the texture-space model alone (front view, plane y) | with the
photo's harmonic part (backend/solid/harmonic.py): front (y), side (x), floor (z), front at seed 1 | a cube whose
visible faces are sampled from the 3D texture | random phase noise.  The slices are those of
``bench/eval_solid_photos.py``.  Neither has the Gaussian rest (backend/solid/spectral.py); with ``--part
gaussian`` the second column is the texture with its harmonic part and without the Gaussian rest, the next five
with the rest where the encode-time check keeps one (the default photos: the held-out photos it is kept for, up
to ``--limit``).  With ``--part upright`` the second column is the texture as it was before the upright rest
(backend/solid/upright.py) was offered, the next five the texture with it, for the held-out photos whose check
takes it.
"""
from __future__ import annotations

import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from omninoise.backend.solid import upright  # noqa: E402
from omninoise.backend.solid.model import SolidTextureModel  # noqa: E402
from bench.eval_solid_photos import cube, photos, read, slice_image  # noqa: E402
from omninoise.export.atomic import atomic_path  # noqa: E402
from omninoise.training.solid import photo_eval as pe  # noqa: E402

DEFAULT = ("brick", "wood", "concrete", "soil__farmland", "fabric__karts", "paving__aegean_anatolia_paving")


def main(argv=None) -> int:
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("prefixes", nargs="*")
    ap.add_argument("--part", choices=("harmonic", "gaussian", "upright"), default="harmonic")
    ap.add_argument("--limit", type=int, default=8, help="--part gaussian or upright: at most this many rows")
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("-o", "--out")
    a = ap.parse_args(argv)
    out = a.out or os.path.join(ROOT, "docs", "img", f"solid_{a.part}.jpg")
    prefixes = tuple(a.prefixes or (DEFAULT if a.part == "harmonic" else ("",)))
    m = SolidTextureModel(a.model)
    rows = []
    for path in photos():
        if not os.path.basename(path).startswith(prefixes) or (a.part != "harmonic" and len(rows) >= a.limit):
            continue
        photo = read(path)
        if a.part == "harmonic":
            alone, with_h = m.photo_code(photo, periodic=False, gaussian=False), m.photo_code(photo, gaussian=False)
        elif a.part == "upright":
            with_h = m.photo_code(photo)
            if (with_h.rest is None or with_h.rest.kind != "upright") and not a.prefixes:
                continue
            gate, upright.UPRIGHT_GATE = upright.UPRIGHT_GATE, 2.0    # never offered: the texture before it
            try:
                alone = m.photo_code(photo)
            finally:
                upright.UPRIGHT_GATE = gate
        else:
            alone = m.photo_code(photo, gaussian=False)
            with_h = m.with_gaussian_rest(alone, photo)
            if with_h.rest is None and not a.prefixes:
                continue
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
    with atomic_path(out) as tmp:
        Image.fromarray(img).save(tmp, format="JPEG", quality=90)
    print("wrote", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
