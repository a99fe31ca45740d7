"""Texture statistics for the solid-texture loss, built without pretrained weights.

Henzler et al. (2020, Sec. 3) match Gram matrices of VGG-19 activations.  No
pretrained VGG weights can be downloaded here, so the loss uses a feature
extractor the project builds itself: a fixed two-layer network of random
zero-mean filters applied to a 4-level image pyramid.  Ustyuzhaninov et al.
("What does it take to generate natural textures?", ICLR 2017) showed that
Gram matrices of random multi-scale filters suffice for texture synthesis.
A sorted-value (1D optimal transport) histogram term per colour channel pins
the colour distribution, which Gram matrices of zero-mean filters do not see.

``seed`` fixes the filters: training uses seed 0; the evaluation's independent
style metric uses another seed *and* other widths and kernel sizes.

Shapes: images (B, 3, H, W) float32 in [0, 1].
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["RandomFeatures", "gram_loss", "histogram_loss", "style_loss"]


class RandomFeatures(nn.Module):
    """Fixed random conv features at ``levels`` pyramid levels; forward gives Gram matrices (B, C, C) per tap."""

    def __init__(self, seed: int = 0, widths=(32, 64), kernels=(5, 3), levels: int = 4):
        super().__init__()
        g = torch.Generator().manual_seed(seed)
        cin = 3
        self.levels = levels
        for j, (w, k) in enumerate(zip(widths, kernels)):
            filt = torch.randn(w, cin, k, k, generator=g)
            filt = filt - filt.mean(dim=(1, 2, 3), keepdim=True)          # zero mean: see structure, not colour
            filt = filt / filt.flatten(1).norm(dim=1).view(-1, 1, 1, 1)
            self.register_buffer(f"w{j}", filt)
            self.register_buffer(f"b{j}", torch.rand(w, generator=g) * 0.1 - 0.05)
            cin = w
        self.n_layers = len(widths)
        for p in self.buffers():
            p.requires_grad_(False)

    def forward(self, img: torch.Tensor) -> list:
        grams = []
        x0 = (img - 0.5) * 4.0
        for lvl in range(self.levels):
            if min(img.shape[-2:]) // 2 ** lvl < 12:      # too small for the valid convolutions: coarser levels skipped
                break
            x = F.avg_pool2d(x0, 2 ** lvl) if lvl else x0
            for j in range(self.n_layers):
                x = F.relu(F.conv2d(x, getattr(self, f"w{j}"), getattr(self, f"b{j}")))   # 'valid': no border artefacts
                f = x.flatten(2)
                grams.append(f @ f.transpose(1, 2) / f.shape[-1])
        return grams


def gram_loss(grams_out: list, grams_ref: list, per_sample: bool = False) -> torch.Tensor:
    """Sum over taps of ||G_out - G_ref||^2 / ||G_ref||^2 (relative, so every scale counts).

    G_ref is the batch mean of the references (one exemplar: a steadier target),
    or with ``per_sample`` each output's own reference (space mode).  The
    denominator is the batch mean of ||G_ref||^2 (one term in single mode): a nearly flat
    crop (small Gram) must not blow its sample's term up (a space run died of
    a 200x loss spike from exactly that).
    """
    total = 0.0
    for go, gr in zip(grams_out, grams_ref):
        ref = gr if per_sample else gr.mean(0, keepdim=True)
        total = total + ((go - ref) ** 2).sum(dim=(1, 2)).mean() / (ref ** 2).sum(dim=(1, 2)).mean().clamp_min(1e-8)
    return total


#: colour directions of the sliced histogram term: the three channels, luminance-like sums and
#: differences, so the joint RGB distribution (not only each channel's) is matched
_DIRS = torch.tensor([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -1, 0], [0, 1, -1], [1, 0, -1],
                      [1, 1, -1], [1, -1, 1], [-1, 1, 1]], dtype=torch.float32)
_DIRS = _DIRS / _DIRS.norm(dim=1, keepdim=True)


def histogram_loss(out: torch.Tensor, ref: torch.Tensor, n: int = 4096, per_sample: bool = False) -> torch.Tensor:
    """Sliced 1D Wasserstein-2 between pixel colours along fixed colour directions (sorted values,
    evenly subsampled to ``n``): pooled over the batch, or with ``per_sample`` image by image."""
    d = _DIRS.to(out.device)
    out = torch.einsum("kc,bchw->bkhw", d, out)
    ref = torch.einsum("kc,bchw->bkhw", d, ref)
    if not per_sample:
        out, ref = out.transpose(0, 1).flatten(1).unsqueeze(0), ref.transpose(0, 1).flatten(1).unsqueeze(0)
    else:
        out, ref = out.flatten(2), ref.flatten(2)
    a = torch.sort(out, dim=-1).values
    b = torch.sort(ref, dim=-1).values
    ia = torch.linspace(0, a.shape[-1] - 1, n, device=a.device).long()
    ib = torch.linspace(0, b.shape[-1] - 1, n, device=b.device).long()
    return ((a[..., ia] - b[..., ib]) ** 2).mean()


def style_loss(feats: RandomFeatures, out: torch.Tensor, ref: torch.Tensor, hist_weight: float = 10.0,
               per_sample: bool = False) -> torch.Tensor:
    """Gram loss of the random features plus ``hist_weight`` times the colour histogram loss."""
    with torch.no_grad():
        gr = feats(ref)
    return gram_loss(feats(out), gr, per_sample) + hist_weight * histogram_loss(out, ref, per_sample=per_sample)
