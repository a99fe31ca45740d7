"""What the extension's panels and operators share: the backend imported on first use, the sidebar panels'
place, image pixels read from and written to datablocks, and the shipped models' folders.

Cheap to import (``bpy``, numpy and ``backend.paths``); nothing here loads a model or an engine.
"""
from __future__ import annotations

import contextlib
import importlib

import bpy
import numpy as np

from .. import backend
from ..backend import paths

__all__ = ["backend_module", "Sidebar", "image_pixels", "image_colours", "holds_linear", "image_srgb",
           "image_clipped_notes", "measured_reads", "store_srgb_image", "neural_model_folder", "solid_models_folder"]


def backend_module(name: str):
    """A backend submodule (``"neural.model"``, ``"solid.request"``...), imported on first use, so that register()
    stays cheap."""
    return importlib.import_module(f"{backend.__name__}.{name}")


class Sidebar:
    """The OmniNoise tab of an editor's sidebar (N panel); a panel sets its ``bl_space_type`` beside this."""

    bl_region_type = "UI"
    bl_category = "OmniNoise"


def image_pixels(ima, setting: str) -> np.ndarray:
    """An image datablock's pixels as stored, float32 (H, W, C), top row first (Blender keeps rows bottom-up);
    an image without pixels (a missing file, the Render Result), with a NaN or infinite one (a float render's), of
    more than ``export.images.MAX_PIXELS`` pixels or of UDIM tiles is a SettingError naming ``setting``."""
    if ima.type in ("RENDER_RESULT", "COMPOSITING"):      # Blender shows these; their pixels are not readable
        raise backend.SettingError(setting, f"image {ima.name!r} is Blender's render view, whose pixels scripts "
                                            "cannot read: save it (Image > Save As) and open the saved file")
    from ..export import images

    if ima.source == "TILED":       # its pixels are the first tile's alone
        raise backend.SettingError(setting, f"image {ima.name!r} is a UDIM tiled image; pick the image of one tile")
    w, h = ima.size
    if w * h == 0:
        raise backend.SettingError(setting, f"image {ima.name!r} has no pixels (is its file missing?)")
    if w * h > images.MAX_PIXELS:     # as an image file is refused
        raise backend.SettingError(setting, f"image {ima.name!r} is {w}x{h} px, more than the {images.MAX_PIXELS} px "
                                            "an input may have")
    px = np.empty(w * h * ima.channels, np.float32)
    ima.pixels.foreach_get(px)
    if not np.isfinite(px).all():
        raise backend.SettingError(setting, f"image {ima.name!r} holds NaN or infinite values")
    return np.flipud(px.reshape(h, w, ima.channels))


#: the image file formats that store floats; Blender reads the others (a 16-bit PNG or TIFF) into float pixels too
FLOAT_FILES = ("OPEN_EXR", "OPEN_EXR_MULTILAYER", "HDR")


def holds_linear(ima) -> bool:
    """Whether an image datablock's colours are scene-linear, as a float file's are (an EXR, an HDR, a float image
    made or painted in Blender), not an integer file's stored values (8 or 16 bits: the command line reads those as
    they are, sRGB-encoded)."""
    return ima.is_float and not (ima.source in ("FILE", "SEQUENCE", "MOVIE") and ima.file_format not in FLOAT_FILES)


def image_colours(ima, setting: str) -> np.ndarray:
    """An input image datablock's colour channels, float32 (H, W, 1 or 3), top row first, as the command line reads
    its file (``export.decode``): an integer file's stored values over their range (Blender reads a 16-bit PNG or
    TIFF into floats linearised from the image's colour space, unless that is Non-Color: they are encoded again), a
    float file's scene-linear values (:func:`holds_linear`).  Its alpha must be opaque everywhere
    (:func:`export.opaque`; a SettingError naming ``setting``) unless the image's Alpha is set to None."""
    from .. import export

    px = image_pixels(ima, setting)
    if ima.alpha_mode == "NONE" and px.shape[2] in (2, 4):
        px = px[..., :-1]
    else:
        try:
            px = export.opaque(px, f"image {ima.name!r}")
        except export.ImageError as exc:
            raise backend.SettingError(setting, str(exc)) from None
    if ima.is_float and not holds_linear(ima):
        if not ima.colorspace_settings.is_data:             # sRGB's inverse: the stored values within 1e-5
            px = export.linear_to_srgb(px)
        stored = _stored(ima, px)
        if stored is not None:
            px = stored
    return px


#: how far a file's decoded colours may be from Blender's pixels of it (sRGB's inverse) and still be taken for them
STORED_TOLERANCE = 1e-4


def _stored(ima, px: np.ndarray):
    """The colours of an integer file Blender read into floats, as the command line decodes them (to the bit), where
    the image still holds that file (not painted, not packed) and they are Blender's pixels ``px`` (H, W, 1 or 3)
    within :data:`STORED_TOLERANCE` (a colour space Blender read it in other than sRGB, or an EXIF turn, shows
    another picture: Blender's stands); else None."""
    if ima.source != "FILE" or ima.packed_file is not None or ima.is_dirty:
        return None
    from .. import export

    path = bpy.path.abspath(ima.filepath, library=ima.library)
    try:
        a, linear = export.images.decode_kind(path)
    except (OSError, export.ImageError):
        return None
    if a.shape[2] in (2, 4):          # its alpha: opaque, or set aside (Alpha None), as Blender's pixels' was
        a = a[..., :-1]
    if a.shape[2] == 1 and px.shape[2] == 3:          # Blender holds a grey file as RGB
        a = np.repeat(a, 3, axis=2)
    same = not linear and a.shape == px.shape and float(np.abs(a - px).max()) <= STORED_TOLERANCE
    return a if same else None


def image_srgb(ima, setting: str) -> np.ndarray:
    """An input image datablock as sRGB-encoded RGB, float32 (H, W, 3), top row first (:func:`image_colours`):
    scene-linear colours (:func:`holds_linear`) are encoded; grey images are repeated into three channels."""
    px = image_colours(ima, setting)
    rgb = px if px.shape[2] == 3 else np.repeat(px[..., :1], 3, axis=2)
    if holds_linear(ima):
        from .. import export

        if _MEASURED:
            _MEASURED[-1][ima.as_pointer()] = export.images.outside_shares(px)
        rgb = export.linear_to_srgb(rgb)
    return np.ascontiguousarray(rgb, np.float32)


#: the blocks of :func:`measured_reads` open now, innermost last
_MEASURED: list = []


@contextlib.contextmanager
def measured_reads():
    """``with measured_reads() as shares:`` -- {image pointer: (share past white, share under black)} of the float
    images :func:`image_srgb` reads inside the block, for :func:`image_clipped_notes` to take in place of reading the
    pixels a second time on the main thread (about 1 s for a 4096^2 float image)."""
    shares = {}
    _MEASURED.append(shares)
    try:
        yield shares
    finally:
        _MEASURED.remove(shares)


def image_clipped_notes(ima, shares: tuple | None = None) -> list[str]:
    """What the artist is told of a float image read as colours in [0, 1] (:func:`image_srgb`): how much of it is
    past white or under black (``export.images.clipped_text``), as the command line's notes say; none for an 8- or
    16-bit image (:func:`holds_linear`). Blender's default view (AgX) shows values above 1 as bright colours, not
    as the white they are read as; ``shares``: those a read of it measured (:func:`measured_reads`), else it is
    read."""
    if not holds_linear(ima):
        return []
    from ..export import images

    return images.clipped_text(*(shares or images.outside_shares(image_colours(ima, "image"))))


def store_srgb_image(name: str, rgb: np.ndarray):
    """An 8-bit sRGB image datablock ``name`` (replaced if its size or kind differs, packed into the .blend)
    holding ``rgb`` (H, W, 3) sRGB values in [0, 1], row 0 at the bottom."""
    H, W, _ = rgb.shape
    ima = bpy.data.images.get(name)
    if ima is None or tuple(ima.size) != (W, H) or ima.is_float:
        if ima is not None:
            bpy.data.images.remove(ima)
        ima = bpy.data.images.new(name, W, H, alpha=False)
    ima.colorspace_settings.name = "sRGB"
    rgba = np.ones((H, W, 4), np.float32)
    rgba[..., :3] = np.round(np.clip(rgb, 0.0, 1.0) * 255.0) / 255.0
    ima.pixels.foreach_set(rgba.ravel())
    ima.update()
    ima.pack()
    return ima


def neural_model_folder() -> str:
    """The shipped neural noise model (``OMNINOISE_MODELS`` overrides the package's ``models`` folder)."""
    return paths.neural_model()


def solid_models_folder() -> str:
    """The folder of the shipped solid texture models, one subfolder each."""
    return paths.solid_models()
