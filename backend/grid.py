"""Chunked evaluation of a noise on a regular grid, with progress and cancel.

A box grid has ``shape`` samples, indexed (y, x) in 2D and (z, y, x) in 3D, at
positions ``lo[a] + i * step[a]`` along axis a (x is axis 0).  A box of lower
rank than the noise (an image of a 3D noise) holds the remaining coordinates
at ``lo``; for 4D noise the fourth coordinate, W, is ``lo[3]``.

:func:`evaluate_grid` is the cubic special case used by the CLI: N samples per
axis over [0, E), sample i at i * E / N, W (4D) or time (2D+t, 3D+t) given by
``time``.  Work streams in slabs of whole rows so peak memory stays near the
output's size; ``out`` may be a ``np.memmap``.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .wavenoise.cellular import CellularNoise
from .errors import SettingError
from .wavenoise import fast
from .wavenoise.wave import OUTPUTS, WaveNoise, select_output

__all__ = ["Cancelled", "evaluate_grid", "evaluate_box", "grid_shape", "evaluate_points"]

_F = np.float32
ProgressFn = Callable[[float], None]
#: samples per slab (progress and cancel are checked between slabs) where points are evaluated in numpy or numba:
#: bounds the (rows, row, dim) coordinate temporaries
POINT_CHUNK = 1 << 18
#: samples per slab where the compiled row kernel fills rows in place (grid_plan): about 25 ms of work on two
#: cores, so progress stays smooth while each slab's thread start and tail (about 1 ms) stay small beside it
PLAN_CHUNK = 1 << 20


class Cancelled(RuntimeError):
    """Raised when the cancel callback asks to stop; nothing has been written."""


def grid_shape(dim: int, size: int) -> tuple:
    return (size,) * min(dim, 3)


def evaluate_points(noise, x: np.ndarray, output: str, time: float = 0.0, cellular: str = "none") -> np.ndarray:
    """Real-valued output at points x: float32 (P, dim) -> float32 (P,)."""
    if isinstance(noise, CellularNoise):
        res = noise.evaluate(x)
        return res.distance if cellular == "polytope" else res.cell
    return select_output(noise.evaluate(x, time), output)


def evaluate_grid(noise: WaveNoise | CellularNoise, size: int, extent: float, output: str = "real",
                  time: float = 0.0, cellular: str = "none", out: np.ndarray | None = None,
                  progress: ProgressFn | None = None, cancel: Callable[[], bool] | None = None,
                  chunk: int | None = None, origin: tuple | None = None) -> np.ndarray:
    """Evaluate on an N^d grid (d = min(dim, 3)) -> float32 array of :func:`grid_shape`.

    time     animation time (2D+t, 3D+t) or the W coordinate (4D)
    progress called with the finished fraction after each slab
    cancel   polled between slabs; returning True raises :class:`Cancelled`
    chunk    samples per slab (None: :data:`PLAN_CHUNK` on the row kernel, else :data:`POINT_CHUNK`)
    """
    dim = noise.dim
    if size < 1:
        raise SettingError("size", f"must be >= 1, got {size}")
    if not extent > 0:
        raise SettingError("extent", f"must be positive, got {extent}")
    lo = np.zeros(dim, _F) if origin is None else np.array(origin, _F)
    if dim == 4:
        lo[3] += _F(time)
    step = (extent / size,) * min(dim, 3)
    return evaluate_box(noise, grid_shape(dim, size), lo, step, output, 0.0 if dim == 4 else time,
                        cellular, out, progress, cancel, chunk)


def evaluate_box(noise: WaveNoise | CellularNoise, shape: tuple, lo, step, output: str = "real",
                 time: float = 0.0, cellular: str = "none", out: np.ndarray | None = None,
                 progress: ProgressFn | None = None, cancel: Callable[[], bool] | None = None,
                 chunk: int | None = None, start: tuple | None = None) -> np.ndarray:
    """Evaluate on a box grid -> float32 array of ``shape``.

    shape  (ny, nx) or (nz, ny, nx); rank <= min(noise.dim, 3)
    lo     float (noise.dim,): position of sample index 0 (all further coordinates fixed here)
    step   float (rank,): spacing along x, y[, z]
    start  int (rank,): index of this box's first sample along x, y[, z] (default 0):
           sample i sits at lo + (start + i) * step, so sub-boxes of a grid
           reproduce the whole grid's values exactly
    time   animation time of 2D+t / 3D+t noise (4D noise takes W from ``lo[3]``)
    """
    dim = noise.dim
    shape = tuple(int(n) for n in shape)
    rank = len(shape)
    if rank not in (2, 3) or rank > min(dim, 3):
        raise SettingError("shape", f"a {dim}D noise bakes 2D{' or 3D' if dim > 2 else ''} grids, got {shape}")
    if min(shape) < 1:
        raise SettingError("shape", f"every axis needs at least 1 sample, got {shape}")
    base = np.asarray(lo, _F).reshape(-1)
    if base.shape != (dim,):
        raise SettingError("lo", f"expected {dim} coordinates, got {base.shape[0]}")
    steps = np.asarray(step, np.float64).reshape(-1)
    if steps.shape != (rank,) or not np.all(steps > 0):
        raise SettingError("step", f"expected {rank} positive spacings, got {tuple(steps)}")
    if out is None:
        out = np.empty(shape, _F)
    elif out.shape != shape:
        raise SettingError("out", f"expected shape {shape}, got {out.shape}")
    first = (0,) * rank if start is None else tuple(int(i) for i in start)
    # axis a (x = 0) has shape[rank - 1 - a] samples
    axes = [np.arange(first[a], first[a] + shape[rank - 1 - a], dtype=_F) * _F(steps[a]) for a in range(rank)]
    row = shape[-1]
    rows_total = int(np.prod(shape[:-1]))
    flat = out.reshape(rows_total, row)
    plan = None
    if isinstance(noise, WaveNoise) and output in OUTPUTS:
        hi = base.copy()
        for a in range(rank):
            hi[a] += axes[a][-1]
        plan = fast.grid_plan(noise, base, hi, time)
    if chunk is None:
        chunk = PLAN_CHUNK if plan is not None else POINT_CHUNK
    rows_per = max(1, chunk // row)
    for r0 in range(0, rows_total, rows_per):
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        r1 = min(rows_total, r0 + rows_per)
        others = np.empty((r1 - r0, dim - 1), _F)
        ridx = np.arange(r0, r1)
        others[:, :] = base[1:]
        if rank == 2:
            others[:, 0] += axes[1][ridx]
        else:
            others[:, 0] += axes[1][ridx % shape[1]]
            others[:, 1] += axes[2][ridx // shape[1]]
        xs = axes[0] + base[0]
        if plan is not None:
            _plan_rows(plan, xs, others, output, flat[r0:r1])
        else:
            x = np.empty((r1 - r0, row, dim), _F)
            x[..., 0] = xs[None, :]
            x[..., 1:] = others[:, None, :]
            pts = x.reshape(-1, dim)
            flat[r0:r1] = evaluate_points(noise, pts, output, time, cellular).reshape(r1 - r0, row)
        if progress is not None:
            progress(r1 / rows_total)
    return out


def _plan_rows(plan, xs, others, output, dst) -> None:
    """Rows through the compiled row kernel of :mod:`backend.wavenoise.fast`: xs (nx,), others (rows, dim-1)."""
    re = dst if type(dst) is np.ndarray and output == "real" else np.empty(dst.shape, _F)
    im = None if output == "real" else np.empty(dst.shape, _F)
    plan.rows(xs, others, re, im)
    if output != "real":
        re = select_output(re + np.complex64(1j) * im, output) if output != "imag" else im
    if re is not dst:
        dst[...] = re
