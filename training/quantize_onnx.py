"""int8 denoisers for a split neural noise export: `python -m omninoise.training.quantize_onnx models/neural_noise`.

Writes ``denoiser_int8.onnx`` and ``denoiser_tile_int8.onnx`` beside the fp32 denoisers and records them in
``neural_noise.json`` under ``int8`` (sha256 per file, how they were made).  The fp32 files, and so the
weights' fingerprint, are untouched; the runtime uses the int8 files only where it is asked to (or, with
``precision: auto``, on CPUs with int8 dot products, see :mod:`backend.neural.precision`).

Method: onnxruntime's static quantization in QDQ form, the convolutions only (where the FLOPs are): int8
weights per output channel, uint8 activations with one range per tensor (the 99.999th percentile) calibrated on real
denoiser inputs: x_t = √ᾱ x₀ + √(1-ᾱ) ε (DDPM's forward process, Ho et al. 2020 Eq. 4) of zoo images x₀
of every class at noise levels spread over the sampler's range, with the encoder's maps of that class.
The first convolution (it reads x_t itself) and the output convolution stay float32: both are tiny and
set the error of every step.  Calibration is seeded: the same folder gives the same files.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile

import numpy as np
import torch

from omninoise.backend.onnx_models import write_model_json
from omninoise import export as _ex
from omninoise.backend.neural import conditioning as C
from omninoise.backend.neural.model import NeuralNoiseModel
from omninoise.backend.onnx_models import sha256_file

from . import zoo

__all__ = ["calibration_feeds", "quantize_folder", "INT8_FILES"]

#: fp32 denoiser -> its int8 twin
INT8_FILES = {"denoiser.onnx": "denoiser_int8.onnx", "denoiser_tile.onnx": "denoiser_tile_int8.onnx"}
#: noise levels (DDPM timesteps) the calibration covers: the sampler's whole range
CALIB_T = (999, 900, 700, 500, 300, 150, 50, 10)


def calibration_feeds(model: NeuralNoiseModel, size: int, tileable: bool, seed: int = 0,
                      classes=None, timesteps=CALIB_T) -> list:
    """Denoiser inputs {x, t, m00..} of every class at every timestep: float32, batch 1, size² px."""
    rng = np.random.default_rng(seed)
    ab = model.alphas_cumprod
    feeds = []
    for ci, name in enumerate(classes or model.config["trained_classes"]):
        params = {k: torch.tensor([float(v)]) for k, v in zoo.default_params(name).items()}
        x0 = zoo.generate(name, params, torch.tensor([1000 + ci]), size).numpy()[None] * 2.0 - 1.0
        maps = model.encode(C.uniform(model, (name, {}), size, size)[None], tileable)
        for t in timesteps:
            eps = rng.standard_normal(x0.shape).astype(np.float32)
            xt = (np.sqrt(ab[t]) * x0 + np.sqrt(1.0 - ab[t]) * eps).astype(np.float32)
            feeds.append(dict(maps, x=xt, t=np.array([float(t)], np.float32)))
    return feeds


def _edge_convs(proto) -> list:
    """Names of the Conv nodes that read the graph input x or write the output eps."""
    ins = {i.name for i in proto.graph.input if i.name == "x"}
    outs = {o.name for o in proto.graph.output}
    return [n.name for n in proto.graph.node if n.op_type == "Conv" and (set(n.input) & ins or set(n.output) & outs)]


#: activation ranges clip the calibration values' extreme 0.001 %: on the orientation-stage weights,
#: five classes at 128², mean |int8 - float32| 0.0121 against 0.0153 with MinMax ranges (99.99: 0.0122)
CALIB_PERCENTILE = 99.999
#: weights in 7 bits: without int8 dot-product instructions (AVX2 but not VNNI) onnxruntime multiplies uint8
#: activations by int8 weights in pairs whose sums saturate 16 bits; with 7-bit weights they cannot
#: (docs/decisions/neural.md)
REDUCE_RANGE = True


def quantize_folder(folder: str, size: int = 64, seed: int = 0, log=print) -> dict:
    """Write the int8 denoisers of split export ``folder``; returns the JSON's ``int8`` section."""
    import onnx
    from onnxruntime.quantization import (CalibrationDataReader, CalibrationMethod, QuantFormat, QuantType,
                                          quantize_static)

    model = NeuralNoiseModel(folder)
    if model.form != "split":
        raise SystemExit(f"quantize: {folder} is a {model.form} export; int8 needs the split form "
                         "(python -m omninoise.training.export_onnx --from-export)")
    files = {}
    for fp32, int8 in INT8_FILES.items():
        if fp32 not in model.config["files"]:
            continue
        feeds = calibration_feeds(model, size, fp32 == "denoiser_tile.onnx", seed)
        proto = onnx.load(os.path.join(folder, fp32))  # with its external weights
        wanted = {i.name for i in proto.graph.input}
        feeds = [{k: v for k, v in f.items() if k in wanted} for f in feeds]

        class Reader(CalibrationDataReader):
            def __init__(self):
                self.it = iter(feeds)

            def get_next(self):
                return next(self.it, None)

        with tempfile.TemporaryDirectory() as tmp:
            src = os.path.join(tmp, "fp32.onnx")
            onnx.save(proto, src)
            with _ex.atomic_path(os.path.join(folder, int8)) as dst:
                quantize_static(src, dst, Reader(), quant_format=QuantFormat.QDQ, op_types_to_quantize=["Conv"],
                                activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8, per_channel=True,
                                nodes_to_exclude=_edge_convs(proto), calibrate_method=CalibrationMethod.Percentile,
                                reduce_range=REDUCE_RANGE, extra_options={"CalibPercentile": CALIB_PERCENTILE})
        files[int8] = sha256_file(os.path.join(folder, int8))
        log(f"{int8}: {len(feeds)} calibration inputs at {size}²")
    section = dict(files=files, of=INT8_FILES, method="onnxruntime static QDQ, Conv only, int8 weights per channel "
                   "in 7 bits (reduce_range), "
                   f"uint8 activations (percentile {CALIB_PERCENTILE} of the calibration values), first and output "
                   "convolutions float32",
                   calibration=dict(size=size, seed=seed, timesteps=list(CALIB_T),
                                    classes=list(model.config["trained_classes"])))
    path = os.path.join(folder, "neural_noise.json")
    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    doc["int8"] = section
    write_model_json(path, doc)
    return section


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.quantize_onnx", description=__doc__.split("\n")[0])
    ap.add_argument("folder", help="a split neural noise export (it gains the int8 denoisers)")
    ap.add_argument("--size", type=int, default=64, help="calibration image side (px)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    section = quantize_folder(a.folder, a.size, a.seed)
    print(json.dumps(section["files"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
