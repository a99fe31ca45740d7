"""Periodic (plane-wave) features of a single-photo model: the photo's strongest Fourier components.

    w_k(x) = a_k (cos(2 pi f_k . x + phi_k), sin(2 pi f_k . x + phi_k)),   k = 1 .. K

f_k (cycles per unit of texture space), phi_k and a_k are measured from the model's exemplar when it is
trained (``training.solid.waves.photo_waves``: the local maxima of the Fourier transform of the photo's
periodic component, with the photo's own phases) and stored in its solid.json as rows [f_x, f_y, phi, a].
They give the decoder the photo's courses and weaves, which no noise octave has.  The phase is computed in
float64: at |x| ~ 64 units and f ~ 60 cycles per unit the argument reaches ~2.4e4 rad, where float32 would
lose ~2e-3 rad.

Shapes: points (N, D) float; waves (K, 4) float (D = 2); result float32 (N, 2 K), wave-major
(wave k: cos at 2 k, sin at 2 k + 1).  The torch twin: ``training.solid.waves.wave_features``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["FEATURES", "wave_features"]

FEATURES = 2   #: values per wave: cos and sin


def wave_features(x: np.ndarray, waves: np.ndarray) -> np.ndarray:
    """(N, 2) points, (K, 4) waves -> (N, 2 K) float32 (see the module doc)."""
    w = np.asarray(waves, np.float64)
    t = 2.0 * np.pi * (np.asarray(x, np.float64)[:, :2] @ w[:, :2].T) + w[:, 2]
    out = np.empty((t.shape[0], 2 * w.shape[0]), np.float32)
    out[:, 0::2] = w[:, 3] * np.cos(t)
    out[:, 1::2] = w[:, 3] * np.sin(t)
    return out
