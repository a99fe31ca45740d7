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
min_f d_f in world units (polytope borders, Fig. 11a).  Each family is one
sub-group, chained through the running Distance and Code; its constants (normal,
offset) are computed by the backend and written into its nodes' socket defaults.
STIT recursion (depth > 0) stays bake-only.
"""
from __future__ import annotations

import json

import bpy
import numpy as np

from .. import backend
from .wave_nodes import (INPUTS, SETTINGS_KEY, TUNED_KEY, NodeBuilder, Tuned, clear_tree, copy_or_build, describe,
                         group_io, new_group, settings_to_json)
from .wave_nodes import TIPS as WAVE_TIPS

__all__ = ["build_cellular_group", "new_cellular_tree", "CELL_OUTPUTS"]

CELL_OUTPUTS = ("Cell", "Distance")
#: the Wave Cellular group's tooltips: the Wave Noise group's, but its cells stand still
TIPS = {**WAVE_TIPS, "Time": "Not read: cellular noise stands still"}
_F = np.float32
_OFFSET, _PLANE, _CODE = 24, 25, 26  # backend.wavenoise.cellular streams


def new_cellular_tree(name: str = "Wave Cellular", tree_type: str = "ShaderNodeTree") -> bpy.types.NodeTree:
    tree = new_group(name, tree_type, INPUTS, tuple((o, "NodeSocketFloat") for o in CELL_OUTPUTS))
    describe(tree, TIPS)
    tree.interface.items_tree["Scale"].min_value = -1000.0
    return tree


def _value(b: NodeBuilder, x, y, z, w):
    """Blender's White Noise Texture (4D) at (x, y, z, w) -> its Value, read as Value + |Color - Color| (exactly the
    Value): Cycles' SVM compiler keeps an output that nothing reads on its 255-float stack for the whole shader,
    three floats for each unread Color, four Colors per plane family.  With the families' wait on the running
    values (:func:`_family_group`) the largest direction counts the node offers compile; without either, a
    shader reading Distance overflowed from 12 directions in 2D and bakes black."""
    colour, value = b.white(x, y, z, w)
    return b.math("ADD", value, b.vmath("DISTANCE", colour, colour))


#: a family sub-group's inputs: the running Distance and Code, the scaled Position and W
_FAMILY_INPUTS = (("Distance", "NodeSocketFloat", None), ("Code", "NodeSocketFloat", None),
                  ("Position", "NodeSocketVector", None), ("W", "NodeSocketFloat", None))
#: the first family's Distance in: min(FAR, d) is d exactly
FAR = float(np.finfo(np.float32).max)


def _family_group(name: str, tree_type: str, dim: int, consts: dict) -> bpy.types.NodeTree:
    """Sub-group for one plane family: (Distance, Code) in -> (min(Distance, d_f), h(slab, Code, 26, seed)) out.

    The family's constants (``consts``: :func:`_family_constants`) are written into its nodes' sockets, as the Wave
    Noise node's strata are (a constant group input would wait on Cycles' SVM stack), and recorded where they sit
    (:class:`.wave_nodes.Tuned`): the next family is this one copied and retuned.  One small tree per family:
    Blender adds a node, a link or a value in time that grows with its tree's node count, so one tree of every
    family's nodes builds in time that grows with the square of the directions (64 directions in 2D: 3971 nodes,
    97 s in Blender 4.2).
    """
    tree = new_group(name, tree_type, _FAMILY_INPUTS, (("Distance", "NodeSocketFloat"), ("Code", "NodeSocketFloat")))
    b = NodeBuilder(tree)
    c = {k: Tuned(k, v) for k, v in consts.items()}
    gi = b.new("NodeGroupInput")
    go = b.new("NodeGroupOutput")
    # Position + (r - r), r = (Distance, Code, 0), exactly the position: every node of the family waits on both
    # running values, so Cycles' SVM compiler finishes family f before it starts family f + 1 (it emits any node
    # whose inputs are ready, and held every family's hashes on its 255-float stack at once)
    running = b.combine(gi.outputs["Distance"], gi.outputs["Code"])
    x = b.vmath("ADD", gi.outputs["Position"], b.vmath("SUBTRACT", running, running))
    dot = b.vmath("DOT_PRODUCT", x, c["Normal"])
    if dim == 4:
        dot = b.math("MULTIPLY_ADD", gi.outputs["W"], c["Normal W"], dot)
    p = b.math("MULTIPLY_ADD", dot, c["Inverse Size"], c["Offset"])
    j = b.math("FLOOR", p)
    o = b.math("SUBTRACT", p, j)

    def plane(i):  # s(i) = 0.3 + 0.4 h(f, i, 25, seed)
        return b.math("MULTIPLY_ADD", _value(b, c["Family"], i, float(_PLANE), c["Seed"]), 0.4, 0.3)

    here, nxt, prv = plane(j), plane(b.math("ADD", j, 1.0)), plane(b.math("SUBTRACT", j, 1.0))
    below = b.math("LESS_THAN", o, here)  # 1 - above
    up = b.math("SUBTRACT", b.math("ADD", nxt, 1.0), o)        # 1 + s(j+1) - φ
    down = b.math("SUBTRACT", b.math("ADD", o, 1.0), prv)      # φ + 1 - s(j-1)
    other = b.math("ADD", up, b.math("MULTIPLY", below, b.math("SUBTRACT", down, up)))
    d = b.math("MULTIPLY", b.math("MINIMUM", b.math("ABSOLUTE", b.math("SUBTRACT", o, here)), other), c["Size"])
    b.put(go.inputs["Distance"], b.math("MINIMUM", gi.outputs["Distance"], d))
    slab = b.math("SUBTRACT", j, below)
    b.put(go.inputs["Code"], _value(b, slab, gi.outputs["Code"], float(_CODE), c["Seed"]))
    tree[TUNED_KEY] = json.dumps(b.tuned)
    return tree


def _family_constants(noise, f: int) -> dict:
    """Plane family f's constants: its index, normal (x, y, z and w), 1 / C, offset o_f, cell size C and seed."""
    normal = np.asarray(noise.normals[f], dtype=np.float64)
    off = float(np.asarray(backend.wavenoise.hashing.white_noise4(_F(f), _F(0), _F(_OFFSET), noise.seed)
                           ).reshape(-1)[0])
    return {"Family": float(f), "Normal": tuple(float(v) for v in (list(normal[:3]) + [0.0] * 3)[:3]),
            "Normal W": float(normal[3]) if len(normal) > 3 else 0.0, "Inverse Size": float(_F(1.0 / noise.cell_size)),
            "Offset": off, "Size": float(noise.cell_size), "Seed": float(noise.seed)}


def build_cellular_group(settings, tree_type: str = "ShaderNodeTree", tree: bpy.types.NodeTree | None = None,
                         name: str = "Wave Cellular") -> bpy.types.NodeTree:
    """Build (or rebuild in place) the Wave Cellular group for ``settings`` (cellular polytope or code): one
    sub-group per plane family (:func:`_family_group`), chained through the running Distance and Code."""
    if settings.cellular not in ("polytope", "code"):
        raise backend.SettingError("cellular", "the node does polytope and code cells; STIT is bake-only")
    noise = backend.compile_noise(settings)
    if tree is None:
        tree = new_cellular_tree(name, tree_type)
    else:
        clear_tree(tree)
        describe(tree, TIPS)
    tree[SETTINGS_KEY] = settings_to_json(settings)
    b = NodeBuilder(tree)
    _, go, x, w = group_io(b)
    group_kind = "GeometryNodeGroup" if b.geo else "ShaderNodeGroup"
    dist, code = FAR, 0.0
    built = {}
    for f in range(len(noise.normals)):
        name, consts = f".{tree.name} family {f + 1}", _family_constants(noise, f)
        node = b.new(group_kind)
        node.node_tree = copy_or_build(built, "family", name, consts,
                                       lambda: _family_group(name, tree.bl_idname, noise.dim, consts))
        node.label = f"Family {f + 1}"
        for sock, v in (("Distance", dist), ("Code", code), ("Position", x), ("W", w)):
            b.put(node.inputs[sock], v)
        dist, code = node.outputs["Distance"], node.outputs["Code"]
    b.put(go.inputs["Cell"], code)
    b.put(go.inputs["Distance"], dist)
    return tree
