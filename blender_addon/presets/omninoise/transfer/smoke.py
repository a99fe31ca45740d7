import bpy
bpy.ops.omninoise.set_transfer(transfer="{\"density_scale\": 2.0, \"interpolation\": \"linear\", \"range\": [-0.5, 1.8], \"stops\": [[0.0, [0.4, 0.4, 0.42, 0.0]], [0.4, [0.25, 0.25, 0.26, 0.2]], [1.0, [0.05, 0.05, 0.05, 1.0]]], \"temperature\": []}")
