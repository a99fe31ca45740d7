"""Where the shipped models are: one answer for the command line, job files, the API and the Blender extension.

The models sit inside the package, beside ``backend`` (``omninoise/models``): in the repository, in the Blender
extension and in a pip installation alike.  ``OMNINOISE_MODELS`` overrides that (a farm's shared model folder).
"""
from __future__ import annotations

import os

from .errors import SettingError

__all__ = ["models_root", "neural_model", "solid_models", "fit_bank", "in_job", "in_job_or_name"]

_HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))   # the package folder, holding backend/


def models_root() -> str:
    """The folder of models: ``OMNINOISE_MODELS`` when set, else the package's own ``models`` folder; a
    SettingError naming ``OMNINOISE_MODELS`` where it names no folder."""
    root = os.environ.get("OMNINOISE_MODELS")
    if not root:
        return os.path.join(_HERE, "models")
    if not os.path.isdir(root):
        raise SettingError("OMNINOISE_MODELS", f"{root} is not a folder (it names the folder of models, which holds "
                                               "neural_noise and solid)")
    return root


def neural_model() -> str:
    """The shipped neural noise model folder."""
    return os.path.join(models_root(), "neural_noise")


def solid_models() -> str:
    """The folder of the shipped solid texture models (one subfolder each)."""
    return os.path.join(models_root(), "solid")


def fit_bank() -> str:
    """The folder of the inverse-design bank (statistics of zoo images, ``tools`` of training.fit_bank)."""
    return os.path.join(models_root(), "fit_bank")


def in_job(base_dir: str, value: str) -> str:
    """A path a job file names: ``~`` and ``~user`` are a home folder, a relative path lies in ``base_dir`` (the job
    file's folder), an absolute one stands.

    >>> in_job("/jobs", "noise.png"), in_job("/jobs", "/tmp/a.vdb")
    ('/jobs/noise.png', '/tmp/a.vdb')
    >>> in_job("/jobs", "~/renders/a.exr") == os.path.join(os.path.expanduser("~"), "renders", "a.exr")
    True
    >>> in_job(".", "photo.png")      # a table read in no job's folder: the path as given
    'photo.png'
    """
    value = os.path.expanduser(value)
    return value if base_dir in ("", os.curdir) else os.path.join(base_dir, value)


def in_job_or_name(base_dir: str, value):
    """A job's exemplar, ``to`` or ``model``: a shipped texture's or model's name (a word with no '.', '/', '\\' or
    '~', such as ``marble_3d`` or ``wood``) stands where nothing of that name lies beside the job; anything else is a
    path, :func:`in_job` (never looked up from the folder the job runs in).  A value that is not a string stands.

    >>> in_job_or_name("/jobs", "photo.png"), in_job_or_name("/jobs", "marble_3d"), in_job_or_name("/jobs", 3)
    ('/jobs/photo.png', 'marble_3d', 3)
    """
    if not isinstance(value, str):
        return value
    path = in_job(base_dir, value)
    word = value and not any(c in value for c in "./\\~")
    return value if word and not os.path.exists(path) else path
