import bpy
props = bpy.context.omninoise_wave

props.dimensions = '3'
props.directions = 16
props.spectrum = 'brown'
props.fmin = 0.5
props.fmax = 4.0
props.exponent = 1.0
props.waveform = 'gaussian'
props.anisotropy = 'none'
props.axis = (1.0, 0.0, 0.0)
props.spread = 20.0
props.axis_scale = (1.0, 2.0, 0.5)
props.speed = 0.0
