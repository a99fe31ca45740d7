"""Diffusion schedules as pure functions (numpy), shared by training and the runtime sampler.

Cosine schedule (Nichol & Dhariwal 2021), as used by Maesumi et al. 2024 with T = 1000:

    ᾱ(t) = f(t) / f(0),   f(t) = cos²(((t / T) + s) / (1 + s) · π / 2),   s = 0.008
    β_t  = min(1 - ᾱ(t + 1) / ᾱ(t), 0.999)

Forward process (DDPM, Ho et al. 2020):  x_t = √ᾱ_t x_0 + √(1 - ᾱ_t) ε.
"""
from __future__ import annotations

import numpy as np

__all__ = ["cosine_alphas_cumprod", "ddim_timesteps", "T_DEFAULT"]

T_DEFAULT = 1000


def cosine_alphas_cumprod(T: int = T_DEFAULT, s: float = 0.008) -> np.ndarray:
    """ᾱ_t for t = 0 .. T-1: float64 (T,), decreasing from ~1 to ~0."""
    steps = np.arange(T + 1, dtype=np.float64) / T
    f = np.cos((steps + s) / (1 + s) * np.pi / 2) ** 2
    ab = f / f[0]
    betas = np.clip(1.0 - ab[1:] / ab[:-1], 0.0, 0.999)
    return np.cumprod(1.0 - betas)


def ddim_timesteps(steps: int, T: int = T_DEFAULT) -> np.ndarray:
    """DDIM's sub-sequence of timesteps, descending: int64 (steps,), from T-1 down to 0 evenly."""
    if not 1 <= steps <= T:
        raise ValueError(f"steps must lie in [1, {T}], got {steps}")
    return np.unique(np.linspace(0, T - 1, steps).round().astype(np.int64))[::-1].copy()
