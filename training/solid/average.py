"""Average the weights of checkpoints along one run's trajectory (stochastic weight averaging).

    python -m omninoise.training.solid.average --out RUN SRC [SRC ...]
    python -m omninoise.training.solid.average --out RUN --snapshots RUN_IN [--from STEP]

Izmailov et al. ("Averaging Weights Leads to Wider Optima and Better
Generalization", UAI 2018) average the weights a run passes through late in
training, at a constant or cyclic learning rate: w_SWA = (1/n) sum_i w_i
(their Eq. 2, with equal weights).  The points lie in one basin, so their
mean is a model too, and usually a better one than any single point: the SGD
iterates bounce around the basin's centre.

SRC: run folders (``ckpt.pt``) of one architecture, the later stages of one
trajectory (a run and the runs continued from it), or weight snapshots of a
run (``RUN/snapshots/step_*.pt``, kept every ``snapshot_every`` steps of its
config).  ``--snapshots RUN_IN --from STEP`` takes every snapshot of RUN_IN
from that step on, and RUN_IN's checkpoint for the rest.  Every floating-point
tensor of the models' state dicts is averaged; integer buffers are taken from
the last SRC.  The result ``RUN/ckpt.pt`` takes the config, step, training
time and hardware of the last SRC that is a run (the latest point), names its sources in
``averaged_from`` (folder and step), holds no optimiser state (continue it
from its export with ``init_onnx``), and exports like any run
(``python -m omninoise.training.solid.export RUN OUT``).
"""
from __future__ import annotations

import argparse
import glob
import os
import sys

import torch

from omninoise import export as _ex

__all__ = ["average_checkpoints", "write_checkpoint", "snapshots", "main"]


def _load(src: str) -> dict:
    """A run folder's checkpoint, or a snapshot file's ``{model, step}``."""
    path = src if os.path.isfile(src) else os.path.join(src, "ckpt.pt")
    if not os.path.isfile(path):
        raise ValueError(f"average: no checkpoint {path}")
    return torch.load(path, map_location="cpu", weights_only=False)


def snapshots(run: str, from_step: int = 0) -> list:
    """The weight snapshots of a run (``snapshot_every``) from ``from_step`` on, oldest first."""
    paths = sorted(glob.glob(os.path.join(run, "snapshots", "step_*.pt")))
    picked = [p for p in paths if int(os.path.basename(p)[5:-3]) >= from_step]
    if not picked:
        raise ValueError(f"average: {run} has no weight snapshots from step {from_step} on "
                         f"({len(paths)} in all; train with snapshot_every in the config)")
    return picked


def average_checkpoints(runs: list, base: str | None = None) -> dict:
    """The checkpoint whose model is the mean of the runs' (or snapshots') models (see the module doc); their
    order is oldest first.  Config, step and the rest come from ``base`` (a run folder) or else from the last
    source that is a run."""
    if len(runs) < 2:
        raise ValueError(f"average: give at least two run folders or snapshots, got {len(runs)}")
    states = [_load(r) for r in runs]
    bases = [s for s in states if "config" in s]
    if base is not None:
        bases.append(_load(base))
    if not bases:
        raise ValueError("average: snapshots alone hold no config: name their run (--snapshots RUN)")
    models = [s["model"] for s in states]
    keys = list(models[-1])
    for run, m in zip(runs, models):
        if list(m) != keys or any(m[k].shape != models[-1][k].shape for k in keys):
            raise ValueError(f"average: {run} is not the architecture of {runs[-1]} (its tensors differ in "
                             "names or shapes)")
    mean = {}
    for k in keys:
        last = models[-1][k]
        if last.is_floating_point():
            mean[k] = (sum(m[k].double() for m in models) / len(models)).to(last.dtype)
        else:
            mean[k] = last.clone()
    out = {k: v for k, v in bases[-1].items() if k != "opt"}
    out["model"] = mean
    out["step"] = int(states[-1]["step"])
    out["averaged_from"] = [dict(run=r, step=int(s["step"])) for r, s in zip(runs, states)]
    return out


def write_checkpoint(run: str, state: dict) -> None:
    """Write ``state`` (:func:`average_checkpoints`) as run folder ``run``'s ``ckpt.pt``, atomically."""
    os.makedirs(run, exist_ok=True)
    with _ex.atomic_path(os.path.join(run, "ckpt.pt")) as tmp:
        torch.save(state, tmp)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.solid.average", description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="the run folder to write (ckpt.pt)")
    ap.add_argument("runs", nargs="*", help="run folders (ckpt.pt) or snapshot files, oldest first")
    ap.add_argument("--snapshots", metavar="RUN", help="average this run's weight snapshots (snapshot_every)")
    ap.add_argument("--from", dest="from_step", type=int, default=0, metavar="STEP",
                    help="with --snapshots: the first step to take")
    a = ap.parse_args(argv)
    try:
        if a.snapshots:
            state = average_checkpoints(a.runs + snapshots(a.snapshots, a.from_step), base=a.snapshots)
        else:
            state = average_checkpoints(a.runs)
    except ValueError as err:
        print(f"solid average: error: {err}", file=sys.stderr)
        return 2
    write_checkpoint(a.out, state)
    print(f"{a.out}: the mean of " + ", ".join(f"{s['run']} (step {s['step']})" for s in state["averaged_from"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
