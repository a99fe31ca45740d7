"""Blender layer of OmniNoise: the only package that imports ``bpy``.

Registration is cheap: classes and menu entries only.  Engines load when first
used (building a node imports numpy and the backend, no model is read).
"""
from __future__ import annotations


def _modules():
    from . import bake_ui, neural_ui, preferences, solid_ui, wave_ui

    return (preferences, wave_ui, bake_ui, neural_ui, solid_ui)


def register():
    for m in _modules():
        m.register()


def unregister():
    from . import tasks

    tasks.shutdown()  # a bake still running is cancelled and joined, its timer dropped: nothing keeps running
    for m in reversed(_modules()):
        m.unregister()
