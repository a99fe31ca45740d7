"""Spectrum term of the solid-texture loss: the shape of the luminance's power spectrum, band by band.

Random phase noise (Galerne, Gousseau, Morel 2011) keeps a photo's Fourier
modulus and nothing else, and it lies nearer to the held-out photos than the
texture-space model on 85 of 87 of them by the level-set morphology measure
(models/solid/MODEL_CARD.md): the model's colours were right and its spectrum
was not (fine speckle, a power spectrum flat where the photo's falls).  The
sliced Wasserstein and histogram terms let that through: a per-pixel speckle
of the right colours matches the colour distribution, which outweighs the
arrangement.  This term asks for the spectrum directly, as Liu, Gousseau and
Xia ("Texture synthesis through convolutional neural networks and spectrum
constraints", ICPR 2016) add it to Gatys et al.'s loss:

    P(k) = |F(w · (y - mean y))(k)|²            periodogram of the Hann-windowed luminance y
    p_b  = Σ_{k in band b} P(k) / Σ_k P(k)      the share of band b (log-spaced radius x orientation)
    L    = mean_b (log(p_b + ε) - log(p̂_b + ε))²

over ``radial`` log-spaced rings from 1/size to the Nyquist frequency, each cut into
``angular`` orientation sectors of [0, π) centred on the axes (the periodogram of a real image is
symmetric), p̂ the reference's.  The shares are normalised, so contrast (the
histogram term's job) does not enter; the log makes a decade of excess power
cost the same in every band, so speckle at the finest scales counts as much as
missing blobs at coarse ones.  A single 128² crop's periodogram is noisy
(each value an exponential variable); summing a band pools its many values.

Shapes: images (B, 3, H, W) float32 in [0, 1]; the loss is a scalar, per sample (output b
against reference b: space mode) or against the references' pooled mean spectrum.
"""
from __future__ import annotations

import math

import torch

__all__ = ["band_index", "band_shares", "spectrum_loss"]

_LUMA = (0.2126, 0.7152, 0.0722)
EPS = 1e-6


def band_index(h: int, w: int, radial: int = 8, angular: int = 4) -> torch.Tensor:
    """int64 (h, w // 2 + 1): the band of each rfft2 coefficient (radial ring x orientation sector), or -1
    for the DC term.  Rings split log2 of the radius |k| (cycles per pixel) from 1/max(h, w) to 1/2 (the
    corners beyond 1/2 join the last ring) evenly."""
    fy = torch.fft.fftfreq(h).view(-1, 1).expand(h, w // 2 + 1)
    fx = torch.fft.rfftfreq(w).view(1, -1).expand(h, w // 2 + 1)
    r = torch.sqrt(fx ** 2 + fy ** 2)
    lo, hi = math.log2(1.0 / max(h, w)), math.log2(0.5)
    ring = ((torch.log2(r.clamp_min(1e-9)) - lo) / (hi - lo) * radial).floor().clamp(0, radial - 1).long()
    theta = torch.atan2(fy, fx) % math.pi                      # orientation in [0, π)
    # sectors centred on the axes (0, π/2) and, with 4, the diagonals: no coefficient on a sector's edge
    sector = (theta / math.pi * angular + 0.5).floor().long() % angular
    idx = ring * angular + sector
    idx[r == 0] = -1
    return idx


def band_shares(img: torch.Tensor, radial: int = 8, angular: int = 4) -> torch.Tensor:
    """(B, 3, H, W) -> (B, radial * angular): each band's share of the windowed luminance's power."""
    B, _, H, W = img.shape
    y = torch.einsum("c,bchw->bhw", torch.tensor(_LUMA, dtype=img.dtype, device=img.device), img)
    y = y - y.mean(dim=(1, 2), keepdim=True)
    win = torch.outer(torch.hann_window(H, periodic=False, dtype=img.dtype, device=img.device),
                      torch.hann_window(W, periodic=False, dtype=img.dtype, device=img.device))
    # the rfft2 keeps half the plane: columns 1 .. ceil(W/2)-1 stand for two (k and -k) of the full one
    twice = torch.ones(W // 2 + 1, dtype=img.dtype, device=img.device)
    twice[1:(W + 1) // 2] = 2.0
    P = torch.fft.rfft2(y * win).abs() ** 2 * twice              # (B, H, W // 2 + 1)
    idx = band_index(H, W, radial, angular).to(img.device)
    keep = idx >= 0
    n = radial * angular
    sums = torch.zeros(B, n, dtype=img.dtype, device=img.device)
    sums = sums.index_add(1, idx[keep], P[:, keep])
    return sums / sums.sum(dim=1, keepdim=True).clamp_min(1e-12)


def spectrum_loss(out: torch.Tensor, ref: torch.Tensor, per_sample: bool = False, radial: int = 8,
                  angular: int = 4) -> torch.Tensor:
    """Mean squared difference of log band shares (see the module docstring); ``per_sample``: output b
    against reference b, else every output against the references' mean shares."""
    po = band_shares(out, radial, angular)
    with torch.no_grad():
        pr = band_shares(ref, radial, angular)
    if not per_sample:
        pr = pr.mean(0, keepdim=True)
    return ((torch.log(po + EPS) - torch.log(pr + EPS)) ** 2).mean()
