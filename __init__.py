"""OmniNoise: wave noise, neural noise and solid textures from photos.

This folder is two things at once:

* the Blender extension ``omninoise`` (Blender 4.2+): :func:`register` and
  :func:`unregister` below, the Blender-facing code in ``blender_addon``;
* the Python package ``omninoise`` (``pip install .``): the Blender-free
  engines in ``backend``, the file writers in ``export``, the command line in
  ``cli`` and four calls that do what the command line does:

  ========================  =====================================================
  :func:`wave`              wave noise (Guehl et al. 2025) on a grid
  :func:`neural`            neural noise (Maesumi et al. 2024) from the ONNX model
  :func:`solid`             a solid texture from a shipped texture or a photo
  :func:`bake`              every bake of a TOML job file
  ========================  =====================================================

>>> import omninoise
>>> omninoise.wave(64, spectrum=("bandpass", 4, 8), seed=1).shape
(64, 64)

Importing the package is cheap: engines, models and numpy load on first use.
"""

__all__ = ["wave", "neural", "solid", "bake", "__version__", "register", "unregister"]

_API = ("wave", "neural", "solid", "bake")


def __getattr__(name: str):
    if name in _API:
        from . import api

        return getattr(api, name)
    if name == "__version__":
        from .backend.version import __version__

        return __version__
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))


def register():
    from . import blender_addon

    blender_addon.register()


def unregister():
    from . import blender_addon

    blender_addon.unregister()
