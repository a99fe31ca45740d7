"""Training precision on the CPU: bf16 autocast + channels_last where the processor computes bf16 natively.

bf16 matrix units (Intel AMX, AVX512-BF16 on Intel and AMD Zen 4+) roughly halve
a training step of the U-Net; without them oneDNN emulates bf16 and a step gets
slower, so ``precision = "auto"`` picks bf16 only on such processors and float32
elsewhere.  The choice is logged with the run (``log.jsonl``'s first line) and
written into the model card.

    resolve(requested, device) -> "bf16" | "fp32"
    autocast(precision, device) -> context manager for the forward pass and loss
"""
from __future__ import annotations

import contextlib
import platform

import torch

__all__ = ["cpu_bf16_native", "check_precision", "resolve", "autocast", "PRECISIONS"]

PRECISIONS = ("auto", "fp32", "bf16")
_BF16_FLAGS = ("amx_bf16", "avx512_bf16")


def cpu_bf16_native(cpuinfo: str | None = None) -> bool:
    """True when the CPU flags (``/proc/cpuinfo`` on Linux) include AMX-BF16 or AVX512-BF16."""
    if cpuinfo is None:
        if platform.system() != "Linux":
            return False
        try:
            with open("/proc/cpuinfo", encoding="utf-8") as fh:
                cpuinfo = fh.read()
        except OSError:
            return False
    for line in cpuinfo.splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            return any(f in flags for f in _BF16_FLAGS)
    return False


def check_precision(requested) -> str:
    """``requested`` if it is one of PRECISIONS, else ValueError naming the choices (configs check it on load)."""
    if requested not in PRECISIONS:
        raise ValueError(f"precision must be one of {', '.join(PRECISIONS)}, got {requested!r}")
    return requested


def resolve(requested: str, device: torch.device) -> str:
    """The precision a run uses: ``auto`` -> bf16 on CUDA with bf16 support or a bf16-native CPU, else fp32."""
    if check_precision(requested) != "auto":
        return requested
    if device.type == "cuda":
        return "bf16" if torch.cuda.is_bf16_supported() else "fp32"
    return "bf16" if cpu_bf16_native() else "fp32"


def autocast(precision: str, device: torch.device):
    """bf16 autocast on ``device`` for ``precision == "bf16"``; a no-op context for fp32."""
    if precision == "bf16":
        return torch.autocast(device_type=device.type, dtype=torch.bfloat16)
    return contextlib.nullcontext()
