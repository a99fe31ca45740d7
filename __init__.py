"""OmniNoise Blender extension root (id ``omninoise``, Blender 4.2+).

Registration stays cheap: engines and models load lazily when first used.
The Blender-facing code lives in ``blender_addon``; ``backend`` and ``export``
are Blender-free.
"""


def register():
    from . import blender_addon

    blender_addon.register()


def unregister():
    from . import blender_addon

    blender_addon.unregister()
