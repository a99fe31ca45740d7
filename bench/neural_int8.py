"""int8 for the neural denoiser, measured: `python bench/neural_int8.py [--size 256] [--threads 2]`.

Quantizes the shipped `denoiser.onnx` with onnxruntime's tools two ways, its convolutions only (where the
FLOPs are): static QDQ (int8 weights per channel, uint8 activations calibrated on 18 real denoiser inputs of six
classes at three noise levels) and dynamic (weights only). Prints in one run each form's seconds per denoiser
step at SIZE², the ratio to fp32, and its ε error against fp32 on the same input (an ε error near the ε scale
of 1 changes the image). Files go to a temporary folder; nothing ships from here.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from backend.neural import conditioning as C  # noqa: E402
from backend.neural.model import NeuralNoiseModel  # noqa: E402
from backend.neural.precision import int8_dot_products  # noqa: E402
from backend.neural.sampler import initial_noise  # noqa: E402


def feed(m, name: str, S: int, seed: int, t: float) -> dict:
    maps = m.encode(C.uniform(m, (name, {}), S, S)[None], False)
    x = initial_noise(seed, (1, 1, S, S)) * (1.0 if t > 900 else 0.3)
    return dict(maps, x=x, t=np.array([t], np.float32), tile=np.array([0.0], np.float32))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "neural_noise"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    import onnxruntime as ort
    from onnxruntime.quantization import (CalibrationDataReader, QuantFormat, QuantType, quantize_dynamic,
                                          quantize_static)
    from onnxruntime.quantization.shape_inference import quant_pre_process

    m = NeuralNoiseModel(a.model, threads=a.threads)
    calib = [feed(m, n, 64, i, t) for i, n in enumerate(("cells_f1", "damascus", "perlin", "spots", "gabor", "fibers"))
             for t in (999.0, 500.0, 100.0)]

    class Reader(CalibrationDataReader):
        def __init__(self):
            self.it = iter(calib)

        def get_next(self):
            return next(self.it, None)

    import onnx
    with tempfile.TemporaryDirectory() as tmp:
        # the shipped denoiser keeps its weights in denoiser.weights (external data): one self-contained copy
        src = os.path.join(tmp, "fp32.onnx")
        proto = onnx.load(os.path.join(a.model, "denoiser.onnx"))
        onnx.save(proto, src)
        wanted = {i.name for i in proto.graph.input}
        calib[:] = [{k: v for k, v in f.items() if k in wanted} for f in calib]
        pre, s8, dyn = (os.path.join(tmp, f) for f in ("pre.onnx", "static.onnx", "dynamic.onnx"))
        quant_pre_process(src, pre, skip_symbolic_shape=True)
        quantize_static(pre, s8, Reader(), quant_format=QuantFormat.QDQ, op_types_to_quantize=["Conv"],
                        activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8, per_channel=True)
        quantize_dynamic(src, dyn, op_types_to_quantize=["Conv"], weight_type=QuantType.QUInt8)
        so = ort.SessionOptions()
        so.intra_op_num_threads, so.inter_op_num_threads = a.threads, 1
        inputs = [feed(m, n, a.size, 7, 400.0) for n in ("damascus", "cells_f1")]
        print(f"denoiser step at {a.size}², {a.threads} threads (median of 7 interleaved rounds: every form once "
              "per round, so a busy spell of the machine hits all forms alike)")
        print("| form | s / step | vs fp32 | max abs ε error | mean abs ε error |")
        print("|---|---|---|---|---|")
        forms = []
        for label, path in (("fp32", src), ("int8 static QDQ", s8), ("int8 dynamic", dyn)):
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
        ref, base = forms[0][3], float(np.median(times["fp32"]))
        for label, _s, _f, outs in forms:
            sec = float(np.median(times[label]))
            err = np.concatenate([np.abs(o - r).ravel() for o, r in zip(outs, ref)])
            print(f"| {label} | {sec:.3f} | {base / sec:.2f}x | {err.max():.3f} | {err.mean():.4f} |")
        print("CPU int8 dot products (VNNI):", "yes" if int8_dot_products() else "no")
    return 0


if __name__ == "__main__":
    sys.exit(main())
