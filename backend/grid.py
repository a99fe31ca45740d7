"""Chunked evaluation of a noise on a regular grid, with progress and cancel.

The grid has N samples per axis over [0, E): sample i sits at i * E / N.
Arrays are indexed (y, x) in 2D and (z, y, x) in 3D and 4D (the fourth
coordinate, W, is fixed by ``time``).  Work streams in slabs of whole rows so
peak memory stays near the output's size; ``out`` may be a ``np.memmap``.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .cellular import CellularNoise
from .errors import SettingError
from . import fast
from .wave import OUTPUTS, WaveNoise, select_output

__all__ = ["Cancelled", "evaluate_grid", "grid_shape", "evaluate_points"]

_F = np.float32
ProgressFn = Callable[[float], None]


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
                  chunk: int = 1 << 18, origin: tuple | None = None) -> np.ndarray:
    """Evaluate on an N^d grid (d = min(dim, 3)) -> float32 array of :func:`grid_shape`.

    time     animation time (2D+t, 3D+t) or the W coordinate (4D)
    progress called with the finished fraction after each slab
    cancel   polled between slabs; returning True raises :class:`Cancelled`
    """
    dim = noise.dim
    if size < 1:
        raise SettingError("size", f"must be >= 1, got {size}")
    if not extent > 0:
        raise SettingError("extent", f"must be positive, got {extent}")
    shape = grid_shape(dim, size)
    if out is None:
        out = np.empty(shape, _F)
    elif out.shape != shape:
        raise SettingError("out", f"expected shape {shape}, got {out.shape}")
    g = np.arange(size, dtype=_F) * _F(extent / size)
    base = np.zeros(dim, _F) if origin is None else np.asarray(origin, _F)
    row = size  # samples per row (x varies fastest)
    rows_total = int(np.prod(shape[:-1]))
    rows_per = max(1, chunk // row)
    flat = out.reshape(rows_total, row)
    plan = None
    if isinstance(noise, WaveNoise) and output in OUTPUTS:
        hi = np.full(dim, g[-1], _F)
        if dim == 4:
            hi[3] = _F(time)
        lo = np.where(np.arange(dim) == 3, _F(time), _F(0.0)).astype(_F)
        plan = fast.grid_plan(noise, lo + base, hi + base, 0.0 if dim == 4 else time)
    for r0 in range(0, rows_total, rows_per):
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        r1 = min(rows_total, r0 + rows_per)
        ridx = np.arange(r0, r1)
        if plan is not None:
            _plan_rows(plan, g, ridx, shape, size, dim, time, base, output, flat, r0, r1)
            if progress is not None:
                progress(r1 / rows_total)
            continue
        x = np.empty((r1 - r0, row, dim), _F)
        x[..., 0] = g[None, :]
        if len(shape) == 2:
            x[..., 1] = g[ridx][:, None]
        else:
            x[..., 1] = g[ridx % size][:, None]
            x[..., 2] = g[ridx // size][:, None]
        if dim == 4:
            x[..., 3] = _F(time)
        x += base
        pts = x.reshape(-1, dim)
        t = 0.0 if dim == 4 else time
        flat[r0:r1] = evaluate_points(noise, pts, output, t, cellular).reshape(r1 - r0, row)
        if progress is not None:
            progress(r1 / rows_total)
    return out


def _plan_rows(plan, g, ridx, shape, size, dim, time, base, output, flat, r0, r1) -> None:
    """Rows r0:r1 through the compiled row kernel of :mod:`backend.fast`."""
    others = np.empty((r1 - r0, dim - 1), _F)
    if len(shape) == 2:
        others[:, 0] = g[ridx]
    else:
        others[:, 0] = g[ridx % size]
        others[:, 1] = g[ridx // size]
    if dim == 4:
        others[:, 2] = _F(time)
    others += base[1:]
    xs = g + base[0]
    dst = flat[r0:r1]
    re = dst if type(dst) is np.ndarray and output == "real" else np.empty(dst.shape, _F)
    im = None if output == "real" else np.empty(dst.shape, _F)
    plan.rows(xs, others, re, im)
    if output != "real":
        re = select_output(re + np.complex64(1j) * im, output) if output != "imag" else im
    if re is not dst:
        dst[...] = re
