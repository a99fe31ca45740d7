"""Diffusion schedules as pure functions (numpy), shared by training and the runtime sampler.

Cosine schedule (Nichol & Dhariwal 2021), as used by Maesumi et al. 2024 with T = 1000:

    ᾱ(t) = f(t) / f(0),   f(t) = cos²(((t / T) + s) / (1 + s) · π / 2),   s = 0.008
    β_t  = min(1 - ᾱ(t + 1) / ᾱ(t), 0.999)

Forward process (DDPM, Ho et al. 2020):  x_t = √ᾱ_t x_0 + √(1 - ᾱ_t) ε.
"""
from __future__ import annotations

import numpy as np

__all__ = ["cosine_alphas_cumprod", "ddim_timesteps", "timesteps", "SPACINGS", "T_DEFAULT", "alphas_from_config"]

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


SPACINGS = ("uniform", "logsnr", "karras", "truncated")

#: the λ interval the "truncated" grid spends its evaluations on after the first (at t = T - 1): below
#: λ = -3.5 (SNR e^-7) the data prediction hardly changes, so one first-order step crosses it; above
#: λ = 3.5 (σ/α = 0.03, a quarter of an 8-bit level's worth of noise after the final denoising) the
#: last evaluation's data prediction is the image.  Chosen by the distance to the converged ODE solution
#: (README, "Sampling"; docs/evaluations/neural_solver_error_64.json)
TRUNCATED_LAMBDA = (-3.5, 3.5)


def timesteps(steps: int, alphas_cumprod: np.ndarray, spacing: str = "uniform", rho: float = 7.0) -> np.ndarray:
    """Descending int64 timesteps from T-1 to 0 for a sampler, ``steps`` of them (fewer if two round together).

    uniform  even in t (DDIM's sub-sequence, :func:`ddim_timesteps`)
    logsnr   even in λ = log(α / σ) = ½ log(ᾱ / (1 - ᾱ)) (Lu et al. 2022's recommendation for few steps)
    karras   s_i = (s_max^{1/ρ} + i/(n-1) (s_min^{1/ρ} - s_max^{1/ρ}))^ρ in s = σ / α (Karras et al. 2022, Eq. 5)
    truncated  T-1 first, then steps - 1 targets even in λ over TRUNCATED_LAMBDA; it ends at λ = 3.5,
             not at t = 0, and every timestep is a distinct evaluation (on the cosine schedule the λ grids
             above merge targets near T - 1: "logsnr" gives 13 timesteps for 15)
    Each continuous target is rounded to the discrete timestep nearest in λ.
    """
    ab = np.asarray(alphas_cumprod, np.float64)
    T = len(ab)
    if spacing == "uniform":
        return ddim_timesteps(steps, T)
    if not 1 <= steps <= T:
        raise ValueError(f"steps must lie in [1, {T}], got {steps}")
    lam = 0.5 * np.log(ab / (1.0 - ab))  # increasing as t decreases
    if steps == 1:
        return np.array([T - 1], np.int64)
    if spacing == "truncated":
        lo, hi = max(TRUNCATED_LAMBDA[0], lam[-1]), min(TRUNCATED_LAMBDA[1], lam[0])
        target = np.concatenate([[lam[-1]], np.linspace(lo, hi, steps - 1)])
        return np.unique(_nearest(lam, target))[::-1].copy()  # target[0] = λ(T-1) rounds to T-1 exactly
    if spacing == "logsnr":
        target = np.linspace(lam[-1], lam[0], steps)
    elif spacing == "karras":
        s_max, s_min = np.exp(-lam[-1]), np.exp(-lam[0])
        r = np.linspace(0.0, 1.0, steps)
        target = -np.log((s_max ** (1 / rho) + r * (s_min ** (1 / rho) - s_max ** (1 / rho))) ** rho)
    else:
        raise ValueError(f"unknown spacing {spacing!r}; choose one of {', '.join(SPACINGS)}")
    ts = _nearest(lam, target)
    ts[0], ts[-1] = T - 1, 0
    return np.unique(ts)[::-1].copy()


def _nearest(lam: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The timestep nearest in λ to each target: int64 like ``target`` (``lam`` decreasing in t)."""
    T = len(lam)
    idx = np.clip(np.searchsorted(lam[::-1], target), 1, T - 1)  # search the reversed (increasing) array
    lo, hi = lam[::-1][idx - 1], lam[::-1][idx]
    idx = np.where(np.abs(target - lo) <= np.abs(target - hi), idx - 1, idx)
    return (T - 1 - idx).astype(np.int64)


def alphas_from_config(schedule: dict) -> np.ndarray:
    """ᾱ of a model JSON's ``schedule`` ({"kind": "cosine", "T": 1000, "s": 0.008}); ValueError for another kind."""
    kind = schedule.get("kind")
    if kind != "cosine":
        raise ValueError(f"unsupported noise schedule {kind!r} (the runtime knows: cosine)")
    return cosine_alphas_cumprod(int(schedule.get("T", T_DEFAULT)), float(schedule.get("s", 0.008)))
