"""Presets through Blender's own preset system: the preset menu with + and − in the headers of the Transfer
Function, Wave Noise, Neural Noise and Solid Texture panels.

Presets are Python files, as Blender's own are. The extension's folder holds the shipped ones
(``presets/omninoise/<kind>/``, written by ``python -m tools.make_presets``), registered with
``bpy.utils.register_preset_path``; Blender keeps them read-only and writes an artist's own presets into the user
scripts folder (Blender 4.2.0 has no ``register_preset_path``: there they are copied into that folder). A wave
preset sets ``bpy.context.omninoise_wave``, which each panel points at the settings it shows (a node tree's or the
bake panel's), so one set of presets serves both.

Each preset menu and its + operator live with the panel they serve (:mod:`.bake_ui`, :mod:`.wave_ui`,
:mod:`.neural_ui`, :mod:`.solid_ui`); this module holds what they share.
"""
from __future__ import annotations

import json
import os
import shutil

__all__ = ["ROOT", "SUBDIRS", "WAVE_VALUES", "NEURAL_VALUES", "SOLID_VALUES", "LOADING", "loading",
           "transfer_preset_text", "copy_presets", "classes", "attach", "detach"]

#: the folder that holds ``presets/omninoise/...`` (this package's own folder)
ROOT = os.path.dirname(os.path.abspath(__file__))
SUBDIRS = {"transfer": "omninoise/transfer", "wave": "omninoise/wave", "neural": "omninoise/neural",
           "solid": "omninoise/solid"}

#: what a wave preset keeps: the look, not the seed
WAVE_VALUES = ["props.dimensions", "props.directions", "props.spectrum", "props.fmin", "props.fmax",
               "props.exponent", "props.waveform", "props.anisotropy", "props.axis", "props.spread",
               "props.axis_scale", "props.speed"]
#: what a neural preset keeps: the swatches and their layout and sampling, not the size, seed or output
NEURAL_VALUES = ["p.swatches", "p.mode", "p.width", "p.sharpness", "p.sampler", "p.steps", "p.tileable"]
#: what a solid texture preset keeps: how a photo becomes a solid (the method, the procedural kinds and the
#: method's options), not the photo, scale, seed, bake target or output
SOLID_VALUES = ["p.source", "p.method", "p.families", "p.refine", "p.periodic", "p.gaussian", "p.rest", "p.tile"]


def transfer_preset_text(tf) -> str:
    """The preset file of transfer function ``tf``: one call of :class:`OMNINOISE_OT_set_transfer`."""
    return ("import bpy\n"
            f"bpy.ops.omninoise.set_transfer(transfer={json.dumps(json.dumps(tf.to_dict(), sort_keys=True))})\n")


#: wave settings whose node group a preset is setting value by value (rebuilt once, after the last)
LOADING = set()


def loading(props) -> bool:
    """True while a preset sets ``props`` value by value (its node group is rebuilt once, after the last)."""
    return props.as_pointer() in LOADING


classes = ()


def attach():
    """The shipped presets' folder on Blender's preset path; in a Blender without ``register_preset_path`` (4.2.0)
    the shipped presets are copied into the user's presets folder instead (:func:`copy_presets`)."""
    import bpy      # here, not at the top: tools/make_presets.py reads this module's tables without Blender

    from .compat import reads_extension_presets

    if reads_extension_presets():
        bpy.utils.register_preset_path(ROOT)
    else:
        copy_presets(lambda sub: bpy.utils.user_resource("SCRIPTS", path=os.path.join("presets", sub), create=True))


#: the file in a user's presets folder that lists the shipped presets copied there (Blender's menus list .py only)
COPIED_RECORD = ".omninoise_shipped"


def copy_presets(folder_of) -> list:
    """Copy each shipped preset into ``folder_of(subdir)`` (the user's presets folder of a kind, made if need be)
    once, as add-ons did before Blender read presets from an extension's folder: a preset is copied where that
    folder has no file of its name and its :data:`COPIED_RECORD` does not list it, so an artist's own edit of a
    preset stays, a preset the artist removed stays removed, and one shipped later is copied at the next start.
    Returns the files copied; a folder that cannot be written leaves that kind without its shipped presets, with a
    line on the console, and the extension starts."""
    copied = []
    for sub in SUBDIRS.values():
        src = os.path.join(ROOT, "presets", sub)
        try:
            dst = folder_of(sub)
            if not dst or not os.path.isdir(dst):       # Blender gives "" for a folder it could not make
                raise NotADirectoryError(f"no folder {dst!r}")
            record = os.path.join(dst, COPIED_RECORD)
            done = set()
            if os.path.isfile(record):
                with open(record, encoding="utf-8") as fh:
                    done = set(fh.read().split())
            shipped = sorted(n for n in os.listdir(src) if n.endswith(".py"))
            for name in shipped:
                if name not in done and not os.path.exists(os.path.join(dst, name)):
                    shutil.copyfile(os.path.join(src, name), os.path.join(dst, name))
                    copied.append(os.path.join(dst, name))
            if not done.issuperset(shipped):
                with open(record, "w", encoding="utf-8") as fh:
                    fh.write("".join(f"{n}\n" for n in sorted(done.union(shipped))))
        except OSError as exc:
            print(f"OmniNoise: the shipped {sub.split('/')[-1]} presets are not available: {exc}")
    return copied


def detach():
    import bpy

    from .compat import reads_extension_presets

    if reads_extension_presets():
        bpy.utils.unregister_preset_path(ROOT)
