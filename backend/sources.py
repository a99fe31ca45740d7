"""Bake sources: anything that fills a box grid with scalar noise values.

A source answers ``evaluate(grid box) -> float32 array``; :mod:`backend.bake`
slices the bake into slabs, maps values through a transfer function and hands
them to writers.  Wave noise is a source here; the neural sources of later
issues implement the same small interface.

Grids are voxel-centred: a :class:`BoxGrid` with ``resolution`` (nx, ny[, nz])
over world ``bounds`` puts sample (i, j, k) at ``lo + (i + 1/2, j + 1/2, k + 1/2) * voxel``,
which is where OpenVDB puts voxel centres under a linear transform with that
voxel size and translation ``lo + voxel / 2``.
"""
from __future__ import annotations

import hashlib
import json
import threading
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from . import limits
from .errors import SettingError
from .paths import in_job, in_job_or_name

__all__ = ["BoxGrid", "Source", "WaveSource", "NeuralSource", "SolidSource", "SpectralSource", "AutoSource",
           "solid_volume", "solid_source", "solid_px_per_unit", "source_from_dict", "register_source", "source_kinds",
           "SOURCES"]

_F = np.float32


@dataclass(frozen=True)
class BoxGrid:
    """A voxel-centred grid.

    resolution  (nx, ny) for images or (nx, ny, nz) for volumes, x first
    bounds      ((x0, y0, z0), (x1, y1, z1)) world box; an image lies in the plane z = z0
    """

    resolution: tuple
    bounds: tuple = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))

    def validate(self) -> "BoxGrid":
        res = tuple(self.resolution)
        if len(res) not in (2, 3) or any(int(n) != n or n < 1 for n in res):
            raise SettingError("resolution", f"expected 2 or 3 positive whole numbers, got {list(res)}")
        lo, hi = (np.asarray(b, np.float64) for b in self.bounds)
        if lo.shape != (3,) or hi.shape != (3,):
            raise SettingError("bounds", f"expected [[x0, y0, z0], [x1, y1, z1]], got {self.bounds}")
        n = len(res)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise SettingError("bounds", f"must be finite numbers, got {self.bounds}")
        if max(np.abs(lo).max(), np.abs(hi).max()) > limits.MAX_COORD:
            raise SettingError("bounds", f"coordinates must lie within +-{limits.MAX_COORD:g} units, got {self.bounds}")
        if not np.all(hi[:n] > lo[:n]):
            raise SettingError("bounds", f"max must exceed min on x, y{', z' if n == 3 else ''}: {self.bounds}")
        if not np.all(hi[:n] - lo[:n] >= limits.MIN_LENGTH):
            raise SettingError("bounds", f"the box must be at least {limits.MIN_LENGTH:g} units wide on x, "
                                         f"y{', z' if n == 3 else ''}: {self.bounds}")
        if np.prod(np.asarray(res, np.float64)) > 2 ** 34:
            raise SettingError("resolution", f"{list(res)} is more than 2^34 voxels")
        # the baked field (float32), with RGBA colour four times that
        limits.check_memory("resolution", float(np.prod(np.asarray(res, np.float64))) * 4 * 5, f"a {list(res)} grid")
        return self

    @property
    def rank(self) -> int:
        return len(self.resolution)

    @property
    def shape(self) -> tuple:
        """Array shape: (ny, nx) or (nz, ny, nx)."""
        return tuple(int(n) for n in reversed(self.resolution))

    @property
    def voxel(self) -> np.ndarray:
        """float64 (rank,): spacing along x, y[, z]."""
        lo, hi = (np.asarray(b, np.float64) for b in self.bounds)
        n = np.asarray(self.resolution, np.float64)
        return (hi[: self.rank] - lo[: self.rank]) / n

    @property
    def first(self) -> np.ndarray:
        """float64 (3,): world position of sample 0 (the first voxel's centre)."""
        p = np.asarray(self.bounds[0], np.float64).copy()
        p[: self.rank] += 0.5 * self.voxel
        return p

    def to_dict(self) -> dict:
        return dict(resolution=[int(n) for n in self.resolution],
                    bounds=[[float(c) for c in b] for b in self.bounds])


class Source(Protocol):
    """What a bake needs from a noise.

    kind      short name ("wave")
    dim       coordinates the noise takes: 2, 3 or 4 (4D: W is the bake's time)
    animated  True when the output changes with time (``animated_by``, where a kind has it: the settings that
              make it change, for a frame range of one that does not)
    chunkable True when any sub-box may be evaluated alone (else the whole grid at once)
    unit      (optional, False when absent) True when every value lies in [0, 1] (neural noise): an 8-bit PNG holds
              the values as they are, not stretched over their percentiles as a preview of unbounded noise is
    """

    kind: str
    dim: int
    animated: bool
    chunkable: bool

    def evaluate(self, shape: tuple, first: np.ndarray, step: np.ndarray, time: float,
                 progress: Callable[[float], None] | None = None,
                 cancel: Callable[[], bool] | None = None, start: tuple | None = None) -> np.ndarray:
        """float32 ``shape`` ((ny, nx) or (nz, ny, nx)) at first + (start + index) * step.

        first (3,) world position of the grid's sample 0; step (rank,); start (rank,)
        index of this box's first sample, x first (default zeros).  A slab's values
        must equal the same samples of the whole grid.
        """

    def to_dict(self) -> dict:
        """Everything that determines the values, as plain JSON types (for up-to-date checks)."""

    # A source may also make its texture at its first use (a fit, a choice: :class:`_Prepared`): ``ready`` says
    # whether it is made, ``prepare(progress, cancel)`` makes it; a bake makes it before drawing a file that is not
    # up to date, and ``to_dict`` does not need it.


class WaveSource:
    """Wave noise (Guehl et al. 2025) from :class:`~backend.wavenoise.settings.WaveSettings`.

    3D grids need a 3D or 4D noise; a 2D grid of a 3D/4D noise is the plane z = z0.
    4D noise takes W = ``w_offset`` + time; 2D+t and 3D+t noise take time directly.
    """

    kind = "wave"
    chunkable = True
    animated_by = "set speed, or dim = 4"

    def __init__(self, settings, w_offset: float = 0.0):
        from .wavenoise.settings import compile_noise

        self.settings = settings.validate()
        self.w_offset = float(w_offset)
        self.dim = settings.dim
        self.animated = settings.dim == 4 or settings.animated
        #: the tables and directions, built here (2 ms; 0.4 s at the most: 4096 directions, 2^20-sample tables) so
        #: that their own rules (a band that holds no table harmonic, a frequency past the table's Nyquist, lobes
        #: of no weight) are checked where the source is made, before any bake runs
        self.noise = compile_noise(self.settings)

    def check_extent(self, spatial: float, time: float, names: tuple = ("bounds", "time")) -> None:
        """Refuse points ``spatial`` world units from the origin at times up to ``time`` when the waves there
        pass :data:`~backend.limits.MAX_CYCLES` (:meth:`WaveSettings.check_reach`); named by ``names``
        (space, time), whichever reaches farther."""
        w = abs(self.w_offset) + time if self.dim == 4 else time * abs(self.settings.speed)
        self.settings.check_reach(names[1] if w > spatial else names[0], spatial + w)

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        from .grid import evaluate_box

        rank = len(shape)
        if rank == 3 and self.dim == 2:
            raise SettingError("grid", "a 2D wave noise bakes images only; set dim = 3 or 4 for volumes")
        lo = np.zeros(self.dim, _F)
        k = min(self.dim, 3)
        lo[:k] = np.asarray(first, np.float64)[:k]
        if self.dim == 4:
            lo[3] = _F(self.w_offset + time)
        s = self.settings
        return evaluate_box(self.noise, shape, lo, step, s.output, 0.0 if self.dim == 4 else float(time),
                            s.cellular, progress=progress, cancel=cancel, start=start)

    def to_dict(self) -> dict:
        """The settings the noise reads (:func:`~backend.wavenoise.settings.read_settings`), ``w_offset`` and the
        by-example image's hash."""
        from .wavenoise.settings import read_settings, settings_to_dict

        d = dict(kind=self.kind, settings=settings_to_dict(read_settings(self.settings)), w_offset=self.w_offset)
        if self.settings.example is not None:
            ex = np.ascontiguousarray(self.settings.example, _F)
            d["example_sha256"] = hashlib.sha256(ex.tobytes() + str(ex.shape).encode()).hexdigest()
        return d


class NeuralSource:
    """Neural noise (Maesumi et al. 2024) as a 2D bake source: any layout of a
    :class:`backend.neural.request.NeuralRequest` (one class, a mask blend of two, two from left to right, four
    corners, a painted map), or keyframed classes (animation).

    The whole image is denoised at once (``chunkable`` is False); progress is per
    sampler step and cancel is polled after each step.  Pixels are the model's
    pixels: the grid's resolution is the image size and its bounds only place it.
    Image rows run top to bottom like the maps', so a mask lines up with the file
    a bake writes.
    """

    kind = "neural"
    dim = 2
    animated = False
    chunkable = False
    unit = True
    animated_by = "give keys: keyframes of its classes"

    def __init__(self, model_folder: str, noise: str, params: dict | None = None, noise2: str | None = None,
                 params2: dict | None = None, mask: np.ndarray | None = None, width: float = 32.0,
                 sharpness: float = 1.0, steps: int | None = None, seed: int = 0, tileable: bool = False,
                 sampler: str | None = None, keys: list | None = None, latent: str = "fixed", drift: float = 0.05,
                 corners: list | None = None, regions: np.ndarray | None = None, region_specs: list | None = None,
                 gradient: list | None = None, colours: list | None = None):
        from .neural.generate import check_sampler
        from .neural.model import ModelError, NeuralNoiseModel
        from .neural.sampler import DEFAULT_SAMPLER, DEFAULT_STEPS

        self.sampler = DEFAULT_SAMPLER if sampler is None else sampler
        steps = DEFAULT_STEPS if steps is None else steps
        try:
            check_sampler(self.sampler, steps)
        except SettingError as exc:
            raise SettingError("source." + exc.setting, exc.message) from None

        try:
            self.model = NeuralNoiseModel(model_folder)
        except ModelError as exc:
            raise SettingError("source.model", str(exc)) from None
        self.spec = (noise, dict(params or {}))
        self.spec2 = None if mask is None else (noise2 or noise, dict(params2 or {}))
        self.mask = None if mask is None else np.asarray(mask, np.float32)
        self.regions = None if regions is None else np.asarray(regions, np.int64)
        #: the painted map's colours, one 8-bit (r, g, b) per region spec, or None: how a job file written from
        #: this source paints its map (:mod:`backend.job_file`); the regions, not their colours, set the image
        self.colours = None if colours is None else [tuple(int(v) for v in c) for c in colours]
        if corners is not None:
            self.layout, self.specs = "corners", [tuple(c) for c in corners]
        elif gradient is not None:
            self.layout, self.specs = "gradient", [tuple(c) for c in gradient]
        elif self.regions is not None:
            self.layout, self.specs = "painted", [tuple(c) for c in region_specs]
        elif self.mask is not None:
            self.layout, self.specs = "blend", [self.spec, self.spec2]
        else:
            self.layout, self.specs = "uniform", [self.spec]
        self.width, self.sharpness = float(width), float(sharpness)
        self.steps, self.seed, self.tileable = int(steps), int(seed), bool(tileable)
        for spec in self.specs if not keys else ():     # keyframes are checked below, each named by its frame
            self.model.param_vector(*spec)  # unknown classes / parameters fail now, with their names
        # animation: keyframes whose `frame` is the bake's time (a job sets time = frame number)
        from .neural.animate import LATENT_MODES, check_keys

        self.keys = list(keys) if keys else None
        self.animated = self.keys is not None
        self.latent, self.drift = str(latent), limits.finite("source.drift", drift)
        if self.keys is not None:
            if self.layout != "uniform":
                raise SettingError("source.keys", "keyframes set the classes of the whole image; leave out blend, "
                                                  "corners and map")
            if self.latent not in LATENT_MODES:
                raise SettingError("source.latent", f"unknown latent motion {self.latent!r}; choose one of "
                                                    f"{', '.join(LATENT_MODES)}")
            check_keys(self.model, self.keys, "source.keys")

    @classmethod
    def from_request(cls, model_folder: str, req, colours: list | None = None) -> "NeuralSource":
        """The source that draws the checked :class:`~backend.neural.request.NeuralRequest` ``req`` (a front end's
        image, the Neural Noise panel's) on a ``req.width`` x ``req.height`` grid: the same conditioning, sampler
        and seed. ``colours`` (painted layout): the 8-bit colour of each region, for a job file's map. SettingError
        for a request's setting a source has no key for (a step spacing, an eta, a tile size)."""
        for name in ("spacing", "eta", "tile"):
            if getattr(req, name) is not None:
                raise SettingError(name, "a bake source (a job file) has no such setting (its bake takes the default): "
                                         "leave it out")
        kw = dict(width=req.transition, sharpness=req.sharpness, steps=req.steps, seed=req.seed,
                  tileable=req.tileable, sampler=req.sampler)
        specs = [(n, dict(p)) for n, p in req.specs]
        if req.layout == "blend":
            kw.update(noise2=specs[1][0], params2=specs[1][1], mask=np.asarray(req.mask, np.float32))
        elif req.layout in ("gradient", "corners"):
            kw[req.layout] = specs
        elif req.layout == "painted":
            kw.update(regions=req.regions, region_specs=specs, colours=colours)
        return cls(model_folder, *specs[0], **kw)

    def check_grid(self, shape) -> None:
        """SettingError before anything runs when the grid cannot be baked: not an image, or a blend mask or
        painted map of other proportions (one of another size with the same is drawn at the resolution)."""
        from .neural.request import map_error

        if len(shape) != 2:
            raise SettingError("grid", "neural noise bakes images (resolution [width, height])")
        for key, what, arr in (("blend", "mask", self.mask), ("map", "map", self.regions)):
            why = None if arr is None else map_error(arr, *shape, what, "the resolution", "the resolution")
            if why is not None:
                raise SettingError(f"source.{key}", why)

    def request(self, shape):
        """The :class:`backend.neural.request.NeuralRequest` of this source on an (H, W) grid (not animated)."""
        from .neural.request import NeuralRequest

        self.check_grid(shape)
        H, W = shape
        return NeuralRequest(self.layout, self.specs, W, H, mask=None if self.mask is None else self.mask > 0.5,
                             regions=self.regions, transition=self.width, sharpness=self.sharpness, seed=self.seed,
                             steps=self.steps, sampler=self.sampler, tileable=self.tileable)

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        from .grid import Cancelled
        from .neural.request import generate_request

        def step_done(i, n, x0):
            if progress is not None:
                progress((i + 1) / n)
            if cancel is not None and cancel():
                raise Cancelled("cancelled")

        if self.keys is None:
            try:
                img = generate_request(self.model, self.request(shape), callback=step_done)
            except SettingError as exc:
                raise SettingError("source." + exc.setting, exc.message) from None
            return np.ascontiguousarray(img[::-1])  # bakes index rows by +y; files put +y at the top
        from .neural.animate import frame_image

        self.check_grid(shape)
        img = frame_image(self.model, self.keys, float(time), *shape, self.latent, self.drift, seed=self.seed,
                          steps=self.steps, tileable=self.tileable, callback=step_done, sampler=self.sampler)
        return np.ascontiguousarray(img[::-1])

    def to_dict(self) -> dict:
        d = dict(kind=self.kind, model=self.model.config["files"], layout=self.layout,
                 specs=[[n, dict(sorted(p.items()))] for n, p in self.specs], sampler=self.sampler, steps=self.steps,
                 seed=self.seed, tileable=self.tileable)
        if self.layout in ("blend", "painted"):
            arr = self.mask > 0.5 if self.layout == "blend" else self.regions     # what the request reads
            d.update(width=self.width, sharpness=self.sharpness,
                     map_sha256=hashlib.sha256(np.ascontiguousarray(arr).tobytes()).hexdigest())
        if self.keys is not None:
            d.update(keys=[[k.frame, k.noise, k.params, k.seed] for k in self.keys], latent=self.latent)
            if self.latent == "drift":      # the other motions do not read its speed
                d["drift"] = self.drift
        return d


def _grid_points(shape, first, step, start=None) -> np.ndarray:
    """The points of a grid block (the solid sources' evaluate): ``shape`` (ny, nx) or (nz, ny, nx) samples from
    index ``start`` (x, y[, z]; zeros when None) of a grid whose first sample is at ``first`` with spacing ``step``
    -> float64 (N, 2 or 3) (x, y[, z]), x fastest."""
    n = len(shape)
    start = np.zeros(n, int) if start is None else np.asarray(start)
    axes = [first[k] + (start[k] + np.arange(shape[::-1][k])) * step[k] for k in range(n)]   # x, y[, z]
    mesh = np.meshgrid(*reversed(axes), indexing="ij")                                      # (z,) y, x
    return np.stack([m.ravel() for m in reversed(mesh)], axis=1)


def _solid_points(shape, first, step, start=None) -> np.ndarray:
    """:func:`_grid_points` in 3D: a 2D grid's points lie on the plane z = ``first[2]`` (0 where first has no z):
    float64 (N, 3) (x, y, z)."""
    pts = _grid_points(shape, first, step, start)
    if len(shape) == 2:
        pts = np.concatenate([pts, np.full((len(pts), 1), first[2] if len(first) > 2 else 0.0)], axis=1)
    return pts


def _named(exemplar) -> str | None:
    """An exemplar as a solid source's key names it: a file by its real path (one file however its path is
    spelled: a job's, relative to its folder, or the command line's), a shipped texture by its name, pixels by
    none (the key holds their digest)."""
    import os

    if not isinstance(exemplar, str):
        return None
    return os.path.realpath(exemplar) if os.path.isfile(exemplar) else exemplar


class SolidSource:
    """A neural solid texture (Henzler et al. 2020) as a bake source of colours (``rgb``).

    evaluate() returns scene-linear RGB float32 (..., 3) at the grid's points
    times ``scale`` (texture units per world unit); a bake writes them as the
    ``color`` grid of a volume (with a constant ``density``), an RGB EXR, an
    sRGB PNG or an (..., 3) .npy.  Any sub-box may be evaluated alone.  The
    texture is the model's own (single-exemplar model), a training exemplar of a
    space model (``exemplar = NAME``) or any image a space model encodes
    (``exemplar = "photo.png"``, optionally ``refine`` search steps).
    """

    kind = "solid"
    animated = False
    chunkable = True
    rgb = True

    def __init__(self, model, request=None, scale: float = 1.0, density: float = 1.0, code=None):
        """model: a model folder or a loaded :class:`~backend.solid.model.SolidTextureModel`; request: the
        :class:`~backend.solid.request.SolidRequest` (exemplar, ``to`` and ``mix``, refine, seed, periodic, gaussian,
        rest; None: the model's own texture at seed 0), checked here; code: its ready
        :class:`~backend.solid.model.TextureCode` (an image Blender holds, a code made once for many bakes), else
        made here by the request's stages (backend/solid/pipeline.py)."""
        from .onnx_models import ModelError
        from .solid.model import SolidTextureModel
        from .solid.request import SolidRequest

        try:
            self.model = model if isinstance(model, SolidTextureModel) else SolidTextureModel(model)
        except ModelError as exc:
            raise SettingError("source.model", str(exc)) from None
        self.scale = limits.scale("source.scale", scale)
        self.density = limits.in_range("source.density", density, 0.0, float("inf"))
        self.request = (SolidRequest() if request is None else request).check("source.")
        self.dim, self.seed = self.model.dim, int(self.request.seed)
        if code is None:
            self.code, self.input_sha256 = self.request.code(self.model, "source.")
            return
        self.code = code
        parts = [np.ravel(code.e), np.ravel(code.T)]
        if code.harmonics is not None:
            parts.append(code.harmonics.values())
        if code.rest is not None:
            parts.append(code.rest.values())
        self.input_sha256 = hashlib.sha256(np.concatenate(parts).astype(np.float32).tobytes()).hexdigest()

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        from .colour import srgb_to_linear

        pts = _solid_points(shape, first, step, start)
        if self.dim == 2:
            pts = pts[:, :2]
        rgb = self.model.evaluate(pts * self.scale, self.code, self.seed, progress=progress, cancel=cancel)
        return srgb_to_linear(rgb).reshape(tuple(shape) + (3,))

    def to_dict(self) -> dict:
        r = self.request
        named = _named(r.exemplar)      # pixels are in input_sha256
        d = dict(kind=self.kind, model=self.model.config["files"], exemplar=named, input_sha256=self.input_sha256,
                 refine=int(r.refine), seed=self.seed, scale=self.scale, density=self.density)
        if r.to is not None:
            d.update(to=_named(r.to), mix=float(r.mix))
        h = self.code.harmonics     # the harmonic part in use (an encoded photo's, a stored one)
        d["harmonics_sha256"] = None if h is None else hashlib.sha256(h.values().astype("<f8").tobytes()).hexdigest()
        r = self.code.rest          # the Gaussian rest in use (backend/solid/gaussian_rest.py), if the check kept one
        d["gaussian_rest_sha256"] = None if r is None else hashlib.sha256(r.values().astype("<f8").tobytes()).hexdigest()
        d["gaussian_rest_kind"] = None if r is None else r.kind     # isotropic / upright (backend/solid/upright.py)
        if self.model.spin:        # how the octaves turn with the seed (backend/solid/spin.py): part of the drawing
            d["spin"] = self.model.spin
        return d


class _Prepared:
    """A solid source of an image method whose texture is made once, at its first use rather than when the source
    is made: a job file's bakes are checked when it is read (their exemplars' pixels too,
    :meth:`~backend.solid.request.SolidRequest.check_pixels`), and a bake that is up to date, a dry run or another
    bake of the job makes nothing.  :meth:`prepare` makes it (with progress and cancel; a bake calls it before
    drawing), :meth:`evaluate` where it was not made yet; ``ready`` says whether it is made.  Subclasses give
    ``_make(progress, cancel)`` and draw it in ``_draw``; the key (:meth:`to_dict`) is the request's."""

    kind = "solid"
    animated = False
    chunkable = True
    rgb = True
    dim = 3

    def __init__(self, request, scale: float = 1.0, density: float = 1.0, made=None):
        self.scale = limits.scale("source.scale", scale)
        self.density = float(limits.in_range("source.density", density, 0.0, float("inf")))
        # the checks and the key read the pixels here; a file is read again when the texture is made, so that a job
        # of many large photos holds none of them until then (a 4096 px photo is 200 MB as floats)
        from .solid.procedural.saved import is_saved

        saved = is_saved(request.exemplar)          # a saved procedural solid: read and checked, no pixels
        seen = request if saved else request.replace(exemplar=request.exemplar_pixels("source.")).check_pixels(
            "source.")
        self._key = seen.key()                                     # hashes the pixels: its digest is taken from it
        self.input_sha256 = (self._key["procedural"] if request.method == "auto" else self._key)["exemplar"]
        self.photo_shape = None if saved else np.shape(seen.exemplar)
        self.request = self._unread(request)
        self._made, self._lock = made, threading.Lock()

    @staticmethod
    def _unread(request):
        """The request without the pixels its file was decoded to (:meth:`SolidRequest.exemplar_pixels` keeps
        them): what a texture is made from reads the file itself, and lets go of them with the request."""
        import dataclasses

        return dataclasses.replace(request)

    @property
    def ready(self) -> bool:
        return self._made is not None

    def prepare(self, progress=None, cancel=None):
        """The texture, made here the first time (``progress(fraction)``; ``cancel()`` returning True stops with
        :class:`~backend.grid.Cancelled`)."""
        with self._lock:
            if self._made is None:
                made = self._make(progress, cancel)
                if cancel is not None and cancel():      # a search stopped early: its best so far is not kept
                    from .grid import Cancelled

                    raise Cancelled("cancelled")
                self._made = made
        if progress is not None:
            progress(1.0)
        return self._made

    def check_grid(self, shape) -> None:
        return None

    def evaluate(self, shape, first, step, time, progress=None, cancel=None, start=None) -> np.ndarray:
        return self._draw(self.prepare(cancel=cancel), shape, first, step, time, progress, cancel, start)

    def to_dict(self) -> dict:
        r = self.request
        return dict(self._key, kind=self.kind, exemplar=_named(r.exemplar),
                    input_sha256=self.input_sha256, scale=self.scale, density=self.density)

    def __getstate__(self) -> dict:
        """Pickled (a farm's workers) with what is made, without the lock."""
        return {k: v for k, v in self.__dict__.items() if k != "_lock"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()


class SpectralSource(_Prepared):
    """A solid source with ``method = "spectral"``: a periodic Gaussian solid whose slices carry an image
    exemplar's spectrum (:mod:`backend.solid.spectral_solid`: random phase noise lifted to 3D), or with ``method =
    "procedural"``: a procedural solid fitted to the image (:mod:`backend.solid.procedural`), made at its first
    use (:class:`_Prepared`), then read at the grid's points, ``scale`` times the texture's own size (the photo's
    pixels at PX_PER_UNIT per unit, as the neural texture).  2D grids read a plane of constant z; 3D grids fill
    volumes (with a constant ``density``, as :class:`SolidSource`)."""

    def __init__(self, request, scale: float = 1.0, density: float = 1.0, field=None):
        """request: a checked :class:`~backend.solid.request.SolidRequest` with method "spectral" or "procedural";
        field: its ready field (``request.solid_field()``; else made at its first use)."""
        super().__init__(request, scale, density, field)

    def _make(self, progress, cancel):
        return self._unread(self.request).solid_field("source.", progress, cancel)

    @property
    def field(self):
        return self.prepare()

    def _draw(self, field, shape, first, step, time, progress, cancel, start) -> np.ndarray:
        from .colour import srgb_to_linear

        rgb = field.evaluate(_solid_points(shape, first, step, start) * self.scale, progress=progress, cancel=cancel)
        return srgb_to_linear(rgb).reshape(tuple(shape) + (3,))


class SynthesisSource(_Prepared):
    """A solid source with ``method = "synthesis"``: a periodic 2D image of ``tile`` px a side synthesised from an
    image exemplar (:mod:`backend.solid.synthesis`, Kwatra et al. 2005 / Kopf et al. 2007) at its first use
    (:class:`_Prepared`), then read at the grid's points, ``scale`` times the texture's own size (the photo's
    pixels at PX_PER_UNIT per unit, as the neural texture).  2D grids only: :meth:`check_grid` names the setting
    for a volume."""

    dim = 2

    def __init__(self, request, scale: float = 1.0, field=None):
        """request: a checked :class:`~backend.solid.request.SolidRequest` with method "synthesis"; field: its
        ready :class:`~backend.solid.synthesis.TileField` (else synthesised at its first use)."""
        super().__init__(request, scale, 1.0, field)

    def _make(self, progress, cancel):
        return self._unread(self.request).synthesis_field("source.", progress, cancel)

    @property
    def field(self):
        return self.prepare()

    def check_grid(self, shape) -> None:
        if len(shape) != 2:
            raise SettingError("source.method", "synthesis makes 2D images; a 3D grid needs the neural texture "
                                                "(method = \"neural\"), method = \"spectral\" or \"procedural\"")

    def _draw(self, field, shape, first, step, time, progress, cancel, start) -> np.ndarray:
        from .colour import srgb_to_linear

        if cancel is not None and cancel():
            from .grid import Cancelled

            raise Cancelled("cancelled")
        rgb = field.evaluate(_grid_points(shape, first, step, start) * self.scale)
        if progress is not None:
            progress(1.0)
        return srgb_to_linear(rgb).reshape(tuple(shape) + (3,))

    def to_dict(self) -> dict:
        import dataclasses

        from .solid.synthesis import image_settings

        r = self.request
        # the settings drawn (as the synthesis reads them off the request and the photo's size), so a bake is redone
        # when they change, not only when the request does
        drawn = image_settings(r.tile, self.photo_shape, r.seed)
        settings = {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(drawn).items()}
        return dict(kind=self.kind, method="synthesis", exemplar=_named(r.exemplar),
                    input_sha256=self.input_sha256, seed=int(r.seed), tile=int(r.tile), scale=self.scale,
                    settings=settings)


class AutoSource(_Prepared):
    """A solid source with ``method = "auto"``: the procedural solid where it is closer to the photo than the
    neural texture and keeps its structure as well, else the neural texture (:mod:`backend.solid.choose`), chosen
    at its first use (:class:`_Prepared`) and drawn as :class:`SpectralSource` or :class:`SolidSource` draws it."""

    def __init__(self, request, scale: float = 1.0, density: float = 1.0):
        """request: a checked :class:`~backend.solid.request.SolidRequest` with method "auto"."""
        super().__init__(request, scale, density)
        self.request.load("source.")        # the neural model is there and reads (before any work)

    def _make(self, progress, cancel):
        c = self._unread(self.request).choose("source.", progress, cancel=cancel)
        if c.method == "procedural":
            return SpectralSource(c.request, self.scale, self.density, field=c.field)
        return SolidSource(c.model, self._unread(c.request), self.scale, self.density, code=c.code)

    def _draw(self, chosen, shape, first, step, time, progress, cancel, start) -> np.ndarray:
        return chosen.evaluate(shape, first, step, time, progress, cancel, start)


class EncodedSource(_Prepared):
    """A neural solid texture of a photo (method "neural" with the texture-space model): :class:`SolidSource`
    once the photo is encoded (:mod:`backend.solid.pipeline`'s stages, seconds a photo), at its first use
    (:class:`_Prepared`) rather than when a job is read.  The key is the request's (the photo's pixels, mix, refine,
    seed, periodic, gaussian, rest) with the model's files."""

    def __init__(self, request, model, scale: float = 1.0, density: float = 1.0):
        """request: a checked :class:`~backend.solid.request.SolidRequest` with method "neural" whose exemplar is an
        image file or pixels; model: its loaded :class:`~backend.solid.model.SolidTextureModel`, of mode "space"."""
        self.model, self.dim = model, model.dim
        super().__init__(request, scale, density)

    def _make(self, progress, cancel):
        code, _ = self.request.code(self.model, "source.", progress)
        return SolidSource(self.model, self.request, self.scale, self.density, code=code)

    def _draw(self, encoded, shape, first, step, time, progress, cancel, start) -> np.ndarray:
        return encoded.evaluate(shape, first, step, time, progress, cancel, start)

    def to_dict(self) -> dict:
        d = dict(super().to_dict(), model=self.model.config["files"])
        if self.model.spin:
            d["spin"] = self.model.spin
        return d


_SOLID_KEYS = ("model", "exemplar", "to", "mix", "seed", "scale", "density", "refine", "periodic", "gaussian",
               "rest", "method", "tile", "families")
_NEURAL_KEYS = ("model", "noise", "params", "noise2", "params2", "blend", "width", "sharpness", "sampler", "steps",
                "seed", "tileable", "keys", "latent", "drift", "gradient", "corners", "map", "regions")


def solid_volume(request, size: int, scale: float = 1.0, where: str = "", progress=None, report=None,
                 on_code=None) -> tuple:
    """(source, extent) of a ``size``-voxel cube of a :class:`~backend.solid.request.SolidRequest`: the colour source
    that fills it and its side in world units (``size`` voxels at ``scale`` voxels per exemplar pixel), as
    ``omninoise solid --dim 3`` bakes it; ``progress``, ``report`` and ``on_code`` as in
    :meth:`~backend.solid.request.SolidRequest.front_image`.  SettingError for a 2D model or method synthesis."""
    if request.method == "synthesis":
        raise SettingError(f"{where}method", f"synthesis makes 2D images ({where}dim 2); volumes come from the "
                                             f"neural texture or {where}method spectral or procedural")
    if request.method in ("spectral", "procedural"):
        field = request.solid_field(where, progress)
        return SpectralSource(request, field=field), size / (field.px_per_unit * scale)
    if request.method == "auto":
        c = request.choose(where, progress, report, on_code)
        if c.method == "procedural":
            return SpectralSource(c.request, field=c.field), size / (c.field.px_per_unit * scale)
        return SolidSource(c.model, c.request, code=c.code), size / (c.model.px_per_unit * scale)
    model = request.load(where)
    if model.dim != 3:
        raise SettingError(f"{where}dim", f"model {model.name!r} is 2D; it cannot fill a volume")
    code, _ = request.code(model, where, progress, report, on_code)
    return SolidSource(model, request, code=code), size / (model.px_per_unit * scale)


def _check_keys(d: dict, known: tuple, kind: str) -> None:
    unknown = sorted(set(d) - set(known))
    if unknown:
        raise SettingError(f"source.{unknown[0]}", f"unknown {kind} setting; known: {', '.join(known)}")


def _neural_from_dict(d: dict, base_dir: str) -> NeuralSource:
    import os

    from .neural.request import check_layout_reads

    _check_keys(d, _NEURAL_KEYS, "neural")
    layouts = [k for k in ("blend", "gradient", "corners", "map") if k in d]
    if len(layouts) > 1:
        raise SettingError(f"source.{layouts[1]}",
                           f"choose one of blend, gradient, corners and map (got {' and '.join(layouts)})")
    # keys beside blend, gradient, corners or map: NeuralSource refuses the pair
    layout = "animated" if "keys" in d else {"map": "painted"}.get(layouts[0], layouts[0]) if layouts else "uniform"
    try:
        check_layout_reads(layout, list(d))     # a key this layout does not read: the image would not be the one asked
    except SettingError as exc:
        raise exc.under("source") from None
    keys = None
    if "keys" in d:  # animation: a keyframe file (relative to the job) or an inline list of [[key]] tables
        from .neural.animate import parse_keys, read_keys

        if isinstance(d["keys"], str):
            keys = read_keys(in_job(base_dir, d["keys"]), "source.keys")
        elif isinstance(d["keys"], list):
            keys = parse_keys({"key": d["keys"]}, "source.keys")
        else:
            raise SettingError("source.keys", f"expected a keyframe file or a list of tables, got {d['keys']!r}")
        d.setdefault("noise", keys[0].noise)
        d.setdefault("params", keys[0].params)
    if "noise" not in d and "gradient" not in d and "corners" not in d and "map" not in d:
        raise SettingError("source.noise", "a neural source needs noise = CLASS (or gradient, corners, or map and "
                                           "regions)")
    from .paths import neural_model

    model = in_job(base_dir, d["model"]) if "model" in d else neural_model()
    corners = regions = region_specs = gradient = colours = None
    if "gradient" in d:
        g = d["gradient"]
        if not isinstance(g, list) or len(g) != 2:
            raise SettingError("source.gradient", f"expected two class specs (left, right), got {g!r}")
        gradient = [_spec_value(v, f"source.gradient[{i}]") for i, v in enumerate(g)]
    if "corners" in d:
        c = d["corners"]
        if not isinstance(c, list) or len(c) != 4:
            raise SettingError("source.corners", f"expected four class specs (top-left, top-right, bottom-left, "
                                                 f"bottom-right), got {c!r}")
        corners = [_spec_value(v, f"source.corners[{i}]") for i, v in enumerate(c)]
    if "map" in d:
        from .. import export
        from .neural.request import region_key, regions_from_map

        if not isinstance(d["map"], str):
            raise SettingError("source.map", f"expected an image file name, got {d['map']!r}")
        path = in_job(base_dir, d["map"])
        if not os.path.isfile(path):
            raise SettingError("source.map", f"map not found: {path}")
        table = d.get("regions")
        if not isinstance(table, dict) or not table:
            raise SettingError("source.regions", "a map needs regions = {\"#rrggbb\" = SPEC, ...} for its colours")
        region_keys = [region_key(k, "source.regions") for k in table]
        colours = [k if isinstance(k, tuple) else (k, k, k) for k in region_keys]     # a grey level as its grey
        region_specs = [_spec_value(v, f"source.regions.{k}") for k, v in table.items()]
        try:
            regions = regions_from_map(export.decode(path), region_keys, "source.map")
        except export.ImageError as exc:
            raise SettingError("source.map", str(exc)) from None
    if gradient is not None or corners is not None or regions is not None:
        d.setdefault("noise", (gradient or corners or region_specs)[0][0])
    mask = None
    if "blend" in d:
        path = in_job(base_dir, d["blend"])
        if not os.path.isfile(path):
            raise SettingError("source.blend", f"mask not found: {path}")
        from .. import export

        try:
            mask = export.read_image(path)
        except export.ImageError as exc:
            raise SettingError("source.blend", str(exc)) from None
    return NeuralSource(model, d["noise"], d.get("params"), d.get("noise2"), d.get("params2"), mask,
                        d.get("width", 32.0), d.get("sharpness", 1.0), d.get("steps"), d.get("seed", 0),
                        d.get("tileable", False), d.get("sampler"), keys, d.get("latent", "fixed"), d.get("drift", 0.05),
                        corners, regions, region_specs, gradient, colours)


def _spec_value(v, where: str) -> tuple:
    """A class spec of a job file: "CLASS" / "CLASS:NAME=V,..." (as the command line) or {noise, params}."""
    if isinstance(v, str):
        name, _, rest = v.partition(":")
        params = {}
        for item in filter(None, rest.split(",")):
            k, sep, val = item.partition("=")
            try:
                params[k.strip()] = float(val) if sep else float("nan")
            except ValueError:
                raise SettingError(where, f"expected NAME=VALUE with a number, got {item!r}") from None
            if not sep or not np.isfinite(params[k.strip()]):
                raise SettingError(where, f"expected NAME=VALUE with a finite number, got {item!r}")
        return name.strip(), params
    if isinstance(v, dict) and isinstance(v.get("noise"), str) and set(v) <= {"noise", "params"}:
        params = v.get("params", {})
        if not isinstance(params, dict) or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                   and np.isfinite(x) for x in params.values()):
            raise SettingError(where, f"params: expected a table of finite numbers, got {params!r}")
        return v["noise"], {str(k): float(x) for k, x in params.items()}
    raise SettingError(where, f"expected \"CLASS:NAME=VALUE,...\" or {{noise = CLASS, params = {{...}}}}, got {v!r}")


def solid_request_from_dict(d: dict, base_dir: str = "."):
    """The :class:`backend.solid.request.SolidRequest` of a job file's solid source, checked (paths relative to
    the job file; ``model`` a folder, a shipped model's name, or left out as on the command line)."""
    from .solid.procedural.field import DEFAULT_KINDS
    from .solid.request import IMAGE_METHODS, SolidRequest, method_for

    _check_keys(d, _SOLID_KEYS, "solid")
    if "mix" in d and "to" not in d:
        raise SettingError("source.mix", "weighs the texture of to: give to = EXEMPLAR too")

    to, exemplar = (in_job_or_name(base_dir, d.get(k)) for k in ("to", "exemplar"))
    if d.get("method") in IMAGE_METHODS + ("auto",) and isinstance(d.get("exemplar"), str):
        exemplar = in_job(base_dir, d["exemplar"])       # these read files only: no shipped texture's name
    mix = d.get("mix", 0.5)
    return SolidRequest(in_job_or_name(base_dir, d.get("model")), exemplar, to, mix, d.get("refine", 0),
                        d.get("seed", 0), d.get("periodic", True), d.get("gaussian", True),
                        d.get("rest", "auto"), method_for(exemplar, d.get("method")), d.get("tile", 256),
                        d.get("families", DEFAULT_KINDS)).check("source.").check_reads(
        [k for k in d if k not in ("method", "scale", "density")], "source.")


def solid_source(request, scale: float = 1.0, density: float = 1.0, where: str = "source."):
    """The bake source of a checked :class:`~backend.solid.request.SolidRequest`, as a job file's solid source is
    made: a photo's texture is made at its first use (:class:`_Prepared`), a shipped texture's code here; ``where``
    prefixes the settings a problem names."""
    import os

    if request.method == "synthesis":
        return SynthesisSource(request, scale)
    if request.method in ("spectral", "procedural"):
        return SpectralSource(request, scale, density)
    if request.method == "auto":
        return AutoSource(request, scale, density)
    model = request.load(where)
    x = request.exemplar
    if model.mode != "single" and (isinstance(x, np.ndarray) or isinstance(x, str) and os.path.isfile(x)):
        return EncodedSource(request, model, scale, density)        # a photo: encoded at its first use
    return SolidSource(model, request, scale, density)


def solid_px_per_unit(request, where: str = "") -> float:
    """Photo pixels per texture unit of the texture a checked request draws (what a scale of 1 draws), known before
    it is made: a saved procedural solid's own, a neural model's, else the image methods' 128.  Auto draws either
    of two: SettingError naming ``where`` + model where the model's differs from the procedural solid's."""
    from .solid.procedural.field import PX_PER_UNIT
    from .solid.procedural.saved import is_saved, read
    from .solid import synthesis

    if is_saved(request.exemplar):
        field = request.exemplar if not isinstance(request.exemplar, str) else read(request.exemplar,
                                                                                    f"{where}exemplar")
        return float(field.px_per_unit)
    if request.method in ("synthesis", "spectral"):
        return synthesis.PX_PER_UNIT
    if request.method == "procedural":
        return PX_PER_UNIT
    model = request.load(where)
    if request.method == "auto" and model.px_per_unit != PX_PER_UNIT:
        raise SettingError(f"{where}model", f"draws {model.px_per_unit:g} photo pixels per unit, the procedural "
                                            f"solid {PX_PER_UNIT:g}: auto's scale would depend on its choice")
    return float(model.px_per_unit)


def _solid_from_dict(d: dict, base_dir: str):
    return solid_source(solid_request_from_dict(d, base_dir), d.get("scale", 1.0), d.get("density", 1.0))


def _wave_from_dict(d: dict, base_dir: str) -> WaveSource:
    import os

    from .wavenoise.settings import check_read, settings_from_dict

    example = None
    if "example" in d:
        path = in_job(base_dir, d.pop("example"))
        if not os.path.isfile(path):
            raise SettingError("source.example", f"image not found: {path}")
        from .. import export

        try:
            example = export.read_image(path)
        except export.ImageError as exc:
            raise SettingError("source.example", str(exc)) from None
    w_offset = limits.finite("source.w_offset", d.pop("w_offset", 0.0))
    spectrum = d.get("spectrum")
    given = list(d) + (["exponent"] if isinstance(spectrum, dict) and "exponent" in spectrum else [])
    try:
        settings = settings_from_dict(d, example)
        check_read(settings, given)     # a key that changes nothing here: the noise would not be the one asked for
        return WaveSource(settings, w_offset)
    except SettingError as exc:      # the settings' own rules name their keys; a job's are under [bake.source]
        raise exc.under("source") from None


#: kind -> builder(table without "kind", base_dir) -> source.  A new kind of source is one module with a class
#: of the :class:`Source` protocol and one :func:`register_source` call; job files, the farm and the bake
#: pipeline then take it (``kind = "..."`` in ``[bake.source]``) with no other change.
SOURCES: dict = {}


def register_source(kind: str, from_dict) -> None:
    """Make ``kind = KIND`` in job files build a source with ``from_dict(table, base_dir)``."""
    if not isinstance(kind, str) or not kind.isidentifier():
        raise ValueError(f"a source kind is an identifier, got {kind!r}")
    SOURCES[kind] = from_dict


register_source("wave", _wave_from_dict)
register_source("neural", _neural_from_dict)
register_source("solid", _solid_from_dict)


def source_kinds() -> tuple:
    return tuple(SOURCES)


def source_from_dict(d: dict, base_dir: str = ".") -> Source:
    """A source from a job-file table: ``kind`` (default "wave") names a registered builder (:data:`SOURCES`).

    Wave: the keys of :class:`~backend.wavenoise.settings.WaveSettings`; ``example = "img.png"``
    (relative to ``base_dir``) for by-example noise; ``w_offset`` for 4D.
    Neural: noise, params, [blend = "mask.png", noise2, params2 | corners = [4 specs] | map = "painted.png",
    regions = {"#rrggbb" = SPEC}], [width, sharpness],
    steps, seed, tileable, [model = folder], [keys, latent, drift] (see :class:`NeuralSource`).
    Solid: model (a folder, or a shipped model's name), [exemplar, refine], seed, scale, density
    (see :class:`SolidSource`).
    """
    from .schema import did_you_mean, shown_value
    from .settings_schema import SOURCE_TABLES

    if not isinstance(d, dict):
        raise SettingError("source", f"expected a [bake.source] table, got {shown_value(d)}")
    kind = d.get("kind", "wave")
    if not isinstance(kind, str) or kind not in SOURCES:
        hint = did_you_mean(kind, SOURCES) if isinstance(kind, str) else ""
        raise SettingError("source.kind", f"unknown source {shown_value(kind)}{hint}; choose one of "
                                          f"{', '.join(SOURCES)}")
    d = dict(SOURCE_TABLES[kind].check(d, "source")) if kind in SOURCE_TABLES else dict(d)
    d.pop("kind", None)
    return SOURCES[kind](d, base_dir)


def describe(obj) -> str:
    """Canonical JSON of a to_dict()-able object or plain value (for hashing)."""
    if hasattr(obj, "to_dict"):
        obj = obj.to_dict()
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))
