"""int8 for the neural denoiser, measured: `python -m bench int8 [--size 256] [--threads 2]`.

Times the model folder's float32 denoiser against two int8 forms of it, its convolutions quantized (where the
FLOPs are): the static QDQ form the project ships (``training/quantize_onnx.py``: int8 weights per channel,
uint8 activations calibrated on forward-process samples of every class; made in a temporary copy when the
folder has none) and onnxruntime's dynamic quantization (weights only).  Prints in one run each form's
seconds per denoiser step at SIZE² (median of 7 interleaved rounds: every form once per round, so a busy
spell of the machine hits all forms alike), the ratio to fp32, and its ε error against fp32 on the same inputs
(an ε error near the ε scale of 1 changes the image).  Nothing ships from here.
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.neural.precision import int8_dot_products
from omninoise.backend.neural.sampler import initial_noise


def feed(m, name: str, S: int, seed: int, t: float) -> dict:
    maps = m.encode(C.uniform(m, (name, {}), S, S)[None], False)
    return dict(maps, x=initial_noise(seed, (1, 1, S, S)) * 0.6, t=np.array([t], np.float32))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args(argv)
    import onnx
    import onnxruntime as ort
    from onnxruntime.quantization import QuantType, quantize_dynamic

    from omninoise.training.quantize_onnx import quantize_folder

    with tempfile.TemporaryDirectory() as tmp:
        folder = a.model
        if not (NeuralNoiseModel(folder).config.get("int8") or {}).get("files"):
            folder = os.path.join(tmp, "model")
            shutil.copytree(a.model, folder)
            quantize_folder(folder, log=lambda s: None)
        m = NeuralNoiseModel(folder, threads=a.threads)
        src = os.path.join(tmp, "fp32.onnx")  # a self-contained copy (the shipped weights are external data)
        onnx.save(onnx.load(os.path.join(folder, "denoiser.onnx")), src)
        dyn = os.path.join(tmp, "dynamic.onnx")
        quantize_dynamic(src, dyn, op_types_to_quantize=["Conv"], weight_type=QuantType.QUInt8)
        static = os.path.join(folder, m.config["int8"]["of"]["denoiser.onnx"])
        so = ort.SessionOptions()
        so.intra_op_num_threads, so.inter_op_num_threads = a.threads, 1
        so.enable_cpu_mem_arena = False
        inputs = [feed(m, n, a.size, 7, 400.0) for n in ("damascus", "cells_f1")]
        forms = []
        for label, path in (("fp32", src), ("int8 static QDQ (shipped)", static), ("int8 dynamic", dyn)):
            s = ort.InferenceSession(path, so, providers=["CPUExecutionProvider"])
            names = {i.name for i in s.get_inputs()}
            feeds = [{k: v for k, v in f.items() if k in names} for f in inputs]
            forms.append((label, s, feeds, [s.run(None, f)[0] for f in feeds]))
        times = {label: [] for label, *_ in forms}
        for _ in range(7):
            for label, s, feeds, _o in forms:
                t0 = time.perf_counter()
                s.run(None, feeds[0])
                times[label].append(time.perf_counter() - t0)
        print(f"denoiser step at {a.size}², {a.threads} threads; CPU int8 dot products (VNNI): "
              f"{'yes' if int8_dot_products() else 'no'}")
        print("| form | s / step | vs fp32 | max abs ε error | mean abs ε error |")
        print("|---|---|---|---|---|")
        ref, base = forms[0][3], float(np.median(times["fp32"]))
        for label, _s, _f, outs in forms:
            sec = float(np.median(times[label]))
            err = np.concatenate([np.abs(o - r).ravel() for o, r in zip(outs, ref)])
            print(f"| {label} | {sec:.3f} | {base / sec:.2f}x | {err.max():.3f} | {err.mean():.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
