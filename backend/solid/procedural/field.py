"""A fitted procedural solid as a colour field over texture space: a family, its parameters, the ramp, the tint
(tint.py; none where the fit found the photo closer without) and the seed, evaluated anywhere (it does not
repeat), and written to and read from JSON (a bake's key, the node group's inputs).

Shapes: points float (P, 2 or 3) in texture units (2D points lie on z = 0) -> float32 (P, 3) sRGB in [0, 1].
"""
from __future__ import annotations

import numpy as np

from ...errors import SettingError, check_points
from ...grid import Cancelled
from .bonds import PATTERNS, Bonds
from .cells import Cells
from .family import MAX_PARAM
from .layers import PROFILES, Layers
from .ramp import Ramp
from .rings import Rings
from .tint import Tint

__all__ = ["FAMILIES", "ProceduralField", "PX_PER_UNIT", "KINDS", "DEFAULT_KINDS"]

PX_PER_UNIT = 128.0    #: photo pixels per texture unit, as the other image methods read a photo

#: the families by name
FAMILIES = {f.name: f for f in (Rings(), Layers(), Cells(), Bonds())}
#: what a fit can try (its ``families`` setting): each family, and "herringbone", bonds laid in herringbones
KINDS = (*FAMILIES, "herringbone")
#: what a fit tries unless asked: every family, bonds in courses.  A herringbone is closer under the fit's loss than
#: courses on a running-bond wall whose courses it does not draw, so it is tried where asked
DEFAULT_KINDS = tuple(FAMILIES)


class ProceduralField:
    """``family`` (a name of :data:`FAMILIES`), ``params`` (its parameters, with ``flip``, for layers
    ``profile`` and for bonds ``pattern``, "courses" where it is absent), ``ramp`` (:class:`~.ramp.Ramp`) and
    ``seed``; ``px_per_unit`` the photo's pixels per unit; ``tint`` (:class:`~.tint.Tint`) or None."""

    dim = 3

    def __init__(self, family: str, params: dict, ramp: Ramp, seed: int = 0, px_per_unit: float = PX_PER_UNIT,
                 tint: Tint | None = None):
        if family not in FAMILIES:
            raise SettingError("family", f"unknown procedural family {family!r}; known: {', '.join(FAMILIES)}")
        fam = FAMILIES[family]
        try:
            p = fam.check(params)
        except ValueError as exc:
            raise SettingError("params", str(exc)) from None
        p["flip"] = bool(params.get("flip", False))
        if family == "layers":
            if params.get("profile") not in PROFILES:
                raise SettingError("params", f"layers: profile must be one of {', '.join(PROFILES)}")
            p["profile"] = params["profile"]
        if family == "bonds":
            if params.get("pattern", "courses") not in PATTERNS:
                raise SettingError("params", f"bonds: pattern must be one of {', '.join(PATTERNS)}")
            p["pattern"] = params.get("pattern", "courses")
        self.family, self.params, self.ramp, self.seed = family, p, ramp, int(seed)
        self.px_per_unit = float(px_per_unit)
        if tint is not None and not (np.isfinite(tint.frequency) and 0 < tint.frequency <= MAX_PARAM):
            raise SettingError("tint", f"the tint's frequency must be a positive number up to {MAX_PARAM:g}, got "
                                       f"{tint.frequency!r}")
        self.tint = tint

    def values(self, points: np.ndarray) -> np.ndarray:
        """The family's value s at points float (P, 3) -> float64 (P,)."""
        return FAMILIES[self.family].values(self.params, points, self.seed)

    def gaps(self, points: np.ndarray) -> np.ndarray:
        """The gap mask of cells and bonds at points float (P, 3) -> float64 (P,): 1 in the gaps and joints, 0
        inside the cells and units, linear between (the node group's Gap Mask: into a Bump node's Height with
        Invert on, the mortar sinks).  Rings and layers have no gaps (SettingError)."""
        fam = FAMILIES[self.family]
        if not fam.GAPPED:
            raise SettingError("family", f"{self.family} have no gaps: a gap mask is drawn for "
                                         f"{', '.join(n for n, f in FAMILIES.items() if f.GAPPED)}")
        return fam.gaps(self.params, check_points(points, (3,), np.float64), self.seed)

    def colours(self, points: np.ndarray) -> np.ndarray:
        """The ramp's colours at points float (P, 3), plus the tint's offsets, before the clip -> float32 (P, 3)."""
        c = self.ramp(self.values(points))
        return c if self.tint is None else c + self.tint(points, self.seed)

    def evaluate(self, points: np.ndarray, chunk: int = 1 << 16, progress=None, cancel=None) -> np.ndarray:
        """points float (P, 2 or 3) -> float32 (P, 3), in chunks: ``progress(fraction)`` after each, ``cancel()``
        returning True raises Cancelled."""
        pts = check_points(points, (2, 3), np.float64)
        if pts.shape[1] == 2:
            pts = np.concatenate([pts, np.zeros((len(pts), 1))], axis=1)
        out = np.empty((len(pts), 3), np.float32)
        for a in range(0, len(pts), chunk):
            if cancel is not None and cancel():
                raise Cancelled("cancelled")
            out[a:a + chunk] = self.colours(pts[a:a + chunk])
            if progress is not None:
                progress(min(1.0, (a + chunk) / len(pts)))
        return np.clip(out, 0.0, 1.0)

    def image(self, size: int, scale: float = 1.0, axis: str = "y", offset=(0.0, 0.0, 0.0)) -> np.ndarray:
        """A (size, size, 3) image of the plane through ``offset`` normal to ``axis`` ("y": the front view, x right
        and z up) at ``scale`` output pixels per photo pixel."""
        from ..model import plane_image

        return plane_image(lambda pts, rows: self.evaluate(pts), size, self.px_per_unit * scale, axis, offset)

    def to_dict(self) -> dict:
        d = dict(family=self.family, params=dict(self.params), ramp=self.ramp.to_dict(), seed=self.seed,
                 px_per_unit=self.px_per_unit)
        return d if self.tint is None else dict(d, tint=self.tint.to_dict())

    @staticmethod
    def from_dict(d: dict) -> "ProceduralField":
        tint = Tint.from_dict(d["tint"]) if d.get("tint") else None
        return ProceduralField(d["family"], d["params"], Ramp.from_dict(d["ramp"]), d.get("seed", 0),
                               d.get("px_per_unit", PX_PER_UNIT), tint)
