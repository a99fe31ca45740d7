"""The procedural solids' sheet in the docs (docs/img/solid_procedural.png): ``.venv/bin/python -m tools.procedural_sheet``.

One row per photo: the photo | the neural texture's front (today's default) | the procedural solid's front, then a
cube, a sphere and a carved bowl in Cycles, each twice: the neural texture (evaluated at the vertices of a dense
mesh, a colour attribute) and the procedural solid (its live node group, blender_addon/procedural_nodes.py, no
bake).  A solid continues through the object, so the rings, veins and courses run on across the cube's edges and
through the bowl's cut rim.  The photos: every structured held-out photo of the evaluation, each with the
procedural solid the evaluation fitted and measured (``python -m bench solid-procedural``, its ``field`` in
:data:`BENCH`), in the evaluation's order.
"""
from __future__ import annotations

import json
import os
import sys

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "docs", "img", "solid_procedural.png")
BENCH = os.path.join(ROOT, "docs", "benchmarks", "solid_procedural.json")
SIDE = 128          #: px per tile
SAMPLES = 16        #: Cycles samples per render


def _meshes() -> dict:
    """A cube, a sphere and a bowl cut from a sphere with a thick wall, dense enough for colour attributes."""
    import bmesh

    out = {}
    for kind in ("cube", "sphere", "bowl"):
        bm = bmesh.new()
        if kind == "cube":
            bmesh.ops.create_cube(bm, size=1.6)
            bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=63, use_grid_fill=True)
        else:
            bmesh.ops.create_uvsphere(bm, u_segments=192, v_segments=96, radius=1.0)
        if kind == "bowl":
            bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.z > 0.3], context="VERTS")
        me = bpy.data.meshes.new(kind)
        bm.to_mesh(me)
        bm.free()
        if kind == "bowl":           # the wall's thickness: the cut rim shows the inside of the solid
            ob = bpy.data.objects.new("tmp", me)
            bpy.context.scene.collection.objects.link(ob)
            mod = ob.modifiers.new("wall", "SOLIDIFY")
            mod.thickness, mod.offset = 0.18, -1.0
            dg = bpy.context.evaluated_depsgraph_get()
            me = bpy.data.meshes.new_from_object(ob.evaluated_get(dg))
            bpy.data.objects.remove(ob)
        for p in me.polygons:
            p.use_smooth = True
        out[kind] = me
    return out


def _scene():
    from omninoise.blender_addon.compat import ensure_node_tree

    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device, sc.cycles.samples, sc.cycles.use_denoising = "CPU", SAMPLES, False
    sc.render.resolution_x = sc.render.resolution_y = SIDE
    sc.render.image_settings.file_format = "PNG"
    sc.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("grey")
    ensure_node_tree(world).nodes["Background"].inputs["Color"].default_value = (0.35, 0.35, 0.35, 1.0)
    sc.world = world
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (2.9, -2.9, 2.5), (0.95, 0.0, 0.785)
    sc.collection.objects.link(cam)
    sc.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy, sun.rotation_euler = 3.0, (0.6, 0.2, 0.4)
    sc.collection.objects.link(sun)
    return sc


def _render(sc, mesh, mat, path: str) -> np.ndarray:
    ob = bpy.data.objects.new("subject", mesh)
    sc.collection.objects.link(ob)
    mesh.materials.clear()
    mesh.materials.append(mat)
    sc.render.filepath = path
    bpy.ops.render.render(write_still=True)
    bpy.data.objects.remove(ob)
    ima = bpy.data.images.load(path)
    px = np.empty(SIDE * SIDE * 4, np.float32)
    ima.pixels.foreach_get(px)
    bpy.data.images.remove(ima)
    return np.flipud(px.reshape(SIDE, SIDE, 4)[..., :3])


def _material(name: str, colour_socket) -> bpy.types.Material:
    from omninoise.blender_addon.compat import ensure_node_tree

    mat = bpy.data.materials.new(name)
    nt = ensure_node_tree(mat)
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Roughness"].default_value = 0.7
    nt.links.new(colour_socket(nt), bsdf.inputs["Base Color"])
    return mat


def write_sheet(path: str, rgb: np.ndarray) -> None:
    """The sheet uint8 (H, W, 3) as a PNG of 256 colours (median cut, dithered): a quarter of the bytes of the full
    colours for a page of the docs, and no tile shows bands."""
    from PIL import Image

    from omninoise.export.atomic import atomic_path

    with atomic_path(path) as tmp:
        Image.fromarray(rgb).quantize(256, method=Image.Quantize.MEDIANCUT).save(tmp, format="PNG", optimize=True)


def main() -> int:
    from omninoise.backend.colour import srgb_to_linear
    from bench.eval_procedural import photos
    from omninoise.backend.solid.procedural.field import ProceduralField
    from omninoise.backend.solid.request import SolidRequest
    from omninoise.blender_addon.procedural_nodes import add_procedural_node, build_procedural_group
    from omninoise.export import read_rgb

    bpy.ops.wm.read_homefile(use_empty=True)
    sc = _scene()
    meshes = _meshes()
    tmp = os.path.join(ROOT, "out", "procedural_sheet")
    os.makedirs(tmp, exist_ok=True)
    rows = []
    with open(BENCH) as f:
        measured = json.load(f)["photos"]
    paths = {os.path.basename(p): p for p in photos("structured", 1)}
    for name, row in measured.items():
        rel = os.path.relpath(paths[name], ROOT)
        photo = read_rgb(paths[name])
        req = SolidRequest(exemplar=photo, method="auto").check()
        c = req.choose(field=ProceduralField.from_dict(row["field"]))
        field, model, code = c.field, c.model, c.code
        tiles = [photo[:SIDE, :SIDE], model.image(SIDE, code, 0), field.image(SIDE)]
        group = build_procedural_group(field)
        for kind, me in meshes.items():
            co = np.empty(len(me.vertices) * 3, np.float32)
            me.vertices.foreach_get("co", co)
            rgb = srgb_to_linear(model.evaluate(co.reshape(-1, 3).astype(np.float64), code, 0))
            attr = me.color_attributes.get("neural") or me.color_attributes.new("neural", "FLOAT_COLOR", "POINT")
            rgba = np.ones((len(me.vertices), 4), np.float32)
            rgba[:, :3] = rgb
            attr.data.foreach_set("color", rgba.ravel())

            def neural_colour(nt):
                n = nt.nodes.new("ShaderNodeVertexColor")
                n.layer_name = "neural"
                return n.outputs["Color"]

            def procedural_colour(nt):
                return add_procedural_node(nt, group).outputs["Color"]

            for name, socket in (("neural", neural_colour), ("procedural", procedural_colour)):
                tiles.append(_render(sc, me, _material(f"{name} {kind}", socket),
                                     os.path.join(tmp, f"{os.path.basename(rel)}_{kind}_{name}.png")))
        rows.append(np.concatenate([np.clip(t, 0.0, 1.0) for t in tiles], 1))
        print(f"{rel}: {field.family}, auto kept {c.method} ({c.distances})", flush=True)
    write_sheet(OUT, np.round(np.concatenate(rows, 0) * 255).astype(np.uint8))
    print(f"wrote {os.path.relpath(OUT, ROOT)}")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)
