"""The photo texture-space section of the solid-texture report (``training/solid/model_card.py``), from which
a maintainer updates the model card's evaluation.

    python -m omninoise.training.solid.photo_card --run RUN --prev PREV.json --new NEW.json \\
        [--shipped] -o runs/cards/solid.md

Reads the candidate's run (``RUN/ckpt.pt`` config, ``RUN/log.jsonl``; or its export's ``solid.json``
when the run folder is gone), and two
``python -m bench solid-photos`` JSONs (the model shipped before, the
candidate) and writes the section between the markers
``<!-- photo-space:begin -->`` / ``<!-- photo-space:end -->`` of the card
(appended when the card has none), leaving the rest of the card as it is.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import sys

from omninoise import export as _ex
from ..model_card import read_json

BEGIN, END = "<!-- photo-space:begin -->", "<!-- photo-space:end -->"
#: the run's config when none is given
DEFAULT_CONFIG = "configs/solid/photo_space_3d.json"

ROWS = (("median patch distance (swd) ↓", "median_swd"), ("… random phase noise, same photos", "median_random_phase"),
        ("… pixel shuffle", "median_pixel_shuffle"), ("… Perlin with the photo's histogram", "median_perlin_hist"),
        ("… a crop of the photo itself", "median_photo_crop"),
        ("ratio to random phase ↓ (target ≤ 1.5)", "ratio_to_random_phase"),
        ("photos where it beats the pixel shuffle", "beats_pixel_shuffle"),
        ("photos where it beats random phase", "beats_random_phase"),
        ("photos where it beats the photo's own crops", "beats_photo_crop"),
        ("median distance per axis (each slice axis alone) ↓", "median_swd_axes"),
        ("… random phase noise, per axis", "median_random_phase_axes"),
        ("… the photo's own crops, per axis", "median_photo_crop_axes"),
        ("axis slices where it beats random phase (3 per photo)", "beats_random_phase_axes"),
        ("median distance on walls (x and y slices) ↓", "median_swd_walls"),
        ("… random phase noise, on walls", "median_random_phase_walls"),
        ("photos where it beats random phase on walls", "beats_random_phase_walls"),
        ("median mean-colour error ↓ (target ≤ 0.03)", "median_colour"), ("worst mean-colour error", "max_colour"),
        ("median diversity between seeds", "median_diversity"), ("median axis spread (x/y/z) ↓", "median_axis_spread"),
        ("median seconds: encode + six 128² slices", "median_seconds"),
        ("median morphology distance ↓", "median_morph"), ("… random phase noise", "median_morph_random_phase"),
        ("… a crop of the photo itself", "median_morph_photo_crop"),
        ("photos where it beats random phase on morphology", "beats_random_phase_morph"),
        ("median power-spectrum band distance ↓", "median_spectrum"),
        ("… random phase noise", "median_spectrum_random_phase"))


def _continued(cfg: dict) -> bool:
    """Whether a run's config continues an earlier stage (from its run folder or its export)."""
    return bool(cfg.get("init_onnx") or cfg.get("init_from"))


def run_facts(run: str) -> dict:
    """Steps, config, wall seconds, hardware (each stretch's, oldest first), final loss and last learning rate
    of a run folder (``ckpt.pt`` and ``log.jsonl``) or, when the run folder is gone, of its export
    (``solid.json``: no loss or learning rate)."""
    if os.path.isfile(os.path.join(run, "ckpt.pt")):
        import torch

        state = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
        log = []    # an averaged checkpoint (average.py) has no loss log of its own
        if os.path.isfile(os.path.join(run, "log.jsonl")):
            with open(os.path.join(run, "log.jsonl"), encoding="utf-8") as fh:
                log = [json.loads(line) for line in fh if line.strip()]
        last = sorted(r["loss"] for r in log[-10:])
        return dict(step=int(state["step"]), config=state["config"], seconds=float(state.get("elapsed", 0)),
                    loss=last[len(last) // 2] if last else None, lr=log[-1].get("lr") if log else None,
                    hardware=str(state.get("hardware", "")),
                    stages=bool(state.get("first_step") or _continued(state["config"])),
                    averaged=[int(a["step"]) for a in state.get("averaged_from", [])],
                    averaged_runs=[str(a["run"]) for a in state.get("averaged_from", [])])
    if os.path.isfile(os.path.join(run, "solid.json")):
        meta = read_json(os.path.join(run, "solid.json"))
        return dict(step=int(meta["step"]), config=meta["config"], seconds=float(meta.get("train_seconds", 0)),
                    loss=None, lr=None, hardware=str(meta.get("hardware", "")), stages=_continued(meta["config"]),
                    averaged=[], averaged_runs=[])
    raise SystemExit(f"photo_card: error: {run} has neither ckpt.pt (a run) nor solid.json (an export)")


def stage_commands(configs) -> list:
    """The shell lines that train a model through its stages: one ``training.solid.train`` per config (oldest
    first; a later one continues the earlier run through ``init_from``, or starts from its export through
    ``init_onnx``, exported first), the first stage's starting export as a
    comment, and the training of a stage's structure network before its first use.  A config file that is not
    there is named by its path alone (its stage's run folder is then ``runs/solid/`` + the file's stem less
    ``_3d``)."""
    lines, prev = [], None
    for i, path in enumerate(configs):
        try:
            cfg = read_json(path)
        except (OSError, ValueError):
            cfg = {"name": os.path.splitext(os.path.basename(path))[0].removesuffix("_3d")}
        if i == 0 and cfg.get("init_onnx"):
            lines.append(f"# starts from the export {cfg['init_onnx']} (sha256 {cfg['init_sha256'][:12]}...): "
                         "the model this one replaced")
        elif i and cfg.get("init_from"):
            lines.append(f"# continues {cfg['init_from']} (the stage above)")
        elif i and cfg.get("init_onnx"):  # starts from the stage above's export
            lines.append(f"python -m omninoise.training.solid.export runs/solid/{prev} {cfg['init_onnx']}   # sha256 "
                         f"{cfg.get('init_sha256', '?')[:12]}..., which the next stage starts from")
        net = cfg.get("structure_net")
        if net and cfg.get("structure_weight") and not any(net in line for line in lines):
            lines.append(f"python -m omninoise.training.solid.structure_features --out {net}   # the structure term's network")
        lines.append(f"python -m omninoise.training.solid.train --config {path} --out runs/solid/{cfg['name']}")
        prev = cfg["name"]
    return lines


def section(run: str, prev: dict, new: dict, shipped: bool, prev_label: str = "previous space model",
            ledger: tuple = (), config=DEFAULT_CONFIG) -> str:
    """``config``: the run's config path, or the paths of its stages oldest first (see :func:`stage_commands`)."""
    f = run_facts(run)
    cfg, step = f["config"], f["step"]
    configs = (config,) if isinstance(config, str) else tuple(config)
    n_photos = len([n for n in os.listdir(os.path.join("data", "photos", "train"))]) if os.path.isdir(
        os.path.join("data", "photos", "train")) else "?"
    ps, ns = prev["summary"], new["summary"]
    L = [BEGIN, "## Photo texture space", "",
         f"**{'Shipped as `space`; its row in the Models table above; the Gram evaluation does not score it (colour from the photo: see its own figures below)' if shipped else 'Candidate, not shipped'}.** Trained on the photo set "
         f"(`data/photos/train`, {n_photos} colour photographs from Debian's 0ad-data, ufoai-textures and "
         "supertuxkart-data; `data/photos/ATTRIBUTION.md`). **Licence of the weights: CC-BY-SA-3.0** (the "
         "training photos are CC-BY-SA-3.0, CC-BY-3.0, CC0, public domain or Expat).", "",
         "```sh", "python tools/build_photo_set.py            # the photo set from the packages (already committed)",
         *stage_commands(configs),
         *([f"python -m omninoise.training.solid.average --out {run} {' '.join(f['averaged_runs'])}   # the mean of "
            "their weights"] if f["averaged"] else []),
         f"python -m omninoise.training.solid.export {run if f['averaged'] else 'runs/solid/' + cfg['name']} models/solid/space",
         "python -m bench solid-photos --model models/solid/space", "```", "",
         f"- **Run:** {step} steps, {'the last stage at ' if f['stages'] else ''}batch {cfg['batch']} "
         f"({cfg['crop']}² crops and slices), "
         f"{f['seconds'] / 60:.1f} min wall in all stages, on {f['hardware'] or 'hardware not recorded'}"
         + (f"; final loss (median of the last ten logged) {f['loss']:.4f}." if f["loss"] is not None else
            f"; the mean of its weights at steps {' and '.join(map(str, f['averaged']))} (stochastic weight "
            "averaging, Izmailov et al. 2018: `python -m omninoise.training.solid.average`)." if f["averaged"] else
            " (read from the export; the run folder and its loss log were not kept).")
         + (f" Stopped at step {step} of its {cfg['steps']}-step cosine schedule (the session's time; "
            f"learning rate {f['lr']:.2g} at the end); `--out` the same folder resumes it."
            if step < cfg["steps"] and f["lr"] is not None else ""),
         "- **Colour from the photo:** the decoder outputs a whitened colour d and the texture is mu + L d, with "
         "the photo's mean colour mu and the Cholesky factor L of its colour covariance appended to the code z "
         f"({cfg.get('z_dim', 8) + 12 + (cfg.get('octaves', 8) if cfg.get('spectral') else 0)} values: "
         f"{cfg.get('z_dim', 8)} learned, {12 + (cfg.get('octaves', 8) if cfg.get('spectral') else 0)} measured). "
         "Refinement moves only the learned part.",
         *(["- **Spectral gains from the photo:** octave i of the noise is multiplied by g_i = sqrt(m s_i / sum s), "
            "s_i the share of the photo's luminance variance at the Haar-pyramid level that octave's lattice makes "
            "(measured crop by crop, like the colour), so a fine-grained photo gets fine-grained noise and a smooth "
            "one smooth noise without the encoder having to learn it."] if cfg.get("spectral") else []),
         *(["- **Code-modulated decoder, colour-blind encoder:** the code e modulates every hidden layer of the "
            "decoder (FiLM: h <- relu((1 + gamma(e)) (W h + b) + beta(e))), and the encoder reads each crop with "
            "its channels standardised (texture, not colour: colour is measured). The model before them mapped "
            "every photo to one texture: its decoder's output differed between photos by 1.4 % of its spread "
            "within one image."] if cfg.get("film") else []),
         "- **Loss:** sliced Wasserstein distance (Heitz et al. 2021) of random multi-scale features (5 x 5 colour "
         f"neighbourhoods and {cfg['swd_width']} zero-mean ReLU filters of sizes {cfg['swd_kernels']} on "
         f"{cfg['swd_levels']} pyramid levels) plus the sliced colour-histogram term (weight {cfg['hist_weight']})"
         + (f" plus the power-spectrum band term (weight {cfg['spectrum_weight']}; `training/solid/spectrum.py`: "
            "log shares of the luminance's power in 8 log-spaced rings x 4 orientations, each slice against "
            "its crop)" if cfg.get("spectrum_weight") else "")
         + (f" plus the learned structure term (weight {cfg['structure_weight']}: the sliced Wasserstein distance "
            "of the features of a small network trained on the photo set to tell photo crops from their "
            "random-phase twins; `training/solid/structure_features.py`)." if cfg.get("structure_weight") else "."),
         "- **Bounded octave transforms:** T_i = R_i e^{c_i} (I + S_i), S_i symmetric with eigenvalues within "
         "±0.6: stretch up to 4:1, never singular. The previous space model's transforms had singular values "
         "down to 0.0, i.e. noise extruded along a line: the diagonal streaks in all its output.", "",
         "Held-out photos (`python -m bench solid-photos`: every photo of `data/photos/val`, whole photos training "
         f"never saw; {ns['photos']} photos, 128² slices normal to x, y and z, two seeds; patch distance = sliced "
         "Wasserstein of 7 x 7 Laplacian-pyramid neighbourhoods x 1000):", "",
         f"| measure | {prev_label} | this model |", "|---|---|---|"]
    for label, key in ROWS:
        L.append(f"| {label} | {ps.get(key, '—')} | {ns.get(key, '—')} |")   # '—': a run before the measure
    if ledger:
        L += ["", "Ledger of this model's stages (oldest first; a stage ships only when the held-out evaluation "
              "says it is better):", "", "| stage | steps | wall time | median swd | ratio to random phase | "
              "beats pixel shuffle | colour error median / worst | shipped |", "|---|---|---|---|---|---|---|---|"]
        for row in ledger:
            L.append("| " + " | ".join(str(c) for c in row) + " |")
    L += ["", END]
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--run", required=True)
    ap.add_argument("--prev", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--shipped", action="store_true")
    ap.add_argument("--prev-label", default="previous space model", help="the column header of --prev")
    ap.add_argument("--ledger", help="a JSON list of rows (stage, steps, wall time, swd, ratio, beats, colour, "
                                     "shipped) for the ledger table")
    ap.add_argument("--config", action="append", help="the run's config (for the command); repeated for a run "
                                                      "continued over stages, oldest first")
    ap.add_argument("-o", "--out", default=os.path.join("runs", "cards", "solid.md"))
    a = ap.parse_args(argv)
    text = section(a.run, read_json(a.prev), read_json(a.new), a.shipped, a.prev_label,
                   tuple(read_json(a.ledger)) if a.ledger else (), a.config or [DEFAULT_CONFIG])
    with open(a.out, encoding="utf-8") as fh:
        card = fh.read()
    if BEGIN in card and END in card:
        card = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: text, card, flags=re.S)
    else:
        card = card.rstrip("\n") + "\n\n" + text + "\n"
    _ex.write_text(a.out, card)
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
