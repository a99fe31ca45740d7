"""CPU thread budget of a training run: torch's intra-op threads and numba's parallel kernels together.

The zoo's wave classes run :mod:`backend`'s numba kernels, whose thread pool
keeps every core busy between calls.  A run told to use one thread (so that two
runs share two cores) must limit both libraries, or the idle numba workers
slow the torch steps several-fold (measured: 1.4 s -> 5 s per step at 32²).
"""
from __future__ import annotations

from contextlib import contextmanager

import torch

__all__ = ["cpu_threads"]


@contextmanager
def cpu_threads(n: int):
    """Within the block torch uses ``n`` threads and numba at most ``n`` (0: both unchanged); restored after."""
    if not n:
        yield
        return
    try:
        import numba
    except ImportError:  # numba is optional for training
        numba = None
    before = torch.get_num_threads(), numba.get_num_threads() if numba else 0
    torch.set_num_threads(n)
    if numba:
        numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        torch.set_num_threads(before[0])
        if numba:
            numba.set_num_threads(before[1])
