"""Sliced Wasserstein texture loss on wide random multi-scale features (no downloaded weights).

Heitz, Vanhoey, Chambon, Belcour ("A Sliced Wasserstein Loss for Neural
Texture Synthesis", CVPR 2021) replace the Gram matrices of Gatys et al. by
the sliced Wasserstein distance between the *distributions* of feature
vectors: for random unit directions v,

    SW(F, G) = E_v  W_2^2( {<v, f_p>}_p , {<v, g_q>}_q )          (Heitz et al., Eq. 7)

and the 1D W_2 is a difference of sorted values.  Gram matrices only see
second moments, so they let through any image with the right covariance
(soft blotches); the full distribution pins down the shapes that make a
texture.  No pretrained VGG can be fetched here, so the features are those
of a fixed random network, made wide and multi-scale as Ustyuzhaninov et al.
(ICLR 2017) found random features need to be: on every level of a Gaussian
pyramid, the raw colour neighbourhoods (a k x k patch is itself a feature
vector) and one ReLU layer of ``width`` zero-mean random filters of each
size in ``kernels``.  Directions are drawn afresh every call (the loss is an
unbiased estimate of SW), or from a given generator.

Shapes: images (B, 3, H, W) float32 in [0, 1].  ``per_sample``: output b is
compared with reference b (space mode); otherwise the references are pooled
into one distribution (single-exemplar mode).
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["SlicedFeatures", "sliced_w2", "swd_loss"]


class SlicedFeatures(nn.Module):
    """Fixed random multi-scale features; forward gives a list of feature maps (B, C_t, H_t, W_t), one per tap."""

    def __init__(self, seed: int = 0, levels: int = 5, patch: int = 5, width: int = 64, kernels=(3, 7, 11),
                 channels: int = 3):
        super().__init__()
        g = torch.Generator().manual_seed(seed)
        self.levels, self.patch, self.kernels = levels, patch, tuple(kernels)
        for k in self.kernels:
            filt = torch.randn(width, channels, k, k, generator=g)
            filt = filt - filt.mean(dim=(1, 2, 3), keepdim=True)          # zero mean: structure, not colour
            filt = filt / filt.flatten(1).norm(dim=1).view(-1, 1, 1, 1)
            self.register_buffer(f"w{k}", filt)
            self.register_buffer(f"b{k}", (torch.rand(width, generator=g) - 0.5) * 0.2)
        # the k x k colour neighbourhood as a feature vector: an identity filter bank
        eye = torch.eye(channels * patch * patch).view(channels * patch * patch, channels, patch, patch)
        self.register_buffer("patches", eye)

    def forward(self, img: torch.Tensor, centred: bool = False) -> list:
        """Taps of ``img`` (B, channels, H, W): values in [0, 1], or with ``centred`` already zero-centred."""
        taps = []
        x = img if centred else (img - 0.5) * 2.0
        for lvl in range(self.levels):
            if lvl:
                x = F.avg_pool2d(x, 2)
            side = min(x.shape[-2:])
            if side < max(self.patch, min(self.kernels)) + 4:
                break
            taps.append(F.conv2d(x, self.patches))                          # 'valid': no border statistics
            for k in self.kernels:
                if side >= k + 4:         # a wide filter stops at the level where it no longer fits
                    taps.append(F.relu(F.conv2d(x, getattr(self, f"w{k}"), getattr(self, f"b{k}"))))
        return taps


def _quantiles(v: torch.Tensor, n: int) -> torch.Tensor:
    """Sorted values (..., N) resampled to n evenly spaced quantiles (linear interpolation)."""
    s = torch.sort(v, dim=-1).values
    N = s.shape[-1]
    if N == n:
        return s
    pos = (torch.arange(n, device=v.device, dtype=v.dtype) + 0.5) * (N / n) - 0.5
    lo = pos.floor().clamp(0, N - 1).long()
    hi = (lo + 1).clamp(max=N - 1)
    t = (pos - lo.to(v.dtype)).clamp(0, 1)
    return s[..., lo] * (1 - t) + s[..., hi] * t


def sliced_w2(a: torch.Tensor, b: torch.Tensor, dirs: torch.Tensor) -> torch.Tensor:
    """Sliced W_2^2 between point sets a (B, C, N) and b (B, C, M) along unit dirs (K, C): (B,).

    Unequal sizes are compared at min(N, M) quantiles."""
    pa = torch.einsum("kc,bcn->bkn", dirs, a)
    pb = torch.einsum("kc,bcn->bkn", dirs, b)
    n = min(pa.shape[-1], pb.shape[-1])
    return ((_quantiles(pa, n) - _quantiles(pb, n)) ** 2).mean(dim=(1, 2))


def swd_loss(feats: SlicedFeatures, out: torch.Tensor, ref: torch.Tensor, per_sample: bool = False,
             n_dirs: int = 32, generator: torch.Generator | None = None, ref_taps: list | None = None) -> torch.Tensor:
    """Sum over taps of the sliced W_2^2 between output and reference feature distributions (Eq. 7).

    Each tap's distance is divided by the mean squared feature of the reference
    (so every scale and filter size counts alike).  ``ref_taps`` reuses the
    references' features (single mode: one exemplar, computed once).
    """
    if ref_taps is None:
        with torch.no_grad():
            ref_taps = feats(ref)
    total = out.new_zeros(())
    for fo, fr in zip(feats(out), ref_taps):
        C = fo.shape[1]
        dirs = torch.randn(n_dirs, C, generator=generator).to(fo)
        dirs = dirs / dirs.norm(dim=1, keepdim=True)
        a, b = fo.flatten(2), fr.flatten(2)
        if not per_sample:
            a = a.transpose(0, 1).flatten(1).unsqueeze(0)
            b = b.transpose(0, 1).flatten(1).unsqueeze(0)
        scale = (b ** 2).mean().clamp_min(1e-6)
        total = total + sliced_w2(a, b, dirs).mean() / scale
    return total
