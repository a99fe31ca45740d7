"""Does a solid-texture loss prefer stones to speckle?  ``python bench/solid_arrangement.py [PHOTO ...]``

Fits settle in speckle because the training loss hardly prefers the
right arrangement once the colours are right.  For each photo (default: the
paving stones the capacity study fits, and held-out paving, brick, rock and
gravel photos), candidate images of SIZE² px are scored against random crops of
the photo by

- ``train``: the space model's training loss (sliced Wasserstein of random colour features + 10 x the colour
  histogram term, :func:`training.solid.train.texture_loss` with ``configs/solid/photo_space_3d.json``);
- ``arrangement``: the arrangement term alone (:mod:`training.solid.arrangement`: the same distance over
  one-channel features of each image's rank-Gaussianised luminance);
- ``soft_morph``: the differentiable morphology term (:mod:`training.solid.soft_morphology`);
- ``patch``: the evaluation's patch distance (:func:`training.solid.photo_eval.patch_swd`, x 1000);
- ``morph``: the level-set morphology distance (:mod:`training.solid.morphology`);
- ``structure`` (with ``--structure NET``): the sliced Wasserstein distance of the learned structure features
  (:mod:`training.solid.structure_features`, a network trained to tell photo crops from their random-phase twins).

Candidates: other crops of the photo; a Voronoi pavement (cells of ``--cell`` px, dark 2 px joints, one
shade per stone, pixel noise 0.01) with its own greys and with the photo's colours by rank; speckle (the
shipped space model's z slices for that photo); the same speckle with the photo's colours by rank; random
phase noise; a pixel shuffle.  Every loss is averaged over ``--draws`` draws of four crops.  A loss that sees
arrangement must put the pavement (with the photo's colours) clearly nearer than the speckle for paving
photos.  Writes JSON (``-o``).
"""
from __future__ import annotations

import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402
import torch  # noqa: E402

from omninoise.backend.solid.model import SolidTextureModel  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.training.solid import exemplars as ex, photo_eval as pe  # noqa: E402
from omninoise.training.solid.arrangement import ArrangementFeatures  # noqa: E402
from omninoise.training.solid.morphology import morphology_distance  # noqa: E402
from omninoise.training.solid.soft_morphology import soft_morphology_loss  # noqa: E402
from omninoise.training.solid.swd import swd_loss  # noqa: E402
from omninoise.training.solid.train import load_config, loss_features, structure_features, texture_loss  # noqa: E402

SIZE = 128
DEFAULT = ("train/paving__alpine_arctic_paving_stones_01.jpg", "val/paving__sahara_paving_stones_01.jpg",
           "val/brick__beige_bricks.jpg", "val/rock__alpine_cliff_b.jpg",
           "val/gravel__temp_dirt_gravel_plants.jpg")


def crops(photo: np.ndarray, n: int, rng: np.random.Generator) -> list:
    H, W, _ = photo.shape
    out = []
    for _ in range(n):
        y, x = rng.integers(0, H - SIZE + 1), rng.integers(0, W - SIZE + 1)
        out.append(photo[y:y + SIZE, x:x + SIZE])
    return out


def candidates(photo: np.ndarray, model: SolidTextureModel, cell: float, rng: np.random.Generator) -> dict:
    """name -> list of 4 (SIZE, SIZE, 3) images."""
    code = model.translate(model.encode(photo))
    speckle = [model.image(SIZE, code, seed=s, axis="z", offset=(3.1 + s, -2.7, 0.37)) for s in range(4)]
    paves = [pe.voronoi_pavement(SIZE, cell, rng) for _ in range(4)]
    return {
        "photo_crops": crops(photo, 4, rng),
        "pavement_own_greys": [np.repeat(p[..., None], 3, -1) for p in paves],
        "pavement_photo_colours": [pe.colour_by_rank(p, photo) for p in paves],
        "speckle": speckle,
        "speckle_photo_colours": [pe.colour_by_rank(s.mean(-1), photo) for s in speckle],
        "random_phase": [pe.random_phase(photo, SIZE, rng) for _ in range(4)],
        "pixel_shuffle": [pe.pixel_shuffle(photo, SIZE, rng) for _ in range(4)],
    }


def score(photo: np.ndarray, images: list, cfg, feats, arr, draws: int, rng: np.random.Generator,
          structure=None) -> dict:
    t = lambda ims: torch.from_numpy(np.stack(ims)).permute(0, 3, 1, 2).contiguous()  # noqa: E731
    out = t(images)
    g = torch.Generator().manual_seed(0)
    train, arrangement, soft, struct = [], [], [], []
    with torch.no_grad():
        for _ in range(draws):
            ref = t(crops(photo, 4, rng))
            train.append(texture_loss(cfg, feats, out, ref, g).item())
            arrangement.append(swd_loss(arr, out, ref, per_sample=True, generator=g).item())
            soft.append(soft_morphology_loss(out, ref, per_sample=True).item())
            if structure is not None:
                struct.append(swd_loss(structure, out, ref, per_sample=True, generator=g).item())
    extra = dict(structure=float(np.mean(struct))) if struct else {}
    return dict(**extra, train=float(np.mean(train)), arrangement=float(np.mean(arrangement)), soft_morph=float(np.mean(soft)),
                patch=float(pe.patch_swd(images, photo)), morph=float(np.mean([morphology_distance(i, photo)
                                                                                for i in images])))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("photos", nargs="*", default=list(DEFAULT), help="paths under data/photos (or any image)")
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "solid", "photo_space_3d.json"))
    ap.add_argument("--cell", type=float, default=28.0, help="pavement cell size, px")
    ap.add_argument("--draws", type=int, default=6)
    ap.add_argument("--structure", help="a trained structure network (training.solid.structure_features) to score too")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "solid_arrangement.json"))
    a = ap.parse_args(argv)
    torch.set_num_threads(2)
    cfg = load_config(a.config)
    feats, arr = loss_features(cfg), ArrangementFeatures()
    structure = structure_features(a.structure) if a.structure else None
    model = SolidTextureModel(a.model)
    table = {}
    for name in a.photos:
        path = name if os.path.isfile(name) else os.path.join(ROOT, "data", "photos", name)
        photo = ex.load_image(path).permute(1, 2, 0).numpy()
        rng = np.random.default_rng(0)
        rows = {k: score(photo, ims, cfg, feats, arr, a.draws, rng, structure)
                for k, ims in candidates(photo, model, a.cell, rng).items()}
        table[os.path.basename(path)] = rows
        print(os.path.basename(path))
        print(f"  {'candidate':24s} {'train':>8s} {'arrange':>8s} {'soft_mo':>8s} {'patch':>8s} {'morph':>6s}"
              + (f" {'struct':>8s}" if structure is not None else ""))
        for k, r in rows.items():
            print(f"  {k:24s} {r['train']:8.4f} {r['arrangement']:8.4f} {r['soft_morph']:8.3f} {r['patch']:8.1f} "
                  f"{r['morph']:6.2f}" + (f" {r['structure']:8.4f}" if structure is not None else ""))
    write_json(a.out, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
