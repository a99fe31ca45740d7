"""Image and array writers (PNG, EXR, .npy) and a reader for exemplar images.

Arrays are float32 (H, W) grayscale or (H, W, C) with C in {1, 3, 4}; row 0 is
the top of the image.
"""
from __future__ import annotations

import os
import re
import struct
import sys
import zlib

import numpy as np

from .atomic import atomic_path, require_finite

__all__ = ["ImageError", "decode", "MAX_PIXELS", "write_npy", "write_png", "write_exr", "write_image",
           "write_unit_image", "read_image", "read_rgb", "outside_unit", "outside_shares", "clipped_notes",
           "clipped_text", "opaque", "preview_8bit", "read_metadata", "encode_srgb8", "linear_to_srgb"]


def write_npy(path: str, array: np.ndarray) -> None:
    require_finite(array, path)
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


#: values encode_srgb8 converts at a time: its float temporaries stay a few MiB whatever the image's size
_ENCODE_BLOCK = 1 << 18


def encode_srgb8(linear: np.ndarray) -> np.ndarray:
    """Scene-linear float (..., C) -> sRGB-encoded uint8; a 4th (alpha) channel stays linear.  Rows are encoded a
    block at a time, so that the float temporaries of a large image (several times its size) are never held."""
    a = np.asarray(linear)
    if a.ndim == 0:
        return encode_srgb8(a[None])[0]
    out = np.empty(a.shape, np.uint8)
    rows = max(1, _ENCODE_BLOCK // max(1, a[:1].size))
    for i in range(0, a.shape[0], rows):
        block = np.clip(np.asarray(a[i: i + rows], np.float32), 0.0, 1.0)
        c = block[..., :3] if block.ndim == 3 and block.shape[-1] >= 3 else block
        c[...] = linear_to_srgb(c)
        out[i: i + rows] = block * 255.0 + 0.5
    return out


def _text_chunk(key: str, value: str) -> tuple:
    """A PNG text chunk's (tag, data) of ``key`` (Latin-1) and ``value``: tEXt where the value is Latin-1 (the text
    every reader reads), else iTXt's uncompressed UTF-8 (PNG specification 11.3.4.3 and 11.3.4.5), for a bake named
    in any script."""
    try:
        return b"tEXt", key.encode("latin-1") + b"\0" + value.encode("latin-1")
    except UnicodeEncodeError:      # iTXt: keyword, 0, compression flag and method 0, no language, no translation
        return b"iTXt", key.encode("latin-1") + b"\0\0\0\0\0" + value.encode("utf-8")


def write_png(path: str, array: np.ndarray, metadata: dict | None = None) -> None:
    """Write uint8 or uint16 (H, W) or (H, W, 2|3|4) as an 8- or 16-bit PNG (zlib, no dependencies); metadata ->
    text chunks (keys Latin-1, values any text)."""
    a = np.asarray(array)
    if a.dtype not in (np.uint8, np.uint16):
        raise TypeError("write_png expects uint8 or uint16; use preview_8bit for floats")
    if a.ndim == 2:
        a = a[:, :, None]
    h, w, c = a.shape
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    depth = 8 * a.dtype.itemsize
    deflate = zlib.compressobj(6)       # row by row: the filtered rows are never held whole beside the image
    idat = [deflate.compress(b"\x00" + (a[y].astype(">u2") if depth == 16 else a[y]).tobytes()) for y in range(h)]
    idat.append(deflate.flush())         # PNG's samples are big-endian; filter type 0 on every row

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0))
           + b"".join(chunk(*_text_chunk(str(k), str(v))) for k, v in (metadata or {}).items())
           + chunk(b"IDAT", b"".join(idat)) + chunk(b"IEND", b""))
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
    require_finite(a, path, half)
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
        require_finite(array, path)       # the writers of .npy and .exr check their own; the preview maps NaN away
        write_png(path, preview_8bit(array))
    else:
        raise ValueError(f"unsupported output type {ext!r} (use .npy, .exr or .png)")


def write_unit_image(path: str, img: np.ndarray, linear: np.ndarray | None = None) -> None:
    """An image whose values lie in [0, 1] (neural noise; sRGB colours): .png 8-bit as they are, without the
    percentile stretch of :func:`write_image`; .exr and .npy float: ``linear`` where given (a colour image's
    scene-linear values), else ``img``."""
    if os.path.splitext(path)[1].lower() == ".png":
        require_finite(img, path)
        write_png(path, preview_8bit(img, 0.0, 1.0))
    else:
        write_image(path, img if linear is None else linear)


MAX_PIXELS = 1 << 27          #: largest image any input reads (about 11585 x 11585; below Pillow's own bomb limit)


class ImageError(ValueError):
    """An input image that cannot be used; the message is one line naming the file."""


def decode(path: str) -> np.ndarray:
    """The one reader of every image input: float32 (H, W, C) with C in 1..4, values by the file's own range.

    8-bit files and uint8 arrays are divided by 255, 16-bit ones by 65535 (a
    16-bit mask is not read as nearly white), float files (.exr, float TIFF,
    .npy) and other arrays are kept as they are.  A file with an EXIF
    orientation (a phone photo taken upright) is turned as image viewers show
    it, so a brick photo's courses stay level
    (Blender's own images are read as Blender shows them).  Empty, truncated,
    non-image, non-finite and oversized (> MAX_PIXELS, 2^27) files raise
    :class:`ImageError`; a missing one FileNotFoundError.
    """
    return _decode(path)[0]


def decode_kind(path: str) -> tuple:
    """(:func:`decode`'s pixels, whether the file stores scene-linear floats: EXR, float TIFF, float .npy)."""
    return _decode(path)


def _decode(path: str) -> tuple:
    """(:func:`decode`'s pixels, whether the file stores floats: scene-linear values by the convention of EXR,
    float TIFF and float .npy, as Blender reads a float image, where 8- and 16-bit files store display values)."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"image not found: {path}")
    if os.path.getsize(path) == 0:
        raise ImageError(f"{path}: empty file")
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext == ".npy":
            a = np.load(path, allow_pickle=False)
            if a.dtype.kind not in "fiub":
                raise ImageError(f"{path}: a .npy image must hold numbers, got {a.dtype}")
            if a.dtype.kind in "iu" and a.dtype not in (np.uint8, np.uint16):     # 0..255 in int64 would clip white
                raise ImageError(f"{path}: a .npy image of {a.dtype} has no range; save it as uint8 (0 to 255), "
                                 "uint16 (0 to 65535) or floats")
            linear = a.dtype.kind == "f"
            scale = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}.get(a.dtype, 1.0)
            with np.errstate(over="ignore"):                 # a float64 past float32's range is refused below
                a = a.astype(np.float32) / np.float32(scale)     # 8- and 16-bit arrays as 8- and 16-bit files
        elif ext == ".exr":
            import OpenEXR

            with OpenEXR.File(path) as f:
                if len(f.parts) > 1:     # a renderer's passes, one a part: which is the picture?
                    raise ImageError(f"{path}: an EXR image must be one part, not {len(f.parts)} ("
                                     f"{', '.join(p.name() or '(unnamed)' for p in f.parts)}); save the picture's "
                                     "part as an EXR of its own")
                chans = f.channels()
                key = next((k for k in ("Y", "RGBA", "RGB") if k in chans), next(iter(chans)) if len(chans) == 1
                           else None)
                if key is None:     # an alpha, a depth or a render layer's colours: which is the picture?
                    raise ImageError(f"{path}: an EXR image must hold RGB, RGBA, Y or one channel, not "
                                     f"{', '.join(sorted(chans))}; save the picture's layer as an RGB(A) EXR")
                a = np.asarray(chans[key].pixels, dtype=np.float32)
            linear = True
        else:
            a, linear = _decode_pillow(path)
    except ImageError:
        raise
    except (OSError, ValueError, EOFError, SyntaxError, MemoryError, RuntimeError) as exc:  # OpenEXR: RuntimeError
        raise ImageError(f"{path}: cannot read the image ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") \
            from None
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[2] > 4 or 0 in a.shape:
        raise ImageError(f"{path}: expected an image (H, W) or (H, W, 1..4), got shape {a.shape}")
    if a.shape[0] * a.shape[1] > MAX_PIXELS:
        raise ImageError(f"{path}: {a.shape[1]}x{a.shape[0]} px is more than the {MAX_PIXELS} px an input may have")
    if not np.all(np.isfinite(a)):
        raise ImageError(f"{path}: the image holds NaN or infinite values")
    return a, linear


_EXIF_ORIENTATION = 0x0112   #: EXIF tag: 1 upright, 2-8 mirrored and/or turned (cameras store the sensor's rows)
#: the stored pixels (H, W[, C]) of each EXIF orientation as viewers show them (Pillow's ``ImageOps.exif_transpose``)
_TURNS = {1: lambda a: a, 2: lambda a: a[:, ::-1], 3: lambda a: a[::-1, ::-1], 4: lambda a: a[::-1],
          5: lambda a: np.swapaxes(a, 0, 1), 6: lambda a: np.rot90(a, -1),
          7: lambda a: np.swapaxes(a, 0, 1)[::-1, ::-1], 8: lambda a: np.rot90(a, 1)}


#: Pillow's raw modes of unsigned 32-bit samples, which it opens as signed 32-bit integers (mode "I")
_UNSIGNED_32 = ("I;32", "I;32L", "I;32B", "I;32N")


def _pillow_pixels(im, raw: str | None) -> tuple:
    """(pixels float32 (H, W[, C]) by the file's own range, whether they are floats) of an image Pillow loaded;
    ``raw`` the raw mode its tiles were unpacked by.  Integer samples are divided by their type's largest value, as
    Blender and OpenImageIO read them: 8-bit by 255, 16-bit by 65535, signed 32-bit by 2^31 - 1 (negative values
    are below black) and unsigned 32-bit by 2^32 - 1."""
    mode = im.mode
    if mode in ("I;16", "I;16B", "I;16L", "I;16N"):
        return np.asarray(im, dtype=np.float32) / 65535.0, False
    if mode == "I":        # 32-bit integers; some Pillow versions open 16-bit PNGs so too (raw mode "I;16B")
        a = np.asarray(im, dtype=np.int32)
        if isinstance(raw, str) and raw.startswith("I;16"):
            return a.astype(np.float32) / np.float32(65535.0), False
        if raw in _UNSIGNED_32:
            return (a.view(np.uint32).astype(np.float64) / (2.0 ** 32 - 1)).astype(np.float32), False
        return (a.astype(np.float64) / (2.0 ** 31 - 1)).astype(np.float32), False
    if mode == "F":
        return np.asarray(im, dtype=np.float32), True
    if mode not in ("L", "LA", "RGB", "RGBA"):
        im = im.convert("RGBA" if im.has_transparency_data else "RGB")     # "LAB" has no alpha
    return np.asarray(im, dtype=np.float32) / 255.0, False


def _decode_pillow(path: str) -> tuple:
    import warnings

    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as im:
                w, h = im.size
                if w * h > MAX_PIXELS:
                    raise ImageError(f"{path}: {w}x{h} px is more than the {MAX_PIXELS} px an input may have")
                wide = _sixteen_bits(path, list(im.tile))     # 16-bit colour: decoded there, not here
                if wide is not None:
                    (a, orientation), linear = wide, False
                else:
                    raws = {_raw_mode(t) for t in im.tile}
                    im.load()
                    orientation = im.getexif().get(_EXIF_ORIENTATION, 1)
                    a, linear = _pillow_pixels(im, raws.pop() if len(raws) == 1 else None)
                turn = _TURNS.get(orientation, _TURNS[1])
                return np.ascontiguousarray(turn(a)), linear      # a phone photo as every viewer shows it
    except (UnidentifiedImageError, Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        if isinstance(exc, UnidentifiedImageError):
            tiff = os.path.splitext(path)[1].lower() in (".tif", ".tiff")   # Pillow reads one float channel only
            raise ImageError(f"{path}: not an image file this reader knows"
                             + ("; a TIFF of float colours is read as .exr: save it as one" if tiff else "")) from None
        raise ImageError(f"{path}: the image is more than the {MAX_PIXELS} px an input may have") from None


#: Pillow's raw modes of 16-bit colour files that it opens as 8-bit colour ("RGB", "RGBA"): the 16-bit samples'
#: byte order (B big-endian, L little, N this machine's)
_WIDE = re.compile(r"(RGB|RGBA|LA);16([BLN])")


def _raw_mode(tile) -> str | None:
    """The raw mode Pillow unpacks a tile by, where it names one (a GIF's args begin with a number, a WebP has
    none)."""
    args = getattr(tile, "args", None)
    return args if isinstance(args, str) else (args[0] if isinstance(args, tuple) and args else None)


def _sixteen_bits(path: str, tiles: list) -> tuple | None:
    """(samples float32 (H, W, C) in [0, 1], EXIF orientation) of the 16-bit colour PNG or TIFF (RGB, RGBA, grey
    with alpha) at ``path``, from the tiles Pillow opened it with (before loading it); None for any other image.
    Pillow's colour modes hold 8 bits, so it opens such a file as 8-bit colour, each sample's high byte alone: the
    file is decoded twice here, unpacking the high and then the low bytes (its raw mode told the other byte order),
    and the bytes are put together.  Grey with alpha, whose 8-bit raw mode has no such twin, is decoded as 8-bit
    RGBA: the same four bytes a pixel."""
    raws = {_raw_mode(t) for t in tiles}
    mode = raws.pop() if len(raws) == 1 and all(hasattr(t, "_replace") for t in tiles) else None
    match = _WIDE.fullmatch(mode) if isinstance(mode, str) else None
    if match is None:
        return None
    kind, order = match.groups()
    if order == "N":
        order = "L" if sys.byteorder == "little" else "B"

    orientation = []        # the file's, read by the decoding (Pillow reads a PNG's eXIf chunk as it loads)

    def decoded(raw: str) -> np.ndarray:
        from PIL import Image

        with Image.open(path) as again:
            again.tile = [t._replace(args=raw if isinstance(t.args, str) else (raw,) + tuple(t.args[1:]))
                          for t in again.tile]
            again.load()
            orientation.append(again.getexif().get(_EXIF_ORIENTATION, 1))
            return np.asarray(again, dtype=np.uint16)

    if kind == "LA":        # opened as RGBA
        b = decoded("RGBA")
        wide = np.stack([b[..., 0] * 256 + b[..., 1], b[..., 2] * 256 + b[..., 3]], axis=-1)
    else:
        high, low = (f"{kind};16{order}", f"{kind};16{'B' if order == 'L' else 'L'}")
        wide = decoded(high) * 256 + decoded(low)
    return wide.astype(np.float32) / np.float32(65535.0), orientation[0]


OPAQUE = 254.5 / 255.0   #: the least alpha an input's pixel may have (an 8-bit 255; 254 is partly transparent)


def transparency(a: np.ndarray) -> str | None:
    """Why an input image (H, W, C) with alpha (C 2 or 4) cannot be read as opaque colours (the share of its partly
    transparent pixels), or None where it can: what lies under a transparent pixel is no colour of the picture (a
    cutout's is often black, a pixel's edge half its background's)."""
    if a.shape[2] not in (2, 4):
        return None
    clear = float(np.mean(a[..., -1] < OPAQUE))
    if clear == 0.0:
        return None
    return (f"the image is partly transparent (alpha below 1 on {100 * clear:.3g} % of its pixels); inputs are read "
            "as opaque colours: flatten it onto a background or crop it to its opaque part")


def opaque(a: np.ndarray, name: str) -> np.ndarray:
    """The colour channels of an input image (H, W, C), its alpha dropped where it is opaque everywhere; ImageError
    naming ``name`` where it is not (:func:`transparency`)."""
    why = transparency(a)
    if why is not None:
        raise ImageError(f"{name}: {why}")
    return a[..., :-1] if a.shape[2] in (2, 4) else a


def read_image(path: str) -> np.ndarray:
    """Read an image as float32 grayscale (H, W) in the file's own range (.npy, .exr or any Pillow format):
    the mean of its colour channels; an alpha channel must be opaque (:func:`opaque`)."""
    a = opaque(decode(path), path)
    return a.mean(axis=2) if a.shape[2] > 1 else a[..., 0]


def read_rgb(path: str) -> np.ndarray:
    """Read an image file as sRGB-encoded float32 (H, W, 3) in [0, 1], the exemplar format of the solid textures:
    an integer file's stored values over its type's range (8, 16 or 32 bits); a float file's (EXR, float TIFF, float
    .npy) scene-linear values encoded (:func:`linear_to_srgb`, clipped to [0, 1] first), as Blender shows a float
    image; a float file of whole numbers above 1 (8- or 16-bit values stored as floats, which would read as white) is
    refused.  Greyscale is repeated,
    an alpha channel must be opaque (:func:`opaque`)."""
    a, linear = _decode(path)
    a = opaque(a, path)
    if linear and a.max() > 1.0 and np.array_equal(a, np.round(a)):
        raise ImageError(f"{path}: a float image holds scene-linear colour (0 to 1, more only in highlights), but "
                         f"this one holds whole numbers up to {a.max():g}, as 8- or 16-bit pixels do: store them as "
                         "uint8 or uint16, or divided by 255 or 65535")
    if a.shape[2] == 1:
        a = np.repeat(a, 3, axis=2)
    return linear_to_srgb(a) if linear else np.clip(a, 0.0, 1.0)


#: linear values above this, below zero, still encode to an 8-bit 0 (half a step of sRGB's 12.92 slope at black)
BLACK_TOLERANCE = 0.5 / 255 / 12.92


def outside_unit(path: str) -> tuple[float, float]:
    """:func:`outside_shares` of a float image file (EXR, float TIFF, float .npy), as :func:`read_rgb` reads it;
    (0, 0) for an integer file, whose values cannot leave [0, 1]."""
    a, linear = _decode(path)
    return outside_shares(a) if linear else (0.0, 0.0)


def outside_shares(pixels: np.ndarray) -> tuple[float, float]:
    """The shares of the pixels of float (H, W, C) scene-linear colours (an alpha channel aside) with a colour above
    1 and with one below 0, which are read as white and as black: an HDR photo's highlights (or all of an
    overexposed one), and values a processing step pushed under black (those within :data:`BLACK_TOLERANCE` of 0
    are black to begin with)."""
    c = pixels[..., :3] if pixels.shape[2] in (3, 4) else pixels[..., :1]
    return float(np.mean((c > 1.0).any(axis=2))), float(np.mean((c < -BLACK_TOLERANCE).any(axis=2)))


#: the share of a float photo's pixels past white (or under black) from which :func:`clipped_text` says so
CLIPPED_NOTE = 0.01


def clipped_notes(path: str) -> list[str]:
    """What a user is told of a photo file read as colours in [0, 1]: :func:`clipped_text` of its shares past white
    and under black (the command line prints them as notes, the Python API warns); none for an integer file, and
    for anything that is no image file (a shipped texture's name)."""
    floats = os.path.splitext(path)[1].lower() in (".exr", ".npy", ".tif", ".tiff")   # others store integers
    try:
        return clipped_text(*outside_unit(path)) if floats and os.path.isfile(path) else []
    except ImageError:
        return []


def clipped_text(bright: float, dark: float) -> list[str]:
    """The notes on a photo's shares of pixels past white and under black, each where it is :data:`CLIPPED_NOTE`
    or more (the command line's notes, the Python API's warnings, Blender's reports)."""
    notes = []
    if bright >= CLIPPED_NOTE:
        notes.append(f"{100 * bright:.3g} % of the photo's pixels are brighter than white (above 1) and are read as "
                     "white; lower its exposure to keep their colours")
    if dark >= CLIPPED_NOTE:
        notes.append(f"{100 * dark:.3g} % of the photo's pixels are darker than black (below 0) and are read as "
                     "black; raise or offset its values into [0, 1] to keep their colours")
    return notes


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
            elif tag == b"iTXt" and b"\0" in data:
                k, rest = data.split(b"\0", 1)
                parts = rest[2:].split(b"\0", 2)    # language, translated keyword, the text
                if rest[:1] == b"\0" and len(parts) == 3:     # uncompressed
                    out[k.decode("latin-1")] = parts[2].decode("utf-8", "replace")


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
