"""Colour encodings shared by the sources and writers (no dependencies beyond numpy)."""
from __future__ import annotations

import numpy as np

__all__ = ["srgb_to_linear"]

_F = np.float32


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] -> scene-linear float32 (IEC 61966-2-1)."""
    c = np.clip(np.asarray(c, _F), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4)).astype(_F)
