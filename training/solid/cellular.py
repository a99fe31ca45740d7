"""Differentiable torch twin of :mod:`backend.solid.cellular` (Worley 1996 features at Eq. 5's positions).

Same cell hash, same jitter, same 3^D search order, so a model trained here
reads the same cells at run time.  Gradients reach the transforms T_i through
the distances F1, F2 (the cell value is piecewise constant).

Shapes: x (B, N, D) float32; T (m, D, D) or (B, m, D, D); seeds int64 (B, m):
the value noise's octave seeds (``training.solid.value_noise.octave_seeds``), from
which the cells' seeds are derived as at run time; result (B, N, 3 K) float32,
octave-major.
"""
from __future__ import annotations

import torch

from omninoise.backend.solid.cellular import CELL_SALT, FEATURES, offsets
from omninoise.backend.solid.value_noise import BITS, MASK32
from .value_noise import lowbias32_torch, octave_positions, salted_seeds

__all__ = ["cellular_features"]

_LEVELS = (1 << BITS) - 1


def cellular_features(x: torch.Tensor, T: torch.Tensor, seeds: torch.Tensor, octaves: int) -> torch.Tensor:
    """(2 F1 - 1, 2 (F2 - F1) - 1, v) of the first ``octaves`` octaves: (B, N, D) -> (B, N, 3 octaves)."""
    B, N, D = x.shape
    if octaves == 0:
        return x.new_zeros(B, N, 0)
    p = octave_positions(x, T, octaves)                        # (B, K, N, D)
    fl = torch.floor(p)
    f = p - fl
    k = fl.to(torch.int64)
    s = salted_seeds(seeds, octaves, CELL_SALT)                   # backend's cell_seeds
    f1 = torch.full_like(f[..., 0], float("inf"))
    f2 = torch.full_like(f1, float("inf"))
    val = torch.zeros_like(f1)
    for off in offsets(D):
        h = s
        for d in range(D):
            h = lowbias32_torch((h + ((k[..., d] + off[d]) & MASK32)) & MASK32)
        d2 = 0.0
        for d in range(D):
            j = ((h >> (BITS * d)) & _LEVELS).to(x.dtype) * (1.0 / (_LEVELS + 1))
            d2 = d2 + (off[d] + j - f[..., d]) ** 2
        v = (lowbias32_torch(h) & _LEVELS).to(x.dtype) * (2.0 / _LEVELS) - 1.0
        nearer = d2 < f1
        f2 = torch.where(nearer, f1, torch.minimum(f2, d2))
        f1 = torch.where(nearer, d2, f1)
        val = torch.where(nearer, v, val)
    # sqrt(0) has an infinite gradient: a point exactly on a feature point is measure zero but clamp anyway
    F1, F2 = f1.clamp_min(1e-12).sqrt(), f2.clamp_min(1e-12).sqrt()
    out = torch.stack([2.0 * F1 - 1.0, 2.0 * (F2 - F1) - 1.0, val], dim=-1)   # (B, K, N, 3)
    return out.permute(0, 2, 1, 3).reshape(B, N, FEATURES * octaves)
