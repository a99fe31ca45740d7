"""Conditioning grids for the neural noise model (Maesumi et al. 2024, Sec. 3.1, Fig. 4).

The network reads a grid F (E + P, H, W): per pixel, a class embedding (E) and
the normalised parameter vector (P).  Training only showed uniform grids and
CutMix patchworks; at inference any grid may be built:

    uniform       one class, one parameter set
    blend         two (class, params) specs mixed by a weight map w (H, W) in [0, 1]:
                  embeddings by spherical interpolation (slerp; linear when they coincide),
                  parameters linearly
    four_corner   bilinear blend of four specs placed at the corners (Fig. 4)
    mask_weight   a weight map from a painted mask: signed Euclidean distance to the
                  mask's border, a transition width and a sharpness exponent
    painted       several regions of an indexed or colour-coded image, each a spec

A "spec" is (class name, {parameter: physical value}).  All arrays float32.
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingError

__all__ = ["slerp", "uniform", "blend", "four_corner", "mask_weight", "distance_transform", "painted", "spec_vectors"]

_F = np.float32


def spec_vectors(model, spec) -> tuple:
    """(class, params) -> (embedding (E,), parameter vector (P,))."""
    name, values = spec
    return model.embedding[model.class_id(name)], model.param_vector(name, values)


def slerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Spherical interpolation of vectors a, b (E,) by weights w (...) -> (..., E); safe when a ≈ b."""
    w = np.asarray(w, np.float64)[..., None]
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    cos = float(np.dot(a, b) / max(na * nb, 1e-12))
    omega = np.arccos(np.clip(cos, -1.0, 1.0))
    if np.sin(omega) < 1e-4:  # (nearly) the same direction: slerp degenerates to lerp
        return ((1 - w) * a + w * b).astype(_F)
    s = np.sin(omega)
    return (np.sin((1 - w) * omega) / s * a + np.sin(w * omega) / s * b).astype(_F)


def _grid(emb: np.ndarray, par: np.ndarray) -> np.ndarray:
    """(H, W, E) and (H, W, P) -> (E + P, H, W)."""
    return np.ascontiguousarray(np.concatenate([emb, par], -1).transpose(2, 0, 1), _F)


def uniform(model, spec, H: int, W: int) -> np.ndarray:
    e, p = spec_vectors(model, spec)
    return _grid(np.broadcast_to(e, (H, W, e.size)), np.broadcast_to(p, (H, W, p.size)))


def blend(model, spec_a, spec_b, weight: np.ndarray) -> np.ndarray:
    """weight (H, W): 0 -> spec_a, 1 -> spec_b."""
    w = np.clip(np.asarray(weight, np.float64), 0.0, 1.0)
    if w.ndim != 2:
        raise SettingError("mask", f"a blend weight map is (H, W), got shape {w.shape}")
    ea, pa = spec_vectors(model, spec_a)
    eb, pb = spec_vectors(model, spec_b)
    par = ((1 - w)[..., None] * pa + w[..., None] * pb).astype(_F)
    return _grid(slerp(ea, eb, w), par)


def _normalised_mix(weights: np.ndarray, embs: np.ndarray) -> np.ndarray:
    """Σ wᵢ eᵢ rescaled to Σ wᵢ |eᵢ|: a spherical-style mix of many embeddings. weights (H, W, n), embs (n, E)."""
    mix = weights @ embs
    norm = weights @ np.linalg.norm(embs, axis=1)
    return (mix * (norm / np.maximum(np.linalg.norm(mix, axis=-1), 1e-12))[..., None]).astype(_F)


def four_corner(model, specs, H: int, W: int) -> np.ndarray:
    """specs: top-left, top-right, bottom-left, bottom-right -> bilinear grid (Fig. 4)."""
    if len(specs) != 4:
        raise SettingError("corners", f"four specs needed, got {len(specs)}")
    v = np.linspace(0.0, 1.0, H)[:, None]
    u = np.linspace(0.0, 1.0, W)[None, :]
    w = np.stack([(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v], -1)
    vecs = [spec_vectors(model, s) for s in specs]
    embs = np.stack([e for e, _ in vecs])
    pars = np.stack([p for _, p in vecs])
    return _grid(_normalised_mix(w, embs), (w @ pars).astype(_F))


def distance_transform(mask: np.ndarray) -> np.ndarray:
    """Exact Euclidean distance (px) from every pixel to the nearest True pixel: float32 (H, W).

    Two separable passes of d²(x) = min_j (x - j)² + f(j) (Felzenszwalb & Huttenlocher's
    definition), each as blocked brute-force minima: O(H W (H + W)) work in numpy.
    """
    m = np.asarray(mask, bool)
    if not m.any():
        return np.full(m.shape, np.inf, _F)
    big = float(m.shape[0] ** 2 + m.shape[1] ** 2)
    f = np.where(m, 0.0, big).astype(np.float64)

    def pass_rows(g):  # along axis 1, for every row
        n = g.shape[1]
        idx = np.arange(n, dtype=np.float64)
        sq = (idx[:, None] - idx[None, :]) ** 2  # (x, j)
        out = np.empty_like(g)
        step = max(1, (1 << 22) // (n * n))
        for r in range(0, g.shape[0], step):
            out[r: r + step] = np.min(g[r: r + step, None, :] + sq[None], axis=2)
        return out

    d2 = pass_rows(pass_rows(f).T).T
    return np.sqrt(d2).astype(_F)


def mask_weight(mask: np.ndarray, width: float = 32.0, sharpness: float = 1.0) -> np.ndarray:
    """A painted mask (H, W) (True / > 0.5 = the second spec) -> blend weights float32 (H, W) in [0, 1].

    s = signed distance to the border (px, positive inside); t = clamp(1/2 + s / width, 0, 1);
    w = tᵏ / (tᵏ + (1 - t)ᵏ) with k = ``sharpness`` (1: linear ramp; larger: a harder edge).
    """
    if not width > 0 or not sharpness > 0:
        raise SettingError("mask", f"width and sharpness must be positive, got {width:g} and {sharpness:g}")
    m = np.asarray(mask)
    m = m > 0.5 if m.dtype != bool else m
    if m.all() or not m.any():
        return np.full(m.shape, 1.0 if m.all() else 0.0, _F)
    s = distance_transform(~m) - distance_transform(m)  # >0 inside, <0 outside
    t = np.clip(0.5 + s / width, 0.0, 1.0)
    tk, uk = t ** sharpness, (1 - t) ** sharpness
    return (tk / np.maximum(tk + uk, 1e-12)).astype(_F)


def painted(model, image: np.ndarray, specs: dict, width: float = 16.0, sharpness: float = 1.0) -> np.ndarray:
    """A multi-class map from an indexed (H, W) int image or a colour-coded (H, W, 3) uint8 image.

    specs maps each index (or (r, g, b) tuple) present in the image to a spec.  Each region
    gets a soft weight (:func:`mask_weight`); weights are normalised to sum 1 per pixel.
    """
    img = np.asarray(image)
    keys = [tuple(int(c) for c in k) if np.ndim(k) else int(k) for k in specs]
    if img.ndim == 3:
        present = {tuple(int(c) for c in v) for v in np.unique(img.reshape(-1, img.shape[2])[:, :3], axis=0)}
        masks = {k: np.all(img[..., :3] == np.asarray(k, img.dtype), axis=-1) for k in keys}
    elif img.ndim == 2:
        present = {int(v) for v in np.unique(img)}
        masks = {k: img == k for k in keys}
    else:
        raise SettingError("map", f"expected an (H, W) index image or (H, W, 3) colours, got shape {img.shape}")
    missing = sorted(map(str, present - set(keys)))
    if missing:
        raise SettingError("map", f"the map uses {missing[0]} but no spec is given for it")
    weights = np.stack([mask_weight(masks[k], width, sharpness) for k in keys], -1).astype(np.float64)
    weights /= np.maximum(weights.sum(-1, keepdims=True), 1e-12)
    vecs = [spec_vectors(model, v) for v in specs.values()]
    embs = np.stack([e for e, _ in vecs]).astype(np.float64)
    pars = np.stack([p for _, p in vecs]).astype(np.float64)
    return _grid(_normalised_mix(weights, embs), (weights @ pars).astype(_F))
