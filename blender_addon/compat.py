"""Differences between the Blender versions OmniNoise supports (4.2 LTS to 5.3), in one place.

Every version check of the Blender layer lives here, so the rest of the code
asks a question ("which EEVEE engine id?") instead of comparing versions.

    4.2.0    ``bpy.utils.register_preset_path`` is missing (later 4.2 releases have it).
    4.2-4.5  EEVEE is ``BLENDER_EEVEE_NEXT``; add-on properties and ID custom
             properties share one storage (a custom key must not equal the name
             of a registered property); materials and worlds get a node tree
             only after ``use_nodes = True``; the OpenVDB Python module is
             ``pyopenvdb`` in Blender 4.2-4.3 and ``openvdb`` from 4.4.
    4.3      Blender's Gabor Texture node appears.
    5.0      EEVEE is ``BLENDER_EEVEE`` again; ``use_nodes`` is deprecated (always on);
             image formats have ``media_type``.
    5.1      Python 3.13 (the extension zips carry cp311 and cp313 wheels).
"""
from __future__ import annotations

import bpy

__all__ = ["VERSION", "reads_extension_presets", "eevee_engine", "has_gabor_node", "ensure_node_tree",
           "set_multilayer_exr", "id_property"]

VERSION: tuple = tuple(bpy.app.version[:2])


def reads_extension_presets() -> bool:
    """Whether Blender reads presets from an extension's own folder (``bpy.utils.register_preset_path``; not 4.2.0)."""
    return hasattr(bpy.utils, "register_preset_path")


def eevee_engine() -> str:
    """The render engine id of EEVEE in this Blender."""
    return "BLENDER_EEVEE_NEXT" if VERSION < (5, 0) else "BLENDER_EEVEE"


def has_gabor_node() -> bool:
    """Blender's Gabor Texture shader node (ShaderNodeTexGabor) exists from 4.3."""
    return VERSION >= (4, 3)


def ensure_node_tree(idblock):
    """The node tree of a material or world, enabling nodes where the version needs it (before 5.0)."""
    if idblock.node_tree is None or (VERSION < (5, 0) and not idblock.use_nodes):
        idblock.use_nodes = True
    return idblock.node_tree


def set_multilayer_exr(image_settings) -> None:
    """Image output settings -> OpenEXR multilayer (5.0 names the media type first)."""
    if hasattr(image_settings, "media_type"):
        image_settings.media_type = "MULTI_LAYER_IMAGE"
    image_settings.file_format = "OPEN_EXR_MULTILAYER"


def id_property(idblock, key: str, *legacy: str):
    """A string custom property of ``idblock`` by ``key``, else the first ``legacy`` key holding a string.

    Legacy keys let files saved by older OmniNoise versions load; a legacy key that
    names a registered property holds that property's group before 5.0, not a string.
    """
    for k in (key,) + legacy:
        v = idblock.get(k)
        if isinstance(v, str) and v:
            return v
    return None

