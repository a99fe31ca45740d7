"""Photos as the solid texture's stages read them: float32 RGB, resized by Pillow's bilinear filter.

Shapes: images float (H, W), (H, W, 3) or (H, W, 4) in; float32 (H, W, 3) sRGB values out.
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingError

__all__ = ["rgb_pixels", "resize_rgb", "at_most", "one_colour", "MIN_SIDE"]

MIN_SIDE = 16    #: px a photo's shorter side keeps in :func:`at_most` (all of its own, where it has fewer)


def rgb_pixels(image) -> np.ndarray:
    """An exemplar image (H, W), (H, W, 3) or (H, W, 4) as float32 (H, W, 3); SettingError for other shapes, no
    pixel, or a NaN or infinite value."""
    try:
        img = np.asarray(image, np.float32)
    except (TypeError, ValueError):
        raise SettingError("exemplar", f"expected pixels (H, W), (H, W, 3) or (H, W, 4), got {type(image).__name__}"
                           ) from None
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or 0 in img.shape:
        raise SettingError("exemplar", f"exemplar must be (H, W), (H, W, 3) or (H, W, 4), got {img.shape}")
    img = img[..., :3]
    if not np.all(np.isfinite(img)):
        raise SettingError("exemplar", "the pixels hold NaN or infinite values")
    return img


def one_colour(pixels: np.ndarray) -> bool:
    """Whether every pixel of ``pixels`` (..., 3) is the same colour: nothing varies for a texture to draw."""
    p = np.reshape(pixels, (-1, 3))
    return bool((p == p[0]).all())      # a compare, not a reduction along the pixels (0.13 s, not 0.84, for 12 MP)


def resize_rgb(img: np.ndarray, h: int, w: int) -> np.ndarray:
    """Bilinear resize of a float32 image (H, W, 3) to (h, w, 3), channel by channel (Pillow's float mode)."""
    from PIL import Image

    return np.stack([np.asarray(Image.fromarray(np.ascontiguousarray(img[..., c], np.float32))
                                .resize((w, h), Image.BILINEAR)) for c in range(3)], -1)


def at_most(image, px_per_unit: float, side: int) -> tuple:
    """(image float32 (H', W', 3), its px per unit): a photo over ``side`` px resized to that size, its frequencies
    in texture units unchanged.  A photo whose sides differ more than ``side`` / :data:`MIN_SIDE` times (a strip)
    is first cut to a central window of its longer side, so that its shorter side keeps ``MIN_SIDE`` px (or all of
    its own, where it has fewer): resized whole, it would be a line or nothing."""
    img = rgb_pixels(image)
    short, axis = min(img.shape[:2]), int(img.shape[1] > img.shape[0])
    window = max(side, short * side // max(1, min(short, MIN_SIDE)))
    if img.shape[axis] > window:
        start = (img.shape[axis] - window) // 2
        img = img[start:start + window] if axis == 0 else img[:, start:start + window]
    ppu, W = float(px_per_unit), img.shape[1]
    f = side / max(img.shape[:2])
    if f < 1.0:
        img = resize_rgb(img, max(1, round(img.shape[0] * f)), max(1, round(W * f)))
        ppu *= img.shape[1] / W
    return img, ppu
