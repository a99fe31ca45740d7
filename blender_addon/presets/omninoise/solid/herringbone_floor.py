import bpy
p = bpy.context.scene.omninoise_solid

p.source = 'IMAGE'
p.method = 'PROCEDURAL'
p.families = {'HERRINGBONE'}
p.refine = 0
p.periodic = True
p.gaussian = True
p.rest = 'auto'
p.tile = 256
