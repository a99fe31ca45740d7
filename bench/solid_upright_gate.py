"""Calibrate the upright Gaussian rest's gate (backend/solid/upright.py, UPRIGHT_GATE) on photos the model was
trained on: which photos the check gives the upright rest when it is offered to every one, and how much closer or
farther each came than without it, by its spectral coherence.

    python bench/eval_solid_photos.py --split train --limit 80 --upright-gate 0 -o ALL.json
    python bench/eval_solid_photos.py --split train --limit 80 --upright-gate 2 -o BEFORE.json --only NAMES...
    python bench/solid_upright_gate.py ALL.json BEFORE.json [--coherence COH.json]

(the second run only on the photos the first gave the upright rest: ``--names ALL.json`` prints them; every
other photo's texture is the same in both runs).  Prints one row per photo (coherence, ratios new / before of the
pooled, wall, per-axis and floor distances and their band-pass twins) and, per candidate gate, how many photos
came more than 5 % closer / farther on each.  The coherence is measured as the runtime measures it (the photo's
rest after its harmonic part) and cached in ``--coherence``.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "bench"))

import numpy as np  # noqa: E402

KEYS = ("swd", "swd_walls", "swd_axes", "band", "band_walls", "band_axes", "z")
RANDOM_PHASE = {"swd": "random_phase", "swd_walls": "random_phase_walls", "band": "random_phase_band"}
GATES = (0.0, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4)


def coherences(names, split: str) -> dict:
    """{photo name: spectral coherence of its rest} as backend.solid.model.gaussian_rest gates it."""
    from eval_solid_photos import photos
    from omninoise.export import read_rgb
    from omninoise.backend.solid.harmonic import remove_harmonics
    from omninoise.backend.solid.model import SolidTextureModel, _measured
    from omninoise.backend.solid.upright import orientation

    m = SolidTextureModel(os.path.join(ROOT, "models", "solid", "space"))
    out = {}
    for path in photos(split):
        if os.path.basename(path) not in names:
            continue
        photo = read_rgb(path)
        h = m.harmonics(photo)
        img, ppu = _measured(photo, m.px_per_unit)
        left = remove_harmonics(img, h, ppu) if h is not None and len(h) else img
        out[os.path.basename(path)] = round(orientation(left)[0], 4)
    return out


def table(new: dict, old: dict, coh: dict) -> list:
    """Lines: per photo the ratios new / old, then per gate the counts closer / farther by more than 5 %."""
    names = sorted((n for n in old if n in new), key=lambda n: -coh[n])
    lines = [f"{'photo':42s} coh  kind (new/before)   " + " ".join(f"{k:>10s}" for k in KEYS)]
    for n in names:
        kinds = f"{new[n].get('gaussian_kind')}/{old[n].get('gaussian_kind')}"
        ratios = " ".join(f"{new[n][k] / old[n][k]:10.3f}" for k in KEYS)
        lines.append(f"{n[:42]:42s} {coh[n]:.2f} {kinds:20s}{ratios}")
    for g in GATES:
        sel = [n for n in names if coh[n] > g and new[n].get("gaussian_kind") == "upright"]
        line = f"gate {g:.2f}: {len(sel):2d} upright;"
        for k in KEYS:
            r = np.array([new[n][k] / old[n][k] for n in sel])
            line += f" {k} {int((r < 0.95).sum())}/{int((r > 1.05).sum())}"
        for k, b in RANDOM_PHASE.items():
            line += f"; closer than random phase ({k}) {sum(old[n][k] < old[n][b] for n in sel)} -> " \
                    f"{sum(new[n][k] < new[n][b] for n in sel)}"
        lines.append(line)
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("all", help="eval_solid_photos.py's JSON with --upright-gate 0")
    ap.add_argument("before", nargs="?", help="its JSON with --upright-gate 2 on (at least) the upright photos")
    ap.add_argument("--names", action="store_true", help="print the photos the first run gave the upright rest")
    ap.add_argument("--coherence", help="a JSON cache of the photos' coherences (read if there, else written)")
    a = ap.parse_args(argv)
    with open(a.all, encoding="utf-8") as fh:
        doc = json.load(fh)
    new = doc["photos"]
    if a.names or a.before is None:
        print(" ".join(n for n, r in new.items() if r.get("gaussian_kind") == "upright"))
        return 0
    with open(a.before, encoding="utf-8") as fh:
        old = json.load(fh)["photos"]
    if a.coherence and os.path.isfile(a.coherence):
        with open(a.coherence, encoding="utf-8") as fh:
            coh = json.load(fh)
    else:
        coh = coherences(set(new), doc.get("split", "val"))
        if a.coherence:
            from omninoise.export.atomic import write_json
            write_json(a.coherence, coh)
    print("\n".join(table(new, old, coh)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
