"""Image and array writers (PNG, EXR, .npy) and a reader for exemplar images.

Arrays are float32 (H, W) grayscale or (H, W, C) with C in {1, 3, 4}; row 0 is
the top of the image.
"""
from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from .atomic import atomic_path

__all__ = ["write_npy", "write_png", "write_exr", "write_image", "read_image", "preview_8bit"]


def write_npy(path: str, array: np.ndarray) -> None:
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.save(fh, np.ascontiguousarray(array, dtype=np.float32))


def preview_8bit(array: np.ndarray, lo: float | None = None, hi: float | None = None) -> np.ndarray:
    """Map floats to uint8: [lo, hi] (default: 0.5th..99.5th percentile) -> [0, 255]."""
    a = np.asarray(array, dtype=np.float32)
    if lo is None or hi is None:
        plo, phi = np.percentile(a, [0.5, 99.5])
        lo = plo if lo is None else lo
        hi = phi if hi is None else hi
    scale = 1.0 / (hi - lo) if hi > lo else 0.0
    return (np.clip((a - lo) * scale, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def write_png(path: str, array: np.ndarray) -> None:
    """Write uint8 (H, W) or (H, W, 3|4) as PNG (zlib, no dependencies)."""
    a = np.asarray(array)
    if a.dtype != np.uint8:
        raise TypeError("write_png expects uint8; use preview_8bit for floats")
    if a.ndim == 2:
        a = a[:, :, None]
    h, w, c = a.shape
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    raw = b"".join(b"\x00" + a[y].tobytes() for y in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(png)


def write_exr(path: str, array: np.ndarray, half: bool = False, channels: str | None = None) -> None:
    """Write float (H, W) or (H, W, C) as a scanline EXR through OpenEXR.

    channels: names, default 'Y' for one channel, 'RGB' / 'RGBA' for 3 / 4.
    half: store 16-bit half floats instead of 32-bit floats.
    """
    import OpenEXR

    a = np.asarray(array, dtype=np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    c = a.shape[2]
    names = channels or {1: "Y", 3: "RGB", 4: "RGBA"}.get(c)
    if names is None or len(names) != c:
        raise ValueError(f"cannot name {c} channels; pass channels=")
    dtype = np.float16 if half else np.float32
    chans = {n: np.ascontiguousarray(a[:, :, i].astype(dtype)) for i, n in enumerate(names)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with atomic_path(path) as tmp:
        with OpenEXR.File(header, chans) as f:
            f.write(tmp)


def write_image(path: str, array: np.ndarray) -> None:
    """Dispatch on extension: .npy raw float32, .exr float image, .png 8-bit preview."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npy":
        write_npy(path, array)
    elif ext == ".exr":
        write_exr(path, array)
    elif ext == ".png":
        write_png(path, preview_8bit(array))
    else:
        raise ValueError(f"unsupported output type {ext!r} (use .npy, .exr or .png)")


def read_image(path: str) -> np.ndarray:
    """Read an image as float32 grayscale (H, W) in [0, 1] (.npy, .exr or any Pillow format)."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"image not found: {path}")
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npy":
        a = np.load(path).astype(np.float32)
    elif ext == ".exr":
        import OpenEXR

        with OpenEXR.File(path) as f:
            chans = f.channels()
            key = "Y" if "Y" in chans else ("RGB" if "RGB" in chans else next(iter(chans)))
            a = np.asarray(chans[key].pixels, dtype=np.float32)
    else:
        from PIL import Image

        with Image.open(path) as im:
            a = np.asarray(im.convert("F"), dtype=np.float32) / 255.0
    if a.ndim == 3:
        a = a[..., :3].mean(axis=2)
    return a
