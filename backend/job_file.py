"""A bake as the job file that bakes it again: the inverse of :mod:`backend.jobs`' reader.

The Bake Noise, Neural Noise and Solid Texture panels save their bakes this way (**Save as Job File**), as do
``omninoise wave``, ``neural`` and ``solid --save-job``, so that ``omninoise bake JOB.toml``, a farm (``omninoise
farm``) or the Batch Job panel bakes the same files on another machine, without Blender::

    >>> from omninoise.backend import WaveSettings, Spectrum
    >>> from omninoise.backend.bake import BakeSpec
    >>> from omninoise.backend.sources import BoxGrid, WaveSource
    >>> spec = BakeSpec("clouds", WaveSource(WaveSettings(dim=3, spectrum=Spectrum("fractal", 1, 8, 1.2))),
    ...                 BoxGrid((32, 32, 16), ((-1, -1, 0), (1, 1, 1))), "/jobs/out/clouds.npy")
    >>> print(job_text([spec], "/jobs"))      # doctest: +NORMALIZE_WHITESPACE
    # An OmniNoise bake job: omninoise bake FILE.toml bakes it (docs/guide/jobs.md).
    <BLANKLINE>
    [[bake]]
    name = "clouds"
    output = "out/clouds.npy"
    resolution = [32, 32, 16]
    bounds = [[-1.0, -1.0, 0.0], [1.0, 1.0, 1.0]]
    <BLANKLINE>
    [bake.source]
    kind = "wave"
    dim = 3
    spectrum = {kind = "fractal", fmin = 1.0, fmax = 8.0, exponent = 1.2}

A job names only what differs from the defaults and what the noise reads: the reader refuses a setting that would
change nothing (an exponent of a band-pass spectrum, a time of still noise), so such a setting of the bake is left
out, as it changes no value. What a bake holds in memory and its job reads from a file is written beside it
(:func:`side_files`): a neural noise's painted map or blend mask as a PNG of hard-edged regions (``JOB_map.png``,
``JOB_mask.png``), a solid texture's photo as a PNG of its pixels (``JOB_photo.png``) and a procedural solid as
saved JSON (``JOB_solid.json``).
:func:`write_job` reads the text back through the job reader and writes it only when every bake it holds is the
one given (the same source, grid, ramp, times and files), atomically.
"""
from __future__ import annotations

import itertools
import json
import os
import re
import tomllib

import numpy as np

from .bake import BakeSpec, frame_path
from .errors import SettingError
from .sources import NeuralSource, WaveSource, describe
from .wavenoise.settings import WaveSettings, read_settings, settings_to_dict

__all__ = ["bake_table", "job_text", "check_job_file", "side_files", "solid_spec", "write_job"]

_BARE = re.compile(r"[A-Za-z0-9_-]+")
HEADER = "# An OmniNoise bake job: omninoise bake FILE.toml bakes it (docs/guide/jobs.md)."


def _by_example(image: str) -> str:
    """Why a by-example noise is not saved as a job: its image (``image``, as the front end names it) is in memory."""
    return (f"a job reads {image}'s image from a file: write its job by hand, with example = \"IMAGE\" in "
            "[bake.source] (docs/guide/jobs.md)")


def check_job_file(path, where: str = "file", example: str | None = None) -> str:
    """``path`` as a job file to write, checked before any work: SettingError naming ``where`` (the setting as the
    front end names it) for a name not ending in .toml or a folder that does not exist, and, where ``example``
    names a by-example image given beside it, for that image (a job reads it from a file)."""
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).lower().endswith(".toml"):
        shown = os.path.basename(os.fspath(path)) if isinstance(path, (str, os.PathLike)) else path
        raise SettingError(where, f"a job file is a .toml file, not {shown!r}")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SettingError(where, f"folder does not exist: {folder}")
    if example:
        raise SettingError(where, _by_example(example))
    return os.fspath(path)


def _spectrum_table(d: dict) -> dict:
    """A spectrum's table without the exponent that only a fractal spectrum reads (the reader refuses it)."""
    return {k: v for k, v in d.items() if k != "exponent" or d["kind"] == "fractal"}


def _class_spec(spec: tuple):
    """A (class, {parameter: value}) pair as a job writes it: the class alone, or {noise, params}."""
    name, params = spec
    return {"noise": name, "params": {k: float(v) for k, v in params.items()}} if params else name


def _neural_table(source: NeuralSource, side: str | None, job_dir: str) -> dict:
    """A neural source's table; ``side``: the file name (from ``job_dir``) of its mask or painted map."""
    from .neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS
    from .paths import neural_model

    table = {"kind": "neural"}
    if os.path.abspath(source.model.folder) != os.path.abspath(neural_model()):
        table["model"] = _relative(source.model.folder, job_dir)
    if source.keys is not None:     # the keyframes set the classes (the reader takes the first's as the noise)
        table["keys"] = [dict(frame=k.frame, noise=k.noise, **({"params": dict(k.params)} if k.params else {}),
                              **({"seed": k.seed} if k.seed else {})) for k in source.keys]
        if source.latent != "fixed":
            table["latent"] = source.latent
        if source.latent == "drift" and source.drift != 0.05:
            table["drift"] = float(source.drift)
    elif source.layout in ("uniform", "blend"):
        table["noise"] = source.spec[0]
        if source.spec[1]:
            table["params"] = dict(source.spec[1])
        if source.layout == "blend":
            table.update(blend=side, noise2=source.spec2[0])
            if source.spec2[1]:
                table["params2"] = dict(source.spec2[1])
    elif source.layout in ("gradient", "corners"):
        table[source.layout] = [_class_spec(s) for s in source.specs]
    else:
        table.update(map=side, regions={"#%02x%02x%02x" % c: _class_spec(s)
                                         for c, s in zip(_region_colours(source), source.specs)})
    if source.layout in ("blend", "painted"):
        if source.width != 32.0:
            table["width"] = float(source.width)
        if source.sharpness != 1.0:
            table["sharpness"] = float(source.sharpness)
    if source.sampler != DEFAULT_SAMPLER:
        table["sampler"] = source.sampler
    if source.steps != DEFAULT_STEPS:
        table["steps"] = int(source.steps)
    if source.seed:
        table["seed"] = int(source.seed)
    if source.tileable:
        table["tileable"] = True
    return table


def _region_colours(source: NeuralSource) -> list:
    """One distinct 8-bit colour per region of a painted source: its own (the panel's swatch colours) where they
    are distinct, others for the rest."""
    own = source.colours if source.colours is not None and len(source.colours) == len(source.specs) else []
    out, used = [], set()
    for i in range(len(source.specs)):      # a region's own colour, unless an earlier region has it
        c = tuple(own[i]) if i < len(own) and tuple(own[i]) not in used else None
        out.append(c)
        used.add(c)
    steps = ((r, g, b) for r in range(0, 256, 51) for g in range(0, 256, 51) for b in range(0, 256, 51))
    every = ((i >> 16, (i >> 8) & 255, i & 255) for i in range(1 << 24))     # past 216 regions
    spare = itertools.chain(steps, every)
    for i, c in enumerate(out):
        if c is None:
            out[i] = next(x for x in spare if x not in used)
            used.add(out[i])
    return out


def _side_image(source: NeuralSource) -> np.ndarray:
    """The mask (0 / 255 grey) or painted map (each region in its colour, (H, W, 3)) a job reads: uint8."""
    if source.layout == "blend":
        return np.where(source.mask > 0.5, 255, 0).astype(np.uint8)
    return np.asarray(_region_colours(source), np.uint8)[source.regions]


#: a side file's kind (:func:`_side_kind`) as a message names it
_SIDE_WORDS = {"mask": "mask", "map": "map", "photo": "photo", "solid": "procedural solid"}


def _side_kind(source) -> tuple | None:
    """(name, extension) of the file a source's job reads beside it, or None: a neural source's blend mask or
    painted map; a solid source's photo (pixels) or procedural solid held in memory (a Blender image, a node
    group's solid)."""
    if isinstance(source, NeuralSource):
        if source.keys is None and source.layout in ("blend", "painted"):
            return ("mask" if source.layout == "blend" else "map", ".png")
        return None
    if getattr(source, "kind", None) != "solid" or isinstance(source.request.exemplar, (str, type(None))):
        return None
    from .solid.procedural.saved import is_saved

    return ("solid", ".json") if is_saved(source.request.exemplar) else ("photo", ".png")


def side_files(path: str, specs: list) -> dict:
    """{index of a spec: the absolute path of the file its job reads beside it, in the job file's folder}: a neural
    source's blend mask or painted map, ``<job name>_mask.png`` / ``_map.png``; a solid source's photo or procedural
    solid held in memory, ``_photo.png`` / ``_solid.json``; a second of a kind ``_map2.png``, and so on."""
    stem = os.path.splitext(os.path.abspath(path))[0]
    out, count = {}, {}
    for i, spec in enumerate(specs):
        kind = _side_kind(spec.source)
        if kind is not None:
            count[kind] = n = count.get(kind, 0) + 1
            out[i] = f"{stem}_{kind[0]}{n if n > 1 else ''}{kind[1]}"
    return out


def _write_side(path: str, source) -> None:
    """The file ``path`` beside a job that ``source`` reads (:func:`side_files`): a neural mask or map as an 8-bit
    PNG; a solid's photo as an 8-bit PNG where its pixels are 8-bit values (an 8-bit photo in Blender), else 16-bit
    (the digest a solid's key holds is of 16-bit values: the same either way); a procedural solid as saved JSON."""
    from ..export.images import write_png

    if isinstance(source, NeuralSource):
        write_png(path, _side_image(source))
        return
    x = source.request.exemplar
    if not isinstance(x, np.ndarray):
        from .solid.procedural import saved

        saved.save(path, x)
        return
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    eight = np.round(x * 255.0)
    write_png(path, eight.astype(np.uint8) if np.abs(x * 255.0 - eight).max() < 1e-3 else
              np.round(x * 65535.0).astype(np.uint16))


def _read_from(spec: BakeSpec, side: str) -> BakeSpec:
    """``spec`` with its solid source's exemplar read from ``side``, the file written beside the job: what the
    job's bake reads, to check the text against.  RuntimeError where the file does not hold the same photo or
    solid (the digest its key holds)."""
    import dataclasses

    from .sources import solid_source

    src = spec.source
    again = solid_source(dataclasses.replace(src.request, exemplar=side), src.scale, getattr(src, "density", 1.0))
    if again.input_sha256 != src.input_sha256:
        raise RuntimeError(f"{os.path.basename(side)} does not hold the exemplar of {spec.name!r}")
    return dataclasses.replace(spec, source=again)


def _exemplar(x, key: str, job_dir: str) -> str:
    """A solid request's exemplar (or ``to``) as a job names it: an image or saved solid's file from ``job_dir``, a
    shipped texture by its name; SettingError for pixels or a solid held in memory (a job reads files)."""
    if not isinstance(x, str):
        raise SettingError(f"source.{key}", "a job reads its image or saved solid from a file; this one is held in "
                                            "memory: write it to a file and name that file")
    return _relative(x, job_dir) if os.path.isfile(x) else x


def _solid_table(source, job_dir: str, side: str | None = None) -> dict:
    """A solid source's table: its request's method, exemplar (``side``: the file beside the job holding one held
    in memory) and the settings that method reads where they differ from a job's defaults (a photo's settings of a
    neural texture only where it reads a photo), its scale and density."""
    from .paths import solid_models
    from .solid.methods import READS
    from .solid.request import PHOTO_READS, SolidRequest

    r, default = source.request, SolidRequest()
    table = {"kind": "solid", "method": r.method}
    if side is not None:
        table["exemplar"] = side
    elif r.exemplar is not None:      # None: a single-texture model's own
        table["exemplar"] = _exemplar(r.exemplar, "exemplar", job_dir)
    photo = r.method != "neural" or side is not None or any(isinstance(x, str) and os.path.isfile(x)
                                                             for x in (r.exemplar, r.to))
    for key in READS[r.method]:
        value = getattr(r, key)
        if key == "model" and value is not None:
            shipped = os.path.dirname(os.path.realpath(value)) == os.path.realpath(solid_models())
            table[key] = (os.path.basename(os.path.realpath(value)) if shipped and os.path.isdir(value)
                          else _relative(value, job_dir) if os.path.isdir(value) else value)
        elif key == "to" and value is not None:
            table.update(to=_exemplar(value, "to", job_dir), mix=float(r.mix))
        elif key == "families" and tuple(value) != tuple(default.families):
            table[key] = list(value)
        elif (key in ("refine", "periodic", "gaussian") or key == "rest" and r.gaussian) and value != getattr(
                default, key) and (photo or key not in PHOTO_READS):
            table[key] = {"refine": int, "rest": str}.get(key, bool)(value)
        elif key == "tile" and value != default.tile:
            table[key] = int(value)
    if r.seed:
        table["seed"] = int(r.seed)
    if source.scale != 1.0:
        table["scale"] = float(source.scale)
    if getattr(source, "dim", 3) == 3 and source.density != 1.0:
        table["density"] = float(source.density)
    return table


def solid_spec(request, size: int, dim: int, scale: float, out: str, names=("out", "save_job", "")) -> BakeSpec:
    """The bake of a checked :class:`~backend.solid.request.SolidRequest` that draws ``out`` as ``omninoise solid``
    does: a volume (``dim`` 3) of ``size`` voxels a side from the origin, ``scale`` voxels per photo pixel; a 2D
    texture's image (a 2D model's, method synthesis) of the plane z = 0, x right and y up from its top-left corner.
    ``names``: how the front end names the output, the job file and the request's settings (a prefix).  SettingError
    for what no job draws so: a fitted solid's .json, a 3D texture's front view (the command line's image of the
    plane y = 0; a job's 2D bake reads the plane z = 0), an image's .npy (a bake's rows run +y first)."""
    from .sources import BoxGrid, solid_px_per_unit, solid_source

    named, where, prefix = names
    ext = os.path.splitext(out)[1].lower()
    if ext == ".json":
        raise SettingError(where, f"a .json {named} is the fitted solid itself, which no job writes: fit it first, "
                                  "then save the job of its volume (the .json as the exemplar, 3D)")
    if dim == 2 and ext == ".npy":
        raise SettingError(where, f"a job's .npy holds an image's rows from the bottom up (+y first, as every bake's "
                                  f"array), {named}'s from the top: write {named} as .png or .exr")
    source = solid_source(request, where=prefix)     # made at its first use: no fit or encoding here
    if dim == 2 and source.dim != 2:
        raise SettingError(where, f"{named}'s image is a solid's front view (the plane y = 0), a job's 2D bake its "
                                  "plane z = 0 (seen from above): save a volume's job (3D), or draw the image")
    extent = size / (solid_px_per_unit(request, prefix) * scale)
    box = ((0.0, 0.0, 0.0), (extent,) * 3) if dim == 3 else ((0.0, -extent, 0.0), (extent, 0.0, 0.0))
    return BakeSpec("solid", source, BoxGrid((size,) * dim, box), os.path.abspath(out)).validate()


def _source_table(source, side: str | None = None, job_dir: str = ".") -> dict:
    if isinstance(source, NeuralSource):
        return _neural_table(source, side, job_dir)
    if source.kind == "solid":
        return _solid_table(source, job_dir, side)
    if not isinstance(source, WaveSource):
        raise SettingError("source", f"a {source.kind} bake is written as a job by hand (docs/guide/jobs.md); "
                                     "only wave noise, neural noise and solid texture bakes are saved as job files")
    s = source.settings
    if s.example is not None:
        raise SettingError("source", _by_example("a by-example noise"))
    ours, default = settings_to_dict(read_settings(s)), settings_to_dict(WaveSettings())
    table = {"kind": "wave", "dim": ours.pop("dim")}
    table.update({k: v for k, v in ours.items() if v != default.get(k)})
    for key in ("spectrum", "transition_to"):
        if key in table:
            table[key] = _spectrum_table(table[key])
    if "axis_spectra" in table:
        table["axis_spectra"] = [_spectrum_table(a) for a in table["axis_spectra"]]
    if source.w_offset:
        table["w_offset"] = float(source.w_offset)
    return table


def _relative(path: str, folder: str) -> str:
    """``path`` from ``folder`` where it can be (the same drive), else absolute; '/' on every system."""
    try:
        rel = os.path.relpath(path, folder)
    except ValueError:          # another drive (Windows)
        return os.path.abspath(path).replace(os.sep, "/")
    return rel.replace(os.sep, "/")


def bake_table(spec: BakeSpec, job_dir: str, side: str | None = None) -> dict:
    """The ``[[bake]]`` table of ``spec`` in a job file in ``job_dir`` (its output from there; ``side``: the file
    of its neural source's mask or painted map, :func:`side_files`)."""
    from .jobs import default_times

    table = dict(name=spec.name, output=_relative(spec.output, job_dir), **spec.grid.to_dict())
    time0, dt = default_times(spec.source, spec.frames)
    if spec.frames is not None:
        table["frames"] = [int(f) for f in spec.frames]
        if spec.time_step != dt or not getattr(spec.source, "keys", None):   # a wave bake's step is always written
            table["time_step"] = float(spec.time_step)
    if spec.source.animated and spec.time != time0:
        table["time"] = float(spec.time)
    ext = os.path.splitext(spec.output)[1].lower()
    if spec.half and ext in (".exr", ".vdb"):
        table["half"] = True
    table["source"] = _source_table(spec.source, None if side is None else _relative(side, job_dir), job_dir)
    if spec.transfer is not None:
        table["transfer"] = spec.transfer.to_dict()
    return table


def _value(v) -> str:
    """A TOML value: strings as basic strings (JSON's escapes are TOML's), floats as Python writes them (read back
    to the same double), lists and inline tables."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):      # JSON escapes every control character TOML refuses but DEL
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):     # keys bare where TOML allows ("scale"), else quoted ("#ff0000")
        return "{" + ", ".join(f"{k if _BARE.fullmatch(k) else _value(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML value for {v!r}")


def _table(header: str, table: dict) -> list:
    lines = ["", header]
    for k, v in table.items():
        if k == "stops":        # a ramp's stops, one a line
            lines += [f"{k} = ["] + [f"  {_value(x)}," for x in v] + ["]"]
        else:
            lines.append(f"{k} = {_value(v)}")
    return lines


def job_text(specs: list, job_dir: str, sides: dict | None = None) -> str:
    """The TOML text of a job file in ``job_dir`` that bakes ``specs`` (:class:`~backend.bake.BakeSpec`); its
    ``output_root`` is the outputs' common folder where that lies outside ``job_dir``. ``sides``: the files written
    beside the job (:func:`side_files`), which a source holding its mask, map, photo or solid in memory needs."""
    sides = sides or {}
    missing = [s.name for i, s in enumerate(specs) if i not in sides and _side_kind(s.source) is not None]
    if missing:
        raise SettingError("source", f"{missing[0]!r} reads its mask, map, photo or solid from a file: name it "
                                     "(side_files)")
    tables = [bake_table(s, job_dir, sides.get(i)) for i, s in enumerate(specs)]
    lines = [HEADER]
    folders = [os.path.dirname(os.path.abspath(s.output)) for s in specs]
    try:
        root = os.path.commonpath(folders + [os.path.abspath(job_dir)]) == os.path.abspath(job_dir)
    except ValueError:      # another drive
        root = False
    if not root:
        lines.append(f"output_root = {_value(_relative(os.path.commonpath(folders), job_dir))}")
    for t in tables:
        t = dict(t)
        source, transfer = t.pop("source"), t.pop("transfer", None)
        lines += _table("[[bake]]", t)
        lines += _table("[bake.source]", source)
        if transfer is not None:
            lines += _table("[bake.transfer]", transfer)
    return "\n".join(lines) + "\n"


def _same(a: BakeSpec, b: BakeSpec) -> bool:
    """Whether two specs bake the same files: every frame's key (source, grid, ramp, time, format) and path."""
    return (a.frame_list() == b.frame_list() and os.path.abspath(a.output) == os.path.abspath(b.output)
            and all(a.key(f) == b.key(f) for f in a.frame_list()))


def write_job(path: str, specs: list, reads: dict | None = None, where: str = "file") -> str:
    """Write the job file ``path`` (.toml) that bakes ``specs``, atomically, and beside it the files its sources
    read that are held in memory (:func:`side_files`: neural masks and painted maps, solid photos and procedural
    solids); returns its text. SettingError naming what cannot be written (:func:`check_job_file`, a source other
    than wave noise, neural noise or a solid texture, a by-example noise, a side file's name that is an output or
    one of ``reads``: {path of a file the front end reads: who reads it, "--map reads"}), named as ``where`` where
    it is the job file's, and RuntimeError where the text would bake anything else than ``specs``; then no job is
    written, and the side files written to check it are removed (one that was there before is put back)."""
    from ..export.atomic import write_text
    from .jobs import JobError, parse_job

    path = check_job_file(path, where)
    job_dir = os.path.dirname(os.path.abspath(path))
    sides = side_files(path, specs)
    read = {os.path.realpath(f): who for f, who in (reads or {}).items() if f}
    words = {i: _SIDE_WORDS[_side_kind(specs[i].source)[0]] for i in sides}
    for i, side in sides.items():     # what it writes beside the job: never over a file read
        if os.path.realpath(side) in read:
            raise SettingError(where, f"the job writes its {words[i]} to {os.path.basename(side)}, the file "
                                      f"{read[os.path.realpath(side)]}: save the job under another name")
    text = job_text(specs, job_dir, sides)
    outputs = {os.path.abspath(frame_path(s.output, f)) for s in specs for f in s.frame_list()}
    taken = [i for i, f in sides.items() if f in outputs]
    if taken:
        raise SettingError("job file", f"{os.path.basename(sides[taken[0]])} is a bake's output; the job writes its "
                                       f"{words[taken[0]]} there: save the job under another name")
    from ..export.atomic import atomic_path

    kept = {}       # a map saved with the job before: put back if this job is not written
    for f in sides.values():
        if os.path.isfile(f):
            with open(f, "rb") as fh:
                kept[f] = fh.read()
    try:
        for i, f in sides.items():      # the job reads them; written before it is read back
            _write_side(f, specs[i].source)
        parsed = parse_job(tomllib.loads(text), job_dir, path)
        for i, (spec, (name, got)) in enumerate(zip(specs, parsed)):
            if isinstance(got, JobError):
                raise SettingError("job file", str(got))
            if i in sides and not isinstance(spec.source, NeuralSource):
                spec = _read_from(spec, sides[i])
            if not _same(spec, got):
                raise RuntimeError(f"the job file would bake {name!r} otherwise than asked: "
                                   f"{describe(bake_table(got, job_dir, sides.get(i)))}")
    except BaseException:
        for f in sides.values():
            if f not in kept:
                if os.path.exists(f):       # one not written yet stays away
                    os.remove(f)
                continue
            with atomic_path(f) as tmp:
                with open(tmp, "wb") as fh:
                    fh.write(kept[f])
        raise
    write_text(path, text)
    return text
