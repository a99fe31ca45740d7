"""One solid texture, whatever asked for it: the typed request the command line, job files and the Blender panel
all build, validated in one place and turned into a texture code in one place.

A request names a model (a folder, a shipped model's name, or None: chosen from the exemplar as the command line
always did), an exemplar (a space model's training exemplar by name, an image file, or pixels a front-end already
holds), an optional second exemplar ``to`` with its share ``mix`` (Henzler et al. 2020, Sec. 4: interpolation in
the latent space), ``refine`` search steps, ``periodic`` (keep an encoded image's harmonic part,
:mod:`backend.solid.harmonic`), ``gaussian`` (mix in an encoded image's Gaussian rest where the encode-time check
finds it closer, :mod:`backend.solid.gaussian_rest`) of the kind ``rest`` asks for ("auto", "isotropic" or "upright",
:mod:`backend.solid.upright`), and the ``seed`` of the noise.  ``method`` "synthesis" asks instead for a periodic
2D image of ``tile`` px a side synthesised from an image exemplar by texture optimisation
(:mod:`backend.solid.synthesis`): no model, no code, 2D only; ``method`` "spectral" a periodic Gaussian solid whose
slices carry the image's spectrum (random phase noise lifted to 3D, :mod:`backend.solid.spectral_solid`): no model,
2D and 3D, with the image's harmonic part where ``periodic``; ``method`` "procedural" a procedural solid (rings,
layers, cells or bonds) fitted to the image (:mod:`backend.solid.procedural`): no model, 2D and 3D; ``method``
"auto" that procedural solid where it is closer to the image than the neural texture, else the neural texture
(:mod:`backend.solid.choose`).  Where the texture is read (grid, zoom, scale)
belongs to the bake, not to the texture.
:meth:`SolidRequest.check` raises :class:`~backend.errors.SettingError` naming the field, with the front-end's
prefix (``--`` for flags, ``source.`` for job files); :meth:`SolidRequest.key` is a JSON summary (images by
sha256): equal settings from any front-end give equal keys (tests/cli/test_solid_request.py).

Shapes: pixel exemplars float32 (H, W, 3) sRGB values in [0, 1], top row first.
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import SettingError
from ..paths import solid_models
from .methods import IMAGE_METHODS, METHODS, READS
from .procedural.field import DEFAULT_KINDS
from .pixels import MIN_SIDE
from .procedural.saved import is_saved

__all__ = ["method_for", "SolidRequest", "MAX_SEED", "METHODS", "IMAGE_METHODS"]

MAX_SEED = 2 ** 32 - 1   #: seeds are 32-bit (the value noise hash, backend/solid/value_noise.py)


def method_for(exemplar, method: str | None = None) -> str:
    """The method a request draws by where its front end was given none: a saved procedural solid (a ``.json``
    exemplar) is drawn by ``"procedural"``, the one method that draws it; anything else by ``"neural"``. A method
    given is kept (and checked by :meth:`SolidRequest.check`)."""
    if method is not None:
        return method
    return "procedural" if is_saved(exemplar) else "neural"


def _pixels_sha(x: np.ndarray) -> str:
    """sha256 of pixels quantised to 16 bits: an 8-bit image gives the same digest whether it was decoded here
    (v / 255) or by Blender (v * (1 / 255), which differs in the last float bit)."""
    q = np.round(np.clip(np.asarray(x, np.float64), 0.0, 1.0) * 65535.0).astype("<u2")
    return "pixels:" + hashlib.sha256(np.ascontiguousarray(q).tobytes() + repr(q.shape).encode()).hexdigest()


def _file_stamp(path: str):
    """(path, modification time in ns, size in bytes) of a file, or None where it cannot be read."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return path, st.st_mtime_ns, st.st_size


#: the neural method's settings that read a photo (the exemplar's or --to's), and what they do
PHOTO_READS = {"refine": "refinement fits the code to a photo", "periodic": "the periodic part is read off a photo",
               "rest": "the rest's orientation is read off a photo"}


def _is_photo(x) -> bool:
    """Whether an exemplar (or ``to``) is a photo: pixels, or an image file (not a shipped texture's name)."""
    return isinstance(x, np.ndarray) or (isinstance(x, str) and os.path.isfile(x))


def _digest(x) -> str | None:
    """What an exemplar is, for the key: a name as itself, a file or pixels by the sha256 of the pixels."""
    if x is None:
        return None
    if isinstance(x, np.ndarray):
        return _pixels_sha(x)
    if os.path.isfile(x):      # a file as the pixels it decodes to: equal to the same pixels handed over
        from ... import export

        return _pixels_sha(export.read_rgb(x))
    return str(x)


def _read_file(path: str, setting: str) -> np.ndarray:
    """An image file decoded to sRGB (H, W, 3) float32; SettingError naming ``setting`` where it cannot be read."""
    from ... import export

    try:
        return export.read_rgb(path)
    except ValueError as exc:
        raise SettingError(setting, str(exc)) from None


def pixels_as_rgb(x, setting: str):
    """``x`` with float pixels of other layouts laid out as sRGB (H, W, 3), as an image file's are read
    (``export.read_rgb``): grey (H, W) or (H, W, 1) repeated to three channels, an alpha channel ((H, W, 2) or
    (H, W, 4)) dropped where it is opaque (SettingError naming ``setting`` where it is not); anything else as
    given, for :func:`check_pixels_given` to name."""
    if not isinstance(x, np.ndarray) or x.dtype.kind != "f" or x.ndim not in (2, 3) or 0 in x.shape:
        return x
    if x.ndim == 2:
        x = x[..., None]
    if x.shape[2] in (2, 4):
        from ...export.images import transparency

        why = transparency(x)
        if why is not None:
            raise SettingError(setting, why)
        x = x[..., :-1]
    return np.repeat(x, 3, axis=2) if x.shape[2] == 1 else x


def check_pixels_given(x, setting: str) -> None:
    """SettingError naming ``setting`` unless ``x`` is None, a name or file (a str), or pixels as every method
    reads them: a float array (H, W, 3) of finite sRGB values in [0, 1] (8-bit pixels divided by 255), at least
    :data:`~backend.solid.pixels.MIN_SIDE` px a side (:func:`check_side`)."""
    if x is None or isinstance(x, str):
        return
    if not isinstance(x, np.ndarray):
        raise SettingError(setting, f"expected a name, an image file or sRGB pixels (H, W, 3), got {type(x).__name__}")
    if x.dtype.kind != "f":
        hint = " (divide 8-bit pixels by 255)" if x.dtype.kind in "ui" else ""
        raise SettingError(setting, f"expected sRGB pixels as floats in [0, 1], got {x.dtype}{hint}")
    if x.ndim != 3 or x.shape[2] != 3 or 0 in x.shape:
        raise SettingError(setting, f"expected sRGB pixels (H, W, 3), got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise SettingError(setting, "the pixels hold NaN or infinite values")
    lo, hi = float(x.min()), float(x.max())
    if lo < 0.0 or hi > 1.0:
        raise SettingError(setting, f"expected sRGB pixels in [0, 1], got values in [{lo:.4g}, {hi:.4g}]")
    check_side(x, setting)


def check_side(photo: np.ndarray, setting: str) -> None:
    """SettingError naming ``setting`` for a photo (H, W, ...) under :data:`~backend.solid.pixels.MIN_SIDE` px a
    side: every method reads a texture from a photo at least that large (the procedural fit's least; spectral
    solids and synthesis need more, and say so)."""
    if min(photo.shape[:2]) < MIN_SIDE:
        raise SettingError(setting, f"the photo is {photo.shape[1]} x {photo.shape[0]} px; a texture is read from a "
                                    f"photo of at least {MIN_SIDE} px a side")


@dataclass(frozen=True, eq=False)
class SolidRequest:
    """A solid texture: ``model`` folder (or None: the exemplar's own shipped model, else the texture-space
    model), ``exemplar`` and ``to`` (names, image files or pixels; for method "procedural" the exemplar may be a
    saved procedural solid instead, a ProceduralField or its ``.json`` file, drawn as saved), ``mix`` in [0, 1],
    ``refine`` >= 0 search steps, ``seed`` in [0, 2^32), ``periodic`` (an encoded image keeps its harmonic part),
    ``gaussian`` (its Gaussian rest, where the check keeps one), ``rest`` (which: one of
    gaussian_rest.REST_CHOICES), ``method`` (one of :data:`METHODS`), for "synthesis" ``tile`` (px per side of the
    periodic image) and for "procedural" and "auto" ``families`` (the kinds of solid the fit tries, a list or tuple
    of procedural.field.KINDS)."""

    model: str | None = None
    exemplar: str | np.ndarray | None = field(default=None, repr=False)
    to: str | np.ndarray | None = field(default=None, repr=False)
    mix: float = 0.0
    refine: int = 0
    seed: int = 0
    periodic: bool = True
    gaussian: bool = True
    rest: str = "auto"
    method: str = "neural"
    tile: int = 256
    families: tuple = DEFAULT_KINDS

    def check(self, where: str = "") -> "SolidRequest":
        """SettingError naming the field (``where`` + name) when a value is out of range; the request when not."""
        from ..settings_schema import SOLID_SOURCE     # the job file's rules, whichever front end asks

        def bad(key, why):
            return SettingError(f"{where}{key}", why)

        f = SOLID_SOURCE.fields
        for key in ("mix", "refine", "seed", "periodic", "gaussian", "rest", "method"):
            value = getattr(self, key)
            f[key].type.check(bool(value) if isinstance(value, np.bool_) else value, f"{where}{key}")
        kinds = self.families
        f["families"].type.check(list(kinds) if isinstance(kinds, (list, tuple)) else kinds, f"{where}families")
        twice = sorted({k for k in kinds if list(kinds).count(k) > 1})
        if twice:
            raise bad("families", f"names {', '.join(twice)} more than once")
        if is_saved(self.exemplar):
            return self._check_saved(where)
        for key in ("exemplar", "to"):
            check_pixels_given(getattr(self, key), f"{where}{key}")
        if self.model is not None and not isinstance(self.model, str):
            raise bad("model", f"expected a model folder or a shipped model's name, got {self.model!r}")
        if self.method in IMAGE_METHODS:
            m, ex = self.method, self.exemplar
            if isinstance(ex, str) and not os.path.isfile(ex):
                raise bad("exemplar", f"{m} works from an image file; there is no file {ex!r}")
            if not isinstance(ex, (np.ndarray, str)):
                raise bad("exemplar", f"{m} works from an image (a file or pixels), got {ex!r}")
            if self.to is not None:
                raise bad("to", f"interpolation needs the neural texture (method neural); {m} draws one texture")
            if self.refine:
                raise bad("refine", f"refinement searches a neural texture's code; {m} has none")
        if self.method == "auto":
            ex = self.exemplar
            if not _is_photo(ex):
                raise bad("exemplar", f"auto chooses for a photo: an image file or pixels, got {ex!r}")
            if self.to is not None:
                raise bad("to", "interpolation needs the neural texture (method neural); auto draws one texture")
        if self.method == "synthesis":
            from .synthesis import MAX_TILE, MIN_TILE, TILE_STEP

            t = self.tile
            if isinstance(t, bool) or not isinstance(t, (int, np.integer)) or not MIN_TILE <= t <= MAX_TILE \
                    or t % TILE_STEP:
                raise bad("tile", f"must be a multiple of {TILE_STEP} in [{MIN_TILE}, {MAX_TILE}], got {t!r}")
        return self

    def _check_saved(self, where: str) -> "SolidRequest":
        """:meth:`check` of a request whose exemplar is a saved procedural solid (a ProceduralField, or its JSON
        file: procedural/saved.py): drawn by method procedural as saved, with nothing to fit or mix, and read here,
        before any work."""
        def bad(key, why):
            return SettingError(f"{where}{key}", why)

        if self.method != "procedural":
            raise bad("exemplar", f"a saved procedural solid is drawn by method procedural, not {self.method}")
        if int(self.seed) != 0:
            raise bad("seed", "a saved procedural solid keeps the seed it was saved with; edit its \"seed\" to draw "
                              "another")
        for key, unset in (("to", None), ("refine", 0), ("families", DEFAULT_KINDS)):
            value = getattr(self, key)
            if (tuple(value) if key == "families" else value) != unset:
                raise bad(key, "a saved procedural solid is drawn as it was saved; nothing is fitted or mixed")
        if self.model is not None:
            raise bad("model", "a saved procedural solid needs no model")
        if isinstance(self.exemplar, str) and not os.path.isfile(self.exemplar):
            raise bad("exemplar", f"there is no file {self.exemplar!r}")
        self.saved_field(where)
        return self

    def saved_field(self, where: str = ""):
        """The saved procedural solid the exemplar is (:func:`~backend.solid.procedural.saved.read`; a file is read
        once per request, and again only where it changed on disk)."""
        if not isinstance(self.exemplar, str):
            return self.exemplar
        from .procedural.saved import read

        stamp = _file_stamp(self.exemplar)
        kept = self.__dict__.get("_saved")
        if stamp is not None and kept is not None and kept[0] == stamp:
            return kept[1]
        field = read(self.exemplar, f"{where}exemplar")
        if stamp is not None:
            object.__setattr__(self, "_saved", (stamp, field))
        return field

    def folder(self, models: str | None = None) -> str:
        """The model folder: ``model`` itself, a shipped model by name, or (no model) the exemplar's own shipped
        model when there is one and nothing is interpolated, else the texture-space model."""
        models = models or solid_models()
        if self.model is not None:
            named = os.path.join(models, self.model)
            return self.model if os.path.isdir(self.model) or not os.path.isdir(named) else named
        if isinstance(self.exemplar, str) and self.to is None:
            own = os.path.join(models, os.path.basename(self.exemplar))
            if os.path.isfile(os.path.join(own, "solid.json")):
                return own
        return os.path.join(models, "space")

    def load(self, where: str = "", threads: int = 0, models: str | None = None):
        """The :class:`~backend.solid.model.SolidTextureModel` of :meth:`folder`; SettingError on a missing or
        altered folder."""
        from ..onnx_models import ModelError
        from .model import SolidTextureModel

        try:
            return SolidTextureModel(self.folder(models), threads)
        except ModelError as exc:
            raise SettingError(f"{where}model", f"{exc}; see models/solid/MODEL_CARD.md") from None

    def photo_config(self):
        """The :class:`~backend.solid.pipeline.PhotoConfig` of this request's stages (periodic, refine, gaussian,
        rest)."""
        from .pipeline import PhotoConfig

        return PhotoConfig(periodic=bool(self.periodic), refine=int(self.refine), gaussian=bool(self.gaussian),
                           rest=self.rest)

    def code(self, model, where: str = "", progress=None, report=None, on_code=None, cancel=None):
        """(TextureCode, the input images' sha256 or None): :func:`backend.solid.pipeline.texture_code` (with its
        ``progress`` and ``cancel``); ``on_code(code)`` hears the code once it is made (a front end's note on what
        the encoding kept)."""
        from .pipeline import texture_code

        code, sha = texture_code(model, self.exemplar, self.to, float(self.mix), self.photo_config(), where,
                                 progress, report, self._read, cancel)
        if on_code is not None:
            on_code(code)
        return code, sha

    def _read(self, path: str) -> np.ndarray:
        """``export.read_rgb(path)``, or this request's own decoding of ``path`` (:meth:`exemplar_pixels`, made by
        the checks) where the file has not changed since: a photo is decoded once per request."""
        img = self._kept(path)
        if img is not None:
            return img
        from ... import export

        return export.read_rgb(path)

    def _kept(self, path: str):
        """This request's decoding of the file at ``path`` (:meth:`_decode`), or None where it has none or the file
        changed since (its modification time or size)."""
        kept = self.__dict__.get("_decoded", {}).get(path)
        return kept[1] if kept is not None and kept[0] == _file_stamp(path) else None

    def _decode(self, path: str, setting: str) -> np.ndarray:
        """The file at ``path`` decoded (read-only float (H, W, 3) sRGB) once per request and again only where it
        changed on disk; SettingError naming ``setting`` for a file it cannot read."""
        kept = self._kept(path)
        if kept is not None:
            return kept
        stamp = _file_stamp(path)
        img = _read_file(path, setting)
        img.setflags(write=False)
        if stamp is not None:       # frozen: the memo is no field (not in key or eq)
            object.__setattr__(self, "_decoded", {**self.__dict__.get("_decoded", {}), path: (stamp, img)})
        return img

    def exemplar_pixels(self, where: str = ""):
        """An image method's exemplar (synthesis, spectral, procedural) as pixels: pixels as given, a path decoded
        to float (H, W, 3) sRGB; SettingError naming the exemplar for a file it cannot read.  A file is decoded once
        per request, and again only where it changed on disk: the grid note and the fit read the same pixels, kept
        read-only (the request keeps the path: a shipped model is looked up by the exemplar's name)."""
        if is_saved(self.exemplar):
            raise SettingError(f"{where}exemplar", "a saved procedural solid is no photo: it is drawn by method "
                                                   "procedural")
        if not isinstance(self.exemplar, str):
            return self.exemplar
        return self._decode(self.exemplar, f"{where}exemplar")

    def check_reads(self, given, where: str = "", names: dict | None = None) -> "SolidRequest":
        """SettingError naming the first of ``given`` (the settings a front end was given, by their names here) that
        this request's method does not read (:data:`~backend.solid.methods.READS`): it would change nothing, and the
        texture would not be the one asked for: a rest's orientation without the Gaussian rest, and the photo's
        settings (:data:`PHOTO_READS`) of a shipped texture, too; ``names`` maps a setting to the name to report (a
        flag)."""
        def name(key):
            return (names or {}).get(key, f"{where}{key}")

        for key in given:
            if key in ("exemplar", "seed") or key in READS[self.method]:
                continue
            readers = [m for m, keys in READS.items() if key in keys]
            who = readers[0] if len(readers) == 1 else f"{', '.join(readers[:-1])} and {readers[-1]}"
            raise SettingError(name(key), f"method {self.method} does not read it; "
                                          f"{who} {'does' if len(readers) == 1 else 'do'}")
        if "rest" in given and not self.gaussian:
            raise SettingError(name("rest"), f"orients the Gaussian rest, which {name('gaussian')} leaves out: it "
                                             "would change nothing")
        if self.method == "neural" and not any(_is_photo(x) for x in (self.exemplar, self.to)):
            for key in PHOTO_READS:
                if key in given:        # a shipped texture is drawn from the model's own code, with no photo read
                    what = (f"{self.exemplar!r} is a shipped texture, drawn" if isinstance(self.exemplar, str)
                            else "the model's one texture is drawn")
                    raise SettingError(name(key), f"{PHOTO_READS[key]}; {what} from the model's own code: it would "
                                                  "change nothing")
        return self

    def check_pixels(self, where: str = "") -> "SolidRequest":
        """What the image methods (synthesis, spectral, procedural, auto) ask of the exemplar's pixels, checked
        before any work (a job file's bakes when the job is read, their textures made when baked): SettingError
        naming the exemplar for an image they cannot use; the request when they can.  The neural method's image
        files (``exemplar``, ``to``) must decode, and its photos (files or pixels) hold at least
        :data:`~backend.solid.pixels.MIN_SIDE` px a side, as the procedural fit's: a photo it cannot use is named
        before the encoding starts."""
        if is_saved(self.exemplar):
            return self
        if self.method not in IMAGE_METHODS + ("auto",):
            for key, x in (("exemplar", self.exemplar), ("to", self.to)):
                if isinstance(x, str) and os.path.isfile(x):
                    check_side(self._decode(x, f"{where}{key}"), f"{where}{key}")
            return self
        img = self.exemplar_pixels(where)
        try:
            if self.method == "synthesis":
                from .synthesis import check_photo, image_settings

                check_photo(img, image_settings(self.tile, np.shape(img), self.seed))
            elif self.method == "spectral":
                from .spectral_solid import check_photo

                check_photo(img)
            else:
                from .procedural.fit import check_photo

                check_photo(img)
        except SettingError as exc:
            raise SettingError(f"{where}exemplar", exc.message) from None
        return self

    def replace(self, **changes) -> "SolidRequest":
        """``dataclasses.replace``, keeping this request's decoding of its file exemplar where the exemplar stays."""
        new = dataclasses.replace(self, **changes)
        if "_decoded" in self.__dict__:         # the files' decodings hold while the files stay
            object.__setattr__(new, "_decoded", dict(self.__dict__["_decoded"]))
        if "exemplar" not in changes and "_saved" in self.__dict__:
            object.__setattr__(new, "_saved", self.__dict__["_saved"])
        return new

    def exemplar_digest(self) -> str | None:
        """The exemplar for the key (``_digest``), a file by the pixels of this request's one decoding, a saved
        procedural solid by its JSON."""
        if is_saved(self.exemplar):
            import json

            text = json.dumps(self.saved_field().to_dict(), sort_keys=True)
            return "procedural:" + hashlib.sha256(text.encode()).hexdigest()
        if isinstance(self.exemplar, str) and os.path.isfile(self.exemplar):
            return _pixels_sha(self.exemplar_pixels())
        return _digest(self.exemplar)

    def __getstate__(self) -> dict:
        """Pickled (a farm's workers) without the decoded pixels: a worker decodes the file where it runs."""
        return {k: v for k, v in self.__dict__.items() if k != "_decoded"}

    def synthesis_field(self, where: str = "", progress=None, cancel=None):
        """Method "synthesis": the :class:`~backend.solid.synthesis.TileField` of a periodic 2D tile of ``tile`` px
        synthesised from the exemplar with ``seed`` (:func:`~backend.solid.synthesis.image_settings`, which the field
        keeps as ``settings``; progress and cancel as :func:`~backend.solid.synthesis.synthesise`'s); SettingError
        naming the exemplar for an image it cannot use."""
        from .synthesis import PX_PER_UNIT, TileField, image_settings, synthesise

        img = self.exemplar_pixels(where)
        settings = image_settings(self.tile, np.shape(img), self.seed)
        try:
            tile = synthesise(img, settings, progress, cancel)
        except SettingError as exc:
            raise SettingError(f"{where}exemplar", exc.message) from None
        return TileField(tile, PX_PER_UNIT, settings)

    def spectral_field(self, where: str = "", progress=None, cancel=None):
        """Method "spectral": the :class:`~backend.solid.spectral_solid.SplineField` of a periodic Gaussian solid
        whose slices carry the exemplar's spectrum, its values mapped onto the exemplar's marginals, drawn with
        ``seed`` (:func:`~backend.solid.spectral_solid.spectral_field`; progress and cancel as
        :func:`~backend.solid.spectral_solid.spectral_tile`'s); SettingError naming the exemplar for an image it
        cannot use."""
        from .harmonic import measure_harmonics
        from .spectral_solid import PX_PER_UNIT, spectral_field

        img = np.asarray(self.exemplar_pixels(where), np.float32)
        try:
            h = measure_harmonics(img, PX_PER_UNIT) if self.periodic else None
            return spectral_field(img, int(self.seed), h, progress, cancel)
        except SettingError as exc:
            raise SettingError(f"{where}exemplar", exc.message) from None

    def procedural_field(self, where: str = "", progress=None, cancel=None):
        """Method "procedural": the :class:`~backend.solid.procedural.field.ProceduralField` fitted to the exemplar
        with ``seed`` (:func:`~backend.solid.procedural.fit.fit_procedural`; progress and cancel as its own);
        SettingError naming the exemplar for an image it cannot use."""
        from .procedural.fit import ProceduralConfig, fit_procedural

        if is_saved(self.exemplar):
            return self.saved_field(where)
        img = np.asarray(self.exemplar_pixels(where), np.float32)
        try:
            config = ProceduralConfig(seed=int(self.seed), families=tuple(self.families))
            return fit_procedural(img, config, progress, cancel).field
        except SettingError as exc:
            raise SettingError(f"{where}exemplar", exc.message) from None

    def repeats_as_grid(self, where: str = "") -> bool:
        """Whether methods "procedural" and "auto" would fit, besides bonds, kinds that draw stones or blotches on a
        photo that repeats as a grid (bricks, tiles: :func:`~backend.solid.procedural.estimate.grid_repeat` at
        least ``GRID``, read at the fit's resolution), so that the interfaces suggest bonds alone."""
        from .pixels import at_most, rgb_pixels
        from .procedural.estimate import GRID, grid_repeat
        from .procedural.fit import PX_PER_UNIT, ProceduralConfig

        if self.method not in ("procedural", "auto") or not set(self.families) - {"bonds", "herringbone"} \
                or is_saved(self.exemplar):
            return False
        if not _is_photo(self.exemplar):
            return False
        img = rgb_pixels(np.asarray(self.exemplar_pixels(where), np.float32))
        if min(img.shape[:2]) < 16:
            return False
        return grid_repeat(at_most(img, PX_PER_UNIT, ProceduralConfig().fit_side)[0]) >= GRID

    def solid_field(self, where: str = "", progress=None, cancel=None):
        """The field of a solid image method (spectral or procedural): :meth:`spectral_field` or
        :meth:`procedural_field`."""
        if self.method == "procedural":
            return self.procedural_field(where, progress, cancel)
        return self.spectral_field(where, progress, cancel)

    def choose(self, where: str = "", progress=None, report=None, on_code=None, field=None, cancel=None):
        """Method "auto": the :class:`~backend.solid.choose.Choice` between the procedural solid (``field`` where
        it is fitted already) and the neural texture (:func:`~backend.solid.choose.choose`)."""
        from .choose import choose

        return choose(self, where, progress, report, on_code, field, cancel)

    def front_image(self, size: int, scale: float = 1.0, where: str = "", progress=None, report=None,
                    on_code=None, draw_progress=None, on_fit=None) -> np.ndarray:
        """The texture's 2D image: the plane y = 0 seen from the front (x right, z up), as the command line's
        ``--dim 2`` writes it: sRGB float32 (size, size, 3) in [0, 1], ``scale`` output pixels per exemplar pixel.
        ``progress`` hears the synthesis, the spectral solid, the procedural fit, auto's stages or the encoding,
        ``draw_progress`` the drawing of a neural texture or a procedural solid; ``report`` hears the refinement as
        in :meth:`code`; ``on_code(code)`` gets the texture code before it is drawn (the neural texture only);
        ``on_fit`` the fitted procedural solid (method "procedural") or auto's
        :class:`~backend.solid.choose.Choice`."""
        if self.method == "synthesis":
            return self.synthesis_field(where, progress).image(size, scale)
        if self.method in ("spectral", "procedural"):
            from .spectral_solid import SpectralTexture

            field = self.solid_field(where, progress)
            if on_fit is not None and self.method == "procedural":
                on_fit(field)
            return SpectralTexture(self).image(size, field, scale=scale, progress=draw_progress)
        if self.method == "auto":
            c = self.choose(where, progress, report, on_code)
            if on_fit is not None:
                on_fit(c)
            if c.method == "procedural":
                from .spectral_solid import SpectralTexture

                return SpectralTexture(c.request).image(size, c.field, scale=scale, progress=draw_progress)
            return c.model.image(size, c.code, int(self.seed), scale=scale, progress=draw_progress)
        model = self.load(where)
        code, _ = self.code(model, where, progress, report, on_code)
        return model.image(size, code, int(self.seed), scale=scale, progress=draw_progress)

    def key(self, exemplar: str | None = None) -> dict:
        """A JSON summary: equal for equal settings from any front-end (images by their pixels' sha256); the rest's
        kind only where a Gaussian rest is asked for (without one it changes nothing, so a bake is not redone); for
        methods "synthesis", "spectral" and "procedural" only what they read (exemplar, seed and tile, or periodic, the
        spectral solid's map onto the photo's marginals and its power's isotropic start; or the families tried);
        ``exemplar``: the exemplar's digest where it is known (:meth:`exemplar_digest`; auto's two keys share one)."""
        ex = self.exemplar_digest() if exemplar is None else exemplar
        if self.method == "synthesis":
            return dict(method="synthesis", exemplar=ex, seed=int(self.seed), tile=int(self.tile))
        if self.method == "spectral":
            # marginals: the tile's values are mapped onto the photo's (spectral_solid.Marginals); start: its power
            # is found from an isotropic start (spectral_solid.solid_power); a bake keyed before either is redone
            return dict(method="spectral", exemplar=ex, seed=int(self.seed),
                        periodic=bool(self.periodic), marginals=True, start="isotropic")
        if self.method == "procedural":
            return dict(method="procedural", exemplar=ex, seed=int(self.seed), families=list(self.families))
        if self.method == "auto":
            return dict(method="auto", procedural=self.replace(method="procedural").key(ex),
                        neural=self.replace(method="neural").key(ex))
        return dict(model=os.path.basename(os.path.normpath(self.folder())), exemplar=ex,
                    to=_digest(self.to), mix=float(self.mix) if self.to is not None else 0.0,
                    refine=int(self.refine), seed=int(self.seed), periodic=bool(self.periodic),
                    gaussian=bool(self.gaussian), rest=self.rest if self.gaussian else None)
