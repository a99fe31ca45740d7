"""Single-exemplar solid textures fitted to photos, measured on pixels they never saw:
`python -m bench solid-singles [--models DIR] [--prev DIR] [-o JSON] [--sheet PNG]`.  ``--models`` is a folder of
model folders (default: the shipped ones) or a line's output (``python -m omninoise.training.line
configs/lines/solid_singles.json --out DIR``: each model in ``DIR/NAME/export``).

A single-exemplar model trained with ``hold_out`` saw only its photo's left three quarters
(``training.solid.exemplars.train_region``); the right quarter (H x W/4) is the reference here.  For each
such model, with 2 seeds of 128² images (3D models: x, y and z slices pooled, or for a model trained with
``fixed_axis`` the two slices through that axis; 2D: the plane):

- ``swd``: the patch distance of ``training.solid.photo_eval.patch_swd`` (7 x 7 neighbourhoods of a Laplacian
  pyramid, x 1000; lower is better) to the held-out strip;
- the same for what an artist could make instead from the pixels the model saw (the training region):
  random phase noise (``random_phase``), the pixel shuffle (``pixel_shuffle``) and the shipped space model
  given that region (``space``: encode with the region's harmonic part, translate, slices); ``photo_crop``: random 128² crops of the training
  region itself (the floor: the photo against its own other part).  Each alternative is scored on as many images
  as the model (fewer images would favour the model);
- ``colour``: mean colour error against the strip; ``morph``: the level-set morphology distance
  (training/solid/morphology.py), with random phase noise's beside it.

``--prev DIR`` adds the previously shipped models of the same names (``previous``: fitted to other exemplars,
scored on the same strip) and their picture.  Writes JSON (default out/bench/solid_singles.json) and, with ``--sheet``, a PNG: photo
(held-out quarter framed) | model seed 0 | seed 1 | space model | random phase | previous model.
"""
from __future__ import annotations

import argparse
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

from omninoise.export.atomic import atomic_path, write_json
from omninoise.export.images import read_rgb
from omninoise.backend.paths import solid_models
from omninoise.backend.solid.model import SolidTextureModel, load_models
from omninoise.backend.solid.pipeline import photo_code
from omninoise.training.solid import photo_eval as pe
from omninoise.training.solid.morphology import morphology_distance

SIZE = 128
SEEDS = 2


def split_photo(photo: np.ndarray) -> tuple:
    """(training region, held-out strip) of a photo (H, W, 3): its left three quarters and the rest."""
    cut = photo.shape[1] * 3 // 4
    return photo[:, :cut], photo[:, cut:]


#: the slices (normal to these axes) through a fixed axis: the planes a ``fixed_axis`` model is trained on
THROUGH_AXIS = {"rows": "xy", "columns": "yz"}


def axes_of(model: SolidTextureModel) -> str:
    """The slice axes a model is scored on: x, y and z (3D), the two through a ``fixed_axis`` model's axis, or
    "z" for a 2D model's plane."""
    fixed = model.config.get("config", {}).get("fixed_axis", "")
    return THROUGH_AXIS.get(fixed, "xyz") if model.dim == 3 else "z"


def images(model: SolidTextureModel, code, seeds: int = SEEDS, axes: str | None = None) -> list:
    """The model's 128² images: per seed, a slice normal to each of ``axes`` (default :func:`axes_of`: x, y and z
    slices for 3D, the plane for 2D).  A model trained with ``fixed_axis`` shows its photo on the planes through
    that axis only (the end grain across it is free): those two slices."""
    axes = axes or axes_of(model)
    return [model.image(SIZE, code, seed=s, axis=a, offset=pe.SLICE_OFFSETS[a]) for s in range(seeds) for a in axes]


def evaluate_model(model: SolidTextureModel, space: SolidTextureModel | None, seeds: int = SEEDS,
                   previous: SolidTextureModel | None = None) -> tuple:
    """(figures dict, pictures dict) of one single-exemplar photo model on its held-out strip; ``previous``:
    the model it replaces (fitted to another exemplar), scored on the same strip.  Every alternative is scored
    on as many images as the model (photo_eval.grouped_swd's doc: the distance falls as more images are
    pooled): baselines drawn that often, 3D models sliced on the model's axes (a 2D model's plane: a 3D
    model's front view, y)."""
    photo = read_rgb(os.path.join(ROOT, model.config["exemplars"][0]))
    train, held = split_photo(photo)
    rng = np.random.default_rng(0)
    axes = axes_of(model)
    n = seeds * len(axes)

    def like(other, code):    # n images: the model's axes (a 2D model's plane: the front view), or n planes
        if other.dim == 2:
            return images(other, code, n)
        return images(other, code, seeds, "y" if model.dim == 2 else axes)

    pics = {"photo": photo, "model": images(model, model.default_code(), seeds)}
    pics["random_phase"] = [pe.random_phase(train, SIZE, rng) for _ in range(n)]
    pics["pixel_shuffle"] = [pe.pixel_shuffle(train, SIZE, rng) for _ in range(n)]
    pics["photo_crop"] = [pe.photo_crop(train, SIZE, rng) for _ in range(n)]
    if space is not None:
        pics["space"] = like(space, photo_code(space, train).code)
    if previous is not None:
        pics["previous"] = like(previous, previous.default_code())
    r = {"photo": model.config["exemplars"][0], "dim": model.dim}
    for k in ("model", "space", "random_phase", "pixel_shuffle", "previous", "photo_crop"):
        if k in pics:
            r["swd" if k == "model" else k] = round(pe.patch_swd(pics[k], held), 1)
    r["colour"] = round(float(np.mean([pe.mean_colour_error(im, held) for im in pics["model"]])), 4)
    for k in ("space", "previous"):
        if k in pics:
            r[k + "_colour"] = round(float(np.mean([pe.mean_colour_error(im, held) for im in pics[k]])), 4)
    r["morph"] = round(morphology_distance(pics["model"], held), 3)
    r["morph_random_phase"] = round(morphology_distance(pics["random_phase"], held), 3)
    if "space" in pics:
        r["morph_space"] = round(morphology_distance(pics["space"], held), 3)
    return r, pics


def write_sheet(rows: list, path: str, size: int = 128) -> None:
    """One row per model: photo (held-out quarter framed in white) | seed 0 | seed 1 | space | random phase | previous."""
    from PIL import Image, ImageDraw

    def tile(a):
        return Image.fromarray((np.clip(a, 0, 1) * 255 + 0.5).astype(np.uint8)).resize((size, size))

    sheet = Image.new("RGB", (6 * size, len(rows) * size), (255, 255, 255))
    for i, (pics, prev) in enumerate(rows):
        per_seed = len(pics["model"]) // SEEDS
        cells = [pics["photo"], pics["model"][0], pics["model"][per_seed], pics.get("space", [None])[0],
                 pics["random_phase"][0], prev]
        for j, c in enumerate(cells):
            if c is not None:
                sheet.paste(tile(c), (j * size, i * size))
        d = ImageDraw.Draw(sheet)
        d.rectangle([size * 3 // 4, i * size, size - 1, (i + 1) * size - 1], outline=(255, 255, 255))
    with atomic_path(path) as tmp:
        sheet.save(tmp, format="PNG")


def summary(rows: dict) -> dict:
    def med(k):
        v = [r[k] for r in rows.values() if k in r]
        return round(float(np.median(v)), 3) if v else None

    beats = {k: sum(r["swd"] < r[k] for r in rows.values() if k in r)
             for k in ("space", "random_phase", "pixel_shuffle", "previous")}
    return dict(models=len(rows), median_swd=med("swd"), median_space=med("space"),
                median_random_phase=med("random_phase"), median_colour=med("colour"),
                worst_colour=max((r["colour"] for r in rows.values()), default=None),
                beats=beats)


def models_in(folder: str) -> dict:
    """{name: model} of the model folders in ``folder``, or of a training line's exports there (NAME/export)."""
    models = load_models(folder)
    if not models and os.path.isdir(folder):
        for name in sorted(os.listdir(folder)):
            if os.path.isfile(os.path.join(folder, name, "export", "solid.json")):
                models[name] = SolidTextureModel(os.path.join(folder, name, "export"))
    return models


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", default=solid_models(),
                    help="folder of solid models, or a training line's output (default: the shipped models)")
    ap.add_argument("--space", default=None,
                    help="space model folder (default: the models folder's 'space', else the shipped one)")
    ap.add_argument("--prev", default=None, help="folder of the previous models of the same names")
    ap.add_argument("--only", default="", help="comma-separated model names")
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "out", "bench", "solid_singles.json"))
    ap.add_argument("--sheet", default=None, help="write the picture here (PNG)")
    a = ap.parse_args(argv)
    models = models_in(a.models)
    places = [a.space] if a.space else [os.path.join(a.models, "space"), os.path.join(solid_models(), "space")]
    space_dir = next((d for d in places if os.path.isfile(os.path.join(d, "solid.json"))), None)
    space = SolidTextureModel(space_dir) if space_dir else None
    only = [s for s in a.only.split(",") if s]
    rows, sheet = {}, []
    for name, m in sorted(models.items()):
        if m.mode != "single" or not m.config.get("config", {}).get("hold_out") or (only and name not in only):
            continue
        prev = None
        if a.prev and os.path.isfile(os.path.join(a.prev, name, "solid.json")):
            prev = SolidTextureModel(os.path.join(a.prev, name))
        r, pics = evaluate_model(m, space, previous=prev)
        rows[name] = r
        print(name, {k: r[k] for k in ("swd", "space", "random_phase", "pixel_shuffle", "previous", "photo_crop",
                                       "colour") if k in r}, flush=True)
        sheet.append((pics, pics["previous"][-1] if "previous" in pics else None))
    if not rows:
        raise SystemExit(f"eval_solid_singles: no single-exemplar model trained with hold_out in {a.models}")
    doc = dict(rows=rows, summary=summary(rows))
    write_json(a.out, doc)
    print(doc["summary"])
    if a.sheet:
        write_sheet(sheet, a.sheet)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
