"""Solid textures as bake sources of colours (``kind = "solid"``): a neural texture (:class:`SolidSource`), one
encoded from a photo at its first use (:class:`EncodedSource`), the image methods' (:class:`SpectralSource` for
spectral and procedural solids, :class:`SynthesisSource`) and auto's choice (:class:`AutoSource`); the job table's
request, and the volume a command bakes."""
from __future__ import annotations

import hashlib
import threading

import numpy as np

from .. import limits
from ..errors import SettingError
from ..paths import in_job, in_job_or_name
from .base import check_keys, grid_points

__all__ = ["SolidSource", "SpectralSource", "SynthesisSource", "AutoSource", "EncodedSource", "solid_volume",
           "solid_source", "solid_px_per_unit", "solid_request_from_dict", "from_dict"]

#: the keys of a job's solid source table
KEYS = ("model", "exemplar", "to", "mix", "seed", "scale", "density", "refine", "periodic", "gaussian", "rest",
        "method", "tile", "families")


def _solid_points(shape, first, step, start=None) -> np.ndarray:
    """:func:`~.base.grid_points` in 3D: a 2D grid's points lie on the plane z = ``first[2]`` (0 where first has no z):
    float64 (N, 3) (x, y, z)."""
    pts = grid_points(shape, first, step, start)
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
        from ..onnx_models import ModelError
        from ..solid.model import SolidTextureModel
        from ..solid.request import SolidRequest

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
        from ..colour import srgb_to_linear

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
        d["gaussian_rest_sha256"] = (None if r is None
                                     else hashlib.sha256(r.values().astype("<f8").tobytes()).hexdigest())
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
        from ..solid.procedural.saved import is_saved

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
                    from ..grid import Cancelled

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
        from ..colour import srgb_to_linear

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
        from ..colour import srgb_to_linear

        if cancel is not None and cancel():
            from ..grid import Cancelled

            raise Cancelled("cancelled")
        rgb = field.evaluate(grid_points(shape, first, step, start) * self.scale)
        if progress is not None:
            progress(1.0)
        return srgb_to_linear(rgb).reshape(tuple(shape) + (3,))

    def to_dict(self) -> dict:
        import dataclasses

        from ..solid.synthesis import image_settings

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
        code, _ = self.request.code(self.model, "source.", progress, cancel=cancel)
        return SolidSource(self.model, self.request, self.scale, self.density, code=code)

    def _draw(self, encoded, shape, first, step, time, progress, cancel, start) -> np.ndarray:
        return encoded.evaluate(shape, first, step, time, progress, cancel, start)

    def to_dict(self) -> dict:
        d = dict(super().to_dict(), model=self.model.config["files"])
        if self.model.spin:
            d["spin"] = self.model.spin
        return d


def solid_volume(request, size: int, scale: float = 1.0, where: str = "", progress=None, report=None,
                 on_code=None, on_fit=None) -> tuple:
    """(source, extent) of a ``size``-voxel cube of a :class:`~backend.solid.request.SolidRequest`: the colour source
    that fills it and its side in world units (``size`` voxels at ``scale`` voxels per exemplar pixel), as
    ``omninoise solid --dim 3`` bakes it; ``progress``, ``report``, ``on_code`` and ``on_fit`` as in
    :meth:`~backend.solid.request.SolidRequest.front_image`.  SettingError for a 2D model or method synthesis."""
    if request.method == "synthesis":
        raise SettingError(f"{where}method", f"synthesis makes 2D images ({where}dim 2); volumes come from the "
                                             f"neural texture or {where}method spectral or procedural")
    if request.method in ("spectral", "procedural"):
        field = request.solid_field(where, progress)
        if on_fit is not None and request.method == "procedural":
            on_fit(field)
        return SpectralSource(request, field=field), size / (field.px_per_unit * scale)
    if request.method == "auto":
        c = request.choose(where, progress, report, on_code)
        if on_fit is not None:
            on_fit(c)
        if c.method == "procedural":
            return SpectralSource(c.request, field=c.field), size / (c.field.px_per_unit * scale)
        return SolidSource(c.model, c.request, code=c.code), size / (c.model.px_per_unit * scale)
    model = request.load(where)
    if model.dim != 3:
        raise SettingError(f"{where}dim", f"model {model.name!r} is 2D; it cannot fill a volume")
    code, _ = request.code(model, where, progress, report, on_code)
    return SolidSource(model, request, code=code), size / (model.px_per_unit * scale)


def solid_request_from_dict(d: dict, base_dir: str = "."):
    """The :class:`backend.solid.request.SolidRequest` of a job file's solid source, checked (paths relative to
    the job file; ``model`` a folder, a shipped model's name, or left out as on the command line)."""
    from ..solid.procedural.field import DEFAULT_KINDS
    from ..solid.request import IMAGE_METHODS, SolidRequest, method_for

    check_keys(d, KEYS, "solid")
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
    from ..solid.procedural.field import PX_PER_UNIT
    from ..solid.procedural.saved import is_saved, read
    from ..solid import synthesis

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


def from_dict(d: dict, base_dir: str):
    return solid_source(solid_request_from_dict(d, base_dir), d.get("scale", 1.0), d.get("density", 1.0))
