"""Blender-free OmniNoise engines (numpy; onnxruntime for neural models).

Wave noise (Guehl et al., "Multi-Dimensional Procedural Wave Noise", TOG 2025):

    >>> from omninoise.backend import WaveSettings, Spectrum, compile_noise, evaluate_grid
    >>> noise = compile_noise(WaveSettings(dim=2, spectrum=Spectrum("bandpass", 4, 8)))
    >>> img = evaluate_grid(noise, size=256, extent=4.0)     # float32 (256, 256)

Nothing here imports ``bpy`` or ``torch``.
"""
from .errors import SettingError
from .wavenoise.spectra import Spectrum
from .wavenoise.tables import WaveTable, build_table
from .wavenoise.settings import WaveSettings, compile_noise
from .grid import evaluate_grid, evaluate_points, Cancelled
from . import bake, jobs, job_file, sources, transfer  # noqa: E402  (bake pipeline: sources -> ramp -> files)

__all__ = ["SettingError", "Spectrum", "WaveTable", "build_table", "WaveSettings", "compile_noise",
           "evaluate_grid", "evaluate_points", "Cancelled"]
from .version import __version__  # noqa: E402  (its own module: submodules read it without importing the package)
