"""Long-range structure at 256²: `python -m bench sheet-structure OUT.png --model A [--model B ...]`.

The classes whose structure spans more than a small crop (damascus bands, fibre runs, Gabor and phasor
orientation and frequency, by default) at their default parameters: one row per class, the zoo's ground truth
first, then each model's generation from the same seed, side by side. Beside each image its orientation
coherence (1 = one orientation over the whole image, 0 = isotropic) and under the sheet a JSON with those and
the low-frequency spectrum error against the zoo (the measures of training/evaluate.py), so the
picture and the numbers can be read together. Writes OUT.png and OUT.json.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np


from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.export.atomic import write_json
from omninoise.export.images import write_png

CLASSES = ("damascus", "fibers", "gabor", "gabor_texture", "phasor")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--model", action="append", required=True, help="a model folder (repeat to compare)")
    ap.add_argument("--label", action="append", help="a column label per --model")
    ap.add_argument("--classes", default=",".join(CLASSES))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--zoo-seeds", type=int, default=8, help="zoo images per class for the spectrum reference")
    ap.add_argument("--threads", type=int, default=0, help="onnxruntime threads (0: its default, every core)")
    a = ap.parse_args(argv)
    import torch

    from omninoise.training import zoo
    from omninoise.training.evaluate import known_params, orientation_coherence, psd_error

    classes = [c.strip() for c in a.classes.split(",") if c.strip()]
    labels = a.label or [os.path.basename(os.path.normpath(m)) for m in a.model]
    if len(labels) != len(a.model):
        ap.error("give one --label per --model")
    models = [NeuralNoiseModel(m, threads=a.threads) for m in a.model]
    S, gap = a.size, 4
    sheet = np.ones((len(classes) * (S + gap), (1 + len(models)) * (S + gap)), np.float32)
    report = dict(size=S, seed=a.seed, models=dict(zip(labels, a.model)), classes={})
    for r, name in enumerate(classes):
        params = zoo.default_params(name)
        real = zoo.generate(name, params, torch.arange(a.zoo_seeds) + 500, S).numpy()
        row = dict(zoo=dict(coherence=round(float(orientation_coherence(real).mean()), 3)))
        imgs = [real[0]]
        for label, m in zip(labels, models):
            t = time.perf_counter()
            img = generate(m, C.uniform(m, (name, known_params(m, name, params)), S, S), seed=a.seed)
            row[label] = dict(coherence=round(float(orientation_coherence(img[None])[0]), 3),
                              psd_low=round(psd_error(img[None], real, low=True), 3),
                              psd=round(psd_error(img[None], real), 3), seconds=round(time.perf_counter() - t, 2))
            imgs.append(img)
        for c, img in enumerate(imgs):
            sheet[r * (S + gap): r * (S + gap) + S, c * (S + gap): c * (S + gap) + S] = np.clip(img, 0, 1)
        report["classes"][name] = row
        print(name, row, file=sys.stderr)
    write_png(a.out, (sheet * 255 + 0.5).astype(np.uint8))
    write_json(os.path.splitext(a.out)[0] + ".json", dict(report, columns=["zoo"] + labels))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
