"""A decoder that sees a neighbourhood: a multi-scale convolutional generator of periodic 2D or 3D textures.

The per-point decoder of Henzler et al. (2020) colours each point from noise values at that point alone, and it
draws speckle and blotches, not stones, grain or courses (models/solid/MODEL_CARD.md, Limitations). This generator
is the alternative: the
multi-scale architecture of Ulyanov et al. ("Texture Networks", ICML 2016), in 3D as Gutierrez, Rabin, Galerne
and Hurtut ("On demand solid texture synthesis using deep 3D networks", Computer Graphics Forum 2020) use it for
solid textures trained from 2D slices.

Noise z_k of ``noise`` channels at resolution S / 2^k, k = 0 .. K-1 (S the output size). Starting from the
coarsest, each scale's noise passes a block of convolutions; the result is upsampled by 2 (nearest), joined
(concatenated) with the next finer scale's block and passes a join block (Ulyanov et al., Fig. 2):

    y_{K-1} = B(z_{K-1});  y_k = J([up(y_{k+1}), B(z_k)]);  d = W y_0 + b        (whitened colour d, (B, 3, S..))

Every convolution pads circularly, so a texture of size S is periodic in S and tiles without a seam; output
colour is rgb = mu + L d (the exemplar's mean and colour Cholesky factor, ``model.apply_colour``), so the
network learns arrangement, not palette. No normalisation layer (an on-demand block must not depend on the
batch). Shapes: noise list [(B, noise, S/2^k, ...)], output (B, 3, S, S[, S]) float32.
"""
from __future__ import annotations

import torch
from torch import nn
import torch.nn.functional as F

__all__ = ["ConvGenerator", "draw_noise"]


def _conv(dim: int, cin: int, cout: int, k: int) -> nn.Module:
    conv = (nn.Conv2d if dim == 2 else nn.Conv3d)(cin, cout, k, padding=k // 2, padding_mode="circular")
    nn.init.kaiming_normal_(conv.weight, a=0.2, nonlinearity="leaky_relu")
    nn.init.zeros_(conv.bias)
    return conv


def _block(dim: int, cin: int, cout: int) -> nn.Sequential:
    """3x3 -> 3x3 -> 1x1 convolutions with leaky ReLUs (Ulyanov et al.'s conv block)."""
    return nn.Sequential(_conv(dim, cin, cout, 3), nn.LeakyReLU(0.2), _conv(dim, cout, cout, 3), nn.LeakyReLU(0.2),
                         _conv(dim, cout, cout, 1), nn.LeakyReLU(0.2))


class ConvGenerator(nn.Module):
    """Multi-scale convolutional texture generator (module docstring). ``width``: channels per scale."""

    def __init__(self, dim: int = 2, scales: int = 5, noise: int = 4, width: int = 32, grow: bool = True):
        super().__init__()
        if dim not in (2, 3):
            raise ValueError(f"dim must be 2 or 3, got {dim}")
        if scales < 1:
            raise ValueError(f"scales must be at least 1, got {scales}")
        self.dim, self.scales, self.noise, self.width, self.grow = dim, scales, noise, width, grow
        self.blocks = nn.ModuleList([_block(dim, noise, width) for _ in range(scales)])
        # join k (k = 0 .. K-2) joins the upsampled coarser result with scale k's block (width channels); with
        # ``grow`` its output keeps all their channels (Ulyanov et al.: width * (K - k)), otherwise it has width
        # (a quarter to a fifth of the cost at full resolution, for 3D)
        cin = [width * (scales - k) if grow else 2 * width for k in range(scales - 1)]
        cout = [c if grow else width for c in cin]
        self.joins = nn.ModuleList([_block(dim, i, o) for i, o in zip(cin, cout)])
        self.out = _conv(dim, cout[0] if scales > 1 else width, 3, 1)
        nn.init.normal_(self.out.weight, std=0.1)

    def forward(self, noise: list) -> torch.Tensor:
        """noise[k]: (B, noise, S/2^k, ...) -> whitened colour d (B, 3, S, ...)."""
        if len(noise) != self.scales:
            raise ValueError(f"the generator has {self.scales} scales, got {len(noise)} noise tensors")
        y = self.blocks[-1](noise[-1])
        for k in range(self.scales - 2, -1, -1):
            up = F.interpolate(y, scale_factor=2, mode="nearest")
            y = self.joins[k](torch.cat([up, self.blocks[k](noise[k])], dim=1))
        return self.out(y)

    def n_params(self) -> int:
        return sum(p.numel() for p in self.parameters())


def draw_noise(batch: int, size: int, dim: int, scales: int, channels: int, generator: torch.Generator,
               device="cpu") -> list:
    """Uniform noise in [-1, 1) for each scale: [(B, channels, size / 2^k, ... dim times)], k = 0 .. scales-1,
    drawn from ``generator`` (on the CPU) and moved to ``device``."""
    if size % (2 ** (scales - 1)):
        raise ValueError(f"size {size} is not divisible by 2^{scales - 1} (the coarsest of {scales} scales)")
    return [(torch.rand((batch, channels) + (size >> k,) * dim, generator=generator) * 2 - 1).to(device)
            for k in range(scales)]
