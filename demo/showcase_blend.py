"""The showcase scene: Wave Noise nodes on objects, saved as out/demo/showcase.blend.

Four objects carry the node in its 2D, 3D, lobe-anisotropic and animated
(Time driven by the frame) forms.  The scene is saved atomically.  A Cycles
render of frame 1 is written next to it as showcase_render.png, which proves
the file renders headless; re-render it with
``blender -b out/demo/showcase.blend -f 1``.
"""
from __future__ import annotations

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import bpy  # noqa: E402

from omninoise.backend import Spectrum, WaveSettings  # noqa: E402
from omninoise.blender_addon.wave_nodes import add_wave_node, build_wave_group  # noqa: E402

VARIANTS = [
    ("2D band", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 3, 6), directions=16, seed=1), "Value"),
    ("3D ridged", WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2, 5), directions=16, seed=2), "Modulus"),
    ("Lobe", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 3, 7), directions=16, seed=3, anisotropy="lobes",
                          lobes=(((1.0, 0.3, 0.0), 1.0),), spread=15.0), "Value"),
    ("Animated", WaveSettings(dim=3, spectrum=Spectrum("gaussian", 2, 5), directions=16, seed=4, speed=0.4),
     "Value"),
]


def _material(name, settings, output):
    grp = build_wave_group(settings, name=f"Wave Noise {name}")
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    g = add_wave_node(nt, grp)
    ramp = nt.nodes.new("ShaderNodeMapRange")
    ramp.inputs["From Min"].default_value = -2.0 if output == "Value" else 0.0
    ramp.inputs["From Max"].default_value = 2.0
    nt.links.new(g.outputs[output], ramp.inputs["Value"])
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    cr = nt.nodes.new("ShaderNodeValToRGB")
    cr.color_ramp.elements[0].color = (0.02, 0.05, 0.12, 1)
    cr.color_ramp.elements[1].color = (0.95, 0.75, 0.45, 1)
    nt.links.new(ramp.outputs[0], cr.inputs[0])
    nt.links.new(cr.outputs[0], bsdf.inputs["Base Color"])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    if settings.speed:
        drv = g.inputs["Time"].driver_add("default_value").driver
        drv.expression = "frame / 24"
    return mat


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 16
    sc.render.resolution_x, sc.render.resolution_y = 640, 200
    sc.frame_start, sc.frame_end = 1, 48
    for i, (name, s, output) in enumerate(VARIANTS):
        if s.dim == 2:
            bpy.ops.mesh.primitive_plane_add(size=1.8, location=(i * 2.2 - 3.3, 0, 0), rotation=(1.5708, 0, 0))
        else:
            bpy.ops.mesh.primitive_uv_sphere_add(radius=0.9, location=(i * 2.2 - 3.3, 0, 0), segments=48,
                                                 ring_count=24)
            bpy.ops.object.shade_smooth()
        ob = bpy.context.active_object
        ob.name = name
        ob.data.materials.append(_material(name, s, output))
    bpy.ops.object.camera_add(location=(0, -12, 0), rotation=(1.5708, 0, 0))
    cam = bpy.context.active_object
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = 9.0
    sc.camera = cam
    bpy.ops.object.light_add(type="SUN", rotation=(1.1, 0.2, 0.4))
    bpy.context.active_object.data.energy = 4.0
    world = bpy.data.worlds.new("World")
    sc.world = world
    world.color = (0.05, 0.05, 0.05)
    return sc


def add_neural_plane(sc, out: str):
    """The Neural Noise panel's workflow, headless: two swatches, a painted map, a bake on a plane.

    The plane sits below the camera's view, so the still render is unchanged; the
    map and the bake are also written side by side to neural_panel.png.
    """
    import numpy as np

    from omninoise import blender_addon
    from omninoise.blender_addon import neural_ui
    from omninoise.export.images import preview_8bit, write_png

    try:
        neural_ui.model()
    except Exception as exc:  # no shipped model: the rest of the showcase still stands
        print(f"neural plane skipped: {exc}")
        return
    blender_addon.register()
    p = sc.omninoise_neural
    p.size, p.seed, p.name = 128, 11, "Neural Blend"  # the panel's default sampler and steps
    for noise, colour in (("cells_f1", (1.0, 0.0, 0.0)), ("damascus", (0.0, 0.0, 1.0))):
        bpy.ops.omninoise.swatch_add()
        p.swatches[-1].noise = noise
        p.swatches[-1].color = colour
    bpy.ops.omninoise.blend_map_new()
    n = p.blend_map.size[0]
    yy, xx = np.mgrid[:n, :n]
    paint = np.ones((n, n, 4), np.float32)
    paint[..., :3] = (1.0, 0.0, 0.0)
    stroke = np.abs(yy - (n / 2 + n / 4 * np.sin(xx / n * 2 * np.pi))) < n / 6  # a wavy band "painted" in blue
    paint[stroke, :3] = (0.0, 0.0, 1.0)
    p.blend_map.pixels.foreach_set(paint.ravel())
    p.blend_map.update()
    p.mode = "MAP"
    p.width = 24.0
    bpy.ops.omninoise.neural_bake()
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0, 0, -3.0), rotation=(1.5708, 0, 0))
    ob = bpy.context.active_object
    ob.name = "Neural Blend"
    mat = bpy.data.materials.new("Neural Blend")
    nt = mat.node_tree
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images["Neural Blend"]
    bsdf = next(nd for nd in nt.nodes if nd.type == "BSDF_PRINCIPLED")
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    ob.data.materials.append(mat)
    baked = np.empty(128 * 128 * 4, np.float32)
    bpy.data.images["Neural Blend"].pixels.foreach_get(baked)
    side = np.concatenate([np.flipud(paint[..., :3]), np.repeat(np.flipud(baked.reshape(128, 128, 4))[..., :1], 3, -1)],
                          1)
    write_png(os.path.join(out, "neural_panel.png"), preview_8bit(side, 0.0, 1.0))


def main(out: str) -> None:
    os.makedirs(out, exist_ok=True)
    sc = build_scene()
    add_neural_plane(sc, out)
    path = os.path.join(out, "showcase.blend")
    tmp = path + ".tmp.blend"
    bpy.ops.wm.save_as_mainfile(filepath=tmp, compress=True)
    os.replace(tmp, path)
    sc.render.filepath = os.path.join(out, "showcase_render.png.tmp")
    sc.render.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)
    os.replace(sc.render.filepath if os.path.exists(sc.render.filepath) else sc.render.filepath + ".png",
               os.path.join(out, "showcase_render.png"))
    print(f"wrote {path} and showcase_render.png")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo"))
