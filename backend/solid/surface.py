"""Surface positions for solid-texture bakes: the 3D point behind every texel of a UV map.

A solid texture colours 3D space, so baking it into a UV image means
evaluating each texel at the surface point it maps to; the UV layout then adds
no seams or pole artefacts of its own (Henzler et al. 2020, Sec. 1: "infinite
domains", point-wise evaluation).  :func:`texel_positions` rasterises the UV
triangles at texel centres and interpolates the corner positions with
barycentric weights; :func:`dilate` extends the positions a few texels past
each UV island's border (the bake margin), so mipmaps and bilinear lookups at
island edges read colours from the continuous 3D field instead of background.

Images are in Blender's pixel order: row 0 is the bottom (v = 0).
Shapes: uv (T, 3, 2), positions (T, 3, 3) float; out mask bool (H, W), points float64 (H, W, 3).
"""
from __future__ import annotations

import numpy as np

from ..grid import Cancelled

__all__ = ["texel_positions", "dilate"]


def texel_positions(uv, positions, width: int, height: int, progress=None, cancel=None):
    """Rasterise UV triangles: (mask (H, W) bool, points (H, W, 3) float64 of the covered texels).

    A texel belongs to the triangle containing its centre ((j + 1/2) / W, (i + 1/2) / H);
    where triangles overlap in UV space, the later one wins.  ``progress(fraction)``;
    ``cancel()`` returning True raises Cancelled.
    """
    uv = np.asarray(uv, np.float64)
    pos = np.asarray(positions, np.float64)
    if uv.ndim != 3 or uv.shape[1:] != (3, 2):
        raise ValueError(f"uv must have shape (T, 3, 2), got {uv.shape}")
    if pos.shape != uv.shape[:2] + (3,):
        raise ValueError(f"positions must have shape {uv.shape[:2] + (3,)}, got {pos.shape}")
    if width < 1 or height < 1:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    mask = np.zeros((height, width), bool)
    pts = np.zeros((height, width, 3))
    px = uv * np.array([width, height]) - 0.5          # texel-centre coordinates: centre (j, i) at (j, i)
    lo = np.clip(np.floor(px.min(axis=1)).astype(np.int64), 0, [width - 1, height - 1])
    hi = np.clip(np.ceil(px.max(axis=1)).astype(np.int64), 0, [width - 1, height - 1])
    T = uv.shape[0]
    every = max(1, T // 100)
    for t in range(T):
        if t % every == 0:
            if cancel is not None and cancel():
                raise Cancelled("cancelled")
            if progress is not None:
                progress(t / T)
        (x0, y0), (x1, y1) = lo[t], hi[t]
        a, b, c = px[t]
        det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
        if abs(det) < 1e-12:        # degenerate in UV space: covers no texel centre
            continue
        xs = np.arange(x0, x1 + 1)
        ys = np.arange(y0, y1 + 1)
        X, Y = np.meshgrid(xs, ys)
        w1 = ((X - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (Y - a[1])) / det
        w2 = ((b[0] - a[0]) * (Y - a[1]) - (X - a[0]) * (b[1] - a[1])) / det
        w0 = 1.0 - w1 - w2
        eps = -1e-9
        inside = (w0 >= eps) & (w1 >= eps) & (w2 >= eps)
        if not inside.any():
            continue
        iy, ix = Y[inside], X[inside]
        p = w0[inside, None] * pos[t, 0] + w1[inside, None] * pos[t, 1] + w2[inside, None] * pos[t, 2]
        mask[iy, ix] = True
        pts[iy, ix] = p
    if progress is not None:
        progress(1.0)
    return mask, pts


def dilate(mask: np.ndarray, values: np.ndarray, margin: int):
    """Grow ``values`` (H, W, C) ``margin`` texels past ``mask``: each new texel takes the mean of its
    already-filled 8-neighbours.  Returns (grown mask, values); the inputs are not modified."""
    mask = mask.copy()
    vals = values.copy()
    H, W = mask.shape
    for _ in range(int(margin)):
        acc = np.zeros_like(vals)
        cnt = np.zeros((H, W))
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                if dx == 0 and dy == 0:
                    continue
                src_y = slice(max(0, -dy), H - max(0, dy))
                dst_y = slice(max(0, dy), H - max(0, -dy))
                src_x = slice(max(0, -dx), W - max(0, dx))
                dst_x = slice(max(0, dx), W - max(0, -dx))
                m = mask[src_y, src_x]
                acc[dst_y, dst_x] += vals[src_y, src_x] * m[..., None]
                cnt[dst_y, dst_x] += m
        new = (~mask) & (cnt > 0)
        if not new.any():
            break
        vals[new] = acc[new] / cnt[new, None]
        mask = mask | new
    return mask, vals
