"""Batched procedural-noise primitives in torch, for the training zoo.

Every function takes per-sample tensors: coordinates ``x, y`` float32 (B, H, W)
in "units" (1 unit = 128 px at the zoo's reference scale), per-sample integer
seeds (B,) int64 and per-sample parameters (B,) float32, and returns float32
(B, H, W).  Randomness is a stateless integer hash of (lattice cell, seed), so a
sample depends only on its seed and parameters, on any device.
"""
from __future__ import annotations

import math

import torch

__all__ = ["hash2", "hash_unit", "perlin", "fbm", "worley", "fft_filter", "blur", "normalise", "grid"]

_M = 0xFFFFFFFF


def hash2(ix: torch.Tensor, iy: torch.Tensor, seed: torch.Tensor, salt: int = 0) -> torch.Tensor:
    """32-bit integer hash of lattice (ix, iy), per-sample seed (B, 1, 1) and a salt -> int64 in [0, 2^32)."""
    h = (ix * 374761393 + iy * 668265263 + seed * 2246822519 + salt * 3266489917) & _M
    h = ((h ^ (h >> 15)) * 2246822519) & _M
    h = ((h ^ (h >> 13)) * 3266489917) & _M
    return h ^ (h >> 16)


def hash_unit(ix, iy, seed, salt: int = 0) -> torch.Tensor:
    """Uniform float32 in [0, 1) from :func:`hash2`."""
    return (hash2(ix, iy, seed, salt) & 0xFFFFFF).to(torch.float32) * (1.0 / 16777216.0)


def _fade(t):
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def perlin(x: torch.Tensor, y: torch.Tensor, seed: torch.Tensor, salt: int = 0) -> torch.Tensor:
    """Perlin gradient noise (Perlin 2002 quintic fade), about [-0.7, 0.7]."""
    s = seed.view(-1, 1, 1)
    x0, y0 = torch.floor(x), torch.floor(y)
    fx, fy = x - x0, y - y0
    ix, iy = x0.to(torch.int64), y0.to(torch.int64)

    def grad(cx, cy, dx, dy):
        a = hash_unit(ix + cx, iy + cy, s, salt) * (2.0 * math.pi)
        return torch.cos(a) * dx + torch.sin(a) * dy

    n00 = grad(0, 0, fx, fy)
    n10 = grad(1, 0, fx - 1.0, fy)
    n01 = grad(0, 1, fx, fy - 1.0)
    n11 = grad(1, 1, fx - 1.0, fy - 1.0)
    u, v = _fade(fx), _fade(fy)
    return torch.lerp(torch.lerp(n00, n10, u), torch.lerp(n01, n11, u), v)


def fbm(x, y, seed, octaves: int, roughness: torch.Tensor, lacunarity: float = 2.0, salt: int = 0):
    """Fractal sum of Perlin octaves; roughness (B,) = amplitude ratio per octave; normalised by the amplitude sum."""
    r = roughness.view(-1, 1, 1)
    total = torch.zeros_like(x)
    amp = torch.ones_like(r)
    norm = torch.zeros_like(r)
    f = 1.0
    for o in range(octaves):
        total = total + amp * perlin(x * f, y * f, seed, salt + 101 * o)
        norm = norm + amp
        amp = amp * r
        f *= lacunarity
    return total / norm


def worley(x, y, seed, jitter: torch.Tensor, salt: int = 0):
    """Worley cells over the unit lattice: (F1, F2, cell value in [0, 1)) for each pixel."""
    s = seed.view(-1, 1, 1)
    j = jitter.view(-1, 1, 1)
    x0, y0 = torch.floor(x), torch.floor(y)
    ix, iy = x0.to(torch.int64), y0.to(torch.int64)
    f1 = torch.full_like(x, 1e9)
    f2 = torch.full_like(x, 1e9)
    val = torch.zeros_like(x)
    for cy in (-1, 0, 1):
        for cx in (-1, 0, 1):
            px = x0 + cx + 0.5 + j * (hash_unit(ix + cx, iy + cy, s, salt) - 0.5)
            py = y0 + cy + 0.5 + j * (hash_unit(ix + cx, iy + cy, s, salt + 1) - 0.5)
            d = torch.sqrt((x - px) ** 2 + (y - py) ** 2)
            v = hash_unit(ix + cx, iy + cy, s, salt + 2)
            closer = d < f1
            f2 = torch.where(closer, f1, torch.minimum(f2, d))
            val = torch.where(closer, v, val)
            f1 = torch.where(closer, d, f1)
    return f1, f2, val


def grid(batch: int, size: int, offset: torch.Tensor, px_per_unit: float = 128.0, device=None):
    """Pixel-centre coordinates in units: x, y float32 (B, H, W), shifted per sample by offset (B, 2)."""
    c = (torch.arange(size, dtype=torch.float32, device=device) + 0.5) / px_per_unit
    y, x = torch.meshgrid(c, c, indexing="ij")
    x = x.expand(batch, size, size) + offset[:, 0].view(-1, 1, 1)
    y = y.expand(batch, size, size) + offset[:, 1].view(-1, 1, 1)
    return x, y


def fft_filter(img: torch.Tensor, response) -> torch.Tensor:
    """Filter (B, H, W) images by a frequency response(fx, fy) -> (B, H, W') with fx, fy in cycles per pixel."""
    B, H, W = img.shape
    fy = torch.fft.fftfreq(H, device=img.device).view(1, H, 1)
    fx = torch.fft.rfftfreq(W, device=img.device).view(1, 1, W // 2 + 1)
    spec = torch.fft.rfft2(img)
    return torch.fft.irfft2(spec * response(fx, fy), s=(H, W))


def blur(img: torch.Tensor, sigma_px: torch.Tensor) -> torch.Tensor:
    """Gaussian blur with per-sample sigma (B,) in pixels (periodic boundary)."""
    s = sigma_px.view(-1, 1, 1)
    return fft_filter(img, lambda fx, fy: torch.exp(-2.0 * math.pi ** 2 * s ** 2 * (fx ** 2 + fy ** 2)))


def normalise(img: torch.Tensor, lo_q: float = 0.005, hi_q: float = 0.995) -> torch.Tensor:
    """Per-sample robust min-max to [0, 1]: the lo_q / hi_q quantiles map to 0 / 1, then clamp."""
    flat = img.reshape(img.shape[0], -1)
    k = max(1, flat.shape[1] // 65536)
    sub = flat[:, ::k]
    lo = torch.quantile(sub, lo_q, dim=1).view(-1, 1, 1)
    hi = torch.quantile(sub, hi_q, dim=1).view(-1, 1, 1)
    return ((img - lo) / (hi - lo).clamp_min(1e-6)).clamp(0.0, 1.0)
