"""The baked showcase volumes in a scene: out/demo/volumes.blend and volumes_render.png.

Run after ``omninoise bake demo/volumes.toml``.  The cloud bank (clouds.vdb,
density + color) floats over a slab textured with the baked marble.exr, and
the animated fire sequence (fire_####.vdb, with temperature) burns beside it;
all three load through the add-on's own loaders, so the file is what the
Bake Noise panel makes.  The still (clouds over marble) renders headless in
Cycles on the CPU; the fire is in the file, hidden from the still.
"""
from __future__ import annotations

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402

from omninoise.blender_addon.bake_blender import load_image, load_volume  # noqa: E402
from omninoise.blender_addon.compat import ensure_node_tree  # noqa: E402


def build_scene(bakes: str):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 16
    sc.cycles.volume_bounces = 1
    sc.cycles.volume_step_rate = 4.0  # 4 voxels per step: a preview-quality march, 3x faster
    sc.render.resolution_x, sc.render.resolution_y = 480, 240
    sc.frame_start, sc.frame_end = 1, 12
    clouds = load_volume("Clouds", [os.path.join(bakes, "clouds.vdb")], None, temperature=False)
    clouds.location = (0.0, 0.0, 0.6)
    fire = load_volume("Fire", [os.path.join(bakes, f"fire_{f:04d}.vdb") for f in range(1, 13)], (1, 12),
                       temperature=True)
    fire.location = (0.0, 3.0, 0.05)
    fire.scale = (0.6, 0.6, 1.2)
    fire.hide_render = True  # in the file to play (frames 1-12); left out of the still to keep it fast
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, 0, 0))
    slab = bpy.context.active_object
    slab.name = "Marble"
    slab.scale = (4.0, 2.0, 1.0)
    mat = bpy.data.materials.new("Marble")
    slab.data.materials.append(mat)
    load_image("marble", [os.path.join(bakes, "marble.exr")], None, raw=False, target_material=None)
    slab.data.materials[0] = bpy.data.materials["OmniNoise marble"]
    bpy.ops.object.camera_add(location=(0.0, -6.2, 4.0), rotation=(0.98, 0.0, 0.0))
    cam = bpy.context.active_object
    cam.data.lens = 38
    sc.camera = cam
    bpy.ops.object.light_add(type="SUN", rotation=(0.7, 0.3, 0.6))
    bpy.context.active_object.data.energy = 5.0
    world = bpy.data.worlds.new("Sky")
    world.color = (0.06, 0.11, 0.24)
    bg = next(n for n in ensure_node_tree(world).nodes if n.type == "BACKGROUND")
    bg.inputs["Color"].default_value = (0.06, 0.11, 0.24, 1.0)
    sc.world = world
    sc.frame_set(6)
    return sc


def main(out: str) -> None:
    bakes = os.path.join(out, "bakes")
    if not os.path.isfile(os.path.join(bakes, "clouds.vdb")):
        sys.exit(f"showcase_volume: run `omninoise bake demo/volumes.toml` first ({bakes} has no clouds.vdb)")
    sc = build_scene(bakes)
    path = os.path.join(out, "volumes.blend")
    tmp = path + ".tmp.blend"
    bpy.ops.wm.save_as_mainfile(filepath=tmp, compress=True, relative_remap=True)
    os.replace(tmp, path)
    sc.render.filepath = os.path.join(out, "volumes_render.tmp.png")
    sc.render.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)
    os.replace(sc.render.filepath, os.path.join(out, "volumes_render.png"))
    print(f"wrote {path} and volumes_render.png")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo"))
