"""Extension preferences: CPU threads for bakes, the neural denoiser's precision, the cache folder, and the
shipped asset library (added to Blender's asset libraries with one click, as Blender leaves the user's
preferences to the user).

The cache defaults to Blender's per-extension user folder
(``bpy.utils.extension_path_user``), never the extension's own folder; where a
script registered the installed Python package instead, to the user's cache
folder (:func:`user_cache`), which outlives the Blender session as that one does.
"""
from __future__ import annotations

import os
import sys

import bpy
from bpy.props import EnumProperty, IntProperty, StringProperty

#: the package above this one: the extension's (``bl_ext.<repo>.omninoise``) when Blender loaded it as an extension,
#: ``omninoise`` when a script registered the installed Python package (``omninoise.register()``)
ROOT_PACKAGE = (__package__ or "").rpartition(".")[0]


def user_cache() -> str:
    """The user's cache folder for OmniNoise outside Blender's extension folders: ``%LOCALAPPDATA%\\omninoise``
    on Windows, ``~/Library/Caches/omninoise`` on macOS, ``$XDG_CACHE_HOME/omninoise`` (``~/.cache``) elsewhere."""
    home = os.path.expanduser("~")
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or os.path.join(home, "AppData", "Local")
    elif sys.platform == "darwin":
        base = os.path.join(home, "Library", "Caches")
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(home, ".cache")
    return os.path.join(base, "omninoise")


def cache_dir() -> str:
    """The folder bakes and previews cache into (created on first use)."""
    prefs = get()
    path = prefs.cache_dir if prefs is not None and prefs.cache_dir else ""
    if not path:
        if ROOT_PACKAGE.startswith("bl_ext."):     # Blender keeps an extension's user files for it
            path = bpy.utils.extension_path_user(ROOT_PACKAGE, path="cache", create=True)
        else:
            path = user_cache()
    os.makedirs(path, exist_ok=True)
    return path


def threads() -> int:
    """The CPU Threads preference, at most the CPUs this machine gives Blender (0: all of them): preferences
    travel between machines, and more threads than CPUs wait on each other (``backend.limits.threads``)."""
    from ..backend.limits import cpus

    prefs = get()
    return min(prefs.threads, cpus()) if prefs is not None and prefs.threads > 0 else cpus()


def precision() -> str:
    """The neural noise denoiser's arithmetic: "fp32" or "int8" (see backend/neural/precision.py)."""
    prefs = get()
    return prefs.neural_precision if prefs is not None else "fp32"


#: the folder of the shipped asset library (materials and node groups, ``tools/make_assets.py``)
ASSETS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "assets")
LIBRARY_NAME = "OmniNoise"


def asset_library():
    """The entry of Blender's asset libraries that points at the shipped assets, or None."""
    for lib in bpy.context.preferences.filepaths.asset_libraries:
        if os.path.normcase(os.path.normpath(bpy.path.abspath(lib.path))) == os.path.normcase(os.path.normpath(ASSETS)):
            return lib
    return None


class OMNINOISE_OT_asset_library_add(bpy.types.Operator):
    """List OmniNoise's ready materials and node groups in the Asset Browser (an asset library named OmniNoise,
    dragged assets are appended)"""

    bl_idname = "omninoise.asset_library_add"
    bl_label = "Add OmniNoise Asset Library"
    bl_options = {"REGISTER", "INTERNAL"}

    def execute(self, context):
        if asset_library() is not None:
            self.report({"INFO"}, "the OmniNoise asset library is already listed")
            return {"FINISHED"}
        if not os.path.isfile(os.path.join(ASSETS, "omninoise_assets.blend")):
            self.report({"ERROR"}, f"no assets in {ASSETS}: reinstall the extension")
            return {"CANCELLED"}
        lib = context.preferences.filepaths.asset_libraries.new(name=LIBRARY_NAME, directory=ASSETS)
        try:                                    # a dragged material is the artist's own copy
            lib.import_method = "APPEND_REUSE"  # reusing what an earlier drag appended (before Blender 5.0)
        except TypeError:
            lib.import_method = "APPEND"
        context.preferences.is_dirty = True
        return {"FINISHED"}


class OMNINOISE_OT_asset_library_remove(bpy.types.Operator):
    """Take OmniNoise's asset library out of the Asset Browser (what was appended stays in your files)"""

    bl_idname = "omninoise.asset_library_remove"
    bl_label = "Remove OmniNoise Asset Library"
    bl_options = {"REGISTER", "INTERNAL"}

    def execute(self, context):
        lib = asset_library()
        if lib is not None:
            context.preferences.filepaths.asset_libraries.remove(lib)
            context.preferences.is_dirty = True
        return {"FINISHED"}


def get():
    if not ROOT_PACKAGE:
        return None
    addon = bpy.context.preferences.addons.get(ROOT_PACKAGE)
    return addon.preferences if addon is not None else None


class OMNINOISE_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = ROOT_PACKAGE or "omninoise"

    threads: IntProperty(name="CPU Threads", default=0, min=0, max=256,
                         description="Threads for bakes (0 = all cores; more than this machine has are read as all "
                                     "of them)")
    neural_precision: EnumProperty(
        name="Neural Precision", default="fp32",
        description="Arithmetic of the neural noise denoiser",
        items=[("fp32", "Float32", "Full precision: the reference images"),
               ("int8", "int8 (Draft)", "Quantized convolutions: about 1.8x faster steps on CPUs with int8 dot "
                                        "products (VNNI), images slightly different from the reference")])
    cache_dir: StringProperty(name="Cache Folder", subtype="DIR_PATH", default="",
                              description="Where bakes and previews are cached (empty = Blender's "
                                          "extension user folder)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "threads")
        layout.prop(self, "neural_precision")
        layout.prop(self, "cache_dir")
        row = layout.row()
        if asset_library() is None:
            row.operator(OMNINOISE_OT_asset_library_add.bl_idname, icon="ASSET_MANAGER")
        else:
            row.label(text="Asset library: listed in the Asset Browser as OmniNoise", icon="CHECKMARK")
            row.operator(OMNINOISE_OT_asset_library_remove.bl_idname, text="", icon="X")


#: the preferences exist where the extension is installed as a package (``__package__`` names its root)
classes = (OMNINOISE_OT_asset_library_add, OMNINOISE_OT_asset_library_remove) + \
    ((OMNINOISE_AP_preferences,) if ROOT_PACKAGE else ())
