"""Export a trained solid texture to ONNX: ``python -m omninoise.training.solid.export RUN OUT_DIR``.

Writes, each atomically:

    OUT_DIR/decoder.onnx     inputs noise (N, m*C), code (B, E) with B = 1 or N -> rgb (N, 3)
                             (colour "affine": the whitened colour d; the runtime adds mu + L d);
                             f(n | e) of Eq. 5 with its first layer split as W_n n + (W_e e + b), so
                             one code is broadcast over all points and per-point codes still work
    OUT_DIR/encoder.onnx     space mode: exemplar (B, 3, 128, 128) in [0, 1] -> z (B, z_dim)
    OUT_DIR/translator.onnx  space mode: z (B, z_dim) -> e (B, E), T (B, m, D, D)
    OUT_DIR/solid.json       dims, octaves, channels, units, the single-mode code e and
                             transforms T (or the codes z of the training exemplars), the
                             training config and every .onnx file's sha256
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import torch
from torch import nn

from omninoise.backend.onnx_models import write_model_json
from omninoise.backend.onnx_models import sha256_file
from omninoise.backend.solid.harmonic import to_json
from omninoise.backend.solid.harmonic import measure_harmonics
from omninoise.backend.solid.model import exemplar_category
from ..export_onnx import onnx_export as _onnx
from . import exemplars as ex
from .model import COLOUR_STATS, colour_stats, spectral_gains
from .train import SolidConfig, build_model, training_images

__all__ = ["export", "SplitDecoder", "FORMAT", "ENCODER_SIZE"]

FORMAT = 1
ENCODER_SIZE = 128


class SplitDecoder(nn.Module):
    """The decoder with its first layer split: same outputs as Decoder(cat(n, e)), broadcasting e
    (and its code modulation ``film``, when it has one)."""

    def __init__(self, dec, n_noise: int):
        super().__init__()
        self.sigmoid, self.layers = dec.sigmoid, dec.layers
        self.film = dec.film
        first = dec.net[0]
        self.wn = nn.Linear(n_noise, first.out_features, bias=False)
        self.we = nn.Linear(first.in_features - n_noise, first.out_features)
        with torch.no_grad():
            self.wn.weight.copy_(first.weight[:, :n_noise])
            self.we.weight.copy_(first.weight[:, n_noise:])
            self.we.bias.copy_(first.bias)
        self.rest = dec.net[1:]

    def forward(self, noise, code):
        if self.film is None:
            y = self.rest(self.wn(noise) + self.we(code))
        else:
            h = torch.relu(self.wn(noise) + self.we(code))
            mod = self.film(code).chunk(2 * (self.layers - 1), dim=-1)
            for j in range(1, self.layers):
                h = torch.relu((1.0 + mod[2 * j - 2]) * self.rest[2 * j - 1](h) + mod[2 * j - 1])
            y = self.rest[2 * self.layers - 1](h)
        return torch.sigmoid(y) if self.sigmoid else y


class _Translator(nn.Module):
    def __init__(self, tr):
        super().__init__()
        self.tr = tr

    def forward(self, z):
        return self.tr(z)


def export(run: str, out: str, extra: dict | None = None) -> dict:
    """Export ``run/ckpt.pt`` into folder ``out``; returns the JSON written."""
    state = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
    cfg = SolidConfig.from_dict(state["config"])
    model = build_model(cfg)
    model.load_state_dict(state["model"])
    model.eval()
    os.makedirs(out, exist_ok=True)
    n_noise = model.n_noise
    files = {}
    _onnx(SplitDecoder(model.decoder, n_noise), (torch.randn(16, n_noise), torch.randn(1, cfg.code_dim)),
          os.path.join(out, "decoder.onnx"), ["noise", "code"], ["rgb"],
          {"noise": {0: "points"}, "code": {0: "codes"}, "rgb": {0: "points"}})
    files["decoder.onnx"] = sha256_file(os.path.join(out, "decoder.onnx"))
    doc = dict(format=FORMAT, model="neural_solid_texture", name=cfg.name,
               paper="Henzler, Mitra, Ritschel 2020, Learning a Neural 3D Texture Space from 2D Exemplars",
               mode=cfg.mode, dim=cfg.dim, octaves=cfg.octaves, channels=cfg.channels, code_dim=cfg.code_dim,
               z_dim=cfg.z_dim, px_per_unit=cfg.px_per_unit, exemplar_scale=cfg.exemplar_scale,
               exemplars=list(cfg.exemplars), colour="sRGB", colour_model=cfg.colour,
               colour_stats=COLOUR_STATS if cfg.colour == "affine" else 0,
               spectral_gains=cfg.octaves if cfg.spectral else 0, cellular=cfg.cellular, bricks=cfg.bricks,
               harmonic_rest=cfg.harmonic_rest, spin=cfg.spin, step=int(state["step"]),
               train_seconds=round(float(state.get("elapsed", 0.0)), 1), n_params=int(state["n_params"]),
               hardware=str(state.get("hardware", "")),
               config=state["config"])
    with torch.no_grad():
        if cfg.mode == "single":
            e, T = model.codes(batch=1)
            doc["code"] = e[0].numpy().astype(float).round(7).tolist()
            doc["T"] = T[0].numpy().astype(float).round(7).tolist()
            if model.waves is not None:   # the photo's periodic components (waves.py), exact float32 values
                doc["waves"] = model.waves.double().numpy().tolist()
            if cfg.colour == "affine":   # the exemplar's colour (mu, L), as training rendered it
                doc["colour_code"] = colour_stats(training_images(cfg)[0].unsqueeze(0))[0].numpy() \
                    .astype(float).round(7).tolist()
        else:
            _onnx(model.encoder, (torch.rand(1, 3, ENCODER_SIZE, ENCODER_SIZE),), os.path.join(out, "encoder.onnx"),
                  ["exemplar"], ["z"], {"exemplar": {0: "batch"}, "z": {0: "batch"}})
            _onnx(_Translator(model.translator), (torch.randn(1, cfg.z_dim),), os.path.join(out, "translator.onnx"),
                  ["z"], ["e", "T"], {"z": {0: "batch"}, "e": {0: "batch"}, "T": {0: "batch"}})
            files["encoder.onnx"] = sha256_file(os.path.join(out, "encoder.onnx"))
            files["translator.onnx"] = sha256_file(os.path.join(out, "translator.onnx"))
            # codes of the training exemplars: mean z over a grid of 128 px crops
            # (photo models: one named code per category, its first training photo; z gets the photo's colour)
            # and, photo models, each name's harmonic part from its photo (not its rest), which code(name) adds
            codes, parts, named = {}, {}, {}
            images = training_images(cfg)
            photos = None
            if cfg.colour == "affine":      # the whole photos the names' parts are measured from, each read once
                photos = training_images(cfg, rests=False) if cfg.harmonic_rest else images
            for i, (name, img) in enumerate(zip(ex.expand(cfg.exemplars), images)):
                key = exemplar_category(name)
                if key in codes:      # photo models: a category's first training photo names it
                    continue
                if photos is not None:
                    photo = photos[i].permute(1, 2, 0).numpy()
                    h = measure_harmonics(photo, cfg.px_per_unit)
                    if len(h):
                        parts[key] = to_json(h)
                    named[key] = (photo, h if len(h) else None)
                crops = img.unfold(1, ENCODER_SIZE, ENCODER_SIZE // 2).unfold(2, ENCODER_SIZE, ENCODER_SIZE // 2)
                crops = crops.permute(1, 2, 0, 3, 4).reshape(-1, 3, ENCODER_SIZE, ENCODER_SIZE)
                z = model.encoder(crops).mean(0)
                if cfg.colour == "affine":
                    z = torch.cat([z, colour_stats(img.unsqueeze(0))[0]])
                if cfg.spectral:   # as the runtime's encode: crop by crop, averaged
                    z = torch.cat([z, spectral_gains(crops, cfg.octaves, cfg.px_per_unit).mean(0)])
                codes[key] = z.numpy().astype(float).round(6).tolist()
            doc["codes"] = codes
            if parts:
                doc["code_harmonics"] = parts
            doc["encoder_size"] = ENCODER_SIZE
    doc["files"] = files
    doc.update(extra or {})
    path = os.path.join(out, "solid.json")
    write_model_json(path, doc)
    if cfg.mode == "space" and cfg.colour == "affine" and cfg.dim == 3:
        # each name's Gaussian rest, as the runtime's check keeps it for its photo (it renders the export itself)
        from omninoise.backend.solid.model import SolidTextureModel

        from .harmonics import rests_of

        rests = rests_of(SolidTextureModel(out), named)
        if rests:
            doc["code_rests"] = rests
            write_model_json(path, doc)
    return doc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.solid.export", description=__doc__.split("\n")[0])
    ap.add_argument("run", help="training run folder (holds ckpt.pt)")
    ap.add_argument("out", help="output folder for the .onnx files and solid.json")
    a = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(a.run, "ckpt.pt")):
        print(f"solid export: error: no checkpoint in {a.run}", file=sys.stderr)
        return 2
    doc = export(a.run, a.out)
    print(json.dumps(doc["files"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
