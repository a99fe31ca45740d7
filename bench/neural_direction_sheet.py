"""Does the model draw the direction it is asked for?  `python bench/neural_direction_sheet.py OUT.png --model A [--model B]`.

For each class with a direction parameter (training/evaluate.py's ORIENTED: fibers, phasor, gabor and
gabor_texture), one row per class: the direction asked for goes 0, 45, 90 and 135 degrees from left to right,
and each direction has a column group: the zoo's image, then each model's image from the same seed and
sampler (the default). Under the sheet a JSON gives the dominant gradient direction of every image and each
model's direction error (the evaluation's measure: 0 follows the parameter, 45 on average draws a direction
of its own). Writes OUT.png and OUT.json.
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.generate import generate  # noqa: E402
from omninoise.backend.neural.model import NeuralNoiseModel  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.export.images import write_png  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--model", action="append", required=True, help="a model folder (repeat to compare)")
    ap.add_argument("--label", action="append", help="a column label per --model")
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=0, help="onnxruntime threads (0: its default, every core)")
    a = ap.parse_args()
    import torch

    from omninoise.training import zoo
    from omninoise.training.evaluate import (DIRECTIONS, ORIENTED, angle_difference, gradient_direction, known_params,
                                   oriented_params)

    labels = a.label or [os.path.basename(os.path.normpath(m)) for m in a.model]
    if len(labels) != len(a.model):
        ap.error("give one --label per --model")
    models = [NeuralNoiseModel(m, threads=a.threads) for m in a.model]
    S, gap, group = a.size, 4, 1 + len(models)
    sheet = np.ones((len(ORIENTED) * (S + gap), len(DIRECTIONS) * (group * (S + gap) + 2 * gap)), np.float32)
    report = dict(size=S, seed=a.seed, directions=list(DIRECTIONS), models=dict(zip(labels, a.model)), classes={})
    for r, name in enumerate(ORIENTED):
        row = {label: dict(direction=[], error=[]) for label in ["zoo"] + labels}
        for j, deg in enumerate(DIRECTIONS):
            params = oriented_params(name, math.radians(deg))
            real = zoo.generate(name, params, torch.tensor([a.seed]), S).numpy()[0]
            imgs = [real] + [generate(m, C.uniform(m, (name, known_params(m, name, params)), S, S), seed=a.seed)
                             for m in models]
            ref = float(gradient_direction(real[None])[0])
            for label, img in zip(["zoo"] + labels, imgs):
                d = float(gradient_direction(img[None])[0])
                row[label]["direction"].append(round(d, 1))
                row[label]["error"].append(round(float(angle_difference(d, ref)), 1))
            for k, img in enumerate(imgs):
                x0 = j * (group * (S + gap) + 2 * gap) + k * (S + gap)
                sheet[r * (S + gap): r * (S + gap) + S, x0: x0 + S] = np.clip(img, 0, 1)
        for label in labels:
            row[label]["mean_error"] = round(float(np.mean(row[label]["error"])), 1)
        report["classes"][name] = dict(row, param=ORIENTED[name][0])
        print(name, {k: v["direction"] for k, v in row.items()}, file=sys.stderr)
    write_png(a.out, (sheet * 255 + 0.5).astype(np.uint8))
    write_json(os.path.splitext(a.out)[0] + ".json", dict(report, columns=["zoo"] + labels))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
