"""Checks of user numbers shared by the CLI, job files and panels: finite, in range, affordable.

Every check raises :class:`SettingError` naming the setting, so each front-end
reports a one-line error (exit status 2) instead of a traceback, a hang or a
crash in a compiled kernel (NaN or infinite time would reach the numba row
kernel and end the process with a segmentation fault).

Limits (each front end names the setting when a value passes one):

MAX_DIRECTIONS     wave directions K (a table per direction; 4096 is far past visible benefit)
MAX_TABLE_SIZE     samples per wave table
MAX_FRAMES         frames one bake or animation writes
MAX_THREADS        CPU threads a command may ask for
MAX_REFINE         search steps refining a solid texture's code (each renders two planes)
MAX_TIME           |time| of an animation or 4D coordinate (float32 phases stay finite and meaningful)
MAX_SPEED          |speed| of animated waves, units per unit time
MIN_LENGTH         the shortest length a setting may give (a slice width, a table period, an extent), world units
MAX_COORD          |world coordinate| of a grid's bounds, an image's extent, an origin or a length, world units
MAX_FREQUENCY      a wave spectrum's frequencies, cycles per world unit
MAX_CYCLES         wave cycles (or cellular cells) from the origin to the farthest point a request reaches: the
                   product of the two above; past about 1e9 float32 phases lose the waves and the noise turns
                   into a few flat values
SCALE_RANGE        a solid texture's scale, texture units per world unit (past it, points overflow or one texel
                   fills the output)
MEMORY_LIMIT       bytes one request may allocate for its result: 16 GiB, or half the machine's memory where that
                   is less; OMNINOISE_MEMORY_LIMIT overrides
"""
from __future__ import annotations

import math
import os
import re

from .errors import SettingError

__all__ = ["MAX_DIRECTIONS", "MAX_TABLE_SIZE", "MAX_FRAMES", "MAX_THREADS", "MAX_REFINE", "SCALE_RANGE", "MAX_TIME", "MAX_SPEED", "MIN_LENGTH", "MAX_COORD", "MAX_FREQUENCY", "MAX_CYCLES", "scale", "time", "cpus", "threads", "frame_count", "memory_limit", "finite", "positive", "in_range", "check_int",
           "check_memory"]

MAX_DIRECTIONS = 4096
MAX_TABLE_SIZE = 1 << 20
MAX_FRAMES = 100_000
MAX_THREADS = 1024
MAX_REFINE = 10_000
SCALE_RANGE = (1e-4, 1e4)
MAX_TIME = 1e9
MAX_SPEED = 1e6
MIN_LENGTH = 1e-6
MAX_COORD = 1e7
MAX_FREQUENCY = 1e5
MAX_CYCLES = 1e8
_DEFAULT_MEMORY = 16 << 30     #: the default limit where half the machine's memory is more


#: a number of bytes: digits (a fraction, an exponent) and a binary unit, 8G, 512M, 8GB, 8GiB, 1.5T, 2e9
_BYTES = re.compile(r"((?:\d+(?:\.\d*)?|\.\d+)(?:E[+-]?\d+)?)\s*([KMGT]?)(?:I?B)?")
_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def physical_memory() -> int | None:
    """Bytes of memory this process may use: the machine's, or its container's (cgroup v2) where less; None where
    the system does not say (Windows)."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None
    try:
        with open("/sys/fs/cgroup/memory.max", encoding="ascii") as fh:
            capped = fh.read().strip()
        total = min(total, int(capped)) if capped.isdigit() else total
    except OSError:
        pass
    return total if total > 0 else None


def default_memory() -> int:
    """The limit without OMNINOISE_MEMORY_LIMIT: 16 GiB, or half of :func:`physical_memory` where that is less: a
    model's own memory and the rest of the process come on top of a result's peak (a 512^3 cloud volume: 4.5 GiB
    estimated by ``backend.bake.PEAK_BYTES``, 3.5 GiB measured), and past the memory the system kills the process,
    Blender and its unsaved file with it."""
    ram = physical_memory()
    return _DEFAULT_MEMORY if ram is None else min(_DEFAULT_MEMORY, ram // 2)


def _given_memory() -> str:
    """OMNINOISE_MEMORY_LIMIT as set, "" where it is not."""
    return os.environ.get("OMNINOISE_MEMORY_LIMIT", "").strip()


def memory_limit() -> int:
    """Bytes a single result may take: OMNINOISE_MEMORY_LIMIT (bytes, or with a K/M/G/T suffix), default
    :func:`default_memory`; a value that is no positive number of bytes up to 2^60 is a SettingError (it would
    refuse every result, or none)."""
    given = _given_memory()
    if not given:
        return default_memory()
    m = _BYTES.fullmatch(given.upper())
    n = float(m[1]) * _UNITS[m[2]] if m else 0.0
    if not 1.0 <= n <= 2.0 ** 60:
        raise SettingError("OMNINOISE_MEMORY_LIMIT", f"expected a positive number of bytes like 8G (a K, M, G or T "
                                                     f"suffix), got {given!r}")
    return int(n)


def _num(name: str, value) -> float:
    if isinstance(value, (bool, str)):
        raise SettingError(name, f"expected a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise SettingError(name, f"expected a number, got {value!r}") from None


def finite(name: str, value) -> float:
    v = _num(name, value)
    if not math.isfinite(v):
        raise SettingError(name, f"must be a finite number, got {value!r}")
    return v


def positive(name: str, value) -> float:
    v = finite(name, value)
    if v <= 0.0:
        raise SettingError(name, f"must be positive, got {v:g}")
    return v


def in_range(name: str, value, lo: float, hi: float) -> float:
    v = finite(name, value)
    if not lo <= v <= hi:
        raise SettingError(name, f"must lie in [{lo:g}, {hi:g}], got {v:g}")
    return v


def frame_count(name: str, first: int, last: int, writer: str) -> None:
    """At most MAX_FRAMES frames from ``first`` to ``last`` (inclusive) for one ``writer`` ("bake", "run")."""
    if last - first >= MAX_FRAMES:
        raise SettingError(name, f"{int(last - first + 1)} frames is more than the {MAX_FRAMES} one {writer} may write")


def time(name: str, value) -> float:
    """A time (or 4D coordinate): finite, within MAX_TIME of zero."""
    return in_range(name, value, -MAX_TIME, MAX_TIME)


def scale(name: str, value) -> float:
    """A solid texture's scale: finite, in SCALE_RANGE."""
    return in_range(name, value, *SCALE_RANGE)


def check_int(name: str, value, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise SettingError(name, f"expected a whole number, got {value!r}")
    if not lo <= value <= hi:
        raise SettingError(name, f"must lie in [{lo}, {hi}], got {value}")
    return value


def cpus() -> int:
    """The CPUs this process may run on (its affinity where the system says, else the machine's count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):       # macOS and Windows have no affinity call
        return max(1, os.cpu_count() or 1)


def threads(name: str, n) -> int:
    """A count of CPU threads asked for: 0 (all CPUs) up to :func:`cpus`.  More threads than CPUs wait on each
    other: neural noise at 64 px on 2 CPUs took 1.1 s with 2 threads, 16.5 s with 64 and 265 s with 1000."""
    n, have = check_int(name, n, 0, MAX_THREADS), cpus()
    if n > have:
        raise SettingError(name, f"{n} threads is more than the {have} CPUs this machine gives it; ask for at most "
                                 f"{have} (0: all of them)")
    return n


def check_memory(name: str, n_bytes: float, what: str) -> None:
    """Refuse a result of ``n_bytes`` above :func:`memory_limit`, saying how much it would need."""
    limit = memory_limit()
    if n_bytes > limit:
        half = ", half this machine's memory" if limit < _DEFAULT_MEMORY and not _given_memory() else ""
        raise SettingError(name, f"{what} needs {_gib(n_bytes)}, above the limit of {_gib(limit)}{half} (set "
                                 "OMNINOISE_MEMORY_LIMIT to raise it)")


def _gib(n_bytes: float) -> str:
    """``n_bytes`` as GiB to one decimal, or MiB below 0.1 GiB (a limit of 1M is not "0.0 GiB")."""
    return f"{n_bytes / 2 ** 30:.1f} GiB" if n_bytes >= 0.1 * 2 ** 30 else f"{n_bytes / 2 ** 20:.1f} MiB"
