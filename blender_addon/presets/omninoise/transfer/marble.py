import bpy
bpy.ops.omninoise.set_transfer(transfer="{\"density_scale\": 10.0, \"interpolation\": \"ease\", \"range\": [-1.2, 1.2], \"stops\": [[0.0, [0.92, 0.9, 0.86, 1.0]], [0.46, [0.85, 0.83, 0.8, 1.0]], [0.5, [0.15, 0.14, 0.14, 1.0]], [0.54, [0.85, 0.83, 0.8, 1.0]], [1.0, [0.95, 0.94, 0.92, 1.0]]], \"temperature\": []}")
