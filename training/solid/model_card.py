"""Write the solid-texture model card: ``python -m training.solid.model_card``.

    python -m training.solid.model_card --models models/solid --runs runs/solid \\
        --eval out/bench/solid_eval.json -o models/solid/MODEL_CARD.md

Everything in the card is read from files the project's own commands wrote:
each model's ``solid.json`` (config, steps, sha256), its run's ``log.jsonl``
(wall time, final loss) and the evaluation JSON of ``bench/eval_solid.py``.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from ..model_card import hardware_line, read_json, wall_seconds

__all__ = ["card"]


def _final_loss(log: str, window: int = 10) -> float:
    """Median of the last ``window`` logged losses (one batch each: the space model's vary several-fold)."""
    with open(log, encoding="utf-8") as fh:
        rows = sorted(json.loads(line)["loss"] for line in fh.readlines()[-window:])
    mid = len(rows) // 2
    return round(rows[mid] if len(rows) % 2 else 0.5 * (rows[mid - 1] + rows[mid]), 4)


def _config_index(configs: str) -> dict:
    """{config name: (file name, config)} of the JSON configs in folder ``configs``."""
    index = {}
    if os.path.isdir(configs):
        for fn in sorted(os.listdir(configs)):
            if fn.endswith(".json"):
                cfg = read_json(os.path.join(configs, fn))
                index.setdefault(cfg.get("name"), (fn, cfg))
    return index


def _config_files(cfg: dict, index: dict) -> list:
    """The config files a model was trained with, in order: its init_from chain, then its own."""
    chain, cur = [], cfg
    while cur is not None and len(chain) < 8:
        chain.insert(0, index.get(cur.get("name"), (f"{cur.get('name')}.json", None))[0])
        parent = os.path.basename(cur.get("init_from", "").rstrip("/"))
        cur = index[parent][1] if parent in index else None
    return chain


def _compare(prev: dict, new: dict, replaced: list, rejected: dict | None = None) -> list:
    """Previous against new evaluation rows of the methods the replaced models feed (replaced:
    "space" or the exemplar of a 3D single model); ``rejected``:
    {model name: (exemplar, evaluation rows of the candidate that did not replace it)}."""
    L = ["## Against the models they replaced", "",
         "Each cell is style error / PSD error / success, previous → new (same evaluation, same seeds). "
         "A retrained model replaces the shipped one only when its style error is lower and its PSD error "
         "no more than 0.02 higher (the space model: their means over its seven exemplars).", "",
         "| exemplar | method | previous | new |", "|---|---|---|---|"]
    pairs = {("*", "space_3d")} if "space" in replaced else set()
    pairs |= {(exemplar, "ours_3d") for exemplar in replaced if exemplar != "space"}
    for name, rows in new.items():
        for meth in sorted(rows):
            a, b = prev.get(name, {}).get(meth), rows[meth]
            if a is None or not ({(name, meth), ("*", meth)} & pairs):
                continue
            L.append(f"| {name} | {meth} | {_cell(a)} | {_cell(b)} |")
    for model, (name, rows) in sorted((rejected or {}).items()):
        meth = "space_3d" if model == "space" else "ours_3d"
        if meth in rows and meth in prev.get(name, {}):
            L.append(f"| {name} | {meth}: {model} continued, **not shipped** | {_cell(prev[name][meth])} | "
                     f"{_cell(rows[meth])} |")
    return L + [""]


def _cell(r: dict) -> str:
    return f"{r['style']} / {r['psd']} / {r['success']}"


def card(models: str, runs: str, eval_path: str | None, configs: str = "configs/solid",
         previous_eval: str | None = None, rejected: dict | None = None) -> str:
    """``rejected``: {model name: path of the evaluation JSON of its continued run}, shown, not shipped."""
    docs = {}
    for name in sorted(os.listdir(models)):
        path = os.path.join(models, name, "solid.json")
        if os.path.isfile(path):
            with open(path, encoding="utf-8") as fh:
                docs[name] = json.load(fh)
    ev = {}
    if eval_path and os.path.isfile(eval_path):
        with open(eval_path, encoding="utf-8") as fh:
            ev = json.load(fh)
    L = ["# Neural solid texture models", "",
         "Solid textures after Henzler, Mitra and Ritschel, \"Learning a Neural 3D Texture Space from 2D "
         "Exemplars\" (CVPR 2020), trained by this project's code (`training/solid/`) on CPU.", "",
         "## How they were made", "", "```sh",
         "# one model per config; configs/solid/NAME.json names its exemplar, dimension and schedule",
         "python -m training.solid.train --config configs/solid/NAME.json --out runs/solid/NAME",
         "python -m training.solid.export runs/solid/NAME models/solid/NAME",
         "python bench/eval_solid.py --speed",
         "python -m training.solid.model_card -o models/solid/MODEL_CARD.md", "```", "",
         "- **Exemplars:** the CC0 photographs brick, grass and gravel from scikit-image's data "
         "(`data/exemplars/README.md`; training never crops their right quarter) and the procedural classes "
         "wood, marble, rust and granite of `training/solid/exemplars.py` (seed 0 trains, seed 1 is held out).",
         "- **Model** (Sec. 3-4, Eq. 5): 8 octaves of lattice value noise, 3 values per lattice point, octave i "
         "read at T_i 2^(i-1) x; decoder MLP of four 128-wide ReLU layers over [noise (24), e (64)] to RGB "
         "(sigmoid, sRGB values). Single mode learns e, T and the decoder; the space model learns an "
         "instance-normalised encoder (128 px patch -> z, 8-D), a translator h(z) -> (e, T) and the decoder jointly.",
         "- **Loss:** no pretrained VGG can be downloaded here, so the Gram matrices are those of a fixed random "
         "two-layer network (32 5x5 and 64 3x3 zero-mean filters, four pyramid levels; Ustyuzhaninov et al. 2017 "
         "showed random multi-scale filters suffice for Gram-based synthesis), plus a sliced Wasserstein term on "
         "the joint RGB distribution (10 colour directions), weight 10.",
         "- **3D from 2D:** each step renders 128² slices through random points of 3D space, axis-aligned "
         "(random axis permutation) or, half the time, randomly rotated; every slice must match the exemplar's "
         "statistics. Exemplar crops are randomly rotated/flipped for 3D models.",
         f"- **Hardware:** {hardware_line()}; one torch thread per run, two or three runs sharing the two cores "
         "(wall times include that sharing).",
         "- **gravel_3d** was trained before the decoder's He initialisation became the default; its config "
         "names `decoder_init = \"torch\"`, which reproduces it. Every other model uses He initialisation.", "",
         "## Models", "",
         "Final loss: the median of the last ten logged batch losses.", "",
         "| model | mode | dim | exemplars | scale | configs | steps | wall time | final loss | sha256 (decoder.onnx) |",
         "|---|---|---|---|---|---|---|---|---|---|"]
    continued, index = [], _config_index(configs)
    for name, d in docs.items():
        log = os.path.join(runs, d["name"], "log.jsonl")
        wall = f"{wall_seconds(log) / 60:.1f} min" if os.path.isfile(log) else "n/a"
        loss = _final_loss(log) if os.path.isfile(log) else "n/a"
        chain = _config_files(d.get("config", {"name": d["name"]}), index)
        if len(chain) > 1:
            continued.append(name)
        L.append(f"| {name} | {d['mode']} | {d['dim']}D | {', '.join(d['exemplars'])} | {d['exemplar_scale']} | "
                 f"{' → '.join(f'`{c}`' for c in chain)} | {d['step']} | {wall} | {loss} | "
                 f"`{d['files']['decoder.onnx'][:16]}…` |")
    if continued:
        L += ["", f"{', '.join(continued)}: trained by the first config, then continued by the second "
              "(`init_from` names the first run; a longer `steps` restarts the cosine learning-rate decay at the "
              "step where the first run ended), each with the `train` command above. Wall time and loss cover "
              "both stages. This is the longest CPU training the session allowed (no GPU was lent): "
              "`python -m training.solid.train --config configs/solid/NAME_long.json "
              "--out runs/solid/NAME_long` after the first run."]
    L += ["", "Full sha256 of every file: each model's `solid.json` (`files`); the runtime refuses a file whose "
          "hash differs. Configs: `configs/solid/<model>.json` (the space model: `space_3d.json`).", ""]
    q = ev.get("quality")
    if q and previous_eval and os.path.isfile(previous_eval) and continued:
        prev = read_json(previous_eval).get("quality", {})
        rej = {}
        for model, path in (rejected or {}).items():
            if model not in docs:
                raise ValueError(f"--rejected: {model!r} is not a shipped model in {models}")
            exemplar = docs[model]["exemplars"][0]
            rej[model] = (exemplar, read_json(path)["quality"].get(exemplar, {}))
        L += _compare(prev, q, ["space" if docs[n]["mode"] == "space" else docs[n]["exemplars"][0]
                                for n in continued if docs[n]["mode"] == "space" or docs[n]["dim"] == 3], rej)
    if q:
        L += ["## Evaluation (`bench/eval_solid.py`)", "",
              f"{ev.get('n', 8)} samples (seeds) per method at 64² px of the training resolution, compared with the exemplar's "
              "held-out pixels. Style error: Gram distance of an independent random network (other seed, widths "
              "and kernels than the loss) plus the colour term; a real 64 px crop scores about 1 on it because one "
              "crop's statistics scatter around the held-out mean. PSD error: mean |log| ratio of luminance power "
              "spectra. Diversity: mean pairwise relative distance of first-layer feature maps (0: every seed gives "
              "the same image). Success = diversity × (row's worst style error − style error), as in Table 3.", "",
              "| exemplar | method | style error ↓ | PSD error ↓ | diversity ↑ | success ↑ |", "|---|---|---|---|---|---|"]
        for name, rows in q.items():
            for meth, r in rows.items():
                L.append(f"| {name} | {meth} | {r['style']} | {r['psd']} | {r['diversity']} | {r['success']} |")
        L.append("")
    sp = ev.get("speed")
    if sp:
        L += ["## Speed and memory (Table 2)", "", "Every point evaluated, in a fresh process each "
              "(peak resident memory includes the interpreter and libraries; measured on one single-exemplar "
              "model: speed depends on the architecture, not the weights):", "",
              "| grid | engine | points/s | seconds | peak MiB |", "|---|---|---|---|---|"]
        for r in sp:
            L.append(f"| {'×'.join([str(r['size'])] * r['dim'])} | {r['engine']} | {r['points_per_s']:,} | "
                     f"{r['seconds']} | {r['peak_mib']} |")
        L.append("")
    L += ["## Limits", "",
          "- The point-wise MLP over value noise reproduces stochastic, stationary textures (granite, gravel-like "
          "speckle, rust, marble clouds) far better than structured ones: bricks come out as blotches, not "
          "courses, as the paper's own results and its Table 1 note for non-stochastic appearance.",
          "- The photographs are greyscale; the models still output RGB.",
          "- The texture-space model needed three fixes before it conditioned on its input at all, each found by "
          "looking at its output during training: its encoder first averaged instance-normalised maps (every "
          "exemplar got the same code; it now reads the per-channel statistics the normalisation removes), its "
          "translator's unbounded transforms grew ~100x (now bounded by tanh), and a x0.1-scaled code output left "
          "the decoder ignoring e (now full scale, with distinct exemplars in every batch). Continued from 1500 to "
          "5000 steps it generalises much better to held-out pixels (mean style error 7.18 -> 2.88), but brick and "
          "marble remain far from their exemplars: it separates colours and coarse character more than structure.",
          "- Longer training does not always help: the continued wood_3d lost to the shipped one on both errors, "
          "and the continued rust_3d and granite_3d gained little, although their training losses fell; the "
          "independent evaluation network, not the training loss, decides what ships.",
          "- Trained on two CPU cores for minutes per model: a GPU run with more steps and a larger batch would "
          "lower the style error further.", ""]
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m training.solid.model_card", description=__doc__.split("\n")[0])
    ap.add_argument("--models", default="models/solid")
    ap.add_argument("--runs", default="runs/solid")
    ap.add_argument("--eval", default="out/bench/solid_eval.json")
    ap.add_argument("--configs", default="configs/solid")
    ap.add_argument("--previous-eval", help="evaluation JSON of the models that retrained ones replaced")
    ap.add_argument("--rejected", nargs="*", default=[], metavar="MODEL=EVAL_JSON",
                    help="continued runs that did not beat the shipped model, with their evaluation")
    ap.add_argument("-o", "--out", default="models/solid/MODEL_CARD.md")
    a = ap.parse_args(argv)
    rejected = dict(r.split("=", 1) for r in a.rejected)
    text = card(a.models, a.runs, a.eval, a.configs, a.previous_eval, rejected)
    from backend._export import export

    export.write_text(a.out, text)
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
