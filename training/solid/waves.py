"""Periodic (plane-wave) features measured from a photo: the decoder's input for courses and weaves.

Value noise, cellular and brick octaves have no period of their own, so a per-point decoder over them cannot
draw the regular courses of a brick wall or the weave of a cloth, which random phase noise (the photo's own
power spectrum) draws by construction.  These features hand the decoder the photo's strongest periodic
components with the photo's own phases:

    w_k(p) = a_k (cos(2 pi f_k . p + phi_k), sin(2 pi f_k . p + phi_k)),   k = 1 .. K

with f_k (cycles per unit of texture space) and phi_k the K strongest local maxima of the luminance's
Fourier transform (one of each conjugate pair, DC and the lowest ``min_cycles`` cycles per image left out),
taken on the photo's periodic component (Moisan 2011, ``training.evaluate.periodic_component``) so the jump at the photo's
border adds no cross of false peaks.  Because the phases are the photo's, the relative placement of the
harmonics (the half-brick offset of alternate courses) is kept; a texture at another position is the same
pattern translated.  a_k = |F_k| / sqrt(mean_j |F_j|^2): the strongest components dominate at the start.

Photo coordinates follow ``model.slice_points``: pixel (row r, column c) sits at p = ((c + 1/2) / u,
-(r + 1/2) / u) with u pixels per unit, so the FFT's term exp(2 pi i (k_x c / W + k_y r / H)) is
exp(i (2 pi f . p + phi)) with f = u (k_x / W, -k_y / H) and phi = arg F - pi (k_x / W + k_y / H).

2D only: a photo gives the waves of its plane.  The runtime's numpy twin: ``backend.solid.waves``.
"""
from __future__ import annotations

import math

import numpy as np
import torch

from omninoise.backend.periodic import periodic_component

__all__ = ["photo_waves", "wave_share", "wave_features"]


def _peaks(img: torch.Tensor, min_cycles: int):
    """The Fourier transform F of a photo's luminance (periodic component, mean removed), its frequency grids
    (k_x, k_y in cycles per image), the flat indices of its peaks strongest first (local maxima of |F| over
    3 x 3, periodic; one of each conjugate pair: k_y > 0, or k_y = 0 and k_x > 0; none below ``min_cycles``
    cycles per image) and its total power without DC."""
    y = img.double().mean(0).numpy()
    H, W = y.shape
    F = np.fft.fft2(periodic_component((y - y.mean())[None])[0])
    P = np.abs(F)
    ky = np.broadcast_to(np.fft.fftfreq(H, d=1.0 / H)[:, None], (H, W))
    kx = np.broadcast_to(np.fft.fftfreq(W, d=1.0 / W)[None, :], (H, W))
    peak = np.ones((H, W), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            peak &= P >= np.roll(P, (dy, dx), axis=(0, 1))
    half = (ky > 0) | ((ky == 0) & (kx > 0))
    far = np.sqrt((kx / W) ** 2 + (ky / H) ** 2) * min(H, W) >= min_cycles
    score = np.where(peak & half & far, P, 0.0).ravel()
    order = np.argsort(-score, kind="stable")
    order = order[score[order] > 1e-9 * max(P.max(), 1e-300)]
    return F, kx, ky, order, float((P ** 2).sum() - P[0, 0] ** 2)


def photo_waves(img: torch.Tensor, k: int, px_per_unit: float, min_cycles: int = 2) -> torch.Tensor:
    """The K strongest periodic components of a photo: (3, H, W) in [0, 1] -> (K, 4) float32 rows
    [f_x, f_y, phi, a] (cycles per unit, radians, relative amplitude; see the module doc)."""
    if not (isinstance(k, int) and k >= 1):
        raise ValueError(f"waves must be a whole number >= 1, got {k!r}")
    F, kx, ky, order, _ = _peaks(img, min_cycles)
    if len(order) < k:
        raise ValueError(f"waves: the photo has fewer than {k} spectral peaks")
    H, W = F.shape
    idx = order[:k]
    fx, fy, amp = kx.ravel()[idx], ky.ravel()[idx], np.abs(F.ravel()[idx])
    phi = np.angle(F.ravel()[idx]) - np.pi * (fx / W + fy / H)
    a = amp / np.sqrt((amp ** 2).mean())
    out = np.stack([px_per_unit * fx / W, -px_per_unit * fy / H, phi, a], axis=1)
    return torch.from_numpy(out.astype(np.float32))


def wave_share(img: torch.Tensor, k: int, min_cycles: int = 2) -> float:
    """The share of a photo's luminance variance (periodic component) that its K strongest peaks carry, both
    halves of each conjugate pair counted: ~1 for a sum of K waves; with K = 16 and 32, 0.13 to 0.58 for the brick, paving
    and perforated-plate photos of the card, 0.02 to 0.04 for grass and gravel (no period: their strongest peaks
    are chance, and waves made from them repeat as stripes)."""
    F, _, _, order, total = _peaks(img, min_cycles)
    return float(2.0 * (np.abs(F.ravel()[order[:k]]) ** 2).sum() / max(total, 1e-300))


def wave_features(x: torch.Tensor, waves: torch.Tensor) -> torch.Tensor:
    """The features at points: x (B, N, 2), waves (K, 4) -> (B, N, 2K) [a_k cos, a_k sin] per wave, in x's
    dtype (the phase in float64, as ``backend.solid.waves`` computes it)."""
    w = waves.double()
    t = 2.0 * math.pi * (x.double() @ w[:, :2].T) + w[:, 2]
    a = w[:, 3]
    return torch.stack([a * torch.cos(t), a * torch.sin(t)], dim=-1).flatten(-2).to(x.dtype)
