"""Batch bake jobs from TOML files (``omninoise bake JOB.toml``, the Blender panel, ``bpy``).

A job file lists bakes; paths are relative to the job file's folder and
missing output folders are created.  Outputs must lie inside the job's folder
unless the job names another root, ``output_root = "../renders"`` (relative to
the job file, or absolute) at the top of the file: a job cannot write anywhere
on a farm machine by accident (``output = "../../x"``)::

    # optional: merged into every bake (a bake's own keys win, tables merge key by key)
    [defaults]
    bounds = [[-1, -1, 0], [1, 1, 1]]

    [[bake]]
    name = "clouds"                     # unique; used in messages and --only
    output = "out/clouds_####.vdb"      # .vdb (3D), .exr / .png (2D), .npy; '#' = frame number
    resolution = [128, 128, 64]         # [nx, ny] image or [nx, ny, nz] volume
    bounds = [[-1, -1, 0], [1, 1, 1]]   # world box, voxel-centred samples
    transfer = "clouds"                 # preset, ramp .json file, or a table (see backend.transfer)
    frames = [1, 24]                    # optional inclusive range -> numbered sequence
    time = 0.0                          # time (4D: W) of the first frame
    time_step = 0.0417                  # time between frames
    half = false                        # EXR / VDB: 16-bit half floats

    [bake.source]                       # kind = "wave" + WaveSettings keys
    kind = "wave"
    dim = 3
    speed = 0.5
    spectrum = {kind = "fractal", fmin = 1, fmax = 8, exponent = 1.0}
    seed = 7

A neural noise image (Maesumi et al. 2024) is a 2D bake with a neural source::

    [[bake]]
    name = "mossy"
    output = "out/mossy.exr"
    resolution = [512, 512]             # image pixels
    [bake.source]
    kind = "neural"
    noise = "cells_f1"
    params = {scale = 8}
    blend = "mask.png"                  # optional: white areas take noise2 / params2
    noise2 = "liquid"
    steps = 30
    seed = 3
    tileable = false

The other layouts of the command line, with the same class specs (``"CLASS:NAME=VALUE,..."`` or
``{noise = CLASS, params = {...}}``) and the same checks (:class:`backend.neural.request.NeuralRequest`)::

    corners = ["spots:coverage=0.3", "perlin", {noise = "cells_f1", params = {scale = 10}}, "spots"]
    # or a painted map: each region's colour (or grey level "0".."255") names its class
    map = "painted.png"
    regions = {"#ff0000" = "spots", "#0000ff" = "gabor:frequency=12"}
    width = 32                          # transition width (px) of blend masks and painted maps

Animated neural noise (a numbered image sequence): ``keys`` gives keyframes of class and parameters, as a
file (see :mod:`backend.neural.animate`) or inline, whose ``frame`` numbers are the bake's frames (the bake's
time is the frame number unless ``time`` / ``time_step`` say otherwise); ``latent`` = "fixed" | "slerp" |
"drift" (``drift`` radians per frame)::

    [[bake]]
    name = "morph"
    output = "out/morph_####.png"
    resolution = [256, 256]
    frames = [1, 48]
    [bake.source]
    kind = "neural"
    keys = [{frame = 1, noise = "perlin", params = {scale = 4}}, {frame = 48, noise = "cells_f1"}]
    latent = "fixed"

A neural solid texture (Henzler et al. 2020) bakes colours: a volume's ``color``
grid (with a constant ``density``), an RGB EXR, an sRGB PNG or a (..., 3) .npy::

    [[bake]]
    name = "gravel_block"
    output = "out/gravel.vdb"
    resolution = [96, 96, 96]
    bounds = [[-1, -1, -1], [1, 1, 1]]
    [bake.source]
    kind = "solid"
    model = "gravel_3d"                 # a shipped model's name or a model folder; left out: chosen from the
                                        # exemplar, as `omninoise solid` does (its own model, else the space model)
    # exemplar = "photo.png"            # space models: an image to encode (or a training exemplar's name)
    # refine = 40                       # search steps refining the encoded code
    # periodic = false                  # leave out the image's periodic part (courses, planks; on by default)
    # gaussian = false                  # never mix in the image's Gaussian rest (on where its check finds it closer)
    # rest = "upright"                  # its kind: "auto" (the check chooses), "isotropic", "upright" (walls)
    # to = "wood"                       # space models: a second exemplar (name or image) ...
    # mix = 0.3                         # ... and its share, as `omninoise solid --to --mix`
    seed = 0
    scale = 1.0                         # texture units per world unit
    density = 1.0

The same source with ``method = "synthesis"`` bakes a seamless 2D image synthesised from an image exemplar by
texture optimisation (``backend/solid/synthesis.py``; 2D grids only, as ``omninoise solid --method synthesis``)::

    [bake.source]
    kind = "solid"
    method = "synthesis"
    exemplar = "photo.png"
    tile = 256                          # the periodic image's side, px (a multiple of 4 in [32, 1024])
    seed = 0
    scale = 1.0

With ``method = "spectral"`` it bakes random phase noise of an image exemplar lifted to a solid
(``backend/solid/spectral_solid.py``: a periodic Gaussian solid with the image's spectrum and colours on every cut;
2D and 3D grids, as ``omninoise solid --method spectral``); with ``method = "procedural"`` a procedural solid
(rings, layers, cells or bonds, ``backend/solid/procedural/``) fitted to the image, the same way::

    [bake.source]
    kind = "solid"
    method = "spectral"
    exemplar = "photo.png"
    seed = 0
    scale = 1.0
    density = 1.0

Every problem is reported as ``bake 'NAME': what is wrong``.
"""
from __future__ import annotations

import copy
import os
import re
from dataclasses import dataclass
from typing import Callable

from .bake import BakeResult, BakeSpec, Cancelled, check_not_read, frame_path, run_bake, still
from .documents import read_document
from .errors import SettingError
from .paths import in_job
from .schema import did_you_mean, shown_value
from .sources import BoxGrid, source_from_dict
from .transfer import load_transfer, transfer_from_dict

__all__ = ["JobError", "load_job", "parse_job", "run_job", "select_bakes", "JobOutcome", "default_times"]



class JobError(ValueError):
    """A job file or one of its bakes is wrong; the message names which and why."""


@dataclass
class JobOutcome:
    name: str
    status: str  # "baked" | "up to date" | "invalid" (bad settings, nothing run) | "failed" | "cancelled"
    message: str = ""
    result: BakeResult | None = None


def _defaulted(setting: str, own: dict, defaults: dict) -> bool:
    """Whether the key a bake's error names (``source.fmax``, ``source.spectrum.fmax``, ``frames[1]``) comes from
    ``[defaults]``, not the bake's own table: a wave setting given there is unknown to a neural bake."""
    here, there = own, defaults
    for part in re.sub(r"\[\d+\]", "", setting).split("."):
        if isinstance(here, dict) and part in here:
            here, there = here[part], there.get(part) if isinstance(there, dict) else None
        else:
            return isinstance(there, dict) and part in there
    return False


def _merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _merge(out[k], v)
        else:
            out[k] = v
    return out


def default_times(source, frames: tuple | None) -> tuple:
    """(time, time_step) of a bake that gives neither: 0 and 1/24 s a frame, but for keyframed neural noise, whose
    time is the frame number its keyframes name (the first frame's, else the first keyframe's) and steps 1."""
    keys = getattr(source, "keys", None)
    if keys:
        return float(frames[0] if frames else keys[0].frame), 1.0
    return 0.0, 1.0 / 24.0


def _spec(d: dict, base_dir: str, index: int, own: frozenset = frozenset()) -> BakeSpec:
    """One merged ``[[bake]]`` table -> its checked BakeSpec (:data:`~backend.settings_schema.BAKE` first, then
    its source's table, then the rules that join keys).  ``own`` names the keys the bake's own table gives (not
    ``[defaults]``, which may set ``time`` for still and animated bakes alike): there, a ``time`` of a still
    source and a ``time_step`` without ``frames`` change nothing and are refused."""
    from .settings_schema import BAKE

    d = BAKE.check(d, "")
    name = d.get("name") or f"bake {index + 1}"
    source = source_from_dict(d["source"], base_dir)
    bounds = tuple(tuple(b) for b in d.get("bounds", [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    grid = BoxGrid(tuple(d["resolution"]), bounds).validate()
    tf = d.get("transfer")
    if isinstance(tf, str):
        path = in_job(base_dir, tf)
        tf = load_transfer(path if os.path.isfile(path) else tf)
    elif isinstance(tf, dict):
        tf = transfer_from_dict(tf)
    elif tf is not None:
        raise SettingError("transfer", f"expected a preset name, a .json file or a table, got {tf!r}")
    frames = tuple(d["frames"]) if "frames" in d else None
    output = os.path.normpath(in_job(base_dir, d["output"]))
    time0, dt = default_times(source, frames)
    if "time" in own and not source.animated:
        raise SettingError("time", f"{still(source)}; its time changes nothing")
    if "time_step" in own and frames is None:
        raise SettingError("time_step", "sets the time between the frames of a sequence; without frames it changes "
                                        "nothing")
    half = d.get("half", False)
    if half and os.path.splitext(output)[1].lower() not in (".exr", ".vdb"):
        raise SettingError("half", f"writes 16-bit floats into .exr and .vdb only, not {os.path.basename(output)}")
    return BakeSpec(name=name, source=source, grid=grid, output=output, transfer=tf, frames=frames,
                    time=d.get("time", time0), time_step=d.get("time_step", dt), half=half,
                    make_folders=True).validate()


def parse_job(doc: dict, base_dir: str, job_path: str | None = None) -> list:
    """Job document -> list of (name, BakeSpec or JobError); ``job_path`` is the job file, which no bake may
    write over."""
    from .settings_schema import BAKE, JOB

    try:
        doc = JOB.check(doc, "")
        for k in doc.get("defaults", {}):
            if k not in BAKE.fields:
                raise SettingError(f"defaults.{k}", f"unknown key{did_you_mean(k, BAKE.fields)}; known: "
                                                    f"{', '.join(BAKE.fields)}")
    except SettingError as exc:
        if exc.setting == "bake" and "bake" not in doc:
            raise JobError("no [[bake]] tables: nothing to do") from None
        raise JobError(str(exc)) from None
    root = os.path.realpath(in_job(base_dir, doc.get("output_root", ".")))
    bakes, defaults = doc["bake"], doc.get("defaults", {})
    out, seen, outputs = [], set(), {}
    for i, b in enumerate(bakes):
        d = _merge(defaults, b)
        name = d.get("name") or f"bake {i + 1}"
        if not isinstance(name, str):
            name = f"bake {i + 1}"
            out.append((name, JobError(f"{name}: name: expected a string, got {shown_value(d['name'])}")))
            continue
        if name in seen:
            out.append((name, JobError(f"bake {name!r}: the name is used twice")))
            continue
        seen.add(name)
        try:
            spec = _spec(d, base_dir, i, frozenset(b))
        except (SettingError, FileNotFoundError) as exc:
            given = " (set in [defaults], which every bake takes)" if isinstance(exc, SettingError) and \
                _defaulted(exc.setting, b, defaults) else ""
            out.append((name, JobError(f"bake {name!r}: {exc}{given}{_written_before(d, base_dir, outputs)}")))
            continue
        real = os.path.realpath(spec.output)
        try:
            inside = os.path.commonpath([root, real]) == root
        except ValueError:  # another drive (Windows)
            inside = False
        if not inside:
            out.append((name, JobError(f"bake {name!r}: output {spec.output} lies outside the output root {root}; "
                                       "set output_root at the top of the job file to allow that folder")))
            continue
        # two bakes writing one file would overwrite each other: every file each writes (a sequence's frames
        # included), compared where they land (links and '..' resolved)
        files = [os.path.normcase(os.path.realpath(frame_path(spec.output, f))) for f in spec.frame_list()]
        clash = next((f for f in files if f in outputs), None)
        if clash is not None:
            out.append((name, JobError(f"bake {name!r}: output {os.path.basename(clash)} is also written by bake "
                                       f"{outputs[clash]!r}")))
            continue
        try:        # a bake written over a file it reads (its photo, mask, ramp) or the job file would lose it
            read = [(key, in_job(base_dir, v)) for key, v in _strings(d) if key != "output"]
            for f in files:
                check_not_read(f, "output", read + [("the job", job_path)])
        except SettingError as exc:
            out.append((name, JobError(f"bake {name!r}: {exc}")))
            continue
        outputs.update(dict.fromkeys(files, name))
        out.append((name, spec))
    return out


def _written_before(d: dict, base_dir: str, outputs: dict) -> str:
    """Where a bake reads a file that is not there yet but an earlier bake of the job writes: a hint that a job's
    bakes are checked before any runs (and a farm runs them at once), so the file must exist first."""
    for _, v in _strings(d):
        f = os.path.normcase(os.path.realpath(in_job(base_dir, v)))
        if f in outputs and not os.path.exists(f):
            return (f" (bake {outputs[f]!r} writes it: a job is checked before any bake runs; bake that one first, "
                    "on its own or with --only)")
    return ""


def _strings(value, key: str = ""):
    """(dotted key, string) of every string a bake table holds, nested tables and lists included."""
    if isinstance(value, str):
        yield key, value
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _strings(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _strings(v, f"{key}[{i}]")


def load_job(path: str) -> list:
    if not os.path.exists(path):
        raise JobError(f"job file not found: {path}")
    try:
        doc = read_document(path, "job file", "toml")
    except SettingError as exc:
        raise JobError(exc.message) from None
    return parse_job(doc, os.path.dirname(os.path.abspath(path)), path)


def select_bakes(entries: list, only: list | None) -> list:
    """The (name, spec) entries named in ``only`` (all when empty); JobError for a name the job lacks."""
    if not only:
        return entries
    names = [n for n, _ in entries]
    missing = [n for n in only if n not in names]
    if missing:
        raise JobError(f"no bake named {missing[0]!r}; the job has {', '.join(names)}")
    return [(n, s) for n, s in entries if n in only]


def run_job(path: str, keep_going: bool = False, force: bool = False, only: list | None = None,
            progress: Callable[[float], None] | None = None,
            cancel: Callable[[], bool] | None = None, log: Callable[[str], None] | None = None,
            on_bake: Callable[[str, int, int], None] | None = None) -> list:
    """Run every bake of a job file in order -> list of :class:`JobOutcome`.

    ``progress(fraction)`` of the whole job after each slab (the core's one
    progress contract); ``on_bake(name, index, count)`` as each bake starts.  Without
    ``keep_going`` the first failure stops the job (the returned list ends with
    it); invalid bakes fail before anything is baked.  Outputs whose stored key
    matches are skipped unless ``force``.
    """
    entries = select_bakes(load_job(path), only)
    outcomes = []
    if not keep_going:
        for name, spec in entries:
            if isinstance(spec, JobError):
                return [JobOutcome(name, "invalid", str(spec))]
    for i, (name, spec) in enumerate(entries):
        if isinstance(spec, JobError):
            outcomes.append(JobOutcome(name, "invalid", str(spec)))
            continue
        if on_bake is not None:
            on_bake(name, i, len(entries))
        cb = None if progress is None else (lambda f, i=i: progress((i + f) / len(entries)))
        try:
            res = run_bake(spec, cb, cancel, force, log)
        except Cancelled:
            outcomes.append(JobOutcome(name, "cancelled", f"bake {name!r}: cancelled"))
            return outcomes
        except (SettingError, OSError, RuntimeError, ValueError) as exc:
            outcomes.append(JobOutcome(name, "failed", f"bake {name!r}: {exc}"))
            if not keep_going:
                return outcomes
            continue
        status = "baked" if res.written else "up to date"
        outcomes.append(JobOutcome(name, status, f"{len(res.written)} written, {len(res.skipped)} up to date", res))
    return outcomes
