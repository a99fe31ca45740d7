"""Turn what tools/gpu_stage.sh brought back from a GPU machine into a run folder that training.export_onnx reads.

    python tools/gpu_export.py GPU_OUT RUN_DIR

GPU_OUT holds ema_a.pt + ema_b.pt (the EMA weights in two halves), stage.json (step, config) and log.jsonl.
RUN_DIR gets ckpt.pt (the EMA weights as both ``model`` and ``ema``; no optimiser state, so a CPU stage
continues from the export, not from this checkpoint) and the log.
"""
from __future__ import annotations

import json
import os
import shutil
import sys

import torch


def main(argv=None) -> int:
    src, run = (argv if argv is not None else sys.argv[1:])
    ema = {}
    for name in ("ema_a.pt", "ema_b.pt"):
        ema.update(torch.load(os.path.join(src, name), map_location="cpu", weights_only=True))
    with open(os.path.join(src, "stage.json"), encoding="utf-8") as fh:
        stage = json.load(fh)
    os.makedirs(run, exist_ok=True)
    torch.save(dict(model=ema, ema=ema, step=stage["step"], config=stage["config"]), os.path.join(run, "ckpt.pt"))
    shutil.copy(os.path.join(src, "log.jsonl"), os.path.join(run, "log.jsonl"))
    print(f"{run}: step {stage['step']}, {len(ema)} tensors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
