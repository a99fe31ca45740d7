"""The Wave Cellular node: cellular wave noise (Guehl et al. 2025, Sec. 6.3, Alg. 2) from Blender's own nodes.

It computes what :class:`backend.wavenoise.cellular.CellularNoise` computes with STIT depth
0.  For each of the 2K plane families (normal n_f, cell size C, offset o_f):

    p = (x · n_f) / C + o_f,   j = floor(p),   φ = p - j
    plane positions  s(i) = 0.3 + 0.4 · h(f, i, 25, seed)          (White Noise 4D, Value)
    above = φ >= s(j)
    d_f   = C · min(|φ - s(j)|, above ? 1 + s(j+1) - φ : φ + 1 - s(j-1))
    slab  = above ? j : j - 1
    code  = h(slab, code, 26, seed)                                  (chained over families)

Outputs: Cell = the final code (a grey id per polytope, Fig. 11c), Distance =
min_f d_f in world units (polytope borders, Fig. 11a).  Constants (normals,
offsets) are computed by the backend and written into socket defaults.  STIT
recursion (depth > 0) stays bake-only.
"""
from __future__ import annotations

import bpy
import numpy as np

from .. import backend
from .wave_nodes import INPUTS, SETTINGS_KEY, clear_tree, group_io, new_group, NodeBuilder, settings_to_json

__all__ = ["build_cellular_group", "new_cellular_tree", "CELL_OUTPUTS"]

CELL_OUTPUTS = ("Cell", "Distance")
_F = np.float32
_OFFSET, _PLANE, _CODE = 24, 25, 26  # backend.wavenoise.cellular streams


def new_cellular_tree(name: str = "Wave Cellular", tree_type: str = "ShaderNodeTree") -> bpy.types.NodeTree:
    tree = new_group(name, tree_type, INPUTS, tuple((o, "NodeSocketFloat") for o in CELL_OUTPUTS))
    tree.interface.items_tree["Scale"].min_value = -1000.0
    return tree


def _value(b: NodeBuilder, x, y, z, w):
    node = b.new("ShaderNodeTexWhiteNoise", noise_dimensions="4D")
    b.put(node.inputs["Vector"], b.combine(x, y, z))
    b.put(node.inputs["W"], w)
    return node.outputs["Value"]


def build_cellular_group(settings, tree_type: str = "ShaderNodeTree", tree: bpy.types.NodeTree | None = None,
                         name: str = "Wave Cellular") -> bpy.types.NodeTree:
    """Build (or rebuild in place) the Wave Cellular group for ``settings`` (cellular polytope or code)."""
    if settings.cellular not in ("polytope", "code"):
        raise backend.SettingError("cellular", "the node does polytope and code cells; STIT is bake-only")
    noise = backend.compile_noise(settings)
    if tree is None:
        tree = new_cellular_tree(name, tree_type)
    else:
        clear_tree(tree)
    tree[SETTINGS_KEY] = settings_to_json(settings)
    seed = float(noise.seed)
    C = noise.cell_size
    inv = float(_F(1.0 / C))
    b = NodeBuilder(tree)
    _, go, x, w = group_io(b)
    dim = noise.dim
    dist, code = None, 0.0
    for f, normal in enumerate(noise.normals):
        n3 = tuple(float(v) for v in (list(normal[:3]) + [0.0] * 3)[:3])
        off = float(np.asarray(backend.wavenoise.hashing.white_noise4(_F(f), _F(0), _F(_OFFSET), noise.seed)).reshape(-1)[0])
        dot = b.vmath("DOT_PRODUCT", x, n3)
        if dim == 4:
            dot = b.math("MULTIPLY_ADD", w, float(normal[3]), dot)
        p = b.math("MULTIPLY_ADD", dot, inv, off)
        j = b.math("FLOOR", p)
        o = b.math("SUBTRACT", p, j)
        def plane(i, f=float(f)):  # s(i) = 0.3 + 0.4 h(f, i, 25, seed)
            return b.math("MULTIPLY_ADD", _value(b, f, i, float(_PLANE), seed), 0.4, 0.3)

        here, nxt, prv = plane(j), plane(b.math("ADD", j, 1.0)), plane(b.math("SUBTRACT", j, 1.0))
        below = b.math("LESS_THAN", o, here)  # 1 - above
        up = b.math("SUBTRACT", b.math("ADD", nxt, 1.0), o)        # 1 + s(j+1) - φ
        down = b.math("SUBTRACT", b.math("ADD", o, 1.0), prv)      # φ + 1 - s(j-1)
        other = b.math("ADD", up, b.math("MULTIPLY", below, b.math("SUBTRACT", down, up)))
        d = b.math("MULTIPLY", b.math("MINIMUM", b.math("ABSOLUTE", b.math("SUBTRACT", o, here)), other), float(C))
        dist = d if dist is None else b.math("MINIMUM", dist, d)
        slab = b.math("SUBTRACT", j, below)
        code = _value(b, slab, code, float(_CODE), seed)
    b.put(go.inputs["Cell"], code)
    b.put(go.inputs["Distance"], dist)
    return tree
