"""Differentiable torch twin of :mod:`backend.solid.value_noise` (Henzler et al. 2020, Eq. 5).

Same hash, same octave seeds, same smoothstep blend, so a model trained here
reads the same lattice values at run time.  Gradients reach the transforms T_i
through the blend weights (the lattice values themselves are constants).

Shapes: x (B, N, D) float32; T (m, D, D) or (B, m, D, D); seeds int64 (B, m)
from :func:`octave_seeds`; result (B, N, m*C) float32.
"""
from __future__ import annotations

import numpy as np
import torch

from omninoise.backend.solid.value_noise import BITS, MASK32, MAX_CHANNELS, octave_seeds as _np_octave_seeds
from omninoise.backend.solid.spin import check_mode, octave_spins

__all__ = ["octave_seeds", "salted_seeds", "value_noise", "lowbias32_torch", "octave_positions", "spun_torch"]

_LEVELS = (1 << BITS) - 1


def lowbias32_torch(x: torch.Tensor) -> torch.Tensor:
    """``lowbias32`` of int64 tensors in [0, 2^32) (the runtime's hash, bit for bit)."""
    x = x ^ (x >> 16)
    x = (x * 0x7FEB352D) & MASK32
    x = x ^ (x >> 15)
    x = (x * 0x846CA68B) & MASK32
    return x ^ (x >> 16)


def octave_seeds(seeds, octaves: int, device=None) -> torch.Tensor:
    """Per-sample user seeds (B,) -> int64 (B, octaves), as the runtime's ``octave_seeds``."""
    rows = [_np_octave_seeds(int(s), octaves) for s in np.asarray(seeds).reshape(-1)]
    return torch.as_tensor(np.stack(rows), dtype=torch.int64, device=device)


def salted_seeds(seeds: torch.Tensor, octaves: int, salt: int) -> torch.Tensor:
    """The first ``octaves`` of another hash stream's seeds from the octave seeds (B, m) -> (B, octaves, 1),
    as the runtime's ``salted_seeds``."""
    return lowbias32_torch((seeds[:, :octaves] ^ salt) & MASK32).unsqueeze(-1)


def octave_positions(x: torch.Tensor, T: torch.Tensor, octaves: int) -> torch.Tensor:
    """The first ``octaves`` octaves' positions p[b, i, n] = 2^i T_i x_n (Eq. 5's argument): x (B, N, D),
    T (m, D, D) or (B, m, D, D) -> (B, octaves, N, D)."""
    B, N, D = x.shape
    if T.dim() == 3:
        T = T.unsqueeze(0).expand(B, T.shape[0], D, D)
    scale = (2.0 ** torch.arange(octaves, device=x.device, dtype=x.dtype)).view(1, octaves, 1, 1)
    return torch.einsum("bmij,bnj->bmni", T[:, :octaves] * scale, x)


def spun_torch(T: torch.Tensor, seeds: torch.Tensor, mode: str) -> torch.Tensor:
    """The runtime's ``backend.solid.spin.spun``: Q(xi_i) T_i (``"lattice"``) or T_i Q(xi_i)^T (``"octave"``);
    T (m, D, D) or (B, m, D, D), octave seeds int64 (B, m) -> (B, m, D, D); the rotations are the runtime's float32
    matrices, the product in float64 as there.  Gradients reach T."""
    B, m = seeds.shape
    D = T.shape[-1]
    Q = torch.as_tensor(octave_spins(seeds.cpu().numpy(), D), device=T.device, dtype=torch.float64)
    T = T.unsqueeze(0).expand(B, m, D, D) if T.dim() == 3 else T
    out = Q @ T.double() if check_mode(mode) == "lattice" else T.double() @ Q.transpose(-1, -2)
    return out.to(T.dtype)


def value_noise(x: torch.Tensor, T: torch.Tensor, seeds: torch.Tensor, channels: int = 3) -> torch.Tensor:
    """Octave noise n_i = noise(T_i 2^(i-1) x | xi_i) (Eq. 5): (B, N, D) -> (B, N, m*C)."""
    if not 1 <= channels <= MAX_CHANNELS:
        raise ValueError(f"channels must be 1..{MAX_CHANNELS}")
    B, N, D = x.shape
    m = T.shape[-3]
    p = octave_positions(x, T, m)
    fl = torch.floor(p)
    t = p - fl
    w1 = t * t * (3.0 - 2.0 * t)
    k = fl.to(torch.int64)
    # hash chain over the axes, shared between corners: lb(lb(lb(xi + kx) + ky) + kz)
    hs = [seeds.view(B, m, 1)]
    ws = [None]
    for d in range(D):
        kd, wd = k[..., d], w1[..., d]
        hs = [lowbias32_torch((h + ((kd + bit) & MASK32)) & MASK32) for h in hs for bit in (0, 1)]
        ws = [(wd if bit else 1.0 - wd) if w is None else w * (wd if bit else 1.0 - wd) for w in ws for bit in (0, 1)]
    shifts = torch.arange(channels, device=x.device, dtype=torch.int64) * BITS
    out = x.new_zeros(B, m, N, channels)
    for h, wt in zip(hs, ws):
        v = ((h.unsqueeze(-1) >> shifts) & _LEVELS).to(x.dtype) * (2.0 / _LEVELS) - 1.0
        out = out + wt.unsqueeze(-1) * v
    return out.permute(0, 2, 1, 3).reshape(B, N, m * channels)
