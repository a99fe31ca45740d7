"""Which arithmetic the neural noise denoiser runs in: float32 (the default), or the int8 export.

The int8 denoisers (``training/quantize_onnx.py``) are a faster draft mode, not a free gain: about 1.8x faster
steps on CPUs with int8 dot products (x86 VNNI), little without them, and images that are not the trained
network's own (single classes' distances to the zoo move by up to 15 %, blends are less local; the model card and
docs/decisions/neural.md).  So float32 stays the default and int8 is opt-in.
"""
from __future__ import annotations

import functools
import platform

from ..errors import SettingError

__all__ = ["PRECISIONS", "int8_dot_products", "resolve", "set_default_precision", "default_precision"]

PRECISIONS = ("fp32", "int8")
_DEFAULT = {"precision": "fp32"}


def _check(precision) -> str:
    if precision not in PRECISIONS:
        raise SettingError("precision", f"unknown precision {precision!r}; choose one of {', '.join(PRECISIONS)}")
    return precision


def set_default_precision(precision: str) -> None:
    """The precision of models created without their own (the CLI's ``--precision``, the add-on's preference)."""
    _DEFAULT["precision"] = _check(precision)


def default_precision() -> str:
    return _DEFAULT["precision"]


@functools.lru_cache(maxsize=1)
def int8_dot_products() -> bool:
    """True on an x86 CPU whose flags (Linux /proc/cpuinfo) list AVX512-VNNI or AVX-VNNI, where int8 pays;
    False where unknown.  Informational: benches and help texts say whether int8 is worth it here."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return False
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("flags"):
                    flags = set(line.split(":", 1)[1].split())
                    return bool(flags & {"avx512_vnni", "avx_vnni"})
    except OSError:
        pass
    return False


def resolve(precision: str | None) -> str:
    """"fp32" | "int8" | None (the default) -> the one used; SettingError for an unknown name."""
    return _check(_DEFAULT["precision"] if precision is None else precision)
