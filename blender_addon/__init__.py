"""Blender layer of OmniNoise: the only package that imports ``bpy``.

Operators, panels and node-group builders register here (later issues); for now
the package provides :mod:`.field_eval`, which evaluates Blender texture nodes
through Geometry Nodes for tests and benchmarks.
"""

_classes: list = []


def register():
    import bpy

    for cls in _classes:
        bpy.utils.register_class(cls)


def unregister():
    import bpy

    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
