"""Solid textures from held-out photos: ``python -m bench solid-photos [--model DIR] [--limit N] [--sheet PNG]``.

For every photo of the photo set's validation split (whole photos that
training never saw, ``data/photos/val``), the texture-space model encodes the
photo (one click in the add-on: no refinement; `--refine N` searches first) and its 3D texture is sliced
normal to x, y and z (SIZE² px at the photo's resolution, ``--seeds`` seeds).
Against the photo, per slice axis and pooled:

- ``swd``: the patch distance of :mod:`training.solid.photo_eval` (7 x 7
  Laplacian-pyramid neighbourhoods, sliced Wasserstein, x 1000), lower is better,
  beside the baselines built from the same photo (pixel shuffle, random phase
  noise, Perlin coloured by the photo's histogram) and ``photo_crop`` (random
  SIZE² crops of the photo itself: how far real pieces of it lie).  Every
  baseline is drawn as many times as the model's slices and grouped alike
  (``training.solid.photo_eval.grouped_swd``): the distance falls as more images
  are pooled, so the pooled figure meets 3 x seeds draws, walls 2 x seeds and
  each axis seeds (``random_phase_axes``, ``random_phase_walls``, and the same
  for ``photo_crop``): scoring the baselines on fewer images than the model
  would favour the model on the pooled and walls figures;
- ``morph``: the level-set morphology distance of :mod:`training.solid.morphology`
  (boundary length and Euler characteristic of quantile excursion sets: region
  sizes, outlines, connectivity), lower is better, beside random phase noise's
  (``morph_random_phase``) and the photo's crops (``morph_photo_crop``), pooled at equal counts;
- ``spectrum``: the power-spectrum band distance of :mod:`training.solid.spectrum` (log shares of the
  luminance's power in log-spaced rings x orientations; speckle, blob size, grain direction), mean over
  the slices against a SIZE² crop of the photo, lower is better, beside random phase noise's
  (``spectrum_random_phase``), which keeps the photo's Fourier modulus;
- ``colour``: mean colour error (mean over R, G, B of |difference of means|), mean over the slices
  (``colour_worst_slice``: the worst slice's);
- ``swd_axes``: the mean of the three axes' distances (``x``, ``y``, ``z``: each axis's slices alone against
  the photo), what each face of a cube shows; ``beats_random_phase_axes`` counts the axis slices (three per
  photo) closer than random phase noise's draws grouped alike (the mean of its three groups, ``random_phase_axes``).  The pooled ``swd`` mixes the three axes' neighbourhoods, so errors
  that differ between axes (fronts leaning one way, floors the other) partly cancel in it; these see them;
- ``band`` (and ``band_axes``, ``band_walls``, and per baseline ``random_phase_band`` ...): the same distance
  over the band-pass levels only (``photo_eval.band_swd``): the low-pass residue of a 128² slice is too small a
  sample of a photo's large-scale layout, and there the photo's own crops score worst; without it they are the
  floor;
- ``swd_walls``, ``colour_walls``: the same over the x and y slices only, the vertical planes on which an
  encoded photo's harmonic part stands as in the photo (on z slices, horizontal cuts, it shows in profile:
  a layered photo's horizontal cut lies within one layer, brick courses become that course's colour);
- ``oblique``, ``oblique_band``: the same distances of six cuts at random orientations
  (``photo_eval.OBLIQUE_NORMALS``, seed 0), as a mesh's faces cut the texture, beside random phase noise's six
  draws (``random_phase_oblique``);
- ``diversity``: mean absolute difference between two seeds' z slices;
- ``axis_spread``: (max - min) / mean of the three axes' swd: 0 when x, y and z
  slices are alike (a solid texture, not a 2D one extruded).

Writes the table as JSON (``-o``, default out/bench/solid_photos.json) and,
with ``--sheet``, a picture: photo | z slice | x slice | seed 2 | a cube whose
three visible faces are sampled from the 3D texture (isometric projection).

The texture is the one an artist gets: the encoded code with the photo's harmonic part
(:mod:`backend.solid.harmonic`); ``--no-periodic`` leaves the harmonic part out.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

from omninoise.export.atomic import atomic_path, write_json
from omninoise.export import read_rgb as read
from omninoise.backend.solid.model import SolidTextureModel
from omninoise.backend.solid.harmonic import HarmonicConfig
from omninoise.backend.solid.pipeline import PhotoConfig, RestCheck, photo_code
from omninoise.training.solid import photo_eval as pe
from omninoise.training.solid.photo_set import photo_set
from omninoise.training.solid.morphology import morphology_distance

SIZE = 128


def photos(split: str = "val") -> list:
    return photo_set(split, os.path.join(ROOT, "data", "photos"))


def slice_image(model: SolidTextureModel, code, axis: str, seed: int, size: int = SIZE) -> np.ndarray:
    off = pe.SLICE_OFFSETS[axis]
    return model.image(size, code, seed=seed, axis=axis, offset=off)


def cube(model: SolidTextureModel, code, seed: int = 0, n: int = 96, out: int = 192) -> np.ndarray:
    """An isometric picture (out, out, 3) of the unit-ish cube [0, s]^3 whose visible faces (x = s, y = s, z = s)
    are sampled from the 3D texture; background white."""
    s = n / model.px_per_unit
    img = np.ones((out, out, 3), np.float32)
    # isometric axes on the screen
    ex_, ey_, ez_ = np.array([0.866, 0.5]), np.array([-0.866, 0.5]), np.array([0.0, -1.0])
    scale = out / (2.2 * s)
    centre = np.array([out / 2, out / 2 + 0.1 * out])
    t = (np.arange(n) + 0.5) / n * s
    a, b = np.meshgrid(t, t, indexing="ij")
    faces = [np.stack([np.full_like(a, s), a, b], -1), np.stack([a, np.full_like(a, s), b], -1),
             np.stack([a, b, np.full_like(a, s)], -1)]
    shade = [0.8, 0.65, 1.0]
    for pts, k in zip(faces, shade):
        rgb = model.evaluate(pts.reshape(-1, 3), code, seed).reshape(n, n, 3) * k
        scr = (pts[..., 0:1] * ex_ + pts[..., 1:2] * ey_ + pts[..., 2:3] * ez_) * scale + centre
        # splat each sample over a 2 x 2 px footprint (faces are n x n samples over ~n px)
        for dy in (0, 1):
            for dx in (0, 1):
                xi = np.clip((scr[..., 0] + dx).astype(int), 0, out - 1)
                yi = np.clip((scr[..., 1] + dy).astype(int), 0, out - 1)
                img[yi, xi] = rgb
    return img


def spectrum_distance(images: list, photo: np.ndarray) -> float:
    """Mean over ``images`` (h, w, 3) of :func:`training.solid.spectrum.spectrum_loss` against the photo's
    top-left crop of the same size."""
    import torch

    from omninoise.training.solid.spectrum import spectrum_loss

    def t(a):
        return torch.from_numpy(np.ascontiguousarray(a, np.float32)).permute(2, 0, 1)[None]

    return float(np.mean([spectrum_loss(t(im), t(photo[:im.shape[0], :im.shape[1]])).item() for im in images]))


#: baselines also scored per axis and on walls (the others pooled only)
GROUPED = ("random_phase", "photo_crop")


def evaluate(model: SolidTextureModel, files: list, seeds: int = 2, sheet: list | None = None,
             config: PhotoConfig = PhotoConfig()) -> dict:
    """Every photo's code made by the pipeline's stages with ``config`` (backend/solid/pipeline.py), its x, y and z
    slices at ``seeds`` seeds, and every measure of them beside the baselines."""
    rows = {}
    for path in files:
        photo = read(path)
        rng = np.random.default_rng(0)
        t = time.time()
        code = photo_code(model, photo, config).code
        h = code.harmonics
        imgs = {ax: [slice_image(model, code, ax, s) for s in range(seeds)] for ax in "xyz"}
        seconds = time.time() - t
        d = pe.grouped_swd(imgs, photo)
        r = {ax: d[ax] for ax in "xyz"}
        r["swd_axes"], r["swd"], r["swd_walls"] = d["axes"], d["pooled"], d["walls"]
        r.update({ax + "_band": d[ax + "_band"] for ax in "xyz"})
        r["band_axes"], r["band"], r["band_walls"] = d["axes_band"], d["pooled_band"], d["walls_band"]
        pooled = [im for v in imgs.values() for im in v]
        r["colour"] = round(float(np.mean([pe.mean_colour_error(im, photo) for im in pooled])), 4)
        walls = imgs["x"] + imgs["y"]     # vertical planes: where a harmonic part stands as in the photo
        r["colour_walls"] = round(float(np.mean([pe.mean_colour_error(im, photo) for im in walls])), 4)
        r["colour_worst_slice"] = round(float(max(pe.mean_colour_error(im, photo) for im in pooled)), 4)
        r["diversity"] = round(float(np.abs(imgs["z"][0] - imgs["z"][1]).mean()), 4) if seeds > 1 else None
        ax = np.array([r["x"], r["y"], r["z"]])
        r["axis_spread"] = round(float((ax.max() - ax.min()) / max(ax.mean(), 1e-9)), 3)
        # every baseline drawn as often as the model's slices and grouped alike (photo_eval.grouped_swd)
        base = {}
        for name, fn in pe.BASELINES.items():
            base[name] = {ax: [fn(photo, SIZE, rng) for _ in range(seeds)] for ax in "xyz"}
            if name in GROUPED:
                b = pe.grouped_swd(base[name], photo)
                r[name], r[name + "_axes"], r[name + "_walls"] = b["pooled"], b["axes"], b["walls"]
                r[name + "_band"], r[name + "_band_axes"] = b["pooled_band"], b["axes_band"]
            else:
                r[name] = round(pe.patch_swd([im for v in base[name].values() for im in v], photo), 1)
            r[name + "_colour"] = round(pe.mean_colour_error(base[name]["x"][0], photo), 4)
        # six cuts at random orientations (photo_eval.OBLIQUE_NORMALS), as a mesh's faces cut the texture, against
        # as many random phase draws (the pooled ones where they are six, as at the default two seeds)
        obl = pe.oblique_slices(lambda p: model.evaluate(p, code, 0), model.px_per_unit, SIZE)
        r["oblique"], r["oblique_band"] = pe.rounded_swds(pe.level_distances(obl, photo))
        rp = [im for v in base["random_phase"].values() for im in v]
        if len(rp) == len(obl):
            r["random_phase_oblique"], r["random_phase_oblique_band"] = r["random_phase"], r["random_phase_band"]
        else:
            rp = (rp + [pe.random_phase(photo, SIZE, rng) for _ in obl])[:len(obl)]
            r["random_phase_oblique"], r["random_phase_oblique_band"] = pe.rounded_swds(
                pe.level_distances(rp, photo))
        r["morph"] = round(morphology_distance(pooled, photo), 3)
        for name in ("random_phase", "photo_crop"):
            r["morph_" + name] = round(morphology_distance([im for v in base[name].values() for im in v], photo), 3)
        r["spectrum"] = round(spectrum_distance(pooled, photo), 3)
        r["spectrum_random_phase"] = round(spectrum_distance([im for v in base["random_phase"].values() for im in v],
                                                             photo), 3)
        r["seconds"] = round(seconds, 2)
        r["harmonic_peaks"], r["harmonic_share"] = (len(h), round(h.share, 4)) if h is not None else (0, 0.0)
        r["gaussian_mix"] = code.rest.mix if code.rest is not None else 0.0
        r["gaussian_kind"] = code.rest.kind if code.rest is not None else None
        rows[os.path.basename(path)] = r
        print(os.path.basename(path), {k: r[k] for k in ("swd", "colour", "random_phase", "pixel_shuffle")},
              flush=True)
        if sheet is not None:
            sheet.append((photo, imgs, cube(model, code)))
    return rows


def summary(rows: dict) -> dict:
    """Medians over the photos and counts of photos (or axis slices) closer than a baseline; every comparison
    meets the baseline at the model's image count (pooled: all slices; walls: x and y; axes: one axis's)."""
    def med(k):
        return round(float(np.median([r[k] for r in rows.values()])), 4)

    def beats(k, b):
        return int(sum(r[k] < r[b] for r in rows.values()))

    swd = np.array([r["swd"] for r in rows.values()])
    return dict(photos=len(rows), median_swd=med("swd"), median_random_phase=med("random_phase"),
                median_pixel_shuffle=med("pixel_shuffle"), median_perlin_hist=med("perlin_hist"),
                median_photo_crop=med("photo_crop"),
                ratio_to_random_phase=round(med("swd") / med("random_phase"), 3),
                beats_pixel_shuffle=beats("swd", "pixel_shuffle"),
                beats_random_phase=beats("swd", "random_phase"),
                beats_photo_crop=beats("swd", "photo_crop"),
                median_colour=med("colour"), max_colour=round(float(max(r["colour"] for r in rows.values())), 4),
                median_swd_axes=med("swd_axes"), median_random_phase_axes=med("random_phase_axes"),
                median_photo_crop_axes=med("photo_crop_axes"),
                beats_random_phase_axes=int(sum(r[ax] < r["random_phase_axes"] for r in rows.values() for ax in "xyz")),
                median_swd_walls=med("swd_walls"), median_random_phase_walls=med("random_phase_walls"),
                median_photo_crop_walls=med("photo_crop_walls"),
                beats_random_phase_walls=beats("swd_walls", "random_phase_walls"),
                max_colour_walls=round(float(max(r["colour_walls"] for r in rows.values())), 4),
                median_diversity=med("diversity"), median_axis_spread=med("axis_spread"),
                median_seconds=med("seconds"), worst_swd=float(swd.max()),
                gaussian_rests=int(sum(r.get("gaussian_mix", 0.0) > 0 for r in rows.values())),
                upright_rests=int(sum(r.get("gaussian_kind") == "upright" for r in rows.values())),
                median_morph=med("morph"), median_morph_random_phase=med("morph_random_phase"),
                median_morph_photo_crop=med("morph_photo_crop"),
                beats_random_phase_morph=beats("morph", "morph_random_phase"),
                median_spectrum=med("spectrum"), median_spectrum_random_phase=med("spectrum_random_phase"),
                # the band-pass levels alone (photo_eval.band_swd): where the photo's own crops are the floor
                median_band=med("band"), median_band_random_phase=med("random_phase_band"),
                median_band_photo_crop=med("photo_crop_band"),
                beats_random_phase_band=beats("band", "random_phase_band"),
                beats_photo_crop_band=beats("band", "photo_crop_band"),
                median_band_axes=med("band_axes"), median_band_random_phase_axes=med("random_phase_band_axes"),
                median_band_photo_crop_axes=med("photo_crop_band_axes"),
                beats_random_phase_band_axes=int(sum(r[ax + "_band"] < r["random_phase_band_axes"]
                                                     for r in rows.values() for ax in "xyz")),
                # cuts at random orientations
                median_oblique=med("oblique"), median_oblique_band=med("oblique_band"),
                median_random_phase_oblique=med("random_phase_oblique"),
                beats_random_phase_oblique=beats("oblique", "random_phase_oblique"),
                beats_random_phase_oblique_band=beats("oblique_band", "random_phase_oblique_band"))


def by_category(rows: dict) -> dict:
    """{category (the file name's prefix before "__"): photos and medians of the model's and baselines' patch
    distances and colour error}."""
    out = {}
    for cat in sorted({name.split("__")[0] for name in rows}):
        rs = [r for name, r in rows.items() if name.split("__")[0] == cat]
        med = lambda k: round(float(np.median([r[k] for r in rs])), 1 if k != "colour" else 4)  # noqa: E731
        out[cat] = dict(photos=len(rs), swd=med("swd"), random_phase=med("random_phase"),
                        pixel_shuffle=med("pixel_shuffle"), perlin_hist=med("perlin_hist"), colour=med("colour"),
                        beats_random_phase=sum(r["swd"] < r["random_phase"] for r in rs),
                        swd_axes=med("swd_axes"), random_phase_axes=med("random_phase_axes"),
                        beats_random_phase_axes=sum(r[ax] < r["random_phase_axes"] for r in rs for ax in "xyz"),
                        band=med("band"), random_phase_band=med("random_phase_band"),
                        photo_crop_band=med("photo_crop_band"),
                        beats_random_phase_band=sum(r["band"] < r["random_phase_band"] for r in rs))
    return out


def write_sheet(sheet: list, path: str, size: int = 128) -> None:
    from PIL import Image

    rows = []
    for photo, imgs, cb in sheet:
        cells = [photo[:size, :size], imgs["z"][0], imgs["x"][0], imgs["z"][1],
                 np.asarray(Image.fromarray((cb * 255).astype(np.uint8)).resize((size, size)), np.float32) / 255]
        rows.append(np.concatenate(cells, 1))
    a = (np.clip(np.concatenate(rows, 0), 0, 1) * 255 + 0.5).astype(np.uint8)
    with atomic_path(path) as tmp:
        Image.fromarray(a).save(tmp, format="PNG")


def against(rows: dict, path: str) -> dict:
    """Per distance (``swd`` pooled, ``swd_axes``, ``swd_walls``, ``oblique`` and their ``band`` twins): the photos
    of ``rows`` more than 5 % closer and farther than in the run of this bench stored at ``path``, and both medians
    over the photos the two share."""
    with open(path, encoding="utf-8") as fh:
        other = json.load(fh)["photos"]
    common = [n for n in rows if n in other]
    out = {"photos": len(common)}
    for key in ("swd", "swd_axes", "swd_walls", "band", "band_axes", "band_walls", "oblique", "oblique_band"):
        both = [n for n in common if key in other[n]]     # runs before swd_axes lack it
        if not both:
            continue
        a, b = (np.array([r[n][key] for n in both]) for r in (other, rows))
        out[key] = dict(median_against=round(float(np.median(a)), 1), median=round(float(np.median(b)), 1),
                        closer_5pct=int((b < 0.95 * a).sum()), farther_5pct=int((b > 1.05 * a).sum()))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default=os.path.join(ROOT, "models", "solid", "space"))
    ap.add_argument("--limit", type=int, default=0, help="only every k-th photo so that about N are evaluated")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--split", default="val", choices=("val", "train"),
                    help="val (default): the held-out photos every reported figure uses; train: the photos the "
                         "model was trained on, to tell overfitting from a loss that leads away from the photos")
    ap.add_argument("--sheet", help="write a picture of (up to 8) photos and their textures")
    ap.add_argument("--no-periodic", dest="periodic", action="store_false",
                    help="leave out the photos' harmonic part (backend/solid/harmonic.py): the decoder alone")
    ap.add_argument("--no-motif", dest="motif", action="store_false",
                    help="read a photographed pattern's peaks as bins, not as its lattice's motif (harmonic.py)")
    ap.add_argument("--no-periods", dest="periods", action="store_false",
                    help="leave out the reading of a tile's few repeats (harmonic.py, periods.py)")
    ap.add_argument("--no-lines", dest="lines", action="store_false",
                    help="leave out the lines straight across the frame (harmonic.py, periods.py)")
    ap.add_argument("--no-gaussian", dest="gaussian", action="store_false",
                    help="leave out the Gaussian rest (backend/solid/gaussian_rest.py) even where its check keeps one")
    ap.add_argument("--upright-gate", type=float, metavar="G",
                    help="offer the upright Gaussian rest where a photo's spectral coherence is above G instead of "
                         "backend/solid/upright.py's UPRIGHT_GATE (0: to every photo, above 1: to none)")
    ap.add_argument("--margin", type=float, metavar="M",
                    help="keep a Gaussian rest where the check finds it M times as close as the decoder alone "
                         "instead of RestCheck's default (calibration, on the training split)")
    ap.add_argument("--check-seeds", type=int, metavar="S",
                    help="the Gaussian rest's check on x, y and z planes at S seeds instead of RestCheck's two "
                         "(calibration, on the training split)")
    ap.add_argument("--only", nargs="+", metavar="PREFIX", help="only photos whose names start so")
    ap.add_argument("--refine", type=int, default=0, metavar="N",
                    help="refine each photo's code by N search steps first (the add-on's Refine Steps)")
    ap.add_argument("--against", metavar="JSON", help="another run of this bench on the same photos: count the "
                    "photos this one is more than 5 %% closer to or farther from, pooled and on walls")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "solid_photos.json"))
    a = ap.parse_args(argv)
    changed = dict(upright_gate=a.upright_gate, margin=a.margin,
                   seeds=None if a.check_seeds is None else tuple(range(6, 6 + a.check_seeds)))
    check = RestCheck(**{k: v for k, v in changed.items() if v is not None})
    config = PhotoConfig(periodic=a.periodic, refine=a.refine, gaussian=a.gaussian, check=check,
                         harmonic=HarmonicConfig(motif=a.motif, periods=a.periods, lines=a.lines))
    model = SolidTextureModel(a.model)
    files = photos(a.split)
    if a.only:
        files = [f for f in files if os.path.basename(f).startswith(tuple(a.only))]
    if a.limit:
        files = files[::max(1, len(files) // a.limit)][:a.limit]
    sheet = [] if a.sheet else None
    rows = evaluate(model, files, a.seeds, sheet, config)
    doc = dict(model=a.model, model_sha=model.config["files"], split=a.split, size=SIZE, seeds=a.seeds,
               periodic=a.periodic, refine=a.refine, gaussian=a.gaussian, upright_gate=check.upright_gate,
               margin=check.margin, check_seeds=list(check.seeds), motif=a.motif, periods=a.periods,
               lines=a.lines,
               summary=summary(rows), by_category=by_category(rows), photos=rows)
    if a.against:
        doc["against"] = against(rows, a.against)
        print("against", a.against, doc["against"])
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    write_json(a.out, doc)
    if sheet:
        pick = sheet[:: max(1, len(sheet) // 8)][:8]
        write_sheet(pick, a.sheet)
    print(doc["summary"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
