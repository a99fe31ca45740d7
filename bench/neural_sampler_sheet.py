"""Side-by-side sheet of samplers on the same seeds: `python -m bench sheet-samplers OUT.png [--size S]`.

Each row is one conditioning (a class at its default parameters, or a mask, four-corner or painted blend).
Columns, all from the same x_T: DDIM with 30 steps (the sampler before DPM-Solver++); the runtime's default
sampler and step count without step noise (η = 0); the runtime's default (its DEFAULT_ETA).  Writes OUT.png and
OUT.json (settings and seconds).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.generate import generate
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.neural.sampler import DEFAULT_ETA, DEFAULT_SAMPLER, DEFAULT_SPACING, DEFAULT_STEPS
from omninoise.export.atomic import write_json
from omninoise.export.images import preview_8bit, write_png

CLASSES = ("cells_f1", "perlin", "clouds", "spots", "fibers", "damascus", "gabor", "wave_cellular")


def conditions(model, S: int) -> list:
    """(label, cond) rows: the classes, then a mask blend, a four-corner blend and a painted map."""
    rows = [(n, C.uniform(model, (n, {}), S, S)) for n in CLASSES]
    yy, xx = np.mgrid[0:S, 0:S]
    mask = (xx + 0.25 * S * np.sin(yy / S * 2 * np.pi)) > S / 2
    rows.append(("mask blend cells_f1 | noise", C.blend(model, ("cells_f1", {}), ("noise", {}),
                                                         C.mask_weight(mask, S / 8, 1.0))))
    rows.append(("four corners", C.four_corner(model, [(n, {}) for n in ("cells_borders", "spots", "clouds",
                                                                          "gabor")], S, S)))
    painted = np.zeros((S, S), np.int64)
    painted[(xx - S / 2) ** 2 + (yy - S / 2) ** 2 < (S / 3) ** 2] = 1
    rows.append(("painted disc", C.painted(model, painted, {0: ("perlin", {}), 1: ("cells_f1", {"scale": 14})},
                                           S / 16, 1.0)))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--threads", type=int, default=0)
    a = ap.parse_args(argv)
    model = NeuralNoiseModel(a.model, threads=a.threads)
    S, gap = a.size, 4
    columns = (("ddim 30", dict(steps=30, sampler="ddim")),
               (f"{DEFAULT_SAMPLER} {DEFAULT_STEPS} eta 0", dict(eta=0.0)),
               (f"{DEFAULT_SAMPLER} {DEFAULT_STEPS} eta {DEFAULT_ETA[DEFAULT_SAMPLER]:g} (default)", {}))
    rows, times, labels = [], {c: 0.0 for c, _ in columns}, []
    for i, (label, cond) in enumerate(conditions(model, S)):
        labels.append(label)
        row = []
        for name, kw in columns:
            t0 = time.perf_counter()
            row += [generate(model, cond, seed=100 + i, **kw), np.ones((S, gap), np.float32)]
            times[name] += time.perf_counter() - t0
        rows.append(np.concatenate(row[:-1], 1))
    sheet = np.concatenate([np.concatenate([r, np.ones((gap, r.shape[1]), np.float32)]) for r in rows])[:-gap]
    write_png(a.out, preview_8bit(sheet, 0.0, 1.0))
    write_json(os.path.splitext(a.out)[0] + ".json", dict(
        rows=labels, size=S, columns=[c for c, _ in columns], spacing=DEFAULT_SPACING[DEFAULT_SAMPLER],
        seconds={k: round(v, 1) for k, v in times.items()}, model=model.fingerprint))
    print(f"{a.out}: " + ", ".join(f"{k} ({v:.0f} s)" for k, v in times.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
