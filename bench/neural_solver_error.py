"""How near each sampler comes to the converged probability-flow solution, per model evaluation.

    python bench/neural_solver_error.py --size 64 --batch 4 ddim:30:uniform dpmpp_2m:15:logsnr dpmpp_2m:10:truncated

For every class of the model (or --classes), ``--batch`` initial noises x_T are denoised by a reference
solver (DPM-Solver++(2M), ``--ref-steps`` timesteps even in log-SNR: converged to well under an 8-bit
level) and by each candidate ``sampler:steps:spacing``, from the same x_T. The figure is the mean absolute
difference of the two images (data range [-1, 1]), per class, then its mean, median and maximum over the
classes, beside the candidate's model evaluations. A sampler is as accurate as DDIM 30 when its distance is
no larger; the evaluation (bench/eval_neural.py) then checks the images' statistics. The reference is
cached in --cache (keyed by model fingerprint, size, batch, classes and steps).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.model import NeuralNoiseModel  # noqa: E402
from omninoise.backend.neural.sampler import evaluations, initial_noise, sample  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402


def parse(spec: str) -> tuple:
    try:
        name, steps, spacing = spec.split(":")
        return name, int(steps), spacing
    except ValueError:
        raise SystemExit(f"candidate {spec!r}: write sampler:steps:spacing, e.g. dpmpp_2m:10:truncated")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("candidates", nargs="+", help="sampler:steps:spacing")
    ap.add_argument("--model", default="models/neural_noise")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--batch", type=int, default=4, help="initial noises per class")
    ap.add_argument("--classes", default="", help="comma-separated (default: all the model's classes)")
    ap.add_argument("--ref-steps", type=int, default=200)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--cache", default="runs/solver_ref")
    ap.add_argument("-o", "--out", default="", help="JSON of every candidate's per-class distances")
    a = ap.parse_args()
    cands = [parse(c) for c in a.candidates]

    model = NeuralNoiseModel(a.model, threads=a.threads)
    eps = model.eps_fn(False)
    classes = a.classes.split(",") if a.classes else list(model.classes)
    S, B = a.size, a.batch
    conds = {n: np.repeat(C.uniform(model, (n, {}), S, S)[None], B, 0) for n in classes}
    x_T = {n: np.stack([initial_noise(1000 + i + 10 * k, (1, S, S)) for i in range(B)]) for k, n in enumerate(classes)}

    key = hashlib.sha256(json.dumps([model.fingerprint, S, B, classes, a.ref_steps]).encode()).hexdigest()[:16]
    ref_path = os.path.join(a.cache, f"ref_{key}.npz")
    if os.path.exists(ref_path):
        ref = dict(np.load(ref_path))
    else:
        t = time.perf_counter()
        ref = {n: sample("dpmpp_2m", eps, x_T[n], conds[n], a.ref_steps, spacing="logsnr") for n in classes}
        os.makedirs(a.cache, exist_ok=True)
        np.savez(ref_path, **ref)
        print(f"reference: dpmpp_2m {a.ref_steps} logsnr, {time.perf_counter() - t:.0f} s", flush=True)

    print(f"{S}², {B} noises x {len(classes)} classes; mean |x - converged| per class")
    print(f"{'sampler':12s} {'steps':>5s} {'spacing':10s} {'evals':>5s} {'mean':>7s} {'median':>7s} {'max':>7s}  worst")
    results = {}
    for name, steps, spacing in cands:
        d = {n: float(np.abs(sample(name, eps, x_T[n], conds[n], steps, spacing=spacing) - ref[n]).mean())
             for n in classes}
        v = np.array(list(d.values()))
        ev = evaluations(name, steps, spacing, model.alphas_cumprod)
        print(f"{name:12s} {steps:5d} {spacing:10s} {ev:5d} {v.mean():7.4f} {np.median(v):7.4f} {v.max():7.4f}  "
              f"{max(d, key=d.get)}", flush=True)
        results[f"{name}:{steps}:{spacing}"] = dict(evaluations=ev, mean=float(v.mean()), median=float(np.median(v)),
                                                     max=float(v.max()), classes=d)
    if a.out:
        write_json(a.out, dict(size=S, batch=B, ref_steps=a.ref_steps, model=model.fingerprint, results=results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
