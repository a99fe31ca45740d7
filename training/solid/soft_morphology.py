"""A differentiable level-set morphology term: the loss sees shapes, not colours.

Random-feature losses hardly tell stones from speckle once the colours are
right: on a paving photo a Voronoi pavement with the photo's colours beats
the trained speckle by 7 % in the training loss, and by 11 % in the same
distance over features of the rank-Gaussianised luminance
(a probe of optimised 2D images), while the level-set morphology of
:mod:`.morphology` puts it twice as near.  This module makes that morphology
a loss.  Per pyramid level of the luminance, each image's luminance is
mapped through its own rank to a standard normal (:func:`.arrangement.gaussianise`),
so the excursion set {G > t_q} with t_q = Phi^-1(q) is the set above the
image's own q-quantile, exactly as in :mod:`.morphology`.  Its indicator is
softened to

    s_q = sigmoid((G - t_q) / tau)

and the Minkowski functionals of :mod:`.morphology` become polynomials of
s_q that equal the hard counts when s_q is 0 or 1:

    P(q)    = sum over horizontal and vertical pixel pairs of |s - s'|, per pixel
    chi(q)  = (E[Q1] - E[Q3] - 2 E[Q_D]) / 4, per pixel (Gray 1971), with each
              2 x 2 quad's pattern probabilities taken as independent
              Bernoulli(s) products.

The term is

    mean over levels of  mean_q |P - P_ref| / mean_q P_ref + mean_q |chi - chi_ref| / mean_q |chi_ref|

(the distance of :func:`.morphology.morphology_distance`, chi scaled by 100
there and here).  The gradient flows through G's straight-through estimator
(:mod:`.arrangement`).  A model trained with this term is no longer judged
independently by the morphology column of the evaluation: judge it by the
patch distance and the pictures.

Shapes: images (B, 3, H, W) float32 in [0, 1].  ``per_sample``: output b is
compared with reference b; otherwise with the references' mean curves.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F

from .arrangement import gaussianise, luminance
from .morphology import LEVELS, QUANTILES

__all__ = ["soft_functionals", "soft_curves", "soft_morphology_loss", "TAU"]

TAU = 0.15          #: softness of the excursion sets, in units of the Gaussianised luminance's spread
_K = torch.tensor([1.0, 4.0, 6.0, 4.0, 1.0], dtype=torch.float64) / 16.0


def soft_functionals(s: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Boundary length and Euler characteristic per pixel of soft indicators s (..., H, W) in [0, 1]: two (...)
    tensors, equal to :func:`.morphology._functionals` of the binary image when s is 0 or 1."""
    n = s.shape[-1] * s.shape[-2]
    perim = ((s[..., 1:, :] - s[..., :-1, :]).abs().sum((-2, -1)) +
             (s[..., :, 1:] - s[..., :, :-1]).abs().sum((-2, -1))) / n
    a, b, c, d = s[..., :-1, :-1], s[..., :-1, 1:], s[..., 1:, :-1], s[..., 1:, 1:]
    na, nb, nc, nd = 1 - a, 1 - b, 1 - c, 1 - d
    q1 = a * nb * nc * nd + na * b * nc * nd + na * nb * c * nd + na * nb * nc * d
    q3 = na * b * c * d + a * nb * c * d + a * b * nc * d + a * b * c * nd
    qd = a * d * nb * nc + b * c * na * nd
    chi = (q1 - q3 - 2 * qd).sum((-2, -1)) / 4.0 / n
    return perim, chi


def _down(g: torch.Tensor) -> torch.Tensor:
    """5-tap binomial blur (reflected borders), then every second pixel: (B, 1, H, W) -> (B, 1, H/2, W/2)."""
    k = _K.to(g)
    g = F.pad(g, (2, 2, 2, 2), mode="reflect")
    g = F.conv2d(g, k.view(1, 1, 1, 5))
    g = F.conv2d(g, k.view(1, 1, 5, 1))
    return g[..., ::2, ::2]


def soft_curves(img: torch.Tensor, levels: int = LEVELS, tau: float = TAU) -> torch.Tensor:
    """P(q) and 100 chi(q) per pyramid level: (B, levels, 2, len(QUANTILES)), as :func:`.morphology.minkowski_curves`.

    Level 0 is the luminance; each coarser level blurs and halves the previous level's luminance, and each level
    is Gaussianised on its own (thresholds at its own quantiles)."""
    t = torch.special.ndtri(torch.as_tensor(QUANTILES, dtype=torch.float64)).to(img).view(1, -1, 1, 1)
    y = luminance(img)
    out = []
    for lvl in range(levels):
        if lvl:
            y = _down(y)
        g = gaussianise(y)
        p, chi = soft_functionals(torch.sigmoid((g - t) / tau))
        out.append(torch.stack([p, 100.0 * chi], 1))
    return torch.stack(out, 1)


def soft_morphology_loss(out: torch.Tensor, ref: torch.Tensor, per_sample: bool = False,
                         levels: int = LEVELS, tau: float = TAU) -> torch.Tensor:
    """Morphology distance (see module doc) of outputs (B, 3, H, W) to references, averaged over outputs."""
    cur = soft_curves(out, levels, tau)
    with torch.no_grad():
        rc = soft_curves(ref, levels, tau)
    if not per_sample:
        rc = rc.mean(0, keepdim=True)
    p = (cur[:, :, 0] - rc[:, :, 0]).abs().mean(-1) / (rc[:, :, 0].mean(-1) + 1e-9)
    c = (cur[:, :, 1] - rc[:, :, 1]).abs().mean(-1) / (rc[:, :, 1].abs().mean(-1) + 1e-9)
    return (p + c).mean()
