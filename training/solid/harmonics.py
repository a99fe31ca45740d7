"""Store a photo model's harmonic parts: ``python -m omninoise.training.solid.harmonics MODEL_DIR [--remove]``.

A space photo model (the texture-space model) stores one part per named code (``code_harmonics``), measured from
the training photo that names it (a category's first: the export's rule), and that photo's Gaussian rest where the
encode-time check keeps one (``code_rests``, ``backend/solid/gaussian_rest.py``), so that ``--exemplar NAME`` draws what
encoding that photo draws; the export writes them too, this adds them to an export made before.  The photo must
still encode to the stored code (checked).

The texture-space model measures a photo's harmonic part when it encodes it (``backend/solid/harmonic.py``).
A single-exemplar photo model has no encoder, so its part is measured here, once, from the pixels it was trained
on: its exemplar's training region (all but the right quarter when the model was trained with ``hold_out``,
``training.solid.exemplars.train_region``), read as the evaluation reads it, at the model's own scale.  It is
written into the folder's solid.json as ``harmonics`` (``backend.solid.harmonic.to_json``), which the runtime
adds to the model's texture; ``--remove`` takes it out.  Nothing is trained and the ONNX files are unchanged.

``--spin MODE`` first sets how the runtime turns the model's octaves with their seeds (solid.json ``spin``,
``backend/solid/spin.py``: ``octave``, ``lattice`` or ``none``); the named codes' rests are then measured as the
model will draw them.  Until they are, the folder is not touched.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile

import numpy as np

from omninoise import export as _ex
from omninoise.backend.onnx_models import ModelError, write_model_json
from omninoise.backend.solid.harmonic import to_json
from omninoise.backend.solid.model import SolidTextureModel, exemplar_category
from omninoise.backend.solid.gaussian_rest import rest_to_json
from omninoise.backend.solid.pipeline import gaussian_rest

from .photo_set import expand

__all__ = ["measure", "measure_codes", "rests_of", "main"]


def measure(folder: str, root: str = ".") -> dict:
    """The harmonic part of the model in ``folder`` measured from its exemplar's training region (``root``: where
    the exemplar paths in solid.json start), as solid.json's ``harmonics``."""
    m = SolidTextureModel(folder)
    if m.mode != "single" or not m.colour_stats:
        raise ModelError(f"model {m.name!r} is not a single photo model; only those store a harmonic part")
    photo = _ex.read_rgb(os.path.join(root, m.config["exemplars"][0]))
    if m.config.get("config", {}).get("hold_out", False):   # train_region's cut, without torch (tests/test_layers.py)
        photo = photo[:, : photo.shape[1] * 3 // 4]
    return to_json(m.harmonics(photo))


def rests_of(m: SolidTextureModel, named: dict) -> dict:
    """``code_rests`` of a space photo model: for each name of ``named`` {name: (photo float (H, W, 3), its
    harmonic part or None)}, the Gaussian rest the check keeps for the photo drawn with the name's stored code
    (names without one are left out)."""
    out = {}
    for key, (photo, h) in named.items():
        r = gaussian_rest(m, photo, m.translate(m.codes[key], h))
        if r is not None:
            out[key] = rest_to_json(r)
    return out


def measure_codes(folder: str, root: str = ".", tolerance: float = 1e-3) -> tuple:
    """A space photo model's (``code_harmonics``, ``code_rests``): for each named code with a part, the part of
    its photo; for each with a Gaussian rest, that (:func:`rests_of`)."""
    m = SolidTextureModel(folder)
    if m.mode != "space" or not m.colour_stats:
        raise ModelError(f"model {m.name!r} is not a space photo model")
    parts, seen, named = {}, set(), {}
    for path in expand(m.config["exemplars"], root):
        key = exemplar_category(path)
        if key in seen or key not in m.codes:
            continue
        seen.add(key)
        photo = _ex.read_rgb(path)
        h = m.harmonics(photo)
        z = m.encode(photo, h)
        off = float(np.abs(z - m.codes[key]).max())
        if off > tolerance:
            raise ModelError(f"{path} does not encode to the stored code {key!r} (off by {off:.3g}): the model was "
                             "exported from other photos")
        if len(h):
            parts[key] = to_json(h)
        named[key] = (photo, h if len(h) else None)
    return parts, rests_of(m, named)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m omninoise.training.solid.harmonics", description=__doc__.split("\n")[0])
    ap.add_argument("folder", help="a single photo model's folder (holds solid.json)")
    ap.add_argument("--remove", action="store_true", help="take the stored harmonic part out")
    ap.add_argument("--root", default=".", help="where the exemplar paths in solid.json start")
    ap.add_argument("--spin", choices=("none", "lattice", "octave"),
                    help="set how the runtime turns the octaves with their seeds (solid.json spin) before measuring")
    a = ap.parse_args(argv)
    path = os.path.join(a.folder, "solid.json")
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
        space = doc.get("mode") == "space"
        for key in ("code_harmonics", "code_rests") if space else ("harmonics",):
            doc.pop(key, None)
        if a.spin:
            doc["spin"] = "" if a.spin == "none" else a.spin
        with tempfile.TemporaryDirectory() as tmp:   # the folder as it will be, measured before it is written
            staged = os.path.join(tmp, "model")
            shutil.copytree(a.folder, staged)
            write_model_json(os.path.join(staged, "solid.json"), doc)
            if not a.remove and space:
                doc["code_harmonics"], doc["code_rests"] = measure_codes(staged, a.root)
            elif not a.remove:
                doc["harmonics"] = measure(staged, a.root)
    except (OSError, ValueError, ModelError) as exc:
        print(f"solid harmonics: error: {exc}", file=sys.stderr)
        return 2
    write_model_json(path, doc)
    if space:
        parts, rests = doc.get("code_harmonics", {}), doc.get("code_rests", {})
        print(f"{path}: " + (", ".join(f"{k} {len(h['freq'])} waves ({h['share']:.3f})" for k, h in parts.items())
                             or "no harmonic parts") + "; Gaussian rests: "
              + (", ".join(f"{k} {r['mix']:.2f}" for k, r in rests.items()) or "none"))
        return 0
    h = doc.get("harmonics")
    print(f"{path}: " + (f"{len(h['freq'])} waves, share {h['share']:.3f}" if h else "no harmonic part"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
