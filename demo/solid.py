"""Neural solid textures showcase: out/demo/solid.blend, solid_render.png and solid_slices.png.

A cube, a UV sphere, Suzanne and a cylinder receive solid textures from
photographs through the add-on's own "Solid Texture from Image" operator
(headless, blocking): the cube from a held-out brick photograph encoded by the
texture-space model (with the photo's harmonic part: its courses stand on the
cube's sides), and the sphere (a held-out rock photograph drawn as a spectral
solid: random phase noise of the photo lifted to 3D, no model) as UV images,
each texel evaluated at its 3D surface point so the UV seams do not show; Suzanne as a colour
attribute on a subdivided mesh, from a held-out farmland photograph encoded by
the texture-space model; the cylinder in the wood photo's model.  The floor
is a tileable image the add-on's Tileable Image operator synthesises from a
held-out paving photograph (no model), repeated 12 times each way without a
seam.  The scene renders in Cycles on the CPU.  solid_slices.png shows, per model, the
exemplar beside slices of the 3D texture along the three axes and an oblique
plane.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402

from omninoise import blender_addon  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402
from omninoise.backend.paths import solid_models  # noqa: E402
from omninoise.backend.solid.model import load_models, plane_points  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.export.images import preview_8bit, read_rgb, write_png  # noqa: E402

MODELS = solid_models()
EXEMPLARS = os.path.join(ROOT, "data", "exemplars")
#: a held-out colour photo (never trained on) that the texture-space model encodes for Suzanne
PHOTO = os.path.join(ROOT, "data", "photos", "val", "soil__farmland_a.jpg")
BRICKS = os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg")
#: a held-out rock photo the sphere draws as a spectral solid (backend/solid/spectral_solid.py)
ROCK = os.path.join(ROOT, "data", "photos", "val", "rock__cliff_greek.jpg")
#: a held-out paving photo: the floor is a tileable image synthesised from it (method "synthesis"), repeated
PAVING = os.path.join(ROOT, "data", "photos", "val", "paving__sahara_paving_stones_01.jpg")


def slices_sheet(out: str, size: int = 160) -> list:
    """Exemplar | xy | xz | yz | oblique slice per shipped 3D single model -> solid_slices.png."""
    rows, names = [], []
    for name, m in load_models(MODELS).items():
        if m.mode != "single" or m.dim != 3:
            continue
        ex = m.config["exemplars"][0]
        # a shipped exemplar by name (data/exemplars/NAME.png) or a photo of the photo set by its path
        path = os.path.join(EXEMPLARS, f"{ex}.png") if os.path.isfile(os.path.join(EXEMPLARS, f"{ex}.png")) \
            else os.path.join(ROOT, ex)
        img = read_rgb(path)
        step = max(1, round(1.0 / m.config["exemplar_scale"]))
        exemplar = img[::step, ::step][:size, :size]
        code = m.default_code()
        scale = 1.0 / step   # the slices at the resolution the exemplar is shown at
        cells = [exemplar] + [m.image(size, code, 0, scale=scale, axis=a, offset=(1.3, 2.1, 0.7)) for a in "zyx"]
        frame = np.linalg.qr(np.random.default_rng(4).normal(size=(3, 3)))[0]
        pts = plane_points(size, m.px_per_unit * scale) @ frame[:, :2].T + 3.0
        cells.append(m.evaluate(pts, code, 0).reshape(size, size, 3))
        gap = np.ones((size, 4, 3), np.float32)
        rows.append(np.concatenate(sum([[c, gap] for c in cells], [])[:-1], 1))
        names.append(name)
    if rows:
        sheet = np.concatenate(sum([[r, np.ones((4, r.shape[1], 3), np.float32)] for r in rows], [])[:-1], 0)
        write_png(os.path.join(out, "solid_slices.png"), preview_8bit(sheet, 0.0, 1.0))
    return names


def _add(kind: str, x: float):
    if kind == "Cube":
        bpy.ops.mesh.primitive_cube_add(size=1.6, location=(x, 0, 0.8), rotation=(0, 0, 0.6))
    elif kind == "Sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.95, segments=64, ring_count=32, location=(x, 0, 0.95))
        bpy.ops.object.shade_smooth()
    elif kind == "Suzanne":
        bpy.ops.mesh.primitive_monkey_add(size=1.7, location=(x, 0, 0.95), rotation=(0.35, 0, 0.35))
        mod = bpy.context.active_object.modifiers.new("Subdivision", "SUBSURF")
        mod.levels = mod.render_levels = 3
        bpy.ops.object.modifier_apply(modifier="Subdivision")   # vertex colours need the dense mesh
        bpy.ops.object.shade_smooth()
    else:
        bpy.ops.mesh.primitive_cylinder_add(radius=0.8, depth=1.7, location=(x, 0, 0.85), vertices=64)
    obj = bpy.context.active_object
    obj.name = kind
    return obj


def _tiled_material(obj, image, repeats: float) -> None:
    """The object's material shows ``image`` repeated ``repeats`` times across its UV square (seamless tiles)."""
    mat = bpy.data.materials.new("Floor")
    ensure_node_tree(mat)
    nt = mat.node_tree
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    tex, mapping, coords = (nt.nodes.new(t) for t in ("ShaderNodeTexImage", "ShaderNodeMapping",
                                                         "ShaderNodeTexCoord"))
    tex.image = image
    mapping.inputs["Scale"].default_value = (repeats, repeats, 1.0)
    nt.links.new(coords.outputs["UV"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    obj.data.materials.append(mat)


def build_scene(out: str) -> dict:
    """A cube and Suzanne textured from held-out photographs (bricks, farmland) through the texture-space model,
    a sphere as the spectral solid of a held-out rock photograph, a cylinder from a single-photo model (wood)."""
    sc = cycles_scene(720, 300)
    p = sc.omninoise_solid
    p.folder = os.path.join(out, "bakes")
    space = os.path.isfile(os.path.join(MODELS, "space", "solid.json"))
    plan = [("Cube", "space" if space else "gravel_3d", BRICKS if space else None, "UV_IMAGE", 1.0),
            ("Sphere", "spectral", ROCK, "UV_IMAGE", 0.5),
            ("Suzanne", "space" if space else "gravel_3d", PHOTO if space else None, "COLOR_ATTRIBUTE", 1.0),
            ("Cylinder", "wood_3d", None, "UV_IMAGE", 1.0)]
    used = {}
    x = -3.3
    for kind, model, photo, target, scale in plan:
        if model != "spectral" and not os.path.isfile(os.path.join(MODELS, model, "solid.json")):
            continue
        obj = _add(kind, x)
        x += 2.2
        p.method = "SPECTRAL" if model == "spectral" else "NEURAL"
        if photo:   # the texture-space model encodes the photograph itself, or it is drawn as a spectral solid
            p.source, p.image = "IMAGE", bpy.data.images.load(photo)
        else:
            p.source, p.texture = "SHIPPED", f"single:{model}"
        p.target, p.scale, p.name, p.size = target, scale, f"{kind} {model}", 1024
        t = time.perf_counter()
        assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
        used[kind] = dict(model=model, photo=photo, target=target, seconds=round(time.perf_counter() - t, 2),
                          object=obj.name)
    bpy.ops.mesh.primitive_plane_add(size=30.0)
    if os.path.isfile(PAVING):      # the floor: a tileable image synthesised from a held-out paving photo
        floor = bpy.context.active_object
        p.source, p.image, p.tile, p.seed, p.name = "IMAGE", bpy.data.images.load(PAVING), 256, 0, "Floor"
        p.method = "NEURAL"
        t = time.perf_counter()
        assert bpy.ops.omninoise.solid_tileable() == {"FINISHED"}
        tile = bpy.data.images["Floor Tile"]
        used["Floor"] = dict(method="synthesis", photo=PAVING, tile=256, seconds=round(time.perf_counter() - t, 2))
        _tiled_material(floor, tile, repeats=12.0)
    bpy.ops.object.camera_add(location=(0.0, -9.0, 3.2), rotation=(1.27, 0.0, 0.0))
    cam = bpy.context.active_object
    cam.data.lens = 38
    sc.camera = cam
    sun_and_sky(sc, (0.8, 0.2, 0.5), 4.0)
    return used


def cycles_scene(width: int, height: int):
    """An empty scene with the add-on registered, rendered by Cycles on the CPU (24 samples) at width x height:
    the solid demos' start."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 24
    sc.render.resolution_x, sc.render.resolution_y = width, height
    return sc


def sun_and_sky(sc, rotation, energy: float) -> None:
    """A sun of ``energy`` turned by ``rotation`` and a grey-blue sky for scene ``sc`` (the solid demos' light)."""
    bpy.ops.object.light_add(type="SUN", rotation=rotation)
    bpy.context.active_object.data.energy = energy
    world = bpy.data.worlds.new("Sky")
    next(n for n in ensure_node_tree(world).nodes if n.type == "BACKGROUND").inputs["Color"].default_value = \
        (0.35, 0.38, 0.42, 1.0)
    sc.world = world


def floor_camera_and_sun(sc, location, rotation) -> None:
    """A floor 40 units wide, a 36 mm camera at ``location`` turned by ``rotation``, and :func:`sun_and_sky`: the
    stage of the demos' rows of cubes."""
    bpy.ops.mesh.primitive_plane_add(size=40.0)
    bpy.ops.object.camera_add(location=location, rotation=rotation)
    cam = bpy.context.active_object
    cam.data.lens = 36
    sc.camera = cam
    sun_and_sky(sc, (0.8, 0.3, -0.6), 3.5)


def save_and_render(out: str, blend: str, png: str) -> float:
    """Save the scene as out/blend and render its camera (PNG) to out/png, each written whole (a temporary file
    renamed): the render's seconds."""
    sc = bpy.context.scene
    path = os.path.join(out, blend)
    bpy.ops.wm.save_as_mainfile(filepath=path + ".tmp.blend", compress=True)
    os.replace(path + ".tmp.blend", path)
    sc.render.filepath = os.path.join(out, png + ".tmp.png")
    sc.render.image_settings.file_format = "PNG"
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    os.replace(sc.render.filepath, os.path.join(out, png))
    return time.perf_counter() - t


def main(out: str) -> int:
    os.makedirs(out, exist_ok=True)
    if not os.path.isdir(MODELS):
        print("solid demo skipped: no models/solid")
        return 0
    t0 = time.perf_counter()
    names = slices_sheet(out)
    used = build_scene(out)
    render = save_and_render(out, "solid.blend", "solid_render.png")
    info = dict(slices=names, objects=used, render_seconds=round(render, 1),
                seconds=round(time.perf_counter() - t0, 1))
    write_json(os.path.join(out, "solid.json"), info)
    print(f"wrote {os.path.join(out, 'solid.blend')}, solid_render.png, solid_slices.png ({info['seconds']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo")))
