"""Validate a solid-texture loss before training with it: optimise the pixels of a 2D image with the loss alone.

``python bench/solid_loss_sheet.py [--steps 300] [-o docs/img/solid_loss_sheet.png]``

For held-out photos of the photo set, an image of SIZE² px is optimised
(Adam on a 5-level Laplacian parametrisation: coarse levels move first,
as in multi-scale texture synthesis) against the training loss of
``configs/solid/photo_space_3d.json`` (sliced Wasserstein of random
multi-scale features + colour histogram) and, for comparison, the earlier
Gram loss.  If the loss sees structure, the optimised image shows the photo's
stones, grains and bricks; a loss that only sees colour and spectrum gives
blotches.  The sheet: photo | Gram loss | sliced Wasserstein loss [| the same plus the learned structure term
of :mod:`training.solid.structure_features`, with ``--structure NET``], one row per photo; the patch distance of
:mod:`training.solid.photo_eval` for each is printed and written beside the sheet (JSON).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402
import torch  # noqa: E402
import torch.nn.functional as F  # noqa: E402

from omninoise.export.atomic import atomic_path, write_json  # noqa: E402
from omninoise.training.solid import exemplars as ex  # noqa: E402
from omninoise.training.solid import photo_eval as pe  # noqa: E402
from omninoise.training.solid.train import SolidConfig, load_config, loss_features, texture_loss  # noqa: E402

DEFAULT_PHOTOS = ("gravel", "rock", "brick", "wood", "paving", "grass")


def optimise(cfg: SolidConfig, ref: torch.Tensor, size: int, steps: int, seed: int = 0) -> torch.Tensor:
    """Pixels (1, 3, size, size) optimised against ``cfg``'s loss for the reference (1, 3, H, W)."""
    g = torch.Generator().manual_seed(seed)
    feats = loss_features(cfg)
    params = [torch.zeros(1, 3, size >> lvl, size >> lvl, requires_grad=True) for lvl in range(5)]
    with torch.no_grad():
        params[-1] += (ref.mean((2, 3), keepdim=True) - 0.5)
        params[-1] += 0.05 * torch.randn(params[-1].shape, generator=g)
    opt = torch.optim.Adam(params, lr=0.03)
    for _ in range(steps):
        img = 0.5 + sum(F.interpolate(p, size=(size, size), mode="bilinear", align_corners=False) for p in params)
        loss = texture_loss(cfg, feats, img, ref, g)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return img.detach().clamp(0, 1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--photos", default=",".join(DEFAULT_PHOTOS), help="categories (first held-out photo of each)")
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "solid", "photo_space_3d.json"))
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--structure", help="a trained structure network (training.solid.structure_features): adds the "
                                        "column 'structure', the sliced Wasserstein loss plus its learned structure term")
    ap.add_argument("--structure-weight", type=float, default=0.2)
    ap.add_argument("--no-gram", action="store_true", help="leave out the Gram-loss column")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "docs", "img", "solid_loss_sheet.png"))
    a = ap.parse_args(argv)
    if a.threads:
        torch.set_num_threads(a.threads)
    from PIL import Image

    swd_cfg = load_config(a.config)
    columns = [] if a.no_gram else [("gram", SolidConfig.from_dict({**vars(swd_cfg), "loss": "gram"}))]
    columns.append(("swd", swd_cfg))
    if a.structure:
        columns.append(("structure", SolidConfig.from_dict({**vars(swd_cfg), "structure_net": a.structure,
                                                            "structure_weight": a.structure_weight})))
    val = ex.photo_set("val")
    rows, results = [], {}
    for cat in a.photos.split(","):
        path = next((p for p in val if os.path.basename(p).startswith(cat + "__")), None)
        if path is None:
            print(f"no held-out {cat} photo", file=sys.stderr)
            continue
        ref = ex.load_image(path).unsqueeze(0)
        photo = ref[0].permute(1, 2, 0).numpy()
        row, res = [ref[..., :a.size, :a.size]], {}
        for name, cfg in columns:
            t = time.time()
            out = optimise(cfg, ref, a.size, a.steps)
            res[name] = round(pe.patch_swd(out[0].permute(1, 2, 0).numpy(), photo), 1)
            res[name + "_seconds"] = round(time.time() - t, 1)
            row.append(out)
        res["random_phase"] = round(pe.patch_swd(pe.random_phase(photo, a.size, np.random.default_rng(0)), photo), 1)
        results[os.path.basename(path)] = res
        print(os.path.basename(path), res, flush=True)
        rows.append(torch.cat(row, dim=3))
    sheet = (torch.cat(rows, dim=2)[0].permute(1, 2, 0).numpy() * 255.0 + 0.5).astype(np.uint8)
    with atomic_path(a.out) as tmp:
        Image.fromarray(sheet).save(tmp, format="PNG")
    write_json(os.path.splitext(a.out)[0] + ".json", dict(steps=a.steps, size=a.size, config=a.config,
                                                          columns=[n for n, _ in columns], structure=a.structure,
                                                          structure_weight=a.structure_weight if a.structure else None,
                                                          photos=results))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
