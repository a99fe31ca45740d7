"""The ε-prediction U-Net of Maesumi et al. 2024 (Sec. 3.1, Appendix C), in torch.

Three levels of 32 / 64 / 128 channels, two ResNet blocks per level and two in
the bottleneck, skip concatenation on the way up.  Every ResNet block's first
normalisation is modulated twice (Eq. 2):

    h = GroupNorm(conv(x)) * (1 + γ₁(t)) + β₁(t)    diffusion time, sinusoidal encoding -> MLP
    h = h * (1 + γ₂(F)) + β₂(F)                      SPADE: F resized (nearest) to the block,
                                                     γ₂, β₂ = 3x3 convs of conv3x3(F)

F is the conditioning feature grid: a per-pixel MLP (three layers of 128, as
1x1 convolutions) of [class embedding, parameter vector] (B, E + P, H, W).
The network takes that grid already embedded, so spatial blends of classes
(slerp of embeddings) and parameters are built outside it, at any resolution.

Shapes: x (B, 1, H, W) float32 with H, W multiples of 8; t (B,) float32 in [0, T);
cond (B, E + P, H, W) float32 -> ε (B, 1, H, W).

The SPADE branch depends on the conditioning alone, not on x_t or t, so the
forward pass is two functions (one code path for training and both exports):

    maps = encode(cond, tile)          per ResBlock k: (B, 2 C_k, H_k, W_k) = [1 + γ₂, β₂]
    ε    = denoise(x, t, maps, tile)   the rest of the network

A sampler runs ``encode`` once per image and ``denoise`` at every step.

``denoise(..., fold=True)`` is the same function in fewer full-resolution operations, for the exported
denoiser: GroupNorm's affine (w, b) and the time modulation fold into one scale and shift per
channel, h = norm(conv(x)) * w(1 + γ₁) + (b(1 + γ₁) + β₁), computed on (B, C) vectors instead of four passes
over the feature map; and each downsampling (pixel unshuffle, then a 1x1 convolution of the 4C channels) is
the 2x2 stride-2 convolution with the same weights, K[o, c, i, j] = W[o, 4c + 2i + j], without the unshuffle's
transpose.  Only the rounding differs.

``deep`` > 0 adds a deep branch at the bottleneck, between its two ResBlocks: ``deep`` further levels
(downsample, two ResBlocks, upsample) whose output is added to the bottleneck through a zero-initialised
convolution.  It doubles the network's reach per level (long-range structure: damascus bands, fibre runs)
and, zero at initialisation, leaves a warm-started network's function exactly as it was, so a deeper
model continues the shipped weights instead of starting over.
"""
from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["UNet", "set_circular"]


class Conv3(nn.Conv2d):
    """3x3 convolution with explicit one-pixel padding: zeros, or circular (wrap-around) for tiles.

    ``tile`` is a float tensor, 0 or 1, shared by every Conv3 of a network during one
    forward pass (see :meth:`UNet.forward`), so one exported ONNX graph serves both
    plain and seamless output.  Weights are those of ``nn.Conv2d(cin, cout, 3, padding=1)``.
    """

    def __init__(self, cin: int, cout: int):
        super().__init__(cin, cout, 3, padding=0)
        self.tile = None  # set by UNet.forward

    def forward(self, x):
        if isinstance(self.tile, str):  # "circular": a graph for seamless tiles only (no blend with zeros)
            return super().forward(F.pad(x, (1, 1, 1, 1), mode="circular"))
        if self.tile is None:  # the convolution's own zero padding: no separate Pad op in an exported graph
            return F.conv2d(x, self.weight, self.bias, 1, 1)
        zero = F.pad(x, (1, 1, 1, 1))
        wrap = F.pad(x, (1, 1, 1, 1), mode="circular")
        return super().forward(zero + (wrap - zero) * self.tile)


class TimeEmbedding(nn.Module):
    def __init__(self, dim: int = 32, out: int = 128):
        super().__init__()
        self.dim = dim
        self.mlp = nn.Sequential(nn.Linear(dim, out), nn.GELU(), nn.Linear(out, out))

    def forward(self, t):
        half = self.dim // 2
        freqs = torch.exp(-math.log(10000.0) * torch.arange(half, device=t.device, dtype=torch.float32) / (half - 1))
        a = t.float()[:, None] * freqs[None]
        return self.mlp(torch.cat([a.sin(), a.cos()], 1))


class SPADE(nn.Module):
    """γ, β maps from the feature grid, nearest-resized to the block (Park et al. 2019)."""

    def __init__(self, channels: int, feat: int = 128, hidden: int = 64):
        super().__init__()
        hid = min(channels, hidden)  # 64 hidden channels keep the network near the paper's ~5M parameters
        self.shared = nn.Sequential(Conv3(feat, hid), nn.SiLU())
        self.gamma = Conv3(hid, channels)
        self.beta = Conv3(hid, channels)

    def maps(self, feat):
        """feat already resized to the block -> [1 + γ, β] stacked on channels (B, 2C, h, w)."""
        f = self.shared(feat)
        return torch.cat([1.0 + self.gamma(f), self.beta(f)], 1)

    @staticmethod
    def apply(h, maps):
        """h * (1 + γ) + β with ``maps`` from :meth:`maps`, or the pair (1 + γ, β) already apart (an export's
        denoiser takes them as two inputs, so no step slices them)."""
        g1, b = maps if isinstance(maps, tuple) else maps.chunk(2, dim=1)
        return h * g1 + b


class Downsample(nn.Sequential):
    """Pixel unshuffle by 2, then a 1x1 convolution (4C -> C); folded (see the module doc), one 2x2 stride-2 convolution."""

    def __init__(self, c: int):
        super().__init__(nn.PixelUnshuffle(2), nn.Conv2d(4 * c, c, 1))
        self.fold = False

    def forward(self, x):
        if not self.fold:
            return super().forward(x)
        conv = self[1]
        # PixelUnshuffle's channel 4c + 2i + j holds pixel (2y + i, 2x + j) of channel c
        k = conv.weight.reshape(conv.out_channels, conv.in_channels // 4, 2, 2)
        return F.conv2d(x, k, conv.bias, stride=2)


class ResBlock(nn.Module):
    def __init__(self, cin: int, cout: int, tdim: int = 128, groups: int = 8):
        super().__init__()
        self.fold = False  # see the module doc: set for each pass by UNet._set_pass
        self.conv1 = Conv3(cin, cout)
        self.norm1 = nn.GroupNorm(groups, cout)
        self.time = nn.Linear(tdim, 2 * cout)
        self.spade = SPADE(cout)
        self.conv2 = Conv3(cout, cout)
        self.norm2 = nn.GroupNorm(groups, cout)
        self.skip = nn.Conv2d(cin, cout, 1) if cin != cout else nn.Identity()

    def forward(self, x, temb, maps):
        """block 1: conv -> GroupNorm -> x(1+γ₁)+β₁ (time) -> x(1+γ₂)+β₂ (SPADE maps) -> SiLU; block 2 plain."""
        g, b = self.time(F.silu(temb)).chunk(2, dim=1)
        if self.fold:  # GroupNorm's affine and the time modulation as one (B, C) scale and shift
            n = self.norm1
            scale, shift = n.weight * (1.0 + g), n.bias * (1.0 + g) + b
            # no affine: the export's drop_identity_arithmetic removes the multiply by ones and add of zeros
            # that the exporter writes for it
            h = F.group_norm(self.conv1(x), n.num_groups, eps=n.eps) * scale[:, :, None, None] + shift[:, :, None, None]
        else:
            h = self.norm1(self.conv1(x)) * (1.0 + g[:, :, None, None]) + b[:, :, None, None]
        h = F.silu(SPADE.apply(h, maps))
        h = F.silu(self.norm2(self.conv2(h)))
        return h + self.skip(x)


class DeepBranch(nn.Module):
    """``depth`` more levels below the bottleneck (channels ``c``): downsample, ResBlock, [inner branch],
    ResBlock, upsample, and a 3x3 convolution initialised to zero, so the branch adds nothing until trained."""

    def __init__(self, c: int, depth: int):
        super().__init__()
        self.depth = depth
        self.down = Downsample(c)
        self.res = nn.ModuleList([ResBlock(c, c), ResBlock(c, c)])
        self.inner = DeepBranch(c, depth - 1) if depth > 1 else None
        self.out = Conv3(c, c)
        nn.init.zeros_(self.out.weight)
        nn.init.zeros_(self.out.bias)

    def blocks(self, level: int) -> list:
        """(ResBlock, level) in the forward pass's order."""
        inner = self.inner.blocks(level + 1) if self.inner is not None else []
        return [(self.res[0], level)] + inner + [(self.res[1], level)]

    def forward(self, h, temb, maps):
        """h (B, c, H, W) -> what the branch adds to it; ``maps`` an iterator over the SPADE maps (shared with
        the caller, so the branch takes its blocks' maps in :meth:`blocks` order)."""
        g = self.res[0](self.down(h), temb, next(maps))
        if self.inner is not None:
            g = g + self.inner(g, temb, maps)
        g = self.res[1](g, temb, next(maps))
        return self.out(F.interpolate(g, scale_factor=2.0, mode="nearest"))


class UNet(nn.Module):
    """ε-network; ``embed`` turns class-id and parameter maps into its conditioning grid."""

    def __init__(self, n_classes: int, n_params: int, emb_dim: int = 32, widths=(32, 64, 128), feat: int = 128,
                 deep: int = 0):
        super().__init__()
        self.n_classes, self.n_params, self.emb_dim, self.widths = n_classes, n_params, emb_dim, tuple(widths)
        self.circular = False
        self.class_emb = nn.Embedding(n_classes, emb_dim)
        nn.init.normal_(self.class_emb.weight)  # E|e|^2 = emb_dim: the spherical penalty's target norm
        self.cond_mlp = nn.Sequential(nn.Conv2d(emb_dim + n_params, feat, 1), nn.GELU(),
                                      nn.Conv2d(feat, feat, 1), nn.GELU(), nn.Conv2d(feat, feat, 1))
        self.temb = TimeEmbedding(32, 128)
        w = self.widths
        self.init = Conv3(1, w[0])
        self.down = nn.ModuleList()
        self.downsample = nn.ModuleList()
        c = w[0]
        skips = []
        for i, cw in enumerate(w):
            blocks = nn.ModuleList([ResBlock(c, cw), ResBlock(cw, cw)])
            self.down.append(blocks)
            skips.append(cw)
            c = cw
            self.downsample.append(Downsample(c))
        self.mid = nn.ModuleList([ResBlock(c, c), ResBlock(c, c)])
        #: the deep branch's levels (nested DeepBranch modules), or None
        self.deep = DeepBranch(c, deep) if deep > 0 else None
        self.up = nn.ModuleList()
        self.upsample = nn.ModuleList()
        for cw in reversed(w):
            self.upsample.append(Conv3(c, c))
            self.up.append(nn.ModuleList([ResBlock(c + skips.pop(), cw), ResBlock(cw, cw)]))
            c = cw
        self.final = ResBlock(c + w[0], w[0])
        self.out = nn.Conv2d(w[0], 1, 1)

    def embed(self, class_ids: torch.Tensor, params: torch.Tensor) -> torch.Tensor:
        """class_ids int64 (B, H, W), params float32 (B, P, H, W) -> cond float32 (B, E + P, H, W)."""
        e = self.class_emb(class_ids).permute(0, 3, 1, 2)
        return torch.cat([e, params], 1)

    def blocks(self) -> list:
        """Every ResBlock with its downsampling level (resolution H / 2^level), in the order of the forward pass."""
        n = len(self.widths)
        out = [(blk, i) for i, blocks in enumerate(self.down) for blk in blocks]
        out += [(self.mid[0], n)]
        out += self.deep.blocks(n + 1) if self.deep is not None else []
        out += [(self.mid[1], n)]
        out += [(blk, n - 1 - j) for j, blocks in enumerate(self.up) for blk in blocks]
        return out + [(self.final, 0)]

    def levels(self) -> int:
        """Downsamplings from the input to the deepest block: H and W must be multiples of 2^levels."""
        return len(self.widths) + (self.deep.depth if self.deep is not None else 0)

    def _set_pass(self, tile, like, fold: bool = False) -> None:
        """Set up this pass, in one walk over the modules: every Conv3's padding, zeros (tile None or 0) or
        circular (1 or ``circular``; the string "circular" pads circularly without the zero branch: the export's
        tileable-only graph); and whether ResBlocks and downsamplings run folded (module doc)."""
        if tile is None and self.circular:
            tile = torch.ones(1, device=like.device)
        for m in self.modules():
            if isinstance(m, Conv3):
                m.tile = tile if tile is None or isinstance(tile, str) else tile.reshape(()).to(like.dtype)
            elif isinstance(m, (ResBlock, Downsample)):
                m.fold = fold

    def encode(self, cond, tile=None) -> list:
        """cond (B, E + P, H, W) -> [maps of each ResBlock in :meth:`blocks` order] (see SPADE.maps)."""
        self._set_pass(tile, cond)
        feat = self.cond_mlp(cond)
        H, W = cond.shape[-2:]
        levels = {}
        for _, lvl in self.blocks():
            if lvl not in levels:  # nearest resize by 2^lvl, once per level (Park et al.: F resized to the block)
                levels[lvl] = feat if lvl == 0 else F.interpolate(feat, size=(H >> lvl, W >> lvl), mode="nearest")
        return [blk.spade.maps(levels[lvl]) for blk, lvl in self.blocks()]

    def denoise(self, x, t, maps, tile=None, fold: bool = False):
        """ε from x (B, 1, H, W), t (B,) and :meth:`encode`'s maps; ``fold`` the export's form (module doc)."""
        self._set_pass(tile, x, fold)
        maps = iter(maps)
        temb = self.temb(t)
        h = self.init(x)
        h0 = h
        skips = []
        for blocks, down in zip(self.down, self.downsample):
            for blk in blocks:
                h = blk(h, temb, next(maps))
            skips.append(h)
            h = down(h)
        h = self.mid[0](h, temb, next(maps))
        if self.deep is not None:
            h = h + self.deep(h, temb, maps)
        h = self.mid[1](h, temb, next(maps))
        for blocks, up in zip(self.up, self.upsample):
            h = up(F.interpolate(h, scale_factor=2.0, mode="nearest"))
            h = torch.cat([h, skips.pop()], 1)
            for blk in blocks:
                h = blk(h, temb, next(maps))
        h = self.final(torch.cat([h, h0], 1), temb, next(maps))
        return self.out(h)

    def forward(self, x, t, cond, tile=None):
        """tile: None, or a float tensor (1,) of 0 (zero padding) or 1 (circular: seamless tiles)."""
        return self.denoise(x, t, self.encode(cond, tile), tile)


def set_circular(model: "UNet", on: bool = True) -> "UNet":
    """Make circular padding the default of a torch model: seamless, tileable output (never for training)."""
    model.circular = bool(on)
    return model
