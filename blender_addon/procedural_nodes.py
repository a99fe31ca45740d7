"""A fitted procedural solid as a live node group: the engine's family, turbulence and ramp built from Blender's own
nodes (backend/solid/procedural), so Cycles, EEVEE and Geometry Nodes draw what the engine draws, and the fitted
parameters are the group's inputs for an artist to turn.

* the point p = Vector x Scale (texture units; Scale is texture units per Blender unit);
* the family's value s from math nodes: rings (distance from the axis through Centre along Axis, in Spacings),
  layers (height along Normal, in Spacings, through the saw or triangle profile), cells (F1, F2 and the nearest
  cell's value over the 27 cubes around p / (Size, Size, Size x Stretch), one sub-group each, a feature point's
  offset from one White Noise Texture's Color (4D) and the cell's value from another's), bonds (courses or a
  herringbone's units, and joints; a unit's number, and how far each row of units is moved into the wall, from
  the White Noise Texture, 4D, W = seed; the pattern is the group's own);
* turbulence, grain and detail: Wave Noise groups (:func:`.wave_nodes.build_wave_group`) of the engine's
  turbulence settings for seeds seed, seed + 1 and seed + 2, each read at its frequency through its Scale input
  and weighed by its amplitude input (an amplitude of 0 leaves its group out of a Cycles render: :func:`_plus`);
  built from Blender's nodes, or as one OSL script each where Cycles runs Open Shading Language (they follow the
  scene as the Wave Noise node's Automatic form does: :func:`follow_form`);
* the ramp as a sum of clamped Map Range nodes (one per stop interval: exact piecewise-linear colours; a Color Ramp
  node is sampled into a 256-entry table in Cycles);
* where the field has a tint (backend/solid/procedural/tint.py), a Wave Noise group for seed + tint.SEED_OFFSET read
  at Tint Frequency through the tint's levels (Map Range nodes again), times Tint (a Multiply: a Tint of 0 leaves
  the group out of a Cycles render), along the tint's colour axis, added to the colour;
* for cells and bonds, the Gap Mask: 1 less how far p lies inside its cell or unit (family.inside).

The field's JSON is stored on the tree (``tree["omninoise_procedural"]``) so the panel can rebuild it.
"""
from __future__ import annotations

import json

import numpy as np

import bpy

from ..backend.errors import SettingError
from .wave_nodes import (NodeBuilder, build_wave_group, check_form, new_group, settings_from_json,
                         tree_implementation, tree_settings_json)

__all__ = ["build_procedural_group", "add_procedural_node", "follow_form", "noise_trees", "PARAMETERS",
           "FIELD_KEY", "procedural_node", "node_field", "node_space"]

FIELD_KEY = "omninoise_procedural"

#: per family: (socket name, type, the engine's parameter or how it is read off the field)
PARAMETERS = {
    "rings": (("Spacing", "spacing"), ("Axis", "axis"), ("Centre", "centre"), ("Grain", "grain")),
    "layers": (("Spacing", "spacing"), ("Normal", "normal")),
    "cells": (("Size", "size"), ("Stretch", "stretch"), ("Jitter", "jitter"), ("Gap", "gap")),
    "bonds": (("Length", "length"), ("Height", "height"), ("Offset", "offset"), ("Joint", "joint")),
}
SHARED = (("Turbulence", "turbulence"), ("Turbulence Frequency", "turb_freq"), ("Detail", "detail"))
#: the sockets of a field with a tint: its amount (1 draws the photo's) and its noise's frequency
TINT = ("Tint", "Tint Frequency")
TIPS = {"Spacing": "Distance between rings or layers (texture units)",
        "Axis": "Direction of the rings' axis", "Centre": "A point on the rings' axis (texture units)",
        "Grain": "Streaks along the axis", "Normal": "Direction across the layers",
        "Size": "A cell's width (texture units)", "Stretch": "A cell's height over its width",
        "Jitter": "How far cells leave a regular grid (0 to 1)", "Gap": "Gap between cells, in cell widths",
        "Length": "A brick's length (texture units; a herringbone's: a whole number of widths)",
        "Height": "A course's height (texture units; a herringbone's: a brick's width)",
        "Offset": "Each course's shift, in brick lengths (0.5: running bond, 0: stack bond; herringbone: "
                  "each slab's)",
        "Joint": "Joint width, in course heights", "Turbulence": "How far the noise bends the pattern",
        "Turbulence Frequency": "The bending noise's frequency (cycles per texture unit)",
        "Detail": "Fine noise within the pattern", "Scale": "Texture units per Blender unit",
        "Tint": "How much of the photo's colour variation that brightness does not explain is drawn, in patches of "
                "its own (1: the photo's, 0: none)",
        "Tint Frequency": "The tint's patches' frequency (cycles per texture unit)",
        "Gap Mask": "1 in the joints and gaps, 0 on the bricks and cells, between at their edges (into a Bump "
                    "node's Height with Invert on, the mortar sinks)",
        "Vector": "Where the solid is read (the object's own coordinates when the node is added)",
        "Color": "The solid's colour, scene-linear: for a Base Color",
        "sRGB": "The solid's colour as sRGB-encoded values, as a baked 8-bit image stores them",
        "Value": "The pattern's value, which its colours are read from (about 0 to 1; detail may pass the ends)"}


def _socket_values(field) -> dict:
    """{socket name: its default} of a field's parameters (vectors for the rings' axis and centre and the
    layers' normal)."""
    from ..backend.solid.procedural.family import axis_vector
    from ..backend.solid.procedural.field import FAMILIES

    p = field.params
    out = {}
    if field.family == "rings":
        d, c = FAMILIES["rings"].geometry(p)
        out.update(Axis=tuple(d), Centre=tuple(c))
    if field.family == "layers":
        out["Normal"] = tuple(axis_vector(p["tilt"], p["azimuth"]))
    for name, key in PARAMETERS[field.family] + SHARED:
        if key in p:
            out[name] = p[key]
    if field.tint is not None:
        out.update({"Tint": 1.0, "Tint Frequency": field.tint.frequency})
    return out


def _bounds(family: str) -> dict:
    """{socket name: (min, max)} of a family's parameters, where the engine draws them (family.Param.check): a
    length, size or frequency no smaller than the engine's smallest, so no slider reaches a division by 0; a noise's
    amplitude no smaller than 0; a share (of a unit, a cube, a course) within its range (a cell's feature point
    beyond its cube, Jitter over 1, would lie outside the 27 cubes the group searches); every one, the vectors'
    components too, within +-MAX_PARAM."""
    from ..backend.solid.procedural.family import MAX_PARAM
    from ..backend.solid.procedural.field import FAMILIES

    ranges = {q.name: q for q in FAMILIES[family].params()}
    out = {}
    for name, key in PARAMETERS[family] + SHARED:
        q = ranges.get(key)
        out[name] = (q.lo if q is not None and q.floor else -MAX_PARAM, q.hi if q is not None and q.cap else MAX_PARAM)
    return out


def _interface(tree, field) -> None:
    from ..backend.solid.procedural.family import MAX_PARAM
    from ..backend.solid.procedural.field import FAMILIES

    values = _socket_values(field)
    bounds = _bounds(field.family)
    if field.tint is not None:
        bounds.update({"Tint": (0.0, MAX_PARAM), "Tint Frequency": (0.01, MAX_PARAM)})
    tint = TINT if field.tint is not None else ()
    for name in ["Vector", "Scale"] + [n for n, _ in PARAMETERS[field.family] + SHARED] + list(tint):
        vector = name in ("Vector", "Axis", "Centre", "Normal")
        s = tree.interface.new_socket(name, in_out="INPUT",
                                      socket_type="NodeSocketVector" if vector else "NodeSocketFloat")
        s.description = TIPS.get(name, "")
        if name == "Vector":
            s.hide_value = True
        elif name == "Scale":
            s.default_value = 1.0
        else:
            s.default_value = values[name]
            if name in bounds:
                s.min_value, s.max_value = bounds[name]
    gapped = ("Gap Mask",) if FAMILIES[field.family].GAPPED else ()
    for name in ("Color", "sRGB", "Value") + gapped:
        s = tree.interface.new_socket(name, in_out="OUTPUT",
                                      socket_type="NodeSocketColor" if name in ("Color", "sRGB") else "NodeSocketFloat")
        s.description = TIPS[name]


def _plus(b, amplitude, noise, base):
    """base + amplitude x noise as a Multiply and an Add, not one Multiply Add: Cycles folds a product with a
    constant 0 (an artist's Turbulence, Grain or Detail of 0) and leaves out the Wave Noise group it reads, which
    is most of the group's render time; it does not fold a Multiply Add."""
    return b.math("ADD", b.math("MULTIPLY", amplitude, noise), base)


def _frac(b, x):
    return b.math("SUBTRACT", x, b.math("FLOOR", x))


class _Noises(dict):
    """A group's Wave Noise trees by seed, built in ``form`` ("nodes" or "osl", wave_nodes.IMPLEMENTATIONS)."""

    def __init__(self, form: str):
        super().__init__()
        self.form = form


def _turbulence(b, groups: _Noises, seed: int, vector, frequency):
    """The Value of a Wave Noise group of the turbulence settings for ``seed`` at ``vector`` x ``frequency``."""
    from ..backend.solid.procedural.turbulence import turbulence_settings

    if seed not in groups:
        groups[seed] = build_wave_group(turbulence_settings(seed), b.tree.bl_idname,
                                        name=f".{b.tree.name} turbulence {seed}", implementation=groups.form)
    node = b.new("GeometryNodeGroup" if b.geo else "ShaderNodeGroup")
    node.node_tree = groups[seed]
    b.put(node.inputs["Vector"], vector)
    b.put(node.inputs["Scale"], frequency)
    return node.outputs["Value"]


def _rings(b, gi, p, seed, groups):
    d = b.vmath("NORMALIZE", gi.outputs["Axis"])
    rel = b.vmath("SUBTRACT", p, gi.outputs["Centre"])
    along = b.vmath("DOT_PRODUCT", rel, d)
    r = b.vmath("LENGTH", b.vmath("SUBTRACT", rel, b.vmath("SCALE", d, scale=along)))
    s = b.math("DIVIDE", r, gi.outputs["Spacing"])
    s = _plus(b, gi.outputs["Turbulence"], _turbulence(b, groups, seed, p, gi.outputs["Turbulence Frequency"]), s)
    from ..backend.solid.procedural.rings import GRAIN_STRETCH

    squash = b.vmath("SUBTRACT", p, b.vmath("SCALE", d, scale=b.math(
        "MULTIPLY", b.vmath("DOT_PRODUCT", p, d), 1.0 - 1.0 / GRAIN_STRETCH)))
    grain = _turbulence(b, groups, seed + 1, squash, b.math("MULTIPLY", gi.outputs["Turbulence Frequency"], 4.0))
    return _frac(b, _plus(b, gi.outputs["Grain"], grain, s))


def _layers(b, gi, p, seed, groups, profile):
    h = b.math("DIVIDE", b.vmath("DOT_PRODUCT", p, b.vmath("NORMALIZE", gi.outputs["Normal"])), gi.outputs["Spacing"])
    h = _plus(b, gi.outputs["Turbulence"], _turbulence(b, groups, seed, p, gi.outputs["Turbulence Frequency"]), h)
    f = _frac(b, h)
    return b.math("ABSOLUTE", b.math("MULTIPLY_ADD", f, 2.0, -1.0)) if profile == "tri" else f


def _inner(b, gi, p, seed, groups, r):
    """1 + r + turbulence: a cell's or a unit's own value."""
    t = _turbulence(b, groups, seed, p, gi.outputs["Turbulence Frequency"])
    return _plus(b, gi.outputs["Turbulence"], t, b.math("ADD", r, 1.0))


def _edge(b, gi, dist, width):
    """clip(dist / max(width, 1e-9) - 1, 0, 1)."""
    return b.math("SUBTRACT", b.math("DIVIDE", dist, b.math("MAXIMUM", width, 1e-9)), 1.0, clamp=True)


def _white(b, vector, w):
    """A White Noise Texture (4D) at (``vector``, ``w``) -> its Color (three hashes: backend.wavenoise.wave
    .white_color4).  Only the Color is read: an unread Color output would hold three floats of Cycles' SVM stack for
    the whole shader."""
    wn = b.new("ShaderNodeTexWhiteNoise", noise_dimensions="4D")
    b.put(wn.inputs["Vector"], vector)
    wn.inputs["W"].default_value = float(w)
    return wn.outputs["Color"]


def _cell_group(tree_type: str, name: str, offset, seed: int):
    """A sub-group for one of the 27 neighbouring cubes: F1, F2 and the nearest cell's value updated with this cube's
    feature point (cells.voronoi's loop body, from White Noise nodes)."""
    from ..backend.solid.procedural.cells import cell_w

    g = new_group(name, tree_type, (("F1", "NodeSocketFloat", None), ("F2", "NodeSocketFloat", None),
                                    ("Value", "NodeSocketFloat", None), ("Base", "NodeSocketVector", None),
                                    ("Local", "NodeSocketVector", None), ("Jitter", "NodeSocketFloat", None)),
                  (("F1", "NodeSocketFloat"), ("F2", "NodeSocketFloat"), ("Value", "NodeSocketFloat")))
    b = NodeBuilder(g)
    gi, go = b.new("NodeGroupInput"), b.new("NodeGroupOutput")
    # floor(F1 / 16) is 0 (F1 <= 8), but it makes this cube wait for the previous one: Cycles compiles every node
    # whose inputs are ready in one pass, and 27 cubes' values at once overflow its SVM stack
    wait = b.math("FLOOR", b.math("MULTIPLY", gi.outputs["F1"], 0.0625))
    c = b.vmath("ADD", b.vmath("ADD", gi.outputs["Base"], b.combine(wait, wait, wait)),
                tuple(float(v) for v in offset))
    point = b.vmath("MULTIPLY_ADD", _white(b, c, cell_w(seed, 0)), gi.outputs["Jitter"],
                    tuple(float(v) for v in offset))
    value = b.channel(_white(b, c, cell_w(seed, 1)), 0)
    d = b.vmath("DISTANCE", point, gi.outputs["Local"])
    nearer = b.math("LESS_THAN", d, gi.outputs["F1"])
    further = b.math("SUBTRACT", 1.0, nearer)
    b.put(go.inputs["F2"], b.math("MULTIPLY_ADD", nearer, gi.outputs["F1"],
                                  b.math("MULTIPLY", further, b.math("MINIMUM", gi.outputs["F2"], d))))
    b.put(go.inputs["Value"], b.math("MULTIPLY_ADD", nearer, value, b.math("MULTIPLY", further, gi.outputs["Value"])))
    b.put(go.inputs["F1"], b.math("MINIMUM", gi.outputs["F1"], d))
    return g


def _cells(b, gi, p, seed, groups):
    from ..backend.solid.procedural.cells import NEIGHBOURS

    size = gi.outputs["Size"]
    q = b.vmath("DIVIDE", p, b.combine(size, size, b.math("MULTIPLY", size, gi.outputs["Stretch"])))
    base = b.vmath("FLOOR", q)
    local = b.vmath("SUBTRACT", q, base)
    f1, f2, r = 8.0, 8.0, 0.0
    kind = "GeometryNodeGroup" if b.geo else "ShaderNodeGroup"
    for i, n in enumerate(NEIGHBOURS):
        node = b.new(kind)
        node.node_tree = _cell_group(b.tree.bl_idname, f".{b.tree.name} cell {i + 1}", n, seed)
        for name, v in (("F1", f1), ("F2", f2), ("Value", r), ("Base", base), ("Local", local),
                        ("Jitter", gi.outputs["Jitter"])):
            b.put(node.inputs[name], v)
        f1, f2, r = node.outputs["F1"], node.outputs["F2"], node.outputs["Value"]
    e = _edge(b, gi, b.math("SUBTRACT", f2, f1), gi.outputs["Gap"])
    return b.math("MULTIPLY_ADD", e, _inner(b, gi, p, seed, groups, r), -1.0), e


def _face(b, t):
    """Distance from t to the nearest integer (bonds._to_face)."""
    f = _frac(b, t)
    return b.math("MINIMUM", f, b.math("SUBTRACT", 1.0, f))


def _courses(b, gi, p, w_seed):
    """(distance to the unit's nearest face, the unit's three integers) of the courses pattern, each row of units
    into the wall moved by its own random fraction (bonds.Bonds.units); ``w_seed`` the White Noise's W."""
    from ..backend.solid.procedural.bonds import PHASE

    x, y, z = b.separate(p)
    length, height = gi.outputs["Length"], gi.outputs["Height"]
    w = b.math("ADD", b.math("DIVIDE", z, height), PHASE)
    row = b.math("FLOOR", w)
    u = b.math("ADD", b.math("DIVIDE", x, length), b.math("MULTIPLY_ADD", gi.outputs["Offset"], row, PHASE))
    i = b.math("FLOOR", u)
    sigma = b.channel(_white(b, b.combine(i, row, 0.5), w_seed), 0)
    v = b.math("ADD", b.math("DIVIDE", y, length), sigma)
    d = b.math("MINIMUM", b.math("MULTIPLY", _face(b, w), height),
               b.math("MULTIPLY", b.math("MINIMUM", _face(b, u), _face(b, v)), length))
    return d, (i, b.math("FLOOR", v), row)


def _herringbone(b, gi, p, turned: bool):
    """(distance, the unit's three integers) of the herringbone patterns (bonds.herringbone, in widths)."""
    x, y, z = b.separate(p)
    width = gi.outputs["Height"]
    n = b.math("MAXIMUM", b.math("FLOOR", b.math("ADD", b.math("DIVIDE", gi.outputs["Length"], width), 0.5)), 1.0)
    slab = b.math("DIVIDE", y, b.math("MULTIPLY", n, width))
    m = b.math("FLOOR", slab)
    x = b.math("MULTIPLY_ADD", b.math("MULTIPLY", gi.outputs["Offset"], n), m, b.math("DIVIDE", x, width))
    z = b.math("DIVIDE", z, width)
    if turned:
        x, z = (b.math("MULTIPLY", b.math("SUBTRACT", x, z), float(np.sqrt(0.5))),
                b.math("MULTIPLY", b.math("ADD", x, z), float(np.sqrt(0.5))))
    i, j = b.math("FLOOR", x), b.math("FLOOR", z)
    k = b.math("FLOOR", b.math("DIVIDE", b.math("ADD", b.math("SUBTRACT", j, i), b.math("SUBTRACT", n, 1.0)),
                                b.math("MULTIPLY", n, 2.0)))
    nk = b.math("MULTIPLY", n, k)
    xl, zl = b.math("ADD", x, nk), b.math("SUBTRACT", z, nk)
    il, jl = b.math("ADD", i, nk), b.math("SUBTRACT", j, nk)
    across = b.math("GREATER_THAN", b.math("SUBTRACT", jl, il), 0.5)
    t = b.math("MULTIPLY_ADD", across, b.math("SUBTRACT", il, jl), jl)
    long_x = b.math("MULTIPLY", b.math("SUBTRACT", 1.0, across), b.math("SUBTRACT", n, 1.0))
    fx = b.math("MINIMUM", b.math("SUBTRACT", xl, t),
                b.math("SUBTRACT", b.math("ADD", b.math("ADD", t, 1.0), long_x), xl))
    fz = b.math("MINIMUM", b.math("SUBTRACT", b.math("SUBTRACT", zl, t), across),
                b.math("SUBTRACT", b.math("MULTIPLY_ADD", across, n, b.math("ADD", t, 1.0)), zl))
    d = b.math("MULTIPLY", b.math("MINIMUM", b.math("MINIMUM", fx, fz), b.math("MULTIPLY", _face(b, slab), n)),
               width)
    return d, (b.math("MULTIPLY_ADD", t, 2.0, across), k, m)


def _bonds(b, gi, p, seed, groups, pattern):
    w_seed = np.float32(int(seed) % (1 << 24))          # family.cell_random's W
    d, unit = _courses(b, gi, p, w_seed) if pattern == "courses" else _herringbone(b, gi, p, pattern == "herringbone45")
    half = b.math("MULTIPLY", b.math("MULTIPLY", gi.outputs["Joint"], gi.outputs["Height"]), 0.5)
    white = b.channel(_white(b, b.combine(*unit), w_seed), 0)
    e = _edge(b, gi, d, half)
    return b.math("MULTIPLY_ADD", e, _inner(b, gi, p, seed, groups, white), -1.0), e


def _ramp(b, s, positions, values):
    """Piecewise linear ``values`` (K,) or colours (K, 3) at stops ``positions`` (K,) read at value socket ``s``:
    c0 + sum_k (c_k+1 - c_k) clamp(t_k, 0, 1), t_k = (s - x_k) / (x_k+1 - x_k); constant beyond the ends."""
    x = np.asarray(positions, np.float64)
    c = np.asarray(values, np.float64)
    acc = tuple(c[0]) if c.ndim == 2 else float(c[0])
    for k in range(len(x) - 1):
        m = b.new("ShaderNodeMapRange", data_type="FLOAT", interpolation_type="LINEAR", clamp=True)
        b.put(m.inputs["Value"], s)
        m.inputs["From Min"].default_value, m.inputs["From Max"].default_value = float(x[k]), float(x[k + 1])
        m.inputs["To Min"].default_value, m.inputs["To Max"].default_value = 0.0, 1.0
        if c.ndim == 2:
            acc = b.vmath("MULTIPLY_ADD", m.outputs["Result"], tuple(c[k + 1] - c[k]), acc)
        else:
            acc = b.math("MULTIPLY_ADD", m.outputs["Result"], float(c[k + 1] - c[k]), acc)
    return acc


def _to_linear(b, c):
    """The sRGB transfer function undone (IEC 61966-2-1), as backend.colour.srgb_to_linear: c / 12.92 up to 0.04045,
    ((c + 0.055) / 1.055)^2.4 above."""
    low = b.math("DIVIDE", c, 12.92)
    high = b.math("POWER", b.math("DIVIDE", b.math("ADD", c, 0.055), 1.055), 2.4)
    above = b.math("GREATER_THAN", c, 0.04045)
    return b.math("MULTIPLY_ADD", above, b.math("SUBTRACT", high, low), low)


def build_procedural_group(field, tree_type: str = "ShaderNodeTree", name: str | None = None,
                           implementation: str = "nodes"):
    """A node group drawing ``field`` (a backend ProceduralField): Vector, Scale and the family's parameters (and
    Tint and Tint Frequency where the field has a tint) in; Color (scene-linear, for a shader's Base Color), sRGB
    (the engine's values), Value (s) and for cells and bonds Gap Mask (ProceduralField.gaps) out.
    ``implementation``: the form of its Wave Noise groups, "nodes" or "osl" (shader trees under Cycles with Open
    Shading Language: :func:`follow_form` switches them as the scene's renderer changes)."""
    check_form(implementation, tree_type)       # before the group exists: a refused form leaves no half-built one
    tree = new_group(name or f"Procedural {field.family.title()}", tree_type, (), ())
    _interface(tree, field)
    tree[FIELD_KEY] = json.dumps(field.to_dict())
    b = NodeBuilder(tree)
    gi, go = b.new("NodeGroupInput"), b.new("NodeGroupOutput")
    p = b.vmath("SCALE", gi.outputs["Vector"], scale=gi.outputs["Scale"])
    seed, groups = field.seed, _Noises(implementation)
    fam, inside = field.family, None
    if fam == "rings":
        s = _rings(b, gi, p, seed, groups)
    elif fam == "layers":
        s = _layers(b, gi, p, seed, groups, field.params["profile"])
    elif fam == "cells":
        s, inside = _cells(b, gi, p, seed, groups)
    else:
        s, inside = _bonds(b, gi, p, seed, groups, field.params.get("pattern", "courses"))
    if inside is not None:
        b.put(go.inputs["Gap Mask"], b.math("SUBTRACT", 1.0, inside))
    from ..backend.solid.procedural.family import DETAIL_FREQ

    s = _plus(b, gi.outputs["Detail"], _turbulence(b, groups, seed + 2, p, DETAIL_FREQ), s)
    colour = _ramp(b, s, field.ramp.positions, field.ramp.colours)
    if field.tint is not None:
        from ..backend.solid.procedural.tint import SEED_OFFSET

        t = field.tint
        u = _turbulence(b, groups, seed + SEED_OFFSET, p, gi.outputs["Tint Frequency"])
        amount = b.math("MULTIPLY", gi.outputs["Tint"], _ramp(b, u, t.positions, t.levels))
        colour = b.vmath("MULTIPLY_ADD", b.combine(amount, amount, amount), tuple(t.axis), colour)
    srgb = b.vmath("MINIMUM", b.vmath("MAXIMUM", colour, (0.0, 0.0, 0.0)), (1.0, 1.0, 1.0))
    b.put(go.inputs["sRGB"], srgb)
    b.put(go.inputs["Color"], b.combine(*(_to_linear(b, c) for c in b.separate(srgb))))
    b.put(go.inputs["Value"], s)
    return tree


def noise_trees(group) -> list:
    """The Wave Noise trees a procedural ``group`` builds and reads (its group nodes' trees that carry wave
    settings; not a Wave Noise node an artist put in, whose form its own setting keeps)."""
    out = []
    for node in group.nodes:
        tree = getattr(node, "node_tree", None)
        if (tree is not None and tree not in out and tree_settings_json(tree) is not None
                and not getattr(getattr(tree, "omninoise_wave", None), "is_wave", False)):
            out.append(tree)
    return out


def follow_form(form: str) -> int:
    """Rebuild, in ``form`` ("nodes" or "osl"), the Wave Noise trees of this file's procedural shader groups (not
    linked from a library) that are in the other -> how many were rebuilt, each from the settings stored on it.  The
    Automatic form of the Wave Noise node (wave_ui.follow_render_settings) calls this as the scene's renderer
    changes: OSL where Cycles runs Open Shading Language, several times faster there, Blender's nodes elsewhere."""
    done = 0
    for group in list(bpy.data.node_groups):
        if FIELD_KEY not in group or group.bl_idname != "ShaderNodeTree" or group.library is not None:
            continue
        for tree in noise_trees(group):
            if tree.library is None and tree_implementation(tree) != form:
                settings = settings_from_json(tree_settings_json(tree))
                try:
                    build_wave_group(settings, tree=tree, implementation=form)
                except SettingError:     # a script that does not compile: the node form renders everywhere
                    build_wave_group(settings, tree=tree, implementation="nodes")
                    continue
                done += 1
    return done


def procedural_node(obj):
    """The group node of a procedural solid in ``obj``'s active material: the material's active node where it is
    one, else its first; SettingError where there is none."""
    mat = getattr(obj, "active_material", None)
    nt = getattr(mat, "node_tree", None)
    found = [] if nt is None else [n for n in nt.nodes if n.type == "GROUP" and n.node_tree is not None
                                   and FIELD_KEY in n.node_tree]
    if not found:
        where = "nothing is selected" if obj is None else f"the active material of {obj.name!r} has none"
        raise SettingError("object", f"no procedural node group: {where} (make one with Procedural Node Group or "
                                     "load a saved solid)")
    return nt.nodes.active if nt.nodes.active in found else found[0]


def _value(node, name: str):
    s = node.inputs.get(name)
    if s is None:
        raise SettingError(name, f"node {node.name!r} has no input {name!r}: its group {node.node_tree.name!r} was "
                                 "changed; make the group again (Procedural Node Group, or Load a saved solid)")
    if s.is_linked:
        raise SettingError(name, f"the {name} of node {node.name!r} is linked to another node; a bake reads the "
                                 "group's own values: unlink it and set it")
    v = s.default_value
    return tuple(float(x) for x in v) if hasattr(v, "__len__") else float(v)


def node_field(node):
    """The ProceduralField a procedural group ``node`` draws as its inputs are set (an artist's edits included):
    the field stored on its group (:data:`FIELD_KEY`) with the family's parameters read off the node's inputs
    (the rings' Axis and Centre and the layers' Normal turned back into angles and offsets), Turbulence,
    Turbulence Frequency and Detail, and the tint's amount (its levels times Tint; none at 0) and frequency.
    SettingError naming an input that is linked, or one the engine does not draw."""
    from ..backend.solid.procedural import saved
    from ..backend.solid.procedural.family import axis_angles
    from ..backend.solid.procedural.field import FAMILIES, ProceduralField
    from ..backend.solid.procedural.tint import Tint

    try:
        stored = saved.from_document(dict(json.loads(node.node_tree[FIELD_KEY]), format=saved.FORMAT))
    except (TypeError, ValueError, RecursionError) as exc:
        why = f"{exc.setting}: {exc.message}" if isinstance(exc, SettingError) else str(exc)
        raise SettingError("node group", f"{node.node_tree.name!r} holds no procedural solid that can be read "
                                         f"(its {FIELD_KEY!r} property: {why})") from None
    family, p, tint = stored.family, dict(stored.params), stored.tint
    for name, key in PARAMETERS[family] + SHARED:
        if key in p:
            p[key] = _value(node, name)
    direction = {"rings": "Axis", "layers": "Normal"}.get(family)
    if direction is not None:
        v = _value(node, direction)
        centre = _value(node, "Centre") if family == "rings" else None
        try:
            if family == "rings":
                p.update(FAMILIES["rings"].placement(v, centre))
            else:
                p["tilt"], p["azimuth"] = axis_angles(v)
        except ValueError as exc:
            raise SettingError(direction, f"{node.name!r}: {exc}") from None
    if tint is not None:
        amount = _value(node, "Tint")
        tint = None if amount == 0 else Tint(_value(node, "Tint Frequency"), tint.positions,
                                             tuple(amount * v for v in tint.levels), tint.axis)
    return ProceduralField(family, p, stored.ramp, stored.seed, stored.px_per_unit, tint)


def node_space(node) -> tuple:
    """(scale, world) of a procedural group ``node``: its Scale input (texture units per Blender unit) and whether
    its Vector is the world Position (a Geometry node's) rather than the object's own space (a Texture Coordinate
    node's Object output, as :func:`add_procedural_node` wires it); SettingError for another Vector."""
    scale = _value(node, "Scale")
    links = node.inputs["Vector"].links
    src = links[0].from_socket if links else None
    if src is not None and src.node.type == "TEX_COORD" and src.name == "Object" and src.node.object is None:
        return scale, False
    if src is not None and src.node.type == "NEW_GEOMETRY" and src.name == "Position":
        return scale, True
    raise SettingError("Vector", f"the Vector of node {node.name!r} is not the object's own space (a Texture "
                                 "Coordinate node's Object, with no object set) or the world Position: a bake draws "
                                 "one of those")


def add_procedural_node(node_tree, group, location=(0.0, 0.0)):
    """A group node of ``group`` in ``node_tree`` with a Texture Coordinate node's Object output on its Vector (a
    solid texture of the object's local space) -> the node."""
    node = node_tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.location = location
    tc = node_tree.nodes.new("ShaderNodeTexCoord")
    tc.location = (location[0] - 220.0, location[1])
    node_tree.links.new(tc.outputs["Object"], node.inputs["Vector"])
    return node
