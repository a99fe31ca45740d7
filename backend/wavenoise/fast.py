"""Optional compiled evaluation of wave noise (numba), identical maths to backend.wavenoise.wave.

Used when numba is importable (the project's .venv installs it; Blender's
bundled Python does not, and then the C kernel of :mod:`.ckernel` runs where it is
built, else the numpy path).  Covers single-table
noises: isotropic, lobes, animated, custom waveforms.  Axis/sector tables and
transitions use the numpy path.

Random numbers are not re-implemented here: per-slice records (border position,
direction, offset) come from :meth:`backend.wavenoise.wave.WaveNoise.slice_records` for the
range of slice ids a chunk touches, and the kernel gathers them.  The blend
weights cos/sin(pi/2 s) use polynomials accurate to 5e-7.
Set OMNINOISE_NO_JIT=1 to disable.

Grid rows (:class:`GridPlan`) run the C kernel of :mod:`.ckernel` instead where it is built (``make
setup``), with or without numba: same maths, within 1e-6, faster; the numba row kernel is the reference.  Points
(:func:`evaluate`) run the C point kernel where numba is missing (Blender): the numba point kernel's bits.
"""
from __future__ import annotations

import importlib.util
import os

import numpy as np

from . import ckernel

#: True where numba is installed and not disabled: its kernels (fast_kernels) are imported on first use,
#: so importing the engine, the command line or the add-on does not load numba (0.2 s)
numba = bool(importlib.util.find_spec("numba")) and not os.environ.get("OMNINOISE_NO_JIT")

__all__ = ["available", "compiled", "supports", "evaluate"]

_F = np.float32
#: fall back to numpy when one stratum would need more slice records than this
MAX_RECORDS = 1 << 20


def _kernels():
    """The numba kernels (compiled or loaded from numba's cache on first call)."""
    from . import fast_kernels
    return fast_kernels


def available() -> bool:
    return bool(numba)


def compiled() -> bool:
    """Whether a compiled kernel (the C row kernel or numba's) evaluates wave noise grids here."""
    return ckernel.available() or bool(numba)


def engine_path() -> str:
    """Which kernel evaluates wave noise grids here, in words: the C row kernel, numba, or numpy (neither is
    installed: ``pip install 'omninoise[fast]'`` brings numba)."""
    if ckernel.available():
        return "C row kernel"
    if numba:
        return "numba kernel"
    return "numpy (pip install 'omninoise[fast]' for the compiled kernel)"


def supports(noise) -> bool:
    """Whether a compiled kernel evaluates this noise at points: numba's, else the C kernel (:func:`.ckernel.points`)
    where it is built (Blender's Python has no numba)."""
    return _single(noise) and (bool(numba) or ckernel.available())


def _single(noise) -> bool:
    return noise.table.mode == "single" and noise.transition is None


def _padded_table(noise) -> np.ndarray:
    """The single table as float32 (size + 2, 2) (re, im) with one wrapped texel on each side; cached."""
    if not hasattr(noise, "_fast_table"):
        t = noise.table.values[0]
        pad = np.concatenate([t[-1:], t, t[:1]])
        noise._fast_table = np.ascontiguousarray(np.stack([pad.real, pad.imag], axis=1).astype(_F))
    return noise._fast_table


def _slice_records(noise, lo: np.ndarray, hi: np.ndarray):
    """Records of every slice the box [lo, hi] (float32 (dim,)) touches, per stratum.

    Returns nmin float32 (K,) (id of each stratum's first slice), slpos (K, S),
    omega (K, S, D), zeta (K, S); or None when a stratum needs more than
    MAX_RECORDS slices.
    """
    sd = noise.slice_dirs
    pmin = np.sum(np.minimum(sd * lo, sd * hi), axis=1) + noise.slice_offsets
    pmax = np.sum(np.maximum(sd * lo, sd * hi), axis=1) + noise.slice_offsets
    nmin = np.floor(pmin).astype(_F) - _F(1.0)
    span = int(np.max(np.floor(pmax) - nmin)) + 3
    if span > MAX_RECORDS:
        return None
    m = (nmin[:, None] + np.arange(span, dtype=_F)).astype(_F) + _F(0.0)
    slpos, omega, zeta = noise.strata_records(m)
    return nmin, slpos, omega, zeta


def evaluate(noise, x: np.ndarray, time) -> np.ndarray | None:
    """Complex noise at x: float32 (P, dim) -> complex64 (P,), or None when not applicable."""
    if not supports(noise) or np.ndim(time) != 0 or len(x) == 0:
        return None
    rec = _slice_records(noise, x.min(axis=0), x.max(axis=0))
    if rec is None:
        return None
    re = np.empty(len(x), _F)
    im = np.empty(len(x), _F)
    args = (np.ascontiguousarray(x, _F), noise.slice_dirs, noise.slice_offsets, noise.dirs.amp, *rec,
            _padded_table(noise), _F(1.0 / noise.table.period), _F(noise.speed) * _F(time), re, im)
    if numba:           # the reference
        _kernels()._kernel(*args)
    else:
        ckernel.points(*args)
    return (re + 1j * im).astype(np.complex64)


# Grid rows: see the row kernel's notes in fast_kernels.py (numba) and rows.c (C).


class GridPlan:
    """Slice records for every slice a box of points touches, for :meth:`rows`.

    Built once per grid (records are hashed in numpy), then reused for every
    slab of rows, so the compiled kernel does no hashing.
    lo, hi: float32 (dim,) corners of the box; time: the animation time.
    """

    def __init__(self, noise, lo: np.ndarray, hi: np.ndarray, time: float):
        rec = _slice_records(noise, lo, hi)
        self.ok = rec is not None
        if not self.ok:
            return
        self.nmin, self.slpos, self.omega, self.zeta = rec
        t = _padded_table(noise)
        self.tre = np.ascontiguousarray(t[:, 0])
        self.tim = np.ascontiguousarray(t[:, 1])
        #: the C kernel's tables (value and difference, padded), when it is built: it then fills the rows
        self.ctables = ckernel.padded(t) if ckernel.available() else None
        self.noise = noise
        self.shift = _F(noise.speed) * _F(time)

    def rows(self, xs: np.ndarray, others: np.ndarray, out_re: np.ndarray, out_im: np.ndarray | None) -> None:
        """Fill rows: xs float32 (Nx,) ascending uniform; others float32 (R, dim-1) -> out (R, Nx).

        ``out_im`` None computes the real part only.
        """
        n = self.noise
        if self.ctables is not None:
            ckernel.rows(np.ascontiguousarray(xs, _F), np.ascontiguousarray(others, _F), n.slice_dirs,
                         n.slice_offsets, n.dirs.amp, self.nmin, self.slpos, self.omega, self.zeta, self.ctables,
                         _F(1.0 / n.table.period), self.shift, out_re, out_im)
            return
        want_imag = out_im is not None
        if out_im is None:
            out_im = np.empty((1, 1), _F)
        k = _kernels()
        k._rows_kernel(np.ascontiguousarray(xs, _F), np.ascontiguousarray(others, _F), n.slice_dirs,
                       n.slice_offsets, n.dirs.amp, self.nmin, self.slpos, self.omega, self.zeta, self.tre,
                       self.tim, _F(1.0 / n.table.period), self.shift, want_imag, 8 * k.numba.get_num_threads(),
                       out_re, out_im)


def grid_plan(noise, lo, hi, time) -> GridPlan | None:
    """A :class:`GridPlan` when the compiled row kernel applies to this noise, else None."""
    if not (_single(noise) and (numba or ckernel.available())) or np.ndim(time) != 0:
        return None
    plan = GridPlan(noise, np.asarray(lo, _F), np.asarray(hi, _F), float(time))
    return plan if plan.ok else None
