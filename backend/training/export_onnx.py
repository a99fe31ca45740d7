"""Export a trained ε-network to ONNX for the runtime: ``python -m backend.training.export_onnx RUN OUT_DIR``.

Writes, each atomically:

    OUT_DIR/eps.onnx           inputs x, t, cond, tile -> eps (batch, height, width dynamic);
                               tile = [0.0] zero padding, [1.0] circular padding (seamless tiles),
                               one graph for both so the weights ship once
    OUT_DIR/neural_noise.json  schedule, class and parameter names and ranges, the class-embedding
                               table, the training config and step, the run's record (wall time
                               and final loss from its log.jsonl, since runs are not kept), and
                               the .onnx file's sha256 (the runtime refuses a file whose hash differs)

The EMA weights are exported (``--raw`` for the optimiser's weights).
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import torch

from .._export import export as _ex

from ..neural.model import sha256_file
from . import zoo
from .model_card import run_record
from .train import TrainConfig, build_model, model_names

__all__ = ["export", "onnx_export"]

FORMAT = 1


def onnx_export(module, args: tuple, path: str, inputs: list, outputs: list, dynamic: dict) -> None:
    """``torch.onnx.export`` (opset 17, TorchScript exporter) to a temporary file, then renamed onto ``path``."""
    tmp = path + ".tmp"
    torch.onnx.export(module, args, tmp, input_names=inputs, output_names=outputs, dynamic_axes=dynamic,
                      opset_version=17, dynamo=False)
    os.replace(tmp, path)


def _export_one(model, path: str, size: int) -> None:
    C = model.emb_dim + model.n_params
    args = (torch.randn(1, 1, size, size), torch.tensor([500.0]), torch.randn(1, C, size, size), torch.zeros(1))
    onnx_export(model, args, path, ["x", "t", "cond", "tile"], ["eps"],
                {"x": {0: "batch", 2: "height", 3: "width"}, "t": {0: "batch"},
                 "cond": {0: "batch", 2: "height", 3: "width"}, "eps": {0: "batch", 2: "height", 3: "width"}})


def export(run: str, out: str, raw: bool = False, extra: dict | None = None) -> dict:
    """Export checkpoint ``run/ckpt.pt`` into folder ``out``; returns the JSON config written."""
    state = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
    cfg = TrainConfig.from_dict(state["config"])
    model = build_model(cfg, state["model"])
    model.load_state_dict(state["model" if raw else "ema"])
    classes, params = model_names(model)
    model.eval()
    os.makedirs(out, exist_ok=True)
    _export_one(model, os.path.join(out, "eps.onnx"), cfg.size)
    files = {"eps.onnx": sha256_file(os.path.join(out, "eps.onnx"))}
    doc = dict(format=FORMAT, model="neural_noise", paper="Maesumi et al. 2024, One Noise to Rule Them All",
               schedule=dict(kind="cosine", T=1000, s=0.008), prediction="epsilon",
               classes=classes, trained_classes=list(cfg.classes), params=params,
               class_params={k: v for k, v in zoo.describe().items() if k in classes}, emb_dim=cfg.emb_dim,
               class_embedding=model.class_emb.weight.detach().numpy().astype(float).round(7).tolist(),
               train_size=cfg.size, step=int(state["step"]), weights="raw" if raw else "ema",
               config=state["config"], files=files, multiple_of=8)
    log = os.path.join(run, "log.jsonl")
    if os.path.isfile(log):
        doc["training"] = run_record(log)
    doc.update(extra or {})
    path = os.path.join(out, "neural_noise.json")
    _ex.write_json(path, doc)
    return doc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m backend.training.export_onnx", description=__doc__.split("\n")[0])
    ap.add_argument("run", help="training run folder (holds ckpt.pt)")
    ap.add_argument("out", help="output folder for eps.onnx and neural_noise.json")
    ap.add_argument("--raw", action="store_true", help="export the raw weights instead of the EMA")
    a = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(a.run, "ckpt.pt")):
        print(f"export: error: no checkpoint in {a.run}", file=sys.stderr)
        return 2
    doc = export(a.run, a.out, a.raw)
    print(json.dumps(doc["files"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
