import bpy
p = bpy.context.scene.omninoise_solid

p.source = 'IMAGE'
p.method = 'SPECTRAL'
p.families = {'BONDS', 'CELLS', 'LAYERS', 'RINGS'}
p.refine = 0
p.periodic = True
p.gaussian = True
p.rest = 'auto'
p.tile = 256
