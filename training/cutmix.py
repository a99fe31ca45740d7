"""CutMix for spatially-varying conditioning (Maesumi et al. 2024, Sec. 3.2, Fig. 3).

With probability ``p`` a training image receives 1-4 rotated rectangles cut
from other samples of the batch whose class differs; the pixels are copied in
place together with their per-pixel conditioning (class id and parameters), so
the network learns to follow a conditioning grid that changes across the image.

Shapes: images (B, 1, H, W) float32, ids (B, H, W) int64, params (B, P, H, W) float32.
"""
from __future__ import annotations

import math

import numpy as np
import torch

__all__ = ["cutmix", "rotated_box_mask"]


def rotated_box_mask(H: int, W: int, cx: float, cy: float, w: float, h: float, angle: float) -> torch.Tensor:
    """bool (H, W): pixel centres inside a w x h box centred at (cx, cy), rotated by ``angle`` radians."""
    y, x = torch.meshgrid(torch.arange(H, dtype=torch.float32) + 0.5, torch.arange(W, dtype=torch.float32) + 0.5,
                          indexing="ij")
    dx, dy = x - cx, y - cy
    c, s = math.cos(angle), math.sin(angle)
    u, v = c * dx + s * dy, -s * dx + c * dy
    return (u.abs() <= w / 2) & (v.abs() <= h / 2)


def cutmix(images, ids, params, rng: np.random.Generator, p: float = 0.5, max_boxes: int = 4,
           min_frac: float = 0.25, max_frac: float = 0.75):
    """Return mixed copies of (images, ids, params); class maps of every mixed sample change."""
    src = (images, ids, params)  # donors give their original pixels, never already-mixed ones
    images, ids, params = images.clone(), ids.clone(), params.clone()
    B, _, H, W = images.shape
    base = ids[:, 0, 0].clone()
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
            images[b, :, m] = src[0][d, :, m]
            ids[b, m] = src[1][d, m]
            params[b][:, m] = src[2][d][:, m]
    return images, ids, params
