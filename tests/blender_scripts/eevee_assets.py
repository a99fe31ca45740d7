"""Run by tests/blender/test_assets.py in a fresh Python: each shipped asset appended and rendered by EEVEE.

argv: ASSETS.blend OUT_DIR RES. For each material (and each node group, through an emission material) a sphere,
or a cube for a volume material, is rendered at RES x RES with EEVEE into OUT_DIR/NAME.png; prints one JSON line
{name: seconds}. EEVEE needs an OpenGL 4.3 context: a GPU, or Mesa's llvmpipe on the CPU.
"""
import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))

from asset_scene import render_assets  # noqa: E402
from omninoise.blender_addon.compat import eevee_engine  # noqa: E402

if __name__ == "__main__":
    blend, out, res = sys.argv[1], sys.argv[2], int(sys.argv[3])
    t0 = time.perf_counter()
    times = render_assets(blend, out, res, eevee_engine())
    print(json.dumps(times))
    sys.stdout.flush()
    os._exit(0)
