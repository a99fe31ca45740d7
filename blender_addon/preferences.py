"""Extension preferences: CPU threads for bakes, the neural denoiser's precision and the cache folder.

The cache defaults to Blender's per-extension user folder
(``bpy.utils.extension_path_user``), never the extension's own folder.
"""
from __future__ import annotations

import os

import bpy
from bpy.props import EnumProperty, IntProperty, StringProperty

#: the extension's package (``bl_ext.<repo>.omninoise``); empty when imported as a plain package
ROOT_PACKAGE = (__package__ or "").rpartition(".")[0]


def cache_dir() -> str:
    """The folder bakes and previews cache into (created on first use)."""
    prefs = get()
    path = prefs.cache_dir if prefs is not None and prefs.cache_dir else ""
    if not path:
        if ROOT_PACKAGE:
            path = bpy.utils.extension_path_user(ROOT_PACKAGE, path="cache", create=True)
        else:
            path = os.path.join(bpy.app.tempdir or os.path.expanduser("~"), "omninoise_cache")
    os.makedirs(path, exist_ok=True)
    return path


def threads() -> int:
    prefs = get()
    return prefs.threads if prefs is not None and prefs.threads > 0 else (os.cpu_count() or 1)


def precision() -> str:
    """The neural noise denoiser's arithmetic: "fp32" or "int8" (see backend/neural/precision.py)."""
    prefs = get()
    return prefs.neural_precision if prefs is not None else "fp32"


def get():
    if not ROOT_PACKAGE:
        return None
    addon = bpy.context.preferences.addons.get(ROOT_PACKAGE)
    return addon.preferences if addon is not None else None


class OMNINOISE_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = ROOT_PACKAGE or "omninoise"

    threads: IntProperty(name="CPU Threads", description="Threads for bakes (0 = all cores)",
                         default=0, min=0, max=256)
    neural_precision: EnumProperty(
        name="Neural Precision", default="fp32",
        description="Arithmetic of the neural noise denoiser",
        items=[("fp32", "Float32", "Full precision: the reference images"),
               ("int8", "int8 (Draft)", "Quantized convolutions: about 1.7x faster steps on CPUs with int8 dot "
                                        "products (VNNI), images slightly further from the reference")])
    cache_dir: StringProperty(name="Cache Folder", subtype="DIR_PATH", default="",
                              description="Where bakes and previews are cached (empty = Blender's "
                                          "extension user folder)")

    def draw(self, context):
        self.layout.prop(self, "threads")
        self.layout.prop(self, "neural_precision")
        self.layout.prop(self, "cache_dir")


#: the preferences exist where the extension is installed as a package (``__package__`` names its root)
classes = (OMNINOISE_AP_preferences,) if ROOT_PACKAGE else ()
