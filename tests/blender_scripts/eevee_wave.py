"""Run by tests/blender/test_wave_eevee.py in a fresh Python: EEVEE renders of the Wave Noise and Wave Cellular
nodes.

argv: CASES.json OUT_DIR RES.  CASES.json maps a case name to {"settings": settings dict,
"inputs": {"Scale"|"Time"|"W": value}}.  For each case an orthographic camera looks
at a 2 x 2 plane ([-1, 1]^2 in object space, filling the frame) whose emission is
0.5 + ENC * (Value, Imaginary, Modulus) (EEVEE clamps negative emission), for cellular settings
0.5 + ENC * (Distance, Cell, 0); a colour
AOV "P" holds the shading position.  One sample, no pixel filter: each pixel is
shaded at its centre.  Writes OUT_DIR/NAME.exr (multilayer, float) and prints one
JSON line {name: seconds}.  EEVEE needs an OpenGL 4.3 context: a GPU, or Mesa's
llvmpipe on the CPU (Debian packages libegl-mesa0 and libgl1-mesa-dri).
"""
import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from bench.bench_node import scene  # noqa: E402  (the plane and orthographic camera of the render bench)
from omninoise.backend.wavenoise.settings import settings_from_dict  # noqa: E402
from omninoise.blender_addon.compat import eevee_engine, ensure_node_tree, set_multilayer_exr  # noqa: E402
from omninoise.blender_addon.cellular_nodes import build_cellular_group  # noqa: E402
from omninoise.blender_addon.wave_nodes import add_wave_node, build_wave_group  # noqa: E402

ENC = 0.1


def render(name: str, spec: dict, out_dir: str, res: int) -> float:
    sc, mat = scene(res, 1)
    sc.render.engine = eevee_engine()
    sc.eevee.taa_render_samples = 1
    sc.render.filter_size = 0.0
    sc.view_settings.view_transform = "Standard"
    aov = sc.view_layers[0].aovs.add()
    aov.name, aov.type = "P", "COLOR"
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    settings = settings_from_dict(spec["settings"])
    cellular = settings.cellular != "none"
    g = add_wave_node(nt, (build_cellular_group if cellular else build_wave_group)(settings, "ShaderNodeTree"))
    for key, val in spec["inputs"].items():
        g.inputs[key].default_value = val
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    for i, o in enumerate(("Distance", "Cell") if cellular else ("Value", "Imaginary", "Modulus")):
        m = nt.nodes.new("ShaderNodeMath")
        m.operation = "MULTIPLY_ADD"
        m.inputs[1].default_value, m.inputs[2].default_value = ENC, 0.5
        nt.links.new(g.outputs[o], m.inputs[0])
        nt.links.new(m.outputs[0], comb.inputs[i])
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(comb.outputs[0], em.inputs["Color"])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    an = nt.nodes.new("ShaderNodeOutputAOV")
    an.aov_name = "P"
    nt.links.new(g.inputs["Vector"].links[0].from_node.outputs["Object"], an.inputs["Color"])
    fmt = sc.render.image_settings
    set_multilayer_exr(fmt)
    fmt.color_depth = "32"
    sc.render.filepath = os.path.join(out_dir, name + ".exr")
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - t


def main() -> None:
    cases_path, out_dir, res = sys.argv[-3], sys.argv[-2], int(sys.argv[-1])
    with open(cases_path, encoding="utf-8") as fh:
        cases = json.load(fh)
    print(json.dumps({name: render(name, spec, out_dir, res) for name, spec in cases.items()}))


main()
