"""Run by tests/blender/test_procedural_blender.py in a fresh Python: EEVEE renders of the procedural solids' node
groups (blender_addon/procedural_nodes.py).

argv: CASES.json OUT_DIR RES.  CASES.json maps a case name to a procedural field's JSON (ProceduralField.to_dict).
For each case the render bench's orthographic camera looks at its 2 x 2 plane, lifted to z = LIFT (a plane at z = 0
would lie along a course's bed joint); its emission is the group's sRGB output.  One sample, no pixel filter: each
pixel is shaded at its centre.  Writes OUT_DIR/NAME.exr (multilayer, float) and prints one JSON line
{name: seconds}.
"""
import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from bench.bench_node import scene  # noqa: E402
from omninoise.backend.solid.procedural.field import ProceduralField  # noqa: E402
from omninoise.blender_addon.compat import eevee_engine, ensure_node_tree, set_multilayer_exr  # noqa: E402
from omninoise.blender_addon.procedural_nodes import add_procedural_node, build_procedural_group  # noqa: E402

LIFT = 0.37


def render(name: str, field: dict, out_dir: str, res: int) -> float:
    sc, mat = scene(res, 1)
    for v in bpy.data.objects["plane"].data.vertices:
        v.co.z = LIFT
    sc.render.engine = eevee_engine()
    sc.eevee.taa_render_samples = 1
    sc.render.filter_size = 0.0
    sc.view_settings.view_transform = "Standard"
    nt = ensure_node_tree(mat)
    nt.nodes.clear()
    g = add_procedural_node(nt, build_procedural_group(ProceduralField.from_dict(field)))
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(g.outputs["sRGB"], em.inputs["Color"])
    nt.links.new(em.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
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
    print(json.dumps({name: render(name, f, out_dir, res) for name, f in cases.items()}))
    sys.stdout.flush()
    os._exit(0)


main()
