"""The colour photo set's files (``tools/build_photo_set.py``): ``data/photos/{train,val}/CATEGORY__NAME.jpg``.

Torch-free, so that the tools that only read the set (``training.solid.harmonics``, the benches) list it the way
training does.
"""
from __future__ import annotations

import os

__all__ = ["PHOTO_DIR", "photo_set", "expand"]

PHOTO_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "data", "photos")


def photo_set(split: str, photo_dir: str | None = None) -> list:
    """Paths of the photo set's ``split`` ('train' or 'val'), sorted; whole photos are held out, never pixels."""
    if split not in ("train", "val"):
        raise ValueError(f"photo split must be 'train' or 'val', got {split!r}")
    folder = os.path.join(photo_dir or PHOTO_DIR, split)
    files = sorted(f for f in os.listdir(folder) if f.endswith((".jpg", ".png"))) if os.path.isdir(folder) else []
    if not files:
        raise ValueError(f"no photos in {folder}: run python tools/build_photo_set.py")
    return [os.path.join(folder, f) for f in files]


def expand(names, root: str | None = None) -> tuple:
    """Exemplar names with ``photos:train`` / ``photos:val`` replaced by the photo set's files; with ``root`` (a
    checkout other than this one) the set is ``root/data/photos`` and other names are paths below ``root``."""
    photo_dir = os.path.join(root, "data", "photos") if root else None
    out = []
    for n in names:
        if n.startswith("photos:"):
            out += photo_set(n.split(":", 1)[1], photo_dir)
        else:
            out.append(os.path.join(root, n) if root else n)
    return tuple(out)
