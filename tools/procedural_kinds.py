"""The procedural kinds' sheet in the docs (docs/img/solid_procedural_kinds.png):
``.venv/bin/python -m tools.procedural_kinds``.

One row per brick or tile photo the evaluation holds out: the photo (a crop at its own pixel scale) | the solid the
default kinds fit (the evaluation's, ``field`` in docs/benchmarks/solid_procedural.json) | the solid fitted with
``families = ["bonds"]``: its front (the wall, y) and side (x) cuts through POINT and its top (z) cut through the
middle of the course that holds POINT (a cut along a bed joint shows nothing but joint), at the photo's scale, and
the front's gap mask (``ProceduralField.gaps``, the node group's Gap Mask: white in the joints).  The side and top
show what the front's courses become round a corner and on a floor.
"""
from __future__ import annotations

import json
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "docs", "img", "solid_procedural_kinds.png")
BENCH = os.path.join(ROOT, "docs", "benchmarks", "solid_procedural.json")
PHOTOS = ("brick__tex_trak_trak4_brick2a.jpg", "brick__beige_bricks.jpg", "tile__tile02.jpg", "tile__tile01.jpg")
SIDE = 160                        #: px per tile
POINT = (0.353, 0.617, 0.241)     #: the point the cuts pass through, texture units


def crop(img: np.ndarray, side: int) -> np.ndarray:
    """The central side x side px of an image (H, W, 3), edge-padded where it is smaller."""
    h, w = img.shape[:2]
    if h < side or w < side:
        img = np.pad(img, ((0, max(0, side - h)), (0, max(0, side - w)), (0, 0)), mode="edge")
        h, w = img.shape[:2]
    y, x = (h - side) // 2, (w - side) // 2
    return img[y:y + side, x:x + side]


def main() -> int:
    from bench.eval_procedural import photos
    from omninoise.backend.solid.model import slice_points
    from omninoise.backend.solid.procedural.field import ProceduralField
    from omninoise.backend.solid.procedural.bonds import PHASE
    from omninoise.backend.solid.procedural.fit import ProceduralConfig, fit_procedural
    from omninoise.export import read_rgb
    from tools.procedural_sheet import write_sheet

    with open(BENCH, encoding="utf-8") as f:
        measured = json.load(f)["photos"]
    paths = {os.path.basename(p): p for p in photos("structured", 1)}
    rows = []
    for name in PHOTOS:
        img = read_rgb(paths[name])
        default = ProceduralField.from_dict(measured[name]["field"])
        bonds = fit_procedural(img, ProceduralConfig(families=("bonds",))).field
        print(f"{name}: {default.family} by default; bonds {bonds.params}", flush=True)
        tiles = [crop(img, SIDE), default.image(SIDE, offset=POINT)]
        h = bonds.params["height"]
        mid = (np.floor(POINT[2] / h + PHASE) + 0.5 - PHASE) * h
        tiles += [bonds.image(SIDE, axis="y", offset=POINT), bonds.image(SIDE, axis="x", offset=POINT),
                  bonds.image(SIDE, axis="z", offset=(POINT[0], POINT[1], mid))]
        front = slice_points(SIDE, bonds.px_per_unit, "y", POINT)
        tiles.append(np.repeat(bonds.gaps(front).reshape(SIDE, SIDE, 1), 3, axis=2))
        rows.append(np.concatenate(tiles, axis=1))
    write_sheet(OUT, (np.clip(np.concatenate(rows, axis=0), 0.0, 1.0) * 255 + 0.5).astype(np.uint8))
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
