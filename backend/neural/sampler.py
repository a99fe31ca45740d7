"""Samplers of the probability-flow ODE (and DDIM's SDE) as free functions over an ε-model callable.

    model(x, t, cond) -> ε      x float32 (B, 1, H, W), t float32 (B,), cond float32 (B, C, H, W)

The samplers own no model: the runtime passes an onnxruntime session wrapper,
the trainer a torch module wrapper, the tests an analytic model.  Each takes
``steps`` timesteps t_0 > ... > t_{n-1} = 0 of the discrete schedule ᾱ (DDIM's
even sub-sequence) and returns the data prediction x̂₀ at t = 0, clipped to
[-1, 1] like the training data.  Notation at timestep t: α = √ᾱ_t, σ = √(1 - ᾱ_t),
λ = log(α / σ), and the data prediction D(x, t) = (x - σ ε(x, t)) / α.

ddim      Song et al. 2021, Eq. 12.  η = 0: deterministic, one evaluation per step.
          η > 0 adds fresh noise of standard deviation
          σ_η = η √((1 - ᾱ') / (1 - ᾱ)) √(1 - ᾱ / ᾱ') at every step (η = 1: DDPM).
dpmpp_2m  DPM-Solver++(2M), Lu et al. 2022 (Alg. 2): multistep second order in the
          data prediction, one evaluation per step, first order on the first step
          and on the last update to t = 0 (diffusers' ``lower_order_final``: on the
          cosine schedule that interval spans λ 1.7 -> 5.1 at 10 steps, and the
          extrapolation weight 1/(2r) would exceed 2):
              h = λ' - λ,  r = h_prev / h,  D̄ = (1 + 1/(2r)) D_i - (1/(2r)) D_{i-1}
              x' = (σ' / σ) x - α' (e^{-h} - 1) D̄
heun      Karras et al. 2022 (Alg. 1, no churn) in the variance-exploding view
          x̃ = x / α, s = σ / α, d = (x̃ - D) / s: Euler predictor, trapezoidal
          corrector.  The first step, from pure noise (s ≈ 2·10⁴ on the cosine
          schedule, where Karras et al. start at 80), is Euler alone: over so long
          an interval the trapezoid is unstable.  2 (steps - 1) evaluations.

callback(i, n, x̂₀) runs after evaluation i of n; it may raise to cancel.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .schedule import T_DEFAULT, cosine_alphas_cumprod, timesteps

__all__ = ["SAMPLERS", "DEFAULT_SAMPLER", "DEFAULT_STEPS", "DEFAULT_SPACING", "DEFAULT_ETA", "sampler_eta", "evaluations",
           "sample", "ddim_step", "ddim_sample", "dpmpp_2m_sample", "heun_sample", "initial_noise"]

_F = np.float32


def initial_noise(seed: int, shape: tuple) -> np.ndarray:
    """x_T: standard normal float32 ``shape`` fully determined by ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), 0xD1FF])).standard_normal(shape).astype(_F)


def step_noise_rng(seed: int) -> np.random.Generator:
    """The generator of DDIM η > 0's per-step noise, fully determined by ``seed`` (independent of x_T's)."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), 0x57E9]))


def _data(x, eps, ab, clip):
    """D = (x - σ ε) / α, clipped to [-1, 1] when ``clip``."""
    x0 = (x - np.sqrt(1.0 - ab) * eps) / np.sqrt(ab)
    return np.clip(x0, -1.0, 1.0) if clip else x0


class _Counter:
    """The model called with t broadcast over the batch; counts evaluations for the callback."""

    def __init__(self, model, cond, total, callback):
        self.model, self.cond, self.total, self.callback, self.i = model, cond, total, callback, 0

    def __call__(self, x, t):
        return np.asarray(self.model(x, np.full(x.shape[0], t, _F), self.cond), _F)

    def done(self, x0):
        if self.callback is not None:
            self.callback(self.i, self.total, x0)
        self.i += 1


def ddim_step(x: np.ndarray, eps: np.ndarray, ab_t: float, ab_next: float, clip: bool = True,
              eta: float = 0.0, noise: np.ndarray | None = None):
    """One DDIM step: (x_t, ε, ᾱ_t, ᾱ_t') -> (x_t', x̂₀), float32 arrays of x's shape (``noise`` ~ N(0, I) if η > 0)."""
    x0 = _data(x, eps, ab_t, clip)
    eps_hat = (x - np.sqrt(ab_t) * x0) / np.sqrt(1.0 - ab_t)
    sig = eta * np.sqrt((1.0 - ab_next) / (1.0 - ab_t)) * np.sqrt(max(1.0 - ab_t / ab_next, 0.0)) if eta else 0.0
    nxt = np.sqrt(ab_next) * x0 + np.sqrt(max(1.0 - ab_next - sig * sig, 0.0)) * eps_hat
    if sig:
        nxt = nxt + sig * noise
    return nxt.astype(_F), x0.astype(_F)


def _grid(steps, T, alphas_cumprod, spacing):
    ab = cosine_alphas_cumprod(T) if alphas_cumprod is None else np.asarray(alphas_cumprod, np.float64)
    return ab, timesteps(steps, ab, spacing)


def ddim_sample(model: Callable, x_T: np.ndarray, cond: np.ndarray, steps: int = 30, T: int = T_DEFAULT,
                callback: Callable[[int, int, np.ndarray], None] | None = None, clip: bool = True,
                alphas_cumprod: np.ndarray | None = None, eta: float = 0.0, spacing: str = "uniform",
                rng: np.random.Generator | None = None) -> np.ndarray:
    """Denoise x_T (B, 1, H, W) -> x̂₀ float32 after ``steps`` DDIM steps (η > 0 needs ``rng``)."""
    if eta and rng is None:
        raise ValueError("DDIM with eta > 0 needs an rng for its step noise")
    ab, ts = _grid(steps, T, alphas_cumprod, spacing)
    f = _Counter(model, cond, len(ts), callback)
    x = np.asarray(x_T, _F)
    x0 = x
    for i, t in enumerate(ts):
        ab_next = float(ab[ts[i + 1]]) if i + 1 < len(ts) else 1.0
        noise = rng.standard_normal(x.shape).astype(_F) if eta and i + 1 < len(ts) else None
        x, x0 = ddim_step(x, f(x, t), float(ab[t]), ab_next, clip, eta if noise is not None else 0.0, noise)
        f.done(x0)
    return x0


def dpmpp_2m_sample(model: Callable, x_T: np.ndarray, cond: np.ndarray, steps: int = 12, T: int = T_DEFAULT,
                    callback: Callable[[int, int, np.ndarray], None] | None = None, clip: bool = True,
                    alphas_cumprod: np.ndarray | None = None, spacing: str = "uniform", eta: float = 0.0,
                    rng: np.random.Generator | None = None) -> np.ndarray:
    """DPM-Solver++(2M): x_T (B, 1, H, W) -> x̂₀ float32 with ``steps`` evaluations.

    η > 0 is the SDE form (Lu et al. 2022, "DPM-Solver++", Sec. 5; k-diffusion's ``sample_dpmpp_2m_sde``,
    midpoint correction), written for the VP process with h = λ_s - λ_t:

        x_s = (σ_s / σ_t) e^{-η h} x_t + α_s (1 - e^{-(1+η) h}) (D + (D - D_prev) / (2 r)) + σ_s √(1 - e^{-2 η h}) z

    with r = h_prev / h and z ~ N(0, I) from ``rng``; η = 0 is the ODE solver exactly."""
    if eta and rng is None:
        raise ValueError("DPM-Solver++(2M) with eta > 0 needs an rng for its step noise")
    ab, ts = _grid(steps, T, alphas_cumprod, spacing)
    f = _Counter(model, cond, len(ts), callback)
    alpha, sigma = np.sqrt(ab), np.sqrt(1.0 - ab)
    lam = np.log(alpha) - np.log(sigma)
    x = np.asarray(x_T, _F)
    d_prev, h_prev, d = None, None, x
    for i, t in enumerate(ts):
        d = _data(x, f(x, t), ab[t], clip).astype(_F)
        f.done(d)
        if i + 1 == len(ts):
            break
        s = ts[i + 1]
        h = lam[s] - lam[t]
        if d_prev is None or i + 2 == len(ts):
            dbar = d
        else:
            r = h_prev / h
            dbar = (1.0 + 0.5 / r) * d - (0.5 / r) * d_prev
        if eta:
            x = ((sigma[s] / sigma[t]) * np.exp(-eta * h) * x - alpha[s] * np.expm1(-(1.0 + eta) * h) * dbar
                 + sigma[s] * np.sqrt(-np.expm1(-2.0 * eta * h)) * rng.standard_normal(x.shape)).astype(_F)
        else:
            x = ((sigma[s] / sigma[t]) * x - alpha[s] * np.expm1(-h) * dbar).astype(_F)
        d_prev, h_prev = d, h
    return d


def heun_sample(model: Callable, x_T: np.ndarray, cond: np.ndarray, steps: int = 8, T: int = T_DEFAULT,
                callback: Callable[[int, int, np.ndarray], None] | None = None, clip: bool = True,
                alphas_cumprod: np.ndarray | None = None, spacing: str = "uniform") -> np.ndarray:
    """Heun's second-order method (Karras et al. 2022): x_T -> x̂₀ float32 with 2 (steps - 1) evaluations."""
    ab, ts = _grid(steps, T, alphas_cumprod, spacing)
    if len(ts) < 2:
        raise ValueError("heun needs at least 2 steps")
    f = _Counter(model, cond, 2 * (len(ts) - 1), callback)
    alpha, sk = np.sqrt(ab), np.sqrt((1.0 - ab) / ab)

    def slope(xt, t):  # dx̃/ds at x̃ = xt, and D
        d = _data(alpha[t] * xt, f(alpha[t] * xt, t), ab[t], clip)
        f.done(d.astype(_F))
        return (xt - d) / sk[t], d

    xt = np.asarray(x_T, np.float64) / alpha[ts[0]]
    dx, d = slope(xt, ts[0])
    for i in range(len(ts) - 1):
        t, s = ts[i], ts[i + 1]
        xt_next = xt + (sk[s] - sk[t]) * dx
        if i > 0:
            dx2, _ = slope(xt_next, s)
            xt_next = xt + (sk[s] - sk[t]) * 0.5 * (dx + dx2)
        xt = xt_next
        dx, d = slope(xt, s)
    return np.asarray(d, _F)


#: name -> (function, evaluations for ``steps``)
SAMPLERS: dict = {
    "ddim": (ddim_sample, lambda n: n),
    "dpmpp_2m": (dpmpp_2m_sample, lambda n: n),
    "heun": (heun_sample, lambda n: 2 * (n - 1)),
}
#: chosen by measurement (README, "Sampling"): DPM-Solver++(2M) on the truncated grid with 10 evaluations is as
#: near the converged probability-flow solution as DDIM 30 (docs/evaluations/neural_solver_error_64.json: 0.031
#: against 0.034 mean |Δ| at 256²) and no worse by the evaluation (python -m bench neural-eval, 64² instrument, all
#: 23 classes); 15 timesteps even in log-SNR would make 13 evaluations, four of them below λ = -4.5
DEFAULT_SAMPLER = "dpmpp_2m"
DEFAULT_STEPS = 10
#: the step noise η each sampler uses unless told (None in the front ends): the SDE form of DPM-Solver++(2M) with
#: η = 0.3, chosen by measurement (README, "Sampling"): on the 64² instrument, 23 classes, the same 10 evaluations
#: give median per-class FD 45.5 against 56.0 for the ODE (η = 0) and 76.4 for DDIM 30, and cells_distorted, which
#: the ODE needs 30 evaluations for, comes within 20 % of DDIM 30 (n = 128); DDIM and Heun stay deterministic
DEFAULT_ETA = {"ddim": 0.0, "dpmpp_2m": 0.3, "heun": 0.0}


def sampler_eta(sampler: str, eta: float | None) -> float:
    """The step noise ``sampler`` runs with: ``eta``, or with None the sampler's DEFAULT_ETA (0 for a name that
    is not a sampler: :func:`backend.neural.generate.check_sampler` refuses those)."""
    return DEFAULT_ETA.get(sampler, 0.0) if eta is None else eta


#: the timestep spacing each sampler uses unless told: the truncated λ grid for DPM-Solver++, uniform t for
#: DDIM (its usual grid) and Heun (it overshoots on λ grids' long first intervals)
DEFAULT_SPACING = {"ddim": "uniform", "dpmpp_2m": "truncated", "heun": "uniform"}


def evaluations(sampler: str, steps: int, spacing: str | None = None, alphas_cumprod: np.ndarray | None = None) -> int:
    """How many model evaluations ``sampler`` makes for ``steps`` timesteps; with ``spacing`` (and the model's ᾱ,
    default the cosine schedule) counted on the actual grid, where targets that round together merge."""
    if spacing is not None:
        steps = len(_grid(steps, T_DEFAULT, alphas_cumprod, spacing)[1])
    return SAMPLERS[sampler][1](steps)


def sample(sampler: str, model: Callable, x_T: np.ndarray, cond: np.ndarray, steps: int, **kw) -> np.ndarray:
    """Run the sampler named ``sampler`` (a key of :data:`SAMPLERS`); ValueError for an unknown name."""
    if sampler not in SAMPLERS:
        raise ValueError(f"unknown sampler {sampler!r}; choose one of {', '.join(SAMPLERS)}")
    return SAMPLERS[sampler][0](model, x_T, cond, steps, **kw)
