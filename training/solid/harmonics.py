"""Store a single photo model's harmonic part: ``python -m training.solid.harmonics MODEL_DIR [--remove]``.

The texture-space model measures a photo's harmonic part when it encodes it (``backend/solid/harmonic.py``).
A single-exemplar photo model has no encoder, so its part is measured here, once, from the pixels it was trained
on: its exemplar's training region (all but the right quarter when the model was trained with ``hold_out``,
``training.solid.exemplars.train_region``), read as the evaluation reads it, at the model's own scale.  It is
written into the folder's solid.json as ``harmonics`` (``backend.solid.harmonic.to_json``), which the runtime
adds to the model's texture; ``--remove`` takes it out.  Nothing is trained and the ONNX files are unchanged.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from backend._export import export as _ex
from backend.onnx_models import ModelError
from backend.solid.harmonic import to_json
from backend.solid.model import SolidTextureModel

__all__ = ["measure", "main"]


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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m training.solid.harmonics", description=__doc__.split("\n")[0])
    ap.add_argument("folder", help="a single photo model's folder (holds solid.json)")
    ap.add_argument("--remove", action="store_true", help="take the stored harmonic part out")
    ap.add_argument("--root", default=".", help="where the exemplar paths in solid.json start")
    a = ap.parse_args(argv)
    path = os.path.join(a.folder, "solid.json")
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
        doc.pop("harmonics", None)
        if not a.remove:
            doc["harmonics"] = measure(a.folder, a.root)
    except (OSError, ValueError, ModelError) as exc:
        print(f"solid harmonics: error: {exc}", file=sys.stderr)
        return 2
    _ex.write_json(path, doc)
    h = doc.get("harmonics")
    print(f"{path}: " + (f"{len(h['freq'])} waves, share {h['share']:.3f}" if h else "no harmonic part"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
