"""How the harmonic part's peak test was chosen: ``python bench/eval_solid_harmonic.py [-o JSON]``.

On photos of the *training* split (every structured one: brick, wood, fabric, metal, concrete, marble, rust;
and every sixth of the rest), the texture-space model encodes each photo and its 3D texture is sliced as
``bench/eval_solid_photos.py`` slices it, without the harmonic part and with it under each peak test
(:func:`backend.solid.harmonic.photo_harmonics`: ``prominence`` over the mean power of a ``window`` ring).
Per setting: the median patch distance, the photos where it beats random phase noise, and the photos it makes
more than 5 % better or worse than the decoder alone, for structured photos and the rest.

Placements (how the photo's plane stands in 3D) are compared under the shipped peak test: ``wall`` (shipped,
q = (x + y, z)), ``floor`` (q = (x, y + z): the photo on planes normal to z and to y) and ``each`` (per wave,
whichever of the two leaves the profile its smaller frequency component).  For these the decoder-only slices are
recombined here as the model does (mu + k (rgb - mu) + h), with the decoder-only texture's clipping to [0, 1]
kept; ``wall`` is also reported through the model, to show the difference is small.

Peak counts: on every training photo where more than ``COUNTS[0]`` peaks pass the shipped test (the cap
``COUNT`` binds only there), the patch distance of the pooled slices and of the walls (x and y slices) under each
cap in ``COUNTS`` ("counts" in the JSON).  Main lobes: on every training photo with a harmonic part, the same two
distances with each peak's bin alone (lobe 0) and with the bins around it (``LOBES``; "lobes" in the JSON).  Spectra:
on every training photo with a part, the same with peaks sought in the luminance's or the colour power spectrum
("detect"; ``--only detect`` runs it alone).  The held-out photos
play no part: the constants in ``backend/solid/harmonic.py`` come from this table, and the held-out figures in
the README from ``bench/eval_solid_photos.py``.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from omninoise.backend.solid.harmonic import DETECTS, Harmonics, harmonic_field, photo_harmonics  # noqa: E402
from omninoise.backend.solid.model import SolidTextureModel, slice_points  # noqa: E402
from bench.eval_solid_photos import SIZE, photos, read, slice_image  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.training.solid import photo_eval as pe  # noqa: E402

STRUCTURED = ("brick", "wood", "fabric", "metal", "concrete", "marble", "rust")
SETTINGS = [(p, w) for w in (3, 5) for p in (4.0, 8.0, 16.0, 32.0)]
PLACEMENTS = ("wall", "floor", "each")
COUNTS = (32, 64, 128, 256, 512)
LOBES = (0, 1, 2)


def placed(h: Harmonics, pts: np.ndarray, placement: str, seed: int) -> np.ndarray:
    """h at 3D points under another placement, through the shipped field and its seed shift: the points
    (x, 0, y + z) give q = (x, y + z)."""
    if placement == "wall":
        return harmonic_field(pts, h, seed)
    floor = np.stack([pts[:, 0], np.zeros(len(pts)), pts[:, 1] + pts[:, 2]], 1)
    if placement == "floor":
        return harmonic_field(floor, h, seed)
    fx, fy = np.abs(h.freq[:, 0]), np.abs(h.freq[:, 1])
    a, b = fx <= fy, fx > fy      # "wall" leaves fx in the profile, "floor" fy
    out = np.zeros((len(pts), 3), np.float32)
    for sel, p in ((a, pts), (b, floor)):
        if sel.any():
            out += harmonic_field(p, Harmonics(h.freq[sel], h.amp[sel], h.share), seed)
    return out


def study(model: SolidTextureModel, paths: list, variants: dict, include) -> dict:
    """Per photo (of ``paths``) for which ``include(photo)`` holds: per variant (name -> keyword arguments of
    photo_harmonics), the waves kept, their share, and the patch distance of the pooled slices and of the walls."""
    rows = {}
    for path in paths:
        photo = read(path)
        if not include(photo):
            continue
        z, r = model.encode(photo), {}
        for name, kw in variants.items():
            h = photo_harmonics(photo, model.px_per_unit, **kw)
            code = model.translate(z, h)
            imgs = {ax: [slice_image(model, code, ax, s) for s in range(2)] for ax in "xyz"}
            r[name] = dict(waves=len(h), share=round(h.share, 3),
                           pooled=round(pe.patch_swd([i for v in imgs.values() for i in v], photo), 1),
                           walls=round(pe.patch_swd(imgs["x"] + imgs["y"], photo), 1))
        rows[os.path.basename(path)] = r
        print(os.path.basename(path), r, flush=True)
    return rows


def count_study(model: SolidTextureModel, paths: list) -> dict:
    """:func:`study` of the caps in COUNTS, each peak its own bin alone (as when the cap was chosen), on the photos
    whose peak test passes more than COUNTS[0] peaks."""
    return study(model, paths, {str(c): dict(count=c, lobe=0) for c in COUNTS},
                 lambda photo: len(photo_harmonics(photo, model.px_per_unit, count=max(COUNTS) + 1, lobe=0))
                 > COUNTS[0])


def lobe_study(model: SolidTextureModel, paths: list) -> dict:
    """:func:`study` of the lobe widths in LOBES on the photos with a harmonic part."""
    return study(model, paths, {str(w): dict(lobe=w) for w in LOBES},
                 lambda photo: len(photo_harmonics(photo, model.px_per_unit, lobe=0)) > 0)


def detect_study(model: SolidTextureModel, paths: list) -> dict:
    """:func:`study` of the spectra peaks are sought in (``DETECTS``: the luminance's power, the sum of the three
    channels' powers) on the photos with a harmonic part under either."""
    return study(model, paths, {d: dict(detect=d) for d in DETECTS},
                 lambda photo: any(len(photo_harmonics(photo, model.px_per_unit, detect=d)) for d in DETECTS))


def paired_summary(rows: dict, base: str, other: str) -> dict:
    """Per distance (pooled, walls): the medians under ``base`` and ``other`` and the photos ``other`` makes more
    than 5 % closer or farther than ``base``."""
    out = {}
    for key in ("pooled", "walls"):
        pairs = [(r[base][key], r[other][key]) for r in rows.values()]
        out[f"{other}/{key}"] = dict(
            median_base=round(float(np.median([p[0] for p in pairs])), 1),
            median=round(float(np.median([p[1] for p in pairs])), 1),
            better_5pct=int(sum(b < 0.95 * a for a, b in pairs)), worse_5pct=int(sum(b > 1.05 * a for a, b in pairs)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "solid_harmonic.json"))
    ap.add_argument("--only", choices=("detect",),
                    help="run this study alone (its JSON holds it alone): detect, the spectrum peaks are sought in")
    a = ap.parse_args(argv)
    model = SolidTextureModel(a.model)
    if model.harmonic_rest:
        ap.error(f"{a.model} was trained on photos' rests: its code depends on the part, and this bench encodes each "
                 "photo once for every peak test (use a model trained on whole photos)")
    if a.only == "detect":
        t0 = time.time()
        rows = detect_study(model, photos("train"))
        doc = dict(model=a.model, split="train", seconds=round(time.time() - t0), detect=rows,
                   detect_summary=paired_summary(rows, "luminance", "colour"))
        write_json(a.out, doc)
        print("detect", doc["detect_summary"])
        return 0
    files = [f for i, f in enumerate(photos("train"))
             if os.path.basename(f).startswith(STRUCTURED) or i % 6 == 0]
    rows, t0 = {}, time.time()
    for path in files:
        photo, rng = read(path), np.random.default_rng(0)
        z = model.encode(photo)

        def swd(h):
            code = model.translate(z, h)
            return pe.patch_swd([slice_image(model, code, ax, s) for ax in "xyz" for s in range(2)], photo)

        rp = [pe.random_phase(photo, SIZE, rng) for _ in range(6)]     # as many images as swd's six slices
        r = dict(model=swd(None), random_phase=pe.patch_swd(rp, photo))
        for p, w in SETTINGS:
            h = photo_harmonics(photo, model.px_per_unit, prominence=p, window=w)
            r[f"{p:g}/{w}"] = swd(h) if len(h) else r["model"]
        h = model.harmonics(photo)
        code = model.translate(z)
        mu = code.mu
        for placement in PLACEMENTS:
            if not len(h):
                r[placement] = r["model"]
                continue
            imgs = []
            for ax in "xyz":
                pts = slice_points(SIZE, model.px_per_unit, ax, pe.SLICE_OFFSETS[ax])
                for s in range(2):
                    rgb = model.evaluate(pts, code, s)
                    imgs.append(np.clip(mu + h.keep * (rgb - mu) + placed(h, pts, placement, s), 0, 1)
                                .reshape(SIZE, SIZE, 3))
            r[placement] = pe.patch_swd(imgs, photo)
        rows[os.path.basename(path)] = {k: round(float(v), 1) for k, v in r.items()}
        print(os.path.basename(path), rows[os.path.basename(path)], flush=True)
    summary = {}
    for group, keep in (("structured", lambda n: n.startswith(STRUCTURED)),
                        ("other", lambda n: not n.startswith(STRUCTURED))):
        rs = [r for n, r in rows.items() if keep(n)]
        summary[group] = {k: dict(median=round(float(np.median([r[k] for r in rs])), 1),
                                  beats_random_phase=int(sum(r[k] < r["random_phase"] for r in rs)),
                                  better_5pct=int(sum(r[k] < 0.95 * r["model"] for r in rs)),
                                  worse_5pct=int(sum(r[k] > 1.05 * r["model"] for r in rs)))
                          for k in ["model"] + [f"{p:g}/{w}" for p, w in SETTINGS] + list(PLACEMENTS)}
        summary[group]["photos"] = len(rs)
    counts, lobes = count_study(model, photos("train")), lobe_study(model, photos("train"))
    lobe_summary = {}
    for lobe in LOBES[1:]:
        lobe_summary.update(paired_summary(lobes, "0", str(lobe)))
    detect = detect_study(model, photos("train"))
    doc = dict(model=a.model, split="train", settings="prominence/window", placements=PLACEMENTS,
               seconds=round(time.time() - t0),
               summary=summary, photos=rows, counts=counts, lobes=lobes, lobe_summary=lobe_summary,
               detect=detect, detect_summary=paired_summary(detect, "luminance", "colour"))
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    write_json(a.out, doc)
    print("lobes", lobe_summary)
    print("detect", doc["detect_summary"])
    for group, s in summary.items():
        print(group, s.pop("photos"), "photos")
        for k, v in s.items():
            print(f"  {k:8s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
