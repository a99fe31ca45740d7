import bpy
bpy.ops.omninoise.set_transfer(transfer="{\"density_scale\": 3.0, \"interpolation\": \"linear\", \"range\": [0.0, 1.8], \"stops\": [[0.0, [0.1, 0.0, 0.0, 0.0]], [0.3, [0.8, 0.1, 0.0, 0.3]], [0.7, [1.0, 0.5, 0.05, 0.7]], [1.0, [1.0, 0.95, 0.7, 1.0]]], \"temperature\": [[0.2, 0.0], [1.0, 1800.0]]}")
