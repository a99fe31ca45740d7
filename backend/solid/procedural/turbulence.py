"""Turbulence for the procedural solids: the project's 3D wave noise (Guehl et al. 2025, Alg. 1) with a fractal
spectrum, its real part.

Perlin's solid textures (Perlin 1985, Sec. 5: marble as ``sin(x + turbulence(x))``) bend their rings and layers by
a band-limited noise; here it is wave noise, whose node group Blender renders as the engine does, so a procedural
solid's live node group reproduces it.  One noise per seed, with the band [1, 2^OCTAVES] cycles per unit and
amplitude ~ 1 / f, is read at ``frequency`` times the point: its band is then [frequency, 2^OCTAVES frequency]
(wave noise is scale-covariant: its tables and slices scale with the band, so T_[f, 4f](p) = T_[1, 4](f p) to
float rounding), and the node group's Scale input carries the frequency.

Shapes: points float (P, 3) in texture units -> float32 (P,), spread about 0.4.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ...wavenoise.settings import WaveSettings, compile_noise
from ...wavenoise.spectra import Spectrum

__all__ = ["turbulence_settings", "turbulence", "OCTAVES", "DIRECTIONS"]

OCTAVES = 2.0      #: the band's width in octaves
DIRECTIONS = 16    #: wave directions


def turbulence_settings(seed: int) -> WaveSettings:
    """The wave noise settings of the turbulence drawn with ``seed``: band [1, 2^OCTAVES] cycles per unit."""
    return WaveSettings(dim=3, spectrum=Spectrum(kind="fractal", fmin=1.0, fmax=2.0 ** OCTAVES, exponent=1.0),
                        directions=DIRECTIONS, seed=int(seed) % (1 << 24)).validate()


@lru_cache(maxsize=16)
def _noise(seed: int):
    return compile_noise(turbulence_settings(seed))


def turbulence(points: np.ndarray, frequency: float, seed: int) -> np.ndarray:
    """The turbulence of lowest frequency ``frequency`` (cycles per unit) at points float (P, 3) in texture units
    -> float32 (P,)."""
    pts = np.ascontiguousarray(np.asarray(points, np.float64).reshape(-1, 3) * float(frequency))
    return np.real(_noise(int(seed)).evaluate(pts)).astype(np.float32)
