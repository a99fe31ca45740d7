"""Photos on meshes without UVs: out/demo/solid_box.png, solid_box.blend and solid_box.json.

Four held-out photographs (brick, paving stones, planks, rock; never trained on) shown on cubes in two ways,
through the add-on's own operators (headless, blocking):

- back row: the 3D solid texture the texture-space model encodes from each photo (Bake, UV Image: each texel
  coloured at its 3D surface point), what volumes and cuts through a mesh show;
- front row: a tileable image synthesised from each photo (Tileable Image, texture optimisation) shown by Project
  Tile onto Object: box projection at the photo's pixel scale, the cube's UV map removed first.

The scene renders in Cycles on the CPU.
"""
from __future__ import annotations

import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402

from omninoise.backend.paths import solid_models  # noqa: E402
from omninoise.export.atomic import write_json  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solid import cycles_scene, floor_camera_and_sun, save_and_render  # noqa: E402  (demo/solid.py: the same scene)

VAL = os.path.join(ROOT, "data", "photos", "val")
PHOTOS = [os.path.join(VAL, n) for n in ("brick__beige_bricks.jpg", "paving__sahara_paving_stones_01.jpg",
                                         "wood__bridge_wood_a.jpg", "rock__rock1.jpg")]
SPACING = 2.1


def _cube(x: float, y: float):
    bpy.ops.mesh.primitive_cube_add(size=1.6, location=(x, y, 0.8), rotation=(0.0, 0.0, 0.6))
    return bpy.context.active_object


def build_scene(out: str) -> dict:
    sc = cycles_scene(900, 500)
    p = sc.omninoise_solid
    space = os.path.isfile(os.path.join(solid_models(), "space", "solid.json"))
    used = {}
    for i, photo in enumerate(PHOTOS):
        x = SPACING * (i - (len(PHOTOS) - 1) / 2)
        name = os.path.basename(photo).split("__")[1].rsplit(".", 1)[0]
        p.source, p.image, p.seed, p.scale, p.coords = "IMAGE", bpy.data.images.load(photo), 0, 1.0, "OBJECT"
        row = {}
        if space:       # back row: the solid texture the texture-space model encodes from the photo
            _cube(x, 2.4)
            p.target, p.size, p.name = "UV_IMAGE", 512, f"{name} solid"
            t = time.perf_counter()
            assert bpy.ops.omninoise.solid_bake() == {"FINISHED"}
            row["solid_seconds"] = round(time.perf_counter() - t, 2)
        cube = _cube(x, 0.0)          # front row: its tileable image, box-projected (no UVs)
        while cube.data.uv_layers:
            cube.data.uv_layers.remove(cube.data.uv_layers[0])
        p.tile, p.name = 256, f"{name}"
        t = time.perf_counter()
        assert bpy.ops.omninoise.solid_tileable() == {"FINISHED"}
        row["tile_seconds"] = round(time.perf_counter() - t, 2)
        bpy.context.view_layer.objects.active = cube
        assert bpy.ops.omninoise.solid_tile_material() == {"FINISHED"}
        used[name] = row
    floor_camera_and_sun(sc, (0.0, -7.4, 7.6), (0.82, 0.0, 0.0))
    return used


def main(out: str) -> int:
    os.makedirs(out, exist_ok=True)
    if not all(os.path.isfile(f) for f in PHOTOS):
        print("box projection demo skipped: no held-out photos in data/photos/val")
        return 0
    t0 = time.perf_counter()
    used = build_scene(out)
    render = save_and_render(out, "solid_box.blend", "solid_box.png")
    info = dict(photos=used, render_seconds=round(render, 1), seconds=round(time.perf_counter() - t0, 1))
    write_json(os.path.join(out, "solid_box.json"), info)
    print(f"wrote {os.path.join(out, 'solid_box.blend')}, solid_box.png ({info['seconds']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo")))
