"""Large neural noise images in overlapping tiles with bounded memory (MultiDiffusion, Bar-Tal et al. 2023).

At every sampler step the one global x_t is cut into overlapping tiles, each
tile's ε is predicted with its slice of the one global conditioning grid, and
the predictions are blended back with feathered weights (a linear ramp across
each overlap), so the sampler sees one image-sized ε:

    ε(p) = Σ_k w_k(p) ε_k(p) / Σ_k w_k(p)

The network's GroupNorm normalises over each tile instead of the whole image, so
a tiled image equals a one-piece one in its statistics, not bit for bit
(python -m bench neural measures both).  Tileable output treats the image as a
torus: tiles wrap around the edges, each runs with zero padding, and the blend
covers the torus, so the result still tiles.

    plan(H, W, tile, overlap, wrap) -> [(y0, x0)]   tile origins (may be negative or past the edge with wrap)
    tiled_eps(model, cond, tile, overlap, wrap, cache_maps) -> model(x, t, cond) callable over the full image
"""
from __future__ import annotations

import numpy as np

__all__ = ["plan", "feather", "tiled_eps", "map_bytes"]

_F = np.float32


def _starts(n: int, tile: int, overlap: int, wrap: bool) -> list:
    """Tile origins along one axis of length n: every pixel covered, neighbours overlapping by >= overlap."""
    if tile >= n:
        return [0]
    stride = tile - overlap
    if wrap:  # on a circle: k tiles of length tile, k * stride >= n
        k = -(-n // stride)
        return [round(i * n / k) for i in range(k)]
    k = -(-(n - overlap) // stride)
    return [round(i * (n - tile) / (k - 1)) for i in range(k)] if k > 1 else [0]


def plan(H: int, W: int, tile: int, overlap: int, wrap: bool = False) -> list:
    """[(y0, x0)] origins of the tiles of side ``tile`` (clipped to the image side) over an H x W image."""
    return [(y, x) for y in _starts(H, tile, overlap, wrap) for x in _starts(W, tile, overlap, wrap)]


def feather(th: int, tw: int, overlap: int, edges: tuple) -> np.ndarray:
    """float32 (th, tw) weights: 1 inside, a linear ramp over ``overlap`` px towards each side whose
    ``edges`` flag (top, bottom, left, right) says a neighbour overlaps it; never 0."""
    def ramp(n, lo, hi):
        r = np.ones(n, _F)
        m = min(overlap, n // 2)
        if m:
            up = (np.arange(m, dtype=_F) + 0.5) / m
            if lo:
                r[:m] = np.minimum(r[:m], up)
            if hi:
                r[-m:] = np.minimum(r[-m:], up[::-1])
        return r

    top, bottom, left, right = edges
    return np.outer(ramp(th, top, bottom), ramp(tw, left, right))


def map_bytes(model, h: int, w: int) -> int:
    """Bytes of the encoder's maps for an h x w tile (split export; 0 for a one-piece export)."""
    blocks = model.config.get("blocks")
    if model.form != "split" or not blocks:
        return 0
    return sum(4 * c * (h >> lvl) * (w >> lvl) for c, lvl in zip(blocks["channels"], blocks["levels"]))


def tiled_eps(model, cond: np.ndarray, tile: int, overlap: int, wrap: bool, cache_maps: bool):
    """model(x, t, cond) over the full image (B, 1, H, W) from ε of tiles; ``cond`` (B, C, H, W) is fixed.

    ``cache_maps``: keep every tile's encoder maps for all steps (fast; memory :func:`map_bytes` per
    tile), or recompute them at each step (bounded memory)."""
    B, C, H, W = cond.shape
    th, tw = min(tile, H), min(tile, W)
    tiles = []
    for y0, x0 in plan(H, W, tile, overlap, wrap):
        ys = np.arange(y0, y0 + th) % H
        xs = np.arange(x0, x0 + tw) % W
        if wrap:
            edges = (H > th,) * 2 + (W > tw,) * 2
        else:
            edges = (y0 > 0, y0 + th < H, x0 > 0, x0 + tw < W)
        # with kept maps a tile keeps its conditioning too (the maps are cached by the array's identity, and take
        # 12x its bytes); without, it is cut out again at each step, so no copy of the grid stays per tile
        sub = np.ascontiguousarray(cond[:, :, ys][:, :, :, xs]) if cache_maps else None
        tiles.append((ys, xs, feather(th, tw, overlap, edges), sub, model.eps_fn(False) if cache_maps else None))
    norm = np.zeros((H, W), _F)
    for ys, xs, w, _, _ in tiles:  # a tile is at most the image: its indices are distinct, so += is safe
        norm[ys[:, None], xs[None, :]] += w

    def eps(x, t, _cond):
        out = np.zeros_like(x, dtype=_F)
        for ys, xs, w, sub, fn in tiles:
            f = fn if fn is not None else model.eps_fn(False)
            c = sub if sub is not None else np.ascontiguousarray(cond[:, :, ys][:, :, :, xs])
            e = f(np.ascontiguousarray(x[:, :, ys][:, :, :, xs]), t, c)
            out[:, :, ys[:, None], xs[None, :]] += w * e
        return out / norm

    return eps
