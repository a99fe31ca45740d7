"""Neural noise images from a conditioning grid: DDIM through the ONNX model.

Any size: the network needs sides that are multiples of ``model.multiple_of``;
other sizes are generated on the next larger such grid (the conditioning grid
padded by edge replication) and cropped.  Tileable output uses the circular-
padding network and needs sides that are multiples already (a crop would
break the wrap).  The seed fully determines the output.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import SettingError
from .sampler import ddim_sample, initial_noise

__all__ = ["generate"]

_F = np.float32


def generate(model, cond: np.ndarray, seed: int = 0, steps: int = 30, tileable: bool = False,
             callback: Callable[[int, int, np.ndarray], None] | None = None) -> np.ndarray:
    """cond float32 (E + P, H, W) -> image float32 (H, W) in [0, 1]."""
    cond = np.asarray(cond, _F)
    C, H, W = cond.shape
    want = model.embedding.shape[1] + len(model.params)
    if C != want:
        raise SettingError("conditioning", f"expected {want} channels, got {C}")
    if not 1 <= steps <= 1000:
        raise SettingError("steps", f"must lie in [1, 1000], got {steps}")
    k = model.multiple_of
    if tileable and (H % k or W % k):
        raise SettingError("size", f"tileable output needs sides that are multiples of {k}, got {W}x{H}")
    Hp, Wp = -(-H // k) * k, -(-W // k) * k
    if (Hp, Wp) != (H, W):
        cond = np.pad(cond, ((0, 0), (0, Hp - H), (0, Wp - W)), mode="edge")
    x0 = ddim_sample(model.eps_fn(tileable), initial_noise(seed, (1, 1, Hp, Wp)), cond[None], steps=steps,
                     callback=callback)
    return np.clip((x0[0, 0, :H, :W] + 1.0) * 0.5, 0.0, 1.0).astype(_F)
