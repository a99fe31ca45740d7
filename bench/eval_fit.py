"""Inverse design, evaluated: `python -m bench fit OUT_PREFIX [--size 128] [--fit-size 64] [--per-class 1]`.

Held-out zoo images: for every trained class, ``--per-class`` images rendered by the zoo (training/zoo.py)
with parameters drawn uniformly in their ranges and seeds the training never drew (10⁶ and up). Each is fitted
(backend/neural/fit.py) and regenerated at its own size with the shipped sampler defaults and the fitted seed.
Reported: class accuracy (the fitted dominant class is the true one), the normalised parameter error of correctly
classified fits against the error of guessing mid-range, and the texture distance (the fit's statistic) from the
target to the regenerated image against the distance to a random same-class zoo image (other parameters, other
seed): a ratio below 1 means the fit found more than the class.

Photos: the first validation photo of every category of data/photos (colour, converted to grey, centre 256² crop),
fitted the same way; reported against the best single class at mid-range parameters (stage 1 of the search, same
seed and steps) and regenerated at ``--size`` for the sheet.

Writes OUT_PREFIX.json and OUT_PREFIX_zoo.png / OUT_PREFIX_photos.png (target | fit, pairs in rows).
Needs torch (for the zoo); the fit itself does not.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend.neural.fit import (describe, distance, fit, fitted_conditioning, load_bank, prepare_target,
                                render, target_statistic)
from omninoise.backend.paths import fit_bank
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.export.atomic import write_json
from omninoise.export.images import read_rgb, write_png


def zoo_image(name: str, u: np.ndarray, seed: int, size: int, classes: dict) -> tuple:
    import torch

    from omninoise.training import zoo

    spec = classes[name]["params"]
    params = {p["name"]: float(p["min"] + uu * (p["max"] - p["min"])) for p, uu in zip(spec, u)}
    img = zoo.generate(name, {k: torch.tensor([v]) for k, v in params.items()}, seeds=torch.tensor([seed]), size=size)
    return img[0].numpy().astype(np.float32), params


def sheet(pairs: list, size: int, path: str) -> None:
    gap, cols = 4, 4
    rows = -(-len(pairs) // cols)
    out = np.ones((rows * (size + gap), cols * (2 * size + 3 * gap)), np.float32)
    for i, (a, b) in enumerate(pairs):
        r, c = divmod(i, cols)
        y, x = r * (size + gap), c * (2 * size + 3 * gap)
        out[y:y + size, x:x + size] = a[:size, :size]
        out[y:y + size, x + size + gap:x + 2 * size + gap] = b[:size, :size]
    write_png(path, (np.clip(out, 0, 1) * 255 + 0.5).astype(np.uint8))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--fit-size", type=int, default=64)
    ap.add_argument("--per-class", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--photos", type=int, default=1, help="photos per category (0: none)")
    ap.add_argument("--bank", default=fit_bank(), help="inverse-design bank folder ('' : none)")
    a = ap.parse_args(argv)
    m = NeuralNoiseModel(a.model, threads=a.threads)
    names = list(m.config.get("trained_classes") or m.classes)
    bank = load_bank(a.bank) if a.bank else None
    rng = np.random.default_rng(2024)
    rows, pairs, t0 = [], [], time.perf_counter()
    for name in names:
        dims = len(m.class_params[name]["params"])
        for j in range(a.per_class):
            u = rng.uniform(0.05, 0.95, dims)
            target, params = zoo_image(name, u, 1_000_000 + 97 * j + names.index(name), a.size, m.class_params)
            t = time.perf_counter()
            res = fit(m, target, size=a.fit_size, seed=0, bank=bank)
            secs = time.perf_counter() - t
            regen = generate(m, fitted_conditioning(m, res, a.size, a.size), seed=res.seed)
            other, _ = zoo_image(name, rng.uniform(0.05, 0.95, dims), 2_000_000 + j, a.size, m.class_params)
            ts = describe(target)
            top = max(res.classes, key=res.classes.get)
            row = dict(cls=name, params=params, fitted=res.to_json(), correct=top == name, seconds=round(secs, 1),
                       d_fit=distance(describe(regen), ts), d_random_same_class=distance(describe(other), ts))
            if top == name and dims:
                spec = m.class_params[name]["params"]
                got = [(res.params[name][p["name"]] - p["min"]) / (p["max"] - p["min"]) for p in spec]
                row["param_error"] = float(np.mean(np.abs(np.array(got) - u)))
                row["param_error_mid"] = float(np.mean(np.abs(0.5 - u)))
            rows.append(row)
            pairs.append((target, regen))
            print(f"{name:16s} -> {top:16s} {res.classes} d {row['d_fit']:.3f} vs random {row['d_random_same_class']:.3f}"
                  f" ({secs:.0f} s)", file=sys.stderr, flush=True)
    sheet(pairs, a.size, a.out + "_zoo.png")
    ok = [r for r in rows if "param_error" in r]
    summary = dict(
        zoo_images=len(rows), class_accuracy=round(float(np.mean([r["correct"] for r in rows])), 3),
        param_error=round(float(np.mean([r["param_error"] for r in ok])), 3) if ok else None,
        param_error_mid_guess=round(float(np.mean([r["param_error_mid"] for r in ok])), 3) if ok else None,
        distance_fit_median=round(float(np.median([r["d_fit"] for r in rows])), 4),
        distance_random_same_class_median=round(float(np.median([r["d_random_same_class"] for r in rows])), 4),
        fit_beats_random_same_class=int(sum(r["d_fit"] < r["d_random_same_class"] for r in rows)),
        seconds_per_fit=round(float(np.mean([r["seconds"] for r in rows])), 1))
    photo_rows, photo_pairs = [], []
    if a.photos:
        man = json.load(open(os.path.join(ROOT, "data", "photos", "manifest.json")))
        seen = {}
        for ph in man["photos"]:
            if ph["split"] == "val" and seen.get(ph["category"], 0) < a.photos:
                seen[ph["category"]] = seen.get(ph["category"], 0) + 1
                rgb = read_rgb(os.path.join(ROOT, "data", "photos", ph["file"]))
                H, W, _ = rgb.shape
                c = min(H, W, 256)
                crop = rgb[(H - c) // 2:(H - c) // 2 + c, (W - c) // 2:(W - c) // 2 + c]
                res = fit(m, crop, size=a.fit_size, seed=0, bank=bank)
                grey = crop.mean(axis=2)
                ts = target_statistic(prepare_target(grey, m.multiple_of)[0], a.fit_size)
                mids = [((n, {}), None, 0.0, 0) for n in names]  # every class at mid-range parameters, seed 0
                singles = {}
                for i in range(0, len(mids), 8):
                    for (spec, *_), g in zip(mids[i:i + 8], render(m, mids[i:i + 8], a.fit_size)):
                        singles[spec[0]] = distance(describe(g), ts)
                best_single = min(singles, key=singles.get)
                single = singles[best_single]
                regen = generate(m, fitted_conditioning(m, res, a.size, a.size), seed=res.seed)
                photo_rows.append(dict(photo=ph["file"], category=ph["category"], licence=ph.get("licence"),
                                       fitted=res.to_json(), d_fit=round(res.distance, 4),
                                       d_best_single_class=round(single, 4), best_single_class=best_single))
                photo_pairs.append((grey, regen))
                print(f"{ph['category']:10s} -> {res.classes} d {res.distance:.3f} vs best single {best_single} "
                      f"{single:.3f}", file=sys.stderr, flush=True)
        sheet(photo_pairs, a.size, a.out + "_photos.png")
        summary.update(photos=len(photo_rows),
                       photo_distance_fit_median=round(float(np.median([r["d_fit"] for r in photo_rows])), 4),
                       photo_distance_best_single_median=round(
                           float(np.median([r["d_best_single_class"] for r in photo_rows])), 4))
    summary["seconds"] = round(time.perf_counter() - t0, 1)
    write_json(a.out + ".json", dict(summary=summary, model=m.fingerprint, size=a.size, fit_size=a.fit_size,
                                     zoo=rows, photos=photo_rows))
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
