"""Train the neural noise model's whole line of stages with one command:
``python -m omninoise.training.line configs/neural_noise_line.json --out runs/line``.

The shipped weights are the end of a line of stages, each a config trained from the export of the stage before
(the ledger: ``python tools/ledger.py models/neural_noise``). A line file lists them in order::

    {"model": "neural_noise", "stages": [{"name": "zoo", "config": "configs/neural_noise_cpu_zoo.json",
                                          "steps": 5600}, ...]}

``config`` is a path from the line file's folder; ``steps`` is where the stage stops (the configs' learning rate is
constant, so a stage stopped early is its config with fewer steps). Stage k trains in ``OUT/NAME``
(:func:`.train.train`, which resumes from the folder's checkpoint) and is exported to ``OUT/NAME/export``
(:func:`.export_onnx.export`); stage k + 1 starts from that export: its config's ``init_onnx`` and ``init_sha256``,
which pin the exports of the shipped line, name the new export instead. The first stage keeps its config's start
(none: a fresh network). The last export gains the int8 denoisers (:func:`.quantize_onnx.quantize_folder`) and is
the line's model, to be evaluated (``python -m bench neural-eval --model OUT/NAME/export``) before it replaces
``models/neural_noise``. A stage whose export holds its last step is done, so the same command goes on where it
stopped (a stage stopped partway resumes from its checkpoint).

``--steps N`` stops every stage after at most N steps: the whole line in minutes, a check of the line itself (its
model is no trained model).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import shutil
import sys
import time

__all__ = ["Stage", "load_line", "run_line", "main"]

NAME = re.compile(r"[a-z0-9_]+")
EXPORT = "export"           #: a stage's export folder, inside its run folder


@dataclasses.dataclass(frozen=True)
class Stage:
    """One stage of a line: its run folder's ``name``, its training ``config`` (a path) and the step it stops at."""

    name: str
    config: str
    steps: int


def load_line(path: str) -> list:
    """The stages of a line file (module docstring), checked: ValueError naming the first bad entry. Each config is
    read (:func:`.train.load_config`), so a line whose config would fail at its stage fails here, before any work."""
    from .train import load_config

    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    entries = doc.get("stages") if isinstance(doc, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: a line needs 'stages', a list of {{name, config, steps}}")
    stages, names = [], set()
    for i, e in enumerate(entries):
        where = f"{path}: stages[{i}]"
        if not isinstance(e, dict) or set(e) != {"name", "config", "steps"}:
            raise ValueError(f"{where}: needs exactly name, config and steps")
        if not isinstance(e["name"], str) or not NAME.fullmatch(e["name"]) or e["name"] in names:
            raise ValueError(f"{where}: name must be a new name of a-z, 0-9 and _, got {e['name']!r}")
        steps = e["steps"]
        if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
            raise ValueError(f"{where}: steps must be a whole number >= 1, got {steps!r}")
        config = os.path.join(os.path.dirname(os.path.abspath(path)), e["config"])
        try:
            cfg = load_config(config)
        except (OSError, ValueError) as exc:
            raise ValueError(f"{where}: config {e['config']}: {exc}") from None
        if steps > cfg.steps:
            raise ValueError(f"{where}: steps {steps} is past its config's {cfg.steps}")
        names.add(e["name"])
        stages.append(Stage(e["name"], config, steps))
    return stages


def _exported_step(folder: str) -> int | None:
    """The training step of the export in ``folder``, None where there is none."""
    try:
        with open(os.path.join(folder, "neural_noise.json"), encoding="utf-8") as fh:
            return json.load(fh).get("step")
    except (OSError, ValueError):
        return None


def _started_from(run: str) -> str | None:
    """The fingerprint of the weights a run folder's training began from ("" for a fresh network; None where
    nothing was trained there): its ``config.json``, which :func:`.train.train` writes."""
    try:
        with open(os.path.join(run, "config.json"), encoding="utf-8") as fh:
            return json.load(fh).get("init_sha256", "")
    except (OSError, ValueError):
        return None


def _export_fingerprint(folder: str) -> str:
    from omninoise.backend.onnx_models import fingerprint, load_model_json

    return fingerprint(load_model_json(folder, "neural_noise.json")["files"])


def run_line(stages: list, out: str, max_steps: int | None = None, log=print) -> str:
    """Train and export each stage in turn into ``out`` (module docstring); returns the last export's folder.
    ``max_steps`` caps every stage's steps (a quick run of the line)."""
    from .export_onnx import export
    from .quantize_onnx import quantize_folder
    from .train import load_config, train

    start = None                    # (export folder, its weights' fingerprint) the next stage starts from
    for k, stage in enumerate(stages, 1):
        run = os.path.join(out, stage.name)
        done = os.path.join(run, EXPORT)
        steps = min(stage.steps, max_steps or stage.steps)
        if _exported_step(done) == steps:
            log(f"[{k}/{len(stages)}] {stage.name}: done ({done})")
        else:
            cfg = dataclasses.replace(load_config(stage.config), steps=steps)
            if start is not None:
                cfg = dataclasses.replace(cfg, init_onnx=start[0], init_sha256=start[1])
            log(f"[{k}/{len(stages)}] {stage.name}: {os.path.relpath(stage.config)}, {cfg.steps} steps, from "
                + (f"{start[0]}" if start else (cfg.init_onnx or "a fresh network")))
            if _started_from(run) not in (None, cfg.init_sha256):   # its run began from another export
                log(f"  {run} began from other weights than the stage before's export: training it again")
                shutil.rmtree(run)
            t0 = time.time()
            train(cfg, run, log=lambda text: log(f"  {text}"))
            export(run, done)       # its JSON, with the step, is written last: a cut-short export is not done
            log(f"  exported to {done} ({time.time() - t0:.0f} s)")
        start = (done, _export_fingerprint(done))
    with open(os.path.join(start[0], "neural_noise.json"), encoding="utf-8") as fh:
        if "int8" not in json.load(fh):
            quantize_folder(start[0])
            log(f"  int8 denoisers added to {start[0]}")
    return start[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.line", description=__doc__.split("\n")[0])
    ap.add_argument("line", help="a line file (configs/neural_noise_line.json)")
    ap.add_argument("--out", required=True, help="the folder of the stages' runs and exports")
    ap.add_argument("--steps", type=int, help="stop every stage after at most this many steps (a check of the line)")
    ap.add_argument("--dry-run", action="store_true", help="list the stages and where each starts, train nothing")
    a = ap.parse_args(argv)
    try:
        if a.steps is not None and a.steps < 1:
            raise ValueError(f"--steps must be >= 1, got {a.steps}")
        stages = load_line(a.line)
    except (OSError, ValueError) as exc:
        print(f"line: error: {exc}", file=sys.stderr)
        return 2
    if a.dry_run:
        from .train import load_config

        for k, s in enumerate(stages, 1):
            start = f"the export of {stages[k - 2].name}" if k > 1 else (load_config(s.config).init_onnx
                                                                          or "a fresh network")
            print(f"[{k}/{len(stages)}] {s.name}: {os.path.relpath(s.config)}, {min(s.steps, a.steps or s.steps)} "
                  f"steps, from {start}")
        return 0
    model = run_line(stages, a.out, a.steps)
    print(f"line: the model is {model}; evaluate it: python -m bench neural-eval --model {model}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
