"""The training zoo itself at 256²: `python -m bench sheet-zoo OUT.png [--size 256] [--seed 0]`.

Every class at its default parameters (what the model is asked to reproduce), labelled, with the orientation
coherence of each image (1 = one orientation over the whole image): the check that the zoo shows
each class's structure at full size before the model is blamed for losing it.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np


from omninoise.export.atomic import atomic_path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--columns", type=int, default=6)
    a = ap.parse_args(argv)
    import torch
    from PIL import Image, ImageDraw

    from omninoise.training import zoo
    from omninoise.training.evaluate import orientation_coherence

    S, cols, label_h, gap = a.size, a.columns, 14, 4
    names = list(zoo.CLASS_NAMES)
    rows = -(-len(names) // cols)
    sheet = Image.new("L", (cols * (S + gap), rows * (S + label_h + gap)), 255)
    draw = ImageDraw.Draw(sheet)
    for i, name in enumerate(names):
        img = zoo.generate(name, zoo.default_params(name), torch.tensor([a.seed]), S)[0].numpy()
        coh = float(orientation_coherence(img[None])[0])
        x, y = (i % cols) * (S + gap), (i // cols) * (S + label_h + gap)
        sheet.paste(Image.fromarray((np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8)), (x, y + label_h))
        draw.text((x + 2, y + 1), f"{name}  coh {coh:.2f}", fill=0)
    with atomic_path(a.out) as tmp:
        sheet.save(tmp, format="PNG")
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
