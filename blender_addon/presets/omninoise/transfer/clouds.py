import bpy
bpy.ops.omninoise.set_transfer(transfer="{\"density_scale\": 3.0, \"interpolation\": \"ease\", \"range\": [0.1, 1.8], \"stops\": [[0.0, [1.0, 1.0, 1.0, 0.0]], [0.25, [0.95, 0.96, 1.0, 0.15]], [1.0, [1.0, 1.0, 1.0, 1.0]]], \"temperature\": []}")
