"""Differentiable torch twin of :mod:`backend.solid.brick` (staggered-lattice features at Eq. 5's positions).

Same hash, same stagger, same layout, so a model trained here reads the same
bricks at run time.  Gradients reach the transforms T_i through the joint
distances (the brick value is piecewise constant).

Shapes: x (B, N, D) float32; T (m, D, D) or (B, m, D, D); seeds int64 (B, m):
the value noise's octave seeds (``training.solid.value_noise.octave_seeds``), from
which the bricks' seeds are derived as at run time; result (B, N, 3 K) float32,
octave-major.
"""
from __future__ import annotations

import torch

from omninoise.backend.solid.brick import BRICK_SALT, FEATURES
from omninoise.backend.solid.value_noise import BITS, MASK32
from .value_noise import lowbias32_torch, octave_positions, salted_seeds

__all__ = ["brick_features"]

_LEVELS = (1 << BITS) - 1


def _tri(t: torch.Tensor) -> torch.Tensor:
    f = t - torch.floor(t)
    return 2.0 * torch.minimum(f, 1.0 - f)


def brick_features(x: torch.Tensor, T: torch.Tensor, seeds: torch.Tensor, octaves: int) -> torch.Tensor:
    """(2 d_row - 1, 2 d_joint - 1, v) of the first ``octaves`` octaves: (B, N, D) -> (B, N, 3 octaves)."""
    B, N, D = x.shape
    if octaves == 0:
        return x.new_zeros(B, N, 0)
    p = octave_positions(x, T, octaves)                        # (B, K, N, D)
    r = torch.floor(p[..., 1])
    ri = r.to(torch.int64)
    shift = 0.5 * (ri & 1).to(x.dtype)
    s = salted_seeds(seeds, octaves, BRICK_SALT)                   # backend's brick_seeds
    h = lowbias32_torch((s + (ri & MASK32)) & MASK32)
    joint = None
    for a in range(D):
        if a == 1:
            continue
        q = p[..., a] + shift
        h = lowbias32_torch((h + (torch.floor(q).to(torch.int64) & MASK32)) & MASK32)
        t = _tri(q)
        joint = t if joint is None else torch.minimum(joint, t)
    v = (h & _LEVELS).to(x.dtype) * (2.0 / _LEVELS) - 1.0
    out = torch.stack([2.0 * _tri(p[..., 1]) - 1.0, 2.0 * joint - 1.0, v], dim=-1)   # (B, K, N, 3)
    return out.permute(0, 2, 1, 3).reshape(B, N, FEATURES * octaves)
