"""The Blender-free packages, imported the same way inside and outside the extension.

Installed as an extension, ``backend`` and ``export`` are siblings of this
package inside ``bl_ext.<repo>.omninoise``; in tests and benchmarks the
repository root is on ``sys.path`` and they are top-level packages.
"""
try:
    from .. import backend, export  # noqa: F401  (inside the extension package)
except ImportError:  # imported as the top-level package ``blender_addon``
    import backend  # noqa: F401
    import export  # noqa: F401
