"""The inverse-design bank: the fit statistic (backend/neural/fit.py) of zoo images with known class and parameters.

``python -m omninoise.training.fit_bank --out models/fit_bank [--size 64] [--sets 48] [--seeds 2]`` renders, for every
class of the shipped model, ``sets`` parameter sets from the zoo's Halton sequence (starting past the first
``offset`` sets) with ``seeds`` seeds each at ``size``², and stores each image's statistic with its class and
normalised parameters in ``bank.npz`` (float32; class index int16), listed with its sha256 in ``fit_bank.json``.
The runtime's fit starts from the bank's nearest neighbours (a nearest-neighbour recognition model of the zoo)
instead of mid-range parameters; it needs no torch, only this file.
"""
from __future__ import annotations

import argparse
import io
import json
import os
import sys
import time

import numpy as np
import torch

from omninoise.backend.neural.fit import describe
from omninoise.backend.onnx_models import sha256_file
from omninoise.backend.paths import neural_model
from . import zoo

__all__ = ["build_bank", "main"]


def build_bank(classes: list, size: int = 64, sets: int = 48, seeds: int = 2, offset: int = 20000) -> dict:
    """{group: float32 (N, n)} statistics, ``cls`` int16 (N,), ``u`` float32 (N, 4) normalised parameters (the
    class's own order, zero-padded) of ``len(classes) * sets * seeds`` zoo images."""
    stats, cls, us = [], [], []
    for ci, name in enumerate(classes):
        spec = zoo.CLASSES[name].params
        idx = np.arange(offset, offset + sets)
        params = zoo.sample_params(name, idx)
        for s in range(seeds):
            seeds_t = torch.tensor(3_000_000 + idx * 7 + s)
            imgs = zoo.generate(name, {k: torch.tensor(v, dtype=torch.float32) for k, v in params.items()},
                                seeds=seeds_t, size=size)
            for j, img in enumerate(imgs.numpy()):
                stats.append(describe(img))
                cls.append(ci)
                u = np.zeros(4, np.float32)
                for d, p in enumerate(spec):
                    u[d] = (params[p.name][j] - p.lo) / (p.hi - p.lo)
                us.append(u)
    out = {k: np.stack([s[k] for s in stats]).astype(np.float32) for k in stats[0]}
    out["cls"] = np.array(cls, np.int16)
    out["u"] = np.stack(us)
    return out


def main(argv: list | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="models/fit_bank")
    ap.add_argument("--model", default=neural_model(), help="the classes are this model's trained classes")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--sets", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--offset", type=int, default=20000, help="first Halton set (past the training's 16384)")
    a = ap.parse_args(argv)
    with open(os.path.join(a.model, "neural_noise.json"), encoding="utf-8") as fh:
        classes = json.load(fh)["trained_classes"]
    torch.manual_seed(0)
    t = time.perf_counter()
    bank = build_bank(classes, a.size, a.sets, a.seeds, a.offset)
    os.makedirs(a.out, exist_ok=True)
    from omninoise.backend.onnx_models import write_model_json
    from omninoise.export.atomic import atomic_path

    buf = io.BytesIO()
    np.savez_compressed(buf, **bank)
    with atomic_path(os.path.join(a.out, "bank.npz")) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(buf.getvalue())
    write_model_json(os.path.join(a.out, "fit_bank.json"), dict(
        kind="omninoise.fit_bank", format=1, classes=classes, size=a.size, sets=a.sets, seeds=a.seeds,
        offset=a.offset, images=int(bank["cls"].shape[0]), zoo="training/zoo.py",
        command=f"python -m omninoise.training.fit_bank --out {a.out} --size {a.size} --sets {a.sets} "
                f"--seeds {a.seeds} --offset {a.offset}",
        seconds=round(time.perf_counter() - t, 1), files={"bank.npz": sha256_file(os.path.join(a.out, "bank.npz"))}))
    print(f"{bank['cls'].shape[0]} zoo images in {time.perf_counter() - t:.0f} s -> {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
