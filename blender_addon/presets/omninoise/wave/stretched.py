import bpy
props = bpy.context.omninoise_wave

props.dimensions = '3'
props.directions = 16
props.spectrum = 'gaussian'
props.fmin = 2.0
props.fmax = 8.0
props.exponent = 1.0
props.waveform = 'gaussian'
props.anisotropy = 'axes'
props.axis = (1.0, 0.0, 0.0)
props.spread = 20.0
props.axis_scale = (1.0, 4.0, 1.0)
props.speed = 0.0
