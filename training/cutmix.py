"""CutMix for spatially-varying conditioning (Maesumi et al. 2024, Sec. 3.2, Fig. 3).

With probability ``p`` a training image receives 1-4 rotated rectangles cut
from other samples of the batch whose class differs; the pixels are copied in
place together with their per-pixel conditioning (class id and parameters), so
the network learns to follow a conditioning grid that changes across the image.

Shapes: images (B, 1, H, W) float32, ids (B, H, W) int64, params (B, P, H, W) float32.

Since pixels are copied in place, a mix is fully described by which sample each pixel comes from: the source map
of :func:`cutmix_sources` (B, H, W).  Training draws that map on the CPU and gathers images, class ids and
parameters through it on the training device (:func:`mix_by_sources`), instead of building (B, P, H, W) parameter
maps on the CPU and copying them over: at 128², batch 64, those are 92 MB a step.
"""
from __future__ import annotations

import math

import numpy as np
import torch

__all__ = ["cutmix", "cutmix_sources", "mix_by_sources", "rotated_box_mask"]


def rotated_box_mask(H: int, W: int, cx: float, cy: float, w: float, h: float, angle: float) -> torch.Tensor:
    """bool (H, W): pixel centres inside a w x h box centred at (cx, cy), rotated by ``angle`` radians."""
    y, x = torch.meshgrid(torch.arange(H, dtype=torch.float32) + 0.5, torch.arange(W, dtype=torch.float32) + 0.5,
                          indexing="ij")
    dx, dy = x - cx, y - cy
    c, s = math.cos(angle), math.sin(angle)
    u, v = c * dx + s * dy, -s * dx + c * dy
    return (u.abs() <= w / 2) & (v.abs() <= h / 2)


def cutmix_sources(base_ids: torch.Tensor, H: int, W: int, rng: np.random.Generator, p: float = 0.5,
                   max_boxes: int = 4, min_frac: float = 0.25, max_frac: float = 0.75) -> torch.Tensor:
    """int64 (B, H, W): the sample each pixel of each mixed image comes from (b itself where nothing was pasted).

    ``base_ids`` int64 (B,): each sample's class; donors are samples of another class.  Draws from ``rng`` in the
    order :func:`cutmix` always did, so a run's data stream is unchanged."""
    B = int(base_ids.shape[0])
    base = base_ids.cpu()
    src = torch.arange(B).view(B, 1, 1).expand(B, H, W).clone()
    for b in range(B):
        if rng.random() >= p:
            continue
        donors = np.nonzero((base != base[b]).numpy())[0]
        if len(donors) == 0:
            continue
        for _ in range(int(rng.integers(1, max_boxes + 1))):
            d = int(rng.choice(donors))
            w = float(rng.uniform(min_frac, max_frac)) * W
            h = float(rng.uniform(min_frac, max_frac)) * H
            m = rotated_box_mask(H, W, float(rng.uniform(0, W)), float(rng.uniform(0, H)), w, h,
                                 float(rng.uniform(0, math.pi)))
            src[b, m] = d
    return src


def mix_by_sources(images: torch.Tensor, ids: torch.Tensor, conds: torch.Tensor, src: torch.Tensor):
    """Per-sample data and a source map -> the mixed batch, on ``src``'s device.

    images (B, 1, H, W) float32, ids (B,) int64, conds (B, P) float32, src (B, H, W) int64 ->
    images (B, 1, H, W), class-id maps (B, H, W), parameter maps (B, P, H, W)."""
    B, _, H, W = images.shape
    dev = src.device
    yy = torch.arange(H, device=dev).view(1, H, 1)
    xx = torch.arange(W, device=dev).view(1, 1, W)
    mixed = images.to(dev)[src, 0, yy, xx].unsqueeze(1)
    return mixed, ids.to(dev)[src], conds.to(dev)[src].permute(0, 3, 1, 2).contiguous()


def cutmix(images, ids, params, rng: np.random.Generator, p: float = 0.5, max_boxes: int = 4,
           min_frac: float = 0.25, max_frac: float = 0.75):
    """Return mixed copies of (images, ids, params) (maps, see the module); class maps of every mixed sample change.
    Donors give their original pixels, never already-mixed ones."""
    B, _, H, W = images.shape
    src = cutmix_sources(ids[:, 0, 0], H, W, rng, p, max_boxes, min_frac, max_frac)
    yy, xx = torch.arange(H).view(1, H, 1), torch.arange(W).view(1, 1, W)
    return (images[src, :, yy, xx].permute(0, 3, 1, 2).contiguous(), ids[src, yy, xx],
            params[src, :, yy, xx].permute(0, 3, 1, 2).contiguous())
