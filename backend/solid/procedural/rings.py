"""Rings: growth rings around an axis (Perlin 1985's wood; a log's rings, a board's figure).

The value is the distance r from an axis through c along d, in ring spacings, bent by turbulence, its fractional
part the phase within a ring (a saw: early wood to late wood, then the next ring):

    s = frac(r / spacing + turbulence * T(p) + grain * T(squash(p)))

where T is the wave noise turbulence and ``squash`` shrinks p along d by GRAIN_STRETCH, so its second term draws
streaks along the axis (the grain).  A cut through the axis shows half rings; a cut along it far from the axis
shows planks' stripes; a cut across it shows rings.
"""
from __future__ import annotations

import numpy as np

from .family import Family, Param, axis_angles, axis_vector, dot3
from .turbulence import turbulence

__all__ = ["Rings", "GRAIN_STRETCH"]

GRAIN_STRETCH = 8.0    #: how much longer the grain's streaks are along the axis than across it


def _basis(d: np.ndarray) -> tuple:
    """Two unit vectors spanning the plane normal to d."""
    a = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(d, e1)


class Rings(Family):
    name = "rings"
    doc = "growth rings around an axis: wood's end grain, its planks' figure"
    PARAMS = (Param("spacing", 0.005, 1.0, log=True, doc="distance between rings, units"),
              Param("tilt", 0.0, np.pi, doc="the axis's angle from +z, radians", floor=False),
              Param("azimuth", 0.0, np.pi, doc="the axis's turn about z from +x, radians", floor=False),
              Param("centre_u", -6.0, 6.0, doc="the axis's offset from the origin, across it, units",
                    floor=False),
              Param("centre_v", -6.0, 6.0, doc="the axis's offset from the origin, across it and u, units",
                    floor=False),
              Param("grain", 0.0, 1.0, doc="the streaks along the axis, in ring spacings"))

    def geometry(self, p: dict) -> tuple:
        """(d, c): the axis's direction and a point on it."""
        d = axis_vector(p["tilt"], p["azimuth"])
        e1, e2 = _basis(d)
        return d, p["centre_u"] * e1 + p["centre_v"] * e2

    def placement(self, axis, centre) -> dict:
        """:meth:`geometry`'s inverse: tilt, azimuth, centre_u and centre_v of the rings about the axis along
        ``axis`` (3,) through ``centre`` (3,) (the node group's inputs); ValueError for an axis of no length."""
        tilt, azimuth = axis_angles(axis)
        e1, e2 = _basis(axis_vector(tilt, azimuth))
        c = np.asarray(centre, np.float64)
        return dict(tilt=tilt, azimuth=azimuth, centre_u=float(c @ e1), centre_v=float(c @ e2))

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        pts = np.asarray(points, np.float64)
        d, c = self.geometry(p)
        rel = pts - c
        along = dot3(rel, d)
        r = np.linalg.norm(rel - along[:, None] * d, axis=1)
        s = r / p["spacing"]
        if p["turbulence"] > 0:
            s += p["turbulence"] * turbulence(pts, p["turb_freq"], seed)
        if p["grain"] > 0:
            squash = pts - (1.0 - 1.0 / GRAIN_STRETCH) * dot3(pts, d)[:, None] * d
            s += p["grain"] * turbulence(squash, 4.0 * p["turb_freq"], seed + 1)
        return s - np.floor(s)

    def starts(self, est) -> list:
        """The axis along the photo's stripes, in the wall x-z (a log seen from the side), 25 spacings behind the
        wall (planks' stripes) or 6 (arcs), each with the ramp either way round."""
        out = []
        a = est.angle + np.pi / 2                       # the stripes' direction in the wall, from +x towards +z
        dx, dz = np.cos(a), np.sin(a)
        if dz < 0:
            dx, dz = -dx, -dz
        tilt, az = float(np.arccos(np.clip(dz, -1, 1))), (0.0 if dx >= 0 else np.pi)
        sp = float(np.clip(est.spacing, 0.006, 0.9))
        for far in (6.0, 25.0):
            for flip in (False, True):
                out.append(dict(spacing=sp, tilt=tilt, azimuth=az, centre_u=0.0,
                                centre_v=float(np.clip(far * sp, 0.05, 5.9)), grain=0.2, turbulence=0.2, detail=0.1,
                                turb_freq=float(np.clip(0.5 / sp, 0.3, 15.0)), flip=flip))
        return out
