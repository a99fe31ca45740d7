"""The Python API: four calls that do what the ``omninoise`` command does, through the same code.

Each call returns arrays (float32, indexed ``[y, x]`` or ``[z, y, x]`` as the command line's ``.npy`` files are)
or, given ``out``, writes the file the command line would write for that name (``.png``, ``.exr``, ``.npy``,
``.vdb``; atomically) and returns its path.  Bad settings raise :class:`~omninoise.backend.errors.SettingError`
(a ``ValueError``) naming the setting, before any work.  ``progress`` is called with the fraction done in [0, 1].

>>> import omninoise
>>> img = omninoise.wave(64, extent=2.0, spectrum=("bandpass", 4, 8), directions=8, seed=3)
>>> img.shape, img.dtype
((64, 64), dtype('float32'))
>>> bool(abs(float(img.mean())) < 0.5 and img.std() > 0)
True
>>> omninoise.wave(8, spectrum=("bandpass", 4, 8), directions=0)
Traceback (most recent call last):
    ...
omninoise.backend.errors.SettingError: directions: must lie in [1, 4096], got 0

Sample positions follow one convention everywhere (``docs/guide/formats.md``): the ``N`` samples of an axis sit
at the cell centres ``(i + 1/2) * extent / N`` of ``[0, extent)``.
"""
from __future__ import annotations

import dataclasses
import os
import warnings
from typing import Callable

import numpy as np

from .backend import limits
from .backend.errors import SettingError

__all__ = ["wave", "neural", "solid", "bake"]

Progress = Callable[[float], None] | None


def _spectrum(value, name: str = "spectrum"):
    """A spectrum setting given as a Spectrum, a dict of its fields or a (kind, fmin, fmax[, exponent]) tuple."""
    from .backend.wavenoise.spectra import Spectrum

    if value is None or isinstance(value, (Spectrum, dict)) or (name == "spectrum" and isinstance(value, str)):
        return value            # a dict's keys and a kind's name are checked with the settings, naming the setting
    if isinstance(value, (tuple, list)) and len(value) in (3, 4) and isinstance(value[0], str):
        return Spectrum(*value)
    raise SettingError(name, f"expected a Spectrum, a dict or a (kind, fmin, fmax[, exponent]) tuple, got {value!r}")


def _plain(value):
    """A Python setting as a job file would hold it: spectra as tables, arrays and tuples as lists, numpy numbers
    as Python's."""
    from .backend.wavenoise.settings import spectrum_to_dict
    from .backend.wavenoise.spectra import Spectrum

    if isinstance(value, Spectrum):
        return spectrum_to_dict(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    return value


def _check_flags(**flags) -> None:
    """SettingError naming a switch that is not True or False (``half="no"`` would have been read as true)."""
    for name, value in flags.items():
        if not isinstance(value, (bool, np.bool_)):
            raise SettingError(name, f"expected True or False, got {value!r}")


def _check_progress(progress) -> None:
    if progress is not None and not callable(progress):
        raise SettingError("progress", f"expected a function of the fraction done, or None, got {progress!r}")


def _check_out(out: str, allowed: tuple, what: str, read: tuple = ()) -> str:
    """The extension of ``out``, a file of ``allowed`` kinds that is not one of the files ``read`` (name, value)."""
    if not isinstance(out, (str, os.PathLike)):
        raise SettingError("out", f"expected a file path, got {out!r}")
    out = os.fspath(out)
    from .backend.bake import check_not_read, check_one_file, output_type

    check_one_file(out, "out")
    check_not_read(out, "out", read)
    ext = output_type(out, allowed, what, "out")
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        raise SettingError("out", f"output folder does not exist: {folder}")
    return ext


def _check_size(size, low: int = 1) -> int:
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < low:
        raise SettingError("size", f"must be a whole number >= {low}, got {size!r}")
    return int(size)


def wave(size: int = 256, extent: float = 4.0, *, time: float = 0.0, out: str | None = None,
         transfer: str | None = None, half: bool = False, progress: Progress = None, save_job: str | None = None,
         **settings):
    """Wave noise (Guehl et al. 2025) on a ``size``-sample grid over ``[0, extent)`` per axis.

    ``settings`` are :class:`~omninoise.backend.wavenoise.settings.WaveSettings` fields (``dim`` 2, 3 or 4,
    ``spectrum``, ``directions``, ``seed``, ``output``, ``waveform``, ``cellular``, ...), checked as a job file's
    ``[bake.source]`` keys are (``docs/guide/job-reference.md``); a spectrum (``spectrum``, ``transition_to``, each
    of ``axis_spectra``) may be a :class:`~omninoise.backend.wavenoise.spectra.Spectrum`, a dict of its fields or a
    tuple ``(kind, fmin, fmax[, exponent])`` with frequencies in cycles per unit, and ``spectrum`` its kind's name
    alone.  ``time`` is the animation time (or the fourth coordinate w for ``dim=4``).

    Returns float32 ``(size, size)`` for ``dim=2`` and ``(size, size, size)`` (``[z, y, x]``) for 3D and 4D, or,
    with ``out``, writes ``.npy``, ``.exr``, ``.png`` (2D) or ``.vdb`` (3D) as ``omninoise wave -o`` does, through
    the RGBA ramp ``transfer`` (a preset name or a ramp ``.json``) where given, and returns the path.  With
    ``save_job`` too (a ``.toml`` path), it writes the job file that bakes ``out`` so (``omninoise bake``, a farm)
    instead of baking it, as ``omninoise wave --save-job`` does, and returns the job's path.

    >>> vol = wave(16, dim=3, spectrum=("fractal", 1, 6), directions=8)
    >>> vol.shape
    (16, 16, 16)
    """
    from .backend.bake import BakeSpec, check_bake_memory, evaluate_values, run_bake
    from .backend.sources import BoxGrid, WaveSource
    from .backend.transfer import load_transfer
    from .backend.wavenoise.schema import WAVE_SETTINGS
    from .backend.wavenoise.settings import WaveSettings, check_none, check_read, check_time, settings_from_dict

    _check_progress(progress)
    size = _check_size(size)
    limits.in_range("extent", extent, limits.MIN_LENGTH, limits.MAX_COORD)
    limits.time("time", time)
    _check_flags(half=half)
    known = [f.name for f in dataclasses.fields(WaveSettings)]
    for name in settings:
        if name not in known:
            raise TypeError(f"wave() got an unexpected keyword argument {name!r}; its settings are "
                            f"{', '.join(known)}")
    for name in ("spectrum", "transition_to"):
        if name in settings:
            settings[name] = _spectrum(settings[name], name)
    if isinstance(settings.get("axis_spectra"), (tuple, list)):
        settings["axis_spectra"] = [_spectrum(v, f"axis_spectra[{i}]") for i, v in enumerate(settings["axis_spectra"])]
    example = settings.pop("example", None)
    # read as a job file's settings are: checked against their table (types, ranges, lengths), then joined; a
    # setting that changes nothing beside the others (a profile without waveform="custom") is refused
    check_none(settings)
    plain = {k: _plain(v) for k, v in settings.items() if v is not None}
    WAVE_SETTINGS.check(plain, "")
    s = settings_from_dict(plain, example)
    check_read(s, list(settings), lambda k, v=None: k if v is None else f"{k}={v!r}")
    check_time("time", time, s, "speed", "dim=4")
    rank = 2 if s.dim == 2 else 3          # 3D and 4D noise fill a volume (4D: at w = time)
    if out is not None:
        ext = _check_out(out, (".npy", ".exr", ".png") if rank == 2 else (".npy", ".vdb"), f"a {s.dim}D grid",
                         (("transfer", transfer),))
        if half and ext not in (".exr", ".vdb"):
            raise SettingError("half", f"writes 16-bit floats into .exr and .vdb only, not {ext}")
    elif transfer is not None or half or save_job is not None:
        raise SettingError("transfer" if transfer is not None else "half" if half else "save_job",
                           "applies to a written file; give out= too")
    if save_job is not None:
        from .backend.job_file import check_job_file

        save_job = check_job_file(save_job, "save_job", "the example" if example is not None else None)
    check_bake_memory("size", (size,) * rank, ext if out is not None else None,
                      "ramp" if transfer is not None else "values", f"a {size}-sample {s.dim}D grid")
    grid = BoxGrid((size,) * rank, ((0.0, 0.0, 0.0), (float(extent),) * 3))
    source = WaveSource(s)
    if out is None:
        return evaluate_values(source, grid.validate(), float(time), progress)
    tf = load_transfer(transfer) if transfer else None
    spec = BakeSpec("wave", source, grid, out, tf, time=float(time), half=half)
    if save_job is not None:
        from .backend.job_file import write_job

        write_job(save_job, [spec.validate()])
        return save_job
    run_bake(spec, progress, force=True)
    return out


def neural(noise: str, size: int = 256, *, params: dict | None = None, seed: int = 0, steps: int | None = None,
           sampler: str | None = None, tileable: bool = False, model: str | None = None, out: str | None = None,
           progress: Progress = None, save_job: str | None = None):
    """Neural noise (Maesumi et al. 2024): one class of the shipped diffusion model, ``size`` x ``size`` pixels.

    ``noise`` is a class name (``omninoise neural --list`` lists them with their ``params``), ``seed`` picks the
    sample, ``steps`` and ``sampler`` the solver (defaults: the command line's), ``tileable`` makes a seamless tile
    (``size`` a multiple of 8), ``model`` another model folder.

    Returns float32 ``(size, size)`` in [0, 1], top row first, or, with ``out`` (``.png``, ``.exr``, ``.npy``),
    writes it as ``omninoise neural -o`` does and returns the path.  With ``save_job`` too (a ``.toml`` path; ``out``
    a ``.png`` or ``.exr``), it writes the job file that draws ``out`` so (``omninoise bake``, a farm) instead of
    drawing it, as ``omninoise neural --save-job`` does, and returns the job's path.

    >>> img = neural("perlin", 32, steps=2, seed=1)
    >>> img.shape, bool(0.0 <= img.min() and img.max() <= 1.0)
    ((32, 32), True)
    """
    from .backend.neural.generate import check_memory as neural_memory
    from .backend.neural.model import ModelError, NeuralNoiseModel
    from .backend.neural.request import NeuralRequest, generate_request
    from .backend.neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS
    from .backend.paths import neural_model

    _check_progress(progress)
    size = _check_size(size, 8)
    if out is not None:
        _check_out(out, (".png", ".exr", ".npy"), "a neural noise image")
    elif save_job is not None:
        raise SettingError("save_job", "applies to a written file; give out= too")
    if save_job is not None:
        from .backend.job_file import check_job_file

        save_job = check_job_file(save_job, "save_job")
        if os.fspath(out).lower().endswith(".npy"):
            raise SettingError("save_job", "a job's .npy holds an image's rows from the bottom up (+y first, as "
                                           "every bake's array), out='s from the top: write out as .png or .exr")
    neural_memory("size", size, size)
    if model is not None and (not isinstance(model, (str, os.PathLike)) or not os.fspath(model)):
        raise SettingError("model", f"expected a model folder's path, got {model!r}")
    try:
        net = NeuralNoiseModel(os.fspath(model) if model is not None else neural_model())
    except ModelError as exc:
        raise SettingError("model", str(exc)) from None
    req = NeuralRequest("uniform", [(noise, params)], width=size, height=size, seed=seed,
                        steps=DEFAULT_STEPS if steps is None else steps, sampler=sampler or DEFAULT_SAMPLER,
                        tileable=tileable).check(net)
    if save_job is not None:
        from .backend.bake import BakeSpec
        from .backend.job_file import write_job
        from .backend.sources import BoxGrid, NeuralSource

        spec = BakeSpec("neural", NeuralSource.from_request(net.folder, req), BoxGrid((size, size)),
                        os.path.abspath(os.fspath(out)))
        write_job(save_job, [spec.validate()])
        return save_job
    cb = None if progress is None else (lambda i, n, x0: progress((i + 1) / n))
    img = np.asarray(generate_request(net, req, callback=cb), np.float32)
    if out is None:
        return img
    from .export.images import write_unit_image

    write_unit_image(out, img)
    return out


def solid(exemplar: str | np.ndarray, size: int = 256, *, dim: int = 2, method: str | None = None, seed: int = 0,
          scale: float = 1.0, refine: int = 0, periodic: bool = True, model: str | None = None,
          families: tuple | None = None, out: str | None = None, progress: Progress = None,
          save_job: str | None = None):
    """A solid texture from a shipped texture's name (``omninoise solid --list``) or a photo (a file, as a string or
    a path, or sRGB float pixels in [0, 1]: ``(H, W, 3)``, grey ``(H, W)`` or with an opaque alpha ``(H, W, 4)``).

    ``method`` is ``"neural"`` (the models' texture, 2D or 3D), ``"spectral"`` (the photo's spectrum and colours
    on every cut, 2D or 3D), ``"procedural"`` (rings, layers, cells or bricks fitted to the photo, 2D or 3D) or
    ``"synthesis"`` (a seamless 2D image); left out, ``"neural"``, or ``"procedural"`` for a saved procedural
    solid; ``scale`` is output pixels per exemplar
    pixel; ``refine`` search steps improve a photo's code; ``periodic`` keeps a photo's courses and planks;
    ``families`` are the kinds of solid a procedural fit tries (of ``"rings"``, ``"layers"``, ``"cells"``,
    ``"bonds"`` and ``"herringbone"``; all but ``"herringbone"`` by default).  With ``method="procedural"`` the
    fitted solid itself is saved by an ``out`` ending in ``.json``, and drawn again, without fitting, from that file
    (or a ``ProceduralField``) given as the exemplar, with no method.

    Returns scene-linear RGB float32: ``(size, size, 3)`` for ``dim=2`` (the front view: x right, z up, top row
    first) or ``(size, size, size, 3)`` indexed ``[z, y, x]`` for ``dim=3``; or, with ``out``, writes it as
    ``omninoise solid -o`` does (2D ``.png``/``.exr``/``.npy``, 3D ``.vdb``/``.npy``; the fitted procedural solid
    ``.json``) and returns the path.  With ``save_job`` too (a ``.toml`` path; ``out`` a volume, or an image of a
    2D texture: a 2D model's, ``method="synthesis"``), it writes the job file that draws ``out`` so (``omninoise
    bake``, a farm) instead of drawing it, as ``omninoise solid --save-job`` does, and returns the job's path.
    A float photo file whose pixels pass white or fall under black (where 1 % or more do) is read clipped to
    [0, 1], with a ``UserWarning`` saying how much.

    >>> rgb = solid("grass", 16)
    >>> rgb.shape, rgb.dtype
    ((16, 16, 3), dtype('float32'))
    """
    from .backend.colour import srgb_to_linear
    from .backend.solid.request import SolidRequest, method_for, pixels_as_rgb

    _check_progress(progress)
    exemplar, model = (os.fspath(x) if isinstance(x, os.PathLike) else x for x in (exemplar, model))  # Paths too
    method = method_for(exemplar, method)
    exemplar = pixels_as_rgb(exemplar, "exemplar")      # grey or RGBA pixels, as an image file's are read
    size = _check_size(size)
    if dim not in (2, 3) or isinstance(dim, bool):
        raise SettingError("dim", f"must be 2 or 3, got {dim!r}")
    limits.scale("scale", scale)
    allowed = (".png", ".exr", ".npy") if dim == 2 else (".vdb", ".npy")
    ext = None if out is None else _check_out(out, allowed + ((".json",) if method == "procedural" else ()),
                                              f"a {dim}D texture", (("exemplar", exemplar),))
    if ext != ".json":      # a fitted solid's .json draws nothing
        from .backend.bake import check_bake_memory

        check_bake_memory("size", (size,) * dim, ext, "rgb", f"a {size}-sample {dim}D texture")
    if ext == ".vdb":
        from .backend.bake import require_vdb

        require_vdb("out")
    if save_job is not None:
        from .backend.job_file import check_job_file

        if out is None:
            raise SettingError("save_job", "applies to a written file; give out= too")
        save_job = check_job_file(save_job, "save_job")
        if not isinstance(exemplar, str):
            raise SettingError("exemplar", "a job reads its image or saved solid from a file: give the file's path")
    for name, value, unset in (("dim", dim, 2), ("size", size, 256), ("scale", scale, 1.0)):
        if ext == ".json" and value != unset:
            raise SettingError(name, "a .json output holds the fitted solid, not a drawing of it: leave "
                                     f"{name} out, and give it when the .json is drawn")
    kinds = {} if families is None else dict(families=families)
    given = [k for k, v in (("model", model is not None), ("refine", refine != 0), ("periodic", not periodic),
                            ("families", families is not None)) if v]
    req = SolidRequest(model, exemplar, None, 0.0, refine, seed, periodic, method=method, **kinds).check()
    req.check_reads(given).check_pixels()      # a photo no method can use is named before any work
    if isinstance(exemplar, str):
        from .export.images import clipped_notes

        for note in clipped_notes(exemplar):        # a float photo's colours past white or under black
            warnings.warn(note, UserWarning, stacklevel=2)
    if save_job is not None:
        from .backend.job_file import solid_spec, write_job

        write_job(save_job, [solid_spec(req, size, dim, float(scale), os.fspath(out))], None, "save_job")
        return save_job
    if ext == ".json":          # the fitted procedural solid itself
        from .backend.solid.procedural import saved

        saved.save(os.fspath(out), req.procedural_field(progress=progress))
        return os.fspath(out)
    from .backend.bake import split_progress

    making, drawing = split_progress(progress)
    if dim == 3:
        from .backend.bake import BakeSpec, evaluate_values, run_bake
        from .backend.sources import BoxGrid, solid_volume

        source, extent = solid_volume(req, size, float(scale), progress=making)
        grid = BoxGrid((size,) * 3, ((0.0, 0.0, 0.0), (extent,) * 3))
        if out is None:
            return evaluate_values(source, grid.validate(), 0.0, drawing)
        run_bake(BakeSpec("solid", source, grid, out), drawing, force=True)
        return out
    rgb = req.front_image(size, float(scale), progress=making, draw_progress=drawing)
    if drawing is not None and req.method == "synthesis":        # a synthesised tile's image is drawn at once
        drawing(1.0)
    if out is None:
        return srgb_to_linear(rgb)     # float32, as the command line's .npy holds it
    from .export.images import write_unit_image

    write_unit_image(out, rgb, None if ext == ".png" else srgb_to_linear(rgb))
    return out


def bake(job: str, *, only: list | None = None, force: bool = False, keep_going: bool = False,
         progress: Progress = None) -> list:
    """Run the bakes of a TOML job file (``docs/guide/jobs.md``) as ``omninoise bake JOB`` does: outputs that are
    up to date are skipped unless ``force``; ``only`` names the bakes to run.

    Returns one :class:`~omninoise.backend.jobs.JobOutcome` per bake (``name``, ``status`` ``"baked"``,
    ``"up to date"``, ``"invalid"``, ``"failed"`` or ``"cancelled"``, ``message``).  A job file that cannot be read
    raises :class:`~omninoise.backend.jobs.JobError`; without ``keep_going`` the first failed bake stops the job and
    ends the list.

    >>> import os, tempfile
    >>> d = tempfile.mkdtemp()
    >>> with open(os.path.join(d, "job.toml"), "w") as fh:
    ...     _ = fh.write('[[bake]]\\nname = "clouds"\\noutput = "clouds.exr"\\nresolution = [16, 16]\\n'
    ...                  '[bake.source]\\nkind = "wave"\\n')
    >>> [(o.name, o.status) for o in bake(os.path.join(d, "job.toml"))]
    [('clouds', 'baked')]
    >>> [(o.name, o.status) for o in bake(os.path.join(d, "job.toml"))]
    [('clouds', 'up to date')]
    """
    from .backend.jobs import run_job

    _check_progress(progress)
    _check_flags(force=force, keep_going=keep_going)
    if only is not None and (isinstance(only, (str, bytes)) or not all(isinstance(n, str) for n in only)):
        raise SettingError("only", f"expected a list of bake names, got {only!r}")
    if only is not None and len(only) == 0:
        raise SettingError("only", "names no bake: leave it out to run every bake of the job")
    if not isinstance(job, (str, os.PathLike)):
        raise SettingError("job", f"expected a job file's path, got {job!r}")
    if not os.path.isfile(job):
        raise SettingError("job", f"job file not found: {job!r}")
    return run_job(os.fspath(job), keep_going=keep_going, force=force, only=only, progress=progress)
