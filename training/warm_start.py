"""Start a training run from a shipped neural-noise export (``neural_noise.json`` and its .onnx files, either form).

Checkpoints stay out of git, so the only durable copy of a trained model is its
export.  This reads the exported weights back into a :class:`.unet.UNet` built
for the current zoo, which may have more classes and parameter slots than the
export (the zoo is append-only, see :mod:`.zoo`):

- ONNX initialisers named like the module's parameters are copied as they are;
- GroupNorm affines, which the exporter stores as anonymous ``onnx::Mul_N`` /
  ``onnx::Add_N`` initialisers, are named by their node's scope
  (``/down.0.0/norm1/Mul`` -> ``down.0.0.norm1.weight``);
- a folded export's 2x2 stride-2 downsampling kernels (see :mod:`.unet`) go back to the 1x1
  convolution over unshuffled channels they were made from;
- a parameter the exporter gave as an ``Identity`` of another, equal one takes that one's values;
- the class embedding comes from the JSON's ``class_embedding`` table;
- a grown class table keeps its fresh N(0, 1) rows (the spherical prior of
  Sec. 3.1.1) for the new classes; a grown parameter vector gets zero input
  columns in ``cond_mlp.0``, so the new slots start without any effect.

The export's sha256 is checked twice: against its JSON (as the runtime does) and
against the hash a training config pins, so a config names one set of weights.
"""
from __future__ import annotations

import os

import numpy as np
import torch

from omninoise.backend.onnx_models import fingerprint, load_model_json
from .config import TrainConfig

__all__ = ["exported_weights", "warm_start", "torch_from_export"]


def _graph_weights(path: str) -> dict:
    """Named weights of one exported graph.  The split form's graphs wrap the UNet as ``net``
    (see :mod:`.export_onnx`), so that prefix is dropped from names and node scopes."""
    import onnx
    from onnx import numpy_helper

    graph = onnx.load(path).graph
    inits = {i.name: numpy_helper.to_array(i) for i in graph.initializer}
    out = {k.removeprefix("net."): v for k, v in inits.items() if not k.startswith("onnx::")}
    affine = {"Mul": "weight", "Add": "bias"}
    for node in graph.node:
        if node.op_type == "Identity" and node.input[0] in inits and not node.output[0].startswith("onnx::"):
            # the exporter keeps one of two equal parameters and gives the other as its Identity (a run's first
            # steps leave GroupNorm weights of several blocks bit for bit equal)
            out[node.output[0].removeprefix("net.")] = inits[node.input[0]]
            continue
        scope, _, op = node.name.rpartition("/")
        name = scope.strip("/").removeprefix("net/").replace("/", ".")
        anon = [i for i in node.input if i in inits and i.startswith("onnx::")]
        if op in affine and "/norm" in scope:
            if len(anon) == 1:
                out[name + "." + affine[op]] = inits[anon[0]].reshape(-1)
        elif node.op_type == "Conv" and len(anon) == 1 and inits[anon[0]].shape[2:] == (2, 2):
            # a folded downsampling (training.unet.Downsample): the 2x2 stride-2 kernel is the 1x1
            # convolution's weight over the unshuffled channels, K[o, c, i, j] = W[o, 4c + 2i + j]
            k = inits[anon[0]]
            out[name + ".1.weight"] = k.reshape(k.shape[0], -1, 1, 1)
    return out


def exported_weights(folder: str, sha256: str) -> dict:
    """{parameter name: float32 array} of the export in ``folder`` (either form), refusing weights whose
    :func:`backend.onnx_models.fingerprint` is not ``sha256``."""
    if not os.path.isfile(os.path.join(folder, "neural_noise.json")):
        raise ValueError(f"init_onnx: no neural_noise.json in {folder}")
    doc = load_model_json(folder, "neural_noise.json")  # checks every file against the JSON's hashes
    got = fingerprint(doc["files"])
    if got != sha256:
        raise ValueError(f"init_onnx: {folder} has weights {got[:12]}..., the config pins {sha256[:12]}... "
                         "(restore the pinned export from git history)")
    out = {}
    for name in sorted(doc["files"]):
        if name.endswith(".onnx"):
            out.update(_graph_weights(os.path.join(folder, name)))
    out["class_emb.weight"] = np.asarray(doc["class_embedding"], np.float32)
    return {k: np.asarray(v, np.float32) for k, v in out.items()}


def warm_start(model: torch.nn.Module, weights: dict) -> None:
    """Copy ``weights`` (see :func:`exported_weights`) into ``model`` in place.

    Every parameter of the model must be found; only the class table and the
    first MLP layer's input columns may be larger in the model than in the export, and a deep branch
    (``UNet(deep=...)``) may be new: it keeps its zero-output initialisation.
    ValueError names the first tensor that cannot be placed.
    """
    state = model.state_dict()
    E = model.class_emb.weight.shape[1]
    with torch.no_grad():
        for name, dst in state.items():
            if name not in weights:
                if name.startswith("deep.") and not any(k.startswith("deep.") for k in weights):
                    continue  # a deep branch new to this run keeps its initialisation: zero output, same function
                raise ValueError(f"init_onnx: the export has no tensor for {name}")
            src = torch.tensor(weights[name], dtype=dst.dtype)
            if name == "class_emb.weight" and src.shape[0] <= dst.shape[0] and src.shape[1] == dst.shape[1]:
                dst[: src.shape[0]] = src
            elif name == "cond_mlp.0.weight" and E <= src.shape[1] <= dst.shape[1] and src.shape[0] == dst.shape[0]:
                dst.zero_()
                dst[:, : src.shape[1]] = src  # input columns [embedding E, old parameter slots]; new slots stay 0
            elif tuple(src.shape) == tuple(dst.shape):
                dst.copy_(src)
            else:
                raise ValueError(f"init_onnx: {name} has shape {tuple(src.shape)} in the export, "
                                 f"{tuple(dst.shape)} in the model")
    model.load_state_dict(state)


def torch_from_export(folder: str):
    """The exported ε-network rebuilt as a torch :class:`.unet.UNet` (eval mode) from ``folder`` alone.

    Shaped by the JSON (its classes, parameter slots and training config) and filled
    by :func:`exported_weights`, so torch runs the very weights onnxruntime does
    without the run's checkpoint (which is not kept).
    """
    from .unet import UNet

    doc = load_model_json(folder, "neural_noise.json")
    cfg = TrainConfig.from_dict(doc["config"])
    model = UNet(len(doc["classes"]), len(doc["params"]), emb_dim=cfg.emb_dim, widths=cfg.widths, deep=cfg.deep)
    warm_start(model, exported_weights(folder, fingerprint(doc["files"])))
    return model.eval()
