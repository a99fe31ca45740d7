"""Solid textures from photos (Henzler et al. 2020) in Blender: preview, and bakes onto the active object.

Settings live on the scene (``Scene.omninoise_solid``).  The texture comes from
a shipped single-exemplar model (``models/solid/<name>``), from an exemplar
the space model was trained on, or from any image datablock, which the space
model encodes into a texture code.  Bake targets:

UV_IMAGE         each texel of the active UV map is evaluated at the 3D surface
                 point it maps to (``backend.solid.surface``), so the UV layout
                 adds no seams; a margin of extrapolated positions pads islands
COLOR_ATTRIBUTE  a float colour attribute on the mesh's vertices
VOLUME           an OpenVDB file (``color`` + ``density`` grids) over the object's
                 bounds, loaded as a Volume object

From an image exemplar, Method chooses the texture: the texture-space model's (Neural Texture) or random phase
noise of the image lifted to a solid (Spectral Solid, ``backend.solid.spectral_solid``: its spectrum and colours on
every cut, its periodic part upright on walls, no stones; the same request as ``omninoise solid --method
spectral``), previewed and baked to the same targets.

From an image exemplar, Tileable Image synthesises a seamless 2D image instead (``backend.solid.synthesis``,
texture optimisation: the photo's pieces rearranged), stored as the image datablock ``<Name> Tile`` for Image
Texture nodes; the same request as ``omninoise solid --method synthesis``.  Project Tile onto Object gives the
active mesh a material that shows it without UVs: box projection from object or world positions, at the photo's
pixel scale times Scale (a surface look, not a solid: a cut through the mesh shows the same projection).

Positions are object-local by default (the texture moves with the object) or
world.  Everything heavy (encoding, rasterising, evaluating, writing) runs on
a :mod:`.tasks` worker with progress and cancel; Blender data is read before
and written after on the main thread.  A preview, a bake and a node group of the
same photo and settings share one fit or encoding (:func:`remembered`).
"""
from __future__ import annotations

import collections
import json
import os
import threading

import bmesh
import bpy
import numpy as np
from bl_operators.presets import AddPresetBase
from bl_ui.utils import PresetPanel
from bpy_extras.io_utils import ExportHelper, ImportHelper
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from . import tasks
from .. import backend
from .compat import ensure_node_tree
from .bake_ui import SaveJobOperator, draw_progress
from .common import (Sidebar, backend_module as _mod, image_clipped_notes, image_srgb, measured_reads,
                     solid_models_folder, store_srgb_image)
from .tasks import TaskOperator
from .preferences import threads
from .presets import SOLID_VALUES, SUBDIRS

__all__ = ["models_dir", "load_model", "panel_request", "tile_request", "texture", "remembered", "tile_repeats",
           "volume_target", "job_spec", "attach", "detach"]

#: another folder of solid texture models than the shipped one (tests point it elsewhere); None: the shipped models
MODELS_DIR: str | None = None
_MODELS = {}   # folder path -> model, or the ModelError it raised (an altered folder is read once)


def models_dir() -> str:
    """The folder the panel's solid texture models come from."""
    return MODELS_DIR or solid_models_folder()


def _models() -> dict:
    """{folder name: model} under :func:`models_dir`, each loaded once (never at register time)."""
    return _mod("solid.model").load_models(models_dir(), threads(), _MODELS)


def load_model(name: str):
    """A model folder under :func:`models_dir` by name (ModelError if it is missing or altered)."""
    m = _models().get(name)
    if m is None:
        err = _MODELS.get(os.path.join(models_dir(), name))
        raise err if isinstance(err, Exception) else \
            _mod("onnx_models").ModelError(f"no solid texture model {name!r} in {models_dir()}")
    return m


def _catalogue() -> list:
    """(identifier, label, description) of every shipped texture: single 3D models, then space exemplars."""
    models = _models()
    items = [(f"single:{name}", m.exemplar_label.replace("_", " ").title(),
              f"Fitted to the exemplar {os.path.basename(m.config['exemplars'][0])} ({name})")
             for name, m in models.items() if m.mode == "single" and m.dim == 3]
    items += [(f"space:{name}:{ex}", f"{ex.replace('_', ' ').title()} (space)",
               f"The {ex} exemplar's code in the texture space {name}")
              for name, m in models.items() if m.mode == "space" and m.dim == 3 for ex in sorted(m.codes)]
    return items


_ITEMS_CACHE = []


def _texture_items(self, context):
    try:
        _ITEMS_CACHE[:] = _catalogue() or [("NONE", "No models", f"No solid texture models in {models_dir()}")]
    except backend.SettingError as exc:         # OMNINOISE_MODELS names no folder: the menu says so
        _ITEMS_CACHE[:] = [("NONE", "No models", str(exc))]
    return _ITEMS_CACHE   # Blender needs the strings kept alive


def _space_model_name():
    return next((name for name, m in _models().items() if m.mode == "space"), None)


class OMNINOISE_PG_solid(bpy.types.PropertyGroup):
    source: EnumProperty(name="Source", description="Start from a ready texture, from a photo or from a procedural "
                                                    "solid's node group", items=[
        ("SHIPPED", "Shipped", "A texture that ships with OmniNoise"),
        ("IMAGE", "Image", "Any image: the texture-space model encodes it into a texture code"),
        ("NODE_GROUP", "Node Group", "The active object's procedural node group as its inputs are set: preview and "
                                     "bake what it renders, or save it for the command line and job files")],
        default="SHIPPED")
    texture: EnumProperty(name="Texture", items=_texture_items, description="Which ready texture to use")
    method: EnumProperty(name="Method", description="How the photo becomes a solid texture", items=[
        ("NEURAL", "Neural Texture", "A network trained on many materials draws a solid that looks like the photo "
                                     "(stones, grains, speckles)"),
        ("SPECTRAL", "Spectral Solid", "The photo's colors and feature sizes on every cut, but no separate stones: "
                                       "often closer for rock, sand and soil; repeats every 128 photo pixels; about "
                                       "6 s to draw"),
        ("PROCEDURAL", "Procedural Solid", "Rings, layers, cells or bricks fitted to the photo: structure that runs "
                                           "on through the object (wood, veins, stones, courses); also a live node "
                                           "group; about 12 s to fit"),
        ("AUTO", "Auto", "The procedural solid where it is closer to the photo than the neural texture and keeps "
                         "the photo's structure (its grain's direction, its grid) as well, else the neural texture")],
        default="NEURAL")
    families: EnumProperty(name="Kinds", options={"ENUM_FLAG"},
                           description="The kinds of procedural solid the fit tries", items=[
        ("RINGS", "Rings", "Growth rings around an axis: ring-cut wood, knots"),
        ("LAYERS", "Layers", "A profile along a bent direction: marble veins, strata, straight grain"),
        ("CELLS", "Cells", "Stones, pebbles, flakes and spots with gaps between them"),
        ("BONDS", "Bonds", "Bricks and tiles in courses (running, stack and raking bonds), as long, high and "
                           "shifted as the photo's. Pick it alone for a brick wall or a tile grid: with the other "
                           "kinds the fit often draws stones or blotches there"),
        ("HERRINGBONE", "Herringbone", "Bricks laid in a herringbone, straight or turned 45 degrees (tried only "
                                       "when picked)")],
                           default={"RINGS", "LAYERS", "CELLS", "BONDS"})
    image: PointerProperty(name="Exemplar", type=bpy.types.Image,
                           description="A photo of the material (at least 128 px; a large one is read in at most 8 x 8 crops)")
    refine: IntProperty(name="Refine Steps", default=0, min=0, soft_max=200,
                        description="Search steps that bring the texture closer to the photo (about 0.1 s a step; "
                                    "0 is usually enough)")
    periodic: BoolProperty(name="Periodic Part", default=True,
                           description="Keep the photo's regular pattern (brick courses, plank seams, weaves) on top "
                                       "of the texture: upright on walls, seen from above on floors")
    gaussian: BoolProperty(name="Fine Detail", default=True,
                           description="Mix in fine detail drawn from the photo's own frequencies where that brings "
                                       "the texture closer to the photo (rock faces, sand, wood grain)")
    rest: EnumProperty(name="Detail Direction", description="Whether the fine detail has a direction", items=[
        ("auto", "Auto", "The check chooses: the upright rest is offered for layered images"),
        ("isotropic", "Isotropic", "The same in every direction: no layers on any face"),
        ("upright", "Upright", "The image's layers, grain or strata kept on faces normal to X and to Y (walls, "
                               "cliffs); floors show only its horizontal detail")], default="auto")
    scale: FloatProperty(name="Scale", default=1.0, min=1e-4, soft_max=100.0,
                         description="Texture units per Blender unit: larger means smaller features")
    seed: IntProperty(name="Seed", default=0, min=0, description="Another seed gives another texture of the same kind")
    coords: EnumProperty(name="Coordinates", description="Which positions the texture is read at", items=[
        ("OBJECT", "Object", "Object-local positions: the texture moves with the object"),
        ("WORLD", "World", "World positions: objects share one block of material")], default="OBJECT")
    target: EnumProperty(name="Bake To", description="What the bake writes onto the active object", items=[
        ("UV_IMAGE", "UV Image", "An image over the active UV map, each pixel colored at its 3D surface point"),
        ("COLOR_ATTRIBUTE", "Color Attribute", "A color attribute on the mesh vertices"),
        ("VOLUME", "Volume", "An OpenVDB volume over the object's bounds (color and density grids)")],
        default="UV_IMAGE")
    size: IntProperty(name="Image Size", default=1024, min=8, soft_max=8192,
                      description="Width and height of the baked UV image in pixels")
    margin: IntProperty(name="Margin", default=4, min=0, max=64, description="Texels padded past each UV island")
    voxels: IntProperty(name="Voxels", default=128, min=4, soft_max=512, description="Voxels along the longest side")
    tile: IntProperty(name="Tile Size", default=256, min=32, max=1024, step=4,
                      description="Width and height of the tileable image in pixels (a multiple of 4; powers of "
                                  "two keep large structures whole; 1024 takes about 16 times as long as 256)")
    periodic_info: StringProperty(name="Pattern Found", default="", options={"SKIP_SAVE"},
                                  description="What the last preview found of the photo's regular pattern")
    gaussian_info: StringProperty(name="Fine Detail Found", default="", options={"SKIP_SAVE"},
                                  description="How much fine detail the last preview mixed in")
    grid_info: StringProperty(name="Grid Found", default="", options={"SKIP_SAVE"},
                              description="Whether the last procedural fit's photo repeats as a grid (bricks, tiles), "
                                          "where Bonds alone lays it in courses")
    name: StringProperty(name="Name", default="Solid Texture",
                         description="Name of the baked image, color attribute, volume and material")
    folder: StringProperty(name="Folder", subtype="DIR_PATH", default="//omninoise_bakes",
                           description="Where volumes are written ('//' = beside the .blend)")


def panel_request(p):
    """The panel's :class:`backend.solid.request.SolidRequest`: the one request of the command line and job
    files, built from the properties (an image's pixels are read here, on the main thread: bpy data)."""
    SolidRequest = _mod("solid.request").SolidRequest
    if p.source == "NODE_GROUP":
        from .procedural_nodes import node_field, procedural_node

        return SolidRequest(exemplar=node_field(procedural_node(bpy.context.active_object)),
                            method="procedural").check()
    if p.source == "IMAGE":
        if p.image is None:
            raise backend.SettingError("image", "pick an exemplar image (or switch Source to Shipped)")
        if p.method == "SPECTRAL":
            return SolidRequest(exemplar=image_srgb(p.image, "image"), seed=int(p.seed), periodic=bool(p.periodic),
                                method="spectral").check()
        kinds = tuple(k for k in _mod("solid.procedural.field").KINDS if k.upper() in p.families)
        if not kinds and p.method in ("PROCEDURAL", "AUTO"):
            raise backend.SettingError("families", "pick at least one kind of procedural solid")
        if p.method == "PROCEDURAL":
            return SolidRequest(exemplar=image_srgb(p.image, "image"), seed=int(p.seed), method="procedural",
                                families=kinds).check()
        name = _space_model_name()
        if name is None:
            raise backend.SettingError("model", f"no texture-space model in {models_dir()} to encode images")
        return SolidRequest(os.path.join(models_dir(), name), image_srgb(p.image, "image"), refine=int(p.refine),
                            seed=int(p.seed), periodic=bool(p.periodic), gaussian=bool(p.gaussian),
                            rest=str(p.rest), method="auto" if p.method == "AUTO" else "neural",
                            **(dict(families=kinds) if p.method == "AUTO" else {})).check()
    ident = p.texture
    if ident == "NONE" or ":" not in ident:
        raise backend.SettingError("texture", f"no solid texture models in {models_dir()}")
    parts = ident.split(":")
    exemplar = None if parts[0] == "single" else parts[2]
    return SolidRequest(os.path.join(models_dir(), parts[1]), exemplar, seed=int(p.seed)).check()


def tile_request(p):
    """The panel's request for a tileable image synthesised from its exemplar image (method "synthesis",
    backend/solid/synthesis.py): the same request as ``omninoise solid --method synthesis`` and job files."""
    if p.source != "IMAGE" or p.image is None:
        raise backend.SettingError("image", "a tileable image is synthesised from an exemplar image: set Source to "
                                            "Image and pick one")
    return _mod("solid.request").SolidRequest(exemplar=image_srgb(p.image, "image"), seed=int(p.seed),
                                              method="synthesis", tile=int(p.tile)).check()


#: the panel's last textures (fitted or drawn solids, auto's choices, codes) by their request's key, at most KEEP:
#: a preview, a bake and a node group of one photo and the same settings fit or encode it once
_DONE = collections.OrderedDict()
_DONE_KEEP = 4
_DONE_LOCK = threading.Lock()


def _memo_keys(req) -> list:
    """The keys :func:`remembered` files ``req``'s texture under: its request's key (equal settings and pixels)
    with, for the methods that read a model, its folder's path (the key names the folder alone); for method auto
    also its procedural solid's (the auto key holds that key: the pixels are hashed once)."""
    key = req.key()
    model = getattr(req, "model", None) if req.method in ("neural", "auto") else None
    keys = [json.dumps([key, None if model is None else str(model)], sort_keys=True)]
    if req.method == "auto":
        keys.append(json.dumps([key["procedural"], None], sort_keys=True))
    return keys


def _known(key: str):
    """What :func:`remembered` holds under ``key``, or None."""
    with _DONE_LOCK:
        return _DONE.get(key)


def remembered(req, make, keys: list | None = None):
    """code_fn(progress, cancel) -> ``make(progress, cancel)``, made once per request key (:func:`_memo_keys`,
    or ``keys`` where the caller has them) while it is among the last :data:`_DONE_KEEP` made; an auto choice also
    stands for its procedural solid (the same fit).  Runs on the worker; a cancelled or failed run leaves nothing."""
    keys = keys or _memo_keys(req)

    def code_fn(progress=None, cancel=None):
        with _DONE_LOCK:
            if keys[0] in _DONE:
                _DONE.move_to_end(keys[0])
                return _DONE[keys[0]]
        out = make(progress, cancel)
        with _DONE_LOCK:
            for k, v in zip(keys, (out, getattr(out, "field", None))):
                _DONE[k] = v
                _DONE.move_to_end(k)
            while len(_DONE) > _DONE_KEEP:
                _DONE.popitem(last=False)
        return out

    return code_fn


def texture(req):
    """(model, code_fn) for the panel's request (:func:`panel_request`); code_fn(progress, cancel) runs on the worker
    (it may encode an image, or draw a spectral solid, about 6 s, or fit a procedural one, about 12 s, with progress
    and cancel; each made once for the same settings: :func:`remembered`)."""
    if req.method in ("spectral", "procedural"):     # no model: the "code" is the drawn or fitted solid
        return (_mod("solid.spectral_solid").SpectralTexture(req),
                remembered(req, lambda progress=None, cancel=None: req.solid_field("", progress, cancel)))
    if req.method == "auto":         # the "code" is the choice (backend.solid.choose)
        keys = _memo_keys(req)                       # a procedural preview's fit (keys[1]) is auto's own
        return (_mod("solid.choose").AutoTexture(req),
                remembered(req, lambda progress=None, cancel=None: req.choose("", progress, field=_known(keys[1]),
                                                                             cancel=cancel),
                           keys))
    m = load_model(os.path.basename(req.model))
    return m, remembered(req, lambda progress=None, cancel=None: req.code(m, "", progress, cancel=cancel)[0])


def periodic_info(code) -> str:
    """A line for the panel: the harmonic part a code (or a spectral solid) carries (backend/solid/harmonic.py), or
    that there is none; for a procedural solid its family, and for method Auto what it chose."""
    if hasattr(code, "distances"):      # method Auto's choice (backend/solid/choose.py)
        d = code.distances
        kept = code.field.family if code.method == "procedural" else "neural texture"
        p, n = d["procedural"], d["neural"]
        return (f"Auto: {kept} (procedural {p['axes']:.0f} / {p['oblique']:.0f} / {p['structure']:.2f}, neural "
                f"{n['axes']:.0f} / {n['oblique']:.0f} / {n['structure']:.2f}: axis cuts / oblique cuts / structure)")
    if hasattr(code, "family"):         # a procedural solid (backend/solid/procedural)
        pattern = code.params.get("pattern", "courses")
        return f"Fitted: {code.family}" + ("" if pattern == "courses" else f" ({pattern})")
    h = code.harmonics
    if h is None:
        return "Pattern: none found"
    return f"Pattern: {len(h)} waves, {100 * h.share:.0f} % of the variance"


def grid_info(req) -> str:
    """A line for the panel: a suggestion of Bonds alone where a procedural fit's photo repeats as a grid (bricks,
    tiles) and other kinds are picked (backend SolidRequest.repeats_as_grid), else ""."""
    return "Repeats as a grid: try Bonds alone" if req.repeats_as_grid() else ""


def gaussian_info(code) -> str:
    """A line for the panel: the share of the rest a code's Gaussian rest carries (backend/solid/gaussian_rest.py)."""
    if not hasattr(code, "rest"):     # a spectral solid is all Gaussian, a procedural one has none: no share
        return ""
    r = code.rest
    if r is None:
        return "Fine detail: none (the texture alone is closer)"
    return f"Fine detail: {100 * r.mix:.0f} % of the variance, {r.kind}"


def _vertex_positions(me, obj, world: bool) -> np.ndarray:
    """A mesh's vertex positions, float64 (V, 3): object-local, or world through ``obj.matrix_world``."""
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3).astype(np.float64)
    if world:
        M = np.array(obj.matrix_world)
        co = co @ M[:3, :3].T + M[:3, 3]
    return co


def active_mesh(context, purpose: str):
    """The active object where it is a mesh; a SettingError naming the object, that asks to select a mesh to
    ``purpose``, where it is not."""
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        raise backend.SettingError("object", f"select a mesh to {purpose}")
    return obj


#: bytes a UV image bake holds per texel at its peak: each texel's surface point (float64), its color, the image's
#: pixels (123 measured on a plane filling a 2048² image)
UV_BAKE_BYTES = 128


def _store_vertex_colors(obj, name: str, rgb: np.ndarray) -> None:
    """Write linear ``rgb`` (V, 3) into the point color attribute ``name`` of mesh ``obj`` and make it the active
    color. In Edit Mode through the edit mesh: Blender writes the edit mesh back over the mesh when Edit Mode ends."""
    me = obj.data
    editing = obj.mode == "EDIT"
    bm = bmesh.from_edit_mesh(me) if editing else None
    count = len(bm.verts) if editing else len(me.vertices)
    if count != len(rgb):
        raise backend.SettingError("object", f"{obj.name!r} has {count} vertices, the bake was of {len(rgb)}: the "
                                             "mesh changed while it ran; bake again")
    attr = me.color_attributes.get(name)
    if attr is not None and (attr.domain != "POINT" or attr.data_type != "FLOAT_COLOR"):
        me.color_attributes.remove(attr)
        attr = None
    attr = attr or me.color_attributes.new(name, "FLOAT_COLOR", "POINT")
    me.color_attributes.active_color = attr
    rgba = np.ones((count, 4), np.float32)
    rgba[:, :3] = rgb
    if editing:
        bm = bmesh.from_edit_mesh(me)          # the attribute's new layer is a new edit mesh layout
        layer = bm.verts.layers.float_color[name]
        for v, c in zip(bm.verts, rgba.tolist()):
            v[layer] = c
        bmesh.update_edit_mesh(me)
    else:
        attr.data.foreach_set("color", rgba.ravel())
        me.update()


def _mesh_arrays(context, obj, world: bool, uv: bool):
    """Triangles of the evaluated mesh: (uv (T, 3, 2) or None, positions (T, 3, 3)) float64."""
    dg = context.evaluated_depsgraph_get()
    eo = obj.evaluated_get(dg)
    me = eo.to_mesh()
    try:
        me.calc_loop_triangles()
        T, L = len(me.loop_triangles), len(me.loops)
        if T == 0:
            raise backend.SettingError("object", f"{obj.name!r} has no faces to bake onto")
        tri = np.empty(T * 3, np.int32)
        me.loop_triangles.foreach_get("loops", tri)
        vidx = np.empty(L, np.int32)
        me.loops.foreach_get("vertex_index", vidx)
        pos = _vertex_positions(me, obj, world)[vidx[tri]].reshape(T, 3, 3)
        uvs = None
        if uv:
            layer = me.uv_layers.active
            if layer is None:
                raise backend.SettingError("uv", f"{obj.name!r} has no UV map; add one (UV > Smart UV Project) "
                                                 "or bake to a color attribute")
            a = np.empty(L * 2, np.float32)
            layer.data.foreach_get("uv", a)
            uvs = a.reshape(L, 2)[tri].reshape(T, 3, 2).astype(np.float64)
        return uvs, pos
    finally:
        eo.to_mesh_clear()


#: how far left of the Principled BSDF the node feeding its Base Color is placed (node editor units)
_BESIDE_BSDF = 320


def _material_with(obj, name: str, make_node):
    """Wire ``make_node(node_tree)``'s Color output into Base Color: the active material's Principled
    BSDF when it has one and is the file's own, else a new material ``OmniNoise <name>`` given to the object (in
    place of the active one: a material linked from a library cannot keep an edit)."""
    mat = obj.active_material
    if mat is None or mat.library is not None or mat.node_tree is None or \
            not any(n.type == "BSDF_PRINCIPLED" for n in mat.node_tree.nodes):
        mat = bpy.data.materials.get((f"OmniNoise {name}", None)) or bpy.data.materials.new(f"OmniNoise {name}")
        ensure_node_tree(mat)
        if obj.active_material is None:
            obj.data.materials.append(mat)
        else:
            obj.active_material = mat
    nt = mat.node_tree
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED") if any(
        n.type == "BSDF_PRINCIPLED" for n in nt.nodes) else nt.nodes.new("ShaderNodeBsdfPrincipled")
    node = make_node(nt)
    node.location = (bsdf.location[0] - _BESIDE_BSDF, bsdf.location[1])
    nt.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    nt.nodes.active = node
    return mat


class SolidTask(TaskOperator):
    """The Solid Texture panel's operators: the request's exemplar is the panel's Image in their errors, and a
    float Image past white or under black is reported as a warning once the work starts."""

    setting_names = {"exemplar": "image"}

    def _begin(self, context, blocking: bool):
        with measured_reads() as shares:          # the request's read of the Image measures what the warning says
            task = TaskOperator._begin(self, context, blocking)
        p = context.scene.omninoise_solid
        if task is not None and p.source == "IMAGE" and p.image is not None:
            for note in image_clipped_notes(p.image, shares.get(p.image.as_pointer())):
                self.report({"WARNING"}, f"Image {p.image.name!r}: {note}")
        return task


class OMNINOISE_OT_solid_preview(SolidTask, bpy.types.Operator):
    """Preview the solid texture: a 128 px slice through the texture (the plane y = 0 seen from the front, z up) as an image"""

    bl_idname = "omninoise.solid_preview"
    bl_label = "Preview Solid Texture"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_solid
        req = panel_request(p)
        m, code_fn = texture(req)
        seed, name = p.seed, f"{p.name} Preview"

        def work(progress, cancel):
            making, drawing = _mod("bake").split_progress(progress, 0.8)     # a fit or an encoding: seconds
            code = code_fn(making, cancel)
            making(1.0)
            img = m.image(128, code, seed, progress=drawing, cancel=cancel)
            return img, periodic_info(code), gaussian_info(code), grid_info(req)

        def done(result):
            img, info, rest, grid = result
            store_srgb_image(name, np.flipud(img)).preview_ensure()
            p.periodic_info, p.gaussian_info, p.grid_info = info, rest, grid

        return tasks.start(tasks.Task("Solid preview", work, done, None, threads()), blocking=blocking)


class OMNINOISE_OT_solid_tileable(SolidTask, bpy.types.Operator):
    """Make a seamless tileable image from the photo by rearranging its pieces (courses, planks, stones), for Image
    Texture nodes on UV-mapped surfaces"""

    bl_idname = "omninoise.solid_tileable"
    bl_label = "Make Tileable Image"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_solid
        req = tile_request(p)
        name = f"{p.name} Tile"

        def work(progress, cancel):
            return req.synthesis_field("", progress, cancel).tile    # (N, N, 3), row 0 at the bottom

        def done(tile):
            store_srgb_image(name, tile).preview_ensure()

        return tasks.start(tasks.Task("Tileable image", work, done, None, threads()), blocking=blocking)


#: how soft the seams between the box projection's three planes are (Image Texture's Blend, 0..1)
BOX_BLEND = 0.2


def tile_repeats(scale: float, tile: int) -> float:
    """How many times a tile of ``tile`` px repeats per Blender unit: ``scale`` texture units per Blender unit,
    PX_PER_UNIT photo px per texture unit (backend/solid/synthesis.py), so the tile keeps the photo's pixel scale,
    as bakes keep it."""
    return float(scale) * _mod("solid.synthesis").PX_PER_UNIT / float(tile)


def _project_tile(nt, ima, repeats: float, world: bool):
    """The Image Texture node of ``ima`` box-projected (no UVs: each face takes the plane of the axis its normal
    is nearest, blended by BOX_BLEND) from object or world positions scaled by ``repeats``, in node tree ``nt``;
    the nodes are reused when it runs again."""
    def get(kind, name):
        n = nt.nodes.get(name)
        if n is not None and n.bl_idname != kind:     # object positions before, world positions now (or back)
            nt.nodes.remove(n)
            n = None
        if n is None:
            n = nt.nodes.new(kind)
            n.name = n.label = name
        return n

    img = get("ShaderNodeTexImage", "OmniNoise Tile")
    img.image, img.projection, img.projection_blend, img.extension = ima, "BOX", BOX_BLEND, "REPEAT"
    mapping = get("ShaderNodeMapping", "OmniNoise Tile Scale")
    mapping.inputs["Scale"].default_value = (repeats, repeats, repeats)
    if world:
        src = get("ShaderNodeNewGeometry", "OmniNoise Tile Positions").outputs["Position"]
    else:
        src = get("ShaderNodeTexCoord", "OmniNoise Tile Positions").outputs["Object"]
    nt.links.new(src, mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], img.inputs["Vector"])
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    x, y = (bsdf.location[0] - _BESIDE_BSDF, bsdf.location[1]) if bsdf is not None else (0.0, 0.0)  # the image's place
    mapping.location, src.node.location = (x - 220, y), (x - 420, y)
    return img


class OMNINOISE_OT_solid_tile_material(bpy.types.Operator):
    """Show the tileable image on the active mesh without UVs: box projection (each face takes the plane of its
    nearest axis; walls show the image upright) at the exemplar's pixel scale times Scale, from object or world
    positions as Coordinates says (the plane follows the face's normal in object space: World suits objects that
    are not rotated)"""

    bl_idname = "omninoise.solid_tile_material"
    bl_label = "Project Tile onto Object"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return tasks.idle(cls)

    def execute(self, context):
        p = context.scene.omninoise_solid
        name = f"{p.name} Tile"
        ima = bpy.data.images.get(name)
        try:
            obj = active_mesh(context, "project the tile onto")
            if ima is None:
                raise backend.SettingError("tile", f"no tileable image {name!r} yet: make one with Make Tileable "
                                                   "Image first")
        except backend.SettingError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        repeats = tile_repeats(p.scale, ima.size[0])
        _material_with(obj, name, lambda nt: _project_tile(nt, ima, repeats, p.coords == "WORLD"))
        return {"FINISHED"}


class OMNINOISE_OT_solid_bake(SolidTask, bpy.types.Operator):
    """Bake the solid texture onto the active object: a UV image, a color attribute or a volume"""

    bl_idname = "omninoise.solid_bake"
    bl_label = "Bake Solid Texture"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        p = context.scene.omninoise_solid
        obj = context.active_object
        if obj is None:
            raise backend.SettingError("object", "select an object to bake onto")
        if p.target != "VOLUME" and obj.type != "MESH":
            raise backend.SettingError("object", f"{obj.name!r} is not a mesh; bake a mesh or choose Volume")
        m, code_fn = texture(panel_request(p))
        if m.dim != 3:
            raise backend.SettingError("model", f"model {m.name!r} is 2D; surfaces need a 3D solid texture")
        return self._start_target(context, p, obj, m, code_fn, blocking)

    def _start_target(self, context, p, obj, m, code_fn, blocking):
        scale, world = _space(p, obj)
        seed, name = int(p.seed), p.name
        surface = _mod("solid.surface")
        if p.target == "UV_IMAGE":
            size, margin = int(p.size), int(p.margin)
            _mod("limits").check_memory("image size", size * size * UV_BAKE_BYTES, f"a {size}² UV image bake")
            uv, pos = _mesh_arrays(context, obj, world, uv=True)

            unwrap = f"the UV map of {obj.name!r} covers no pixel of the image: unwrap it (UV > Smart UV Project)"
            share, part = _mod("bake").PREPARE_SHARE, _mod("progress").part   # texels, making, drawing

            def work(progress, cancel):
                mask, pts = surface.texel_positions(uv, pos, size, size, part(progress, 0.0, 0.2), cancel)
                if not mask.any():          # UVs at a point, or faces too small to hold a pixel's centre: refused
                    raise backend.SettingError("uv", unwrap)        # before the texture is made (a fit: seconds)
                code = code_fn(part(progress, 0.2, share - 0.2), cancel)
                mask, pts = surface.dilate(mask, pts, margin)
                rgb = np.zeros((size, size, 3), np.float32)
                rgb[mask] = m.evaluate(pts[mask] * scale, code, seed, progress=part(progress, share, 1.0 - share),
                                       cancel=cancel)
                return rgb

            def done(rgb):
                ima = store_srgb_image(name, rgb)

                def node(nt):
                    n = next((x for x in nt.nodes if x.type == "TEX_IMAGE" and x.image == ima), None)
                    n = n or nt.nodes.new("ShaderNodeTexImage")
                    n.image = ima
                    return n

                _material_with(obj, name, node)

        elif p.target == "COLOR_ATTRIBUTE":
            me = obj.data
            if obj.mode == "EDIT":      # the mesh holds the shape it had when Edit Mode began
                obj.update_from_editmode()
            co = _vertex_positions(me, obj, world)
            linear = _mod("solid.bake").srgb_to_linear

            def work(progress, cancel):
                making, drawing = _mod("bake").split_progress(progress)
                code = code_fn(making, cancel)
                rgb = m.evaluate(co * scale, code, seed, progress=drawing, cancel=cancel)
                return linear(rgb)

            def done(rgb):
                _store_vertex_colors(obj, name, rgb)

                def node(nt):
                    n = next((x for x in nt.nodes if x.type == "VERTEX_COLOR" and x.layer_name == name), None)
                    n = n or nt.nodes.new("ShaderNodeVertexColor")
                    n.layer_name = name
                    return n

                _material_with(obj, name, node)

        else:  # VOLUME
            from .bake_blender import load_volume

            grid, path = volume_target(p, obj, world)
            bake = _mod("solid.bake")

            def work(progress, cancel):
                making, progress = _mod("bake").split_progress(progress)
                code, model = code_fn(making, cancel), m
                if isinstance(model, _mod("solid.choose").AutoTexture):      # what Auto chose
                    model, code = ((_mod("solid.spectral_solid").SpectralTexture(code.request), code.field)
                                   if code.method == "procedural" else (code.model, code.code))
                if isinstance(model, _mod("solid.spectral_solid").SpectralTexture):    # the job files' source
                    src = _mod("sources").SpectralSource(model.request, scale, field=code)
                    bake_mod = _mod("bake")
                    bake_mod.run_bake(bake_mod.BakeSpec("solid", src, grid, path), progress, cancel, force=True)
                else:
                    bake.bake_volume(model, code, grid, path, seed, scale, progress=progress, cancel=cancel)
                return path

            def done(path):
                vol = load_volume(name, [path], None, False)
                if not world:  # baked in the object's own space: place it like the object
                    vol.matrix_world = obj.matrix_world.copy()

        return tasks.start(tasks.Task(f"Solid {name}", work, done, None, threads()), blocking=blocking)


def volume_target(p, obj, world: bool) -> tuple:
    """(BoxGrid, path) of the panel's volume bake of ``obj``: its bounding box (world or its own space), Voxels
    along the longest side, ``<Name>.vdb`` in the panel's folder; SettingError for an object with no extent."""
    from .bake_blender import output_folder

    lo = np.array([min(c[i] for c in obj.bound_box) for i in range(3)])
    hi = np.array([max(c[i] for c in obj.bound_box) for i in range(3)])
    if world:
        from .bake_blender import world_bounds

        lo, hi = (np.array(b) for b in world_bounds(obj))
    if float((hi - lo).max()) <= 1e-6:     # a camera, light, empty or empty volume: nothing to fill
        raise backend.SettingError("object", f"{obj.name!r} has no extent to fill with a volume (its bounding "
                                             "box is a point); bake an object with a size")
    ext = np.maximum(hi - lo, 1e-6)
    vs = float(ext.max()) / int(p.voxels)
    res = tuple(int(max(1, round(e / vs))) for e in ext)
    grid = _mod("sources").BoxGrid(res, (tuple(lo), tuple(lo + np.array(res) * vs))).validate()
    return grid, os.path.join(output_folder(p.folder), bpy.path.clean_name(p.name) + ".vdb")


def job_spec(context):
    """The panel's volume bake as a :class:`~backend.bake.BakeSpec` for a job file: the request the panel draws
    (a photo or a node group's solid held in memory, which the job writer saves beside the job), at the bake's
    scale and over its box; SettingError for what a job does not bake (a UV image or colour attribute: written into
    the mesh) and what the bake refuses."""
    p = context.scene.omninoise_solid
    if p.target != "VOLUME":
        raise backend.SettingError("target", "a job bakes files: a UV image or color attribute is written into the "
                                             "mesh; set Bake To to Volume")
    obj = context.active_object
    if obj is None:
        raise backend.SettingError("object", "select an object to bake onto")
    req = panel_request(p)
    scale, world = _space(p, obj)
    grid, path = volume_target(p, obj, world)
    source = _mod("sources").solid_source(req, scale, where="")
    if source.dim != 3:
        raise backend.SettingError("model", "the texture is 2D; a volume needs a 3D solid texture")
    return _mod("bake").BakeSpec(p.name, source, grid, path).validate()


class OMNINOISE_OT_solid_save_job(SaveJobOperator, bpy.types.Operator):
    """Save the panel's volume bake as a TOML job file (the photo or procedural solid beside it), that
    `omninoise bake`, a farm or the Batch Job panel bakes again without Blender"""

    bl_idname = "omninoise.solid_save_job"
    bl_label = "Save Solid Bake as Job File"
    settings = "omninoise_solid"

    @classmethod
    def poll(cls, context):
        p = getattr(context.scene, "omninoise_solid", None)
        if p is not None and p.target != "VOLUME":
            cls.poll_message_set("A job bakes files: set Bake To to Volume (a UV image or color attribute is "
                                 "written into the mesh)")
            return False
        return True

    def specs(self, context) -> list:
        return [job_spec(context)]

    def reads(self, context) -> dict:
        """The exemplar image's file: the photo the job reads is never written over it."""
        ima = context.scene.omninoise_solid.image
        return {bpy.path.abspath(ima.filepath): "of the Exemplar image"} if ima is not None and ima.filepath else {}


class OMNINOISE_OT_solid_procedural_node(SolidTask, bpy.types.Operator):
    """Fit a procedural solid to the photo and give the active object a material drawing it live from nodes: a node
    group whose inputs (spacing, sizes, turbulence...) can be edited afterwards"""

    bl_idname = "omninoise.solid_procedural_node"
    bl_label = "Procedural Node Group"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context, blocking: bool):
        import dataclasses

        p = context.scene.omninoise_solid
        obj = active_mesh(context, "give the procedural material to")
        req = dataclasses.replace(panel_request(p), method="procedural")
        if req.exemplar is None or isinstance(req.exemplar, str):
            raise backend.SettingError("image", "a procedural solid is fitted to a photo: set Source to Image")
        scale, world, name = float(p.scale), p.coords == "WORLD", p.name

        fit = remembered(req, lambda progress=None, cancel=None: req.procedural_field("", progress, cancel))

        def work(progress, cancel):
            return fit(progress, cancel), grid_info(req)

        def done(result):
            field, grid = result
            _give_procedural(obj, field, name, scale, world)
            p.periodic_info, p.grid_info = periodic_info(field), grid

        return tasks.start(tasks.Task(f"Procedural {name}", work, done, None, threads()), blocking=blocking)


def _give_procedural(obj, field, name: str, scale: float, world: bool):
    """Give ``obj`` the material ``<name> Procedural`` (or its active one with a Principled BSDF) drawing ``field``
    live: a new node group of it, in the scene's form, read at object positions (or world ones) times ``scale``."""
    from .procedural_nodes import add_procedural_node, build_procedural_group
    from .wave_ui import scene_form

    group = build_procedural_group(field, name=f"{name} Procedural", implementation=scene_form(bpy.context.scene))

    def node(nt):
        n = add_procedural_node(nt, group, (-400.0, 0.0))
        n.inputs["Scale"].default_value = scale
        if world:
            nt.links.new(_world_position(nt), n.inputs["Vector"])
        return n

    return _material_with(obj, f"{name} Procedural", node)


def _space(p, obj) -> tuple:
    """(scale, world) a bake reads the texture at: the panel's Scale and Coordinates, or with Source Node Group the
    node's own Scale and Vector (procedural_nodes.node_space), so that the bake is what the node renders."""
    if p.source == "NODE_GROUP":
        from .procedural_nodes import node_space, procedural_node

        return node_space(procedural_node(obj))
    return float(p.scale), p.coords == "WORLD"


class OMNINOISE_OT_solid_save_procedural(bpy.types.Operator, ExportHelper):
    """Save the active object's procedural node group, as its inputs are set, as a JSON file that the command line
    (--method procedural --exemplar FILE), job files and Python draw without fitting"""

    bl_idname = "omninoise.solid_save_procedural"
    bl_label = "Save Procedural Solid"
    bl_options = {"REGISTER"}      # writes a file only: nothing in the .blend to undo

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        """The file browser, at ``<node group name>.json`` beside the .blend (or in the last folder)."""
        from .procedural_nodes import procedural_node

        if not self.filepath:
            try:
                name = bpy.path.clean_name(procedural_node(context.active_object).node_tree.name)
            except backend.SettingError as exc:
                self.report({"ERROR"}, str(exc))
                return {"CANCELLED"}
            folder = os.path.dirname(bpy.data.filepath) if bpy.data.filepath else ""
            self.filepath = os.path.join(folder, name + self.filename_ext)
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from .procedural_nodes import node_field, procedural_node

        saved = _mod("solid.procedural.saved")
        try:
            field = node_field(procedural_node(context.active_object))
            path = bpy.path.abspath(self.filepath)
            if not self.filepath:
                raise backend.SettingError("file", "no file to save to: pick one in the file browser (a script: "
                                                   "filepath=...)")
            if not path.lower().endswith(".json"):
                raise backend.SettingError("file", f"a saved procedural solid is a .json file, not {path!r}")
            saved.save(path, field)
        except (backend.SettingError, OSError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Saved the {field.family} to {path}")
        return {"FINISHED"}


class OMNINOISE_OT_solid_load_procedural(bpy.types.Operator, ImportHelper):
    """Give the active mesh a material drawing a saved procedural solid (a JSON file of the command line's -o or of
    Save Procedural Solid) live from nodes, at the panel's Scale and Coordinates; no fit"""

    bl_idname = "omninoise.solid_load_procedural"
    bl_label = "Load Procedural Solid"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return tasks.idle(cls)

    def execute(self, context):
        p = context.scene.omninoise_solid
        path = bpy.path.abspath(self.filepath)
        try:
            obj = active_mesh(context, "give the procedural material to")
            if not self.filepath:
                raise backend.SettingError("file", "pick a saved procedural solid (.json) to load")
            field = _mod("solid.procedural.saved").read(path, "file")
        except backend.SettingError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        name = os.path.splitext(os.path.basename(path))[0]
        _give_procedural(obj, field, name, float(p.scale), p.coords == "WORLD")
        self.report({"INFO"}, f"Loaded the {field.family} of {os.path.basename(path)} (Source: Node Group bakes it)")
        return {"FINISHED"}


def _world_position(nt):
    """A Geometry node's Position output (world space) in ``nt``."""
    geo = next((n for n in nt.nodes if n.type == "NEW_GEOMETRY"), None) or nt.nodes.new("ShaderNodeNewGeometry")
    return geo.outputs["Position"]


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _idle_row(layout):
    row = layout.row(align=True)
    row.enabled = tasks.current() is None
    return row


def draw_solid(layout, context) -> None:
    """The Solid Texture panel's body: where the texture comes from, its scale and seed, preview and bake (the
    other settings are in the sub-panels below it, :data:`SECTIONS`)."""
    p = context.scene.omninoise_solid
    draw_progress(layout)
    layout.row().prop(p, "source", expand=True)
    _split(layout)
    if p.source == "SHIPPED":
        layout.prop(p, "texture")
    elif p.source == "IMAGE":
        layout.template_ID(p, "image", open="image.open")
        layout.prop(p, "method")
    else:
        _draw_node_group(layout, context)
    for suffix in ("Preview", "Tile"):
        prev = bpy.data.images.get(f"{p.name} {suffix}")
        if prev is not None and prev.preview is not None:
            layout.template_icon(icon_value=prev.preview.icon_id, scale=6.0)
    if p.source != "NODE_GROUP":        # a node group's own Scale, and its seed is the fit's
        layout.prop(p, "scale")
        layout.prop(p, "seed")
    row = _idle_row(layout)
    row.operator(OMNINOISE_OT_solid_preview.bl_idname, text="Preview", icon="HIDE_OFF")
    row.operator(OMNINOISE_OT_solid_bake.bl_idname, text="Bake", icon="RENDER_STILL")
    row.operator(OMNINOISE_OT_solid_save_job.bl_idname, text="", icon="EXPORT")


def _draw_node_group(layout, context) -> None:
    """Which node group Source Node Group reads (or why none), and saving and loading procedural solids."""
    from .procedural_nodes import procedural_node

    try:
        node = procedural_node(context.active_object)
        layout.label(text=f"{context.active_object.active_material.name} > {node.node_tree.name}", icon="NODETREE")
        layout.label(text="Scale and coordinates: the node's")
    except backend.SettingError as exc:
        layout.label(text=exc.message, icon="ERROR")
    row = _idle_row(layout)
    row.operator(OMNINOISE_OT_solid_save_procedural.bl_idname, text="Save", icon="EXPORT")
    row.operator(OMNINOISE_OT_solid_load_procedural.bl_idname, text="Load", icon="IMPORT")


def _draw_photo(layout, p) -> None:
    if p.method in ("NEURAL", "AUTO"):
        layout.prop(p, "refine")
    if p.method in ("PROCEDURAL", "AUTO"):
        layout.label(text="Procedural Kinds:")
        layout.row(align=True).prop(p, "families", expand=True)
        if p.grid_info:
            layout.label(text=p.grid_info, icon="INFO")
    if p.method == "PROCEDURAL":
        if p.periodic_info:
            layout.label(text=p.periodic_info)
        _idle_row(layout).operator(OMNINOISE_OT_solid_procedural_node.bl_idname, icon="NODETREE")
        return
    layout.prop(p, "periodic")
    if p.periodic_info and (p.periodic or p.method == "AUTO"):
        layout.label(text=p.periodic_info)
    if p.method in ("NEURAL", "AUTO"):
        layout.prop(p, "gaussian")
        if p.gaussian:
            layout.prop(p, "rest")
        if p.gaussian and p.gaussian_info:
            layout.label(text=p.gaussian_info)


def _draw_bake(layout, p) -> None:
    layout.prop(p, "target")
    if p.source != "NODE_GROUP":
        layout.prop(p, "coords")
    if p.target == "UV_IMAGE":
        layout.prop(p, "size")
        layout.prop(p, "margin")
    elif p.target == "VOLUME":
        layout.prop(p, "voxels")
        layout.prop(p, "folder")
    layout.prop(p, "name")


def _draw_tile(layout, p) -> None:
    layout.prop(p, "tile")
    row = _idle_row(layout)
    row.operator(OMNINOISE_OT_solid_tileable.bl_idname, text="Make Tileable Image", icon="IMAGE_DATA")
    if bpy.data.images.get(f"{p.name} Tile") is not None:
        layout.operator(OMNINOISE_OT_solid_tile_material.bl_idname, text="Project Tile onto Object",
                        icon="MOD_UVPROJECT")


def _from_photo(p) -> bool:
    return p.source == "IMAGE"


#: the Solid Texture panel's sub-panels: (name, label, draw(layout, settings), shown when, closed at first)
SECTIONS = (("photo", "Photo Options", _draw_photo, _from_photo, True),
            ("bake", "Bake", _draw_bake, None, False),
            ("tile", "Tileable Image", _draw_tile, _from_photo, True))


def draw_solid_all(layout, context) -> None:
    """The panel and every sub-panel in one layout (scripts and tests that look at everything the panel offers)."""
    draw_solid(layout, context)
    p = context.scene.omninoise_solid
    for _, _, draw, shown, _ in SECTIONS:
        if shown is None or shown(p):
            draw(_split(layout), p)


class OMNINOISE_PT_solid_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Solid Texture Presets"
    preset_subdir = SUBDIRS["solid"]
    preset_operator = "script.execute_preset"
    preset_add_operator = "omninoise.solid_preset_add"


class OMNINOISE_OT_solid_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a solid texture preset (the method, the procedural kinds and the method's options)"""

    bl_idname = "omninoise.solid_preset_add"
    bl_label = "Add Solid Texture Preset"
    preset_menu = "OMNINOISE_PT_solid_presets"
    preset_subdir = SUBDIRS["solid"]
    preset_defines = ["p = bpy.context.scene.omninoise_solid"]
    preset_values = SOLID_VALUES


class OMNINOISE_PT_solid(Sidebar, bpy.types.Panel):
    bl_label = "Solid Texture"
    bl_space_type = "VIEW_3D"

    def draw_header_preset(self, context):
        OMNINOISE_PT_solid_presets.draw_panel_header(self.layout)

    def draw(self, context):
        draw_solid(self.layout, context)


def _section_panel(name, label, draw, shown, closed):
    def panel_draw(self, context):
        draw(_split(self.layout), context.scene.omninoise_solid)

    ns = dict(bl_label=label, bl_space_type="VIEW_3D", bl_parent_id="OMNINOISE_PT_solid", draw=panel_draw)
    if closed:
        ns["bl_options"] = {"DEFAULT_CLOSED"}
    if shown is not None:
        def poll(cls, context):
            return shown(context.scene.omninoise_solid)
        ns["poll"] = classmethod(poll)
    return type(f"OMNINOISE_PT_solid_{name}", (Sidebar, bpy.types.Panel), ns)


PANELS = (OMNINOISE_PT_solid,) + tuple(_section_panel(*section) for section in SECTIONS)


classes = (OMNINOISE_PG_solid, OMNINOISE_OT_solid_preview, OMNINOISE_OT_solid_tileable,
           OMNINOISE_OT_solid_tile_material, OMNINOISE_OT_solid_bake, OMNINOISE_OT_solid_save_job,
           OMNINOISE_OT_solid_procedural_node,
           OMNINOISE_OT_solid_save_procedural, OMNINOISE_OT_solid_load_procedural,
           OMNINOISE_PT_solid_presets, OMNINOISE_OT_solid_preset_add) + PANELS


def attach():
    """What register() adds beyond the classes: the scene's solid texture settings."""
    bpy.types.Scene.omninoise_solid = PointerProperty(type=OMNINOISE_PG_solid)


def detach():
    del bpy.types.Scene.omninoise_solid
