"""Bakes: a source on a grid, through an optional transfer function, into files.

A :class:`BakeSpec` names a source (:mod:`backend.sources`), a voxel-centred
grid, an optional RGBA transfer function (:mod:`backend.transfer`, Guehl et
al. 2025 Sec. 7.1), an output path and an optional frame range.  :func:`run_bake`
evaluates it in slabs (memory stays near the output's size), reports progress,
polls cancel between slabs and writes every file atomically through ``export``.

Outputs by extension:

    .vdb  3D grid.  ``density`` float grid (the raw value without a transfer
          function; alpha x density_scale with one), ``color`` vec3 grid and,
          where the ramp has temperature stops, ``temperature`` (Kelvin).
          Voxels of zero density are inactive (sparse).
    .exr  2D grid.  ``Y`` (raw value) or ``RGBA`` (through the ramp), half or float.
    .png  2D grid.  8-bit: sRGB-encoded RGBA through the ramp, else grey: a source's values in [0, 1] as
          they are (neural noise, ``unit``), others (a preview) over their 0.5th..99.5th percentiles.
    .npy  raw float32 values (2D or 3D), indexed (y, x) or (z, y, x).

Image files put +y up (row 0 is the top row, y = y1).

A frame range bakes a numbered sequence: ``#`` runs in the path become the
zero-padded frame number (``clouds_####.vdb`` -> ``clouds_0001.vdb``), the
naming Blender plays as an animation.  Frame f is evaluated at
``time + (f - start) * time_step``.

Every file carries a key (sha256 of everything that determines it) in its
metadata; a bake skips files whose key matches unless ``force`` is set.
"""
from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from . import limits
from .errors import SettingError
from .grid import Cancelled
from .progress import part
from .sources import BoxGrid, Source, describe
from .transfer import TransferFunction

__all__ = ["BakeSpec", "BakeResult", "run_bake", "evaluate_values", "write_values", "require_vdb", "frame_path",
           "check_one_file", "check_not_read", "output_type", "still", "check_bake_memory", "PEAK_BYTES", "FORMATS",
           "NPY_RAMP", "KEY_NAME", "Cancelled"]

_F = np.float32
FORMATS = (".vdb", ".exr", ".png", ".npy")
#: why a ramp and a .npy output are refused together, in every front end (named by its own setting there)
NPY_RAMP = ".npy holds the raw values, which a ramp does not colour: write .vdb, .exr or .png, or remove the ramp"
KEY_NAME = "omninoise_key"
#: voxels per slab: ~2 MiB of values plus ~8 MiB of colour at a time
SLAB_VOXELS = 1 << 19
_FRAME = re.compile(r"#+")

#: bytes a result holds at its peak per sample of its grid, by the file it is written to (None: returned in memory)
#: and what it holds: a source's values ("values"), a ramp's colours from them ("ramp"), a solid texture's RGB
#: ("rgb"). The growth of `omninoise wave` and `omninoise solid`'s peak resident memory from 2048^2 to 4096^2 px
#: (1024^2 to 1792^2 for RGB) and from 192^3 to 256^3 voxels (96^3 to 144^3 for RGB), rounded up: the values, a
#: ramp's RGBA, the writers' copies (an EXR's channels, OpenVDB's grids, a PNG's bytes). A model's or a tile's own
#: memory, the same at every size, comes on top (the neural models: about 0.2 GiB)
PEAK_BYTES = {None: {"values": 6, "rgb": 26}, ".npy": {"values": 6, "rgb": 20},
              ".png": {"values": 14, "ramp": 28, "rgb": 16}, ".exr": {"values": 10, "ramp": 42, "rgb": 26},
              ".vdb": {"values": 10, "ramp": 36, "rgb": 18}}


def check_bake_memory(setting: str, shape, ext: str | None, holds: str, what: str) -> None:
    """SettingError naming ``setting`` where a result of grid ``shape`` written as ``ext`` (None: kept in memory),
    holding ``holds`` ("values", "ramp" or "rgb"), would take more than :func:`limits.memory_limit` at its peak
    (:data:`PEAK_BYTES`); ``what`` names it in the message ("a [512, 512, 512] grid")."""
    per_sample = PEAK_BYTES[ext].get(holds)
    if per_sample is not None:          # none: a pair refused on its own (a ramp into .npy)
        limits.check_memory(setting, float(np.prod(np.asarray(shape, np.float64))) * per_sample, what)


@dataclass(frozen=True)
class BakeSpec:
    """One bake.

    name       label for messages and logs
    source     a :class:`~backend.sources.Source`
    grid       a :class:`~backend.sources.BoxGrid` (2D for images, 3D for volumes)
    output     file path; with ``frames``, ``#`` runs are replaced by the frame number
    transfer   RGBA ramp, or None for raw values
    frames     (start, end) inclusive, or None for one file
    time       time (or 4D W) of the single bake / of frame ``start``
    time_step  time between frames
    half       EXR and VDB: store 16-bit half floats
    make_folders  create a missing output folder when baking (job files) instead of failing
    """

    name: str
    source: Source
    grid: BoxGrid
    output: str
    transfer: TransferFunction | None = None
    frames: tuple | None = None
    time: float = 0.0
    time_step: float = 1.0 / 24.0
    half: bool = False
    make_folders: bool = False

    def validate(self) -> "BakeSpec":
        self.grid.validate()
        limits.time("time", self.time)
        limits.positive("time_step", self.time_step)
        last = self.time + (float(self.frames[1]) - float(self.frames[0])) * self.time_step if self.frames else self.time
        if self.frames is not None:     # every frame's time within MAX_TIME
            if not abs(last) <= limits.MAX_TIME:
                raise SettingError("time_step", f"the last frame's time, {last:g}, passes {limits.MAX_TIME:g}; use a "
                                                "smaller time_step or fewer frames")
        ext = output_type(self.output, FORMATS, "a bake", "output")
        rank = self.grid.rank
        if ext == ".vdb" and rank != 3:
            raise SettingError("output", f"{os.path.basename(self.output)}: .vdb needs a 3D grid (resolution [nx, ny, nz])")
        if ext == ".vdb":
            require_vdb("output")
        if ext in (".exr", ".png") and rank != 2:
            raise SettingError("output", f"{os.path.basename(self.output)}: {ext} needs a 2D grid; bake volumes to .vdb or .npy")
        check = getattr(self.source, "check_grid", None)  # a source's own requirements on the grid (named first)
        if check is not None:
            check(self.grid.shape)
        check = getattr(self.source, "check_extent", None)  # ... and on how far from the origin it reaches
        if check is not None:
            check(float(np.max(np.abs(self.grid.bounds))), max(abs(self.time), abs(last)))
        if rank == 3 and self.source.dim == 2:
            raise SettingError("grid", "a 2D noise cannot fill a 3D grid; use dim = 3 or 4")
        if getattr(self.source, "rgb", False) and self.transfer is not None:
            raise SettingError("transfer", "a solid texture has its own colours; remove the transfer function")
        if ext == ".npy" and self.transfer is not None:
            raise SettingError("transfer", NPY_RAMP)
        if self.half and self.transfer is not None and ext in (".exr", ".vdb"):
            from ..export.atomic import HALF_MAX

            top = self.transfer.largest(volume=ext == ".vdb")
            if top > HALF_MAX:
                raise SettingError("half", f"the ramp writes values up to {top:g} (colour, density or temperature), "
                                           f"past {HALF_MAX:g}, the largest 16-bit half float: leave out half")
        holds = "rgb" if getattr(self.source, "rgb", False) else "values" if self.transfer is None else "ramp"
        check_bake_memory("resolution", self.grid.shape, ext, holds, f"a {list(self.grid.resolution)} grid")
        if self.frames is not None:
            a, b = self.frames
            if int(a) != a or int(b) != b or b < a:
                raise SettingError("frames", f"expected [start, end] whole numbers with end >= start, got {list(self.frames)}")
            limits.frame_count("frames", a, b, "bake")
            if not _FRAME.search(os.path.basename(self.output)):
                raise SettingError("output", f"{os.path.basename(self.output)}: a frame range needs '#' in the file name "
                                   "(e.g. clouds_####.vdb)")
            if not self.source.animated:
                raise SettingError("frames", still(self.source))
        else:
            check_one_file(self.output, "output", " (or give a frame range)")
        folder = os.path.dirname(os.path.abspath(self.output))
        if not self.make_folders and not os.path.isdir(folder):
            raise SettingError("output", f"folder does not exist: {folder}")
        from ..export.atomic import check_target

        try:      # what writing would refuse, refused now: the longest name, and a folder in any frame's place
            frames = self.frame_list()
            check_target(frame_path(self.output, frames[-1]), folder_made=self.make_folders)
            for f in frames if os.path.isdir(folder) else ():
                if os.path.isdir(frame_path(self.output, f)):
                    raise IsADirectoryError(f"output path is a folder, not a file: {frame_path(self.output, f)}")
        except OSError as exc:
            raise SettingError("output", str(exc)) from None
        return self

    def frame_list(self) -> list:
        if self.frames is None:
            return [None]
        return list(range(int(self.frames[0]), int(self.frames[1]) + 1))

    def frame_time(self, frame) -> float:
        if frame is None:
            return float(self.time)
        return float(self.time) + (frame - int(self.frames[0])) * float(self.time_step)

    def key(self, frame) -> str:
        """sha256 of everything that determines the file of ``frame``."""
        from .version import __version__

        ext = os.path.splitext(self.output)[1].lower()
        doc = dict(version=__version__, source=self.source.to_dict(), grid=self.grid.to_dict(),
                   transfer=None if self.transfer is None else self.transfer.to_dict(),
                   time=self.frame_time(frame) if self.source.animated else 0.0,    # still noise reads no time
                   half=bool(self.half and ext in (".exr", ".vdb")), format=ext)
        if ext == ".png" and self.transfer is None and getattr(self.source, "unit", False):
            doc["png"] = "as is"    # a [0, 1] source's grey levels are its values, not a preview's stretch
        return hashlib.sha256(describe(doc).encode()).hexdigest()

    def is_up_to_date(self, frame, key: str | None = None) -> bool:
        """True when the file of ``frame`` exists and carries this spec's key (.npy never does)."""
        path = frame_path(self.output, frame)
        if os.path.splitext(path)[1].lower() == ".npy":
            return False
        from .. import export

        return export.read_metadata(path).get(KEY_NAME) == (key or self.key(frame))


@dataclass
class BakeResult:
    name: str
    written: list = field(default_factory=list)
    skipped: list = field(default_factory=list)


def has_frame_field(pattern: str) -> bool:
    """Whether a file name has a '#' run for the frame number (``clouds_####.vdb``)."""
    return bool(_FRAME.search(os.path.basename(pattern)))


def check_one_file(path: str, setting: str, or_else: str = "") -> None:
    """SettingError naming ``setting`` where ``path``, written as one file, has a '#' in its name: '#' stands for a
    sequence's frame number everywhere (job files, Blender), and a file named ``clouds_####.exr`` is a mistake."""
    if has_frame_field(path):
        raise SettingError(setting, f"{os.path.basename(path)}: '#' stands for the frame number of a sequence, and "
                                    f"this writes one file: take it out of the name{or_else}")


def still(source) -> str:
    """Why a setting of time reads nothing of ``source``, a source that does not change over time: what would
    animate its kind (its ``animated_by``), where it has that."""
    how = getattr(source, "animated_by", None)
    return "this source does not change over time" + (f" ({how})" if how else "")


def output_type(path: str, allowed: tuple, what: str, setting: str) -> str:
    """The extension of the output file ``path``, lower case; SettingError naming ``setting`` where ``path`` is a
    folder or its type none of ``allowed`` (what ``what``, "a neural noise image", is written as)."""
    if os.path.isdir(path):
        raise SettingError(setting, f"output path is a folder, not a file: {os.fspath(path)}")
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext not in allowed:
        base = os.path.basename(os.fspath(path))
        if base.lower() in allowed:         # '.png': a hidden file's name, with no type after it
            raise SettingError(setting, f"{base!r} is a name without a type: give the file a name before {base}")
        if not ext:
            raise SettingError(setting, f"{os.fspath(path)!r} is a name without a type: {what} is written as "
                                        f"{', '.join(allowed)}")
        raise SettingError(setting, f"{what} is written as {', '.join(allowed)}, not {ext!r}")
    return ext


def check_not_read(path: str, setting: str, inputs) -> None:
    """SettingError naming ``setting`` where writing the file ``path`` would replace a file the work reads:
    ``inputs`` holds (name, path) pairs of what it reads (a photo, a mask, a ramp, the job file), and a photo
    written over would be lost. Paths are compared as files (links and '..' resolved); anything that is no file is
    passed over."""
    if not os.path.isfile(path):
        return
    for name, src in inputs:
        if isinstance(src, (str, os.PathLike)) and os.path.isfile(src) and os.path.samefile(path, src):
            raise SettingError(setting, f"{os.path.basename(path)} is the file {name} reads: write to another file")


def frame_path(pattern: str, frame) -> str:
    """``clouds_####.vdb``, 7 -> ``clouds_0007.vdb`` (the last run of '#' in the file name)."""
    if frame is None:
        return pattern
    folder, base = os.path.split(pattern)
    runs = list(_FRAME.finditer(base))
    m = runs[-1]
    base = base[: m.start()] + f"{int(frame):0{len(m.group())}d}" + base[m.end():]
    return os.path.join(folder, base)


def require_vdb(setting: str) -> None:
    """SettingError naming ``setting`` where no OpenVDB Python module can write .vdb files (before any work)."""
    from ..export.vdb import openvdb_module

    try:
        openvdb_module()
    except RuntimeError as exc:
        raise SettingError(setting, str(exc)) from None


def _slabs(n_outer: int, per_outer: int, chunkable: bool):
    """(start, stop) ranges of the outermost axis with about SLAB_VOXELS voxels each."""
    step = n_outer if not chunkable else max(1, SLAB_VOXELS // max(1, per_outer))
    for a in range(0, n_outer, step):
        yield a, min(n_outer, a + step)


def evaluate_rows(source: Source, grid: BoxGrid, time: float, a: int, b: int, progress=None,
                  cancel=None) -> np.ndarray:
    """The source on rows a .. b - 1 of the grid's outermost axis (z of a volume, y of an image): float32
    (b - a, ...) - the one sub-box call of a slab-wise bake and a farm's brick."""
    start = [0] * grid.rank
    start[grid.rank - 1] = int(a)          # start is (x, y[, z]); the outermost array axis is the last of them
    vals = source.evaluate((b - a,) + tuple(grid.shape[1:]), grid.first, grid.voxel, time, progress, cancel,
                           tuple(start))
    return np.asarray(vals, _F)


def evaluate_slabs(source: Source, grid: BoxGrid, time: float, progress=None, cancel=None):
    """Yield (start, values) over the grid's outermost axis; values float32 (n, ...) slabs."""
    shape = grid.shape
    per = int(np.prod(shape[1:]))
    for a, b in _slabs(shape[0], per, getattr(source, "chunkable", True)):
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        sub = None if progress is None else (lambda x, a=a, b=b: progress((a + x * (b - a)) / shape[0]))
        yield a, evaluate_rows(source, grid, time, a, b, sub, cancel)


def evaluate_values(source: Source, grid: BoxGrid, time: float = 0.0, progress=None, cancel=None) -> np.ndarray:
    """The source on the whole grid, as a .npy bake holds it: float32 ``grid.shape`` (indexed (y, x) or
    (z, y, x)), with a trailing axis of 3 for a colour source (scene-linear RGB)."""
    rgb = getattr(source, "rgb", False)
    values = np.empty(grid.shape + ((3,) if rgb else ()), _F)
    for a, vals in evaluate_slabs(source, grid, time, progress, cancel):
        values[a: a + vals.shape[0]] = vals
    if cancel is not None and cancel():
        raise Cancelled("cancelled")
    return values


def volume_grids(spec: BakeSpec) -> dict:
    """{grid name: "float" | "vec3"} of the .vdb a spec writes: raw ``density``; with a ramp also ``color``
    (and ``temperature`` where the ramp has temperature stops); a colour source ``color`` and ``density``."""
    if getattr(spec.source, "rgb", False):
        return {"density": "float", "color": "vec3"}
    grids = {"density": "float"}
    if spec.transfer is not None:
        grids["color"] = "vec3"
        if spec.transfer.has_temperature:
            grids["temperature"] = "float"
    return grids


def volume_channels(spec: BakeSpec, vals: np.ndarray) -> dict:
    """A slab of source values (nz, ny, nx) (or (nz, ny, nx, 3) colours) -> {grid name: slab} as the .vdb
    holds them (Sec. 7.1 of the wave-noise paper: the ramp's alpha times the density scale, colour and
    temperature zero where the density is); any z range may be computed alone (bricks on a farm)."""
    if getattr(spec.source, "rgb", False):
        return {"color": vals, "density": np.full(vals.shape[:-1], spec.source.density, _F)}
    tf = spec.transfer
    if tf is None:
        return {"density": vals}
    rgba = tf.rgba(vals)
    dens = tf.density(rgba)
    empty = dens <= 0.0
    dens[empty] = 0.0
    col = rgba[..., :3]
    col[empty] = 0.0
    out = {"density": dens, "color": col}
    if tf.has_temperature:
        temp = tf.kelvin(vals)
        temp[empty] = 0.0
        out["temperature"] = temp
    return out


def bake_frame(spec: BakeSpec, frame, progress=None, cancel=None) -> str:
    """Write the file of one frame (None: the single output) whatever its state -> its path."""
    path = frame_path(spec.output, frame)
    _bake_file(spec, path, spec.frame_time(frame), spec.key(frame), progress, cancel)
    return path


#: the share of a result's progress that making its texture takes where it is made first (a procedural fit of
#: about 12 s, auto's choice of about 17 s, an encoding of about 3 s): a job's bake, a Solid Texture panel's bake,
#: ``omninoise.solid``
PREPARE_SHARE = 0.5


def split_progress(progress, share: float = PREPARE_SHARE) -> tuple:
    """(making, drawing): ``progress(fraction)`` (None: none) heard over the first ``share`` of the work (making the
    texture) and then over the rest (drawing it)."""
    return part(progress, 0.0, share), part(progress, share, 1.0 - share)


def _bake_file(spec: BakeSpec, path: str, time: float, key: str, progress, cancel) -> None:
    from .. import export

    if not getattr(spec.source, "ready", True):     # a texture made at its first use (sources.solid._Prepared)
        making, progress = split_progress(progress)
        spec.source.prepare(making, cancel)

    ext = os.path.splitext(path)[1].lower()
    meta = _meta(spec, key)
    if ext == ".vdb":  # values and colour sources alike: volume_grids / volume_channels
        writer = export.VolumeWriter(spec.grid.voxel, spec.grid.first, volume_grids(spec), meta, half=spec.half)
        for z0, vals in evaluate_slabs(spec.source, spec.grid, time, progress, cancel):
            for name, slab in volume_channels(spec, vals).items():
                writer.add(name, z0, slab)
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        writer.write(path)
        return
    _write_values(spec, path, evaluate_values(spec.source, spec.grid, time, progress, cancel), meta)


def write_values(spec: BakeSpec, frame, values: np.ndarray) -> str:
    """Write ``values`` drawn elsewhere (as ``spec.source.evaluate`` gives them on ``spec.grid``: float32 (ny, nx)
    indexed by +y, or (ny, nx, 3) of a colour source) as the image or array file of ``frame`` (None: the single
    output), with the key that makes it up to date for ``spec``, atomically -> its path. A front end that draws the
    image itself (the Neural Noise panel) writes through this the file a job of ``spec`` writes."""
    path = frame_path(spec.output, frame)
    if os.path.splitext(path)[1].lower() not in (".exr", ".png", ".npy"):
        raise SettingError("output", f"write_values writes images and arrays, not {os.path.basename(path)}")
    _write_values(spec, path, np.asarray(values, np.float32), _meta(spec, spec.key(frame)))
    return path


def _meta(spec: BakeSpec, key: str) -> dict:
    """The metadata every baked file carries."""
    return {KEY_NAME: key, "omninoise_source": spec.source.kind, "omninoise_bake": spec.name}


def _write_values(spec: BakeSpec, path: str, values: np.ndarray, meta: dict) -> None:
    """An image or array file of a source's values on the grid (+y first; files put +y at the top)."""
    from .. import export

    ext = os.path.splitext(path)[1].lower()
    if ext == ".npy":
        export.write_npy(path, values)  # indexed (y, x) / (z, y, x) like the grid
        return
    values = values[::-1]  # row 0 of an image file is its top: +y up, as a plane shows it in Blender
    tf = spec.transfer
    if getattr(spec.source, "rgb", False):      # scene-linear colours: RGB EXR, sRGB PNG
        if ext == ".exr":
            export.write_exr(path, values, half=spec.half, metadata=meta)
        else:
            export.write_png(path, export.encode_srgb8(values), metadata=meta)
    elif ext == ".exr":
        export.write_exr(path, values if tf is None else tf.rgba(values), half=spec.half, metadata=meta)
    elif tf is not None:
        export.write_png(path, export.encode_srgb8(tf.rgba(values)), metadata=meta)
    elif getattr(spec.source, "unit", False):       # values in [0, 1]: as they are (omninoise neural -o's PNG)
        export.write_png(path, export.preview_8bit(values, 0.0, 1.0), metadata=meta)
    else:
        export.write_png(path, export.preview_8bit(values), metadata=meta)


def run_bake(spec: BakeSpec, progress: Callable[[float], None] | None = None,
             cancel: Callable[[], bool] | None = None, force: bool = False,
             log: Callable[[str], None] | None = None) -> BakeResult:
    """Bake every frame of ``spec``; progress gets the fraction done over all frames.

    Raises :class:`~backend.grid.Cancelled` when cancel() turns True (the file in
    progress is not written; finished frames stay) and SettingError for bad specs.
    """
    spec.validate()
    if spec.make_folders:
        os.makedirs(os.path.dirname(os.path.abspath(spec.output)), exist_ok=True)
    frames = spec.frame_list()
    res = BakeResult(spec.name)
    for i, frame in enumerate(frames):
        path = frame_path(spec.output, frame)
        key = spec.key(frame)
        if not force and spec.is_up_to_date(frame, key):
            res.skipped.append(path)
            if progress is not None:
                progress((i + 1) / len(frames))
            continue
        sub = None if progress is None else (lambda x, i=i: progress((i + x) / len(frames)))
        _bake_file(spec, path, spec.frame_time(frame), key, sub, cancel)
        res.written.append(path)
        if log is not None:
            log(f"{spec.name}: wrote {path}")
        if progress is not None:
            progress((i + 1) / len(frames))
    return res
