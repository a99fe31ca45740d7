"""A neural model's report from its run, export and evaluation: ``python -m omninoise.training.model_card ...``.

    python -m omninoise.training.model_card [--run RUN] --model MODEL_DIR --eval EVAL.json \\
        [--ablation-eval EVAL_NO_CUTMIX.json] --train-command "..." -o runs/cards/neural_noise.md

A maintainer updates ``models/neural_noise/MODEL_CARD.md`` (kept short by hand) from it.
Everything in the report is read from files the project's own commands wrote:
the run's log (wall time, final loss), the export's JSON (config, steps, sha256,
classes) and the evaluation JSON of ``python -m bench neural-eval``.  Runs are not kept,
so the export also records the log's figures (``training`` in its JSON) and the
card reads them there when no ``--run`` is given; an export made before that
record existed takes them from ``--wall-minutes`` and ``--final-mse`` (figures
written down from the run's log when it finished), and the card says so.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys

__all__ = ["wall_seconds", "run_record", "run_figures", "card"]


def wall_seconds(log_path: str) -> float:
    """Training wall time from log.jsonl: the sum over resumed segments (``seconds`` restarts at 0)."""
    total, last = 0.0, 0.0
    with open(log_path, encoding="utf-8") as fh:
        for line in fh:
            s = json.loads(line)["seconds"]
            if s < last:
                total += last
            last = s
    return total + last


def run_record(log_path: str) -> dict:
    """What a card needs from a run's log.jsonl (the export keeps it): wall seconds over resumed segments,
    the final MSE (mean of the last log window) and the step it was logged at."""
    with open(log_path, encoding="utf-8") as fh:
        last = [json.loads(line) for line in fh if line.strip()][-1]
    return dict(wall_seconds=round(wall_seconds(log_path), 1), final_mse=round(float(last["mse"]), 5),
                log_step=int(last["step"]))


def read_json(path: str | None):
    """The JSON document at ``path``, or None when no path is given."""
    if not path:
        return None
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)


def cpu_name() -> str:
    """The CPU's model name (/proc/cpuinfo), else what platform knows."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            names = [ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")]
        if names:
            cpu = names[0]
    except OSError:
        pass
    return cpu


def hardware_line() -> str:
    return f"{cpu_name()}, {os.cpu_count()} cores visible, 1 training thread"


def _table(ev: dict) -> str:
    rows = ["| class | FD ↓ | classifier acc ↑ | PSD error ↓ | response error ↓ (parameter) |", "|---|---|---|---|---|"]
    for name, r in ev["classes"].items():
        rows.append(f"| {name} | {r['fd']} | {r['acc']} | {r['psd']} | {r['response']} ({r['param']}) |")
    return "\n".join(rows)


def kept_sections(card_text: str, headings) -> str:
    """The ``## heading`` sections of an earlier card, verbatim, in the order asked (ValueError if one is missing)."""
    parts = {}
    for block in ("\n" + card_text).split("\n## ")[1:]:
        title, _, body = block.partition("\n")
        parts[title.strip()] = body.rstrip("\n")
    out = []
    for h in headings:
        if h not in parts:
            raise ValueError(f"the earlier card has no section '## {h}'")
        out.append(f"## {h}\n{parts[h]}")
    return "\n\n".join(out)


def run_figures(run: str | None, meta: dict, wall_minutes: float | None = None,
                final_mse: float | None = None) -> tuple:
    """(wall minutes, final MSE, where they come from) of a model's training run.

    From the run's log.jsonl when ``run`` is given, else the export's ``training``
    record, else the figures given; ValueError when none of these has them.
    """
    if run:
        rec, source = run_record(os.path.join(run, "log.jsonl")), "the run's log"
    elif "training" in meta:
        rec, source = meta["training"], "the run's log, recorded in the export's JSON"
    else:
        rec = None
    if rec is not None:
        return rec["wall_seconds"] / 60, rec["final_mse"], source
    if wall_minutes is None or final_mse is None:
        raise ValueError("no --run, and the export has no training record: give --wall-minutes and --final-mse")
    return wall_minutes, final_mse, "the run's log when it finished (the run folder is not kept)"


def _sampler_words(ev: dict) -> str:
    """'30 DDIM steps' (evaluations before samplers were selectable) or the sampler the evaluation names."""
    smp = ev.get("sampler", dict(name="ddim", steps=ev["model"]["steps"]))
    return f"{smp['steps']} {smp['name'].upper().replace('DPMPP_2M', 'DPM-Solver++(2M)')} steps"


def card(run: str | None, model: str, ev: dict, ablation: dict | None, train_command: str, hardware: str | None = None,
         previous: dict | None = None, previous_label: str = "previous model", ablation_label: str = "",
         ablation_reference: dict | None = None, compare: dict | None = None, kept: str = "",
         wall_minutes: float | None = None, final_mse: float | None = None, note: str = "") -> str:
    """The card's markdown.  ``ablation_reference``: the evaluation of the CutMix model trained like
    the ablation (same steps) when this model was trained longer; default: this model.
    ``compare``: this model evaluated on ``previous``'s classes with the same instrument (when the
    two models know different classes); ``kept``: sections carried over from the earlier card; ``note``:
    a paragraph closing the comparison (why this model replaced the previous one)."""
    with open(os.path.join(model, "neural_noise.json"), encoding="utf-8") as fh:
        meta = json.load(fh)
    wall, mse, source = run_figures(run, meta, wall_minutes, final_mse)
    cfg = meta["config"]
    t = ev["timing"]
    mean = lambda key, e: round(sum(r[key] for r in e["classes"].values()) / len(e["classes"]), 3)  # noqa: E731
    lines = [
        "# Neural noise model card",
        "",
        f"One diffusion model for {len(meta['trained_classes'])} noise classes (Maesumi et al. 2024), trained by this "
        "project's code on its procedural zoo.",
        "",
        "## How it was made",
        "",
        "```sh",
        train_command.strip(),
        "```",
        "",
        f"- **Data:** `training/zoo.py`, generated on the fly. Classes: {', '.join(meta['trained_classes'])}. "
        f"Halton parameter sets, {cfg['seeds_per_set']} seeds each, {cfg['size']}² px.",
        f"- **Config:** size {cfg['size']}, batch {cfg['batch']}, {cfg['steps']} steps, lr {cfg['lr']}, "
        f"EMA {cfg['ema_decay']}, CutMix p {cfg['cutmix_p']}, widths {cfg['widths']}"
        + (f" with a {cfg['deep']}-level deep branch" if cfg.get("deep") else "") + f", embedding {cfg['emb_dim']}-D.",
        f"- **Hardware:** {hardware or hardware_line()}.",
        f"- **Steps:** {meta['step']}. **Wall time:** {wall:.1f} min.",
        f"- **Final training MSE** (mean of the last log window): {mse:.4f}. Wall time and loss are from {source}.",
        f"- **Weights:** {meta['weights']} (exported with `python -m omninoise.training.export_onnx`).",
        f"- **Form:** {meta.get('form', 'one-piece')}; **sha256** "
        + ", ".join(f"of `{name}`: `{digest}`" for name, digest in sorted(meta["files"].items())) + ".",
        "",
        "## Evaluation (`python -m bench neural-eval`)",
        "",
        f"{ev['model']['n']} samples per class, {_sampler_words(ev)}. The zoo classifier is accurate to "
        f"{ev['zoo_accuracy']} on held-out zoo samples.",
        "",
        _table(ev),
        "",
        f"- **Means:** FD {mean('fd', ev)}, accuracy {mean('acc', ev)}, PSD error {mean('psd', ev)}, "
        f"response error {mean('response', ev)}.",
        f"- **Seams:** the wrap difference over the interior neighbour difference is {ev['seam_tileable']} for tileable "
        f"output and {ev['seam_plain']} for plain output (1 means seamless).",
        f"- **Blend locality** (half/half mask blends, crops classified as their side's class): {ev['locality']}.",
        f"- **DDIM step at {t['size']}²:** onnxruntime {t['onnxruntime_s']} s, torch {t['torch_s']} s with the same "
        f"weights (torch / onnxruntime = {t['ratio']}; max |Δε| {t['max_eps_difference']:.1e}).",
    ]
    if previous is not None:
        cur = compare if compare is not None else ev
        lines += ["", "## Against the model it replaced", "",
                  f"The same evaluation of the {previous_label}"
                  + (f", both models on its {len(previous['classes'])} classes ({', '.join(previous['classes'])}) "
                     "with one instrument (the same classifier, trained with the same seed and thread count)"
                     if compare is not None else "") + ":", "",
                  "| measure | previous | this model |", "|---|---|---|"]
        for key, label in (("fd", "mean FD ↓"), ("acc", "mean classifier accuracy ↑"), ("psd", "mean PSD error ↓"),
                           ("response", "mean response error ↓")):
            lines.append(f"| {label} | {mean(key, previous)} | {mean(key, cur)} |")
        lines += [f"| seam ratio, tileable ↓ | {previous['seam_tileable']} | {cur['seam_tileable']} |",
                  f"| blend locality ↑ | {previous['locality']} | {cur['locality']} |",
                  f"| zoo classifier accuracy (the instrument) | {previous['zoo_accuracy']} | {cur['zoo_accuracy']} |"]
        if compare is not None:
            lines += ["", "| class | FD ↓ previous / this | accuracy ↑ previous / this | PSD error ↓ previous / this |",
                      "|---|---|---|---|"]
            for name, r in previous["classes"].items():
                c = compare["classes"][name]
                lines.append(f"| {name} | {r['fd']} / {c['fd']} | {r['acc']} / {c['acc']} | {r['psd']} / {c['psd']} |")
        if note:
            lines += ["", note.strip()]
    if ablation is not None:
        ref = ablation_reference if ablation_reference is not None else ev
        lines += ["", "## CutMix ablation (Fig. 13)", "",
                  f"The same config and steps with `cutmix_p = 0` (`configs/neural_noise_cpu_nocutmix.json`)"
                  f"{ablation_label}:", "",
                  "| model | blend locality ↑ | mean FD ↓ | mean accuracy ↑ |", "|---|---|---|---|",
                  f"| with CutMix | {ref['locality']} | {mean('fd', ref)} | {mean('acc', ref)} |",
                  f"| without CutMix | {ablation['locality']} | {mean('fd', ablation)} | {mean('acc', ablation)} |"]
    if kept:
        lines += ["", kept]
    lines += ["", "## Limits", "",
              "This is a small model trained on a CPU. The paper's setting (a GPU, 128² or more, far more steps; "
              "`configs/neural_noise_gpu.json`) is needed for production quality. The numbers above are this "
              "model's own, measured as written."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.model_card", description=__doc__.split("\n")[0])
    ap.add_argument("--run", help="the training run (its log.jsonl); default: the export's training record")
    ap.add_argument("--wall-minutes", type=float, help="without --run or a training record: the run's wall time")
    ap.add_argument("--final-mse", type=float, help="without --run or a training record: the run's final MSE")
    ap.add_argument("--model", required=True)
    ap.add_argument("--eval", required=True)
    ap.add_argument("--ablation-eval")
    ap.add_argument("--train-command", required=True)
    ap.add_argument("--hardware")
    ap.add_argument("--previous-eval", help="evaluation JSON of the model this one replaces")
    ap.add_argument("--previous-label", default="previous model")
    ap.add_argument("--ablation-label", default="", help="text after the ablation's heading sentence")
    ap.add_argument("--ablation-reference", help="evaluation JSON of the CutMix model with the ablation's steps")
    ap.add_argument("--compare-eval", help="evaluation JSON of this model on the previous model's classes "
                                           "(python -m bench neural-eval --classes ...), when their classes differ")
    ap.add_argument("--note", default="", help="a paragraph after the comparison: why this model replaced the previous")
    ap.add_argument("--keep-from", help="an earlier card whose --keep sections are carried over verbatim")
    ap.add_argument("--keep", action="append", default=[], help="a '## ' heading of --keep-from (repeatable)")
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args(argv)
    ev, abl, prev, ref, cmp = (read_json(p) for p in (a.eval, a.ablation_eval, a.previous_eval, a.ablation_reference,
                                                       a.compare_eval))
    kept = ""
    if a.keep:
        if not a.keep_from:
            ap.error("--keep needs --keep-from")
        with open(a.keep_from, encoding="utf-8") as fh:
            try:
                kept = kept_sections(fh.read(), a.keep)
            except ValueError as exc:
                ap.error(str(exc))
    try:
        text = card(a.run, a.model, ev, abl, a.train_command, a.hardware, prev, a.previous_label, a.ablation_label,
                    ref, cmp, kept, a.wall_minutes, a.final_mse, a.note)
    except ValueError as exc:
        ap.error(str(exc))
    from omninoise import export

    export.write_text(a.out, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
