"""Run by tests/blender/test_extension.py in a fresh Python with temporary Blender user folders.

argv[-1]: the extension zip.  Prints one JSON line of what it observed.
"""
import importlib
import json
import sys
import threading
import time

import bpy
import numpy as np

MOD = "bl_ext.user_default.omninoise"
out = {}
out["install"] = sorted(bpy.ops.extensions.package_install_files(filepath=sys.argv[-1], repo="user_default",
                                                                  enable_on_install=True))
out["enabled"] = MOD in bpy.context.preferences.addons
out["props"] = hasattr(bpy.types.NodeTree, "omninoise_wave")
out["menu_op"] = hasattr(bpy.types, "NODE_OT_omninoise_add_wave_noise")
ui = importlib.import_module(MOD + ".blender_addon.wave_ui")
tree = ui.new_wave_node_tree("Wave Noise", "ShaderNodeTree")
out["directions_default"] = sum(n.bl_idname == "ShaderNodeGroup" for n in tree.nodes)
tree.omninoise_wave.directions = 5
out["directions_after_edit"] = sum(n.bl_idname == "ShaderNodeGroup" for n in tree.nodes)
tree.omninoise_wave.directions = 60  # above the 3D limit: a message, the old tree stays
out["error"] = tree.omninoise_wave.error
out["directions_after_error"] = sum(n.bl_idname == "ShaderNodeGroup" for n in tree.nodes)
tree.omninoise_wave.directions = 5
# an Automatic group follows the scene: the OSL script once Cycles runs OSL, nodes again after
osl = importlib.import_module(MOD + ".blender_addon.wave_osl")
out["osl_available"] = osl.osl_available()
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.render.resolution_x = scene.render.resolution_y = 8
scene.cycles.samples = 1
scene.cycles.shading_system = True
bpy.ops.render.render()  # the switch itself does not reach the depsgraph from Python: render_pre does it
out["form_osl_scene"] = tree.get("omninoise_wave_implementation")
out["scripts_osl_scene"] = sum(n.bl_idname == "ShaderNodeScript" for n in tree.nodes)
scene.cycles.shading_system = False
bpy.ops.render.render()
out["form_svm_scene"] = tree.get("omninoise_wave_implementation")
out["groups_svm_scene"] = sum(n.bl_idname == "ShaderNodeGroup" for n in tree.nodes)
out["cache_dir"] = importlib.import_module(MOD + ".blender_addon.preferences").cache_dir()
# the Python API through the installed package (its lazy attributes, the api module in the zip)
out["api_wave_shape"] = list(importlib.import_module(MOD).wave(8, directions=4).shape)
# a volume bake through the installed package (its relative backend/export imports, bundled openvdb)
vdb = importlib.import_module(MOD + ".export.vdb")
try:
    vdb.openvdb_module()
    out["openvdb"] = True
except RuntimeError:  # the bpy 4.2 wheel: no OpenVDB module; the bake must say so in one line
    out["openvdb"] = False
# the C row kernel from the extension's omninoise_rows wheel (zips built with --kernel), against the
# engine's other path (numba where this Python has it, else numpy)
ck = importlib.import_module(MOD + ".backend.wavenoise.ckernel")
be = importlib.import_module(MOD + ".backend")
out["kernel_path"] = ck.library_path()
out["kernel_available"] = ck.available()
noise = be.compile_noise(be.WaveSettings(dim=3, directions=8, seed=1))
with_kernel = be.evaluate_grid(noise, 12, 2.0)
ck.set_enabled(False)
without = be.evaluate_grid(noise, 12, 2.0)
ck.set_enabled(True)
out["kernel_vs_other"] = float(abs(with_kernel - without).max())
out["kernel_signal"] = float(without.std())
fast = importlib.import_module(MOD + ".backend.wavenoise.fast")
out["other_path"] = "numba" if fast.available() else "numpy"
# points and the procedural cells as Blender's Python (no numba) reads them: the wheel's point and cell kernels
pts = np.random.default_rng(0).uniform(-4.0, 4.0, (3000, 3)).astype(np.float32)
saved, fast.numba = fast.numba, False
try:
    out["points_compiled"] = fast.supports(noise)
    points = noise.evaluate(pts)
finally:
    fast.numba = saved
out["points_vs_numpy"] = float(abs(points - noise.evaluate(pts, accelerate=False)).max())
cells = importlib.import_module(MOD + ".backend.solid.procedural.cells")
f1, f2, cube = cells.voronoi(pts, 0.9, 3)
ck.set_enabled(False)
g1, g2, gcube = cells.voronoi(pts, 0.9, 3)
ck.set_enabled(True)
out["cells_same"] = bool((f1 == g1).all() and (f2 == g2).all() and (cube == gcube).all())
bake = bpy.context.scene.omninoise_bake
bake.bounds_mode = "CUSTOM"
bake.volume_resolution = (8, 8, 8)
bake.name = "Installed"
try:
    out["bake"] = sorted(bpy.ops.omninoise.bake_volume())
except RuntimeError as exc:
    out["bake"], out["bake_error"] = ["ERROR"], str(exc)
obj = bpy.data.objects.get("Installed")
out["bake_grids"] = sorted(g.name for g in obj.data.grids) if obj else []
out["bake_file"] = bpy.path.abspath(obj.data.filepath) if obj else ""
# a task still running when the add-on is disabled is cancelled, its thread joined and its timer dropped
tasks = importlib.import_module(MOD + ".blender_addon.tasks")


def spin(progress, cancelled):
    while not cancelled():
        time.sleep(0.01)


task = tasks.start(tasks.Task("spin", spin), blocking=False)
out["task_running_before_disable"] = task.running and task._thread.is_alive()
out["task_timer_before_disable"] = bpy.app.timers.is_registered(task.timer)
bpy.ops.preferences.addon_disable(module=MOD)
out["task_thread_alive_after_disable"] = task._thread.is_alive()
out["task_timer_after_disable"] = bpy.app.timers.is_registered(task.timer)
out["task_status_after_disable"] = task.status
out["disabled_bake_props"] = hasattr(bpy.types.Scene, "omninoise_bake")
out["disabled_props"] = hasattr(bpy.types.NodeTree, "omninoise_wave")
bpy.ops.preferences.addon_enable(module=MOD)
out["reenabled_props"] = hasattr(bpy.types.NodeTree, "omninoise_wave")
bpy.ops.preferences.addon_disable(module=MOD)
# enable / disable three times more: classes, properties and threads come and go cleanly
cycles = []
for _ in range(3):
    bpy.ops.preferences.addon_enable(module=MOD)
    on = hasattr(bpy.types.NodeTree, "omninoise_wave") and hasattr(bpy.types.Scene, "omninoise_bake")
    bpy.ops.preferences.addon_disable(module=MOD)
    off = hasattr(bpy.types.NodeTree, "omninoise_wave") or hasattr(bpy.types.Scene, "omninoise_bake")
    cycles.append([on, off])
out["cycles"] = cycles
out["threads_left"] = sorted(t.name for t in threading.enumerate() if t.name.startswith("omninoise"))
print("RESULT " + json.dumps(out))
