"""A bake as the job file that bakes it again: the inverse of :mod:`backend.jobs`' reader.

The Bake Noise panel saves its bake this way (**Save as Job File**), so that ``omninoise bake JOB.toml``, a farm
(``omninoise farm``) or the Batch Job panel bakes the same files on another machine, without Blender::

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
out, as it changes no value. :func:`write_job` reads the text back through the job reader and writes it only when
every bake it holds is the one given (the same source, grid, ramp, times and files), atomically.
"""
from __future__ import annotations

import json
import os
import tomllib

from .bake import BakeSpec
from .errors import SettingError
from .sources import WaveSource, describe
from .wavenoise.settings import WaveSettings, read_settings, settings_to_dict

__all__ = ["bake_table", "job_text", "check_job_file", "write_job"]

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


def _source_table(source) -> dict:
    if not isinstance(source, WaveSource):
        raise SettingError("source", f"a {source.kind} bake is written as a job by hand (docs/guide/jobs.md); "
                                     "only wave noise bakes are saved as job files")
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


def bake_table(spec: BakeSpec, job_dir: str) -> dict:
    """The ``[[bake]]`` table of ``spec`` in a job file in ``job_dir`` (its output from there)."""
    table = dict(name=spec.name, output=_relative(spec.output, job_dir), **spec.grid.to_dict())
    if spec.frames is not None:
        table.update(frames=[int(f) for f in spec.frames], time_step=float(spec.time_step))
    if spec.source.animated and spec.time != 0.0:
        table["time"] = float(spec.time)
    ext = os.path.splitext(spec.output)[1].lower()
    if spec.half and ext in (".exr", ".vdb"):
        table["half"] = True
    table["source"] = _source_table(spec.source)
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
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML value for {v!r}")


def _table(header: str, table: dict) -> list:
    lines = ["", header]
    for k, v in table.items():
        if k == "stops":        # a ramp's stops, one a line
            lines += [f"{k} = ["] + [f"  {_value(x)}," for x in v] + ["]"]
        else:
            lines.append(f"{k} = {_value(v)}")
    return lines


def job_text(specs: list, job_dir: str) -> str:
    """The TOML text of a job file in ``job_dir`` that bakes ``specs`` (:class:`~backend.bake.BakeSpec`); its
    ``output_root`` is the outputs' common folder where that lies outside ``job_dir``."""
    tables = [bake_table(s, job_dir) for s in specs]
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


def write_job(path: str, specs: list) -> str:
    """Write the job file ``path`` (.toml) that bakes ``specs``, atomically; returns its text. SettingError naming
    what cannot be written (:func:`check_job_file`, a source other than wave noise, a by-example noise), and
    RuntimeError where the text
    would bake anything else than ``specs``, before anything is written."""
    from ..export.atomic import write_text
    from .jobs import JobError, parse_job

    path = check_job_file(path)
    job_dir = os.path.dirname(os.path.abspath(path))
    text = job_text(specs, job_dir)
    parsed = parse_job(tomllib.loads(text), job_dir, path)
    for spec, (name, got) in zip(specs, parsed):
        if isinstance(got, JobError):
            raise SettingError("job file", str(got))
        if not _same(spec, got):
            raise RuntimeError(f"the job file would bake {name!r} otherwise than asked: "
                               f"{describe(bake_table(got, job_dir))}")
    write_text(path, text)
    return text
