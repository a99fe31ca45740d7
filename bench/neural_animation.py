"""Animated neural noise, measured: `python bench/neural_animation.py OUT_PREFIX [--size 128] [--frames 24]`.

Three keyframes (perlin -> cells_f1 -> spots; frames 1, N/2, N) rendered with each latent motion of
backend/neural/animate.py (fixed, slerp, drift). For each: the mean frame-to-frame absolute difference, the
largest step over the median step (a jump if far above 1; target at most 3), and the mean step over the
difference between two independent seeds of the same conditioning (what a flickering sequence would show every
frame). Writes OUT_PREFIX.json, OUT_PREFIX_strip.png (every few frames of each motion, one row each) and
OUT_PREFIX.gif (the fixed-latent sequence, looped forward and back).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.backend.neural import conditioning as C  # noqa: E402
from omninoise.backend.neural.animate import Keyframe, animate, temporal_coherence  # noqa: E402
from omninoise.backend.neural.generate import generate  # noqa: E402
from omninoise.backend.neural.model import NeuralNoiseModel  # noqa: E402
from omninoise.export.atomic import atomic_path, write_json  # noqa: E402
from omninoise.export.images import write_png  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="prefix of the outputs (OUT.json, OUT_strip.png, OUT.gif)")
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--every", type=int, default=3, help="strip: one frame in this many")
    a = ap.parse_args()
    m = NeuralNoiseModel(a.model)
    N, S = a.frames, a.size
    keys = [Keyframe(1, "perlin", {"scale": 4.0}, 0), Keyframe(N // 2, "cells_f1", {"scale": 8.0}, 1),
            Keyframe(N, "spots", {"scale": 6.0}, 2)]
    first = generate(m, C.uniform(m, keys[0].spec, S, S), seed=0)
    independent = float(np.abs(generate(m, C.uniform(m, keys[0].spec, S, S), seed=12345) - first).mean())
    report, rows = dict(size=S, frames=N, keys=[k.__dict__ for k in keys], model=m.fingerprint), []
    for mode in ("fixed", "slerp", "drift"):
        t = time.perf_counter()
        seq = [img for _, img in animate(m, keys, (1, N), S, S, latent=mode, speed=0.05)]
        report[mode] = dict(temporal_coherence(seq, independent),
                            seconds_per_frame=round((time.perf_counter() - t) / N, 3))
        print(mode, report[mode], file=sys.stderr)
        rows.append(seq)
    picks = list(range(0, N, a.every))
    gap = 4
    strip = np.ones((len(rows) * (S + gap), len(picks) * (S + gap)), np.float32)
    for r, seq in enumerate(rows):
        for c, i in enumerate(picks):
            strip[r * (S + gap): r * (S + gap) + S, c * (S + gap): c * (S + gap) + S] = seq[i]
    write_png(a.out + "_strip.png", (np.clip(strip, 0, 1) * 255 + 0.5).astype(np.uint8))
    from PIL import Image

    loop = rows[0] + rows[0][-2:0:-1]
    ims = [Image.fromarray((np.clip(f, 0, 1) * 255 + 0.5).astype(np.uint8)) for f in loop]
    with atomic_path(a.out + ".gif") as tmp:
        ims[0].save(tmp, format="GIF", save_all=True, append_images=ims[1:], duration=80, loop=0)
    write_json(a.out + ".json", report)
    print(a.out + ".json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
