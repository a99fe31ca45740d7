"""What each stage and reading of the solid pipeline is worth on held-out photos, each left out in turn:
``python -m bench solid-ablation [--split val] [--limit N] [-o JSON]``.

For every photo of the split the texture-space model makes the product's code (backend/solid/pipeline.py, default
PhotoConfig), and once more with each entry of :data:`VARIANTS` switched off.  A photo whose code a variant leaves
unchanged (same e, T, harmonic part and Gaussian rest) keeps its distance; the others are sliced normal to x, y and
z (128 px, two seeds) and scored by the held-out evaluation's patch distance (``python -m bench solid-photos``:
pooled x, y and z slices, and walls, the x and y slices).  Per variant: the photos it changes, how many of them
come more than 2 % closer or farther without it, the median over all photos with and without it, and the lines of
code it takes (the functions listed with it).  The decisions page (docs/decisions/solid.md) keeps the table.
"""
from __future__ import annotations

import argparse
import dataclasses
import inspect
import os
import time

import numpy as np

from omninoise.backend.solid import band_distance, gaussian_rest, harmonic, motif, periods, pipeline, upright
from omninoise.backend.solid.harmonic import HarmonicConfig
from omninoise.backend.solid.model import SolidTextureModel
from omninoise.backend.solid.pipeline import PhotoConfig, RestCheck, photo_code
from omninoise.export import read_rgb
from omninoise.export.atomic import write_json

from bench.eval_solid_photos import photos, slice_image
from bench.stamp import stamp

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: name -> (the config without it, the code it costs: the functions and modules whose lines are counted)
VARIANTS = {
    "harmonic part": (PhotoConfig(periodic=False), (harmonic, motif, periods)),
    "main lobes": (PhotoConfig(harmonic=HarmonicConfig(lobe=0)), (harmonic._main_lobes,)),
    "lattice motif": (PhotoConfig(harmonic=HarmonicConfig(motif=False)), (motif, harmonic.read_motif)),
    "few repeats": (PhotoConfig(harmonic=HarmonicConfig(periods=False)),
                    (harmonic.read_few_repeats, periods.autocorrelation, periods.translations,
                     periods.period_lattice, periods.lattice_bins, periods._dip, periods._ring_max,
                     periods._reduce)),
    "lines": (PhotoConfig(harmonic=HarmonicConfig(lines=False)),
              (harmonic.read_lines, periods.frame_lines, periods._line_profile)),
    "Gaussian rest": (PhotoConfig(gaussian=False), (gaussian_rest, band_distance, pipeline.gaussian_rest)),
    "upright rest": (PhotoConfig(check=RestCheck(upright_gate=2.0)), (upright,)),
}


def variant_code(model, photo, full, config: PhotoConfig):
    """The code without the variant's entry; ``full`` where it cannot differ (so no second encode is spent): a
    harmonic reading whose part comes out the same, no Gaussian rest (the same code less its rest), an upright rest
    not offered where the check did not choose one."""
    if config.periodic and config.harmonic != HarmonicConfig():
        h = model.harmonics(photo, config.harmonic)
        if full.harmonics is not None and np.array_equal(h.values(), full.harmonics.values()) \
                or full.harmonics is None and not len(h):
            return full
    if not config.gaussian:
        return dataclasses.replace(full, rest=None)
    if config.check != RestCheck() and (full.rest is None or full.rest.kind != "upright"):
        return full
    return photo_code(model, photo, config).code


def lines_of(objs) -> int:
    """Source lines of these functions and modules (docstrings and comments included: what a reader reads)."""
    return sum(len(inspect.getsource(o).splitlines()) for o in objs)


def same(a, b) -> bool:
    """Two texture codes draw the same texture."""
    def values(c):
        parts = [np.ravel(c.e), np.ravel(c.T), np.ravel(c.mu), np.ravel(c.L)]
        for p in (c.harmonics, c.rest):
            parts.append(np.zeros(0) if p is None else p.values())
        return parts

    va, vb = values(a), values(b)
    return all(x.shape == y.shape and np.array_equal(x, y) for x, y in zip(va, vb))


def score(model, code, photo, seeds: int) -> dict:
    from omninoise.training.solid import photo_eval as pe

    imgs = {ax: [slice_image(model, code, ax, s) for s in range(seeds)] for ax in "xyz"}
    d = pe.grouped_swd(imgs, photo)
    return dict(pooled=round(float(d["pooled"]), 2), walls=round(float(d["walls"]), 2))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("--split", default="val")
    ap.add_argument("--folder", help="every image in this folder instead of a split (a texture library's tiles)")
    ap.add_argument("--limit", type=int, default=0, help="every k-th photo, about this many")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--only", nargs="+", metavar="VARIANT", choices=tuple(VARIANTS), help="these variants alone")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "solid_ablation.json"))
    a = ap.parse_args(argv)
    model = SolidTextureModel(a.model)
    files = photos(a.split) if not a.folder else sorted(
        os.path.join(a.folder, n) for n in os.listdir(a.folder) if n.lower().endswith((".jpg", ".jpeg", ".png")))
    if a.limit:
        files = files[::max(1, len(files) // a.limit)][:a.limit]
    variants = {k: v for k, v in VARIANTS.items() if not a.only or k in a.only}
    rows, t0 = {}, time.time()
    for path in files:
        name = os.path.basename(path)
        photo = read_rgb(path)
        full = photo_code(model, photo).code
        row = {"all": score(model, full, photo, a.seeds)}
        for v, (config, _) in variants.items():
            code = variant_code(model, photo, full, config)
            row[v] = row["all"] if same(code, full) else dict(score(model, code, photo, a.seeds), changed=True)
        rows[name] = row
        print(name, {k: r["pooled"] for k, r in row.items() if k == "all" or r.get("changed")}, flush=True)
    table = {}
    for v, (config, objs) in variants.items():
        changed = [n for n, r in rows.items() if r[v].get("changed")]
        t = dict(changed=len(changed), lines=lines_of(objs))
        for key in ("pooled", "walls"):
            with_, without = (np.array([r[k][key] for r in rows.values()]) for k in ("all", v))
            t[f"median_{key}"] = round(float(np.median(with_)), 2)
            t[f"median_{key}_without"] = round(float(np.median(without)), 2)
            t[f"closer_{key}"] = int(np.sum(with_ < without / 1.02))     # photos the entry brings > 2 % closer
            t[f"farther_{key}"] = int(np.sum(with_ > without * 1.02))
        table[v] = t
        print(v, t, flush=True)
    write_json(a.out, dict(stamp=stamp(), model=os.path.relpath(a.model, ROOT),
                           split=f"folder {os.path.basename(os.path.normpath(a.folder))}" if a.folder else a.split,
                           photos=len(rows),
                           seeds=a.seeds, seconds=round(time.time() - t0), table=table, rows=rows))
    print("wrote", a.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
