"""Exemplars for the neural solid textures: shipped photographs and procedural classes.

Photographs (``data/exemplars/{brick,grass,gravel}.png``): the CC0 texture
photographs that scikit-image ships (brick and gravel from CC0Textures, grass
from DeviantArt user linolafett; see ``data/exemplars/README.md``).  They are
greyscale; the model still outputs RGB.

Procedural classes (wood rings, marble veins, rust, granite) are generated
here from the noise zoo's operators, in colour, at any seed:
``python -m omninoise.training.solid.exemplars OUT_DIR`` writes the shipped
ones (seed 0 for training, seed 1 held out).

Held-out split: for the photographs, the right quarter (columns >= 3/4 of
the width) is held out and never cropped for training; for procedural
classes, seed 1 is held out.

Images are float32 (3, H, W) in [0, 1] (sRGB-encoded values, as in the files).
"""
from __future__ import annotations

import functools
import math
import os
import sys

import numpy as np
import torch

from omninoise import export as _export
from .. import noise_ops as ops
from .photo_set import PHOTO_DIR, expand, photo_set

__all__ = ["PHOTO_DIR", "expand", "photo_set", "PHOTOS", "PROCEDURAL", "DATA_DIR", "load_image", "procedural", "exemplar", "train_region",
           "heldout_region", "random_crops"]

DATA_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "data", "exemplars")
PHOTOS = ("brick", "grass", "gravel")
PROCEDURAL = ("wood", "marble", "rust", "granite")


def load_image(path: str) -> torch.Tensor:
    """An image file -> float32 (3, H, W) in [0, 1]; greyscale is repeated to RGB, alpha dropped."""
    from PIL import Image
    with Image.open(path) as im:
        a = np.asarray(im.convert("RGB"), dtype=np.float32) / 255.0
    return torch.from_numpy(a).permute(2, 0, 1).contiguous()


def _ramp(v: torch.Tensor, stops) -> torch.Tensor:
    """Piecewise-linear colour ramp: v (H, W) in [0, 1], stops [(pos, (r, g, b)), ...] -> (3, H, W)."""
    pos = torch.tensor([s[0] for s in stops])
    col = torch.tensor([s[1] for s in stops], dtype=torch.float32)
    v = v.clamp(0, 1)
    idx = torch.clamp(torch.searchsorted(pos, v.contiguous(), right=True), 1, len(stops) - 1)
    t = ((v - pos[idx - 1]) / (pos[idx] - pos[idx - 1]).clamp_min(1e-6)).clamp(0, 1)
    return (col[idx - 1] * (1 - t.unsqueeze(-1)) + col[idx] * t.unsqueeze(-1)).permute(2, 0, 1)


def procedural(name: str, seed: int, size: int = 512) -> torch.Tensor:
    """A procedural exemplar of class ``name`` (one of :data:`PROCEDURAL`): float32 (3, size, size)."""
    return _procedural(name, int(seed), int(size)).clone()


@functools.lru_cache(maxsize=16)
def _procedural(name: str, seed: int, size: int) -> torch.Tensor:
    s = torch.tensor([seed], dtype=torch.int64)
    x, y = ops.grid(1, size, torch.tensor([[seed * 37.0, seed * 11.0]]), 128.0)
    r = torch.tensor([0.5])
    if name == "wood":      # growth rings of a plank cut along the trunk: stripes warped by low-frequency noise
        w = x + 0.35 * ops.fbm(x * 0.6, y * 0.15, s, 4, r, salt=1)
        ring = torch.frac(w * 2.2 + 0.15 * ops.fbm(x * 4, y * 0.4, s, 3, r, salt=2))
        grain = ops.fbm(x * 24.0, y * 1.5, s, 3, r, salt=3)
        v = ring ** 3 * 0.75 + 0.12 * grain + 0.1
        img = _ramp(v[0], [(0.0, (0.80, 0.60, 0.38)), (0.45, (0.62, 0.40, 0.22)), (1.0, (0.33, 0.18, 0.08))])
    elif name == "marble":  # veins: |sin| of a turbulent phase
        turb = ops.fbm(x * 1.2, y * 1.2, s, 6, torch.tensor([0.55]), salt=4)
        v = torch.abs(torch.sin(2 * math.pi * (0.9 * (x + 0.4 * y) + 1.8 * turb))) ** 0.35
        cloud = ops.fbm(x * 3.0, y * 3.0, s, 4, r, salt=5)
        img = _ramp((v * 0.85 + 0.15 * (cloud + 0.5))[0],
                    [(0.0, (0.25, 0.27, 0.30)), (0.35, (0.62, 0.64, 0.66)), (0.7, (0.90, 0.90, 0.88)),
                     (1.0, (0.97, 0.96, 0.94))])
    elif name == "rust":    # blotches of rust over grey steel with fine pitting
        base = ops.normalise(ops.fbm(x * 3.0, y * 3.0, s, 6, torch.tensor([0.6])))
        blotch = torch.sigmoid((base - 0.45) * 18.0)
        fine = ops.fbm(x * 24.0, y * 24.0, s, 3, torch.tensor([0.6]), salt=91)
        v = blotch * (0.75 + 0.5 * fine)
        img = _ramp(v[0], [(0.0, (0.42, 0.43, 0.45)), (0.25, (0.35, 0.28, 0.24)), (0.6, (0.58, 0.27, 0.10)),
                           (1.0, (0.78, 0.45, 0.20))])
    elif name == "granite":  # crystals (Worley cells, three minerals) with speckle
        _, _, cell = ops.worley(x * 14.0, y * 14.0, s, torch.tensor([1.0]), salt=6)
        f1, f2, _ = ops.worley(x * 14.0, y * 14.0, s, torch.tensor([1.0]), salt=6)
        speck = ops.hash_unit(torch.floor(x * 128).long(), torch.floor(y * 128).long(), s.view(-1, 1, 1), 7)
        edge = torch.clamp((f2 - f1) * 6.0, 0, 1)
        v = (cell * 0.85 + 0.15 * speck) * (0.6 + 0.4 * edge)
        img = _ramp(v[0], [(0.0, (0.08, 0.08, 0.09)), (0.3, (0.30, 0.29, 0.30)), (0.55, (0.72, 0.66, 0.64)),
                           (0.8, (0.86, 0.74, 0.70)), (1.0, (0.95, 0.93, 0.92))])
    else:
        raise ValueError(f"unknown procedural exemplar {name!r}; choose from {', '.join(PROCEDURAL)}")
    return img.clamp(0, 1).to(torch.float32)


def exemplar(name: str, data_dir: str | None = None) -> torch.Tensor:
    """A shipped exemplar by name (photo or procedural, seed 0), or any image path: (3, H, W)."""
    if name in PROCEDURAL:
        return procedural(name, 0)
    if name in PHOTOS:
        return load_image(os.path.join(data_dir or DATA_DIR, f"{name}.png"))
    if os.path.isfile(name):
        return load_image(name)
    raise ValueError(f"unknown exemplar {name!r}: not a file and not one of {', '.join(PHOTOS + PROCEDURAL)}")


def train_region(img: torch.Tensor, name: str, hold_out: bool = False) -> torch.Tensor:
    """The part of an exemplar that training may crop: all but the right quarter of a shipped photo, or of
    any photo when ``hold_out`` (a single-exemplar model's own held-out pixels, :func:`heldout_region`);
    other images whole."""
    return img[:, :, : img.shape[2] * 3 // 4] if name in PHOTOS or (hold_out and name not in PROCEDURAL) else img


def heldout_region(name: str, data_dir: str | None = None) -> torch.Tensor:
    """Held-out pixels: the photo's right quarter, or the procedural class at seed 1."""
    if name in PROCEDURAL:
        return procedural(name, 1)
    img = exemplar(name, data_dir)
    return img[:, :, img.shape[2] * 3 // 4:]


def random_crops(img: torch.Tensor, batch: int, size: int, generator: torch.Generator, augment: bool = False):
    """Random (B, 3, size, size) crops; ``augment`` adds the 8 rotations/flips (for isotropic 3D training)."""
    _, H, W = img.shape
    if H < size or W < size:
        raise ValueError(f"exemplar of {W}x{H} px is smaller than the {size} px training crop")
    out = []
    for _ in range(batch):
        i = int(torch.randint(0, H - size + 1, (1,), generator=generator))
        j = int(torch.randint(0, W - size + 1, (1,), generator=generator))
        c = img[:, i:i + size, j:j + size]
        if augment:
            k = int(torch.randint(0, 8, (1,), generator=generator))
            c = torch.rot90(c, k % 4, dims=(1, 2))
            if k >= 4:
                c = torch.flip(c, dims=(2,))
        out.append(c)
    return torch.stack(out)


def main(argv=None) -> int:
    out = (argv or sys.argv[1:] or [DATA_DIR])[0]
    from PIL import Image
    os.makedirs(out, exist_ok=True)
    for name in PROCEDURAL:
        a = (procedural(name, 0).permute(1, 2, 0).numpy() * 255.0 + 0.5).astype(np.uint8)
        path = os.path.join(out, f"{name}.png")
        with _export.atomic_path(path) as tmp:
            Image.fromarray(a).save(tmp, format="PNG")
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
