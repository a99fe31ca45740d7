import bpy
p = bpy.context.scene.omninoise_neural

p.swatches.clear()
item_sub_1 = p.swatches.add()
item_sub_1.name = ''
item_sub_1.noise = 'fibers'
item_sub_1.p0 = 15.0
item_sub_1.p1 = 4.5
item_sub_1.p2 = 1.5707963267948966
item_sub_1.p3 = 0.0
item_sub_1.color = (1.0, 0.0, 0.0)
p.mode = 'SINGLE'
p.width = 32.0
p.sharpness = 1.0
p.sampler = 'dpmpp_2m'
p.steps = 10
p.tileable = False
