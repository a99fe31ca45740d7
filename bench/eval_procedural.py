"""Procedural solids on held-out photos: ``python -m bench solid-procedural [--set structured|stochastic]``.

For every photo of the set, the procedural solid the product fits (method "procedural",
:mod:`backend.solid.procedural`), the neural texture the product draws by default (method "neural"), random phase
noise drawn as a solid (``bench.solid_synthesis.random_phase_solid``: the closer of the isotropic and upright
Gaussian solids, figure by figure; each one's figures are kept too) and what method "auto" delivers
(:mod:`backend.solid.choose`: the procedural solid where its own check finds it closer than the neural texture by a
margin and its walls keep the photo's structure about as well, else the neural texture) are cut by the same planes
and measured by the held-out patch distance (``training.solid.photo_eval``: 7 x 7 Laplacian-pyramid neighbourhoods,
sliced Wasserstein, x 1000; lower is better):

- ``axes``: the mean of the x, y and z cuts' distances (``photo_eval.SLICE_OFFSETS``, two seeds each, grouped as
  ``photo_eval.grouped_swd`` groups them), what each face of a cube shows;
- ``oblique``: six cuts at random orientations (``photo_eval.OBLIQUE_NORMALS``), as a mesh's faces cut the solid;
- ``axes_band`` and ``oblique_band``: the same over the band-pass levels alone (``photo_eval.band_swd``), without
  the low-pass residue, where the photo's own crops score worst;
- ``structure``: the structure error of the x and y cuts (the walls, where the photo stands) against the photo
  (``backend.solid.structure``: which way it runs, whether it repeats as a grid; lower is better), what patch
  statistics do not see: a tile grid drawn as stones is near by the patch distance and far by this.

Sets: ``structured``, the photo set's held-out brick, paving, tile and wood photos and the structured photos
(``data/structured``, ``tools/build_structured_set.py``); ``stochastic``, every ``--every``-th other held-out
photo (grass, rock, soil, sand, snow...), where "auto" is to keep the neural texture.  Writes OUT.json (per photo,
and the counts of the summary: photos where the procedural solid and "auto" are closer than random phase noise
as a solid and than the neural texture, per figure; photos where "auto" is farther than the neural texture) and,
with ``--sheet``, OUT.png: photo | neural front | procedural front, x and z cuts, per photo.  Also the seconds
each fit took on this machine, and again with numba off, as Blender's Python fits (``seconds_without_numba``;
``same_fit_without_numba``: whether that fit came out the same), and each fitted solid (``field``:
``ProceduralField.to_dict``), which the docs' sheet (``tools/procedural_sheet.py``) renders.
"""
from __future__ import annotations

import argparse
import dataclasses
import glob
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np

from bench.solid_synthesis import SOLIDS, gaussian_solid, random_phase_solid, slices
from bench.stamp import stamp
from omninoise.backend.solid.choose import STRUCTURE_TOLERANCE, photo_structure
from omninoise.backend.solid.gaussian_rest import rest_field
from omninoise.backend.solid.procedural.field import ProceduralField
from omninoise.backend.solid.request import SolidRequest
from omninoise.backend.solid.procedural.structure import structure_error
from omninoise.backend.solid.synthesis import PX_PER_UNIT
from omninoise.backend.wavenoise import fast
from omninoise.export import read_rgb
from omninoise.export.atomic import write_json
from omninoise.training.solid import photo_eval as pe
from omninoise.training.solid.photo_set import photo_set

STRUCTURED = ("brick", "paving", "tile", "wood", "marble", "rust")   #: the photo set's structured categories
SEEDS = 2
#: the figures per texture: the patch distance of the axis cuts, of all of them pooled and of the oblique cuts, and
#: the axis and oblique ones over the band-pass levels alone (``photo_eval.band_swd``)
FIGURES = ("axes", "pooled", "oblique", "axes_band", "oblique_band", "structure")


class _Field:
    """A texture as :func:`bench.solid_synthesis.slices` reads it: ``evaluate(points)``, ``px_per_unit``."""

    def __init__(self, evaluate, px_per_unit: float):
        self.evaluate, self.px_per_unit = evaluate, px_per_unit


def photos(which: str, every: int) -> list:
    val = photo_set("val", os.path.join(ROOT, "data", "photos"))
    if which == "structured":
        return [f for f in val if os.path.basename(f).split("__")[0] in STRUCTURED] + sorted(
            glob.glob(os.path.join(ROOT, "data", "structured", "*.jpg")))
    return [f for f in val if os.path.basename(f).split("__")[0] not in STRUCTURED][::every]


def _figures(axes: dict, oblique: list, photo: np.ndarray, structure: tuple) -> dict:
    """:data:`FIGURES` of a texture's axis cuts ({axis: [images]}) and oblique cuts ([images]); ``structure``:
    the photo's :func:`~backend.solid.choose.photo_structure`."""
    g = pe.grouped_swd(axes, photo)
    obl = pe.rounded_swds(pe.level_distances(oblique, photo))
    walls = axes["x"] + axes["y"]        # drawn at choose.SIDE px, as auto's check draws its walls
    return {"axes": g["axes"], "pooled": g["pooled"], "oblique": obl[0], "axes_band": g["axes_band"],
            "oblique_band": obl[1], "structure": round(structure_error(walls, *structure), 3)}


def figures(field: _Field, photo: np.ndarray, structure: tuple) -> dict:
    """:data:`FIGURES` of a texture drawn anywhere."""
    return _figures(slices(field, SEEDS), pe.oblique_slices(field.evaluate, field.px_per_unit), photo, structure)


def gaussian_field(photo: np.ndarray, kind: str) -> _Field:
    """random_phase_solid's Gaussian solid as a field (the oblique cuts read it anywhere)."""
    m, r = gaussian_solid(photo, kind)
    if r is None:
        return _Field(lambda pts: np.broadcast_to(m, (len(pts), 3)).astype(np.float32), PX_PER_UNIT)
    return _Field(lambda pts: np.clip(m + rest_field(pts, r, 0), 0.0, 1.0).astype(np.float32), PX_PER_UNIT)


def _fit_without_numba(req) -> tuple:
    """(seconds, the fitted solid's dict) of the fit again with numba off, as Blender's Python runs it (the C
    kernels where built, else numpy); (None, None) where numba is not installed (the fit just timed ran so)."""
    if not fast.numba:
        return None, None
    fast.numba = False
    try:
        t = time.time()
        field = dataclasses.replace(req, method="procedural").procedural_field()
        return round(time.time() - t, 1), field.to_dict()
    finally:
        fast.numba = True


def measure(path: str, fitted: dict | None = None) -> dict:
    """The figures of one photo; ``fitted``: its row of an earlier run, whose solid and fit seconds are taken."""
    photo = read_rgb(path)
    req = SolidRequest(exemplar=photo, method="auto").check()
    t = time.time()
    if fitted is None:
        field = dataclasses.replace(req, method="procedural").procedural_field()
        seconds = time.time() - t
        plain, again = _fit_without_numba(req)
        fd = field.to_dict()
        same = None if again is None else again == fd
    else:
        field, seconds = ProceduralField.from_dict(fitted["field"]), fitted["seconds"]
        fd = field.to_dict()
        plain, same = fitted.get("seconds_without_numba"), fitted.get("same_fit_without_numba")
    choice = req.choose(field=field)
    model, code = choice.model, choice.code
    neural = _Field(lambda pts: model.evaluate(pts, code, 0), model.px_per_unit)
    structure = photo_structure(photo)
    r = {"family": field.family, "seconds": round(seconds, 1), "seconds_without_numba": plain,
         "same_fit_without_numba": same, "chosen": choice.method, "choice_distances": choice.distances,
         "field": fd}
    for name, f in (("procedural", field), ("neural", neural)):
        r.update({f"{name}_{k}": v for k, v in figures(f, photo, structure).items()})
    # random phase as a solid: the closer kind, figure by figure, as solid-methods
    rp = [_figures(random_phase_solid(photo, kind, SEEDS),
                   pe.oblique_slices(gaussian_field(photo, kind).evaluate, PX_PER_UNIT), photo, structure)
          for kind in SOLIDS]
    for k in FIGURES:
        r[f"random_phase_solid_{k}"] = min(f[k] for f in rp)
        r.update({f"random_phase_solid_{kind}_{k}": f[k] for kind, f in zip(SOLIDS, rp)})
    for k in FIGURES:
        r[f"auto_{k}"] = r[f"{choice.method}_{k}"]
    return r, field, neural, photo


def summary(rows: dict) -> dict:
    s = {"photos": len(rows), "median_fit_seconds": round(float(np.median([r["seconds"] for r in rows.values()])), 1),
         "chosen_procedural": sum(r["chosen"] == "procedural" for r in rows.values())}
    plain = [r for r in rows.values() if r.get("seconds_without_numba") is not None]
    if plain:
        s["median_fit_seconds_without_numba"] = round(float(np.median([r["seconds_without_numba"] for r in plain])), 1)
        s["same_fit_without_numba"] = sum(bool(r["same_fit_without_numba"]) for r in plain)
    for who in ("procedural", "auto"):
        for k in ("axes", "oblique", "axes_band", "oblique_band"):
            s[f"{who}_beats_random_phase_solid_{k}"] = sum(r[f"{who}_{k}"] < r[f"random_phase_solid_{k}"]
                                                          for r in rows.values())
            for kind in SOLIDS:     # each Gaussian solid alone
                s[f"{who}_beats_random_phase_solid_{kind}_{k}"] = sum(
                    r[f"{who}_{k}"] < r[f"random_phase_solid_{kind}_{k}"] for r in rows.values())
            s[f"{who}_beats_neural_{k}"] = sum(r[f"{who}_{k}"] < r[f"neural_{k}"] for r in rows.values())
            s[f"{who}_farther_than_neural_{k}"] = sum(r[f"{who}_{k}"] > r[f"neural_{k}"] for r in rows.values())
    for k in ("axes", "oblique", "axes_band", "oblique_band"):
        s[f"neural_beats_random_phase_solid_{k}"] = sum(r[f"neural_{k}"] < r[f"random_phase_solid_{k}"]
                                                        for r in rows.values())
        for who in ("procedural", "neural", "random_phase_solid", "auto"):
            s[f"median_{who}_{k}"] = round(float(np.median([r[f"{who}_{k}"] for r in rows.values()])), 1)
    for who in ("procedural", "neural", "random_phase_solid", "auto"):
        s[f"median_{who}_structure"] = round(float(np.median([r[f"{who}_structure"] for r in rows.values()])), 3)
    for who in ("procedural", "auto", "random_phase_solid"):     # loses the structure the neural texture keeps
        s[f"{who}_structure_farther_than_neural"] = sum(
            r[f"{who}_structure"] > r["neural_structure"] + STRUCTURE_TOLERANCE for r in rows.values())
    s["families"] = {f: sum(r["family"] == f for r in rows.values()) for f in sorted({r["family"] for r in rows.values()})}
    return s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", default="structured", choices=("structured", "stochastic"))
    ap.add_argument("--every", type=int, default=3, help="stochastic: every N-th photo")
    ap.add_argument("--limit", type=int, default=0)
    ap.add_argument("--sheet", action="store_true")
    ap.add_argument("--fields", default=None, help="an earlier run's JSON: measure its fitted solids (and keep its fit "
                                                  "seconds) instead of fitting, as when auto's check changes")
    ap.add_argument("-o", "--out", default=None, help="default: out/bench/solid_procedural_SET")
    a = ap.parse_args(argv)
    fitted = {}
    if a.fields:
        import json

        with open(a.fields) as f:
            fitted = json.load(f)["photos"]
    out = a.out or os.path.join(ROOT, "out", "bench", f"solid_procedural_{a.set}")
    files = photos(a.set, a.every)
    files = files[:a.limit] if a.limit else files
    rows, sheet = {}, []
    print(f"{'photo':40s} {'family':7s} {'chosen':10s} {'proc':>6s} {'neural':>6s} {'rp':>6s}  (axes)  "
          f"{'proc':>6s} {'neural':>6s} {'rp':>6s}  (oblique)   s")
    for path in files:
        name = os.path.basename(path)
        r, field, neural, photo = measure(path, fitted.get(name))
        rows[name] = r
        print(f"{name[:40]:40s} {r['family']:7s} {r['chosen']:10s} {r['procedural_axes']:6.1f} {r['neural_axes']:6.1f} "
              f"{r['random_phase_solid_axes']:6.1f}          {r['procedural_oblique']:6.1f} {r['neural_oblique']:6.1f} "
              f"{r['random_phase_solid_oblique']:6.1f}  {r['seconds']:5.1f}", flush=True)
        if a.sheet:
            from omninoise.backend.solid.model import slice_points

            cut = [neural.evaluate(slice_points(128, PX_PER_UNIT, "y", (0.0, 0.37, 0.0))).reshape(128, 128, 3)]
            cut += [field.evaluate(slice_points(128, PX_PER_UNIT, ax, o)).reshape(128, 128, 3)
                    for ax, o in (("y", (0.0, 0.37, 0.0)), ("x", (0.37, 0.0, 0.0)), ("z", (0.0, 0.0, 0.37)))]
            sheet.append(np.concatenate([photo[:128, :128]] + cut, 1))
    s = summary(rows)
    print(s)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    write_json(out + ".json", {"stamp": stamp(), "set": a.set, "seeds": SEEDS, "summary": s, "photos": rows})
    if a.sheet and sheet:
        from omninoise.export.images import write_png

        write_png(out + ".png", np.round(np.concatenate(sheet, 0) * 255).astype(np.uint8))
    return 0


if __name__ == "__main__":
    sys.exit(main())
