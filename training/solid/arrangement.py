"""Arrangement loss: a texture's structure with its colour distribution factored out.

Scored against a paving photo, a hand-made Voronoi pavement with the photo's
colour histogram beat the trained speckle by only 7 % in the training loss
(docs/decisions/solid.md): the colour terms weigh far
more than where the colours are, so fits settle in speckle.  This term sees
only the arrangement.  Each image's luminance

    Y = 0.2126 R + 0.7152 G + 0.0722 B      (Rec. 709, as :mod:`.morphology`)

is mapped through its own rank to a standard normal marginal (histogram
specification onto N(0, 1), as in Heeger & Bergen 1995 and Portilla &
Simoncelli 2000, where the marginal is imposed apart from the structure):

    G(p) = Phi^-1((rank(Y(p)) + 1/2) / N)

so two images with the same arrangement of light and dark score the same
whatever their colours, contrast or histogram shape.  The loss is
:func:`.swd.swd_loss` (sliced Wasserstein distance, Heitz et al. 2021, Eq. 7)
over :class:`ArrangementFeatures`: random multi-scale features of the
one-channel G images (k x k neighbourhoods and zero-mean ReLU filters on
every pyramid level).

The rank is piecewise constant, so G has no gradient.  The output's G carries
the gradient of its linear stand-in (Y - mean Y) / std Y (a straight-through
estimator: the slope of the monotone map taken as that of the standardisation),
so the loss moves the luminance where the arrangement needs it.

Shapes: images (B, 3, H, W) float32 in [0, 1].  ``per_sample``: output b is
compared with reference b (space mode); otherwise the references are pooled
into one distribution (single-exemplar mode).
"""
from __future__ import annotations

import torch

from .swd import SlicedFeatures

__all__ = ["LUMA", "luminance", "gaussianise", "ArrangementFeatures"]

LUMA = (0.2126, 0.7152, 0.0722)


def luminance(img: torch.Tensor) -> torch.Tensor:
    """(B, 3, H, W) -> (B, 1, H, W)."""
    w = torch.tensor(LUMA, dtype=img.dtype, device=img.device).view(1, 3, 1, 1)
    return (img * w).sum(1, keepdim=True)


def gaussianise(y: torch.Tensor) -> torch.Tensor:
    """One-channel images (B, 1, H, W) with each image's marginal specified to N(0, 1): (B, 1, H, W).

    Ties keep their order of appearance.  Forward: exact ranks; backward: the
    gradient of the per-image standardisation (see the module doc)."""
    B, _, H, W = y.shape
    flat = y.flatten(1)
    n = flat.shape[1]
    q = torch.special.ndtri((torch.arange(n, dtype=torch.float64, device=y.device) + 0.5) / n).to(y.dtype)
    order = torch.argsort(flat.detach(), dim=1, stable=True)
    g = torch.empty_like(flat).scatter_(1, order, q.expand(B, n))
    mean = flat.mean(1, keepdim=True)
    std = flat.std(1, keepdim=True).clamp_min(1e-4)
    lin = (flat - mean) / std
    return (g + lin - lin.detach()).view(B, 1, H, W)


class ArrangementFeatures(SlicedFeatures):
    """One-channel random multi-scale features of the Gaussianised luminance (:class:`.swd.SlicedFeatures`)."""

    def __init__(self, seed: int = 0, levels: int = 5, patch: int = 5, width: int = 32, kernels=(3, 7, 15)):
        super().__init__(seed=seed, levels=levels, patch=patch, width=width, kernels=kernels, channels=1)

    def forward(self, img: torch.Tensor) -> list:
        """Taps of the Gaussianised luminance of ``img`` (B, 3, H, W) in [0, 1]."""
        return super().forward(gaussianise(luminance(img)) * 0.5, centred=True)
