"""Where the shipped models are: one answer for the command line, job files and the runtimes.

In the repository and in the Blender extension the models sit beside the packages (``models/``). A
non-editable ``pip install .`` puts them into ``<prefix>/share/omninoise/models`` (``[tool.setuptools.data-files]``
in ``pyproject.toml``). ``OMNINOISE_MODELS`` overrides both (a farm's shared model folder).
"""
from __future__ import annotations

import os
import sys

__all__ = ["models_root", "neural_model", "solid_models", "fit_bank"]

_HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))   # the folder holding backend/


def _candidates() -> list:
    env = os.environ.get("OMNINOISE_MODELS")
    if env:
        return [env]
    site = _HERE  # site-packages when installed
    return [os.path.join(_HERE, "models"),
            os.path.join(sys.prefix, "share", "omninoise", "models"),
            os.path.normpath(os.path.join(site, "..", "..", "..", "share", "omninoise", "models")),  # posix prefix
            os.path.normpath(os.path.join(site, "..", "..", "share", "omninoise", "models")),        # Windows prefix
            os.path.join(site, "share", "omninoise", "models")]                                      # pip --target


def models_root() -> str:
    """The first folder of models that exists (``OMNINOISE_MODELS`` when set, even if missing: its error then
    names it); else the repository layout's ``models`` folder, for messages."""
    cands = _candidates()
    if os.environ.get("OMNINOISE_MODELS"):
        return cands[0]
    for c in cands:
        if os.path.isdir(c):
            return c
    return cands[0]


def neural_model() -> str:
    """The shipped neural noise model folder."""
    return os.path.join(models_root(), "neural_noise")


def solid_models() -> str:
    """The folder of the shipped solid texture models (one subfolder each)."""
    return os.path.join(models_root(), "solid")


def fit_bank() -> str:
    """The folder of the inverse-design bank (statistics of zoo images, ``tools`` of training.fit_bank)."""
    return os.path.join(models_root(), "fit_bank")
