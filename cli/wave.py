"""``omninoise wave``: wave noise on a grid, written as an array, an image or a volume."""
from __future__ import annotations

import argparse
import os
import sys
import warnings

import numpy as np

from omninoise.backend import limits
from omninoise.backend.bake import NPY_RAMP, check_bake_memory, output_type
from omninoise.backend.errors import SettingError
from omninoise.backend.transfer import PRESETS, load_transfer
from omninoise.backend.wavenoise.cellular import CELLULAR_MODES
from omninoise.backend.wavenoise.settings import ANISOTROPY, PLANES, WaveSettings, check_read, check_time, field_of
from omninoise.backend.wavenoise.spectra import SPECTRUM_KINDS, Spectrum
from omninoise.backend.wavenoise.tables import WAVEFORMS
from omninoise.backend.wavenoise.wave import OUTPUTS

from .common import Bar, add_command, flag_image

__all__ = ["add_parser", "run", "settings_from_args"]


#: the spectra a flag names (a custom spectrum's amplitudes are given in a job file or from Python)
FLAG_SPECTRA = tuple(k for k in SPECTRUM_KINDS if k != "custom")


def spectrum_arg(text: str) -> Spectrum:
    """'kind:fmin:fmax[:exponent]' -> Spectrum."""
    parts = text.split(":")
    try:
        kind, fmin, fmax = parts[0], float(parts[1]), float(parts[2])
        exponent = float(parts[3]) if len(parts) > 3 else 1.0
    except (IndexError, ValueError):
        raise argparse.ArgumentTypeError(f"expected kind:fmin:fmax[:exponent], got {text!r}") from None
    if kind not in FLAG_SPECTRA:
        why = " (a custom spectrum's amplitudes are given in a job file or from Python)" if kind == "custom" else ""
        raise argparse.ArgumentTypeError(f"expected a kind of {', '.join(FLAG_SPECTRA)}, got {kind!r}{why}")
    return Spectrum(kind, fmin, fmax, exponent)


def lobe_arg(text: str) -> tuple:
    """'x,y[,z[,w]]:weight' -> ((axis...), weight)."""
    axis, _, weight = text.partition(":")
    try:
        return tuple(float(v) for v in axis.split(",")), float(weight or 1.0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y[,z]:weight, got {text!r}") from None


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    w = add_command(sub, "wave", "wave noise on a grid",
                    "Wave noise (Guehl et al. 2025): a sum of randomly oriented waves read from 1D tables, in 2D, 3D or 4D, "
                    "still or animated, written as an array, an image or a volume. The grid has --size samples per axis "
                    "over [0, --extent); frequencies are in cycles per unit.",
                    """omninoise wave --size 512 --spectrum bandpass --fmin 4 --fmax 8 -o band.png
omninoise wave --dim 3 --size 128 --fmin 1 --fmax 6 --transfer clouds -o clouds.vdb
omninoise wave --dim 3 --size 128 --speed 0.5 --time 2.0 -o frame.npy
omninoise wave --size 512 --cellular stit --stit-depth 3 -o cracks.png
omninoise wave --dim 3 --size 256 --transfer fire -o fire.vdb --save-job fire.toml   # for omninoise bake or a farm""")
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
    g.add_argument("--save-job", metavar="JOB.toml",
                   help="write a job file that bakes -o with these settings (omninoise bake JOB.toml, a farm) "
                        "instead of baking it now")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar or notes")
    g = w.add_argument_group("spectrum")
    g.add_argument("--spectrum", choices=FLAG_SPECTRA, default="gaussian",
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
    g.add_argument("--anisotropy", choices=ANISOTROPY, default="none",
                   help="axes: a spectrum per axis; lobes: directions gathered around axes")
    g.add_argument("--axis-spectrum", type=spectrum_arg, action="append", default=[], metavar="KIND:FMIN:FMAX",
                   help="--anisotropy axes: one per axis, in order")
    g.add_argument("--lobe", type=lobe_arg, action="append", default=[], metavar="X,Y[,Z]:WEIGHT",
                   help="--anisotropy lobes: a lobe's axis and weight (repeat)")
    g.add_argument("--spread", type=float, default=20.0, help="lobe or plane band half-angle, degrees")
    g = w.add_argument_group("by example and transitions")
    g.add_argument("--example", help="a grayscale image whose spectrum the noise takes")
    g.add_argument("--example-plane", choices=tuple(PLANES), default="xy", help="the plane the image lies in")
    g.add_argument("--example-extent", type=float, help="world units across the image (default: --extent)")
    g.add_argument("--sectors", type=int, default=8, help="angular sectors read from the image's spectrum")
    g.add_argument("--transition", type=spectrum_arg, metavar="KIND:FMIN:FMAX",
                   help="blend towards this spectrum along x")
    g.add_argument("--transition-length", type=float, help="units over which the blend runs (default: --extent)")
    g = w.add_argument_group("tables")
    g.add_argument("--slice-width", type=float, help="width of a direction's slices in units (default: from the band)")
    g.add_argument("--table-size", type=int, default=1024, help="samples per wave table")
    g.add_argument("--period", type=float, help="table period in units (default: 255 / fmax)")
    return w


#: the defaults of the flags of the settings :data:`~backend.wavenoise.settings.READ_WITH` names: a flag is given
#: where its value is not its default
READ_WITH_DEFAULTS = {"exponent": 1.0, "profile": None, "cell_size": None, "stit_probability": 0.5, "stit_depth": 3,
                      "axis_spectra": [], "lobes": [], "spread": 20.0, "example_plane": "xy", "example_extent": None,
                      "sectors": 8, "transition_length": None}


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

        example = flag_image("--example", read_image, a.example)
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
            prof = np.asarray(prof, np.float64)
            if sum(n > 1 for n in prof.shape) > 1:
                raise ValueError(f"one row or column of samples expected, got shape {prof.shape}")
            profile = tuple(prof.ravel())
        except (ValueError, OSError, EOFError, TypeError) as exc:
            raise SettingError("--profile", f"{a.profile}: not a list of numbers "
                                            f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
        if not profile or not np.all(np.isfinite(profile)):
            raise SettingError("--profile", f"{a.profile}: needs finite numbers, got {len(profile)} values")
    # the by-example and transition lengths default to the output's extent only where they are used, so
    # equal settings from flags, job files and the panel are equal requests (tests/blender/test_wave_front_ends.py)
    used = {}
    if example is not None:
        used["example_extent"] = a.example_extent if a.example_extent is not None else a.extent
    if a.transition is not None:
        used["transition_length"] = a.transition_length if a.transition_length is not None else a.extent
    s = WaveSettings(
        dim=a.dim, spectrum=Spectrum(a.spectrum, a.fmin, a.fmax, a.exponent), directions=a.directions,
        seed=a.seed, output=a.output, speed=a.speed, slice_width=a.slice_width, waveform=a.waveform,
        profile=profile, cellular=a.cellular, cell_size=a.cell_size, stit_probability=a.stit_probability,
        stit_depth=a.stit_depth, anisotropy=a.anisotropy, axis_spectra=tuple(a.axis_spectrum),
        lobes=tuple(a.lobe), spread=a.spread, example=example, example_plane=a.example_plane, sectors=a.sectors,
        transition_to=a.transition, table_size=a.table_size, table_period=a.period, **used)
    try:
        s = s.validate()
    except SettingError as exc:     # named as the flag the user typed, where the setting has one
        raise SettingError(_flag(a, exc.setting), exc.message) from None
    check_read(s, [k for k, unset in READ_WITH_DEFAULTS.items() if getattr(a, _FLAGS.get(k, k)) != unset],
               lambda k, v=None: _flag(a, k) if v is None else f"{_flag(a, k)} {v}")
    return s


#: settings whose flag has another name
_FLAGS = {"lobes": "lobe", "axis_spectra": "axis_spectrum", "table_period": "period", "transition_to": "transition"}


def _flag(a: argparse.Namespace, setting: str) -> str:
    """The flag behind a setting's dotted name ("spectrum.fmax" -> --fmax, "lobes[0][1]" -> --lobe), or the
    name itself."""
    dest = field_of(setting)
    dest = _FLAGS.get(dest, dest)
    return "--" + dest.replace("_", "-") if hasattr(a, dest) else setting


def run(a: argparse.Namespace) -> int:
    ext = output_type(a.out, (".npy", ".exr", ".png", ".vdb"), "wave noise", "-o")
    if a.dim > 2 and ext not in (".npy", ".vdb"):
        raise SettingError("-o", f"a {a.dim}D grid is a volume; write it as .vdb or .npy")
    if a.dim == 2 and ext == ".vdb":
        raise SettingError("-o", "a .vdb volume needs --dim 3 or 4")
    if ext == ".vdb":
        from omninoise.backend.bake import require_vdb

        require_vdb("-o")
    if a.transfer and ext == ".npy":
        raise SettingError("--transfer", NPY_RAMP)
    if a.range and not a.transfer:
        raise SettingError("--range", "maps values onto a ramp; give --transfer too")
    if a.half and ext not in (".exr", ".vdb"):
        raise SettingError("--half", f"writes 16-bit floats into .exr and .vdb only, not {ext}")
    if a.save_job:
        from omninoise.backend.job_file import check_job_file

        check_job_file(a.save_job, "--save-job", "--example" if a.example else None)
    if a.size < 1:
        raise SettingError("--size", f"must be >= 1, got {a.size}")
    limits.in_range("--extent", a.extent, limits.MIN_LENGTH, limits.MAX_COORD)
    limits.time("--time", a.time)
    if a.example_extent is not None:
        limits.positive("--example-extent", a.example_extent)
    check_bake_memory("--size", (a.size,) * (2 if a.dim == 2 else 3), ext, "ramp" if a.transfer else "values",
                      f"a {a.size}-sample {a.dim}D grid")
    s = settings_from_args(a)
    check_time("--time", a.time, s, "--speed", "--dim 4")
    tf = load_transfer(a.transfer, "--transfer") if a.transfer else None
    if tf is not None and a.range:
        try:
            tf = tf.with_range(*a.range)
        except SettingError as exc:     # "range", "range[0]": the flag's two values
            raise SettingError("--range", exc.message) from None
    from omninoise.backend.sources import WaveSource

    try:
        source = WaveSource(s)      # the tables' own rules, named as the flag the user typed
    except SettingError as exc:
        raise SettingError(_flag(a, exc.setting), exc.message) from None
    source.check_extent(a.extent, abs(a.time), ("--extent", "--time"))
    if not a.quiet:
        from omninoise.backend.wavenoise import fast

        if not fast.compiled():     # the one case worth a note: several times slower (--version names the kernel)
            print(f"omninoise wave: note: wave noise runs on {fast.engine_path()}", file=sys.stderr)
    nyq = a.size / (2.0 * a.extent)
    if a.fmax > nyq and a.cellular == "none" and not a.quiet:
        print(f"omninoise wave: warning: --fmax {a.fmax:g} is above the grid's Nyquist {nyq:g}; "
              "the image will alias", file=sys.stderr)
    return _bake(a, source, tf, ext)


def _bake(a: argparse.Namespace, source, tf, ext: str) -> int:
    """``wave``, every output type, through the bake pipeline: one sampling convention (docs/conventions.md:
    sample centres (i + 1/2) E / N over [0, E)^d; .npy indexed [y, x] / [z, y, x]; images with +y up), the
    ramp, an atomic write."""
    from omninoise.backend.bake import BakeSpec, run_bake
    from omninoise.backend.sources import BoxGrid

    rank = 3 if ext == ".vdb" or (ext == ".npy" and a.dim > 2) else 2
    grid = BoxGrid((a.size,) * rank, ((0.0, 0.0, 0.0), (a.extent,) * 3))
    spec = BakeSpec("wave", source, grid, a.out, tf, time=a.time, half=a.half)
    if a.save_job:
        from omninoise.backend.job_file import write_job

        try:
            write_job(a.save_job, [spec.validate()])
        except SettingError as exc:      # what a job cannot hold (a by-example noise), named by the flag
            raise SettingError("--save-job", exc.message) from None
        if not a.quiet:
            print(f"omninoise wave: wrote {a.save_job}: omninoise bake {a.save_job} bakes {a.out}", file=sys.stderr)
        return 0
    try:
        run_bake(spec, Bar(a.quiet), force=True)
    except SettingError as exc:     # the bake's own rules (a ramp past what --half holds), named by their flags
        raise SettingError(_flag(a, exc.setting), exc.message) from None
    return 0


