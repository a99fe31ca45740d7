import bpy
props = bpy.context.omninoise_wave

props.dimensions = '3'
props.directions = 16
props.spectrum = 'gaussian'
props.fmin = 3.0
props.fmax = 5.0
props.exponent = 1.0
props.waveform = 'gaussian'
props.anisotropy = 'lobes'
props.axis = (1.0, 0.0, 0.0)
props.spread = 6.0
props.axis_scale = (1.0, 2.0, 0.5)
props.speed = 0.0
