"""Periodic plus smooth image decomposition (Moisan 2011, "Periodic plus smooth image decomposition", J. Math.
Imaging Vis. 39): the discrete Fourier transform's view of an image as a tile, without the false spectrum its
borders make.  numpy only; used by the runtime (backend/solid/harmonic.py) and by training and evaluation."""
from __future__ import annotations

import numpy as np

__all__ = ["periodic_component"]


def periodic_component(imgs: np.ndarray) -> np.ndarray:
    """The periodic part p of images u (n, H, W) in the periodic plus smooth decomposition u = p + s (Moisan 2011,
    "Periodic plus smooth image decomposition", J. Math. Imaging Vis. 39: the smooth s carries the jumps between
    opposite edges; Sec. 3, Eq. 11-12 in closed form through the FFT).  The discrete Fourier transform treats an
    image as a tile; an image that is not one jumps at its borders, and those jumps spread power over every
    frequency (a cross through the spectrum, falling like 1/k²).  p has the image's mean; the s taken from an
    image that tiles is only what its ordinary steps across the edges make (smooth and faint).  Returns float64
    (n, H, W)."""
    u = np.asarray(imgs, np.float64)
    n, H, W = u.shape
    v = np.zeros_like(u)  # the boundary image: differences across the opposite edges (Moisan, Eq. 11)
    v[:, 0, :] = u[:, -1, :] - u[:, 0, :]
    v[:, -1, :] = -v[:, 0, :]
    v[:, :, 0] += u[:, :, -1] - u[:, :, 0]
    v[:, :, -1] -= u[:, :, -1] - u[:, :, 0]
    q = 2.0 * np.cos(2.0 * np.pi * np.arange(H) / H)[:, None] + 2.0 * np.cos(2.0 * np.pi * np.arange(W) / W)[None, :] - 4.0
    q[0, 0] = 1.0  # the mean is left to p
    S = np.fft.fft2(v) / q
    S[:, 0, 0] = 0.0
    return u - np.real(np.fft.ifft2(S))
