"""Export a trained ε-network to ONNX for the runtime: ``python -m omninoise.training.export_onnx RUN OUT_DIR``.

Two forms (``form`` in the JSON).  ``split`` (the default) is what the runtime
wants: the SPADE branch depends on the conditioning only (see :mod:`.unet`), so it
is a graph of its own that a sampler runs once per image:

    OUT_DIR/encoder.onnx       inputs cond, tile -> m00 .. mNN: every ResBlock's [1 + γ₂, β₂]
                               (batch, height, width dynamic; block k at H / 2^level_k)
    OUT_DIR/denoiser.onnx      inputs x, t, m00 .. mNN -> eps, zero padding
    OUT_DIR/denoiser_tile.onnx the same with circular padding (seamless tiles)
    OUT_DIR/denoiser.weights   the two denoisers' weights, once (ONNX external data)

(Older exports have one denoiser with a ``tile`` input, which blended both paddings at every
convolution: 20 % of each step at 256²; the runtime still loads them.)

``one-piece`` (``--one-piece``; the form of models exported before the split):

    OUT_DIR/eps.onnx           inputs x, t, cond, tile -> eps (batch, height, width dynamic)

A ``tile`` input of [0.0] means zero padding and [1.0] circular padding (seamless tiles).  And:

    OUT_DIR/neural_noise.json  schedule, class and parameter names and ranges, the class-embedding
                               table, the training config and step, the run's record (wall time
                               and final loss from its log.jsonl, since runs are not kept), and
                               the .onnx file's sha256 (the runtime refuses a file whose hash differs)

The EMA weights are exported (``--raw`` for the optimiser's weights).  An older
export is re-exported from its own weights, without a checkpoint:
``python -m omninoise.training.export_onnx --from-export OLD_DIR OUT_DIR``.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
import torch

from omninoise.backend.onnx_models import write_model_json

from omninoise.backend.neural.model import sha256_file
from . import zoo
from .model_card import run_record
from .train import TrainConfig, build_model, model_names

__all__ = ["export", "export_model", "reexport", "onnx_export"]

FORMAT = 2  # 2: "form" (one-piece | split); a format-1 JSON is a one-piece export
#: the files of a split export: the encoder (with a tile input), one denoiser per padding (no tile input: zero
#: padding, or circular for seamless tiles; the blend of both in one graph cost 20 % of every step), and the
#: denoisers' weights, shared (external data)
SPLIT_FILES = ("encoder.onnx", "denoiser.onnx", "denoiser_tile.onnx", "denoiser.weights")


def onnx_export(module, args: tuple, path: str, inputs: list, outputs: list, dynamic: dict) -> None:
    """``torch.onnx.export`` (opset 17, TorchScript exporter) to a temporary file, then renamed onto ``path``."""
    from omninoise import export

    with export.atomic_path(path) as tmp:
        torch.onnx.export(module, args, tmp, input_names=inputs, output_names=outputs, dynamic_axes=dynamic,
                          opset_version=17, dynamo=False)


def _export_one(model, path: str, size: int) -> None:
    C = model.emb_dim + model.n_params
    args = (torch.randn(1, 1, size, size), torch.tensor([500.0]), torch.randn(1, C, size, size), torch.zeros(1))
    onnx_export(model, args, path, ["x", "t", "cond", "tile"], ["eps"],
                {"x": {0: "batch", 2: "height", 3: "width"}, "t": {0: "batch"},
                 "cond": {0: "batch", 2: "height", 3: "width"}, "eps": {0: "batch", 2: "height", 3: "width"}})


class _Encoder(torch.nn.Module):
    def __init__(self, net):
        super().__init__()
        self.net = net

    def forward(self, cond, tile):
        # every block's maps as two outputs, 1 + γ and β: the denoiser then reads them without a Slice per step
        return tuple(half for m in self.net.encode(cond, tile) for half in m.chunk(2, dim=1))


class _Denoiser(torch.nn.Module):
    """The denoiser with one padding baked in: zeros (``mode`` None) or circular (``mode`` "circular")."""

    def __init__(self, net, mode=None):
        super().__init__()
        self.net, self.mode = net, mode

    def forward(self, x, t, *maps):
        # the folded form (GroupNorm affine and time modulation per channel, strided downsampling: see
        # training.unet): the same function in fewer passes over the feature maps
        return self.net.denoise(x, t, [tuple(maps[i:i + 2]) for i in range(0, len(maps), 2)], self.mode, fold=True)


def drop_identity_arithmetic(path: str) -> int:
    """Remove from the ONNX graph at ``path`` every Mul by a constant 1 and Add of a constant 0 that cannot change
    its other operand's shape (a one-element constant of no higher rank): the TorchScript exporter writes such a
    pair after every affine-free instance norm, two passes over a feature map that do nothing.  Returns how many."""
    import onnx
    from onnx import numpy_helper

    from omninoise import export

    model = onnx.load(path)
    graph = model.graph
    rank = {v.name: len(v.type.tensor_type.shape.dim)
            for v in list(onnx.shape_inference.infer_shapes(model).graph.value_info) + list(graph.input)}
    const = {n.output[0]: numpy_helper.to_array(n.attribute[0].t) for n in graph.node
             if n.op_type == "Constant" and n.attribute and n.attribute[0].name == "value"}
    const.update({i.name: numpy_helper.to_array(i) for i in graph.initializer})
    outputs = {o.name for o in graph.output}
    neutral = {"Mul": 1.0, "Add": 0.0}
    rename, keep = {}, []
    for node in graph.node:
        node.input[:] = [rename.get(i, i) for i in node.input]
        if node.op_type in neutral and node.output[0] not in outputs and len(node.input) == 2:
            for c, other in (node.input, node.input[::-1]):
                v = const.get(c)
                if (v is not None and v.size == 1 and float(v.reshape(())) == neutral[node.op_type]
                        and v.ndim <= rank.get(other, -1)):
                    rename[node.output[0]] = other
                    break
            else:
                keep.append(node)
            continue
        keep.append(node)
    used = {i for n in keep for i in n.input} | outputs
    keep = [n for n in keep if n.op_type != "Constant" or n.output[0] in used]
    del graph.node[:]
    graph.node.extend(keep)
    with export.atomic_path(path) as tmp:
        onnx.save(model, tmp)
    return len(rename)


def share_weights(folder: str, graphs: list, weights: str) -> None:
    """Move the large initializers of ``graphs`` (ONNX files in ``folder``) into one external-data file
    ``weights``, each distinct tensor once: graphs exported from the same network then ship its weights once.
    Tensors under 1 KiB stay inline."""
    import hashlib

    import onnx
    from onnx import external_data_helper, numpy_helper

    from omninoise import export

    models = [onnx.load(os.path.join(folder, g)) for g in graphs]
    where, blob = {}, bytearray()
    for model in models:
        for init in model.graph.initializer:
            arr = numpy_helper.to_array(init)
            raw = np.ascontiguousarray(arr).astype(arr.dtype.newbyteorder("<")).tobytes()
            if len(raw) < 1024:
                continue
            key = hashlib.sha256(raw + str(arr.dtype).encode() + str(arr.shape).encode()).digest()
            if key not in where:
                blob += b"\0" * (-len(blob) % 64)  # 64-byte aligned tensors
                where[key] = (len(blob), len(raw))
                blob += raw
            init.CopyFrom(numpy_helper.from_array(arr, init.name))  # raw_data form
            external_data_helper.set_external_data(init, location=weights, offset=where[key][0], length=len(raw))
            init.data_location = onnx.TensorProto.EXTERNAL
            init.ClearField("raw_data")
    with export.atomic_path(os.path.join(folder, weights)) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(bytes(blob))
    for g, model in zip(graphs, models):
        with export.atomic_path(os.path.join(folder, g)) as tmp:
            onnx.save(model, tmp, save_as_external_data=False)


def map_names(model) -> list:
    """m00, m01, ...: one SPADE map input per ResBlock, in :meth:`UNet.blocks` order."""
    return [f"m{k:02d}" for k in range(len(model.blocks()))]


def _export_split(model, out: str, size: int) -> dict:
    """encoder.onnx + denoiser.onnx in ``out``; returns the JSON's ``blocks`` description."""
    C = model.emb_dim + model.n_params
    cond, tile = torch.randn(1, C, size, size), torch.zeros(1)
    names = map_names(model)
    tensors = [n + half for n in names for half in ("g", "b")]  # per block: 1 + γ ("m00g") and β ("m00b")
    hw = {0: "batch", 2: "height", 3: "width"}
    map_axes = {n: {0: "batch", 2: f"h{n[:-1]}", 3: f"w{n[:-1]}"} for n in tensors}  # block k: H / 2^level_k
    onnx_export(_Encoder(model), (cond, tile), os.path.join(out, "encoder.onnx"), ["cond", "tile"], tensors,
                {"cond": hw, **map_axes})
    with torch.no_grad():
        maps = model.encode(cond, tile)
    args = (torch.randn(1, 1, size, size), torch.tensor([500.0]), *(h for m in maps for h in m.chunk(2, dim=1)))
    for name, mode in (("denoiser.onnx", None), ("denoiser_tile.onnx", "circular")):
        onnx_export(_Denoiser(model, mode), args, os.path.join(out, name), ["x", "t"] + tensors, ["eps"],
                    {"x": hw, "t": {0: "batch"}, "eps": hw, **map_axes})
        drop_identity_arithmetic(os.path.join(out, name))
    share_weights(out, ["denoiser.onnx", "denoiser_tile.onnx"], "denoiser.weights")
    return dict(names=names, tensors=tensors, channels=[int(m.shape[1]) for m in maps],
                levels=[lvl for _, lvl in model.blocks()])


def export_model(model, out: str, meta: dict, one_piece: bool = False) -> dict:
    """Write ``model`` (eval mode) into folder ``out`` in either form with a JSON of ``meta`` plus what the runtime needs."""
    classes, params = model_names(model)
    os.makedirs(out, exist_ok=True)
    size = int(meta["train_size"])
    doc = dict(format=FORMAT, model="neural_noise", paper="Maesumi et al. 2024, One Noise to Rule Them All",
               schedule=dict(kind="cosine", T=1000, s=0.008), prediction="epsilon",
               classes=classes, params=params,
               class_params={k: v for k, v in zoo.describe().items() if k in classes}, emb_dim=model.emb_dim,
               class_embedding=model.class_emb.weight.detach().numpy().astype(float).round(7).tolist(),
               multiple_of=1 << model.levels())
    doc.update(meta)
    if one_piece:
        _export_one(model, os.path.join(out, "eps.onnx"), size)
        doc.update(form="one-piece", files={"eps.onnx": sha256_file(os.path.join(out, "eps.onnx"))})
    else:
        doc.update(form="split", blocks=_export_split(model, out, size))
        doc["files"] = {n: sha256_file(os.path.join(out, n)) for n in SPLIT_FILES}
    write_model_json(os.path.join(out, "neural_noise.json"), doc)
    return doc


def export(run: str, out: str, raw: bool = False, extra: dict | None = None, one_piece: bool = False) -> dict:
    """Export checkpoint ``run/ckpt.pt`` into folder ``out``; returns the JSON config written."""
    state = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
    cfg = TrainConfig.from_dict(state["config"])
    model = build_model(cfg, state["model"])
    model.load_state_dict(state["model" if raw else "ema"])
    model.eval()
    meta = dict(trained_classes=list(cfg.classes), train_size=cfg.size, step=int(state["step"]),
                weights="raw" if raw else "ema", config=state["config"])
    log = os.path.join(run, "log.jsonl")
    if os.path.isfile(log):
        meta["training"] = run_record(log)
    meta.update(extra or {})
    return export_model(model, out, meta, one_piece)


#: what a re-export carries over from the old JSON (the rest is rebuilt from the weights)
_CARRIED = ("trained_classes", "train_size", "step", "weights", "config", "training")


def reexport(src: str, out: str, one_piece: bool = False) -> dict:
    """Export folder ``src`` again, from its own weights (torch rebuilt from the export), into ``out``."""
    from omninoise.backend.onnx_models import load_model_json
    from .warm_start import torch_from_export

    old = load_model_json(src, "neural_noise.json")
    model = torch_from_export(src)
    meta = {k: old[k] for k in _CARRIED if k in old}
    meta["reexported_from"] = dict(form=old.get("form", "one-piece"), files=old["files"])
    return export_model(model, out, meta, one_piece)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.export_onnx", description=__doc__.split("\n")[0])
    ap.add_argument("run", help="training run folder (holds ckpt.pt), or with --from-export an export folder")
    ap.add_argument("out", help="output folder for the .onnx files and neural_noise.json")
    ap.add_argument("--raw", action="store_true", help="export the raw weights instead of the EMA")
    ap.add_argument("--one-piece", action="store_true", help="one eps.onnx instead of encoder + denoiser")
    ap.add_argument("--from-export", action="store_true", help="RUN is an export folder: re-export its weights")
    a = ap.parse_args(argv)
    if a.from_export:
        if os.path.realpath(a.run) == os.path.realpath(a.out):
            print("export: error: --from-export needs an output folder other than its source", file=sys.stderr)
            return 2
        doc = reexport(a.run, a.out, a.one_piece)
        print(json.dumps(doc["files"], indent=1))
        return 0
    if not os.path.isfile(os.path.join(a.run, "ckpt.pt")):
        print(f"export: error: no checkpoint in {a.run}", file=sys.stderr)
        return 2
    doc = export(a.run, a.out, a.raw, one_piece=a.one_piece)
    print(json.dumps(doc["files"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
