"""The ``export`` package, reached the same way inside and outside the extension.

Inside the extension ``export`` is a sibling of ``backend`` in
``bl_ext.<repo>.omninoise``; in the repository it is a top-level package.
``backend`` imports it lazily, only where a bake writes files.
"""
try:
    from .. import export  # noqa: F401  (inside the extension package)
except (ImportError, ValueError):  # top-level package ``backend``
    import export  # noqa: F401
