"""Transparent huge pages for large neural images (Linux, glibc 2.35 or later).

At 1024² onnxruntime's first network evaluation touches about 4 GB of fresh
memory through malloc, and with the kernel's usual THP mode (``madvise``) every
4 KiB page of it is a separate page fault: 6.2 million faults, 15 s for a step
that takes 6.4 s once the memory is mapped.  glibc's malloc tunable
``glibc.malloc.hugetlb=1`` asks for transparent huge pages on the memory it
maps, which cut that to 0.12 million faults and an 8.5 s first step, and a
whole 1024² image from 79 to 71 s (2-core AMD EPYC, README "Speed").  The
images are identical.

A tunable is read once, when the process starts, so the command line re-executes
itself with it (:func:`reexec`) before a large neural image, and a local farm
starts its worker processes with it (:func:`environment`).  ``OMNINOISE_HUGEPAGES=0``
turns both off.
"""
from __future__ import annotations

import os
import platform
import sys

__all__ = ["TUNABLE", "MIN_SIDE", "OFF_ENV", "supported", "environment", "wanted", "reexec"]

TUNABLE = "glibc.malloc.hugetlb=1"
MIN_SIDE = 512                 #: neural images at least this wide get huge pages (256² gains nothing)
OFF_ENV = "OMNINOISE_HUGEPAGES"
_THP = "/sys/kernel/mm/transparent_hugepage/enabled"


def _glibc_at_least(version: str, need=(2, 35)) -> bool:
    try:
        return tuple(int(p) for p in version.split(".")[:2]) >= need
    except ValueError:
        return False


def supported(system: str | None = None, libc: tuple | None = None, thp: str | None = None) -> bool:
    """Whether the tunable can take effect here: Linux, glibc >= 2.35 and THP not ``never``
    (the arguments stand in for ``platform.system()``, ``platform.libc_ver()`` and the THP setting)."""
    system = platform.system() if system is None else system
    if system != "Linux":
        return False
    name, version = platform.libc_ver() if libc is None else libc
    if name != "glibc" or not _glibc_at_least(version):
        return False
    if thp is None:
        try:
            with open(_THP, encoding="ascii") as fh:
                thp = fh.read()
        except OSError:
            return False
    return "[never]" not in thp


def environment(env, **probe) -> dict:
    """``env`` (a mapping) with the tunable added to GLIBC_TUNABLES where :func:`supported` and not
    turned off by ``OMNINOISE_HUGEPAGES=0``; unchanged (a copy) otherwise, or when it is already set."""
    out = dict(env)
    if out.get(OFF_ENV) == "0" or not supported(**probe):
        return out
    have = out.get("GLIBC_TUNABLES", "")
    if "glibc.malloc.hugetlb=" in have:
        return out
    out["GLIBC_TUNABLES"] = f"{have}:{TUNABLE}" if have else TUNABLE
    return out


def wanted(command: str, size: int, env, **probe) -> bool:
    """Whether ``omninoise COMMAND`` should re-execute itself: a neural image of at least MIN_SIDE px
    a side, in a process that does not have the tunable yet and could use it."""
    return command == "neural" and size >= MIN_SIDE and environment(env, **probe) != dict(env)


def reexec() -> None:
    """Replace this process by the same command line with the tunable set (never returns)."""
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, [sys.executable, *sys.orig_argv[1:]], environment(os.environ))
