"""Train a model's whole line of stages with one command:
``python -m omninoise.training.line configs/lines/neural_noise.json --out runs/line`` (or
``configs/lines/solid_space.json``).

A shipped model is the end of a line of stages, each a config trained from the export of the stage before (the
ledgers: ``python tools/ledger.py models/neural_noise``). A line file lists them in order::

    {"model": "neural_noise", "stages": [{"name": "zoo", "config": "../neural_noise_cpu_zoo.json", "steps": 5600},
                                         ...], "finish": "int8"}

``config`` is a path from the line file's folder. ``steps`` is the step the stage stops at, as its trainer counts:
a neural noise stage counts from 0 (its learning rate is constant, so a stage stopped early is its config with
fewer steps); a solid texture stage goes on from its start's step under its config's cosine schedule. Stage k
trains in ``OUT/NAME`` (resuming from the folder's checkpoint) and is exported to ``OUT/NAME/export``. A stage whose
config continues an export (its ``init_onnx`` and ``init_sha256``, which pin the exports of the shipped line) or a
solid texture run (``init_from``) starts from the export of the stage before instead (a solid texture stage's step
and schedule go on; Adam's moments start afresh); a config that starts from a fresh network begins a new model, so
one line may also train several models side by side (``configs/lines/solid_singles.json``: one per shipped
texture). A stage's ``finish`` (``"finish": "harmonics"``: a single-photo solid model's harmonic
part, :mod:`.solid.harmonics`) runs on its export. A solid texture line may also hold

* ``{"name": ..., "structure_net": STEPS}``: the structure term's network (:mod:`.solid.structure_features`),
  trained once into ``OUT/NAME/net.pt``, which every later config with a structure term reads;
* ``{"name": ..., "average": [STAGE, ...]}``: the mean of those stages' weights (:mod:`.solid.average`),
  exported as a stage of its own (no training);

and a line's ``finish`` ends it, the last stage's: ``"int8"`` (neural noise: :func:`.quantize_onnx.quantize_folder`)
or ``"spin octave"`` (solid texture: octaves turned by their seeds, the codes' harmonic parts measured again:
:mod:`.solid.harmonics`). The line's models are the exports that no later stage continues or averages (the last
one where each stage continues the one before), to be evaluated before they replace the shipped ones. A stage whose
export holds its last step is done, so the same command goes on where it stopped.

``--steps N`` trains every stage for at most N steps: the whole line in minutes, a check of the line itself (its
model is no trained model). ``--device`` trains every stage there (a line of GPU stages on the CPU, slowly).
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

__all__ = ["Stage", "load_line", "run_line", "line_models", "main"]

NAME = re.compile(r"[a-z0-9_]+")
EXPORT = "export"           #: a stage's export folder, inside its run folder
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@dataclasses.dataclass(frozen=True)
class Stage:
    """One stage of a line: its run folder's ``name`` and what it does: train ``config`` (a path) until ``steps``,
    train the structure network for ``steps`` (``kind`` "structure_net"), or average the stages ``average``."""

    name: str
    kind: str               # "train", "structure_net" or "average"
    config: str = ""
    steps: int = 0
    average: tuple = ()
    cfg: object = dataclasses.field(default=None, compare=False)    # ``config`` as read and checked by load_line
    finish: str = ""        # run on the stage's export once it is done ("" none; the line's finish on the last)

    @property
    def continues(self) -> bool:
        """Whether the stage starts from the export before it (its config continues an export or a run), not
        afresh."""
        return self.kind == "train" and bool(self.cfg.init_onnx or getattr(self.cfg, "init_from", ""))


class _Neural:
    """What a line needs of the neural noise model's training code."""

    json = "neural_noise.json"
    kinds = ("train",)
    finishes = ("int8",)

    @staticmethod
    def config(path: str):
        from .config import load_config
        return load_config(path)

    @staticmethod
    def train(cfg, run: str, start_step: int, stop: int, log) -> None:
        from .train import train
        train(dataclasses.replace(cfg, steps=stop), run, log=log)

    @staticmethod
    def export(run: str, out: str) -> None:
        from .export_onnx import export
        export(run, out)

    @staticmethod
    def finished(doc: dict, finish: str) -> bool:
        return "int8" in doc

    @staticmethod
    def finish(folder: str, finish: str, log) -> None:
        from .quantize_onnx import quantize_folder
        quantize_folder(folder, log=log)


class _Solid:
    """What a line needs of the solid texture model's training code."""

    json = "solid.json"
    kinds = ("train", "structure_net", "average")
    finishes = ("spin octave", "spin lattice", "harmonics")

    @staticmethod
    def config(path: str):
        from .solid.train import load_config
        return load_config(path)

    @staticmethod
    def train(cfg, run: str, start_step: int, stop: int, log) -> None:
        import torch

        from .solid.train import train
        ckpt = os.path.join(run, "ckpt.pt")
        at = torch.load(ckpt, map_location="cpu", weights_only=False)["step"] if os.path.isfile(ckpt) else start_step
        train(cfg, run, max_steps=max(stop - at, 0), log=log)

    @staticmethod
    def export(run: str, out: str) -> None:
        from .solid.export import export
        export(run, out)

    @staticmethod
    def finished(doc: dict, finish: str) -> bool:
        if finish == "harmonics":           # a single-photo model's harmonic part
            return "harmonics" in doc
        return doc.get("spin") == finish.split()[1] and "code_harmonics" in doc

    @staticmethod
    def finish(folder: str, finish: str, log) -> None:
        from .solid import harmonics
        spin = [] if finish == "harmonics" else ["--spin", finish.split()[1]]
        if harmonics.main([folder, *spin, "--root", ROOT]) != 0:
            raise RuntimeError(f"finish {finish!r} failed on {folder}")


MODELS = {"neural_noise": _Neural, "solid": _Solid}


def _stage(entry, where: str, folder: str, names: set, model) -> Stage:
    """One entry of a line file as a Stage, checked (ValueError naming what is wrong)."""
    keys = set(entry) if isinstance(entry, dict) else set()
    kind = {frozenset({"name", "config", "steps"}): "train", frozenset({"name", "structure_net"}): "structure_net",
            frozenset({"name", "average"}): "average"}.get(frozenset(keys - {"finish"}))
    if kind not in model.kinds or ("finish" in keys and kind == "structure_net"):
        shapes = {"train": "name, config, steps", "structure_net": "name, structure_net", "average": "name, average"}
        raise ValueError(f"{where}: needs exactly " + " or ".join(shapes[k] for k in model.kinds)
                         + " (and, but for a structure network, a finish)")
    finish = entry.get("finish", "")
    if "finish" in keys and finish not in model.finishes:
        raise ValueError(f"{where}: finish must be one of {', '.join(model.finishes)}, got {finish!r}")
    name = entry["name"]
    if not isinstance(name, str) or not NAME.fullmatch(name) or name in names:
        raise ValueError(f"{where}: name must be a new name of a-z, 0-9 and _, got {name!r}")
    if kind == "average":
        runs = entry["average"]
        if not isinstance(runs, list) or len(runs) < 2 or any(r not in names for r in runs):
            raise ValueError(f"{where}: average names two or more stages before it, got {runs!r}")
        return Stage(name, kind, average=tuple(runs), finish=finish)
    steps = entry["steps" if kind == "train" else "structure_net"]
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"{where}: steps must be a whole number >= 1, got {steps!r}")
    if kind == "structure_net":
        return Stage(name, kind, steps=steps)
    config = os.path.join(folder, entry["config"])
    try:
        cfg = model.config(config)
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"{where}: config {entry['config']}: {exc}") from None
    if steps > cfg.steps:
        raise ValueError(f"{where}: steps {steps} is past its config's {cfg.steps}")
    return Stage(name, kind, config, steps, cfg=cfg, finish=finish)


def load_line(path: str) -> tuple:
    """(model, stages, finish) of a line file (module docstring), checked: ValueError naming the first bad entry.
    Each config is read, so a line whose config would fail at its stage fails here, before any work."""
    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    if not isinstance(doc, dict) or doc.get("model") not in MODELS:
        raise ValueError(f"{path}: 'model' must be one of {', '.join(MODELS)}")
    model = MODELS[doc["model"]]
    entries = doc.get("stages")
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: a line needs 'stages', a list of stages")
    finish = doc.get("finish", "")
    if finish and finish not in model.finishes:
        raise ValueError(f"{path}: finish must be one of {', '.join(model.finishes)}, got {finish!r}")
    stages, names = [], set()
    for i, e in enumerate(entries):
        stages.append(_stage(e, f"{path}: stages[{i}]", os.path.dirname(os.path.abspath(path)), names, model))
        names.add(stages[-1].name)
    if stages[-1].kind == "structure_net":
        raise ValueError(f"{path}: the last stage gives no model")
    if finish and stages[-1].finish:
        raise ValueError(f"{path}: the line's finish and its last stage's are both given")
    if finish and len(line_models(stages)) > 1:
        raise ValueError(f"{path}: a line of several models gives a finish to each stage that needs one, not to "
                         "the line")
    return model, stages, finish


def _start(stages: list, k: int) -> Stage | None:
    """The stage whose export stage ``k`` (0-based) starts from: the model-giving stage before it where its config
    continues an export, else None (a fresh network)."""
    if not stages[k].continues:
        return None
    before = [s for s in stages[:k] if s.kind != "structure_net"]
    return before[-1] if before else None


def line_models(stages: list) -> list:
    """The stages whose exports are the line's models: those no later stage continues or averages."""
    used = {b.name for b in (_start(stages, k) for k in range(len(stages))) if b is not None}
    used |= {name for s in stages for name in s.average}
    return [s for s in stages if s.kind != "structure_net" and s.name not in used]


def _json(folder: str, name: str) -> dict | None:
    try:
        with open(os.path.join(folder, name), encoding="utf-8") as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def _started_from(run: str) -> str | None:
    """The fingerprint of the weights a run folder's training began from ("" for a fresh network; None where
    nothing was trained there), from the config its checkpoint or ``config.json`` records."""
    doc = _json(run, "config.json")
    if doc is None and os.path.isfile(os.path.join(run, "ckpt.pt")):
        import torch
        doc = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False).get("config")
    return None if doc is None else doc.get("init_sha256", "")


def _structure_net(stage: Stage, out: str, max_steps: int | None, log) -> str:
    """Train the structure network into OUT/NAME/net.pt unless it holds as many steps; returns its path."""
    import torch

    from .solid.structure_features import save_photo_set_net

    path = os.path.join(out, stage.name, "net.pt")
    steps = min(stage.steps, max_steps or stage.steps)
    if os.path.isfile(path) and torch.load(path, weights_only=False)["record"]["steps"] == steps:
        log(f"{stage.name}: done ({path})")
        return path
    log(f"{stage.name}: the structure network, to step {steps}")
    save_photo_set_net(path, steps, log=lambda s: log(f"  {s}"))
    return path


def run_line(line: tuple, out: str, max_steps: int | None = None, device: str | None = None, log=print) -> str:
    """Train and export each stage of ``line`` (:func:`load_line`) in turn into ``out`` (module docstring); returns
    the last export's folder. ``max_steps`` caps every stage's steps (a quick run of the line); ``device`` trains
    every stage there."""
    from omninoise.backend.onnx_models import fingerprint

    model, stages, finish = line
    net = None                          # the structure network
    for k, stage in enumerate(stages, 1):
        say = f"[{k}/{len(stages)}] {stage.name}"
        if stage.kind == "structure_net":
            net = _structure_net(stage, out, max_steps, lambda s: log(f"[{k}/{len(stages)}] {s}"))
            continue
        run, done = os.path.join(out, stage.name), os.path.join(out, stage.name, EXPORT)
        before = _start(stages, k - 1)
        start = None if before is None else os.path.join(out, before.name, EXPORT)   # None: the config's own start
        start_step = 0 if start is None or model is _Neural else int(_json(start, model.json).get("step", 0))
        if stage.kind == "average":
            stop = int(_json(os.path.join(out, stage.average[-1], EXPORT), model.json)["step"])
        else:
            stop = min(stage.steps, start_step + max_steps) if max_steps else stage.steps
        if (_json(done, model.json) or {}).get("step") == stop:
            log(f"{say}: done ({done})")
        elif stage.kind == "average":
            from .solid.average import average_checkpoints, write_checkpoint

            log(f"{say}: the mean of {', '.join(stage.average)}")
            write_checkpoint(run, average_checkpoints([os.path.join(out, name) for name in stage.average]))
            model.export(run, done)
        else:
            cfg = stage.cfg
            if start is not None:
                cfg = dataclasses.replace(cfg, init_onnx=start,
                                          init_sha256=fingerprint(_json(start, model.json)["files"]),
                                          **({"init_from": ""} if getattr(cfg, "init_from", "") else {}))
            if net is not None and getattr(cfg, "structure_weight", 0):
                cfg = dataclasses.replace(cfg, structure_net=net)
            if device:
                cfg = dataclasses.replace(cfg, device=device)
            origin = start or cfg.init_onnx or "a fresh network"
            log(f"{say}: {os.path.relpath(stage.config)}, to step {stop}, from {origin}")
            if _started_from(run) not in (None, cfg.init_sha256):   # its run began from another export
                log(f"  {run} began from other weights than the stage before's export: training it again")
                shutil.rmtree(run)
            t0 = time.time()
            model.train(cfg, run, start_step, stop, lambda text: log(f"  {text}"))
            model.export(run, done)     # its JSON, with the step, is written last: a cut-short export is not done
            log(f"  exported to {done} ({time.time() - t0:.0f} s)")
        last = finish if k == len(stages) else ""
        for end in filter(None, (stage.finish, last)):
            if not model.finished(_json(done, model.json), end):
                model.finish(done, end, lambda text: log(f"  {text}"))
                log(f"  {end}: {done}")
    return done


def _check_devices(line: tuple) -> None:
    """ValueError naming the first stage whose config trains on a GPU that torch does not see here."""
    import torch

    for s in line[1]:
        if s.kind == "train" and s.cfg.device.startswith("cuda") and not torch.cuda.is_available():
            raise ValueError(f"stage {s.name} trains on {s.cfg.device} and torch sees no CUDA device here: give "
                             "--device cpu to train every stage on the CPU")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.line",
                                 description="Train a model's whole line of stages, each from the export of the one "
                                             "before, where the shipped line stopped it; run again, it goes on "
                                             "where it stopped.")
    ap.add_argument("line", help="a line file (configs/lines/neural_noise.json, configs/lines/solid_space.json)")
    ap.add_argument("--out", required=True, help="the folder of the stages' runs and exports")
    ap.add_argument("--steps", type=int, help="train every stage for at most this many steps (a check of the line)")
    ap.add_argument("--device", help="train every stage on this torch device (cpu, cuda)")
    ap.add_argument("--dry-run", action="store_true", help="list the stages and where each starts, train nothing")
    a = ap.parse_args(argv)
    try:
        if a.steps is not None and a.steps < 1:
            raise ValueError(f"--steps must be >= 1, got {a.steps}")
        line = load_line(a.line)
        if not a.device and not a.dry_run:
            _check_devices(line)
    except (OSError, ValueError) as exc:
        print(f"line: error: {exc}", file=sys.stderr)
        return 2
    if a.dry_run:
        stages = line[1]
        for k, s in enumerate(stages, 1):
            what = {"structure_net": f"the structure network, {s.steps} steps",
                    "average": f"the mean of {', '.join(s.average)}"}.get(s.kind)
            if what is None:
                before = _start(stages, k - 1)
                start = f"the export of {before.name}" if before else (s.cfg.init_onnx or "a fresh network")
                what = f"{os.path.relpath(s.config)}, to step {s.steps}, from {start}"
            print(f"[{k}/{len(stages)}] {s.name}: {what}" + (f", then {s.finish}" if s.finish else ""))
        if line[2]:
            print(f"then {line[2]}")
        return 0
    run_line(line, a.out, a.steps, a.device)
    models = [os.path.join(a.out, s.name, EXPORT) for s in line_models(line[1])]
    print(f"line: the model is {models[0]}" if len(models) == 1 else "line: the models are " + ", ".join(models))
    return 0


if __name__ == "__main__":
    sys.exit(main())
