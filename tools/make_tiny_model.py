"""The tiny models the torch-free tests run on: ``python tools/make_tiny_model.py``.

Trains the tests' tiny configuration (16² crops, widths 8/16/16, three classes, 3 steps: seconds on a CPU) with the
project's trainer and exports it in the split form to ``tests/data/tiny_neural`` (2.2 MB, committed), so that
the runtime's tests (conditioning, sampling, tiles, CLI, job files, animation) need onnxruntime only. Likewise three
tiny solid texture models (2 training steps, width 16: single-exemplar 3D and 2D, and a texture-space model) in
``tests/data/tiny_solid`` for the solid CLI and Blender tests. Their images are not textures an artist would want;
the tests check properties (shapes, seeds, files, equality of paths), never pictures. Rerun after a change of an
export format; the torch tests train and export their own models. The committed ``tiny_neural`` is in the
older split form (one denoiser with a ``tile`` input, exported before the per-padding denoisers): the runtime
must keep loading it (tests/core/test_neural_onnx.py), so it is kept as it is; a rerun writes the current form.
"""
from __future__ import annotations

import os
import shutil
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

#: the tiny solid models: name -> (mode, dim, exemplars)
SOLID = {"single3": ("single", 3, ["gravel"]), "single2": ("single", 2, ["gravel"]),
         "space3": ("space", 3, ["gravel", "grass"])}
#: the tests' tiny training configuration (tests/training/test_neural_runtime.py trains the same)
TINY = dict(size=16, batch=4, steps=3, widths=(8, 16, 16), emb_dim=8, log_every=1, checkpoint_every=3,
            sample_every=0, classes=("perlin", "spots", "cells_f1"), seed=0)


def make_neural(out: str) -> None:
    import torch

    from omninoise.training.export_onnx import export
    from omninoise.training.train import TrainConfig, train

    torch.manual_seed(0)
    with tempfile.TemporaryDirectory() as run:
        train(TrainConfig.from_dict(TINY), run, log=lambda s: None)
        staged = os.path.join(run, "export")
        export(run, staged)
        if os.path.isdir(out):
            shutil.rmtree(out)
        shutil.copytree(staged, out)


def make_solid(root: str) -> None:
    import torch

    from omninoise.training.solid.export import export
    from omninoise.training.solid.train import SolidConfig, train

    for name, (mode, dim, exemplars) in SOLID.items():
        torch.manual_seed(0)
        cfg = SolidConfig.from_dict(dict(name=name, mode=mode, dim=dim, crop=32 if mode == "single" else 128,
                                         batch=1, steps=2, width=16, threads=1, exemplars=exemplars))
        with tempfile.TemporaryDirectory() as run:
            train(cfg, run, log=lambda *_: None)
            staged = os.path.join(run, "export")
            export(run, staged)
            out = os.path.join(root, name)
            if os.path.isdir(out):
                shutil.rmtree(out)
            shutil.copytree(staged, out)


def main(argv: list) -> int:
    data = os.path.join(ROOT, "tests", "data")
    if not argv or "neural" in argv:
        make_neural(os.path.join(data, "tiny_neural"))
    if not argv or "solid" in argv:
        make_solid(os.path.join(data, "tiny_solid"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
