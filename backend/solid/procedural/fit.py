"""A photo becomes a procedural solid: the stages in order.

    1. read      the photo's pixels, at most ``fit_side`` px a side (its frequencies in texture units unchanged)
    2. estimate  its strongest wave and its spacings across and up (estimate.py)
    3. start     the starts of every kind tried (``families``: rings, layers, cells, bonds in courses by default;
                 herringbone where asked), each as it comes and textured (TEXTURED: more turbulence and detail, at
                 a higher frequency), drawn on the fit's planes and scored; a photo of one colour, which every
                 kind draws alike, gets the first kind's starts as they come and no search
    4. search    the best start of the ``finalists`` best kinds refined by Nelder-Mead (search.py) over its
                 parameters, ``budget`` calls each
    5. ramp      each finalist's colour ramp from its values over a block of space (ramp.py)
    6. tint      each finalist with no tint and with the photo's tint (tint.py) at each of tint.FREQUENCIES, drawn
                 with its ramp on the fit's planes and scored as in the search; the closest kept
    7. check     every finalist drawn on held-out planes (:data:`CHECK_PLANES`) and scored as in the search, with
                 other draws; the closest kept, unless another within :data:`STRUCTURE_MARGIN` of its distance holds
                 the photo's structure better (structure.py: its walls' structure error lower by more than
                 structure.TOLERANCE): patch statistics do not see which way a photo's courses and slabs run or
                 that they repeat, and can find a brick wall's blotches a little closer than its courses

Every score draws the slices through :data:`FIT_PLANES` (two across each axis, two oblique) with the ramp fitted
to those slices' values, and measures them by :class:`~.loss.SliceLoss` (the photo's patch statistics over a
Laplacian pyramid, each group of cuts alike; the ramp matches its colour distribution).  The settings are one frozen
:class:`ProceduralConfig`.

Shapes: photo float (H, W, 3) sRGB in [0, 1], top row first.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ...errors import SettingError
from ..model import slice_points
from ..pixels import at_most, one_colour, rgb_pixels
from .estimate import estimate
from .bonds import units_long
from .field import DEFAULT_KINDS, FAMILIES, KINDS, PX_PER_UNIT, ProceduralField
from .loss import SliceLoss
from .ramp import fit_ramp, photo_colours
from .search import minimise
from .structure import TOLERANCE, photo_structure, structure_error
from .tint import FREQUENCIES, fit_tint

__all__ = ["ProceduralConfig", "ProceduralFit", "fit_procedural", "check_photo", "MIN_SIDE", "FIT_PLANES",
           "CHECK_PLANES", "oblique_points", "plane_group", "kind_starts", "pick", "walls_structure",
           "STRUCTURE_MARGIN", "STRUCTURE_SIDE"]

MIN_SIDE = 16      #: the shortest photo side a fit reads, px
#: a start's textured twin: turbulence and detail amplitudes, and the factor on its turbulence's frequency
TEXTURED = (0.35, 0.35, 4.0)
#: what the photo measures and the search keeps, by pattern: bonds in courses keep the units' length, the courses'
#: height and shift read off the photo's autocorrelation (estimate.py); the fit's loss, patch statistics, does not
#: see which way a lattice's units line up, and moved tile grids' courses into running bonds
MEASURED = {"courses": ("length", "height", "offset")}
#: the fit's planes: (normal, a point on it), in units, two across each axis and two oblique: the loss weighs the
#: groups alike (loss.py), as the held-out evaluation weighs a cube's faces and a mesh's oblique cuts
FIT_PLANES = (((1.0, 0.0, 0.0), (0.31, 0.17, -0.4)), ((1.0, 0.0, 0.0), (-0.83, 0.6, 0.35)),
              ((0.0, 1.0, 0.0), (-0.6, 0.23, 0.5)), ((0.0, 1.0, 0.0), (0.45, -0.71, -0.2)),
              ((0.0, 0.0, 1.0), (0.2, -0.35, 0.29)), ((0.0, 0.0, 1.0), (-0.55, 0.8, -0.65)),
              ((0.6, 0.5, 0.62), (1.1, -0.9, 0.7)), ((-0.5, 0.7, 0.5), (-1.2, 0.3, -0.9)))
#: the check's planes, none of the fit's, grouped alike (three across each axis and three oblique: each shows few
#: courses or stones, so one plane's distance is a noisy figure)
CHECK_PLANES = (((1.0, 0.0, 0.0), (-1.7, 2.1, 0.9)), ((1.0, 0.0, 0.0), (2.45, -1.3, 0.2)),
                ((1.0, 0.0, 0.0), (0.77, -3.1, 2.6)), ((0.0, 1.0, 0.0), (1.3, -2.6, -1.1)),
                ((0.0, 1.0, 0.0), (-2.1, 1.85, 1.4)), ((0.0, 1.0, 0.0), (3.3, 0.9, -2.75)),
                ((0.0, 0.0, 1.0), (-0.8, 1.4, -2.3)), ((0.0, 0.0, 1.0), (2.9, -2.2, 1.15)),
                ((0.0, 0.0, 1.0), (-3.05, -0.35, -1.9)), ((-0.3, 0.8, 0.5), (2.2, 0.4, -1.6)),
                ((0.7, -0.2, 0.7), (-2.4, -1.2, 1.9)), ((0.1, -0.6, -0.8), (-0.45, 3.4, 3.1)))

#: how much farther than the closest finalist by the check's distance one that holds the photo's structure better
#: may be and still be kept in its place (stage 7), a fraction
STRUCTURE_MARGIN = 0.05
STRUCTURE_SIDE = 128    #: px per side of the check's walls (its cuts across x and y) drawn for their structure


def plane_group(normal) -> str:
    """The group of a plane for the loss (loss.py): "x", "y" or "z" for a cut across that axis, else "oblique"."""
    n = np.abs(np.asarray(normal, np.float64))
    return "xyz"[int(np.argmax(n))] if n.max() == np.linalg.norm(n) else "oblique"


@dataclass(frozen=True)
class ProceduralConfig:
    """``side`` px per slice, ``budget`` search calls per finalist, ``finalists`` kinds searched, ``seed`` of
    the solid (cells', units' and turbulence's random numbers), ``fit_side``: a larger photo is fitted at this side
    (its frequencies in texture units unchanged), ``textured``: each start's textured twin is tried too (stage 3),
    ``families``: the kinds tried (names of :data:`KINDS`; :data:`DEFAULT_KINDS` by default)."""
    side: int = 80
    budget: int = 48
    finalists: int = 2
    seed: int = 0
    fit_side: int = 256
    textured: bool = True
    families: tuple = DEFAULT_KINDS

    def __post_init__(self):
        if not self.families or any(f not in KINDS for f in self.families):
            raise SettingError("families", f"must name one or more of {', '.join(KINDS)}, got "
                                           f"{', '.join(map(str, self.families)) or 'none'}")


@dataclass(frozen=True)
class ProceduralFit:
    """The fitted ``field``; ``scores`` {kind: its check distance} of the finalists; ``tried`` the number of
    solids drawn; ``structure`` {kind: its walls' structure error} of the finalists (empty for one finalist)."""
    field: ProceduralField
    scores: dict
    tried: int
    structure: dict


def oblique_points(size: int, px_per_unit: float, normal, origin) -> np.ndarray:
    """Pixel centres of a size x size image of the plane through ``origin`` normal to ``normal`` (row 0 at the
    top): float64 (size*size, 3) in units.  Axis normals give model.slice_points' orientation."""
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    for axis, k in (("x", 0), ("y", 1), ("z", 2)):
        if abs(n[k]) == 1.0:
            return slice_points(size, px_per_unit, axis, origin)
    u = np.cross((0.0, 0.0, 1.0), n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    t = (np.arange(size) + 0.5) / px_per_unit
    vv, uu = np.meshgrid(t, t, indexing="ij")
    return np.asarray(origin, np.float64) + uu.reshape(-1, 1) * u - vv.reshape(-1, 1) * v


def _draw(family: str, params: dict, planes: np.ndarray, seed: int, colours: np.ndarray, side: int) -> tuple:
    """(slices, ramp): the solid drawn on ``planes`` (the planes' points one after the other, float (N side^2, 3):
    one call draws them all) with the ramp of those slices' values."""
    vals = FAMILIES[family].values(params, planes, seed)
    ramp = fit_ramp(vals, colours, params.get("flip", False))
    return [np.clip(ramp(v), 0.0, 1.0).reshape(side, side, 3) for v in np.split(vals, len(vals) // (side * side))], ramp


def _textured(p: dict) -> dict:
    """A start's textured twin (:data:`TEXTURED`)."""
    turb, detail, k = TEXTURED
    return dict(p, turbulence=turb, detail=detail, turb_freq=float(min(k * p["turb_freq"], 15.9)))


def _searched(fam, start: dict) -> tuple:
    """The parameters the search moves from ``start``: all of the family's but those the photo measured
    (:data:`MEASURED`)."""
    return tuple(q for q in fam.params() if q.name not in MEASURED.get(start.get("pattern"), ()))


def _pack(fam, p: dict) -> np.ndarray:
    return np.array([q.to_unit(p[q.name]) for q in _searched(fam, p)])


def _unpack(fam, x: np.ndarray, fixed: dict) -> dict:
    """The parameters at search coordinates ``x``, with the start's (``fixed``) measured and discrete settings; a
    herringbone's units keep the start's whole number of widths (its length follows its width)."""
    p = {q.name: fixed[q.name] for q in fam.params()}
    p.update({q.name: q.from_unit(u) for q, u in zip(_searched(fam, fixed), x)})
    p.update({k: v for k, v in fixed.items() if k in ("flip", "profile", "pattern")})
    if p.get("pattern", "courses") != "courses":
        p["length"] = float(np.clip(units_long(fixed) * p["height"], 0.02, 2.0))
    return p


def kind_starts(kind: str, est) -> list:
    """[(family, start parameters)] of a kind of :data:`KINDS` for the photo's estimates."""
    if kind == "herringbone":
        return [("bonds", s) for s in FAMILIES["bonds"].herringbone_starts(est)]
    return [(kind, s) for s in FAMILIES[kind].starts(est)]


def check_photo(photo: np.ndarray) -> np.ndarray:
    """The photo's RGB pixels, float (H, W, 3); SettingError naming the exemplar for one under :data:`MIN_SIDE` px
    a side (what a fit reads, checked before any work)."""
    img = rgb_pixels(photo)
    if min(img.shape[:2]) < MIN_SIDE:
        raise SettingError("exemplar", f"a procedural solid is fitted to a photo of at least {MIN_SIDE} x {MIN_SIDE} "
                                       f"px, got {img.shape[1]} x {img.shape[0]}")
    return img


def walls_structure(field: ProceduralField, ppu: float, photo: tuple) -> float:
    """The structure error (structure.py) of ``field``'s walls among :data:`CHECK_PLANES`, drawn
    :data:`STRUCTURE_SIDE` px a side at ``ppu`` px per unit, against ``photo``: the photo's
    ``photo_structure(photo pixels, STRUCTURE_SIDE)`` at that px per unit."""
    walls = [field.evaluate(oblique_points(STRUCTURE_SIDE, ppu, n, o)).reshape(STRUCTURE_SIDE, STRUCTURE_SIDE, 3)
             for n, o in CHECK_PLANES if plane_group(n) in ("x", "y")]
    return round(structure_error(walls, *photo), 3)


def pick(scores: dict, structure: dict) -> str:
    """The finalist stage 7 keeps: the closest by ``scores`` (its check distance), unless others within
    :data:`STRUCTURE_MARGIN` of it have a ``structure`` error lower than its own by more than structure.TOLERANCE;
    then the lowest of those."""
    win = min(scores, key=scores.get)
    better = [k for k in structure if scores[k] <= (1.0 + STRUCTURE_MARGIN) * scores[win]
              and structure[k] < structure[win] - TOLERANCE]
    return min(better, key=structure.get) if better else win


def fit_procedural(photo: np.ndarray, config: ProceduralConfig = ProceduralConfig(), progress=None,
                   cancel=None) -> ProceduralFit:
    """The stages (module doc) on a photo float (H, W, 3) sRGB; ``progress(fraction)`` after each solid drawn,
    ``cancel()`` returning True stops the search with the best so far."""
    img = check_photo(photo)                                                                # 1. read
    img, ppu = at_most(img, PX_PER_UNIT, config.fit_side)
    if one_colour(img):     # every kind draws it alike: nothing to search
        config = replace(config, families=config.families[:1], budget=0, finalists=1, textured=False)
    est = estimate(img, ppu)                                                                # 2. estimate
    side, seed = config.side, config.seed
    planes = np.concatenate([oblique_points(side, ppu, n, o) for n, o in FIT_PLANES])
    loss = SliceLoss(img, side, [plane_group(n) for n, _ in FIT_PLANES])
    colours = photo_colours(img)
    starts = [(kind, name, t) for kind in config.families for name, s in kind_starts(kind, est)
              for t in ((s, _textured(s)) if config.textured else (s,))]
    total = len(starts) + min(config.finalists, len(config.families)) * (config.budget + len(FREQUENCIES) + 1)
    tried = [0]

    def tick():
        tried[0] += 1
        if progress is not None:
            progress(min(1.0, tried[0] / total))

    def score(name, p):
        tick()
        return loss(_draw(name, p, planes, seed, colours, side)[0])

    def score_field(field):
        tick()
        return loss(list(field.evaluate(planes).reshape(-1, side, side, 3)))

    scored = sorted(((score(n, s), k, n, s) for k, n, s in starts), key=lambda t: t[0])    # 3. start
    best = {}
    for d, k, n, s in scored:
        best.setdefault(k, (d, n, s))
    finalists = sorted(best, key=lambda k: best[k][0])[:config.finalists]
    results = {}
    for kind in finalists:                                                                  # 4. search
        d0, name, s0 = best[kind]
        fam = FAMILIES[name]
        x, d = minimise(lambda x: score(name, _unpack(fam, x, s0)), _pack(fam, s0), 0.08, config.budget, cancel)
        results[kind] = (name, _unpack(fam, x, s0) if d < d0 else s0)
    block = np.random.default_rng(seed).uniform(-2.0, 2.0, (1 << 15, 3))                  # 5. ramp
    tint = fit_tint(img, FREQUENCIES[0], seed)        # its axis, levels and stops hold at every frequency
    tints = [None] + [replace(tint, frequency=f) for f in FREQUENCIES]
    fields = {}
    for kind, (name, p) in results.items():
        ramp = fit_ramp(FAMILIES[name].values(p, block, seed), colours, p["flip"])
        tinted = [ProceduralField(name, p, ramp, seed, PX_PER_UNIT, t) for t in tints]    # 6. tint
        fields[kind] = min(tinted, key=score_field)
    check = [oblique_points(side, ppu, n, o) for n, o in CHECK_PLANES]                    # 7. check
    held_out = SliceLoss(img, side, [plane_group(n) for n, _ in CHECK_PLANES], seed=1)
    scores = {name: round(held_out([f.evaluate(c).reshape(side, side, 3) for c in check]), 2)
              for name, f in fields.items()}
    structure = {}
    if len(fields) > 1:
        photo_walls = photo_structure(img, STRUCTURE_SIDE)
        structure = {name: walls_structure(f, ppu, photo_walls) for name, f in fields.items()}
    return ProceduralFit(fields[pick(scores, structure)], scores, tried[0], structure)
