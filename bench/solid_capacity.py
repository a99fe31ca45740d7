"""Can the per-point decoder over noise octaves carry a photo's structure at all?

Single-exemplar 2D models of structured photos (paving stones, brick courses), trained with the sliced
Wasserstein loss by ``python -m omninoise.training.solid.train --config C --out RUN``, one per decoder size, are
rendered at the photo's smaller side (at most 256 px) for several seeds and compared with the photo they were fitted to (a capacity question:
how near can the model get to its own exemplar, not generalisation) by the patch distance of
``training/solid/photo_eval.py`` (x 1000, lower is better) and by the level-set morphology distance of
``training/solid/morphology.py`` (region sizes, outlines, connectivity; lower is better), beside random
phase noise and a pixel shuffle of the same photo.

    python bench/solid_capacity.py RUN [RUN ...] [--out docs/img/solid_capacity]

Prints a table and writes OUT.json and OUT.png (per photo: the photo, each run's texture, random phase).
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.training.solid.model import colour_stats  # noqa: E402
from omninoise.training.solid.morphology import morphology_distance  # noqa: E402
from omninoise.training.solid.photo_eval import patch_swd, pixel_shuffle, random_phase, tile_sheet  # noqa: E402
from omninoise.training.solid.train import SolidConfig, build_model, render, training_images  # noqa: E402

MAX_SIZE = 256


def load_run(folder: str):
    state = torch.load(os.path.join(folder, "ckpt.pt"), map_location="cpu", weights_only=False)
    cfg = SolidConfig.from_dict(state["config"])
    model = build_model(cfg)
    model.load_state_dict(state["model"])
    return cfg, model.eval(), state


def textures(cfg, model, photo: torch.Tensor, seeds, SIZE: int) -> list:
    """(SIZE, SIZE, 3) float32 images of the model at the training scale, one per seed."""
    u = (torch.arange(SIZE, dtype=torch.float32) + 0.5) / cfg.px_per_unit
    vv, uu = torch.meshgrid(u, u, indexing="ij")
    plane = torch.stack([uu.flatten(), -vv.flatten()], dim=-1)
    out = []
    stats = colour_stats(photo.unsqueeze(0)) if cfg.colour == "affine" else None
    for s in seeds:
        off = torch.tensor([[[17.0 * s, -9.0 * s]]])
        with torch.no_grad():
            e, T = model.codes(batch=1)
            img = render(model, e, T, plane.unsqueeze(0) + off, np.array([s]), SIZE, stats)
        out.append(img[0].permute(1, 2, 0).clamp(0, 1).numpy().astype(np.float32))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "solid_capacity"))
    a = ap.parse_args(argv)
    rows, sheet = [], {}
    for run in a.runs:
        cfg, model, state = load_run(run)
        photo = training_images(cfg)[0]                      # (3, H, W) at the training scale
        ref = photo.permute(1, 2, 0).numpy().astype(np.float32)
        SIZE = min(MAX_SIZE, *ref.shape[:2])
        imgs = textures(cfg, model, photo, range(1, a.seeds + 1), SIZE)
        rng = np.random.default_rng(0)
        rpn = [random_phase(ref, SIZE, rng) for _ in range(a.seeds)]
        shuffled = [pixel_shuffle(ref, SIZE, rng) for _ in range(a.seeds)]
        name = os.path.basename(cfg.exemplars[0]).rsplit(".", 1)[0]
        row = dict(run=os.path.basename(run.rstrip("/")), photo=name, width=cfg.width, layers=cfg.layers,
                   octaves=cfg.octaves, params=int(state.get("n_params", 0)), steps=int(state["step"]),
                   train_minutes=round(state.get("elapsed", 0.0) / 60, 1),
                   model=round(patch_swd(imgs, ref), 1),
                   random_phase=round(patch_swd(rpn, ref), 1), pixel_shuffle=round(patch_swd(shuffled, ref), 1),
                   morph=round(morphology_distance(imgs, ref), 3), morph_random_phase=round(morphology_distance(rpn, ref), 3),
                   morph_pixel_shuffle=round(morphology_distance(shuffled, ref), 3),
                   # the photo against itself: its right half against its left half (what "near" means)
                   morph_photo_halves=round(morphology_distance(ref[:, ref.shape[1] // 2:],
                                                                ref[:, :ref.shape[1] // 2]), 3),
                   cellular=cfg.cellular, size=SIZE)
        rows.append(row)
        sheet.setdefault(name, dict(photo=ref[:SIZE, :SIZE], rpn=random_phase(ref, SIZE, np.random.default_rng(1)),
                                    runs=[], size=SIZE))
        sheet[name]["runs"].append(imgs[0])
    cols = ["run", "photo", "size", "width", "layers", "cellular", "params", "steps", "train_minutes", "model",
            "random_phase", "pixel_shuffle", "morph", "morph_random_phase", "morph_pixel_shuffle",
            "morph_photo_halves"]
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r[c]) for c in cols) + " |")
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    write_json(a.out + ".json", dict(seeds=a.seeds, rows=rows))
    tile_sheet([[v["photo"]] + v["runs"] + [v["rpn"]] for v in sheet.values()], a.out + ".png")
    print(f"wrote {a.out}.json and {a.out}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
