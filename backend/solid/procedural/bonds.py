"""Bonds: bricks and tiles laid in courses, in 3D (a wall's corner shows its courses meeting).

Courses of ``height`` run along z; within a course, units ``length`` long along x and along y (square in plan),
each course moved along both by ``offset`` of a unit (0: stack bond, 1/2: running bond, 1/3 or 1/4: raking
bonds).  Joints of width ``joint`` (in course heights) take the value -1, units their own random number r
(family.cell_random of the unit), reached linearly over as far again from the joint:

    d = the distance to the unit's nearest face,    e = clip(d / (joint height / 2) - 1, 0, 1),
    s = e (1 + r + turbulence * T(p)) - 1
"""
from __future__ import annotations

import numpy as np

from .family import Family, Param, cell_random, gapped

__all__ = ["Bonds"]


def _to_face(u: np.ndarray) -> np.ndarray:
    """Distance from u to the nearest integer, in the same units (0 to 1/2)."""
    f = u - np.floor(u)
    return np.minimum(f, 1.0 - f)


class Bonds(Family):
    name = "bonds"
    doc = "bricks and tiles in courses: running, stack and raking bonds"
    PARAMS = (Param("length", 0.02, 2.0, log=True, doc="a unit's length along x and y, units"),
              Param("height", 0.01, 1.0, log=True, doc="a course's height along z, units"),
              Param("offset", 0.0, 1.0, doc="each course's shift along x and y, in unit lengths"),
              Param("joint", 0.0, 0.5, doc="the joints' width, in course heights"))

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        pts = np.asarray(points, np.float64)
        w = pts[:, 2] / p["height"]
        row = np.floor(w)
        u = pts[:, 0] / p["length"] + p["offset"] * row
        v = pts[:, 1] / p["length"] + p["offset"] * row
        d = np.minimum(_to_face(w) * p["height"], np.minimum(_to_face(u), _to_face(v)) * p["length"])
        return gapped(d, 0.5 * p["joint"] * p["height"], cell_random(np.floor(u), np.floor(v), row, seed), p, pts,
                      seed)

    def starts(self, est) -> list:
        """Units the photo's repeat across; courses its repeat up (stack bond) or half of it (running bond, which
        repeats every second course); each ramp order."""
        length = float(np.clip(est.spacing_x, 0.021, 1.9))
        return [dict(length=length, height=float(np.clip(k * est.spacing_z, 0.011, 0.95)), offset=off, joint=0.15,
                     turbulence=0.1, detail=0.1, turb_freq=float(np.clip(0.5 / length, 0.3, 15.0)), flip=flip)
                for k, off in ((0.5, 0.5), (1.0, 0.0)) for flip in (False, True)]
