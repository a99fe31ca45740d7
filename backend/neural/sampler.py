"""DDIM sampling (Song et al. 2021, η = 0) as free functions over an ε-model callable.

    model(x, t, cond) -> ε      x float32 (B, 1, H, W), t float32 (B,), cond float32 (B, C, H, W)

The sampler owns no model: the runtime passes an onnxruntime session wrapper,
the trainer a torch module wrapper, the tests an analytic model.  One step from
timestep t to t' < t (Eq. 12 of Song et al. with σ = 0):

    x̂₀ = (x_t - √(1 - ᾱ_t) ε) / √ᾱ_t, clipped to [-1, 1]
    x_t' = √ᾱ_t' x̂₀ + √(1 - ᾱ_t') ε'      with ε' = (x_t - √ᾱ_t x̂₀) / √(1 - ᾱ_t)

and ᾱ = 1 after the last step (x̂₀ is returned).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .schedule import T_DEFAULT, cosine_alphas_cumprod, ddim_timesteps

__all__ = ["ddim_step", "ddim_sample", "initial_noise"]

_F = np.float32


def initial_noise(seed: int, shape: tuple) -> np.ndarray:
    """x_T: standard normal float32 ``shape`` fully determined by ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), 0xD1FF])).standard_normal(shape).astype(_F)


def ddim_step(x: np.ndarray, eps: np.ndarray, ab_t: float, ab_next: float, clip: bool = True):
    """One η = 0 step: (x_t, ε, ᾱ_t, ᾱ_t') -> (x_t', x̂₀), float32 arrays of x's shape."""
    x0 = (x - np.sqrt(1.0 - ab_t) * eps) / np.sqrt(ab_t)
    if clip:
        x0 = np.clip(x0, -1.0, 1.0)
    eps_hat = (x - np.sqrt(ab_t) * x0) / np.sqrt(1.0 - ab_t)
    nxt = np.sqrt(ab_next) * x0 + np.sqrt(1.0 - ab_next) * eps_hat
    return nxt.astype(_F), x0.astype(_F)


def ddim_sample(model: Callable, x_T: np.ndarray, cond: np.ndarray, steps: int = 30, T: int = T_DEFAULT,
                callback: Callable[[int, int, np.ndarray], None] | None = None, clip: bool = True,
                alphas_cumprod: np.ndarray | None = None) -> np.ndarray:
    """Denoise x_T (B, 1, H, W) -> x̂₀ float32 in [-1, 1] after ``steps`` DDIM steps.

    callback(i, steps, x̂₀) runs after step i (0-based); it may raise to cancel.
    """
    ab = cosine_alphas_cumprod(T) if alphas_cumprod is None else alphas_cumprod
    ts = ddim_timesteps(steps, T)
    x = np.asarray(x_T, _F)
    x0 = x
    for i, t in enumerate(ts):
        ab_next = float(ab[ts[i + 1]]) if i + 1 < len(ts) else 1.0
        eps = np.asarray(model(x, np.full(x.shape[0], t, _F), cond), _F)
        x, x0 = ddim_step(x, eps, float(ab[t]), ab_next, clip)
        if callback is not None:
            callback(i, len(ts), x0)
    return x0
