"""Can a decoder that sees a neighbourhood draw a photo's structure where the per-point decoder cannot?

The capacity experiment of ``bench/solid_capacity.py`` with the per-point decoder replaced by the multi-scale
convolutional generator of ``training/solid/conv_generator.py``: the same single-exemplar 2D config (photo, crop,
batch, steps, learning-rate schedule, loss: ``train.texture_loss``), colour through the photo's mean and colour
Cholesky factor as the affine decoders. Trained here, then rendered at the photo's smaller side (at most 256 px)
for several seeds and measured as ``solid_capacity`` measures (patch distance x 1000 and level-set morphology,
lower is better), beside random phase noise and a pixel shuffle of the same photo.

    python bench/solid_conv_capacity.py CONFIG [CONFIG ...] [--width 32 --scales 5 --steps N] [--out OUT]

In 3D (``--dim 3``) each step generates volumes of side ``--crop`` and fits slices of them
(``training/solid/conv_fit.py``); the measure pools the middle slices of 128³ volumes.

Prints a table; writes OUT.json, OUT.png (per photo: the photo, two textures (3D: slices), random phase noise) and
OUT_<name>.pt (the generator's weights). Long fits (3D on a CPU): ``--save-every N`` keeps a checkpoint every N
steps in OUT_<name>.ckpt, and ``--resume`` goes on from it (the same settings are required; the fit resumes
exactly, random draws included).
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np
import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.export.atomic import atomic_path, write_json  # noqa: E402
from omninoise.training.precision import resolve  # noqa: E402
from omninoise.training.solid.conv_fit import colour, fit  # noqa: E402
from omninoise.training.solid.conv_generator import ConvGenerator, draw_noise  # noqa: E402
from omninoise.training.solid.model import colour_stats  # noqa: E402
from omninoise.training.solid.morphology import morphology_distance  # noqa: E402
from omninoise.training.solid.photo_eval import patch_swd, pixel_shuffle, random_phase, tile_sheet  # noqa: E402
from omninoise.training.solid.train import load_config, loss_features, texture_loss, training_images  # noqa: E402

MAX_SIZE = 256


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("configs", nargs="+")
    ap.add_argument("--dim", type=int, default=2, choices=(2, 3))
    ap.add_argument("--crop", type=int, default=None, help="default: the config's (3D: the volume's side)")
    ap.add_argument("--batch", type=int, default=None, help="default: the config's")
    ap.add_argument("--scale", type=float, default=None, help="exemplar_scale; default: the config's")
    ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--device", default="cpu", help="cpu or cuda (training; the measurements run on the CPU)")
    ap.add_argument("--precision", default="auto", choices=("auto", "fp32", "bf16"))
    ap.add_argument("--upright", action="store_true",
                    help="3D: train and measure only the slices through the vertical axis, upright (walls)")
    ap.add_argument("--flat", action="store_true", help="joins keep width channels instead of growing")
    ap.add_argument("--scales", type=int, default=5)
    ap.add_argument("--noise", type=int, default=4)
    ap.add_argument("--steps", type=int, default=None, help="default: the config's")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--budget-seconds", type=float, default=None, metavar="S",
                    help="fit the number of steps (at most --steps) to S seconds of training per config")
    ap.add_argument("--save-every", type=int, default=0, metavar="N", help="keep a checkpoint every N steps")
    ap.add_argument("--resume", action="store_true", help="go on from OUT_<name>.ckpt where it exists")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "solid_conv_capacity"))
    a = ap.parse_args(argv)
    rows, tiles = [], []
    for path in a.configs:
        cfg = load_config(path)
        for key, v in (("crop", a.crop), ("batch", a.batch), ("exemplar_scale", a.scale)):
            if v is not None:
                setattr(cfg, key, v)
        torch.manual_seed(cfg.seed)
        net = ConvGenerator(a.dim, a.scales, a.noise, a.width, grow=not a.flat)
        steps = a.steps or cfg.steps
        precision = resolve(a.precision, torch.device(a.device))
        photo = training_images(cfg)[0]
        name = os.path.basename(path).rsplit(".", 1)[0]
        ckpt = f"{a.out}_{name}.ckpt"
        # what a checkpoint must share with this run to be resumed by it
        setting = dict(config=os.path.relpath(os.path.abspath(path), ROOT), dim=a.dim, crop=cfg.crop, batch=cfg.batch,
                       scale=cfg.exemplar_scale, width=a.width, grow=not a.flat, scales=a.scales, noise=a.noise,
                       upright=a.upright, precision=precision)
        resume = None
        if a.resume and os.path.exists(ckpt):
            resume = torch.load(ckpt, weights_only=False, map_location=a.device)
            if resume["setting"] != setting:
                diff = sorted(k for k in setting if resume["setting"].get(k) != setting[k])
                raise SystemExit(f"{ckpt}: made with other settings ({', '.join(diff)}); drop --resume or match them")
            print(f"resuming {ckpt} at step {resume['step']}/{resume['steps']}", flush=True)

        def save(state: dict) -> None:
            os.makedirs(os.path.dirname(os.path.abspath(ckpt)), exist_ok=True)
            with atomic_path(ckpt) as tmp:
                torch.save(dict(state, setting=setting), tmp)

        seconds, steps = fit(cfg, net.to(a.device), photo, steps, loss_features(cfg).to(a.device), texture_loss,
                             precision, device=a.device, upright=a.upright, budget_seconds=a.budget_seconds,
                             resume=resume, save=save if a.save_every else None, save_every=a.save_every)
        net = net.cpu().eval()
        ref = photo.permute(1, 2, 0).numpy().astype(np.float32)
        size = min(MAX_SIZE if a.dim == 2 else MAX_SIZE // 2, *ref.shape[:2])
        size -= size % (2 ** (a.scales - 1))
        stats = colour_stats(photo.unsqueeze(0))
        g = torch.Generator().manual_seed(1)
        imgs = []
        with torch.no_grad():
            for _ in range(a.seeds):
                out = colour(net(draw_noise(1, size, a.dim, a.scales, a.noise, g)), stats)[0].clamp(0, 1)
                # 3D: the middle slices normal to x, y and z (upright: x and y, z along rows), pooled
                if a.dim == 2:
                    views = [out]
                else:
                    walls = [out[:, :, :, size // 2], out[:, :, size // 2]]
                    views = walls if a.upright else [out[:, size // 2]] + walls
                imgs += [v.permute(1, 2, 0).numpy().astype(np.float32) for v in views]
        rng = np.random.default_rng(0)
        rpn = [random_phase(ref, size, rng) for _ in imgs]
        shuffled = [pixel_shuffle(ref, size, rng) for _ in imgs]
        rows.append(dict(config=name, dim=a.dim, upright=a.upright,
                         photo=os.path.basename(cfg.exemplars[0]).rsplit(".", 1)[0], size=size, width=a.width,
                         grow=not a.flat, scales=a.scales, params=net.n_params(), steps=steps,
                         train_minutes=round(seconds / 60, 1), precision=precision, device=a.device,
                         model=round(patch_swd(imgs, ref), 1),
                         random_phase=round(patch_swd(rpn, ref), 1),
                         pixel_shuffle=round(patch_swd(shuffled, ref), 1),
                         morph=round(morphology_distance(imgs, ref), 3),
                         morph_random_phase=round(morphology_distance(rpn, ref), 3)))
        print(rows[-1], flush=True)
        tiles.append([ref[:size, :size]] + imgs[:3 if a.dim == 3 and not a.upright else 2] + [rpn[0]])
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        with atomic_path(f"{a.out}_{name}.pt") as tmp:
            torch.save(dict(state=net.state_dict(), dim=a.dim, scales=a.scales, noise=a.noise, width=a.width,
                            grow=not a.flat, config=path), tmp)
    cols = list(rows[0])
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r[c]) for c in cols) + " |")
    write_json(a.out + ".json", dict(seeds=a.seeds, rows=rows))
    tile_sheet(tiles, a.out + ".png")
    print(f"wrote {a.out}.json and {a.out}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
