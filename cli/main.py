"""``omninoise`` command line (also ``python -m cli``).

Command-line only: imports the ``export`` package for file output, which the
add-on reaches through its own relative imports instead.
"""
from __future__ import annotations

import argparse
import os
import warnings
import sys
import time

import numpy as np

from omninoise.export.images import ImageError
from omninoise.cli import hugepages
from omninoise.backend import limits
from omninoise.backend.errors import SettingError
from omninoise.backend.neural.precision import PRECISIONS
from omninoise.backend.wavenoise.spectra import SPECTRUM_KINDS, Spectrum
from omninoise.backend.paths import neural_model
from omninoise.backend.wavenoise.settings import WaveSettings
from omninoise.backend.wavenoise.cellular import CELLULAR_MODES
from omninoise.backend.wavenoise.tables import WAVEFORMS
from omninoise.backend.transfer import PRESETS, load_transfer
from omninoise.backend.wavenoise.wave import OUTPUTS

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


def _version_line() -> str:
    from omninoise.backend.version import __version__
    from omninoise.backend.wavenoise.fast import engine_path

    return f"omninoise {__version__} (wave noise: {engine_path()})"


class _Version(argparse.Action):
    """``--version``: the line of :func:`_version_line`, made only when asked for (finding the wave kernel loads
    the C library, which no other option needs at start-up)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_version_line())      # on standard output, as argparse's own version action prints
        parser.exit()


class _Help(argparse.RawDescriptionHelpFormatter):
    """Each option's default after its help (unless it has none, is a switch, or the help names it already);
    descriptions and examples kept as written."""

    def _get_help_string(self, action):
        text = action.help or ""
        d = action.default
        if d is None or isinstance(d, bool) or d == [] or d is argparse.SUPPRESS or "default" in text:
            return text
        if action.option_strings or action.nargs in (argparse.OPTIONAL, argparse.ZERO_OR_MORE):
            return text + " (default: %(default)s)"
        return text


def _sub(sub, name: str, help: str, description: str, examples: str):
    return sub.add_parser(name, help=help, description=description, formatter_class=_Help,
                          epilog="examples:\n" + "\n".join("  " + ln for ln in examples.strip().splitlines()))


def _class_args(g) -> None:
    """The options of one noise class image, shared by ``neural`` and ``zoo``."""
    g.add_argument("--noise", help="class name (see --list)")
    g.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="a class parameter (repeat)")
    g.add_argument("--size", type=int, default=256, help="output side in pixels")
    g.add_argument("--seed", type=int, default=0, help="another seed draws another image")
    g.add_argument("-o", "--out", help="output: .png, .exr or .npy")
    g.add_argument("--list", action="store_true", help="print the classes and their parameters as JSON")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="omninoise", formatter_class=_Help,
        description="OmniNoise: wave noise, neural noise and solid textures from photos, as images, arrays and "
                    "volumes.",
        epilog="Run 'omninoise SUBCOMMAND --help' for each subcommand's options and examples. Exit status: 0 done, "
               "2 bad input (one line naming the option), 1 a failure while running, 130 interrupted.")
    ap.add_argument("--version", action=_Version, help="print the version and the wave kernel in use, then exit")
    ap.add_argument("--debug", action="store_true",
                    help="show the Python traceback of an internal error instead of one line")
    sub = ap.add_subparsers(dest="command", required=True, metavar="SUBCOMMAND")

    w = _sub(sub, "wave", "wave noise on a grid",
             "Wave noise (Guehl et al. 2025): a sum of randomly oriented waves read from 1D tables, in 2D, 3D or 4D, "
             "still or animated, written as an array, an image or a volume. The grid has --size samples per axis "
             "over [0, --extent); frequencies are in cycles per unit.",
             """omninoise wave --size 512 --spectrum bandpass --fmin 4 --fmax 8 -o band.png
omninoise wave --dim 3 --size 128 --fmin 1 --fmax 6 --transfer clouds -o clouds.vdb
omninoise wave --dim 3 --size 128 --speed 0.5 --time 2.0 -o frame.npy
omninoise wave --size 512 --cellular stit --stit-depth 3 -o cracks.png""")
    g = w.add_argument_group("grid and output")
    g.add_argument("-o", "--out", required=True,
                   help="output: .npy (raw float32), .exr or .png (2D), .vdb (3D: density [+ color])")
    g.add_argument("--dim", type=int, choices=(2, 3, 4), default=2, help="dimensions of the noise")
    g.add_argument("--size", type=int, default=512, help="samples per axis")
    g.add_argument("--extent", type=float, default=4.0, help="the grid spans [0, EXTENT) in every dimension")
    g.add_argument("--time", type=float, default=0.0, help="animation time, or the coordinate W of 4D noise")
    g.add_argument("--speed", type=float, default=0.0, help="wave speed in units per unit time (animated noise)")
    g.add_argument("--output", choices=OUTPUTS, default="real", help="which part of the complex noise")
    g.add_argument("--transfer", help="an RGBA ramp: a preset (%s) or a ramp .json; colours .exr and .png, adds "
                                      "color (and temperature) grids to .vdb" % ", ".join(PRESETS))
    g.add_argument("--range", type=float, nargs=2, metavar=("V0", "V1"),
                   help="noise values mapped to the ramp's ends (default: the ramp's own)")
    g.add_argument("--half", action="store_true", help="16-bit half floats (.exr and .vdb)")
    g.add_argument("--seed", type=int, default=0, help="another seed draws other directions and phases")
    g.add_argument("--quiet", action="store_true", help="no progress bar or notes")
    g = w.add_argument_group("spectrum")
    g.add_argument("--spectrum", choices=[k for k in SPECTRUM_KINDS if k != "custom"], default="gaussian",
                   help="amplitude profile over the band")
    g.add_argument("--fmin", type=float, default=2.0, help="band low, cycles per unit")
    g.add_argument("--fmax", type=float, default=8.0, help="band high, cycles per unit")
    g.add_argument("--exponent", type=float, default=1.0, help="fractal amplitude exponent (A ~ f^-n)")
    g.add_argument("--directions", type=int, default=16, help="wave directions summed (more: smoother, slower)")
    g = w.add_argument_group("waveform and cells")
    g.add_argument("--waveform", choices=[x for x in WAVEFORMS if x != "custom"] + ["custom"], default="gaussian",
                   help="the profile of each wave")
    g.add_argument("--profile", help="--waveform custom: a .npy or text file with a 1D profile")
    g.add_argument("--cellular", choices=CELLULAR_MODES, default="none", help="cellular variant")
    g.add_argument("--cell-size", type=float, help="cellular: cell size in units (default: from the band)")
    g.add_argument("--stit-probability", type=float, default=0.5, help="--cellular stit: split probability")
    g.add_argument("--stit-depth", type=int, default=3, help="--cellular stit: split depth")
    g = w.add_argument_group("anisotropy")
    g.add_argument("--anisotropy", choices=("none", "axes", "lobes"), default="none",
                   help="axes: a spectrum per axis; lobes: directions gathered around axes")
    g.add_argument("--axis-spectrum", type=_spectrum_arg, action="append", default=[], metavar="KIND:FMIN:FMAX",
                   help="--anisotropy axes: one per axis, in order")
    g.add_argument("--lobe", type=_lobe_arg, action="append", default=[], metavar="X,Y[,Z]:WEIGHT",
                   help="--anisotropy lobes: a lobe's axis and weight (repeat)")
    g.add_argument("--spread", type=float, default=20.0, help="lobe or plane band half-angle, degrees")
    g = w.add_argument_group("by example and transitions")
    g.add_argument("--example", help="a grayscale image whose spectrum the noise takes")
    g.add_argument("--example-plane", choices=("xy", "xz", "yz"), default="xy", help="the plane the image lies in")
    g.add_argument("--example-extent", type=float, help="world units across the image (default: --extent)")
    g.add_argument("--sectors", type=int, default=8, help="angular sectors read from the image's spectrum")
    g.add_argument("--transition", type=_spectrum_arg, metavar="KIND:FMIN:FMAX",
                   help="blend towards this spectrum along x")
    g.add_argument("--transition-length", type=float, help="units over which the blend runs (default: --extent)")
    g = w.add_argument_group("tables")
    g.add_argument("--slice-width", type=float, help="width of a direction's slices in units (default: from the band)")
    g.add_argument("--table-size", type=int, default=1024, help="samples per wave table")
    g.add_argument("--period", type=float, help="table period in units (default: 255 / fmax)")

    b = _sub(sub, "bake", "run the bakes of a TOML job file",
             "Run every bake of a job file (TOML): wave, neural and solid sources into .vdb, .exr, .png and .npy "
             "files, numbered sequences included. Outputs that are up to date are skipped. Every bake is checked "
             "before any runs. The job-file reference is in docs/guide/jobs.md.",
             """omninoise bake job.toml
omninoise bake job.toml --only clouds --force
omninoise bake job.toml --dry-run
omninoise bake job.toml --workers 4""")
    b.add_argument("job", help="job file (.toml)")
    b.add_argument("--only", action="append", metavar="NAME", help="bake only these (repeatable)")
    b.add_argument("--force", action="store_true", help="re-bake outputs that are up to date")
    b.add_argument("--keep-going", action="store_true", help="after a failed bake, carry on with the others")
    b.add_argument("--dry-run", action="store_true", help="check the job and list what would be baked")
    b.add_argument("--threads", type=int, default=0, help="CPU threads for the neural models (0: all cores)")
    b.add_argument("--precision", default="fp32", choices=PRECISIONS,
                   help="neural noise arithmetic (int8: a faster draft on CPUs with int8 dot products)")
    b.add_argument("--quiet", action="store_true", help="no progress bars")
    farm = b.add_argument_group("farm (Dask; pip install 'omninoise[farm]')")
    farm.add_argument("--workers", type=int, metavar="N", help="bake on a local cluster of N worker processes")
    farm.add_argument("--cluster", metavar="ADDRESS", help="bake on a running Dask scheduler (tcp:// or tls://)")
    farm.add_argument("--retries", type=int, default=2, help="runs of a failed task after the first")
    farm.add_argument("--brick-voxels", type=int, help="voxels per brick of a large volume (default: from the "
                                                       "workers' memory)")
    farm.add_argument("--tls-ca-file", help="tls://: the CA certificate")
    farm.add_argument("--tls-cert", help="tls://: this client's certificate")
    farm.add_argument("--tls-key", help="tls://: this client's private key")

    n = _sub(sub, "neural", "neural noise from the trained diffusion model",
             "Neural noise (Maesumi et al. 2024): one diffusion model for 23 noise classes and their blends, at "
             "any size, on the CPU. One class, a blend through a mask, four corners or a painted map; animated "
             "between keyframes; or fitted to an image.",
             """omninoise neural --list
omninoise neural --noise cells_f1 --param scale=12 --size 256 --seed 7 --tileable -o cells.png
omninoise neural --noise cells_f1 --blend mask.png --noise2 noise --size 256 -o blend.png
omninoise neural --map painted.png --region '#ff0000=spots' --region '#0000ff=gabor' -o map.png
omninoise neural --keys anim.toml --frames 1 48 --latent slerp -o morph_####.png
omninoise neural --fit photo.jpg --report fit.json -o fitted.png""")
    g = n.add_argument_group("noise and output")
    _class_args(g)
    g.add_argument("--tileable", action="store_true", help="a seamless tile (size a multiple of 8)")
    g.add_argument("--model", help="another model folder (default: the shipped model)")
    g.add_argument("--quiet", action="store_true", help="no progress bar")
    g = n.add_argument_group("blends")
    g.add_argument("--blend", metavar="MASK", help="a grayscale mask image: white areas take --noise2 / --param2")
    g.add_argument("--noise2", help="class of the masked area (default: --noise)")
    g.add_argument("--param2", action="append", default=[], metavar="NAME=VALUE", help="its parameters (repeat)")
    g.add_argument("--width", type=float, default=32.0, help="blend transition width, px")
    g.add_argument("--sharpness", type=float, default=1.0, help="blend sharpness exponent (1: linear)")
    g.add_argument("--corners", nargs=4, metavar="SPEC",
                   help="four-corner blend: top-left top-right bottom-left bottom-right, each CLASS[:NAME=V,...]")
    g.add_argument("--map", metavar="PAINTED", help="a painted map: an indexed, grey or colour-coded image")
    g.add_argument("--region", action="append", default=[], metavar="KEY=SPEC",
                   help="--map: a grey index (0-255) or #rrggbb colour = CLASS[:NAME=V,...] (repeat)")
    g = n.add_argument_group("animation")
    g.add_argument("--keys", metavar="KEYS.toml", help="keyframes of class and parameters over frames (needs "
                                                       "--frames)")
    g.add_argument("--frames", type=int, nargs=2, metavar=("FIRST", "LAST"),
                   help="write frames FIRST..LAST into -o with '#' for the frame number")
    g.add_argument("--latent", choices=("fixed", "slerp", "drift"), default="fixed",
                   help="how the initial latent moves: fixed, slerp between the keys' seeds, or drift")
    g.add_argument("--drift", type=float, default=0.05, help="--latent drift: radians per frame")
    g = n.add_argument_group("inverse design")
    g.add_argument("--fit", metavar="IMAGE", help="find the classes, parameters and seed whose noise looks like "
                                                  "IMAGE and write that noise to -o")
    g.add_argument("--report", metavar="FIT.json", help="--fit: write the fitted classes, parameters and seed here")
    g.add_argument("--fit-size", type=int, default=64, help="--fit: side of the windows compared, px")
    g = n.add_argument_group("sampling and speed")
    g.add_argument("--sampler", default=None, help="ddim, dpmpp_2m or heun (default: dpmpp_2m)")
    g.add_argument("--steps", type=int, default=None, help="model evaluations (default: 10)")
    g.add_argument("--spacing", default=None,
                   help="timestep spacing: uniform, logsnr, karras or truncated (default: the sampler's own)")
    g.add_argument("--eta", type=float, default=None,
                   help="ddim or dpmpp_2m: fresh noise per step, 0 (deterministic) to 1 (default: 0.3 for "
                        "dpmpp_2m, 0 for ddim; animation always 0)")
    g.add_argument("--tile", type=int, default=None,
                   help="draw in overlapping tiles of this side (default: whole up to 1024 px, else 512 px tiles; "
                        "0: never)")
    g.add_argument("--threads", type=int, default=0, help="CPU threads (0: all cores)")
    g.add_argument("--precision", default="fp32", choices=PRECISIONS,
                   help="int8: about 1.7x faster steps on CPUs with int8 dot products (VNNI), a draft")

    s = _sub(sub, "solid", "solid textures from shipped textures or photos",
             "Solid textures (Henzler et al. 2020): a shipped texture or any photo becomes a 3D texture, written as "
             "an image (--dim 2: the plane y = 0 seen from the front, x right, z up) or a volume (--dim 3).",
             """omninoise solid --list
omninoise solid --exemplar wood_3d --dim 3 --size 128 -o wood.vdb
omninoise solid --exemplar photo.jpg --size 512 -o like.png
omninoise solid --exemplar gravel --to marble --mix 0.5 -o halfway.png
omninoise solid --method spectral --exemplar photo.jpg --dim 3 --size 128 -o rock.vdb
omninoise solid --method synthesis --exemplar photo.jpg --tile 256 --size 1024 -o tileable.png""")
    g = s.add_argument_group("texture and output")
    g.add_argument("--exemplar", help="a shipped texture (see --list) or an image file")
    g.add_argument("-o", "--out", help="2D: .png (sRGB), .exr or .npy (linear); 3D: .vdb or .npy (linear)")
    g.add_argument("--dim", type=int, choices=(2, 3), default=2, help="2: an image; 3: a volume")
    g.add_argument("--size", type=int, default=256, help="pixels (or voxels) per side")
    g.add_argument("--scale", type=float, default=1.0, help="zoom: output pixels per exemplar pixel")
    g.add_argument("--seed", type=int, default=0, help="another seed gives another texture of the same kind")
    g.add_argument("--method", default="neural", choices=("neural", "synthesis", "spectral"),
                   help="neural: the models' texture, 2D or 3D; spectral: the photo's spectrum and colours on every "
                        "cut, 2D or 3D, no network; synthesis: a seamless 2D image copied from the photo")
    g.add_argument("--list", action="store_true", help="print the shipped textures as JSON")
    g.add_argument("--model", help="a model folder (default: the exemplar's own shipped model, else the "
                                   "texture-space model)")
    g.add_argument("--quiet", action="store_true", help="no progress or notes")
    g = s.add_argument_group("photos (the texture-space model)")
    g.add_argument("--refine", type=int, default=0, metavar="N", help="improve a photo's code with N search steps")
    g.add_argument("--to", metavar="EXEMPLAR", help="interpolate towards this exemplar")
    g.add_argument("--mix", type=float, default=0.5, help="interpolation weight of --to, 0 to 1")
    g.add_argument("--no-periodic", dest="periodic", action="store_false",
                   help="leave out the photo's periodic part (courses, plank seams, tile joints)")
    g.add_argument("--no-gaussian", dest="gaussian", action="store_false",
                   help="never mix in fine detail drawn from the photo's spectrum (by default mixed in where a "
                        "check on rendered planes finds it closer)")
    g.add_argument("--rest", default="auto", choices=("auto", "isotropic", "upright"),
                   help="that detail's kind: auto (the check chooses), isotropic, or upright (layers and grain "
                        "kept on walls)")
    g = s.add_argument_group("--method synthesis")
    g.add_argument("--tile", type=int, default=256, help="the tile's side, px (a multiple of 4 in [32, 1024])")

    z = _sub(sub, "zoo", "images of the neural model's training classes (needs torch)",
             "Ground-truth images of the procedural zoo the neural model was trained on. Needs torch: "
             "pip install 'omninoise[train]'.",
             """omninoise zoo --list
omninoise zoo --noise damascus --param frequency=6 --size 256 -o damascus.png""")
    _class_args(z)

    t = _sub(sub, "transfer", "print or save a transfer-function preset as an editable ramp",
             "Transfer functions map noise values to colour, density and temperature, as Blender's Color Ramp "
             "does. Save a preset as a ramp .json, edit it, and pass it to --transfer or a job file.",
             """omninoise transfer --list
omninoise transfer fire -o my_ramp.json""")
    t.add_argument("preset", nargs="?", choices=tuple(PRESETS), help="the preset to print or save")
    t.add_argument("--list", action="store_true", help="list the presets")
    t.add_argument("-o", "--out", help="write the ramp here (default: print it)")
    return ap


def settings_from_args(a: argparse.Namespace) -> WaveSettings:
    if not 1 <= a.directions <= limits.MAX_DIRECTIONS:
        raise SettingError("--directions", f"must lie in [1, {limits.MAX_DIRECTIONS}], got {a.directions}")
    if a.period is not None:
        limits.positive("--period", a.period)
    limits.check_int("--table-size", a.table_size, 16, limits.MAX_TABLE_SIZE)
    if a.fmin > a.fmax:
        raise SettingError("--fmin", f"{a.fmin:g} is greater than --fmax {a.fmax:g}")
    example = None
    if a.example:
        if not os.path.isfile(a.example):
            raise SettingError("--example", f"image not found: {a.example}")
        from omninoise.export.images import read_image

        example = read_image(a.example)
    profile = ()
    if a.waveform == "custom":
        if not a.profile:
            raise SettingError("--profile", "--waveform custom needs --profile FILE")
        if not os.path.isfile(a.profile):
            raise SettingError("--profile", f"file not found: {a.profile}")
        try:
            with warnings.catch_warnings():     # an empty file is reported below, in one line, not as a warning too
                warnings.simplefilter("ignore", UserWarning)
                prof = np.load(a.profile, allow_pickle=False) if a.profile.endswith(".npy") else np.loadtxt(a.profile)
            profile = tuple(np.asarray(prof, np.float64).ravel())
        except (ValueError, OSError, EOFError, TypeError) as exc:
            raise SettingError("--profile", f"{a.profile}: not a list of numbers "
                                            f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
        if not profile or not np.all(np.isfinite(profile)):
            raise SettingError("--profile", f"{a.profile}: needs finite numbers, got {len(profile)} values")
    # the by-example and transition lengths default to the output's extent only where they are used, so
    # equal settings from flags, job files and the panel are equal requests (tests/blender/test_wave_front_ends.py)
    used = {}
    if example is not None:
        used["example_extent"] = a.example_extent or a.extent
    if a.transition is not None:
        used["transition_length"] = a.transition_length or a.extent
    return WaveSettings(
        dim=a.dim, spectrum=Spectrum(a.spectrum, a.fmin, a.fmax, a.exponent), directions=a.directions,
        seed=a.seed, output=a.output, speed=a.speed, slice_width=a.slice_width, waveform=a.waveform,
        profile=profile, cellular=a.cellular, cell_size=a.cell_size, stit_probability=a.stit_probability,
        stit_depth=a.stit_depth, anisotropy=a.anisotropy, axis_spectra=tuple(a.axis_spectrum),
        lobes=tuple(a.lobe), spread=a.spread, example=example, example_plane=a.example_plane, sectors=a.sectors,
        transition_to=a.transition, table_size=a.table_size, table_period=a.period, **used)


class _Bar:
    def __init__(self, quiet: bool, label: str = ""):
        self.quiet, self.t0, self.label, self.done = quiet, time.perf_counter(), label, False

    def __call__(self, frac: float) -> None:
        if self.quiet or self.done:
            return
        self.done = frac >= 1.0
        n = int(frac * 30)
        sys.stderr.write(f"\r{self.label}[{'#' * n}{'.' * (30 - n)}] {frac * 100:5.1f}%  "
                         f"{time.perf_counter() - self.t0:6.1f}s")
        if frac >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def run_wave(a: argparse.Namespace) -> int:
    ext = os.path.splitext(a.out)[1].lower()
    if ext not in (".npy", ".exr", ".png", ".vdb"):
        raise SettingError("-o", f"unsupported output type {ext or a.out!r}; use .npy, .exr, .png or .vdb")
    if a.dim > 2 and ext not in (".npy", ".vdb"):
        raise SettingError("-o", f"a {a.dim}D grid is a volume; write it as .vdb or .npy")
    if a.dim == 2 and ext == ".vdb":
        raise SettingError("-o", "a .vdb volume needs --dim 3 or 4")
    if ext == ".vdb":
        from omninoise.backend.bake import require_vdb

        require_vdb("-o")
    if a.transfer and ext == ".npy":
        raise SettingError("--transfer", ".npy holds raw values; use .vdb, .exr or .png for a ramp")
    if a.range and not a.transfer:
        raise SettingError("--range", "maps values onto a ramp; give --transfer too")
    if a.half and ext not in (".exr", ".vdb"):
        raise SettingError("--half", f"writes 16-bit floats into .exr and .vdb only, not {ext}")
    if a.size < 1:
        raise SettingError("--size", f"must be >= 1, got {a.size}")
    limits.positive("--extent", a.extent)
    limits.finite("--time", a.time)
    if a.example_extent is not None:
        limits.positive("--example-extent", a.example_extent)
    limits.check_memory("--size", float(a.size) ** (min(a.dim, 3) if ext in (".npy", ".vdb") else 2)
                        * 4 * (5 if a.transfer else 2), f"a {a.size}-sample {a.dim}D grid")
    folder = os.path.dirname(os.path.abspath(a.out))
    if not os.path.isdir(folder):
        raise SettingError("-o", f"output folder does not exist: {folder}")
    s = settings_from_args(a)
    if not a.quiet:
        from omninoise.backend.wavenoise.fast import engine_path

        print(f"omninoise wave: {engine_path()}", file=sys.stderr)
    nyq = a.size / (2.0 * a.extent)
    if a.fmax > nyq and a.cellular == "none" and not a.quiet:
        print(f"omninoise wave: warning: --fmax {a.fmax:g} is above the grid's Nyquist {nyq:g}; "
              "the image will alias", file=sys.stderr)
    return _bake_wave(a, s, ext)


def _bake_wave(a: argparse.Namespace, s: WaveSettings, ext: str) -> int:
    """``wave``, every output type, through the bake pipeline: one sampling convention (docs/conventions.md:
    sample centres (i + 1/2) E / N over [0, E)^d; .npy indexed [y, x] / [z, y, x]; images with +y up), the
    ramp, an atomic write."""
    from omninoise.backend.bake import BakeSpec, run_bake
    from omninoise.backend.sources import BoxGrid, WaveSource

    tf = load_transfer(a.transfer) if a.transfer else None
    if tf is not None and a.range:
        tf = tf.with_range(*a.range)
    rank = 3 if ext == ".vdb" or (ext == ".npy" and a.dim > 2) else 2
    grid = BoxGrid((a.size,) * rank, ((0.0, 0.0, 0.0), (a.extent,) * 3))
    spec = BakeSpec("wave", WaveSource(s), grid, a.out, tf, time=a.time, half=a.half)
    run_bake(spec, _Bar(a.quiet), force=True)
    return 0


def _bake_on_farm(a: argparse.Namespace) -> int:
    """``bake --workers N`` / ``--cluster ADDRESS``: the job on Dask (cli/farm.py); exit codes as locally."""
    from omninoise.backend.jobs import JobError

    if a.workers is not None and a.cluster:
        raise SettingError("--workers", "choose one of --workers (a local cluster) and --cluster (a scheduler)")
    if a.workers is not None and not 1 <= a.workers <= 512:
        raise SettingError("--workers", f"must be 1 to 512, got {a.workers}")
    if a.retries < 0:
        raise SettingError("--retries", f"must be >= 0, got {a.retries}")
    if a.brick_voxels is not None and a.brick_voxels < 1:
        raise SettingError("--brick-voxels", f"must be >= 1, got {a.brick_voxels}")
    if not os.path.isfile(a.job):
        raise JobError(f"job file not found: {a.job}")
    try:
        from . import farm
    except ImportError as exc:
        raise SettingError("--workers" if a.workers else "--cluster",
                           f"needs Dask ({exc}); pip install 'dask[distributed]' or the farm extra") from None
    try:
        client = farm.local_client(a.workers) if a.workers else farm.remote_client(a.cluster, a.tls_ca_file,
                                                                                   a.tls_cert, a.tls_key)
    except ImportError as exc:
        raise SettingError("--workers" if a.workers else "--cluster",
                           f"needs Dask distributed ({exc}); pip install 'dask[distributed]'") from None
    except OSError as exc:
        raise SettingError("--cluster", f"cannot reach the scheduler {a.cluster}: {exc}") from None
    try:
        if not a.quiet and client.dashboard_link:
            print(f"omninoise bake: Dask dashboard {client.dashboard_link}", file=sys.stderr)

        def status(done, total, moved, eta):
            if not a.quiet:
                sys.stderr.write(f"\r  {done}/{total} tasks, {moved / 2 ** 20:.1f} MiB, ETA {eta:.0f} s   ")
                if done == total:
                    sys.stderr.write("\n")
                sys.stderr.flush()

        outcomes = farm.run_farm(a.job, client, force=a.force, only=a.only, brick_voxels=a.brick_voxels,
                                 retries=a.retries, status=status, precision=a.precision)
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None:
            cluster.close()
    for o in outcomes:
        if o.status in ("baked", "up to date") and not a.quiet:
            print(f"omninoise bake: {o.name}: {o.status} ({o.message})", file=sys.stderr)
    bad = [o for o in outcomes if o.status not in ("baked", "up to date")]
    for o in bad:
        print(f"omninoise bake: error: {o.message}", file=sys.stderr)
    if any(o.status == "invalid" for o in bad):
        return 2
    return 1 if bad else 0


def _set_threads(n: int, precision: str = "fp32") -> None:
    """The CLI's --threads and --precision as the defaults of every model the command loads."""
    from omninoise.backend.neural.precision import set_default_precision
    from omninoise.backend.onnx_models import set_default_threads

    if n < 0:
        raise SettingError("--threads", f"must be >= 0 (0: all cores), got {n}")
    set_default_threads(n)
    set_default_precision(precision)


def run_bake_job(a: argparse.Namespace) -> int:
    from omninoise.backend.jobs import JobError, load_job, run_job

    if a.dry_run:
        entries = load_job(a.job)
        bad = [s for _, s in entries if isinstance(s, JobError)]
        for name, spec in entries:
            if isinstance(spec, JobError):
                print(f"  invalid  {spec}")
            else:
                frames = spec.frame_list()
                fresh = sum(spec.is_up_to_date(f) for f in frames)
                state = "up to date" if fresh == len(frames) else "to bake"
                print(f"  {state:10s} {name}: {list(spec.grid.resolution)} -> {spec.output}"
                      + (f" ({len(frames)} frames, {fresh} up to date)" if spec.frames else ""))
        if bad:
            print(f"omninoise bake: error: {len(bad)} of {len(entries)} bakes are invalid (listed above)",
                  file=sys.stderr)
            return 2
        return 0
    _set_threads(a.threads, a.precision)
    if a.workers is not None or a.cluster:
        return _bake_on_farm(a)
    now = {}      # the bake in progress: one bar per bake

    def on_bake(name, i, count):
        now.update(bar=_Bar(a.quiet, f"[{i + 1}/{count}] {name} "), i=i, count=count)

    def progress(frac):   # the job's fraction -> this bake's
        now["bar"](min(1.0, max(0.0, frac * now["count"] - now["i"])))

    outcomes = run_job(a.job, keep_going=a.keep_going, force=a.force, only=a.only, progress=progress,
                       on_bake=on_bake)
    failed = [o for o in outcomes if o.status != "baked" and o.status != "up to date"]
    for o in outcomes:
        if o.status in ("baked", "up to date") and not a.quiet:
            print(f"omninoise bake: {o.name}: {o.status} ({o.message})", file=sys.stderr)
    for o in failed:
        print(f"omninoise bake: {'cancelled' if o.status == 'cancelled' else 'error'}: {o.message}", file=sys.stderr)
    # exit status as documented: 2 bad input, 130 interrupted, 1 a failure while running
    if any(o.status == "invalid" for o in failed):
        return 2
    if any(o.status == "cancelled" for o in failed):
        return 130
    return 1 if failed else 0




def _param_items(items: list, flag: str) -> dict:
    out = {}
    for item in items:
        key, sep, val = item.partition("=")
        if not sep:
            raise SettingError(flag, f"expected NAME=VALUE, got {item!r}")
        try:
            out[key] = float(val)
        except ValueError:
            raise SettingError(flag, f"expected NAME=VALUE with a number, got {item!r}") from None
    return out


def _spec_arg(text: str, flag: str) -> tuple:
    """'cells_f1:scale=8,jitter=0.5' -> ('cells_f1', {'scale': 8.0, 'jitter': 0.5})."""
    name, _, rest = text.partition(":")
    return name, _param_items([p for p in rest.split(",") if p], flag)


def _painted_parts(a: argparse.Namespace) -> tuple:
    """--map and its --region flags -> (regions int (H, W) into specs, specs)."""
    from omninoise.export.images import decode
    from omninoise.backend.neural.request import region_key, regions_from_map

    if not os.path.isfile(a.map):
        raise SettingError("--map", f"map not found: {a.map}")
    if not a.region:
        raise SettingError("--region", "a --map needs --region KEY=SPEC for each of its colours")
    px = decode(a.map)
    if px.shape[:2] != (a.size, a.size):
        raise SettingError("--map", f"map is {px.shape[1]}x{px.shape[0]} but --size is {a.size}")
    keys, specs = [], []
    for r in a.region:
        key, sep, spec = r.partition("=")
        if not sep:
            raise SettingError("--region", f"expected KEY=SPEC, got {r!r}")
        keys.append(region_key(key, "--region"))
        specs.append(_spec_arg(spec, "--region"))
    return regions_from_map(px, keys, "--map"), specs


def neural_request(a: argparse.Namespace, model):
    """The :class:`backend.neural.request.NeuralRequest` of ``omninoise neural`` flags (checked)."""
    from omninoise.backend.neural.request import NeuralRequest
    from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    if sum(bool(x) for x in (a.blend, a.corners, a.map)) > 1:
        raise SettingError("--blend", "choose one of --blend, --corners and --map")
    kw = dict(width=a.size, height=a.size, transition=a.width, sharpness=a.sharpness, seed=a.seed,
              steps=DEFAULT_STEPS if a.steps is None else a.steps, sampler=a.sampler or DEFAULT_SAMPLER,
              spacing=a.spacing, eta=a.eta, tileable=a.tileable, tile=a.tile)
    spec = (a.noise, _param_items(a.param, "--param"))
    if a.corners:
        req = NeuralRequest("corners", [_spec_arg(c, "--corners") for c in a.corners], **kw)
    elif a.map:
        regions, specs = _painted_parts(a)
        req = NeuralRequest("painted", specs, regions=regions, **kw)
    elif a.blend:
        from omninoise.export.images import read_image

        if not os.path.isfile(a.blend):
            raise SettingError("--blend", f"mask not found: {a.blend}")
        mask = read_image(a.blend)
        if mask.shape != (a.size, a.size):
            raise SettingError("--blend", f"mask is {mask.shape[1]}x{mask.shape[0]} but --size is {a.size}")
        spec2 = (a.noise2 or a.noise, _param_items(a.param2, "--param2"))
        req = NeuralRequest("blend", [spec, spec2], mask=mask > 0.5, **kw)
    else:
        if a.noise2 or a.param2:
            raise SettingError("--noise2", "a second noise needs --blend MASK")
        req = NeuralRequest("uniform", [spec], **kw)
    try:
        return req.check(model)
    except SettingError as exc:  # name the flag where the request's field has one
        flag = {"noise": "--noise", "map": "--map", "blend": "--blend", "size": "--size", "seed": "--seed",
                "width": "--width"}.get(exc.setting, exc.setting)
        raise SettingError(flag, exc.message) from None


def run_neural(a: argparse.Namespace) -> int:
    import json

    from omninoise.backend.neural.model import ModelError, NeuralNoiseModel, PrecisionUnavailable
    from omninoise.backend.neural.request import generate_request

    from omninoise.backend.neural.generate import check_sampler
    from omninoise.backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

    _set_threads(a.threads, a.precision)
    sampler = a.sampler or DEFAULT_SAMPLER
    steps = DEFAULT_STEPS if a.steps is None else a.steps
    try:
        check_sampler(sampler, steps, a.spacing, a.eta)
    except SettingError as exc:         # named as the flag the user typed
        raise SettingError(f"--{exc.setting}", exc.message) from None
    if not 0 <= a.seed < 2 ** 32:
        raise SettingError("--seed", f"must lie in [0, 2^32), got {a.seed}")
    limits.check_memory("--size", float(a.size) ** 2 * 4 * 160, f"a {a.size}² neural image (activations)")
    tile = a.tile
    if tile is not None and tile < 0:
        raise SettingError("--tile", f"must be >= 0 (0: never tile), got {tile}")
    folder = a.model or neural_model()
    try:
        model = NeuralNoiseModel(folder)
    except PrecisionUnavailable as exc:
        raise SettingError("--precision", str(exc)) from None
    except ModelError as exc:
        raise SettingError("--model", f"{exc}; train and export one (see models/README.md) or pass --model") from None
    if a.list:
        print(json.dumps(dict(classes=model.class_params, trained=model.config.get("trained_classes")), indent=2))
        return 0
    if a.keys or a.frames:
        return _animate_neural(a, model, sampler, steps, tile)
    if a.fit:
        return _fit_neural(a, model, sampler, steps, tile)
    if a.report:
        raise SettingError("--report", "a fit report needs --fit IMAGE")
    if not (a.noise or a.corners or a.map) or not a.out:
        raise SettingError("neural", "give --noise CLASS (or --corners / --map) and -o OUT (or --list)")
    ext = os.path.splitext(a.out)[1].lower()
    if ext not in (".png", ".exr", ".npy"):
        raise SettingError("-o", f"unsupported output type {ext or a.out!r}; use .png, .exr or .npy")
    req = neural_request(a, model)
    bar = _Bar(a.quiet)
    img = generate_request(model, req, callback=lambda i, n, x0: bar((i + 1) / n))
    from omninoise.export.images import write_unit_image

    write_unit_image(a.out, img)
    return 0


def _animate_neural(a: argparse.Namespace, model, sampler: str, steps: int, tile) -> int:
    """``neural --keys KEYS.toml --frames FIRST LAST -o name_####.png``: one file per frame, each written
    atomically (an interrupted run keeps the frames it finished)."""
    from omninoise.backend.bake import frame_path, has_frame_field
    from omninoise.backend.neural.animate import animate, read_keys
    from omninoise.export.images import write_unit_image

    if not (a.keys and a.frames):
        raise SettingError("--keys", "an animation needs both --keys KEYS.toml and --frames FIRST LAST")
    if a.noise or a.corners or a.map or a.blend:
        raise SettingError("--keys", "the keyframes set the classes; leave out --noise, --corners, --map and --blend")
    if not a.out or not has_frame_field(a.out):
        raise SettingError("-o", "an animation writes one file per frame: put '#' for the frame number in the "
                                 "name, e.g. -o noise_####.png")
    ext = os.path.splitext(a.out)[1].lower()
    if ext not in (".png", ".exr", ".npy"):
        raise SettingError("-o", f"unsupported output type {ext or a.out!r}; use .png, .exr or .npy")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    first, last = a.frames
    if last < first:
        raise SettingError("--frames", f"expected FIRST LAST with LAST >= FIRST, got {first} {last}")
    if last - first >= 100_000:
        raise SettingError("--frames", f"{last - first + 1} frames is more than the 100000 one run may write")
    limits.finite("--drift", a.drift)
    folder = os.path.dirname(os.path.abspath(a.out))
    if not os.path.isdir(folder):
        raise SettingError("-o", f"output folder does not exist: {folder}")
    keys = read_keys(a.keys)
    n = last - first + 1
    bar = _Bar(a.quiet, "frames ")
    frames = animate(model, keys, (first, last), a.size, a.size, latent=a.latent, speed=a.drift, steps=steps,
                     sampler=sampler, spacing=a.spacing, eta=a.eta, tileable=a.tileable, tile=tile)
    for i, (f, img) in enumerate(frames):
        write_unit_image(frame_path(a.out, f), img)
        bar((i + 1) / n)
    return 0


def _fit_neural(a: argparse.Namespace, model, sampler: str, steps: int, tile) -> int:
    """``neural --fit IMAGE -o OUT [--report FIT.json]``: inverse design (backend/neural/fit.py), then the fitted
    noise at --size with the sampler settings."""
    import json

    from omninoise.export.atomic import write_json
    from omninoise.export.images import decode, write_unit_image
    from omninoise.backend.neural.fit import fit, fitted_conditioning, load_bank, prepare_target
    from omninoise.backend.neural.generate import generate
    from omninoise.backend.onnx_models import ModelError
    from omninoise.backend.paths import fit_bank

    if a.noise or a.corners or a.map or a.blend:
        raise SettingError("--fit", "the fit finds the classes; leave out --noise, --corners, --map and --blend")
    if not a.out:
        raise SettingError("-o", "--fit writes the fitted noise: give -o OUT (.png, .exr or .npy)")
    ext = os.path.splitext(a.out)[1].lower()
    if ext not in (".png", ".exr", ".npy"):
        raise SettingError("-o", f"unsupported output type {ext or a.out!r}; use .png, .exr or .npy")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    if not os.path.isfile(a.fit):
        raise SettingError("--fit", f"image not found: {a.fit}")
    try:
        img = decode(a.fit)
    except (OSError, ValueError) as exc:
        raise SettingError("--fit", f"{a.fit}: not an image we can read ({exc})") from None
    try:
        bank = load_bank(fit_bank())
    except ModelError as exc:  # the fit still works, starting from every class at mid-range parameters
        print(f"note: no inverse-design bank ({exc}); trying every class", file=sys.stderr)
        bank = None
    img = img[..., 0] if img.shape[2] == 1 else img
    for note in prepare_target(img, model.multiple_of, os.path.basename(a.fit))[1]:  # refuses too small images
        print("note: " + note, file=sys.stderr)
    bar = _Bar(a.quiet, "fit    ")
    res = fit(model, img, size=a.fit_size, seed=a.seed, bank=bank, progress=lambda f: bar(0.8 * f))
    cond = fitted_conditioning(model, res, a.size, a.size)
    out = generate(model, cond, res.seed, steps, a.tileable, callback=lambda i, n, x0: bar(0.8 + 0.2 * (i + 1) / n),
                   sampler=sampler, spacing=a.spacing, tile=tile)
    write_unit_image(a.out, out)
    report = dict(res.to_json(), image=os.path.abspath(a.fit), output=os.path.abspath(a.out), size=a.size,
                  model=model.fingerprint)
    if a.report:
        write_json(a.report, report)
    if not a.quiet:
        print(json.dumps(dict(classes=res.classes, params=res.params, seed=res.seed, command=res.command())))
    return 0


def solid_request(a: argparse.Namespace):
    """The :class:`backend.solid.request.SolidRequest` of ``omninoise solid``'s flags, checked."""
    from omninoise.backend.solid.request import SolidRequest

    return SolidRequest(a.model, a.exemplar, a.to, a.mix, a.refine, a.seed, a.periodic, a.gaussian,
                        a.rest, a.method, a.tile).check("--")


def run_solid(a: argparse.Namespace) -> int:
    import json

    from omninoise.backend.solid.model import load_models

    if a.list:
        out = {name: dict(mode=m.mode, dim=m.dim, exemplars=m.config["exemplars"], codes=sorted(m.codes))
               for name, m in load_models().items()}
        print(json.dumps(out, indent=2))
        return 0
    if not a.exemplar or not a.out:
        raise SettingError("solid", "give --exemplar (a shipped texture or an image file) and -o OUT (or --list)")
    if a.size < 1:
        raise SettingError("--size", f"must be >= 1, got {a.size}")
    limits.positive("--scale", a.scale)
    limits.check_memory("--size", float(a.size) ** a.dim * 4 * 4, f"a {a.size}-sample {a.dim}D texture")
    ext = os.path.splitext(a.out)[1].lower()
    allowed = (".png", ".exr", ".npy") if a.dim == 2 else (".vdb", ".npy")
    if ext not in allowed:
        raise SettingError("-o", f"a {a.dim}D result is written as {', '.join(allowed)}, not {ext or a.out!r}")
    if ext == ".vdb":
        from omninoise.backend.bake import require_vdb

        require_vdb("-o")
    req = solid_request(a)
    t0 = time.perf_counter()
    if not a.quiet and req.method == "neural" and os.path.isfile(a.exemplar):
        print(f"encoding {a.exemplar} ...", end="", file=sys.stderr, flush=True)

    def report(name, hist):
        if not a.quiet:
            kept = len(hist) > 1 and hist[-1] == hist[0] and min(hist) < hist[0]
            print(f"refined {name}: neighbourhood distance {hist[0]:.4f} -> {min(hist):.4f}"
                  + (" on the searched planes, not closer on fresh ones: the encoder's code is kept" if kept else ""),
                  file=sys.stderr)

    def on_code(code):
        if a.quiet:
            return
        if os.path.isfile(a.exemplar):
            print(f" done ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
        if code.harmonics is not None:
            h = code.harmonics
            print(f"periodic part: {len(h)} waves at spectral peaks, {100 * h.share:.0f} % of the photo's variance "
                  "(--no-periodic leaves it out)", file=sys.stderr)
        if code.rest is not None:
            from omninoise.backend.solid.spectral import KIND_WORDS
            print(f"gaussian rest: {100 * code.rest.mix:.0f} % of the rest's variance drawn as "
                  f"{KIND_WORDS[code.rest.kind]}, found closer to the image than the decoder alone (--no-gaussian "
                  "leaves it out)", file=sys.stderr)

    stage = {"neural": "refine ", "synthesis": "synthesis ", "spectral": "spectral solid "}[req.method]
    if a.dim == 3:  # volumes through the bake pipeline: .vdb color + density grids, or linear RGB .npy
        from omninoise.backend.bake import BakeSpec, run_bake
        from omninoise.backend.sources import BoxGrid, solid_volume

        source, extent = solid_volume(req, a.size, a.scale, "--", _Bar(a.quiet, stage), report, on_code)
        grid = BoxGrid((a.size,) * 3, ((0.0, 0.0, 0.0), (extent,) * 3))
        run_bake(BakeSpec("solid", source, grid, a.out), _Bar(a.quiet), force=True)
        return 0
    _write_solid_image(a.out, req.front_image(a.size, a.scale, "--", _Bar(a.quiet, stage), report, on_code,
                                              _Bar(a.quiet)))
    return 0


def _write_solid_image(out: str, rgb: np.ndarray) -> None:
    """A 2D solid texture, sRGB float (H, W, 3) in [0, 1]: .png as it is, .exr and .npy linear."""
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.export.images import write_unit_image

    write_unit_image(out, rgb, srgb_to_linear(rgb))


def run_zoo(a: argparse.Namespace) -> int:
    import json

    try:
        from omninoise.training import zoo
    except ImportError as exc:
        raise SettingError("zoo", f"needs torch ({exc})") from None
    if a.list:
        print(json.dumps(zoo.describe(), indent=2))
        return 0
    if not a.noise or not a.out:
        raise SettingError("zoo", "give --noise CLASS and -o OUT (or --list)")
    if a.size < 8:
        raise SettingError("--size", f"must be >= 8, got {a.size}")
    if os.path.splitext(a.out)[1].lower() not in (".png", ".exr", ".npy"):
        raise SettingError("-o", f"unsupported output type {os.path.splitext(a.out)[1] or a.out!r}; use .png, .exr or .npy")
    limits.check_memory("--size", float(a.size) ** 2 * 4 * 8, f"a {a.size}² zoo image")
    try:
        params = zoo.parse_params(a.noise, a.param)
    except ValueError as exc:
        raise SettingError("--noise" if "class" in str(exc) else "--param", str(exc)) from None
    from omninoise.export.images import write_unit_image

    write_unit_image(a.out, zoo.generate(a.noise, params, [a.seed], a.size)[0].numpy())
    return 0


def run_transfer(a: argparse.Namespace) -> int:
    import json

    from omninoise.backend.transfer import preset

    if a.list or not a.preset:
        print("\n".join(PRESETS))
        return 0
    text = json.dumps(preset(a.preset).to_dict(), indent=2)
    if not a.out:
        print(text)
        return 0
    from omninoise.export.atomic import atomic_path

    with atomic_path(a.out) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    a = ap.parse_args(argv)
    if argv is None and hugepages.wanted(a.command, getattr(a, "size", 0) or 0, os.environ):
        try:   # a large neural image: the same command again, with huge pages (cli/hugepages.py)
            hugepages.reexec()
        except OSError:
            pass
    try:
        if a.command == "wave":
            return run_wave(a)
        if a.command == "bake":
            return run_bake_job(a)
        if a.command == "transfer":
            return run_transfer(a)
        if a.command == "zoo":
            return run_zoo(a)
        if a.command == "neural":
            return run_neural(a)
        if a.command == "solid":
            return run_solid(a)
    except (SettingError, FileNotFoundError, PermissionError, IsADirectoryError, ImageError) as exc:
        print(f"omninoise {a.command}: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:
        from omninoise.backend.grid import Cancelled
        from omninoise.backend.jobs import JobError

        if isinstance(exc, JobError):
            print(f"omninoise {a.command}: error: {exc}", file=sys.stderr)
            return 2
        if isinstance(exc, Cancelled):
            print(f"omninoise {a.command}: cancelled", file=sys.stderr)
            return 130
        if a.debug:
            raise
        what = str(exc).splitlines()[0] if str(exc) else ""
        print(f"omninoise {a.command}: internal error: {type(exc).__name__}{': ' + what if what else ''} "
              "(a bug: please report it with the command; --debug before the command shows the traceback)",
              file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"\nomninoise {a.command}: interrupted; no partial file was left", file=sys.stderr)
        return 130
    return 1
