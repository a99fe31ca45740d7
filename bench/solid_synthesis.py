"""Textures by optimisation (``backend/solid/synthesis.py``, Kopf et al. 2007; Kwatra et al. 2005) on held-out photos, measured as
``python -m bench solid-photos`` measures the neural texture, beside random phase noise and the shipped model.

With ``--dim 3`` (the default), for every chosen photo of the validation split (``data/photos/val``; ``--only`` keeps names containing any of the
given words, for example ``brick,wood,rock``) a periodic tile is synthesised from the photo alone, then sliced
normal to x, y and z through ``photo_eval.SLICE_OFFSETS`` (SIZE² px at the photo's resolution, one slice per seed
and axis; a seed moves the slices through the tile as it moves the runtime's texture).  Patch distances (x 1000,
lower is better) pooled, on the walls (x and y slices) and per axis, against random phase noise drawn as often and
grouped alike (``photo_eval.grouped_swd``), and Gaussian spot noise with the photo's expected spectrum drawn alike
(``gaussian_2d``: ``photo_eval.gaussian_noise``, whose amplitudes vary per draw as a Gaussian solid's slices' do);
the same without the low-pass residue (``_band``: the band-pass levels,
where a photo's own crops are the floor) and the photo's own crops drawn as often (``photo_crop``: how close real
pieces of it come, and on how many photos even they beat random phase noise); in 3D also random phase noise as a
solid (:func:`random_phase_solid`, isotropic and upright, and per photo the closer of the two: random phase noise
drawn as a 2D image per slice has the photo's spectrum on every slice, which no solid can have on an oriented photo,
``photo_eval.axis_imbalance``, also reported); mean colour error; seconds and tile size.  With ``--against JSON`` (an
``eval_solid_photos.py`` result) the neural texture's figures for the same photos are printed beside them.  With ``--dim 2`` the tile is a 2D texture, what ``method = "synthesis"`` ships:
``--seeds`` tiles (synthesis seeds), each drawn as the product draws it (its SIZE² image at scale 1, top row first),
against as many draws of random phase noise and of the pixel shuffle (2D output, where the issue asks for it beside
slices of 3D output).

    python -m bench solid-methods [--only brick,wood,rock] [--size 128] [--planes all] [--out out/bench/solid_synthesis]

With ``--method spectral`` the 3D texture measured is instead what ``method = "spectral"`` ships
(``backend/solid/spectral_solid.py``: random phase noise lifted to a periodic solid with the photo's harmonic part,
``--no-periodic`` without it, its values mapped onto the photo's marginals, ``--no-marginals`` without that, its
power found from an isotropic start, ``--flat-start`` from flat power; one draw per photo, sliced as the tiles are;
the synthesis settings are not used).

In 3D every texture is also cut by six planes at random orientations (``photo_eval.OBLIQUE_NORMALS``, one image
each: ``oblique``, ``oblique_band``), as a mesh's faces cut it, against random phase noise's pooled draws (six as
well).

Writes OUT.json and, with ``--sheet``, OUT.png (3D: photo | x, y, z slices and the first two oblique cuts | x, y, z
slices of the closer random phase solid | random phase noise drawn in 2D; 2D: photo | the first
tile | the second (another seed) | the first repeated 2 x 2 at half size, to show it has no seams | random phase, at
the tile's size).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

from omninoise.export import read_rgb
from omninoise.export.atomic import write_json
from omninoise.backend.solid.harmonic import measure_harmonics
from omninoise.backend.solid.model import slice_points
from omninoise.backend.solid.pixels import resize_rgb
from omninoise.backend.solid.spectral_solid import ISOTROPIC_ITERATIONS, spectral_field
from omninoise.backend.solid.gaussian_rest import GaussianRest, rest_field, rest_waves, seed_shift3
from omninoise.backend.solid.upright import upright_waves
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.solid.synthesis import (PLANES, PX_PER_UNIT, SynthesisSettings, TileField, image_settings,
                                     synthesise)
from omninoise.training.solid import photo_eval as pe
from omninoise.training.solid.photo_set import photo_set

SIZE = 128
#: the Gaussian solids random phase noise is drawn as in 3D (:func:`random_phase_solid`)
SOLIDS = ("isotropic", "upright")


def slices(field: TileField, seeds: int, size: int = SIZE) -> dict:
    """{axis: [one (size, size, 3) slice per seed]} as eval_solid_photos cuts them."""
    out = {}
    for ax in "xyz":
        pts = slice_points(size, field.px_per_unit, ax, pe.SLICE_OFFSETS[ax])
        out[ax] = [field.evaluate(pts + seed_shift3(s)).reshape(size, size, 3) for s in range(seeds)]
    return out


def gaussian_solid(photo: np.ndarray, kind: str) -> tuple:
    """(the photo's mean colour float64 (3,), the runtime's Gaussian solid of the whole photo or None for a flat
    photo): ``kind`` "isotropic" (``spectral.rest_waves``) or "upright" (``upright.upright_waves``)."""
    waves = (rest_waves if kind == "isotropic" else upright_waves)(photo, PX_PER_UNIT)
    m = np.asarray(photo, np.float64).reshape(-1, 3).mean(0)
    return m, (None if waves is None else GaussianRest(waves[0], waves[1], 1.0))


def random_phase_solid(photo: np.ndarray, kind: str, seeds: int, size: int = SIZE) -> dict:
    """Random phase noise as a solid, sliced as :func:`slices` slices a tile: {axis: [one (size, size, 3) slice per
    seed]}.  The photo's mean colour plus the runtime's Gaussian solid of the whole photo (``kind`` "isotropic":
    ``spectral.rest_waves``, every cut has the photo's radial spectrum and colour correlations; "upright":
    ``upright.upright_waves``, the walls have its horizontal and vertical frequencies).  Unlike random phase noise
    drawn as a 2D image per slice, a solid can be cut this way, so it is the Gaussian baseline a solid can reach
    (``photo_eval.axis_imbalance``)."""
    m, r = gaussian_solid(photo, kind)
    if r is None:       # a flat photo
        return {ax: [np.broadcast_to(m, (size, size, 3)).astype(np.float32)] * seeds for ax in "xyz"}
    return {ax: [np.clip(m + rest_field(slice_points(size, PX_PER_UNIT, ax, pe.SLICE_OFFSETS[ax]), r, s),
                         0.0, 1.0).reshape(size, size, 3).astype(np.float32) for s in range(seeds)] for ax in "xyz"}


def measure(photo: np.ndarray, imgs: dict, rng: np.random.Generator) -> dict:
    """The grouped patch distances of the slices ({axis: images}) and of random phase noise drawn alike
    (SIZE² crops), and the colour error.  A 2D texture comes as {"x": images}: grouped_swd counts x as the walls,
    so its pooled, walls and axes figures are the same."""
    d = pe.grouped_swd(imgs, photo)
    seeds = len(imgs["x"])
    b = pe.grouped_swd({ax: [pe.random_phase(photo, SIZE, rng) for _ in range(seeds)] for ax in imgs}, photo)
    pooled = [im for v in imgs.values() for im in v]
    keys = [k for k in ("x", "y", "z", "pooled", "walls", "axes") if k in d]
    r = {k: d[k] for k in keys}
    r.update({"random_phase_" + k: b[k] for k in keys})
    r["colour"] = round(float(np.mean([pe.mean_colour_error(im, photo) for im in pooled])), 4)
    r["pixel_shuffle"] = round(pe.patch_swd([pe.pixel_shuffle(photo, SIZE, rng) for _ in pooled], photo), 1)
    # the band-pass part (no low-pass residue), and the photo's own crops drawn as often (after the
    # earlier draws, so those stay as they were): the floor of both
    crops = pe.grouped_swd({"x": [pe.photo_crop(photo, SIZE, rng) for _ in pooled]}, photo)
    r.update({"pooled_band": d["pooled_band"], "random_phase_pooled_band": b["pooled_band"],
              "photo_crop": crops["pooled"], "photo_crop_band": crops["pooled_band"]})
    # Gaussian noise with the photo's expected spectrum drawn as a 2D image per slice (spot noise: its amplitudes
    # vary per draw as a Gaussian solid's slices' do), grouped alike, after the draws above
    g2 = pe.grouped_swd({ax: [pe.gaussian_noise(photo, SIZE, rng) for _ in range(seeds)] for ax in imgs}, photo)
    r.update({"gaussian_2d_" + k: g2[k] for k in ("pooled", "walls", "pooled_band")})
    if "z" in imgs:     # 3D: the Gaussian solids a solid can be compared with, each and the closer of the two per
        # figure, and how oriented the photo is
        for kind in SOLIDS:
            g = pe.grouped_swd(random_phase_solid(photo, kind, seeds), photo)
            r.update({f"random_phase_solid_{kind}_{k}": g[k] for k in ("pooled", "walls", "axes")})
        for k in ("pooled", "walls", "axes"):
            r[f"random_phase_solid_{k}"] = min(r[f"random_phase_solid_{kind}_{k}"] for kind in SOLIDS)
        r["axis_imbalance"] = round(pe.axis_imbalance(photo), 3)
    return r


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="comma-separated words; photos whose names hold one (default: all)")
    ap.add_argument("--limit", type=int, default=0)
    ap.add_argument("--size", type=int, default=128, help="tile voxels per side")
    ap.add_argument("--dim", type=int, default=3, choices=(2, 3))
    ap.add_argument("--planes", default="all", choices=PLANES)
    ap.add_argument("--iterations", default=None, help="per level, coarse to fine (default: the product's in 2D, "
                                                       "16,6,2 in 3D); as many levels as counts")
    ap.add_argument("--sharpness", default=None, help="the weights' sharpness per level, coarse to fine (default: "
                                                     "the product's in 2D, 10 on every level in 3D)")
    ap.add_argument("--stride", type=int, default=2)
    ap.add_argument("--patch", type=int, default=SynthesisSettings.patch)
    ap.add_argument("--candidates", type=int, default=SynthesisSettings.candidates)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--photo-side", type=int, default=0, help="scale each photo to this many px (at least 128) on its "
                                                                "short side first (small photos: swatches, game textures)")
    ap.add_argument("--method", default="synthesis", choices=("synthesis", "spectral", "procedural"),
                    help="what is measured in 3D: the synthesised tile, or the spectral or procedural solid the "
                         "product draws")
    ap.add_argument("--no-marginals", action="store_true",
                    help="--method spectral: the Gaussian tile's values as drawn, not mapped onto the photo's "
                         "marginals")
    ap.add_argument("--flat-start", action="store_true",
                    help="with --method spectral: the solid's power found by EM from flat power, as before its "
                         "isotropic start (spectral_solid.solid_power)")
    ap.add_argument("--no-periodic", action="store_true",
                    help="--method spectral: without the photo's harmonic part (the product's --no-periodic)")
    ap.add_argument("--against", default=None, help="an eval_solid_photos.py JSON: the neural texture's figures")
    ap.add_argument("--sheet", action="store_true")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "solid_synthesis"))
    a = ap.parse_args(argv)
    if a.method in ("spectral", "procedural") and a.dim != 3:
        ap.error(f"--method {a.method} is measured in 3D (--dim 3): its 2D image is a slice of the same solid")
    if a.photo_side and a.photo_side < SIZE:
        ap.error(f"--photo-side must be at least {SIZE} (the measured images are {SIZE}² px)")
    words = [w for w in a.only.split(",") if w]
    files = [f for f in photo_set("val", os.path.join(ROOT, "data", "photos"))
             if not words or any(w in os.path.basename(f) for w in words)]
    files = files[:a.limit] if a.limit else files
    # 2D without --iterations and --sharpness: what the product draws from each photo (image_settings)
    product = a.dim == 2 and a.iterations is None and a.sharpness is None
    iterations = tuple(int(x) for x in a.iterations.split(",")) if a.iterations else SynthesisSettings.iterations
    settings = SynthesisSettings(size=a.size, dim=a.dim, planes=a.planes, stride=a.stride, patch=a.patch,
                                 candidates=a.candidates, levels=len(iterations), iterations=iterations,
                                 sharpness=tuple(float(x) for x in a.sharpness.split(",")) if a.sharpness
                                 else (10.0,) * len(iterations))
    neural = json.load(open(a.against))["photos"] if a.against else {}
    rows, sheet = {}, []
    print(f"{'photo':44s} {'pooled':>7s} {'rp':>7s} {'walls':>7s} {'rp':>7s} {'axes':>7s} {'rp':>7s} "
          f"{'neural':>7s} {'colour':>7s} {'s':>6s} {'solid':>7s}")
    for path in files:
        name = os.path.basename(path)
        photo = read_rgb(path)
        if a.photo_side:
            k = a.photo_side / min(photo.shape[:2])
            photo = resize_rgb(photo, max(1, round(photo.shape[0] * k)), max(1, round(photo.shape[1] * k)))
        t = time.time()
        if a.dim == 3 and a.method == "spectral":     # as the product draws it, through the request
            req = SolidRequest(exemplar=photo, method="spectral", periodic=not a.no_periodic).check()
            if a.no_marginals or a.flat_start:     # what the request draws, less the marginal map or the start
                h = measure_harmonics(photo, PX_PER_UNIT) if req.periodic else None
                field = spectral_field(photo, int(req.seed), h, marginals=not a.no_marginals,
                                       isotropic_iterations=0 if a.flat_start else ISOTROPIC_ITERATIONS)
            else:
                field = req.spectral_field()
            imgs = slices(field, a.seeds)
        elif a.dim == 3 and a.method == "procedural":     # as the product draws it, through the request
            field = SolidRequest(exemplar=photo, method="procedural").check().procedural_field()
            r_fit = dict(family=field.family)
            imgs = slices(field, a.seeds)
        elif a.dim == 3:
            field = TileField(synthesise(photo, settings), PX_PER_UNIT)
            imgs = slices(field, a.seeds)
        else:       # one tile per seed, its SIZE² image as the product draws it (top row first), grouped as x
            drawn = [image_settings(a.size, photo.shape, s) if product else dataclasses.replace(settings, seed=s)
                     for s in range(a.seeds)]
            fields = [TileField(synthesise(photo, d), PX_PER_UNIT) for d in drawn]
            imgs = {"x": [f.image(SIZE) for f in fields]}
        seconds = time.time() - t
        r = measure(photo, imgs, np.random.default_rng(0))
        r["seconds"] = round(seconds, 1)
        if a.method == "procedural":
            r.update(r_fit)
        if a.dim == 3:      # six cuts at random orientations, against random phase noise's pooled draws (six at
            # the default two seeds; python -m bench solid-photos draws six where the seeds give another count)
            obl = pe.oblique_slices(field.evaluate, field.px_per_unit)
            r["oblique"], r["oblique_band"] = pe.rounded_swds(pe.level_distances(obl, photo))
        if a.dim == 2:      # the levels drawn, and the mean colour error of whole tiles (what repeats on a surface)
            r["levels"] = drawn[0].levels
            r["colour_tile"] = round(float(np.mean([pe.mean_colour_error(f.image(a.size), photo) for f in fields])), 4)
        if name in neural:
            r["neural_pooled"], r["neural_walls"] = neural[name]["swd"], neural[name]["swd_walls"]
            r["neural_axes"] = neural[name]["swd_axes"]
        rows[name] = r
        print(f"{name[:44]:44s} {r['pooled']:7.1f} {r['random_phase_pooled']:7.1f} {r['walls']:7.1f} "
              f"{r['random_phase_walls']:7.1f} {r['axes']:7.1f} {r['random_phase_axes']:7.1f} "
              f"{r.get('neural_pooled', float('nan')):7.1f} {r['colour']:7.4f} {seconds:6.1f} "
              f"{r.get('random_phase_solid_pooled', float('nan')):7.1f}", flush=True)
        if a.sheet and a.dim == 2:  # photo | two tiles | 2 x 2 of the first at half size: no seams | random phase
            n = min(a.size, *photo.shape[:2])
            sheet.append([photo[:n, :n]] + [f.image(n) for f in fields[:2]] + [fields[0].image(n, 0.5),
                          pe.random_phase(photo, n, np.random.default_rng(1))])
        elif a.sheet:   # photo | the tile's x, y, z slices and first two oblique cuts | the closer Gaussian solid's
            # x, y, z slices | 2D random phase noise
            kind = min(SOLIDS, key=lambda k: r[f"random_phase_solid_{k}_pooled"])
            solid = random_phase_solid(photo, kind, 1)
            sheet.append([photo[:SIZE, :SIZE]] + [imgs[ax][0] for ax in "xyz"] + obl[:2]
                         + [solid[ax][0] for ax in "xyz"] + [pe.random_phase(photo, SIZE, np.random.default_rng(1))])

    def med(k):
        return round(float(np.median([r[k] for r in rows.values()])), 1)

    def beats(k):
        return int(sum(r[k] < r["random_phase_" + k] for r in rows.values()))

    summary = {"photos": len(rows), "median_seconds": med("seconds"),
               "max_colour": max((r["colour"] for r in rows.values()), default=0.0)}
    if a.dim == 2:
        summary["max_colour_tile"] = max((r["colour_tile"] for r in rows.values()), default=0.0)
    for k in ("pooled", "walls", "axes"):
        summary.update({f"median_{k}": med(k), f"median_random_phase_{k}": med("random_phase_" + k),
                        f"beats_random_phase_{k}": beats(k)})
    summary.update({"median_pooled_band": med("pooled_band"),
                    "median_random_phase_pooled_band": med("random_phase_pooled_band"),
                    "beats_random_phase_pooled_band": beats("pooled_band"),
                    "median_photo_crop": med("photo_crop"), "median_photo_crop_band": med("photo_crop_band"),
                    # how often the photo's own crops are closer than random phase noise: what the distance allows
                    "photo_crop_beats_random_phase_pooled": int(sum(r["photo_crop"] < r["random_phase_pooled"]
                                                                    for r in rows.values())),
                    "photo_crop_beats_random_phase_pooled_band": int(sum(
                        r["photo_crop_band"] < r["random_phase_pooled_band"] for r in rows.values()))})
    if a.dim == 3:      # against the better of the two Gaussian solids, photo by photo
        for k in ("pooled", "walls", "axes"):
            summary[f"median_random_phase_solid_{k}"] = med(f"random_phase_solid_{k}")
            summary[f"beats_random_phase_solid_{k}"] = int(sum(r[k] < r[f"random_phase_solid_{k}"]
                                                               for r in rows.values()))
            if neural:
                summary[f"neural_beats_random_phase_solid_{k}"] = int(sum(
                    r[f"neural_{k}"] < r[f"random_phase_solid_{k}"] for r in rows.values() if "neural_pooled" in r))
    if a.dim == 3:      # cuts at random orientations
        for k in ("", "_band"):
            summary[f"median_oblique{k}"] = med("oblique" + k)
            summary[f"beats_random_phase_oblique{k}"] = int(sum(r["oblique" + k] < r["random_phase_pooled" + k]
                                                                for r in rows.values()))
    for k in ("pooled", "walls", "pooled_band"):     # against spot noise drawn in 2D
        summary[f"median_gaussian_2d_{k}"] = med("gaussian_2d_" + k)
        summary[f"beats_gaussian_2d_{k}"] = int(sum(r[k] < r["gaussian_2d_" + k] for r in rows.values()))
    summary["beats_pixel_shuffle_pooled"] = int(sum(r["pooled"] < r["pixel_shuffle"] for r in rows.values()))
    summary["beats_random_phase_axis_slices"] = int(sum(r[ax] < r["random_phase_axes"]
                                                        for r in rows.values() for ax in "xyz" if ax in r))
    cats = {}
    for name, r in rows.items():
        c = cats.setdefault(name.split("__")[0], {"photos": 0, "beats_random_phase_pooled": 0,
                                                  "beats_random_phase_walls": 0,
                                                  "beats_random_phase_pooled_band": 0})
        c["photos"] += 1
        c["beats_random_phase_pooled_band"] += int(r["pooled_band"] < r["random_phase_pooled_band"])
        c["beats_random_phase_pooled"] += int(r["pooled"] < r["random_phase_pooled"])
        c["beats_random_phase_walls"] += int(r["walls"] < r["random_phase_walls"])
    summary["by_category"] = cats
    if neural:
        summary["beats_neural_pooled"] = int(sum(r["pooled"] < r["neural_pooled"] for r in rows.values()
                                                 if "neural_pooled" in r))
    print(json.dumps(summary))
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    write_json(a.out + ".json", {"method": a.method if a.dim == 3 else "synthesis",
                                 "periodic": not a.no_periodic if a.method == "spectral" else None,
                                 "marginals": not a.no_marginals if a.method == "spectral" else None,
                                 "isotropic_start": not a.flat_start if a.method == "spectral" else None,
                                 "settings": "the product's (image_settings; levels per photo)" if product else
                                 {k: getattr(settings, k) for k in settings.__dataclass_fields__},
                                 "px_per_unit": PX_PER_UNIT, "seeds": a.seeds, "against": a.against,
                                 "photo_side": a.photo_side or None,
                                 "summary": summary, "photos": rows})
    if sheet:
        pe.tile_sheet(sheet, a.out + ".png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
