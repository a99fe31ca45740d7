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

__all__ = ["write_npy", "write_png", "write_exr", "write_image", "read_image", "read_rgb", "preview_8bit", "read_metadata",
           "encode_srgb8", "linear_to_srgb"]


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


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """Scene-linear values -> sRGB-encoded float32 in [0, 1] (IEC 61966-2-1; clipped to [0, 1] first)."""
    c = np.clip(np.asarray(linear, np.float32), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055).astype(np.float32)


def encode_srgb8(linear: np.ndarray) -> np.ndarray:
    """Scene-linear float (..., C) -> sRGB-encoded uint8; a 4th (alpha) channel stays linear."""
    out = np.clip(np.asarray(linear, np.float32), 0.0, 1.0)
    c = out[..., :3] if out.ndim == 3 and out.shape[-1] >= 3 else out
    c[...] = linear_to_srgb(c)
    return (out * 255.0 + 0.5).astype(np.uint8)


def write_png(path: str, array: np.ndarray, metadata: dict | None = None) -> None:
    """Write uint8 (H, W) or (H, W, 3|4) as PNG (zlib, no dependencies); metadata -> tEXt chunks."""
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
           + b"".join(chunk(b"tEXt", f"{k}".encode("latin-1") + b"\0" + f"{v}".encode("latin-1"))
                      for k, v in (metadata or {}).items())
           + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(png)


def write_exr(path: str, array: np.ndarray, half: bool = False, channels: str | None = None,
              metadata: dict | None = None) -> None:
    """Write float (H, W) or (H, W, C) as a scanline EXR through OpenEXR.

    channels: names, default 'Y' for one channel, 'RGB' / 'RGBA' for 3 / 4.
    half: store 16-bit half floats instead of 32-bit floats.
    metadata: extra string attributes in the header.
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
    header.update({str(k): str(v) for k, v in (metadata or {}).items()})
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


def read_rgb(path: str) -> np.ndarray:
    """Read an 8/16-bit image file as float32 (H, W, 3) in [0, 1], its stored (sRGB) values;
    greyscale is repeated, alpha dropped.  The exemplar format of the solid textures."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"image not found: {path}")
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            return np.asarray(im.convert("RGB"), dtype=np.float32) / 255.0
    except UnidentifiedImageError:
        raise ValueError(f"not an image Pillow can read: {path}") from None


def _png_text(path: str) -> dict:
    out = {}
    with open(path, "rb") as fh:
        if fh.read(8) != b"\x89PNG\r\n\x1a\n":
            return out
        while True:
            head = fh.read(8)
            if len(head) < 8:
                return out
            n, tag = struct.unpack(">I", head[:4])[0], head[4:]
            if tag == b"IDAT" or tag == b"IEND":
                return out
            data = fh.read(n)
            fh.read(4)
            if tag == b"tEXt" and b"\0" in data:
                k, v = data.split(b"\0", 1)
                out[k.decode("latin-1")] = v.decode("latin-1")


def read_metadata(path: str) -> dict:
    """String metadata of an output file (.vdb, .exr, .png); {} if absent or unreadable."""
    if not os.path.isfile(path):
        return {}
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext == ".vdb":
            from .vdb import read_vdb_metadata

            return read_vdb_metadata(path)
        if ext == ".exr":
            import OpenEXR

            with OpenEXR.File(path, header_only=True) as f:
                return {k: v for k, v in f.header().items() if isinstance(v, str)}
        if ext == ".png":
            return _png_text(path)
    except Exception:  # a damaged or foreign file is simply not up to date
        return {}
    return {}
