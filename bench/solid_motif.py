"""Photographs, not tiles: ``python bench/solid_motif.py [--split val] [--sheet] [--out PREFIX]``.

The held-out photos are game textures that tile: their periods divide their 256 px frame, and the harmonic part
(backend/solid/harmonic.py) reads them exactly from the DFT's bins.  A photograph of a brick wall is framed
anywhere.  This bench frames every photo of the split as a photograph would, by three interior crops whose sides
no period divides (224 x 232, 200 x 245 and 250 x 200 px), and wherever the motif (backend/solid/motif.py)
changes the harmonic part measured from a crop it draws the 3D texture from that crop both ways (the harmonic
part from the bins, ``motif=False``, and the shipped one), with the neural texture (the space model, as
``omninoise solid --exemplar CROP`` encodes it) and the spectral solid (``--method spectral``).  Each is scored
against the whole photo as ``bench/eval_solid_photos.py`` scores a texture: x, y and z slices at two seeds
(pooled and walls), six cuts at random orientations, patch distance x 1000 and its band-pass part; lower is
better.  Photos and crops where the motif changes nothing are counted, not drawn (the same code path: the same
texture, bit for bit).  ``--sheet`` writes PREFIX.jpg: photo crop | the x slice (a wall) of the neural texture
with the bins | with the motif | the same two of the spectral solid, one row per drawn framing (or per framing
named ``--sheet-framing``).
"""
from __future__ import annotations

import argparse
import functools
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

import omninoise.backend.solid.model as solid_model  # noqa: E402
from omninoise.backend.solid import harmonic  # noqa: E402
from omninoise.backend.solid.request import SolidRequest  # noqa: E402
from bench.eval_solid_photos import slice_image  # noqa: E402
from bench.solid_synthesis import slices  # noqa: E402
from omninoise.export import read_rgb  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.training.solid import photo_eval as pe  # noqa: E402
from omninoise.training.solid.photo_set import photo_set  # noqa: E402

SIZE = 128
#: interior crops (rows, columns) of a 256 px photo whose sides no period of a tileable 256 px texture divides
CROPS = {"224x232": (slice(8, 232), slice(8, 240)), "200x245": (slice(20, 220), slice(5, 250)),
         "250x200": (slice(3, 253), slice(30, 230))}
METHODS = ("neural", "spectral")
FIGURES = ("pooled", "walls", "band", "walls_band", "oblique", "oblique_band")


def same(a, b) -> bool:
    return len(a) == len(b) and np.array_equal(a.freq, b.freq) and np.array_equal(a.amp, b.amp)


def draw(crop: np.ndarray, method: str, motif: bool, **reading):
    """(slices {axis: [two (SIZE, SIZE, 3) images]}, six oblique cuts, seconds) of the texture drawn from ``crop``
    with the harmonic part read with or without the motif, and with ``reading``'s other arguments of
    harmonic.photo_harmonics (every reader of the part goes through model.photo_harmonics, which this sets for the
    call)."""
    saved = solid_model.photo_harmonics
    solid_model.photo_harmonics = functools.partial(harmonic.photo_harmonics, motif=motif, **reading)
    try:
        t = time.time()
        req = SolidRequest(exemplar=crop, method=method).check()
        if method == "spectral":      # cut as the synthesis bench cuts a tile, and the neural texture as its bench
            field = req.spectral_field()
            ev, ppu = field.evaluate, field.px_per_unit
            imgs = slices(field, 2, SIZE)
        else:
            model = req.load()
            code = req.code(model)[0]
            ppu = model.px_per_unit

            def ev(q):
                return model.evaluate(q, code, 0)

            imgs = {ax: [slice_image(model, code, ax, s, SIZE) for s in range(2)] for ax in "xyz"}
        return imgs, pe.oblique_slices(ev, ppu, SIZE), time.time() - t
    finally:
        solid_model.photo_harmonics = saved


def score(photo: np.ndarray, imgs: dict, obl: list) -> dict:
    d = pe.grouped_swd(imgs, photo)
    o, ob = pe.rounded_swds(pe.level_distances(obl, photo))
    return {"pooled": d["pooled"], "walls": d["walls"], "band": d["pooled_band"], "walls_band": d["walls_band"],
            "oblique": o, "oblique_band": ob,
            "colour": round(float(np.mean([pe.mean_colour_error(im, photo) for v in imgs.values() for im in v])), 4)}


def compare(rows: list, methods: list, before: str, after: str) -> dict:
    """{METHOD_FIGURE: {median_BEFORE, median_AFTER, closer, farther}}: each method's FIGURES over the rows (dicts
    holding METHOD_BEFORE and METHOD_AFTER scores), their medians and how many rows came closer or went farther."""
    out = {}
    for m in methods:
        for k in FIGURES:
            b = [r[f"{m}_{before}"][k] for r in rows]
            v = [r[f"{m}_{after}"][k] for r in rows]
            if b:
                out[f"{m}_{k}"] = {f"median_{before}": round(float(np.median(b)), 1),
                                   f"median_{after}": round(float(np.median(v)), 1),
                                   "closer": int(sum(y < x for x, y in zip(b, v))),
                                   "farther": int(sum(y > x for x, y in zip(b, v)))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--split", default="val", choices=("val", "train"))
    ap.add_argument("--only", default="", help="comma-separated words; photos whose names hold one (default: all)")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--framings", default=",".join(["whole", *CROPS]),
                    help="comma-separated: whole and the crops' names (default: all)")
    ap.add_argument("--count", action="store_true", help="only count the framings the motif changes (no drawing)")
    ap.add_argument("--sheet", action="store_true")
    ap.add_argument("--sheet-framing", default="", help="only this framing's rows on the sheet (default: every one)")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "solid_motif"))
    a = ap.parse_args(argv)
    words = [w for w in a.only.split(",") if w]
    methods = [m for m in a.methods.split(",") if m]
    files = [f for f in photo_set(a.split, os.path.join(ROOT, "data", "photos"))
             if not words or any(w in os.path.basename(f) for w in words)]
    rows, changed, unchanged, sheet = {}, [], 0, []
    crops = {k: v for k, v in {"whole": (slice(None), slice(None)), **CROPS}.items() if k in a.framings.split(",")}
    for path in files:
        name = os.path.basename(path)
        photo = read_rgb(path)
        for cname, sl in crops.items():
            crop = np.ascontiguousarray(photo[sl])
            hb = harmonic.photo_harmonics(crop, 128.0, motif=False)
            hm = harmonic.photo_harmonics(crop, 128.0)
            if same(hb, hm):
                unchanged += 1
                continue
            changed.append(f"{name}|{cname}")
            if a.count:
                print(f"{name[:40]:40s} {cname:8s} waves {len(hb):3d} -> {len(hm):3d}  share {hb.share:.2f} -> "
                      f"{hm.share:.2f}", flush=True)
                continue
            row = {"waves": [len(hb), len(hm)], "share": [round(hb.share, 3), round(hm.share, 3)]}
            pics = [crop[:SIZE, :SIZE]]
            for method in methods:
                for motif in (False, True):
                    imgs, obl, sec = draw(crop, method, motif)
                    r = score(photo, imgs, obl)
                    r["seconds"] = round(sec, 1)
                    row[f"{method}_{'motif' if motif else 'bins'}"] = r
                    pics.append(imgs["x"][0])
            rows[f"{name}|{cname}"] = row
            if not a.sheet_framing or cname == a.sheet_framing:
                sheet.append(pics)
            print(f"{name[:40]:40s} {cname:8s} waves {len(hb):3d} -> {len(hm):3d}  share {hb.share:.2f} -> "
                  f"{hm.share:.2f}  " + "  ".join(
                      f"{m}: walls {row[m + '_bins']['walls']:.1f} -> {row[m + '_motif']['walls']:.1f}, oblique "
                      f"{row[m + '_bins']['oblique']:.1f} -> {row[m + '_motif']['oblique']:.1f}, pooled "
                      f"{row[m + '_bins']['pooled']:.1f} -> {row[m + '_motif']['pooled']:.1f}" for m in methods),
                  flush=True)
    summary = {"photos": len(files), "framings": len(files) * len(crops), "unchanged": unchanged,
               "changed": len(changed), "changed_photos": len({c.split("|")[0] for c in changed})}
    summary.update(compare(list(rows.values()), methods, "bins", "motif"))
    for k, v in summary.items():
        print(k, v)
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    write_json(a.out + ".json", {"split": a.split, "crops": {k: [s[0].start, s[0].stop, s[1].start, s[1].stop]
                                                             for k, s in CROPS.items()},
                                 "summary": summary, "rows": rows})
    if a.sheet and sheet:
        pe.tile_sheet(sheet, a.out + ".jpg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
