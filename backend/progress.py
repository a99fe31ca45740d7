"""Progress and cancel across a pipeline's stages.

Every long operation of the backend takes ``progress(fraction)`` (fraction of the work done, in [0, 1]; None: no
one listens) and ``cancel()`` (True: stop; None: never), and stops by raising :class:`~backend.grid.Cancelled`,
leaving nothing half made.  A pipeline gives each stage a part of its bar (:func:`part`) and reports and checks
between steps (:func:`step`).

>>> seen = []
>>> fit = part(seen.append, 0.0, 0.7)      # a stage that takes the first 70 % of the bar
>>> fit(0.5); step(part(seen.append, 0.7, 0.3), 1.0, None)
>>> seen
[0.35, 1.0]
"""
from __future__ import annotations

from .grid import Cancelled

__all__ = ["part", "step", "Cancelled"]


def part(progress, lo: float, share: float):
    """``progress`` heard over [lo, lo + share] of the work: a stage's own fraction f (clipped to [0, 1]) is
    reported as lo + share f; None where ``progress`` is None."""
    if progress is None:
        return None
    return lambda f: progress(lo + share * min(max(float(f), 0.0), 1.0))


def step(progress, fraction: float, cancel) -> None:
    """Report ``fraction`` of a stage done (``progress`` None: nothing) and raise
    :class:`~backend.grid.Cancelled` where ``cancel()`` asks to stop."""
    if progress is not None:
        progress(fraction)
    if cancel is not None and cancel():
        raise Cancelled("cancelled")
