"""Optional compiled evaluation of wave noise (numba), identical maths to backend.wave.

Used when numba is importable (the project's .venv installs it; Blender's
bundled Python does not, and then the numpy path runs).  Covers single-table
noises: isotropic, lobes, animated, custom waveforms.  Axis/sector tables and
transitions use the numpy path.

Random numbers are not re-implemented here: per-slice records (border position,
direction, offset) come from :meth:`backend.wave.WaveNoise.slice_records` for the
range of slice ids a chunk touches, and the kernel gathers them.  The blend
weights cos/sin(pi/2 s) use polynomials accurate to 5e-7.
Set OMNINOISE_NO_JIT=1 to disable.
"""
from __future__ import annotations

import os

import numpy as np

try:  # optional accelerator
    if os.environ.get("OMNINOISE_NO_JIT"):
        raise ImportError("disabled by OMNINOISE_NO_JIT")
    import numba
except ImportError:  # pragma: no cover - exercised when numba is absent
    numba = None

__all__ = ["available", "supports", "evaluate"]

_F = np.float32
#: fall back to numpy when one stratum would need more slice records than this
MAX_RECORDS = 1 << 20


def available() -> bool:
    return numba is not None


def supports(noise) -> bool:
    return numba is not None and noise.table.mode == "single" and noise.transition is None


if numba is not None:

    @numba.njit(cache=True, fastmath=False, inline="always")
    def _cos_half_pi(s):
        # cos(pi/2 s), s in [0, 1]: Taylor series of cos to x^12 (error < 5e-7)
        x = np.float32(1.5707963267948966) * s
        x2 = x * x
        return np.float32(1.0) + x2 * (np.float32(-0.5) + x2 * (np.float32(1.0 / 24) + x2 * (
            np.float32(-1.0 / 720) + x2 * (np.float32(1.0 / 40320) + x2 * (
                np.float32(-1.0 / 3628800) + x2 * np.float32(1.0 / 479001600))))))

    @numba.njit(parallel=True, cache=True, fastmath=False)
    def _kernel(x, sdirs, soffs, amps, nmin, slpos, omega, zeta, tab, inv_period, shift, out_re, out_im):
        P, D = x.shape
        K = sdirs.shape[0]
        N = tab.shape[0] - 2
        fN = np.float32(N)
        half = np.float32(0.5)
        for i in numba.prange(P):
            zr = np.float32(0.0)
            zi = np.float32(0.0)
            for k in range(K):
                acc = np.float32(0.0)
                for d in range(D):
                    acc += x[i, d] * sdirs[k, d]
                p = acc + soffs[k]
                n = np.floor(p)
                f = p - n
                r = np.int64(n - nmin[k])
                u = (f - slpos[k, r]) * np.float32(0.5 / 0.3) + half
                if u < 0:
                    u = np.float32(0.0)
                elif u > 1:
                    u = np.float32(1.0)
                s = u * u * (np.float32(3.0) - np.float32(2.0) * u)
                w0 = _cos_half_pi(s)
                w1 = _cos_half_pi(np.float32(1.0) - s)
                br = np.float32(0.0)
                bi = np.float32(0.0)
                for side in range(2):
                    rr = r + side
                    dot = np.float32(0.0)
                    for d in range(D):
                        dot += x[i, d] * omega[k, rr, d]
                    c = (dot - shift) * inv_period + zeta[k, rr]
                    c = c - np.floor(c)
                    j = c * fN - half
                    j0 = np.floor(j)
                    t = j - j0
                    idx = np.int64(j0) + 1
                    ar = tab[idx, 0] + (tab[idx + 1, 0] - tab[idx, 0]) * t
                    ai = tab[idx, 1] + (tab[idx + 1, 1] - tab[idx, 1]) * t
                    w = w0 if side == 0 else w1
                    br += w * ar
                    bi += w * ai
                zr += amps[k] * br
                zi += amps[k] * bi
            out_re[i] = zr
            out_im[i] = zi


def _padded_table(values: np.ndarray) -> np.ndarray:
    """(size,) complex -> float32 (size + 2, 2) with one wrapped texel on each side."""
    t = values[0]
    pad = np.concatenate([t[-1:], t, t[:1]])
    return np.ascontiguousarray(np.stack([pad.real, pad.imag], axis=1).astype(_F))


def evaluate(noise, x: np.ndarray, time) -> np.ndarray | None:
    """Complex noise at x: float32 (P, dim) -> complex64 (P,), or None when not applicable."""
    if not supports(noise) or np.ndim(time) != 0 or len(x) == 0:
        return None
    K = noise.dirs.count
    lo, hi = x.min(axis=0), x.max(axis=0)
    sd = noise.slice_dirs
    pmin = np.sum(np.minimum(sd * lo, sd * hi), axis=1) + noise.slice_offsets
    pmax = np.sum(np.maximum(sd * lo, sd * hi), axis=1) + noise.slice_offsets
    nmin = np.floor(pmin).astype(_F) - _F(1.0)
    span = int(np.max(np.floor(pmax) - nmin)) + 3
    if span > MAX_RECORDS:
        return None
    D = noise.dim
    slpos = np.empty((K, span), _F)
    omega = np.empty((K, span, D), _F)
    zeta = np.empty((K, span), _F)
    for k in range(K):
        m = (nmin[k] + np.arange(span, dtype=_F)).astype(_F) + _F(0.0)
        slpos[k], omega[k], zeta[k] = noise.slice_records(k, m)
    if not hasattr(noise, "_fast_table"):
        noise._fast_table = _padded_table(noise.table.values)
    re = np.empty(len(x), _F)
    im = np.empty(len(x), _F)
    _kernel(np.ascontiguousarray(x, _F), sd, noise.slice_offsets, noise.dirs.amp, nmin, slpos, omega, zeta,
            noise._fast_table, _F(1.0 / noise.table.period), _F(noise.speed) * _F(time), re, im)
    return (re + 1j * im).astype(np.complex64)
