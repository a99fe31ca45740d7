"""Neural noise showcase: out/demo/neural.png (and neural.json) from the shipped model.

One row per kind of conditioning grid, all from the ONNX model through the
numpy/onnxruntime sampler (no torch): every trained class at its default
parameters (wrapped onto rows of eight); a parameter sweep; a mask-driven blend of two classes next to its
mask; a four-corner blend; and a tileable tile repeated 2x2.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.generate import generate  # noqa: E402
from omninoise.backend.neural.model import ModelError, NeuralNoiseModel  # noqa: E402
from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.export.images import preview_8bit, write_png  # noqa: E402

STEPS = DEFAULT_STEPS  # the runtime's default sampler (DPM-Solver++(2M), truncated grid, step noise 0.3) and step count
PER_ROW = 8  # tiles per row of the sheet; the classes wrap onto as many rows as they need


def main(out: str) -> int:
    try:
        model = NeuralNoiseModel(os.path.join(ROOT, "models", "neural_noise"))
    except ModelError as exc:
        print(f"neural demo skipped: {exc}")
        return 0
    S = int(model.config["train_size"]) * 2
    names = model.config["trained_classes"]
    t0 = time.perf_counter()
    row1 = [generate(model, C.uniform(model, (n, {}), S, S), seed=i, steps=STEPS) for i, n in enumerate(names)]
    first = model.class_params[names[0]]["params"][0]
    sweep = [generate(model, C.uniform(model, (names[0], {first["name"]: v}), S, S), seed=3, steps=STEPS)
             for v in np.linspace(first["min"], first["max"], PER_ROW)]
    other = "noise" if "noise" in names[1:] else names[-1]
    W = S * 3
    mask = np.zeros((S, W), bool)
    yy, xx = np.mgrid[:S, :W]
    mask[(xx - W * 0.6) ** 2 + (yy - S * 0.5) ** 2 < (S * 0.4) ** 2] = True
    blend = generate(model, C.blend(model, (names[0], {}), (other, {}), C.mask_weight(mask, S / 4, 2.0)),
                     seed=4, steps=STEPS)
    corners = generate(model, C.four_corner(model, [(n, {}) for n in (names + names)[1:5]], S, W), seed=5, steps=STEPS)
    tile = generate(model, C.uniform(model, (names[1 % len(names)], {}), S, S), seed=6, steps=STEPS, tileable=True)
    tiled = np.tile(tile, (1, 2))
    wide = PER_ROW * S
    pad = lambda a: np.pad(a, ((0, 0), (0, wide - a.shape[1])))  # noqa: E731
    rows = [np.concatenate(row1[i: i + PER_ROW], 1) for i in range(0, len(row1), PER_ROW)]
    rows += [np.concatenate(sweep, 1),
            pad(np.concatenate([mask.astype(np.float32), blend], 1)), pad(np.concatenate([corners, tiled], 1))]
    sheet = np.concatenate([pad(r) if r.shape[1] < wide else r[:, :wide] for r in rows], 0)
    os.makedirs(out, exist_ok=True)
    write_png(os.path.join(out, "neural.png"), preview_8bit(sheet, 0.0, 1.0))
    info = dict(classes=names, sweep=dict(cls=names[0], param=first["name"]), blend=[names[0], other],
                sampler=DEFAULT_SAMPLER, steps=STEPS, size=S,
                seconds=round(time.perf_counter() - t0, 1), model_sha256=model.fingerprint)
    write_json(os.path.join(out, "neural.json"), info)
    print(f"wrote {out}/neural.png in {info['seconds']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo")))
