"""The C kernels (``rows.c``: wave noise on grid rows and at points, procedural cells), loaded with ctypes when built.

``tools/build_kernel.py`` (run by ``make setup``) compiles ``rows.c`` next to this file as
``_omni_rows.so`` (``.dylib`` on macOS, ``.dll`` on Windows); an installed extension has it from the
``omninoise_rows`` wheel that ``make dist`` builds for each platform.  Without either, or with
OMNINOISE_NO_CKERNEL=1, :mod:`.fast` runs its numba row kernel, which stays the reference: equal bits on
CPUs without AVX2 (the scalar loops), within 2e-6 with the AVX2 loops, which fuse the lerps and the ramp's weights
and sums and take the weights' cosine from a shorter polynomial (see rows.c; tested).  The call releases the GIL, so rows are split across Python threads.

Arrays are those of :class:`backend.wavenoise.fast.GridPlan`; see ``rows.c`` for shapes.  The point kernel
(:func:`points`) evaluates noise at any points where numba is missing (Blender's Python), with numba's point
kernel's bits (a procedural solid's fit reads its turbulence at its cuts' points through it); the cell kernel
(:func:`cells`) runs the procedural cells' nearest feature point loop with numpy's bits.

Table reads in the AVX2 loops come in two forms that read the same texels (so give the same bits): "window"
(two vector loads and a permute where eight texels lie within 16, else a gather) and "gather" (always a
gather).  Which is faster depends on the CPU: gathers are cheap on Intel's Sapphire Rapids and dear on CPUs
whose microcode slows them.  The first large call of a process times both on its own first rows (rows it had to
compute anyway) and keeps the faster (:func:`fetch_mode`); OMNINOISE_FETCH=window|gather sets it instead.
"""
from __future__ import annotations

import ctypes
import os
import sys
import threading
import time

import numpy as np

from ..errors import SettingError

__all__ = ["local_path", "library_path", "available", "set_enabled", "vector", "fetch_mode", "padded", "rows",
           "points", "cells"]

_F = np.float32
ABI = 2
#: texels after the padded table so the 16-texel window loads of rows.c stay inside the arrays
PAD = 16
_SUFFIX = {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")
_lib = None
_enabled = not os.environ.get("OMNINOISE_NO_CKERNEL")
#: omni_rows' vector argument per table-read form
FETCH_MODES = {"window": 1, "gather": 2}
#: the form this process uses: from OMNINOISE_FETCH, else None until the first large call has timed both
_fetch = os.environ.get("OMNINOISE_FETCH") or None
#: a call times both forms when it has at least this many samples (and 16 rows), on its first quarter: pieces
#: of 1/16 of it, about 1 ms each.  Smaller calls (64³ is 1/4 of it) timed pieces of a quarter millisecond and
#: could keep the slower form for the whole process: a 128³ grid after a 64³ one took 20.8 ns per sample
#: instead of 14.8 (AMD EPYC); they use windows, undecided, until a large call decides
CALIBRATE_SAMPLES = 1 << 20


def local_path() -> str:
    """Where tools/build_kernel.py builds the library for this machine (a development checkout)."""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "_omni_rows" + _SUFFIX)


def library_path() -> str | None:
    """The library to load: a local build, else the ``omninoise_rows`` wheel's (the extension's); or None."""
    if os.path.isfile(local_path()):
        return local_path()
    try:
        import omninoise_rows
    except ImportError:
        return None
    path = getattr(omninoise_rows, "LIBRARY", None)
    return path if path and os.path.isfile(path) else None


def _load():
    global _lib
    if _lib is None:
        _lib = False
        path = library_path()
        if path is None:
            return None
        try:
            lib = ctypes.CDLL(path)
            if lib.omni_abi() != ABI:
                return None
        except (OSError, AttributeError):  # a library of another platform or an older build: numba runs
            return None
        f, i64, i32 = ctypes.POINTER(ctypes.c_float), ctypes.c_int64, ctypes.c_int
        lib.omni_rows.argtypes = [f, i64, f, i64, i64, f, f, f, i64, i64, f, f, f, f, i64, f, f, f, f, i64,
                                  ctypes.c_float, ctypes.c_float, i32, i32, f, f]
        lib.omni_rows.restype = None
        lib.omni_points.argtypes = [f, i64, i64, i64, f, f, f, i64, f, f, f, f, i64, f, i64, ctypes.c_float,
                                    ctypes.c_float, f, f, i32]
        lib.omni_points.restype = None
        lp = ctypes.POINTER(ctypes.c_int64)
        lib.omni_cells.argtypes = [f, lp, i64, i64, f, f, i64, i64, i64, ctypes.c_float, f, f, lp]
        lib.omni_cells.restype = None
        lib.omni_vector.restype = i32
        _lib = lib
    return _lib or None


def available() -> bool:
    """True when the kernel is built, loads, and is enabled (see :func:`set_enabled`)."""
    return _enabled and _load() is not None


def set_enabled(on: bool) -> bool:
    """Switch the kernel on or off for grids planned from now on (the bench compares both); returns
    the previous setting."""
    global _enabled
    before, _enabled = _enabled, bool(on)
    return before


def vector() -> bool:
    """True where the loaded kernel runs its AVX2 loops (else its scalar ones)."""
    lib = _load()
    return bool(lib is not None and lib.omni_vector())


def fetch_mode() -> str | None:
    """The table-read form the AVX2 loops use in this process ("window" or "gather"), or None while no call has
    been large enough to time them.  OMNINOISE_FETCH with another value is an error, named here."""
    if _fetch is not None and _fetch not in FETCH_MODES:
        raise SettingError("OMNINOISE_FETCH", f"must be one of {', '.join(FETCH_MODES)}, got {_fetch!r}")
    return _fetch


def padded(table: np.ndarray) -> tuple:
    """float32 (N + 2, 2) padded table (fast._padded_table) -> tre, tim, dre, dim: float32 (N + 2 + PAD)
    values and forward differences T[i + 1] - T[i] (float32, as the reference computes them)."""
    out = []
    for c in range(2):
        v = np.zeros(len(table) + PAD, _F)
        v[:len(table)] = table[:, c]
        d = np.zeros_like(v)
        d[:len(table) - 1] = table[1:, c] - table[:-1, c]
        out.append((v, d))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def _threads() -> int:
    numba = sys.modules.get("numba")  # numba's thread count when it runs (Blender and the CLI may set it)
    if numba is not None:
        return numba.get_num_threads()
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))


def _checked(kernel: str, arrays: list):
    """The loaded library, once every (array, dtype) of ``arrays`` is C-contiguous of that dtype (else ValueError);
    RuntimeError where it is not built (callers ask :func:`available` first)."""
    lib = _load()
    if lib is None:
        raise RuntimeError(f"the C {kernel} kernel is not built (python tools/build_kernel.py)")
    for a, t in arrays:
        if a.dtype != t or not a.flags.c_contiguous:
            kinds = " and ".join(sorted({np.dtype(t).name for _, t in arrays}))
            raise ValueError(f"the C {kernel} kernel needs C-contiguous {kinds} arrays")
    return lib


def rows(xs, others, sdirs, soffs, amps, nmin, slpos, omega, zeta, tables, inv_period, shift,
         out_re, out_im=None, use_vector: bool = True) -> None:
    """Fill out_re (and out_im) float32 (R, Nx), C-contiguous, like fast._rows_kernel.

    tables: :func:`padded`'s four arrays.  Every array must be C-contiguous float32 (checked)."""
    arrays = (xs, others, sdirs, soffs, amps, nmin, slpos, omega, zeta, *tables, out_re)
    lib = _checked("row", [(a, _F) for a in arrays + ((out_im,) if out_im is not None else ())])
    R, Nx = out_re.shape
    K, D = sdirs.shape
    if xs.shape != (Nx,) or others.shape != (R, D - 1) or (out_im is not None and out_im.shape != (R, Nx)):
        raise ValueError(f"row kernel shapes: xs {xs.shape}, others {others.shape}, out {out_re.shape}")
    S = slpos.shape[1]
    N = len(tables[0]) - 2 - PAD
    im = _ptr(out_im) if out_im is not None else None
    vec = bool(use_vector) and lib.omni_vector()
    args = (_ptr(sdirs), _ptr(soffs), _ptr(amps), K, D, _ptr(nmin), _ptr(slpos), _ptr(omega), _ptr(zeta), S,
            *[_ptr(t) for t in tables], N, _F(inv_period), _F(shift), int(out_im is not None))

    def run(r0, r1, mode=None):
        m = FETCH_MODES[mode or fetch_mode() or "window"] if vec else 0  # undecided (a small call): windows
        lib.omni_rows(_ptr(xs), Nx, _ptr(others), r0, r1, *args, m, _ptr(out_re), im)

    first = 0
    if vec and fetch_mode() is None and R >= 16 and R * Nx >= CALIBRATE_SAMPLES:
        first = _calibrate(run, R)  # a quarter of the rows at most
    _split(run, first, R)


def points(x, sdirs, soffs, amps, nmin, slpos, omega, zeta, table, inv_period, shift, out_re, out_im,
           use_vector: bool = True) -> None:
    """Fill out_re and out_im float32 (P,) with the noise at points x float32 (P, D), like fast_kernels._kernel
    (the same bits). ``table``: the padded table float32 (N + 2, 2) of fast._padded_table; ``use_vector``: the
    AVX2 build where the CPU runs it, else the scalar one.  Every array must be C-contiguous float32 (checked)."""
    lib = _checked("point", [(a, _F) for a in (x, sdirs, soffs, amps, nmin, slpos, omega, zeta, table, out_re,
                                                out_im)])
    P, D = x.shape
    K = sdirs.shape[0]
    if sdirs.shape != (K, D) or out_re.shape != (P,) or out_im.shape != (P,) or table.ndim != 2:
        raise ValueError(f"point kernel shapes: x {x.shape}, sdirs {sdirs.shape}, out {out_re.shape}")
    S = slpos.shape[1]
    args = (D, _ptr(sdirs), _ptr(soffs), _ptr(amps), K, _ptr(nmin), _ptr(slpos), _ptr(omega), _ptr(zeta), S,
            _ptr(table), len(table) - 2, _F(inv_period), _F(shift), _ptr(out_re), _ptr(out_im), int(bool(use_vector)))
    _split(lambda i0, i1: lib.omni_points(_ptr(x), i0, i1, *args), 0, P, grain=4096)


def cells(local, back, near, hashes, first: int, jitter: float, f1, f2, which) -> None:
    """One batch of :func:`backend.solid.procedural.cells.voronoi`'s loop (the same bits): points' ``local``
    float32 (P, 3) positions in their cubes and ``back`` int64 (P,) rows of their cubes, against the neighbour
    offsets ``near`` float32 (B, 3) whose cubes' feature point offsets are ``hashes`` float32 (B, C, 3); updates F1,
    F2 float32 (P,) and ``which`` int64 (P,), the nearest feature point's neighbour (``first`` + its batch row)."""
    lib = _checked("cell", [(local, _F), (near, _F), (hashes, _F), (f1, _F), (f2, _F), (back, np.int64),
                            (which, np.int64)])
    P, B = len(local), len(near)
    if local.shape != (P, 3) or near.shape != (B, 3) or hashes.shape[::2] != (B, 3) or not (
            back.shape == f1.shape == f2.shape == which.shape == (P,)):
        raise ValueError(f"cell kernel shapes: local {local.shape}, near {near.shape}, hashes {hashes.shape}")
    lp = ctypes.POINTER(ctypes.c_int64)
    bp, wp = back.ctypes.data_as(lp), which.ctypes.data_as(lp)
    args = (_ptr(near), _ptr(hashes), B, hashes.shape[1], int(first), _F(jitter), _ptr(f1), _ptr(f2), wp)
    _split(lambda i0, i1: lib.omni_cells(_ptr(local), bp, i0, i1, *args), 0, P, grain=4096)


def _split(run, first: int, R: int, grain: int = 1) -> None:
    """run(r0, r1) over rows (or points) first .. R - 1 on up to _threads() threads: the calling thread and
    helpers that live for this call only, taking pieces of at least ``grain`` rows in turn."""
    n = max(1, min(_threads(), (R - first) // grain))
    if n == 1:
        return run(first, R)
    # more pieces than threads, so a thread that got cheap rows takes another.  The calling thread works too,
    # beside n - 1 helpers that live for this call only (none outlives a bake; starting one takes about 0.3 ms)
    pieces = min((R - first) // grain, 4 * n)
    bounds = [first + (R - first) * i // pieces for i in range(pieces + 1)]
    todo = iter([(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a])
    lock, errors = threading.Lock(), []

    def work():
        try:
            while True:
                with lock:
                    piece = next(todo, None)
                if piece is None:
                    return
                run(*piece)
        except BaseException as exc:  # re-raised in the calling thread
            errors.append(exc)

    helpers = [threading.Thread(target=work, name="omninoise-rows", daemon=True) for _ in range(n - 1)]
    for h in helpers:
        h.start()
    work()
    for h in helpers:
        h.join()
    if errors:
        raise errors[0]


def _calibrate(run, R: int) -> int:
    """Time both table-read forms on the call's first rows (computed for real, one thread), keep the faster for
    this process; returns how many rows are done.  Each form does two pieces of about 1/16 of the rows,
    interleaved, and its faster piece counts."""
    global _fetch
    step = max(1, R // 16)
    best, row = {}, 0
    for mode in ("window", "gather", "window", "gather"):
        t = time.perf_counter()
        run(row, row + step, mode)
        best[mode] = min(best.get(mode, float("inf")), time.perf_counter() - t)
        row += step
    _fetch = min(best, key=best.get)
    return row
