"""``omninoise`` command line (also ``python -m backend``).

Command-line only: imports the ``export`` package for file output, which the
add-on reaches through its own relative imports instead.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

from .errors import SettingError
from .grid import evaluate_grid
from .spectra import SPECTRUM_KINDS, Spectrum
from .settings import WaveSettings, compile_noise
from .cellular import CELLULAR_MODES
from .tables import WAVEFORMS
from .wave import OUTPUTS

__all__ = ["main", "build_parser", "settings_from_args"]


def _spectrum_arg(text: str) -> Spectrum:
    """'kind:fmin:fmax[:exponent]' -> Spectrum."""
    parts = text.split(":")
    try:
        kind, fmin, fmax = parts[0], float(parts[1]), float(parts[2])
        exponent = float(parts[3]) if len(parts) > 3 else 1.0
    except (IndexError, ValueError):
        raise argparse.ArgumentTypeError(f"expected kind:fmin:fmax[:exponent], got {text!r}") from None
    return Spectrum(kind, fmin, fmax, exponent)


def _lobe_arg(text: str) -> tuple:
    """'x,y[,z[,w]]:weight' -> ((axis...), weight)."""
    axis, _, weight = text.partition(":")
    try:
        return tuple(float(v) for v in axis.split(",")), float(weight or 1.0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y[,z]:weight, got {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="omninoise", description="OmniNoise: wave noise and neural noise bakes.")
    sub = ap.add_subparsers(dest="command", required=True)
    w = sub.add_parser("wave", help="evaluate wave noise (Guehl et al. 2025) on a grid")
    w.add_argument("--dim", type=int, choices=(2, 3, 4), default=2)
    w.add_argument("--size", type=int, default=512, help="samples per axis (N)")
    w.add_argument("--extent", type=float, default=4.0, help="grid spans [0, E) in every dimension")
    w.add_argument("--time", type=float, default=0.0, help="animation time, or W for --dim 4")
    w.add_argument("--speed", type=float, default=0.0, help="wave speed (units per unit time); animated noise")
    w.add_argument("--spectrum", choices=[k for k in SPECTRUM_KINDS if k != "custom"], default="gaussian")
    w.add_argument("--fmin", type=float, default=4.0, help="band low, cycles per unit")
    w.add_argument("--fmax", type=float, default=8.0, help="band high, cycles per unit")
    w.add_argument("--exponent", type=float, default=1.0, help="fractal amplitude exponent (A ~ f^-n)")
    w.add_argument("--directions", type=int, default=16)
    w.add_argument("--output", choices=OUTPUTS, default="real")
    w.add_argument("--waveform", choices=[x for x in WAVEFORMS if x != "custom"] + ["custom"], default="gaussian")
    w.add_argument("--profile", help="custom waveform: .npy or text file with a 1D profile")
    w.add_argument("--cellular", choices=CELLULAR_MODES, default="none")
    w.add_argument("--cell-size", type=float)
    w.add_argument("--stit-probability", type=float, default=0.5)
    w.add_argument("--stit-depth", type=int, default=3)
    w.add_argument("--anisotropy", choices=("none", "axes", "lobes"), default="none")
    w.add_argument("--axis-spectrum", type=_spectrum_arg, action="append", default=[],
                   help="per-axis spectrum kind:fmin:fmax (repeat once per axis)")
    w.add_argument("--lobe", type=_lobe_arg, action="append", default=[], help="lobe axis and weight x,y[,z]:w")
    w.add_argument("--spread", type=float, default=20.0, help="lobe / plane band half-angle, degrees")
    w.add_argument("--example", help="grayscale exemplar image (by-example noise)")
    w.add_argument("--example-plane", choices=("xy", "xz", "yz"), default="xy")
    w.add_argument("--example-extent", type=float, help="world units across the exemplar (default: --extent)")
    w.add_argument("--sectors", type=int, default=8)
    w.add_argument("--transition", type=_spectrum_arg, help="blend towards kind:fmin:fmax along x")
    w.add_argument("--transition-length", type=float)
    w.add_argument("--slice-width", type=float)
    w.add_argument("--table-size", type=int, default=1024)
    w.add_argument("--period", type=float, help="table period in world units (default: 255 / fmax)")
    w.add_argument("--seed", type=int, default=0)
    w.add_argument("--quiet", action="store_true")
    w.add_argument("-o", "--out", required=True, help="output: .npy (raw float32), .exr or .png (2D)")
    return ap


def settings_from_args(a: argparse.Namespace) -> WaveSettings:
    if a.directions < 1:
        raise SettingError("--directions", f"must be at least 1, got {a.directions}")
    if a.fmin > a.fmax:
        raise SettingError("--fmin", f"{a.fmin:g} is greater than --fmax {a.fmax:g}")
    example = None
    if a.example:
        if not os.path.isfile(a.example):
            raise SettingError("--example", f"image not found: {a.example}")
        from export.images import read_image

        example = read_image(a.example)
    profile = ()
    if a.waveform == "custom":
        if not a.profile:
            raise SettingError("--profile", "--waveform custom needs --profile FILE")
        if not os.path.isfile(a.profile):
            raise SettingError("--profile", f"file not found: {a.profile}")
        prof = np.load(a.profile) if a.profile.endswith(".npy") else np.loadtxt(a.profile)
        profile = tuple(np.asarray(prof, np.float64).ravel())
    return WaveSettings(
        dim=a.dim, spectrum=Spectrum(a.spectrum, a.fmin, a.fmax, a.exponent), directions=a.directions,
        seed=a.seed, output=a.output, speed=a.speed, slice_width=a.slice_width, waveform=a.waveform,
        profile=profile, cellular=a.cellular, cell_size=a.cell_size, stit_probability=a.stit_probability,
        stit_depth=a.stit_depth, anisotropy=a.anisotropy, axis_spectra=tuple(a.axis_spectrum),
        lobes=tuple(a.lobe), spread=a.spread, example=example, example_plane=a.example_plane,
        example_extent=a.example_extent or a.extent, sectors=a.sectors, transition_to=a.transition,
        transition_length=a.transition_length or a.extent, table_size=a.table_size, table_period=a.period)


class _Bar:
    def __init__(self, quiet: bool):
        self.quiet, self.t0 = quiet, time.perf_counter()

    def __call__(self, frac: float) -> None:
        if self.quiet:
            return
        n = int(frac * 30)
        sys.stderr.write(f"\r[{'#' * n}{'.' * (30 - n)}] {frac * 100:5.1f}%  {time.perf_counter() - self.t0:6.1f}s")
        if frac >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def run_wave(a: argparse.Namespace) -> int:
    from export.images import write_image

    ext = os.path.splitext(a.out)[1].lower()
    if ext not in (".npy", ".exr", ".png"):
        raise SettingError("-o", f"unsupported output type {ext or a.out!r}; use .npy, .exr or .png")
    if a.dim > 2 and ext != ".npy":
        raise SettingError("-o", f"a {a.dim}D grid is a volume; write it as .npy")
    if a.size < 1:
        raise SettingError("--size", f"must be >= 1, got {a.size}")
    folder = os.path.dirname(os.path.abspath(a.out))
    if not os.path.isdir(folder):
        raise SettingError("-o", f"output folder does not exist: {folder}")
    s = settings_from_args(a)
    nyq = a.size / (2.0 * a.extent)
    if a.fmax > nyq and a.cellular == "none" and not a.quiet:
        print(f"omninoise wave: warning: --fmax {a.fmax:g} is above the grid's Nyquist {nyq:g}; "
              "the image will alias", file=sys.stderr)
    noise = compile_noise(s)
    arr = evaluate_grid(noise, a.size, a.extent, s.output, a.time, s.cellular, progress=_Bar(a.quiet))
    write_image(a.out, arr)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    a = ap.parse_args(argv)
    try:
        if a.command == "wave":
            return run_wave(a)
    except (SettingError, FileNotFoundError, PermissionError) as exc:
        print(f"omninoise {a.command}: error: {exc}", file=sys.stderr)
        return 2
    return 1
