"""Per-stratum constants of a compiled wave noise, as the Wave Noise node's two forms use them.

The node group (:mod:`.wave_nodes`) writes them into socket defaults, the OSL script
(:mod:`.wave_osl`) into constant arrays: slicing direction and offset (Alg. 1), the
stratum's box in the direction map's unit cube, the cap's spread and measure, the
Householder mirror onto the lobe axis, amplitude and table size.  Blender-free.
"""
from __future__ import annotations

import numpy as np

from .. import backend

__all__ = ["stratum_constants", "OUTPUTS"]

#: the Wave Noise outputs, in order, of both forms (node group and OSL script)
OUTPUTS = ("Value", "Imaginary", "Modulus", "Phase")

_F = np.float32


def stratum_constants(noise, k: int) -> dict:
    dirs = noise.dirs
    dom = dirs.domains[dirs.domain[k]]
    if dom.kind != "cap":
        raise backend.SettingError("example", "by-example noise is bake-only; the node supports caps and lobes")
    dim = noise.dim
    s = _F(dom.spread)
    if dim == 4:
        cap = _F(s - np.sin(s) * np.cos(s))
    else:
        cap = _F(_F(1.0) - np.cos(s))
    v = -np.asarray(dom.axis, dtype=_F)
    v[dim - 1] += 1.0
    vv = float(np.dot(v, v))
    scale = float(_F(2.0 / vv)) if vv >= 1e-12 else 0.0
    sd = noise.slice_dirs[k]
    pad = lambda a, fill=0.0: tuple(float(c) for c in (list(a[:3]) + [fill] * (3 - len(a[:3]))))  # noqa: E731
    return {
        "k": float(k), "Seed": float(noise.seed),
        "Slice Dir": pad(sd), "Slice Dir W": float(sd[3]) if dim == 4 else 0.0,
        "Slice Offset": float(noise.slice_offsets[k]),
        "Box Lo": pad(dirs.lo[k]), "Box Size": pad(dirs.hi[k] - dirs.lo[k]),
        "Spread": float(s), "Cap": float(cap),
        "Mirror": pad(v), "Mirror W": float(v[3]) if dim == 4 else 0.0, "Mirror Scale": scale,
        "Inv Period": float(_F(1.0 / noise.table.period)), "Amplitude": float(dirs.amp[k]),
        "Table Size": int(noise.table.size),
    }
