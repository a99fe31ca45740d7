"""The Wave Noise node: a node group built from Blender's own nodes, or one OSL script (:mod:`.wave_osl`).

The group computes exactly the sum of :mod:`backend.wavenoise.wave` (Guehl et al. 2025,
Eq. 6 and 9, Algorithm 1), node for node:

* per stratum k: slice coordinate p = x . s_k + o_k, slice n = floor(p), f = p - n;
* slice records of n and n+1 from Blender's White Noise Texture (4D) at
  (k, slice, stream, seed), which :mod:`backend.wavenoise.hashing` reproduces bit for bit;
* the jittered direction by the same equal-measure map as
  :func:`backend.wavenoise.directions.map_directions` (2D angle; 3D arccos; 4D with five
  Newton steps for psi), Householder-rotated onto the lobe axis;
* the wave (x . omega - v t) / L + zeta read from the complex table with the
  engine's linear interpolation (texel centres at (i + 1/2) / N), done in nodes:
  one float RGBA image packed into the .blend holds T (R = real, G = imaginary)
  and its forward difference dT[i] = T[i+1] - T[i] (B, A); it is read once at
  texel j0's centre with Closest interpolation and Repeat extension, and T + t dT
  is two multiply-adds.  A Linear Image Texture would not do: EEVEE samples it with
  mipmaps and anisotropic filtering, and the table coordinate jumps at every
  slice border and table wrap, where the screen-space derivative then picks a
  blurred mip level (measured: correlation 0.81 with the engine at 48 px);
  Closest is unfiltered on every engine;
* border weights cos / sin(pi/2 smoothstep(u)), amplitude sqrt(1/K).

Every per-stratum quantity the backend precomputes (s_k, o_k, stratum box,
lobe axis) enters as a constant input of a stratum sub-group, so the main
group reads: Vector, W, Scale, Time in; Value, Imaginary, Modulus, Phase out.
The same builder makes shader groups (Cycles, EEVEE, any device) and
Geometry Nodes groups (fields on geometry).

Rebuilding for new settings clears the inner nodes and keeps the interface,
so links to the group node survive.  Settings are stored as JSON on the tree
(``tree["omninoise_wave_settings"]``; files saved by OmniNoise 0.1 on Blender 5.0
used ``tree["omninoise_wave"]``, the name of the ``NodeTree.omninoise_wave``
property, which Blender before 5.0 refuses as a custom key; both are read).
"""
from __future__ import annotations

import hashlib
import json

import bpy
import numpy as np

from .. import backend
from .compat import id_property
from .wave_constants import OUTPUTS, stratum_constants

__all__ = ["build_wave_group", "new_wave_tree", "add_wave_node", "ensure_table_image", "settings_to_json",
           "settings_from_json", "INPUTS", "OUTPUTS", "TIPS", "describe", "SETTINGS_KEY", "tree_settings_json",
           "NodeBuilder", "new_group", "clear_tree", "group_io", "IMPLEMENTATIONS", "IMPLEMENTATION_KEY",
           "tree_implementation", "check_form", "SHAPE_KEY", "Tuned", "TUNED_KEY", "copy_or_build", "retune_tree"]

_F = np.float32
SETTINGS_KEY = "omninoise_wave_settings"
#: the key of OmniNoise 0.1 (Blender 5.0 only: before 5.0 it collides with the registered property)
LEGACY_SETTINGS_KEY = "omninoise_wave"


def tree_settings_json(tree) -> str | None:
    """The settings JSON stored on a Wave Noise (or Wave Cellular) tree, or None if it has none."""
    return id_property(tree, SETTINGS_KEY, LEGACY_SETTINGS_KEY)
#: the two forms of the group: Blender's math nodes (every engine) or one OSL script (Cycles with OSL)
IMPLEMENTATIONS = ("nodes", "osl")
#: tree key holding the form a group was built in
IMPLEMENTATION_KEY = "omninoise_wave_implementation"
#: a node-form group's and each stratum sub-group's shape (everything but the constants a setting's change
#: retunes) and, on both, where those constants sit: a change of band, exponent, seed, speed or waveform that keeps
#: the shape rewrites them and the table image in place instead of building every node again
SHAPE_KEY = "omninoise_wave_shape"
TUNED_KEY = "omninoise_wave_tuned"
#: the stratum constants (wave_constants.stratum_constants, with :func:`_node_constants`' box corners) that are
#: retuned in place
TUNED = ("k", "Slice Dir", "Slice Dir W", "Slice Offset", "Seed", "Inv Period", "Amplitude", "Box Lo 3", "Box Size 3",
         "Box Lo W", "Box Size W")
#: the stratum constants the nodes read only through others (the box, through its corners' sockets)
_UNREAD = ("Box Lo", "Box Size")


def _node_constants(consts: dict) -> dict:
    """A stratum's constants (:func:`stratum_constants`) with its box as the nodes hold it: (0, lo0, lo1) and
    (1, size0, size1), the offset and scale of the slice record (zeta, jitter 0, jitter 1), and lo2, size2 (4D)."""
    lo, size = consts["Box Lo"], consts["Box Size"]
    return dict(consts, **{"Box Lo 3": (0.0,) + tuple(lo[:2]), "Box Size 3": (1.0,) + tuple(size[:2]),
                           "Box Lo W": lo[2], "Box Size W": size[2]})


def _stratum_shape(consts: dict) -> str:
    """What a stratum's sub-group is built from besides the constants it retunes (JSON)."""
    return json.dumps({k: v for k, v in consts.items() if k not in TUNED and k not in _UNREAD})


class Tuned:
    """A constant that :meth:`NodeBuilder.put` writes into a socket and records by name, to be retuned in place."""

    __slots__ = ("name", "value")

    def __init__(self, name: str, value):
        self.name, self.value = name, value


def tree_implementation(tree) -> str:
    """The form ('nodes' or 'osl') a Wave Noise tree was built in; trees from before the OSL form are 'nodes'."""
    return str(tree.get(IMPLEMENTATION_KEY, "nodes"))


#: (name, socket type, default) of the group's inputs and outputs
INPUTS = (("Vector", "NodeSocketVector", (0.0, 0.0, 0.0)), ("W", "NodeSocketFloat", 0.0),
          ("Scale", "NodeSocketFloat", 1.0), ("Time", "NodeSocketFloat", 0.0))
#: the tooltips of the Wave Noise and Wave Cellular groups' inputs and outputs (both forms, OSL and nodes)
TIPS = {"Vector": "Where the noise is read (the object's own coordinates when the node is added)",
        "W": "The fourth coordinate, read by 4D noise: move it to slide through the noise",
        "Scale": "Multiplies Vector and W: larger values draw smaller features",
        "Time": "Moves the waves at the panel's Speed; key it or drive it with the frame to animate",
        "Value": "The noise: the real part of the sum of waves",
        "Imaginary": "The imaginary part of the sum of waves: a second noise of the same look",
        "Modulus": "The size of the sum of waves (0 or more): ridges where the waves add up",
        "Phase": "The angle of the sum of waves, radians from -pi to pi",
        "Cell": "One grey level in [0, 1] for each cell",
        "Distance": "Distance to the nearest cell border, in units of Vector after Scale"}
STREAM = backend.wavenoise.wave.STREAM


# -- settings <-> JSON ----------------------------------------------------------

def settings_to_json(s) -> str:
    """WaveSettings -> JSON stored on the tree (by-example images are bake-only)."""
    return json.dumps(backend.wavenoise.settings.settings_to_dict(s), sort_keys=True)


def settings_from_json(text: str):
    return backend.wavenoise.settings.settings_from_dict(json.loads(text))


# -- the table as a packed float image ---------------------------------------------

def ensure_table_image(values: np.ndarray) -> bpy.types.Image:
    """A packed float image of a complex table: complex64 (rows, N) -> N x rows RGBA image.

    One texel holds all a lerp needs: R, G = re, im T[i] and B, A = re, im of the forward
    difference dT[i] = T[(i + 1) mod N] - T[i] (float32, as the engine's lerp computes it), so
    the node group reads the table once per lerp (1.16x faster in Cycles SVM at 16 directions
    than two images of T and dT, the same values to 2.4e-7).  Images are shared by content (the
    name carries a hash of the values), so identical tables are stored once per .blend.
    """
    values = np.ascontiguousarray(values, np.complex64)
    rows, size = values.shape
    name = "OmniNoise packed " + hashlib.sha256(values.tobytes()).hexdigest()[:12]
    img = bpy.data.images.get(name)
    if img is not None and tuple(img.size) == (size, rows):
        return img
    img = bpy.data.images.new(name, size, rows, alpha=True, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    img.alpha_mode = "CHANNEL_PACKED"
    img.use_half_precision = False  # Cycles would otherwise sample a half-float copy (5e-4 error)
    diff = (np.roll(values, -1, axis=1) - values).astype(np.complex64)
    px = np.stack([values.real, values.imag, diff.real, diff.imag], axis=-1).astype(_F)
    img.pixels.foreach_set(px.ravel())
    img.pack()
    return img


# -- a small node-building helper ---------------------------------------------

class NodeBuilder:
    """Adds math nodes to a shader or geometry tree; constants go into socket defaults."""

    def __init__(self, tree: bpy.types.NodeTree):
        self.tree = tree
        self.geo = tree.bl_idname == "GeometryNodeTree"
        self.col = 0
        self.row = 0
        self.tuned = []         # [socket path, Tuned name] of every Tuned constant put

    def new(self, kind: str, **props):
        n = self.tree.nodes.new(kind)
        for k, v in props.items():
            setattr(n, k, v)
        n.location = (200.0 * self.col, -160.0 * self.row)
        self.row += 1
        if self.row > 24:
            self.row, self.col = 0, self.col + 1
        return n

    def put(self, sock, v) -> None:
        if isinstance(v, Tuned):
            self.tuned.append([sock.path_from_id(), v.name])
            v = v.value
        if isinstance(v, bpy.types.NodeSocket):
            self.tree.links.new(v, sock)
        elif isinstance(v, (tuple, list, np.ndarray)):
            sock.default_value = tuple(float(c) for c in v)
        else:
            sock.default_value = float(v)

    def math(self, op: str, a, b=0.0, c=0.0, clamp: bool = False):
        n = self.new("ShaderNodeMath", operation=op, use_clamp=clamp)
        for s, v in zip(n.inputs, (a, b, c)):
            self.put(s, v)
        return n.outputs[0]

    def vmath(self, op: str, a, b=(0.0, 0.0, 0.0), c=None, scale=None):
        n = self.new("ShaderNodeVectorMath", operation=op)
        self.put(n.inputs[0], a)
        self.put(n.inputs[1], b)
        if c is not None:
            self.put(n.inputs[2], c)
        if scale is not None:
            self.put(n.inputs["Scale"], scale)
        return n.outputs["Value"] if op in ("DOT_PRODUCT", "LENGTH", "DISTANCE") else n.outputs["Vector"]

    def combine(self, x=0.0, y=0.0, z=0.0):
        n = self.new("ShaderNodeCombineXYZ")
        for s, v in zip(n.inputs, (x, y, z)):
            self.put(s, v)
        return n.outputs[0]

    def separate(self, v):
        n = self.new("ShaderNodeSeparateXYZ")
        self.put(n.inputs[0], v)
        return tuple(n.outputs)

    def white(self, k: float, n, stream: int, seed) -> tuple:
        """Blender's White Noise Texture, 4D, at (k, n, stream, seed) -> its (Color, Value) sockets.

        Channel c of the Color is backend.wavenoise.wave.white_color4(k, n, stream, seed, c); the
        Value is channel 0 (Blender's hash_float4_to_float3 starts with hash_float4_to_float).
        The slice id n sits in the Combine XYZ, so the node depends on the stratum's chain
        (a constant Combine could be scheduled early and crowd Cycles' SVM stack).  Cycles' SVM
        compiler keeps an output nothing reads on its 255-float stack for the whole shader, and a
        Bump node compiles its Height three times: read both outputs where the stack needs it
        (:meth:`both`).
        """
        node = self.new("ShaderNodeTexWhiteNoise", noise_dimensions="4D")
        self.put(node.inputs["Vector"], self.combine(k, n, float(stream)))
        self.put(node.inputs["W"], seed)
        return node.outputs["Color"], node.outputs["Value"]

    def both(self, color, value):
        """The Color, read with its Value as its scale Compare(Value, Value) = 1 (exactly the Color)."""
        return self.vmath("SCALE", color, scale=self.math("COMPARE", value, value, 0.0))

    def channel(self, color, c: int):
        """Channel c of a colour socket, read with an exact dot product (c . e_c).

        A Separate XYZ whose other outputs are unlinked would stay on Cycles' stack
        for the whole shader."""
        return self.vmath("DOT_PRODUCT", color, tuple(np.eye(3)[c]))

    def image(self, img: bpy.types.Image, vector, alpha: bool = False):
        """Unfiltered (Closest), repeating image lookup -> colour socket (r, g, b) read as a vector, and with
        ``alpha`` the alpha socket too (one lookup)."""
        if self.geo:
            node = self.new("GeometryNodeImageTexture", interpolation="Closest", extension="REPEAT")
            node.inputs["Image"].default_value = img
        else:
            node = self.new("ShaderNodeTexImage", interpolation="Closest", extension="REPEAT", image=img)
        self.put(node.inputs["Vector"], vector)
        return (node.outputs["Color"], node.outputs["Alpha"]) if alpha else node.outputs["Color"]

    def texel(self, coord, size: int):
        """Texel j0 = floor(coord N) of an N-texel row, for a coordinate already shifted by -1/(2N):
        -> (fraction t, centre (j0 + 1/2) / N).  Reading at the centre keeps a GPU's fixed-point
        nearest-texel rounding away from texel edges."""
        v = self.math("MULTIPLY", coord, float(size))
        j0 = self.math("FLOOR", v)
        return self.math("SUBTRACT", v, j0), self.math("MULTIPLY_ADD", j0, float(_F(1.0 / size)), float(_F(0.5 / size)))

    def lerp(self, img, t, where):
        """Linear interpolation T + t dT from the packed image (R, G = T; B, A = dT; :func:`ensure_table_image`)
        read once at ``where`` -> vector (re, im, 0)."""
        color, alpha = self.image(img, where, alpha=True)
        rgb = self.separate(color)
        return self.combine(self.math("MULTIPLY_ADD", rgb[2], t, rgb[0]), self.math("MULTIPLY_ADD", alpha, t, rgb[1]),
                            0.0)


def new_group(name: str, tree_type: str, inputs, outputs) -> bpy.types.NodeTree:
    tree = bpy.data.node_groups.new(name, tree_type)
    for nm, st, default in inputs:
        s = tree.interface.new_socket(nm, in_out="INPUT", socket_type=st)
        if default is not None:
            s.default_value = default
    for nm, st in outputs:
        tree.interface.new_socket(nm, in_out="OUTPUT", socket_type=st)
    return tree


# -- one stratum -----------------------------------------------------------------

_STRATUM_INPUTS = (("Sum", "NodeSocketVector", None), ("Position", "NodeSocketVector", None),
                   ("W", "NodeSocketFloat", None), ("Shift", "NodeSocketFloat", None))


def _direction(b: NodeBuilder, u, dim: int, full: bool, g) -> tuple:
    """map_directions (backend.wavenoise.directions) for a cap domain: u sockets (dim-1) -> (vec3, w)."""
    u = list(u)
    sign = None
    if full:  # the last u coordinate picks the hemisphere
        last = b.math("MULTIPLY", u[-1], 2.0)
        below = b.math("LESS_THAN", last, 1.0)               # 1 when last < 1
        flip = b.math("SUBTRACT", 1.0, below)
        sign = b.math("MULTIPLY_ADD", below, 2.0, -1.0)      # +1 / -1
        u[-1] = b.math("SUBTRACT", last, flip)
    w = None
    if dim == 2:
        t = b.math("MULTIPLY", g["Spread"], b.math("MULTIPLY_ADD", u[0], 2.0, -1.0))
        vec = b.combine(b.math("SINE", t), b.math("COSINE", t), 0.0)
    elif dim == 3:
        phi = b.math("MULTIPLY", u[0], float(_F(2.0 * np.pi)))
        ct = b.math("MULTIPLY_ADD", u[1], -g["Cap"], 1.0)
        st = b.math("SQRT", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", ct, ct)))  # SQRT is 0 below 0
        vec = b.combine(b.math("MULTIPLY", st, b.math("COSINE", phi)), b.math("MULTIPLY", st, b.math("SINE", phi)), ct)
    else:
        phi = b.math("MULTIPLY", u[0], float(_F(2.0 * np.pi)))
        ct = b.math("MULTIPLY_ADD", u[1], 2.0, -1.0)
        st = b.math("SQRT", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", ct, ct)))
        # psi - sin psi cos psi = u2 (sigma - sin sigma cos sigma): safeguarded Newton (psi_inverse)
        c = b.math("MULTIPLY", u[2], g["Cap"])
        psi = b.math("MINIMUM", b.math("POWER", b.math("MULTIPLY", c, 1.5), float(_F(1.0 / 3.0))), g["Spread"])
        for _ in range(backend.wavenoise.directions.NEWTON_STEPS):
            sp = b.math("SINE", psi)
            gv = b.math("SUBTRACT", b.math("SUBTRACT", psi, b.math("MULTIPLY", sp, b.math("COSINE", psi))), c)
            dg = b.math("ADD", b.math("MULTIPLY", 2.0, b.math("MULTIPLY", sp, sp)), 1e-6)
            psi = b.math("MINIMUM", b.math("MAXIMUM", b.math("SUBTRACT", psi, b.math("DIVIDE", gv, dg)), 0.0),
                         g["Spread"])
        sp = b.math("SINE", psi)
        sst = b.math("MULTIPLY", sp, st)
        vec = b.combine(b.math("MULTIPLY", sst, b.math("COSINE", phi)), b.math("MULTIPLY", sst, b.math("SINE", phi)),
                        b.math("MULTIPLY", sp, ct))
        w = b.math("COSINE", psi)
    if g["Mirror Scale"] != 0.0:  # Householder reflection of e_last onto the cap axis
        proj = b.vmath("DOT_PRODUCT", vec, g["Mirror"])
        if w is not None:
            proj = b.math("ADD", proj, b.math("MULTIPLY", w, g["Mirror W"]))
        m = b.math("MULTIPLY", g["Mirror Scale"], proj)
        vec = b.vmath("SUBTRACT", vec, b.vmath("SCALE", g["Mirror"], scale=m))
        if w is not None:
            w = b.math("SUBTRACT", w, b.math("MULTIPLY", m, g["Mirror W"]))
    if sign is not None:
        vec = b.vmath("SCALE", vec, scale=sign)
        if w is not None:
            w = b.math("MULTIPLY", w, sign)
    return vec, w


def _stratum_group(name: str, tree_type: str, dim: int, full: bool, img: bpy.types.Image, rows: int,
                   mode: str, consts: dict) -> bpy.types.NodeTree:
    """Sub-group for one stratum: Sum + amp (w0 T0 + w1 T1) as a vector (re, im, 0).

    The stratum's constants (``consts``, from :func:`stratum_constants`) are
    written into the nodes' sockets, not passed as group inputs: Cycles' SVM
    compiler would load every constant group input of every stratum onto its
    255-float stack before the first wave.  The position is offset by
    (Sum - Sum), exactly zero: that data dependency makes the compiler finish
    stratum k before it starts stratum k+1.
    """
    tree = new_group(name, tree_type, _STRATUM_INPUTS, (("Sum", "NodeSocketVector"),))
    b = NodeBuilder(tree)
    gi = b.new("NodeGroupInput")
    go = b.new("NodeGroupOutput")
    tuned = {k: (Tuned(k, v) if k in TUNED and v is not None else v) for k, v in consts.items()}
    b.put(go.inputs["Sum"], _stratum_nodes(b, {s.name: s for s in gi.outputs if s.name}, dim, full, img, rows,
                                           mode, tuned))
    tree[TUNED_KEY] = json.dumps(b.tuned)
    tree[SHAPE_KEY] = _stratum_shape(consts)
    return tree


def copy_or_build(built: dict, shape: str, name: str, values: dict, build) -> bpy.types.NodeTree:
    """A sub-group named ``name``: a copy of the one of its ``shape`` in ``built`` ({shape: sub-group}) with its
    tuned constants set to ``values`` (:func:`retune_tree`), or ``build()`` (then put in ``built``).  Blender copies
    a tree in one call; built node by node, a 4D stratum of the Wave Noise node takes about 0.17 s."""
    first = built.get(shape)
    if first is not None:
        sub = first.copy()
        sub.name = name
        if retune_tree(sub, values):
            return sub
        bpy.data.node_groups.remove(sub)
    built[shape] = build()
    return built[shape]


def retune_tree(tree: bpy.types.NodeTree, values: dict) -> bool:
    """Write ``values`` ({name: constant}) into the sockets where ``tree``'s builder put its :class:`Tuned`
    constants; False where the tree holds no such record or was edited by hand (a node renamed or removed)."""
    try:
        for path, name in json.loads(tree[TUNED_KEY]):
            _put(tree, path, values[name])
    except (ValueError, KeyError, IndexError, TypeError, AttributeError):
        return False
    return True


def _new_stratum(built: dict, shape: str, name: str, tree_type: str, dim: int, full: bool, img: bpy.types.Image,
                 rows: int, mode: str, consts: dict) -> bpy.types.NodeTree:
    """A stratum's sub-group, copied from one of its ``shape`` (:func:`_stratum_shape`) built here
    (:func:`copy_or_build`)."""
    return copy_or_build(built, shape, name, consts,
                         lambda: _stratum_group(name, tree_type, dim, full, img, rows, mode, consts))


def _stratum_nodes(b: NodeBuilder, ins: dict, dim: int, full: bool, img: bpy.types.Image, rows: int, mode: str, consts: dict):
    """Nodes of one stratum added through ``b``; ins: sockets Sum, Position, W, Shift -> new Sum socket.

    img: the packed table image of :func:`ensure_table_image`; Shift carries
    v t + L / (2 N), so the coordinate below is already half a texel early.

    Per slice one White Noise node gives (zeta, jitter 0, jitter 1) (backend.wavenoise.wave
    slice_records); one vector multiply-add maps them into the stratum's box.
    """
    g = dict(consts)
    g.update(ins)
    x = b.vmath("ADD", g["Position"], b.vmath("SUBTRACT", g["Sum"], g["Sum"]))
    # slice coordinate p = x . s_k + o_k (Alg. 1); s_k is pre-divided by the slice width
    p = b.vmath("DOT_PRODUCT", x, g["Slice Dir"])
    if dim == 4:
        p = b.math("ADD", p, b.math("MULTIPLY", g["W"], g["Slice Dir W"]))
    p = b.math("ADD", p, g["Slice Offset"])
    n0 = b.math("ADD", b.math("FLOOR", p), 0.0)
    f = b.math("SUBTRACT", p, n0)
    n1 = b.math("ADD", n0, 1.0)
    k, seed = g["k"], g["Seed"]
    lo3, size3 = g["Box Lo 3"], g["Box Size 3"]
    waves = []
    for side, n in enumerate((n0, n1)):
        # (zeta, u0, u1) = (r, lo0 + size0 g, lo1 + size1 b) of node A
        # Cycles' SVM stack, in a Bump of the noise at the most directions the node offers (2D 64, 4D 32), holds
        # no unread output: in 2D zeta is the Value (r x 1 + 0), in 4D the Values are read by b.both; 3D fits
        color, value = b.white(k, n, STREAM["slice_a"], seed)
        zu = b.vmath("MULTIPLY_ADD", b.both(color, value) if dim == 4 else color, size3, c=lo3)
        # a Separate XYZ with an unlinked output would hold that float on the SVM stack for good
        if dim == 2:
            zeta, uu = value, [b.channel(zu, 1)]
        else:
            zeta, *uu = b.separate(zu)
        if side == 0:  # border ramp of slice n0: slpos = SLPOS_MIN + SLPOS_RANGE fract(16 zeta_0)
            frac = b.math("FRACT", b.math("MULTIPLY", zeta, 16.0))
            slpos = b.math("MULTIPLY_ADD", frac, backend.wavenoise.wave.SLPOS_RANGE, backend.wavenoise.wave.SLPOS_MIN)
            u = b.math("MULTIPLY_ADD", b.math("SUBTRACT", f, slpos), 0.5 / backend.wavenoise.wave.BLEND_HALF_WIDTH, 0.5)
        if dim == 4:
            jb = b.channel(b.both(*b.white(k, n, STREAM["slice_b"], seed)), 0)
            uu.append(b.math("MULTIPLY_ADD", jb, g["Box Size W"], g["Box Lo W"]))
        omega, om_w = _direction(b, uu, dim, full, g)
        dot = b.vmath("DOT_PRODUCT", x, omega)
        if om_w is not None:
            dot = b.math("ADD", dot, b.math("MULTIPLY", g["W"], om_w))
        coord = b.math("MULTIPLY_ADD", b.math("SUBTRACT", dot, g["Shift"]), g["Inv Period"], zeta)
        t, centre = b.texel(coord, g["Table Size"])
        if mode == "single":  # a one-row image: a float Vector (c, c, c) reads T(c)
            waves.append(b.lerp(img, t, centre))
        else:  # per-axis tables, interpolated by omega_a^2 (Fig. 5 left)
            # a Separate XYZ's unread z (2D) would hold a float of the SVM stack per wave: 2D, 64 directions overflowed
            comps = b.separate(omega) if rows >= 3 else [b.channel(omega, a) for a in range(rows)]
            acc = None
            for a in range(rows):
                wa = om_w if a == 3 else comps[a]
                ta = b.vmath("SCALE", b.lerp(img, t, b.combine(centre, (a + 0.5) / rows, 0.0)),
                             scale=b.math("MULTIPLY", wa, wa))
                acc = ta if acc is None else b.vmath("ADD", acc, ta)
            waves.append(acc)
    # s = smoothstep(u) pi/2; Map Range clamps u to [0, 1]
    mr = b.new("ShaderNodeMapRange", data_type="FLOAT", interpolation_type="SMOOTHSTEP", clamp=False)
    b.put(mr.inputs["Value"], u)
    for name, v in (("From Min", 0.0), ("From Max", 1.0), ("To Min", 0.0), ("To Max", float(_F(np.pi / 2)))):
        b.put(mr.inputs[name], v)
    s = mr.outputs["Result"]
    w0, w1 = b.math("COSINE", s), b.math("SINE", s)
    if g["Amplitude"] is not None:
        w0, w1 = b.math("MULTIPLY", w0, g["Amplitude"]), b.math("MULTIPLY", w1, g["Amplitude"])
    out = b.vmath("MULTIPLY_ADD", waves[0], w0, c=g["Sum"])
    return b.vmath("MULTIPLY_ADD", waves[1], w1, c=out)


# -- the whole group ------------------------------------------------------------------

def clear_tree(tree: bpy.types.NodeTree) -> None:
    """Remove every node of ``tree``, and the sub-groups left without a user."""
    for n in list(tree.nodes):
        if n.bl_idname == "ShaderNodeGroup" or n.bl_idname == "GeometryNodeGroup":
            sub = n.node_tree
            tree.nodes.remove(n)
            if sub is not None and sub.users == 0:
                bpy.data.node_groups.remove(sub)
        else:
            tree.nodes.remove(n)


def describe(tree: bpy.types.NodeTree, tips: dict = TIPS) -> None:
    """Put ``tips`` on the group's inputs and outputs of those names: the tooltips of its sockets, as Blender's
    own texture nodes have (a group saved without them gets them when it is rebuilt)."""
    for item in tree.interface.items_tree:
        if getattr(item, "item_type", "") == "SOCKET" and item.name in tips:
            item.description = tips[item.name]


def new_wave_tree(name: str = "Wave Noise", tree_type: str = "ShaderNodeTree") -> bpy.types.NodeTree:
    """An empty group with the Wave Noise interface (INPUTS in, OUTPUTS out), ready for build_wave_group."""
    tree = new_group(name, tree_type, INPUTS, tuple((o, "NodeSocketFloat") for o in OUTPUTS))
    tree.interface.items_tree["Scale"].min_value = -1000.0
    describe(tree)
    return tree


def add_wave_node(node_tree: bpy.types.NodeTree, group: bpy.types.NodeTree, location=(0.0, 0.0)):
    """Add a group node using ``group`` to ``node_tree`` -> the node.

    In shader trees a Texture Coordinate node's Object output feeds its Vector,
    so the noise is a solid texture of the object's local space.
    """
    kind = "GeometryNodeGroup" if node_tree.bl_idname == "GeometryNodeTree" else "ShaderNodeGroup"
    node = node_tree.nodes.new(kind)
    node.node_tree = group
    node.location = location
    if kind == "ShaderNodeGroup":
        tc = node_tree.nodes.new("ShaderNodeTexCoord")
        tc.location = (location[0] - 220.0, location[1])
        node_tree.links.new(tc.outputs["Object"], node.inputs["Vector"])
    return node


def group_io(b: NodeBuilder) -> tuple:
    """Group input and output nodes, and the scaled inputs every OmniNoise group starts from:
    (group input, group output, Vector x Scale, W x Scale)."""
    gi = b.new("NodeGroupInput")
    go = b.new("NodeGroupOutput")
    x = b.vmath("SCALE", gi.outputs["Vector"], scale=gi.outputs["Scale"])
    w = b.math("MULTIPLY", gi.outputs["W"], gi.outputs["Scale"])
    return gi, go, x, w


def check_form(implementation: str, tree_type: str) -> None:
    """SettingError unless ``implementation`` is one of :data:`IMPLEMENTATIONS` that a tree of ``tree_type`` can
    hold (the OSL form: shader trees only)."""
    if implementation not in IMPLEMENTATIONS:
        raise backend.SettingError("implementation", f"unknown {implementation!r}; choose nodes or osl")
    if implementation == "osl" and tree_type != "ShaderNodeTree":
        raise backend.SettingError("implementation",
                                   "the OSL form is for shader trees; Geometry Nodes use the node form")


def build_wave_group(settings, tree_type: str = "ShaderNodeTree", tree: bpy.types.NodeTree | None = None,
                     name: str = "Wave Noise", implementation: str = "nodes") -> bpy.types.NodeTree:
    """Build (or rebuild in place) the Wave Noise group for ``settings`` (a backend WaveSettings).

    tree_type: 'ShaderNodeTree' or 'GeometryNodeTree'.  implementation: 'nodes' (Blender's
    math nodes: every engine and device) or 'osl' (one compiled OSL script,
    :mod:`.wave_osl`: Cycles with Open Shading Language only, shader trees only).
    Returns the group tree; its interface (INPUTS, OUTPUTS) is the same for every setting and form.
    """
    check_form(implementation, tree.bl_idname if tree is not None else tree_type)
    if settings.cellular != "none":
        raise backend.SettingError("cellular", "use the Wave Cellular node for cellular variants")
    if settings.example is not None or settings.transition_to is not None:
        raise backend.SettingError("example", "by-example and transition noises are bake-only")
    noise = backend.compile_noise(settings)
    table = noise.table
    if table.mode not in ("single", "axes"):
        raise backend.SettingError("anisotropy", f"table mode {table.mode!r} has no node form")
    amps = noise.dirs.amp
    uniform = bool(np.all(amps == amps[0]))  # then one scale after the sum replaces 2 K multiplies
    strata = [_node_constants(stratum_constants(noise, k)) for k in range(noise.dirs.count)]
    if uniform:
        for consts in strata:
            consts["Amplitude"] = None
    # v t (Eq. 9) plus half a texel in world units: the lookup reads texel floor(c N - 1/2)
    top = {"Speed": float(_F(noise.speed)), "Half Texel": float(_F(0.5 * noise.table.period / table.size)),
           "Amplitude": float(amps[0])}
    full = any(d.full for d in noise.dirs.domains)
    own = [noise.dim, full, table.mode, table.values.shape[0], uniform]
    shapes = [_stratum_shape(c) for c in strata]
    shape = json.dumps([own, shapes])
    img = ensure_table_image(table.values) if implementation == "nodes" else None
    if tree is not None:
        describe(tree)
    if tree is not None and implementation == "nodes" and _retune(tree, shape, shapes, strata, top, img):
        tree[SETTINGS_KEY] = settings_to_json(settings)
        return tree
    if tree is None:
        tree = new_wave_tree(name, tree_type)
    else:
        clear_tree(tree)
    tree[SETTINGS_KEY] = settings_to_json(settings)
    tree[IMPLEMENTATION_KEY] = implementation
    for key in (SHAPE_KEY, TUNED_KEY):
        if key in tree:
            del tree[key]
    if implementation == "osl":
        _build_osl(tree, noise)
        return tree
    dim = noise.dim
    b = NodeBuilder(tree)
    gi, go, x, w = group_io(b)
    shift = b.math("MULTIPLY_ADD", gi.outputs["Time"], Tuned("Speed", top["Speed"]),
                   Tuned("Half Texel", top["Half Texel"]))
    group_kind = "GeometryNodeGroup" if b.geo else "ShaderNodeGroup"
    acc = (0.0, 0.0, 0.0)
    built = {}              # {stratum shape: a sub-group built here}, copied and retuned for the next of that shape
    for k, consts in enumerate(strata):
        node = b.new(group_kind)
        node.node_tree = _new_stratum(built, shapes[k], f".{tree.name} direction {k + 1}", tree.bl_idname, dim,
                                      full, img, table.values.shape[0], table.mode, consts)
        node.label = f"Direction {k + 1}"
        b.put(node.inputs["Sum"], acc)
        b.put(node.inputs["Position"], x)
        b.put(node.inputs["W"], w)
        b.put(node.inputs["Shift"], shift)
        acc = node.outputs["Sum"]
    if uniform:
        acc = b.vmath("SCALE", acc, scale=Tuned("Amplitude", top["Amplitude"]))
    re, im, _ = b.separate(acc)
    b.put(go.inputs["Value"], re)
    b.put(go.inputs["Imaginary"], im)
    b.put(go.inputs["Modulus"], b.vmath("LENGTH", acc))
    b.put(go.inputs["Phase"], b.math("ARCTAN2", im, re))
    tree[TUNED_KEY] = json.dumps(b.tuned)
    tree[SHAPE_KEY] = shape
    return tree


def _put(tree: bpy.types.NodeTree, path: str, value) -> None:
    tree.path_resolve(path).default_value = tuple(float(c) for c in value) if isinstance(value, tuple) \
        else float(value)


def _retune_stratum(sub: bpy.types.NodeTree, shape: str, consts: dict, img: bpy.types.Image) -> bool:
    """A stratum's sub-group given ``consts`` (of the stratum shape ``shape``, :func:`_stratum_shape`) and the
    table image in place; False where it was built from other constants than those it retunes, not built so, or
    edited by hand (the caller then builds it again)."""
    if sub.get(SHAPE_KEY) != shape or not retune_tree(sub, consts):
        return False
    for n in sub.nodes:
        if n.bl_idname == "ShaderNodeTexImage":
            n.image = img
        elif n.bl_idname == "GeometryNodeImageTexture":
            n.inputs["Image"].default_value = img
    return True


def _sub_groups(tree: bpy.types.NodeTree) -> list:
    """The trees of ``tree``'s group nodes (a node-form group's strata), in order; None for a node without one."""
    return [n.node_tree for n in tree.nodes if n.bl_idname in ("ShaderNodeGroup", "GeometryNodeGroup")]


def _own(sub) -> bool:
    """Whether a stratum's sub-group was built so and belongs to its group alone: a group copied in Blender (a
    node's group made single user) shares its sub-groups with the original, which retuning them would change."""
    return sub is not None and TUNED_KEY in sub and sub.users == 1


def _retune(tree: bpy.types.NodeTree, shape: str, shapes: list, strata: list, top: dict,
            img: bpy.types.Image) -> bool:
    """A node-form group of the same ``shape`` given its new constants (``strata``: each stratum's, of the stratum
    shapes ``shapes``; ``top``: the group's own) and table image in place; False where its shape differs, it was
    not built so or it was edited by hand (the caller then builds it again)."""
    if tree.get(IMPLEMENTATION_KEY) != "nodes" or tree.get(SHAPE_KEY) != shape:
        return False
    subs = _sub_groups(tree)
    if len(subs) != len(strata) or not all(_own(t) for t in subs):
        return False
    if not retune_tree(tree, top):          # a group edited by hand is built again
        return False
    return all(_retune_stratum(*args, img) for args in zip(subs, shapes, strata))


def _build_osl(tree: bpy.types.NodeTree, noise) -> None:
    """The OSL form: Vector x Scale, W x Scale and Time into one Script node (:func:`.wave_osl.script_node`)."""
    from .wave_osl import script_node

    b = NodeBuilder(tree)
    gi, go, x, w = group_io(b)
    try:
        node = script_node(tree, noise, "Wave Noise (OSL)")
    except backend.SettingError:
        clear_tree(tree)
        raise
    tree.links.new(x, node.inputs["Position"])
    tree.links.new(w, node.inputs["W"])
    tree.links.new(gi.outputs["Time"], node.inputs["Time"])
    for o in OUTPUTS:
        tree.links.new(node.outputs[o], go.inputs[o])
