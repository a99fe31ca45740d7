import bpy
bpy.ops.omninoise.set_transfer(transfer="{\"density_scale\": 6.0, \"interpolation\": \"constant\", \"range\": [-1.2, 1.2], \"stops\": [[0.0, [0.0, 0.0, 0.0, 0.0]], [0.45, [0.2, 0.5, 0.7, 0.4]], [0.6, [0.4, 0.8, 0.9, 0.8]], [0.8, [0.8, 0.95, 1.0, 1.0]]], \"temperature\": []}")
