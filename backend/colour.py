"""Colour encodings shared by the sources and writers (no dependencies beyond numpy)."""
from __future__ import annotations

import numpy as np

__all__ = ["srgb_to_linear"]

_F = np.float32


#: values converted at a time: the float temporaries stay a few MiB whatever the image's size
_BLOCK = 1 << 18


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] -> scene-linear float32 (IEC 61966-2-1), a block of values at a time."""
    c = np.asarray(c)
    out = np.empty(c.shape, _F)
    flat_in, flat_out = c.reshape(-1), out.reshape(-1)
    for a in range(0, flat_in.size, _BLOCK):
        b = np.clip(np.asarray(flat_in[a: a + _BLOCK], _F), 0.0, 1.0)
        flat_out[a: a + _BLOCK] = np.where(b <= 0.04045, b / 12.92, np.power((b + 0.055) / 1.055, 2.4))
    return out
