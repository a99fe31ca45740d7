"""Method "auto": a photo's procedural solid where it is closer to the photo than the neural texture, the neural
texture otherwise.

    1. fit     the procedural solid (:func:`~backend.solid.procedural.fit.fit_procedural`)
    2. encode  the neural texture's code (backend/solid/pipeline.py, as method "neural" makes it)
    3. check   both drawn on :data:`PLANES` (two cuts across each axis and six oblique, none of the fit's planes)
               and measured by the runtime's band distance (band_distance.py) as the evaluation measures them: the
               axis cuts group by group, and the oblique cuts (:func:`check_figures`); the procedural solid is kept
               only where it is closer on both figures by the margin the Gaussian rest's check asks
               (gaussian_rest.MARGIN: at most 0.92 times the neural texture's figure: one draw's distance is a noisy
               figure), so a photo it does not suit, or suits only on a cube's faces, keeps the neural texture;
               and only where its walls (the cuts across x and y) hold the photo's structure, which way it runs and
               whether it repeats as a grid (procedural/structure.py), about as well as the neural texture's do: its
               structure error at most STRUCTURE_TOLERANCE above theirs.  Patch statistics found a tile grid's irregular
               stones and a red board's cracked cells closer than the neural texture's grid and planks

Shapes: photos float32 (H, W, 3) sRGB in [0, 1].
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..progress import part, step
from .band_distance import BandReference, band_distance
from .gaussian_rest import MARGIN
from .procedural.fit import oblique_points, plane_group
from .procedural.structure import TOLERANCE as STRUCTURE_TOLERANCE, photo_structure as _photo_structure, structure_error

__all__ = ["Choice", "choose", "AutoTexture", "PLANES", "SHARES", "SIDE", "check_figures", "photo_structure",
           "wall_structure", "STRUCTURE_TOLERANCE"]

SIDE = 128     #: px per side of each plane drawn for the check
#: the check's planes (normal, a point on it), units: two across each axis and six at orientations drawn once (as a
#: cube's faces and a mesh's faces cut a solid; a solid and a neural texture differ most from cut to cut on oblique
#: ones), none of the fit's
PLANES = (((1.0, 0.0, 0.0), (4.1, -3.7, 2.9)), ((1.0, 0.0, 0.0), (-3.6, 2.2, -4.7)),
          ((0.0, 1.0, 0.0), (-3.3, 4.45, -2.6)), ((0.0, 1.0, 0.0), (2.7, -4.3, 3.5)),
          ((0.0, 0.0, 1.0), (3.6, 3.1, -4.4)), ((0.0, 0.0, 1.0), (-4.5, -2.8, 4.2)),
          ((0.45, -0.6, 0.66), (-2.9, -3.4, 3.8)), ((-0.7, 0.1, 0.7), (3.9, -2.5, -3.1)),
          ((0.93, 0.36, -0.1), (-3.48, 1.38, 3.18)), ((0.66, 0.44, 0.6), (-0.26, -0.76, -1.36)),
          ((-0.19, 0.92, -0.35), (-1.0, 0.36, 1.65)), ((-0.62, 0.52, -0.59), (3.16, 3.95, -4.38)))


def check_figures(images: list, photo) -> dict:
    """The check's figures of ``images`` (one per plane of :data:`PLANES`) against the photo (or its
    :class:`~backend.solid.band_distance.BandReference`, measuring several textures against it), as the held-out
    evaluation gives them: ``axes``, the mean of the band distances of the cuts across x, across y and across z
    (each group pooled: ``plane_group``), and ``oblique``, the band distance of the oblique cuts; rounded to 0.01."""
    groups = {}
    for img, (n, _) in zip(images, PLANES):
        groups.setdefault(plane_group(n), []).append(img)
    d = {g: band_distance(v, photo) for g, v in groups.items()}
    return {"axes": round(float(np.mean([d[g] for g in "xyz"])), 2), "oblique": round(d["oblique"], 2)}


def photo_structure(photo: np.ndarray) -> tuple:
    """(readings, lags): structure.photo_structure of the photo for the check's cuts of SIDE px."""
    return _photo_structure(photo, SIDE)


def wall_structure(images: list, structure: tuple) -> float:
    """The structure error (procedural/structure.py) of the walls among ``images`` (one per plane of :data:`PLANES`:
    the cuts across x and across y) against the photo's :func:`photo_structure`; rounded to 0.001."""
    walls = [img for img, (n, _) in zip(images, PLANES) if plane_group(n) in ("x", "y")]
    return round(structure_error(walls, *structure), 3)


@dataclass(frozen=True)
class Choice:
    """``method``: "procedural" or "neural"; ``request``: the request as that method (what a bake's key reads);
    ``field`` the procedural solid (always fitted); ``model`` and ``code`` the neural texture; ``distances``
    {method: {"axes": figure, "oblique": figure, "structure": its walls' structure error}} of the check."""
    method: str
    request: object
    field: object
    model: object
    code: object
    distances: dict

    def summary(self) -> str:
        """One line of what was kept and the check's figures that kept it (the command line says it)."""
        p, n = self.distances["procedural"], self.distances["neural"]
        kept = f"the procedural {self.field.family}" if self.method == "procedural" else "the neural texture"
        return (f"auto: kept {kept} (distance on axis and oblique cuts, structure error: procedural "
                f"{self.field.family} {p['axes']:.1f}, {p['oblique']:.1f}, {p['structure']:.2f}; neural texture "
                f"{n['axes']:.1f}, {n['oblique']:.1f}, {n['structure']:.2f})")


#: the shares of auto's progress its stages take: a fit of about 12 s, an encoding of about 3 s and a check of about
#: 2 s on 2 cores (the fit's time varies most from photo to photo)
SHARES = {"fit": 0.7, "encode": 0.15, "check": 0.15}


def choose(request, where: str = "", progress=None, report=None, on_code=None, field=None, cancel=None) -> Choice:
    """The stages (module doc) for a checked request with method "auto" and an image exemplar; ``field``: its
    procedural solid when it is fitted already (the evaluation measures it on its own too); ``progress(fraction)``
    over the three stages (:data:`SHARES`), ``cancel()`` -> True stops it between steps (raises
    :class:`~backend.grid.Cancelled`), as the fit's (:func:`~backend.solid.procedural.fit.fit_procedural`)."""
    fit_share, code_share = SHARES["fit"], SHARES["encode"]
    fitting, encoding = part(progress, 0.0, fit_share), part(progress, fit_share, code_share)
    img = np.asarray(request.exemplar_pixels(where), np.float32)     # a file is read once: every stage takes these
    proc = request.replace(method="procedural")
    if field is None:                                                                   # 1. fit
        field = dataclasses.replace(proc, exemplar=img).procedural_field(where, fitting, cancel)
    step(fitting, 1.0, cancel)
    neural = request.replace(method="neural")
    model = neural.load(where)
    named = None if report is None else (lambda _, history: report(request.exemplar, history))
    code, _ = dataclasses.replace(neural, exemplar=img).code(model, where, encoding, named, on_code,
                                                             cancel)                    # 2. encode
    step(encoding, 1.0, cancel)
    ppu = model.px_per_unit
    planes = [oblique_points(SIDE, ppu, n, o) for n, o in PLANES]                      # 3. check
    checked = part(progress, fit_share + code_share, 1.0 - fit_share - code_share)
    drawn = {"procedural": [], "neural": []}
    for i, p in enumerate(planes):
        drawn["procedural"].append(field.evaluate(p, cancel=cancel).reshape(SIDE, SIDE, 3))
        drawn["neural"].append(model.evaluate(p, code, int(request.seed), cancel=cancel).reshape(SIDE, SIDE, 3))
        step(checked, 0.4 * (i + 1) / len(planes), cancel)            # drawing the planes: 0.8 s of 2.2 s
    structure = photo_structure(img)
    ref = BandReference(img)
    d = {k: dict(check_figures(v, ref), structure=wall_structure(v, structure)) for k, v in drawn.items()}
    step(checked, 1.0, None)
    closer = (all(d["procedural"][f] <= MARGIN * d["neural"][f] for f in ("axes", "oblique"))
              and d["procedural"]["structure"] <= d["neural"]["structure"] + STRUCTURE_TOLERANCE)
    keep = "procedural" if closer else "neural"
    return Choice(keep, proc if keep == "procedural" else neural, field, model, code, d)


class AutoTexture:
    """Method "auto" seen as a texture model (what the Blender panel's preview and surface bakes call of
    :class:`~backend.solid.model.SolidTextureModel`): its "code" is the :class:`Choice`; points are drawn by the
    procedural solid or by the neural texture, whichever was chosen."""

    dim = 3
    name = "auto"

    def __init__(self, request):
        from .procedural.field import PX_PER_UNIT

        self.request = request
        self.px_per_unit = PX_PER_UNIT

    def evaluate(self, points, code: Choice, seed: int = 0, chunk: int = 1 << 16, progress=None,
                 cancel=None) -> np.ndarray:
        """points float (N, 2 or 3) in texture units -> sRGB float32 (N, 3)."""
        if code.method == "procedural":
            return code.field.evaluate(points, chunk, progress, cancel)
        return code.model.evaluate(points, code.code, seed, progress=progress, cancel=cancel)

    def image(self, size: int, code: Choice, seed: int = 0, scale: float = 1.0, offset=(0.0, 0.0, 0.0),
              axis: str = "y", **kw) -> np.ndarray:
        """A (size, size, 3) image of the plane through ``offset`` normal to ``axis`` (the front view, "y", by
        default)."""
        from .model import plane_image

        ppu = code.field.px_per_unit if code.method == "procedural" else code.model.px_per_unit
        progress = kw.pop("progress", None)
        return plane_image(lambda pts, rows: self.evaluate(pts, code, seed, **kw), size, ppu * scale, axis, offset,
                           progress)
