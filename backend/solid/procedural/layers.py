"""Layers: a colour profile along a warped coordinate (Perlin 1985's marble; sandstone strata, straight grain).

The value is the height along a normal n in layer spacings, bent by turbulence, read through a profile:

    h = p . n / spacing + turbulence * T(p),    s = frac(h) (profile "saw") or |2 frac(h) - 1| (profile "tri")

A saw rises through a layer and drops at its edge (strata, a board's rings seen edge on); a triangle rises and
falls (marble's veins, ``sin(x + turbulence)`` up to the ramp, which reads any monotone profile alike).
"""
from __future__ import annotations

import numpy as np

from .family import Family, Param, axis_vector, dot3
from .turbulence import turbulence

__all__ = ["Layers", "PROFILES"]

PROFILES = ("saw", "tri")


class Layers(Family):
    name = "layers"
    doc = "a profile along a warped coordinate: veins, strata, straight grain"
    PARAMS = (Param("spacing", 0.005, 2.0, log=True, doc="distance between layers, units"),
              Param("tilt", 0.0, np.pi, doc="the layers' normal's angle from +z, radians", floor=False),
              Param("azimuth", 0.0, np.pi, doc="the normal's turn about z from +x, radians", floor=False))

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        pts = np.asarray(points, np.float64)
        h = dot3(pts, axis_vector(p["tilt"], p["azimuth"])) / p["spacing"]
        if p["turbulence"] > 0:
            h += p["turbulence"] * turbulence(pts, p["turb_freq"], seed)
        f = h - np.floor(h)
        return np.abs(2.0 * f - 1.0) if p["profile"] == "tri" else f

    def starts(self, est) -> list:
        """The normal along the photo's strongest wave (in the wall x-z), each profile, each ramp order."""
        wx, wz = np.cos(est.angle), np.sin(est.angle)
        if wz < 0:
            wx, wz = -wx, -wz
        tilt, az = float(np.arccos(np.clip(wz, -1, 1))), (0.0 if wx >= 0 else np.pi)
        sp = float(np.clip(est.spacing, 0.006, 1.9))
        return [dict(spacing=sp, tilt=tilt, azimuth=az, turbulence=t, detail=0.1, turb_freq=float(np.clip(0.5 / sp, 0.3, 15.0)),
                     profile=prof, flip=flip)
                for prof in PROFILES for flip in (False, True) for t in (0.1, 0.6)]
