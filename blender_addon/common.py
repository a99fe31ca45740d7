"""What the extension's panels and operators share: the backend imported on first use, the sidebar panels'
place, image pixels read from and written to datablocks, and the shipped models' folders.

Cheap to import (``bpy``, numpy and ``backend.paths``); nothing here loads a model or an engine.
"""
from __future__ import annotations

import importlib

import bpy
import numpy as np

from .. import backend
from ..backend import paths

__all__ = ["backend_module", "Sidebar", "image_pixels", "image_srgb", "image_clipped_notes", "store_srgb_image",
           "neural_model_folder", "solid_models_folder"]


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


def image_colours(ima, setting: str) -> np.ndarray:
    """An input image datablock's colour channels, float32 (H, W, 1 or 3), top row first: its alpha must be opaque
    everywhere (:func:`export.opaque`; a SettingError naming ``setting``) unless the image's Alpha is set to None."""
    from .. import export

    px = image_pixels(ima, setting)
    if ima.alpha_mode == "NONE" and px.shape[2] in (2, 4):
        return px[..., :-1]
    try:
        return export.opaque(px, f"image {ima.name!r}")
    except export.ImageError as exc:
        raise backend.SettingError(setting, str(exc)) from None


def image_srgb(ima, setting: str) -> np.ndarray:
    """An input image datablock as sRGB-encoded RGB, float32 (H, W, 3), top row first (:func:`image_colours`): float
    images hold scene-linear values and are encoded; grey images are repeated into three channels."""
    px = image_colours(ima, setting)
    rgb = px if px.shape[2] == 3 else np.repeat(px[..., :1], 3, axis=2)
    if ima.is_float:
        from .. import export

        _SHARES[ima.as_pointer()] = export.images.outside_shares(px)
        rgb = export.linear_to_srgb(rgb)
    return np.ascontiguousarray(rgb, np.float32)


#: the shares past white and under black of the float images :func:`image_srgb` read last, by the image's pointer:
#: :func:`image_clipped_notes` takes them (a read after it measures again) in place of reading the pixels a second
#: time on the main thread (about 1 s for a 4096^2 float image)
_SHARES: dict = {}


def image_clipped_notes(ima) -> list[str]:
    """What the artist is told of a float image read as colours in [0, 1] (:func:`image_srgb`): how much of it is
    past white or under black (``export.images.clipped_text``), as the command line's notes say; none for an 8- or
    16-bit image. Blender's default view (AgX) shows values above 1 as bright colours, not as the white they are
    read as; the shares the request's own read of it measured where it made one."""
    if not ima.is_float:
        return []
    from ..export import images

    shares = _SHARES.pop(ima.as_pointer(), None)
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
