"""Training-time code for the neural models (torch).  Never imported by the add-on or the runtime.

zoo        procedural noise classes (training data and ground truth for ``omninoise zoo``)
noise_ops  batched torch noise primitives behind the zoo
"""

try:
    import torch  # noqa: F401
except ImportError as exc:  # one line that says what to install, under the name pytest and pip users know
    raise ModuleNotFoundError("omninoise.training needs torch: pip install 'omninoise[train]'",
                              name="torch") from exc
