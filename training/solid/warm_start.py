"""Start a solid-texture run from a shipped export (``solid.json`` and its .onnx files).

Run folders (``ckpt.pt``) stay out of git, so the durable copy of a trained
solid texture is its export.  This reads the exported weights back into a
:class:`.model.SolidTexture` built from the export's own training config:

- ``decoder.onnx`` holds the decoder with its first layer split
  (:class:`.export.SplitDecoder`): W_e and b are named ``we.*``; W_n is an
  anonymous MatMul initialiser (stored transposed), found through the node
  ``/wn/MatMul``; the first layer is [W_n | W_e] again; ``film.*`` is the
  code modulation of a ``film`` decoder;
- ``encoder.onnx`` and ``translator.onnx`` (space mode) keep the module names
  (the translator wrapped as ``tr.``).  The last instance norm of the encoder
  feeds nothing the code reads, so the exporter drops it; it keeps its
  initial affine (ones, zeros), which changes no output;
- single mode: e and T come from the JSON (``code``, ``T``).

The export's files are checked against its JSON's sha256 (as the runtime
does) and the weights' fingerprint against the one the config pins
(``init_sha256``), so a config names one set of weights.
"""
from __future__ import annotations

import os

import numpy as np
import torch

from omninoise.backend.onnx_models import fingerprint, load_model_json

__all__ = ["exported_weights", "warm_start", "export_config"]


def _inits(path: str):
    import onnx
    from onnx import numpy_helper

    graph = onnx.load(path).graph
    return graph, {i.name: numpy_helper.to_array(i) for i in graph.initializer}


def _decoder(path: str) -> dict:
    graph, inits = _inits(path)
    wn = [n for n in graph.node if n.name == "/wn/MatMul"]
    if len(wn) != 1 or wn[0].input[1] not in inits:
        raise ValueError(f"init_onnx: {path} has no /wn/MatMul weight (not a solid decoder export)")
    out = {"decoder.net.0.weight": np.concatenate([inits[wn[0].input[1]].T, inits["we.weight"]], axis=1),
           "decoder.net.0.bias": inits["we.bias"]}
    for k, v in inits.items():
        if k.startswith("rest."):
            idx, _, rest = k[len("rest."):].partition(".")
            out[f"decoder.net.{int(idx)}.{rest}"] = v     # rest = net[1:], so its indices are the net's
        elif k.startswith("film."):
            out[f"decoder.{k}"] = v
    return out


def export_config(folder: str) -> dict:
    """The training config (dict) an export was made from."""
    return dict(load_model_json(folder, "solid.json")["config"])


def exported_weights(folder: str, sha256: str) -> dict:
    """{state-dict name: float32 array} of the solid export in ``folder``, refusing weights whose
    :func:`backend.onnx_models.fingerprint` is not ``sha256``."""
    if not os.path.isfile(os.path.join(folder, "solid.json")):
        raise ValueError(f"init_onnx: no solid.json in {folder}")
    doc = load_model_json(folder, "solid.json")
    got = fingerprint(doc["files"])
    if got != sha256:
        raise ValueError(f"init_onnx: {folder} has weights {got[:12]}..., the config pins {sha256[:12]}... "
                         "(restore the pinned export from git history)")
    out = _decoder(os.path.join(folder, "decoder.onnx"))
    if doc["mode"] == "single":
        out["code"] = np.asarray(doc["code"], np.float32)
        out["T"] = np.asarray(doc["T"], np.float32)
        if "waves" in doc:   # the photo's periodic components (waves.py), measured when it was first trained
            out["waves"] = np.asarray(doc["waves"], np.float32)
    else:
        _, enc = _inits(os.path.join(folder, "encoder.onnx"))
        out.update({f"encoder.{k}": v for k, v in enc.items() if not k.startswith("onnx::")})
        _, tr = _inits(os.path.join(folder, "translator.onnx"))
        out.update({f"translator.{k.removeprefix('tr.')}": v for k, v in tr.items() if k.startswith("tr.")})
    return {k: np.asarray(v, np.float32) for k, v in out.items()}


#: the one tensor an export may lack: the encoder's last instance norm (its output is never read)
_OPTIONAL = ("encoder.norms.4.weight", "encoder.norms.4.bias")


def warm_start(model: torch.nn.Module, weights: dict, new_features: int = 0) -> None:
    """Copy ``weights`` into ``model`` in place; every other tensor must be found with its shape
    (ValueError names the first that is not).

    ``new_features``: the model's decoder reads this many more noise features than the export's
    (cellular or brick features added to a model trained without them, appended after its value
    noise): their columns of the first layer start at zero, so the model starts as the export
    exactly and training learns to use them."""
    state = model.state_dict()
    with torch.no_grad():
        for name, dst in state.items():
            if name not in weights:
                if name in _OPTIONAL:
                    continue
                raise ValueError(f"init_onnx: the export has no tensor for {name}")
            src = torch.tensor(np.array(weights[name]), dtype=dst.dtype)
            if name == "decoder.net.0.weight" and new_features:
                n_old = src.shape[1] - model.code_dim
                src = torch.cat([src[:, :n_old], src.new_zeros(src.shape[0], new_features), src[:, n_old:]], 1)
            if tuple(src.shape) != tuple(dst.shape):
                raise ValueError(f"init_onnx: {name} has shape {tuple(src.shape)} in the export, "
                                 f"{tuple(dst.shape)} in the model")
            dst.copy_(src)
    model.load_state_dict(state)
