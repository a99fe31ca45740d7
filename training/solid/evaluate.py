"""Evaluation of neural solid textures against baselines (Henzler et al. 2020, Sec. 5, Table 3).

For each exemplar and method, N samples (seeds 0..N-1) of S x S px at the
model's training resolution are compared with the exemplar's *held-out*
pixels (:func:`exemplars.heldout_region`):

style error  relative Gram distance of an *independent* random feature network
             (other seed, other widths and kernel sizes than the training loss:
             :data:`METRIC_FEATURES`) between each sample and the mean Gram of
             held-out crops, plus the sliced colour Wasserstein term; lower is better
PSD error    mean |log| ratio of the radially averaged luminance power spectra
             (sample vs held-out crops), a classical statistic independent of both networks
diversity    mean pairwise relative distance between the samples' first-layer
             feature maps (pixel-aligned): 0 when every seed gives the same image
success      diversity x (max style error of the row's methods - style error), the paper's
             combined measure

Methods: ``ours`` (2D model, or random axis-aligned and oblique slices of a 3D
model), ``tiled`` (the exemplar itself, the same tile whatever the seed),
``perlin_hist`` (fBm of the same lattice noise, coloured through the
exemplar's luminance-sorted colour histogram) and ``linear`` (Perlin's Eq. 1:
octaves of the lattice noise weighted by the exemplar's band energies along
its principal colour axis, mean and spread matched: a linear, non-learned
noise transform).
"""
from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

from omninoise.backend.solid.value_noise import value_noise
from omninoise.backend.solid.model import plane_points
from . import exemplars as ex
from .features import RandomFeatures, gram_loss, histogram_loss
from .model import axis_frame

__all__ = ["METRIC_FEATURES", "evaluate_exemplar", "slices_3d", "baselines", "EVAL_SIZE"]

EVAL_SIZE = 64
#: the evaluation's own feature network: not the one the models were trained against
METRIC_FEATURES = dict(seed=1234, widths=(48, 96), kernels=(7, 3), levels=3)


def _to_t(img: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(img, np.float32)).permute(2, 0, 1).unsqueeze(0)


def _crops(region: torch.Tensor, n: int, size: int, seed: int) -> torch.Tensor:
    g = torch.Generator().manual_seed(seed)
    return ex.random_crops(region, n, size, g)


def _psd(img: torch.Tensor) -> np.ndarray:
    """Radially averaged power spectrum of luminance (B, 3, S, S) -> (S//2,) mean over the batch."""
    y = img.mean(1)
    y = y - y.mean(dim=(1, 2), keepdim=True)
    P = (torch.fft.fft2(y).abs() ** 2).mean(0).numpy()
    S = P.shape[0]
    f = np.fft.fftfreq(S) * S
    R = np.rint(np.hypot(*np.meshgrid(f, f, indexing="ij"))).astype(int)
    tot = np.bincount(R.ravel(), P.ravel())[1:S // 2]
    cnt = np.bincount(R.ravel())[1:S // 2]
    return tot / np.maximum(cnt, 1)


def _metrics(samples: torch.Tensor, refs: torch.Tensor, feats: RandomFeatures) -> dict:
    with torch.no_grad():
        gr = feats(refs)
        style = float(np.mean([float(gram_loss(feats(s[None]), gr)) + 10.0 * float(histogram_loss(s[None], refs))
                               for s in samples]))
        psd = float(np.mean(np.abs(np.log((_psd(samples) + 1e-12) / (_psd(refs) + 1e-12)))))
        x = (samples - 0.5) * 4.0
        fm = F.relu(F.conv2d(x, feats.w0, feats.b0)).flatten(1)
        n = fm.shape[0]
        d = [float((fm[a] - fm[b]).norm() / (0.5 * (fm[a].norm() + fm[b].norm()) + 1e-8))
             for a in range(n) for b in range(a + 1, n)]
    return dict(style=round(style, 4), psd=round(psd, 4), diversity=round(float(np.mean(d)), 4))


def slices_3d(evaluate, n: int, size: int, px_per_unit: float, seed: int = 0, fixed_axis: str = "") -> np.ndarray:
    """n slices (axis-aligned xy/xz/yz in turn, every 4th oblique) of a 3D texture through random
    points, sample i with seed i: evaluate(points (N, 3), seed) -> (N, 3).  Returns (n, size, size, 3).
    ``fixed_axis`` ("columns" or "rows", a model trained so): the planes it was trained on instead, through
    that axis at random angles about it, the image's horizontal along x ("columns") or its vertical along z."""
    rng = np.random.default_rng(seed)
    plane = plane_points(size, px_per_unit)
    out = []
    for i in range(n):
        if fixed_axis:
            frame = np.array(axis_frame(fixed_axis, rng.uniform(0.0, 2.0 * np.pi))).T   # columns u, v
        elif i % 4 == 3:
            q, r = np.linalg.qr(rng.normal(size=(3, 3)))
            frame = q * np.sign(np.diag(r))
        else:
            frame = np.eye(3)[:, [(0, 1, 2), (0, 2, 1), (1, 2, 0)][i % 4]]
        pts = plane @ frame[:, :2].T + rng.uniform(-50, 50, 3)
        out.append(evaluate(pts, i).reshape(size, size, 3))
    return np.stack(out)


def _fbm(n: int, size: int, octaves: int, dim: int = 2, seed0: int = 0) -> np.ndarray:
    """Per-octave value noise of the runtime's lattice (identity transforms): (n, size, size, octaves)."""
    u = (np.arange(size) + 0.5) / size * 4.0     # 4 coarse cells across the image
    vv, uu = np.meshgrid(u, u, indexing="ij")
    pts = np.stack([uu.ravel(), vv.ravel()], 1)
    T = np.stack([np.eye(dim, dtype=np.float32)] * octaves)
    return np.stack([value_noise(pts + 100.0 * i, T, seed0 + i, 1).reshape(size, size, octaves)
                     for i in range(n)])


def baselines(region: torch.Tensor, n: int, size: int) -> dict:
    """The baseline methods' samples for a training region (3, H, W): {name: (n, 3, S, S)}."""
    img = region.permute(1, 2, 0).numpy().reshape(-1, 3)
    out = {"tiled": region[:, :size, :size].unsqueeze(0).repeat(n, 1, 1, 1)}
    octs = int(math.log2(size / 4)) + 1        # octave i: 4 * 2^i cells across the image, the finest ~1 per px
    noise = _fbm(n, size, octs)
    # Perlin noise coloured by the exemplar's histogram: fBm ranks -> luminance-sorted exemplar colours
    fbm = (noise * 0.5 ** np.arange(octs)).sum(-1)
    lum_sorted = img[np.argsort(img.mean(1), kind="stable")]
    ph = []
    for f in fbm:
        ranks = np.argsort(np.argsort(f.ravel(), kind="stable"), kind="stable")
        ph.append(lum_sorted[(ranks * (len(img) - 1)) // max(1, f.size - 1)].reshape(size, size, 3))
    out["perlin_hist"] = torch.from_numpy(np.stack(ph).astype(np.float32)).permute(0, 3, 1, 2)
    # linear: octaves weighted by the exemplar's band energies along its principal colour axis
    lum = region.mean(0).numpy()
    P = np.abs(np.fft.fft2(lum - lum.mean())) ** 2
    fy, fx = np.meshgrid(np.fft.fftfreq(lum.shape[0]), np.fft.fftfreq(lum.shape[1]), indexing="ij")
    R = np.hypot(fy, fx) * size / 4.0            # cycles per coarse cell of the noise
    w = np.array([math.sqrt(P[(R >= 2 ** (k - 1)) & (R < 2 ** k)].sum() + 1e-12) for k in range(octs)])
    s = (noise * w).sum(-1)                      # octave k of the noise has 2^k cells per coarse cell
    s = (s - s.mean()) / (s.std() + 1e-8)
    mean = img.mean(0)
    cov = np.cov(img.T)
    evals, evecs = np.linalg.eigh(cov)
    axis = evecs[:, -1] * math.sqrt(max(evals[-1], 0.0))
    lin = np.clip(mean + s[..., None] * axis, 0.0, 1.0)
    out["linear"] = torch.from_numpy(lin.astype(np.float32)).permute(0, 3, 1, 2)
    return out


def evaluate_exemplar(name: str, region_scale: float, methods: dict, n: int = 8, size: int = EVAL_SIZE) -> dict:
    """Metrics of every method for exemplar ``name``.

    methods  {method: (n, size, size, 3) float32 samples at the training resolution}
    Returns {method: {style, psd, diversity, success}} with the baselines added.
    """
    def rescale(t):
        if region_scale == 1.0:
            return t
        return F.interpolate(t.unsqueeze(0), scale_factor=region_scale, mode="bilinear", antialias=region_scale < 1,
                             align_corners=False)[0].clamp(0, 1)

    held = rescale(ex.heldout_region(name))
    train_region = rescale(ex.train_region(ex.exemplar(name), name, hold_out=True))   # never the held-out pixels
    refs = _crops(held, 16, size, seed=99)
    feats = RandomFeatures(**METRIC_FEATURES)
    res = {}
    for m, arr in methods.items():
        res[m] = _metrics(torch.from_numpy(np.asarray(arr, np.float32)).permute(0, 3, 1, 2), refs, feats)
    for m, t in baselines(train_region, n, size).items():
        res[m] = _metrics(t, refs, feats)
    worst = max(r["style"] for r in res.values())
    for r in res.values():
        r["success"] = round(r["diversity"] * (worst - r["style"]), 4)
    return res
