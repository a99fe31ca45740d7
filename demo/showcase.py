"""Headless showcase bake: a gallery of wave-noise images into OUT (default out/demo).

Each tile is evaluated by the backend engine and written as an 8-bit PNG and a
float EXR; a contact sheet ``gallery.png`` and ``gallery.json`` (settings and
timings) sit beside them.  Later issues add volumes and neural textures.
"""
from __future__ import annotations

import json
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from omninoise.backend import Spectrum, WaveSettings, compile_noise, evaluate_grid  # noqa: E402
from omninoise.export.images import preview_8bit, write_exr, write_png  # noqa: E402

SIZE, EXTENT = 384, 4.0


def example_image() -> np.ndarray:
    """A synthetic anisotropic exemplar (oriented band-pass noise) for the by-example tile."""
    ang = np.radians(30.0)
    s = WaveSettings(dim=2, spectrum=Spectrum("bandpass", 3, 9), directions=16, seed=99,
                     anisotropy="lobes", lobes=(((np.cos(ang), np.sin(ang)), 1.0), ((0.0, 1.0), 0.5)), spread=8.0)
    return evaluate_grid(compile_noise(s), 256, EXTENT)


GALLERY = [
    ("gaussian_2d", "Gaussian band, 2D", WaveSettings(dim=2, spectrum=Spectrum("gaussian", 3, 9), directions=16)),
    ("fractal_2d", "Fractal 1/f", WaveSettings(dim=2, spectrum=Spectrum("fractal", 1, 24, 1.0), directions=32)),
    ("bandpass_3d", "Band-pass 3D slice", WaveSettings(dim=3, spectrum=Spectrum("bandpass", 4, 6), directions=32)),
    ("ridged_3d", "Modulus (ridged)", WaveSettings(dim=3, spectrum=Spectrum("brown", 1, 12), directions=32,
                                                   output="modulus")),
    ("phasor_2d", "Phase (phasor)", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 4, 5), directions=8,
                                                 output="phase", anisotropy="lobes",
                                                 lobes=(((1.0, 0.3), 1.0),), spread=25.0)),
    ("lobes_2d", "Two anisotropic lobes", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 4, 10), directions=16,
                                                       anisotropy="lobes",
                                                       lobes=(((1.0, 0.0), 1.0), ((0.0, 1.0), 0.6)), spread=10.0)),
    ("axes_3d", "Per-axis tables", WaveSettings(dim=3, directions=32, anisotropy="axes",
                                               axis_spectra=(Spectrum("bandpass", 12, 16), Spectrum("bandpass", 2, 3),
                                                             Spectrum("bandpass", 5, 8)))),
    ("crystal_2d", "Crystal waveform", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 1, 3), directions=6,
                                                    waveform="crystal")),
    ("wired_2d", "Wired waveform", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 1, 2), directions=6,
                                                waveform="wired")),
    ("polytope_2d", "Cellular polytopes", WaveSettings(dim=2, directions=4, cellular="polytope", cell_size=1.5)),
    ("code_2d", "Polytope codes", WaveSettings(dim=2, directions=4, cellular="code", cell_size=1.5)),
    ("stit_2d", "STIT-like cells", WaveSettings(dim=2, directions=3, cellular="stit", cell_size=3.0,
                                                stit_probability=0.6, stit_depth=3)),
    ("example_2d", "By example", None),
    ("transition_2d", "Smooth transition", WaveSettings(dim=2, spectrum=Spectrum("bandpass", 2, 3), directions=32,
                                                        transition_to=Spectrum("bandpass", 10, 14),
                                                        transition_axis=(1.0, 0.0), transition_length=EXTENT)),
    ("animated_t0", "3D+t, t = 0", WaveSettings(dim=3, spectrum=Spectrum("gaussian", 3, 9), directions=16, speed=0.4)),
    ("animated_t1", "3D+t, t = 1", WaveSettings(dim=3, spectrum=Spectrum("gaussian", 3, 9), directions=16, speed=0.4)),
    ("fourd_w0", "4D, W = 0", WaveSettings(dim=4, spectrum=Spectrum("gaussian", 3, 9), directions=48)),
    ("fourd_w05", "4D, W = 0.5", WaveSettings(dim=4, spectrum=Spectrum("gaussian", 3, 9), directions=48)),
]


def main(out: str) -> None:
    os.makedirs(out, exist_ok=True)
    tiles, meta = [], []
    for name, title, s in GALLERY:
        if s is None:
            s = WaveSettings(dim=2, directions=32, example=example_image(), example_extent=EXTENT, sectors=12)
            write_png(os.path.join(out, "example_input.png"), preview_8bit(s.example))
        time_value = {"animated_t1": 1.0, "fourd_w05": 0.5}.get(name, 0.0)
        t0 = time.perf_counter()
        noise = compile_noise(s)
        size = SIZE
        if s.dim == 2:
            img = evaluate_grid(noise, size, EXTENT, s.output, time_value, s.cellular)
        else:  # one z-slice of the volume, evaluated as a 2D cut through 3D / 4D space
            from omninoise.backend.grid import evaluate_points

            g = np.arange(size, dtype=np.float32) * np.float32(EXTENT / size)
            yy, xx = np.meshgrid(g, g, indexing="ij")
            cols = [xx.ravel(), yy.ravel(), np.full(xx.size, 0.5, np.float32)]
            if s.dim == 4:
                cols.append(np.full(xx.size, time_value, np.float32))
            t = 0.0 if s.dim == 4 else time_value
            img = evaluate_points(noise, np.stack(cols, 1), s.output, t, s.cellular).reshape(size, size)
        dt = time.perf_counter() - t0
        lo, hi = (None, None)
        if s.cellular == "polytope":
            lo, hi = 0.0, float(np.percentile(img, 95))
        elif s.cellular in ("code", "stit") or s.output == "phase":
            lo, hi = float(img.min()), float(img.max())
        tile = preview_8bit(img, lo, hi)
        write_png(os.path.join(out, f"{name}.png"), tile)
        write_exr(os.path.join(out, f"{name}.exr"), img)
        tiles.append(tile)
        meta.append(dict(name=name, title=title, seconds=round(dt, 3), dim=s.dim, directions=s.directions,
                         spectrum=s.spectrum.kind, output=s.output, cellular=s.cellular, waveform=s.waveform,
                         anisotropy=s.anisotropy))
        print(f"{name:16s} {dt:6.2f} s  {title}")
    cols = 6
    rows = -(-len(tiles) // cols)
    pad = 6
    sheet = np.full((rows * (SIZE + pad) + pad, cols * (SIZE + pad) + pad), 255, np.uint8)
    for i, t in enumerate(tiles):
        r, c = divmod(i, cols)
        sheet[pad + r * (SIZE + pad): pad + r * (SIZE + pad) + SIZE, pad + c * (SIZE + pad): pad + c * (SIZE + pad) + SIZE] = t
    write_png(os.path.join(out, "gallery.png"), sheet)
    with open(os.path.join(out, "gallery.json"), "w") as fh:
        json.dump(dict(size=SIZE, extent=EXTENT, tiles=meta), fh, indent=1)
    print(f"wrote {len(tiles)} tiles and gallery.png to {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "demo"))
