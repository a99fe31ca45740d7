"""Neural noise images from a conditioning grid: a sampler of :mod:`.sampler` over the ONNX model.

Any size: the network needs sides that are multiples of ``model.multiple_of``;
other sizes are generated on the next larger such grid (the conditioning grid
padded by edge replication) and cropped.  Tileable output uses the circular-
padding network and needs sides that are multiples already (a crop would
break the wrap).  The seed fully determines the output.

Large images are denoised in overlapping tiles (:mod:`.tiles`), which bounds
memory.  By default (``tile=None``) images up to ``AUTO_WHOLE`` px a side are made
in one piece (the encoder's maps take about 2080·H·W bytes: 2.2 GB at 1024²) and
larger ones in tiles of ``AUTO_TILE`` px; the encoder's maps are kept for every
tile while they fit ``MAP_CACHE_BYTES``, else recomputed at each step.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .. import limits
from ..errors import SettingError
from .sampler import (DEFAULT_SAMPLER, DEFAULT_SPACING, DEFAULT_STEPS, SAMPLERS, initial_noise, sample, sampler_eta,
                      step_noise_rng)
from .schedule import SPACINGS

__all__ = ["generate", "check_sampler", "image_eps", "auto_tile", "peak_bytes", "check_memory", "AUTO_WHOLE",
           "AUTO_TILE", "DEFAULT_OVERLAP", "MAP_CACHE_BYTES", "PIECE_BYTES", "IMAGE_BYTES"]

_F = np.float32
AUTO_WHOLE = 1024          #: with tile=None, sides up to this are generated in one piece ...
AUTO_TILE = 512            #: ... and larger images in tiles of this side
DEFAULT_OVERLAP = 64       #: overlap of neighbouring tiles (px)
MAP_CACHE_BYTES = 2 << 30  #: keep the encoder's maps of all tiles while they take at most this


def auto_tile(H: int, W: int) -> int:
    """The tile side ``tile=None`` means for an H x W image (0: one piece)."""
    return 0 if max(H, W) <= AUTO_WHOLE else AUTO_TILE


#: peak bytes per pixel of the piece generated at once (the U-Net's activations; 3.3 K measured from whole 512² and
#: 1024² images) and of the whole image (conditioning, the sampler's state, the tiles' cached encoder maps; 230
#: measured at 2048² and 4096² in 512 px tiles)
PIECE_BYTES, IMAGE_BYTES = 3400, 256


def peak_bytes(H: int, W: int, tile: int | None = None) -> float:
    """About the most memory generating an H x W image takes, in bytes, drawn whole or in tiles of side ``tile``
    (None: :func:`auto_tile`; 0: whole)."""
    t = auto_tile(H, W) if tile is None else tile
    piece = H * W if not t or max(H, W) <= t else min(t, H) * min(t, W)
    return float(piece) * PIECE_BYTES + float(H) * W * IMAGE_BYTES


def check_memory(setting: str, H: int, W: int, tile: int | None = None) -> None:
    """Refuse, naming ``setting``, an image whose :func:`peak_bytes` pass :func:`limits.memory_limit`."""
    limits.check_memory(setting, peak_bytes(H, W, tile), f"a {W} x {H} neural image")


def image_eps(model, cond: np.ndarray, tileable: bool, tile: int, overlap: int = DEFAULT_OVERLAP):
    """The model(x, t, cond) callable for a (1, C, H, W) conditioning grid whose sides are multiples of
    ``model.multiple_of``: one piece when no side exceeds ``tile`` (or tile is 0), else overlapping tiles
    whose encoder maps are kept while they fit MAP_CACHE_BYTES.  Returns (eps, tiles, maps_cached)."""
    H, W = cond.shape[-2:]
    if not tile or max(H, W) <= tile:
        return model.eps_fn(tileable), 1, True
    from .tiles import map_bytes, plan, tiled_eps

    k = model.multiple_of
    if tileable and min(H, W) <= tile:  # every tile must be smaller than the torus it wraps around
        tile = (min(H, W) - 1) // k * k
        overlap = min(overlap, tile // 2 // k * k)
    count = len(plan(H, W, tile, overlap, tileable))
    cache = count * map_bytes(model, min(tile, H), min(tile, W)) <= MAP_CACHE_BYTES
    return tiled_eps(model, cond, tile, overlap, tileable, cache), count, cache


def check_sampler(sampler: str, steps: int, spacing: str | None = None, eta: float | None = 0.0) -> None:
    """SettingError naming the first bad sampler setting (spacing and eta None: the sampler's defaults)."""
    if sampler not in SAMPLERS:
        raise SettingError("sampler", f"unknown sampler {sampler!r}; choose one of {', '.join(SAMPLERS)}")
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or not 1 <= steps <= 1000:
        raise SettingError("steps", f"must be a whole number in [1, 1000], got {steps!r}")
    if sampler == "heun" and steps < 2:
        raise SettingError("steps", "heun needs at least 2 steps")
    if spacing is not None and spacing not in SPACINGS:
        raise SettingError("spacing", f"unknown spacing {spacing!r}; choose one of {', '.join(SPACINGS)}")
    if eta is None:
        return
    if not (np.isfinite(eta) and 0.0 <= eta <= 1.0):
        raise SettingError("eta", f"must lie in [0, 1], got {eta!r}")
    if eta and sampler not in ("ddim", "dpmpp_2m"):
        raise SettingError("eta", f"eta > 0 is a DDIM or DPM-Solver++(2M) setting; {sampler} is deterministic")


def generate(model, cond: np.ndarray, seed: int = 0, steps: int = DEFAULT_STEPS, tileable: bool = False,
             callback: Callable[[int, int, np.ndarray], None] | None = None, sampler: str = DEFAULT_SAMPLER,
             spacing: str | None = None, eta: float | None = None, tile: int | None = None,
             overlap: int = DEFAULT_OVERLAP, x_T: np.ndarray | None = None) -> np.ndarray:
    """cond float32 (E + P, H, W) -> image float32 (H, W) in [0, 1].

    ``x_T``: the initial latent float32 (H', W') with H', W' the sides rounded up to the model's multiple
    (default: ``initial_noise(seed)``); animation passes latents that move smoothly between frames.

    ``steps`` timesteps of ``sampler`` (see :data:`backend.neural.sampler.SAMPLERS`) on the
    model's own schedule (its JSON), spaced by ``spacing`` (None: the sampler's DEFAULT_SPACING), with step
    noise ``eta`` (None: the sampler's DEFAULT_ETA; the noise is drawn from ``step_noise_rng(seed)``);
    callback(i, n, x̂₀) after each of the n model evaluations.
    Sides above ``tile`` px are denoised in tiles overlapping by ``overlap`` px (0: never tile;
    None: :func:`auto_tile`).
    """
    cond = np.asarray(cond, _F)
    C, H, W = cond.shape
    want = model.embedding.shape[1] + len(model.params)
    if C != want:
        raise SettingError("conditioning", f"expected {want} channels, got {C}")
    check_sampler(sampler, steps, spacing, eta)
    spacing = DEFAULT_SPACING[sampler] if spacing is None else spacing
    eta = sampler_eta(sampler, eta)
    k = model.multiple_of
    if tileable and (H % k or W % k):
        raise SettingError("size", f"tileable output needs sides that are multiples of {k}, got {W}x{H}")
    Hp, Wp = -(-H // k) * k, -(-W // k) * k
    if (Hp, Wp) != (H, W):
        cond = np.pad(cond, ((0, 0), (0, Hp - H), (0, Wp - W)), mode="edge")
    if tile is None:
        tile = auto_tile(Hp, Wp)
    if tile and (tile % k or tile < 4 * k):
        raise SettingError("tile", f"must be 0 (never tile) or a multiple of {k} of at least {4 * k} px, got {tile}")
    if tile and (not 0 <= overlap <= tile // 2 or overlap % k):
        raise SettingError("tile", f"{tile} px tiles are too small for their {overlap} px overlap (at most half a "
                                   f"tile): use tiles of at least {max(4 * k, 2 * overlap)} px")
    kw = dict(eta=eta, rng=step_noise_rng(seed)) if eta else {}
    eps, _, _ = image_eps(model, cond[None], tileable, tile, overlap)
    if x_T is None:
        x_T = initial_noise(seed, (1, 1, Hp, Wp))
    else:
        x_T = np.asarray(x_T, _F)
        if x_T.shape != (Hp, Wp):
            raise SettingError("x_T", f"the initial latent must be {Wp}x{Hp} for a {W}x{H} image, got {x_T.shape}")
        x_T = x_T[None, None]
    x0 = sample(sampler, eps, x_T, cond[None], steps,
                callback=callback, alphas_cumprod=model.alphas_cumprod, spacing=spacing, **kw)
    return np.clip((x0[0, 0, :H, :W] + 1.0) * 0.5, 0.0, 1.0).astype(_F)
