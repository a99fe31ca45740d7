"""Bonds: bricks and tiles laid in courses or in a herringbone, in 3D (a wall's corner shows its courses meeting).

Pattern "courses": courses of ``height`` run along z; within a course, units ``length`` long along x and along y
(square in plan), each course moved along x by ``offset`` of a unit (0: stack bond, 1/2: running bond, 1/3 or
1/4: raking bonds).  Along y (into the wall) each row of units, one course and one unit along x, is moved by its
own random fraction of a unit, sigma = cell_random(i, row, 1/2): a wall cut along y then crosses the depth joints
of scattered units, as many as a cut anywhere, not every unit of a course (or of every course, in a stack bond)
at once.

    w = z / height + phi,  row = floor(w),  u = x / length + offset row + phi,  i = floor(u),  v = y / length + sigma

The phase phi = 1/4 (:data:`PHASE`) keeps the joints off the planes through the origin and through round
coordinates: z = 0 cuts every course a quarter of its height above a bed joint, and x = 0 every unit a quarter
of its length from a head joint (in stack and running bonds alike), so the faces of a cube at x, z = +-1 cut
units, not a sheet of mortar, where the units' sizes are 1/k (as photos' 32 and 64 px bricks are, at 128 px a
unit) or 2/(2k + 1).

Patterns "herringbone" and "herringbone45": in the wall (x, z), units ``height`` wide and n = max(1,
round(length / height)) widths long, laid alternately along and across (the 90-degree herringbone, its zigzag on
the diagonal) or the same turned 45 degrees (zigzags along x, as a herringbone wall or path shows them).  In
widths (X, Z), a cell (i, j) on diagonal d = j - i belongs to band k = floor((d + n - 1) / 2n) (the tiling repeats
by n (1, -1)); within the band, d' = d - 2nk, a unit lies along X from t = j - nk where d' <= 0 and across it from
t = i + nk where d' > 0:

    along:   X - nk in [t, t + n],    Z + nk in [t, t + 1]
    across:  X - nk in [t, t + 1],    Z + nk in [t + 1, t + 1 + n]

(X + nk and Z - nk in the band's own coordinates; see :func:`herringbone`).  Along y the wall is slabs n widths
deep, each moved along x by ``offset`` of a unit.

Joints of width ``joint`` (in course heights or unit widths) take the value -1, units their own random number r
(family.cell_random of the unit), reached linearly over as far again from the joint:

    d = the distance to the unit's nearest face,    e = clip(d / (joint height / 2) - 1, 0, 1),
    s = e (1 + r + turbulence * T(p)) - 1
"""
from __future__ import annotations

import numpy as np

from .family import Family, Param, cell_random, gapped, inside

__all__ = ["Bonds", "PATTERNS", "herringbone", "units_long", "PHASE"]

PATTERNS = ("courses", "herringbone", "herringbone45")
PHASE = 0.25     #: added to z / height and to u (module doc): joints stand off round coordinates


def _to_face(u: np.ndarray) -> np.ndarray:
    """Distance from u to the nearest integer, in the same units (0 to 1/2)."""
    f = u - np.floor(u)
    return np.minimum(f, 1.0 - f)


def _half_joint(p: dict) -> float:
    """Half a joint's width, units (``joint`` is in course heights)."""
    return 0.5 * p["joint"] * p["height"]


def units_long(p: dict) -> float:
    """A herringbone unit's length in widths: max(1, round(length / height))."""
    return float(max(1.0, np.floor(p["length"] / p["height"] + 0.5)))


def herringbone(x: np.ndarray, z: np.ndarray, n: float) -> tuple:
    """The herringbone of units 1 wide and ``n`` long (a whole number) at (x, z) in widths -> (distance to the
    unit's nearest face in widths, the unit's integer coordinates t, k and its direction: 0 along x, 1 across)."""
    i, j = np.floor(x), np.floor(z)
    k = np.floor((j - i + n - 1.0) / (2.0 * n))
    xl, zl = x + n * k, z - n * k
    il, jl = i + n * k, j - n * k
    across = (jl - il > 0.5).astype(np.float64)
    t = np.where(across > 0, il, jl)
    fx = np.minimum(xl - t, t + 1.0 + (1.0 - across) * (n - 1.0) - xl)
    fz = np.minimum(zl - t - across, t + 1.0 + across * n - zl)
    return np.minimum(fx, fz), t, k, across


class Bonds(Family):
    name = "bonds"
    doc = "bricks and tiles in courses (running, stack and raking bonds) or in a herringbone"
    PARAMS = (Param("length", 0.02, 2.0, log=True, doc="a unit's length along x and y, units"),
              Param("height", 0.01, 1.0, log=True, doc="a course's height along z (herringbone: a unit's width), "
                                                        "units"),
              Param("offset", 0.0, 1.0, doc="each course's (herringbone: each slab's) shift, in unit lengths",
                    cap=True),
              Param("joint", 0.0, 0.5, doc="the joints' width, in course heights", cap=True))

    GAPPED = True

    def units(self, p: dict, points: np.ndarray, seed: int) -> tuple:
        """(the distance to the unit's nearest face float64 (P,), units; the unit's random number r float64 (P,))
        at points (P, 3)."""
        pts = np.asarray(points, np.float64)
        pattern = p.get("pattern", "courses")
        if pattern == "courses":
            w = pts[:, 2] / p["height"] + PHASE
            row = np.floor(w)
            u = pts[:, 0] / p["length"] + p["offset"] * row + PHASE
            i = np.floor(u)
            v = pts[:, 1] / p["length"] + cell_random(i, row, 0.5, seed)
            d = np.minimum(_to_face(w) * p["height"], np.minimum(_to_face(u), _to_face(v)) * p["length"])
            r = cell_random(i, np.floor(v), row, seed)
        else:
            n, width = units_long(p), p["height"]
            slab = pts[:, 1] / (n * width)
            m = np.floor(slab)
            x = pts[:, 0] / width + p["offset"] * n * m
            z = pts[:, 2] / width
            if pattern == "herringbone45":
                x, z = (x - z) * np.sqrt(0.5), (x + z) * np.sqrt(0.5)
            dist, t, k, across = herringbone(x, z, n)
            d = np.minimum(dist, _to_face(slab) * n) * width
            r = cell_random(2.0 * t + across, k, m, seed)
        return d, r

    def shape(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        d, r = self.units(p, points, seed)
        return gapped(d, _half_joint(p), r, p, np.asarray(points, np.float64), seed)

    def gaps(self, p: dict, points: np.ndarray, seed: int) -> np.ndarray:
        return 1.0 - inside(self.units(p, points, seed)[0], _half_joint(p))

    def starts(self, est) -> list:
        """Courses: units the photo's repeat across long, courses as high and shifted as the photo's
        (``est.courses``: a running bond's courses are half its repeat up, each shifted half a unit); joints dark
        or pale as the photo's are (``est.dark_gaps``)."""
        length = float(np.clip(est.spacing_x, 0.021, 1.9))
        height, offset = est.courses
        return [dict(length=length, height=float(np.clip(height, 0.011, 0.95)), offset=float(offset), joint=0.15,
                     turbulence=0.1, detail=0.1, turb_freq=float(np.clip(0.5 / length, 0.3, 15.0)),
                     flip=not est.dark_gaps, pattern="courses")]

    def herringbone_starts(self, est) -> list:
        """Herringbones of units n widths long, joints dark or pale as the photo's are.  The turned one repeats
        every sqrt(2) widths along x and sqrt(2) n along z; the 90-degree one is the same turned back, so it repeats
        every sqrt(2) widths along one diagonal and sqrt(2) n along the other.  So n = round(longer / shorter),
        within [2, 4]."""
        out = []
        for pattern, repeats in (("herringbone", est.diagonals), ("herringbone45", (est.spacing_x, est.spacing_z))):
            short, long = sorted(repeats)
            n = float(np.clip(np.floor(long / max(short, 1e-9) + 0.5), 2.0, 4.0))
            width = float(np.clip(short / np.sqrt(2.0), 0.011, 0.45))
            out.append(dict(length=n * width, height=width, offset=0.5, joint=0.15, turbulence=0.1, detail=0.1,
                            turb_freq=float(np.clip(0.5 / (n * width), 0.3, 15.0)), flip=not est.dark_gaps,
                            pattern=pattern))
        return out
