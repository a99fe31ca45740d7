"""Wave noise (Guehl et al., "Multi-Dimensional Procedural Wave Noise", ACM TOG 2025): the engine.

``spectra`` (the spectral profiles), ``tables`` (the precomputed complex 1D tables), ``directions`` (direction sets
and domains), ``hashing`` (the integer hashes shared with the Blender node), ``wave`` (the sum of oriented waves,
Alg. 1), ``cellular`` (the cellular variants), ``byexample`` (tables from an image's spectrum), ``fast`` (the numba
kernels) and ``settings`` (the frozen :class:`~backend.wavenoise.settings.WaveSettings` every front-end builds).
"""
