"""A derivative-free search: Nelder and Mead's simplex (Nelder & Mead 1965, "A simplex method for function
minimization"; the standard coefficients: reflection 1, expansion 2, contraction 1/2, shrink 1/2) over the unit
cube, every coordinate clipped to [0, 1], for at most ``budget`` calls of the function.

A free function over a callable, as the project's samplers are: ``minimise(f, x0, step, budget)``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["minimise"]


class _Spent(Exception):
    """The budget is spent."""


def minimise(f, x0, step: float = 0.1, budget: int = 40, cancel=None) -> tuple:
    """(x, f(x)) of the best point found from ``x0`` (float (d,) in [0, 1]) with a first simplex of side ``step``,
    calling ``f`` at most ``budget`` times; ``cancel()`` returning True stops early with the best so far."""
    best = [None, np.inf]
    calls = [0]

    def g(x):
        if calls[0] >= budget or (cancel is not None and cancel()):
            raise _Spent
        calls[0] += 1
        v = float(f(x))
        if v < best[1]:
            best[:] = [x, v]
        return v

    def clip(x):
        return np.clip(x, 0.0, 1.0)

    x0 = clip(np.asarray(x0, np.float64))
    d = len(x0)
    try:
        pts = [x0] + [clip(x0 + step * np.eye(d)[i] * (1 if x0[i] + step <= 1 else -1)) for i in range(d)]
        vals = [g(p) for p in pts]
        while True:
            order = np.argsort(vals)
            pts, vals = [pts[i] for i in order], [vals[i] for i in order]
            centre = np.mean(pts[:-1], axis=0)
            xr = clip(centre + (centre - pts[-1]))
            fr = g(xr)
            if fr < vals[0]:
                xe = clip(centre + 2.0 * (centre - pts[-1]))
                fe = g(xe)
                pts[-1], vals[-1] = (xe, fe) if fe < fr else (xr, fr)
            elif fr < vals[-2]:
                pts[-1], vals[-1] = xr, fr
            else:
                xc = clip(centre + 0.5 * (pts[-1] - centre)) if fr >= vals[-1] else clip(centre + 0.5 * (xr - centre))
                fc = g(xc)
                if fc < min(fr, vals[-1]):
                    pts[-1], vals[-1] = xc, fc
                else:                   # shrink towards the best
                    for i in range(1, len(pts)):
                        pts[i] = clip(pts[0] + 0.5 * (pts[i] - pts[0]))
                        vals[i] = g(pts[i])
    except _Spent:
        pass
    if best[0] is None:
        return x0, np.inf
    return best[0], best[1]
