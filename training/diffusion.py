"""Training objective of the neural noise model (Maesumi et al. 2024, Sec. 3.1).

ε-prediction DDPM loss on the cosine schedule with offset noise, plus the
spherical regulariser of the class embeddings (Sec. 3.1.1):

    L = E ‖ε - ε_θ(√ᾱ_t x₀ + √(1-ᾱ_t) ε, t, F)‖²  +  λ · mean_i (‖e_i‖ - r)²

ε = n + 0.1·m with n ~ N(0, I) per pixel and m ~ N(0, 1) per image (offset
noise), λ = 0.02, and r = √E the norm a standard normal E-vector has on
average (E‖z‖² = E), so slerp between embeddings stays on the shell that the
network saw.

Min-SNR-γ weighting (Hang et al. 2023, "Efficient Diffusion Training via Min-SNR
Weighting Strategy", Eq. 8 for ε-prediction): with SNR(t) = ᾱ_t / (1 - ᾱ_t), each
sample's squared error is weighted by min(SNR(t), γ) / SNR(t), which caps the
weight of the low-noise steps whose gradients conflict with the rest.  γ = 0
turns it off (plain MSE, the paper's loss).

Low-SNR weighting (``low_snr_weight`` = W > 1): each sample's squared ε error is weighted by
min(1 + 1/SNR(t), W).  1 + 1/SNR = 1/ᾱ_t is the weight that turns the ε error into the
v-prediction error (v = √ᾱ ε - √(1-ᾱ) x₀, Salimans & Ho 2022: |v - v̂|² = |ε - ε̂|² / ᾱ_t), capped
at W.  Plain ε-MSE gives the noisiest steps almost no say: there ε ≈ x_t / σ is easy, and what a
global variable of the image (the direction of fibres, the course of a band) changes in the best
ε shrinks like SNR², although those are the steps at which a sampler decides it.  W = 1 turns it
off.
"""
from __future__ import annotations

import math

import torch

from omninoise.backend.neural.schedule import T_DEFAULT, cosine_alphas_cumprod

__all__ = ["Diffusion"]


class Diffusion:
    def __init__(self, T: int = T_DEFAULT, offset_noise: float = 0.1, emb_lambda: float = 0.02, device=None,
                 min_snr_gamma: float = 0.0, low_snr_weight: float = 1.0):
        if min_snr_gamma < 0:
            raise ValueError(f"min_snr_gamma must be >= 0 (0: off), got {min_snr_gamma}")
        if not low_snr_weight >= 1:
            raise ValueError(f"low_snr_weight must be >= 1 (1: off), got {low_snr_weight}")
        self.T = T
        self.min_snr_gamma = float(min_snr_gamma)
        self.low_snr_weight = float(low_snr_weight)
        self.offset = offset_noise
        self.emb_lambda = emb_lambda
        self.ab = torch.as_tensor(cosine_alphas_cumprod(T), dtype=torch.float32, device=device)

    def noise_like(self, x0: torch.Tensor, generator=None) -> torch.Tensor:
        n = torch.randn(x0.shape, generator=generator, device=x0.device)
        m = torch.randn((x0.shape[0], x0.shape[1], 1, 1), generator=generator, device=x0.device)
        return n + self.offset * m

    def q_sample(self, x0, t, eps):
        a = self.ab.to(x0.device)[t].view(-1, 1, 1, 1)
        return a.sqrt() * x0 + (1.0 - a).sqrt() * eps

    @property
    def weighted(self) -> bool:
        """Whether :meth:`snr_weight` is anything but ones."""
        return self.min_snr_gamma > 0 or self.low_snr_weight > 1

    def snr_weight(self, t: torch.Tensor) -> torch.Tensor:
        """Per-sample loss weight: min(SNR(t), γ) / SNR(t) (Hang et al. 2023, Eq. 8) where γ > 0, times
        min(1/ᾱ_t, W) where W = ``low_snr_weight`` > 1; ones when neither is on."""
        w = torch.ones(t.shape, dtype=torch.float32, device=t.device)
        a = self.ab.to(t.device)[t]
        if self.min_snr_gamma > 0:
            snr = a / (1.0 - a).clamp_min(1e-12)
            w = w * torch.clamp(snr, max=self.min_snr_gamma) / snr.clamp_min(1e-12)
        if self.low_snr_weight > 1:
            w = w * torch.clamp(1.0 / a.clamp_min(1e-12), max=self.low_snr_weight)
        return w

    def embedding_penalty(self, emb: torch.Tensor) -> torch.Tensor:
        target = math.sqrt(emb.shape[1])
        return self.emb_lambda * ((emb.norm(dim=1) - target) ** 2).mean()

    def loss(self, model, x0: torch.Tensor, cond: torch.Tensor, generator=None) -> tuple:
        """x0 float32 (B, 1, H, W) in [-1, 1], cond (B, E + P, H, W) -> (total, mse) scalars.

        ``mse`` is the unweighted ε error (comparable across weightings); ``total`` carries the
        weights of :meth:`snr_weight` and the embedding regulariser."""
        B = x0.shape[0]
        t = torch.randint(0, self.T, (B,), generator=generator, device=x0.device)
        eps = self.noise_like(x0, generator)
        pred = model(self.q_sample(x0, t, eps), t.to(torch.float32), cond)
        per = torch.mean((pred.float() - eps) ** 2, dim=(1, 2, 3))  # fp32 even under bf16 autocast
        mse = per.mean()
        weighted = (self.snr_weight(t) * per).mean() if self.weighted else mse
        return weighted + self.embedding_penalty(model.class_emb.weight), mse
