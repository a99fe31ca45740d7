"""The package version (a module of its own, so that submodules can read it without importing ``backend``)."""

__version__ = "0.2.0"
