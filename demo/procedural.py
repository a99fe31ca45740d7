"""Procedural solids fitted to photos, live in Blender: out/demo/procedural.png, procedural.blend, procedural.json,
wood_grain.json and wood_grain.png.

Three photographs (a red brick wall and a paving of stones, held out from training, and a board) each fitted as a
procedural solid through the add-on's own operators (headless, blocking), as an artist would: Source Image, Method
Procedural Solid, the kinds the panel's presets pick for such a photo (Bonds for the wall, Cells for the stones,
Layers for the board), then Procedural Node Group on a cube, which draws the solid live from Blender's nodes. The
board's node group is then edited as the Blender guide says for fine grain (Spacing 0.07, Turbulence 1, Turbulence
Frequency 0.3), saved with Save Procedural Solid as wood_grain.json, and that file drawn again by the Python API
without fitting (wood_grain.png: its front, side and top). The scene renders in Cycles on the CPU.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402

from omninoise.export.atomic import write_json  # noqa: E402
from omninoise.export.images import linear_to_srgb, write_png  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solid import cycles_scene, floor_camera_and_sun, save_and_render  # noqa: E402  (demo/solid.py: the same scene)

#: (photo, the kinds fitted, the node group's inputs edited afterwards)
PHOTOS = ((os.path.join(ROOT, "data", "photos", "val", "brick__tex_trak_trak4_brick2a.jpg"), {"BONDS"}, {}),
          (os.path.join(ROOT, "data", "photos", "val", "paving__sahara_paving_stones_01.jpg"), {"CELLS"}, {}),
          (os.path.join(ROOT, "data", "structured", "wood__wood17.jpg"), {"LAYERS"},
           {"Spacing": 0.07, "Turbulence": 1.0, "Turbulence Frequency": 0.3}))
SPACING = 2.3


def build_scene(out: str) -> dict:
    from omninoise.blender_addon.procedural_nodes import procedural_node

    sc = cycles_scene(800, 372)
    sc.cycles.samples = 16
    p = sc.omninoise_solid
    used = {}
    for i, (photo, kinds, edits) in enumerate(PHOTOS):
        name = os.path.basename(photo).split("__")[1].rsplit(".", 1)[0]
        bpy.ops.mesh.primitive_cube_add(size=1.6, location=(SPACING * (i - 1), 0.0, 0.8), rotation=(0.0, 0.0, 0.6))
        p.source, p.image, p.method, p.families = "IMAGE", bpy.data.images.load(photo), "PROCEDURAL", kinds
        p.seed, p.scale, p.coords, p.name = 0, 1.0, "OBJECT", name
        t = time.perf_counter()
        assert bpy.ops.omninoise.solid_procedural_node() == {"FINISHED"}
        node = procedural_node(bpy.context.active_object)
        for socket, value in edits.items():
            node.inputs[socket].default_value = value
        used[name] = dict(fit_seconds=round(time.perf_counter() - t, 2), kinds=sorted(kinds), family=p.periodic_info,
                          edits=edits)
    p.source = "NODE_GROUP"           # the board as edited, saved for the command line and job files
    assert bpy.ops.omninoise.solid_save_procedural(filepath=os.path.join(out, "wood_grain.json")) == {"FINISHED"}
    floor_camera_and_sun(sc, (0.0, -6.6, 4.6), (1.08, 0.0, 0.0))
    return used


def draw_saved(out: str) -> float:
    """wood_grain.json drawn by the Python API, no fit: its front, side and top, 256 px each -> wood_grain.png."""
    import omninoise
    from omninoise.backend.solid.procedural import saved

    t = time.perf_counter()
    front = omninoise.solid(os.path.join(out, "wood_grain.json"), 256, method="procedural")
    field = saved.read(os.path.join(out, "wood_grain.json"))
    seconds = time.perf_counter() - t
    sheet = np.concatenate([linear_to_srgb(front), field.image(256, axis="x"), field.image(256, axis="z")], 1)
    write_png(os.path.join(out, "wood_grain.png"), np.round(np.clip(sheet, 0, 1) * 255).astype(np.uint8))
    return seconds


def main(out: str) -> int:
    os.makedirs(out, exist_ok=True)
    if not all(os.path.isfile(photo) for photo, _, _ in PHOTOS):
        print("procedural demo skipped: its photos are not in data/")
        return 0
    t0 = time.perf_counter()
    used = build_scene(out)
    render = save_and_render(out, "procedural.blend", "procedural.png")
    drawn = draw_saved(out)
    info = dict(photos=used, render_seconds=round(render, 1), saved_drawn_seconds=round(drawn, 2),
                seconds=round(time.perf_counter() - t0, 1))
    write_json(os.path.join(out, "procedural.json"), info)
    print(f"wrote {os.path.join(out, 'procedural.blend')}, procedural.png, wood_grain.json, wood_grain.png "
          f"({info['seconds']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo")))
