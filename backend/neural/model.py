"""The exported neural noise model, run by onnxruntime (no torch).

A model folder holds ``eps.onnx`` and ``neural_noise.json`` (see
``backend/training/export_onnx.py``).  Loading checks the .onnx file's sha256
against the JSON before onnxruntime sees it; the session is created on first
use.  The graph's ``tile`` input switches every convolution between zero and
circular padding (seamless tiles).
"""
from __future__ import annotations


import numpy as np

from ..errors import SettingError
from ..onnx_models import ModelError, SessionCache, load_model_json, sha256_file

__all__ = ["NeuralNoiseModel", "ModelError", "sha256_file"]

_F = np.float32


class NeuralNoiseModel:
    """ε-network plus what the sampler and the conditioning need.

    classes      class names (index = class id)
    params       names of the shared parameter vector
    embedding    float32 (n_classes, E) class embeddings
    """

    def __init__(self, folder: str, threads: int = 0):
        self.config = load_model_json(folder, "neural_noise.json")
        self.folder = folder
        self.classes = tuple(self.config["classes"])
        self.params = tuple(self.config["params"])
        self.class_params = self.config["class_params"]
        self.embedding = np.asarray(self.config["class_embedding"], _F)
        self.multiple_of = int(self.config.get("multiple_of", 8))
        self.threads = threads
        self._sessions = SessionCache(folder, threads)

    def session(self):
        return self._sessions("eps.onnx")

    def eps_fn(self, tileable: bool = False):
        """model(x, t, cond) -> ε callable for :func:`backend.neural.sampler.ddim_sample`."""
        sess = self.session()
        tile = np.array([1.0 if tileable else 0.0], _F)

        def eps(x, t, cond):
            return sess.run(None, {"x": np.ascontiguousarray(x, _F), "t": np.ascontiguousarray(t, _F),
                                   "cond": np.ascontiguousarray(cond, _F), "tile": tile})[0]

        return eps

    # -- classes and parameters -----------------------------------------------------------
    def class_id(self, name: str) -> int:
        if name not in self.classes:
            raise SettingError("noise", f"unknown class {name!r}; choose one of {', '.join(self.classes)}")
        return self.classes.index(name)

    def param_vector(self, name: str, values: dict | None = None) -> np.ndarray:
        """Physical parameter values of class ``name`` -> float32 (P,) normalised vector (zeros elsewhere).

        Missing parameters take the middle of their range; unknown names or values
        outside the range raise SettingError naming them.
        """
        self.class_id(name)
        spec = {p["name"]: p for p in self.class_params[name]["params"]}
        values = dict(values or {})
        unknown = sorted(set(values) - set(spec))
        if unknown:
            raise SettingError("param", f"{name} has no parameter {unknown[0]!r}; it has {', '.join(spec)}")
        vec = np.zeros(len(self.params), _F)
        for pname, p in spec.items():
            v = float(values.get(pname, 0.5 * (p["min"] + p["max"])))
            if not p["min"] <= v <= p["max"]:
                raise SettingError("param", f"{pname}={v:g} is outside [{p['min']:g}, {p['max']:g}] ({p['unit']})")
            vec[self.params.index(pname)] = (v - p["min"]) / (p["max"] - p["min"])
        return vec
