"""Blender layer of OmniNoise: the only package that imports ``bpy``.

Registration is cheap: classes and menu entries only.  Each UI module has one ``classes`` tuple and, where it
adds more than classes (scene settings, menu entries, handlers), an ``attach()``/``detach()`` pair; this package
registers them all in one loop.  Engines load when first used (building a node imports numpy and the backend, no
model is read).
"""
from __future__ import annotations


def _modules():
    from . import bake_ui, menus, neural_ui, preferences, presets, solid_ui, wave_ui

    return (preferences, presets, wave_ui, bake_ui, neural_ui, solid_ui, menus)


def register():
    """Every module's ``classes`` registered in order, then what each ``attach()`` adds (scene settings, menu
    entries, handlers)."""
    import bpy

    from . import tasks

    for m in _modules():
        for cls in m.classes:
            bpy.utils.register_class(cls)
        if hasattr(m, "attach"):
            m.attach()
    tasks.attach()  # a task still running when another file opens is cancelled and dropped


def unregister():
    import bpy

    from . import tasks

    tasks.shutdown()  # a bake still running is cancelled and joined, its timer dropped: nothing keeps running
    tasks.detach()
    for m in reversed(_modules()):
        if hasattr(m, "detach"):
            m.detach()
        for cls in reversed(m.classes):
            bpy.utils.unregister_class(cls)
