import bpy
p = bpy.context.scene.omninoise_neural

p.swatches.clear()
item_sub_1 = p.swatches.add()
item_sub_1.name = ''
item_sub_1.noise = 'cells_f1'
item_sub_1.p0 = 12.0
item_sub_1.p1 = 0.6
item_sub_1.p2 = 0.0
item_sub_1.p3 = 0.0
item_sub_1.color = (1.0, 0.0, 0.0)
item_sub_1 = p.swatches.add()
item_sub_1.name = ''
item_sub_1.noise = 'perlin'
item_sub_1.p0 = 9.0
item_sub_1.p1 = 0.0
item_sub_1.p2 = 0.0
item_sub_1.p3 = 0.0
item_sub_1.color = (0.0, 0.0, 1.0)
p.mode = 'GRADIENT'
p.width = 32.0
p.sharpness = 1.0
p.sampler = 'dpmpp_2m'
p.steps = 10
p.tileable = False
