"""Write the presets the extension ships (blender_addon/presets/omninoise/...) from the backend's own tables.

    python -m tools.make_presets            # rewrite them
    python -m tools.make_presets --check    # exit 1 when a shipped preset differs from what this writes

Transfer functions: backend.transfer.PRESETS. Wave noise: the looks in WAVE below. Neural noise: one swatch of each
class the shipped model was trained on (its parameters at the middle of their ranges), and a few blends. Solid
textures: how a photo of each kind of material in SOLID below becomes a solid (the method and the procedural kinds).
The files are what Blender's own preset operators write (``bpy.utils.execfile`` runs them), so an artist's presets
and these sit side by side in the same menus.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from omninoise.backend.paths import neural_model
from omninoise.backend.transfer import PRESETS, preset
from omninoise.blender_addon.presets import NEURAL_VALUES, SOLID_VALUES, WAVE_VALUES, transfer_preset_text

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDER = os.path.join(ROOT, "blender_addon", "presets", "omninoise")

#: wave looks: the values a wave preset sets (WAVE_VALUES), by file name
WAVE_BASE = dict(dimensions="3", directions=16, spectrum="gaussian", fmin=2.0, fmax=8.0, exponent=1.0,
                 waveform="gaussian", anisotropy="none", axis=(1.0, 0.0, 0.0), spread=20.0,
                 axis_scale=(1.0, 2.0, 0.5), speed=0.0)
WAVE = {
    "clouds": dict(spectrum="fractal", fmin=0.5, fmax=12.0, exponent=1.2),
    "marble_veins": dict(spectrum="fractal", fmin=1.0, fmax=6.0, exponent=1.5, waveform="wired"),
    "wood_rings": dict(spectrum="gaussian", fmin=3.0, fmax=5.0, anisotropy="lobes", axis=(1.0, 0.0, 0.0), spread=6.0),
    "cells": dict(spectrum="gaussian", fmin=2.0, fmax=5.0, waveform="crystal", directions=24),
    "fine_grain": dict(spectrum="bandpass", fmin=12.0, fmax=24.0, directions=24),
    "stretched": dict(anisotropy="axes", axis_scale=(1.0, 4.0, 1.0)),
    "rolling_hills": dict(spectrum="brown", fmin=0.5, fmax=4.0),
    "flowing_water": dict(spectrum="fractal", fmin=1.0, fmax=8.0, exponent=1.0, speed=0.5),
}
PALETTE = [(1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (1.0, 1.0, 0.0)]
NEURAL_SETTINGS = dict(width=32.0, sharpness=1.0, sampler="dpmpp_2m", steps=10, tileable=False)
#: blends of the shipped classes: name -> (layout, classes)
BLENDS = {"blend_cells_to_perlin": ("GRADIENT", ["cells_f1", "perlin"]),
          "blend_four_corners": ("CORNERS", ["cells_f1", "perlin", "spots", "damascus"])}

#: solid texture presets: the values a solid preset sets (SOLID_VALUES), by file name. The procedural kinds where
#: the fit, left to choose, often draws another material's look (stones on a brick wall, docs/guide/blender.md)
SOLID_BASE = dict(source="IMAGE", method="PROCEDURAL", families={"RINGS", "LAYERS", "CELLS", "BONDS"}, refine=0,
                  periodic=True, gaussian=True, rest="auto", tile=256)
SOLID = {
    "best_match": dict(method="AUTO"),
    "neural_texture": dict(method="NEURAL"),
    "rock_sand_soil": dict(method="SPECTRAL"),
    "brick_wall_or_tiles": dict(families={"BONDS"}),
    "herringbone_floor": dict(families={"HERRINGBONE"}),
    "wood": dict(families={"RINGS", "LAYERS"}),
    "veined_marble": dict(families={"LAYERS"}),
    "stones_and_paving": dict(families={"CELLS"}),
}


def _literal(v) -> str:
    """repr, with a set's items sorted (a preset file is compared as text)."""
    return "{" + ", ".join(repr(x) for x in sorted(v)) + "}" if isinstance(v, (set, frozenset)) else repr(v)


def values_text(define: str, paths: list, values: dict) -> str:
    """A preset file that sets each of ``paths`` ("name.attribute") to ``values[attribute]``, after ``define``."""
    lines = ["import bpy", define, ""] + [f"{path} = {_literal(values[path.split('.')[1]])}" for path in paths]
    return "\n".join(lines) + "\n"


def solid_text(look: dict) -> str:
    return values_text("p = bpy.context.scene.omninoise_solid", SOLID_VALUES, dict(SOLID_BASE, **look))


def wave_text(look: dict) -> str:
    return values_text("props = bpy.context.omninoise_wave", WAVE_VALUES, dict(WAVE_BASE, **look))


def neural_text(layout: str, classes: list, class_params: dict) -> str:
    lines = ["import bpy", "p = bpy.context.scene.omninoise_neural", "", "p.swatches.clear()"]
    for i, name in enumerate(classes):
        lines += ["item_sub_1 = p.swatches.add()", "item_sub_1.name = ''", f"item_sub_1.noise = {name!r}"]
        params = class_params[name]["params"][:4]
        for j in range(4):
            value = 0.5 * (params[j]["min"] + params[j]["max"]) if j < len(params) else 0.0
            lines.append(f"item_sub_1.p{j} = {float(value)!r}")
        lines.append(f"item_sub_1.color = {PALETTE[i % len(PALETTE)]!r}")
    lines.append(f"p.mode = {layout!r}")
    lines += [f"{path} = {NEURAL_SETTINGS[path.split('.')[1]]!r}" for path in NEURAL_VALUES[2:]]
    return "\n".join(lines) + "\n"


def presets() -> dict:
    """{path relative to FOLDER: text} of every shipped preset."""
    with open(os.path.join(neural_model(), "neural_noise.json"), encoding="utf-8") as fh:
        config = json.load(fh)
    out = {f"transfer/{name}.py": transfer_preset_text(preset(name)) for name in PRESETS}
    out.update({f"wave/{name}.py": wave_text(look) for name, look in WAVE.items()})
    out.update({f"neural/{name}.py": neural_text("SINGLE", [name], config["class_params"])
                for name in config["trained_classes"]})
    out.update({f"neural/{name}.py": neural_text(layout, classes, config["class_params"])
                for name, (layout, classes) in BLENDS.items()})
    out.update({f"solid/{name}.py": solid_text(look) for name, look in SOLID.items()})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when a shipped preset is out of date")
    a = ap.parse_args(argv)
    want = presets()
    have = {os.path.relpath(os.path.join(d, f), FOLDER).replace(os.sep, "/"): open(os.path.join(d, f), encoding="utf-8").read()
            for d, _, fs in os.walk(FOLDER) for f in fs if f.endswith(".py")} if os.path.isdir(FOLDER) else {}
    if a.check:
        stale = sorted(set(want) ^ set(have) | {k for k in want if have.get(k) != want[k]})
        print("presets up to date" if not stale else "presets out of date: " + ", ".join(stale))
        return 0 if not stale else 1
    for rel in set(have) - set(want):
        os.remove(os.path.join(FOLDER, rel))
    for rel, text in want.items():
        path = os.path.join(FOLDER, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path + ".tmp", "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(path + ".tmp", path)
    print(f"wrote {len(want)} presets under {os.path.relpath(FOLDER, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
