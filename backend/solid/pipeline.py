"""A photo becomes a solid texture's code: the stages in order, for the command line, job files, the farm, the
Blender panel, the benches and the tests alike.

    1. read       the exemplar: an image file, pixels (float (H, W, 3) sRGB in [0, 1]) or a training exemplar's name
                  (a name skips 2 to 4 and 6: the model stores its code, harmonic part and Gaussian rest)
    2. measure    the photo's harmonic part (harmonic.py's :func:`measure_harmonics`: the readings of harmonic.py, each a small
                  strategy, and their chooser), at the model's pixels per unit; ``periodic=False`` leaves it out
    3. encode     the photo (less that part, for a model trained on rests) into z, with its colour statistics
                  (Henzler et al. 2020, Sec. 3 encoder g; ``SolidTextureModel.encode``)
    4. refine     z by ``refine`` steps of a derivative-free search, checked on unseen planes (refine.py)
    5. translate  z into the decoder's code and octave transforms, the harmonic part riding along (Sec. 3
                  translator h)
    6. rest       the Gaussian share of what the part leaves, mixed in where the check on rendered planes finds it
                  closer (:func:`gaussian_rest`: gaussian_rest.py's isotropic and upright.py's upright rests)
    7. mix        with a second exemplar's code (``to``, ``mix``): z, parts and rests interpolated (Sec. 4)

Each stage's settings are one frozen config: :class:`PhotoConfig` (which stages run), holding
:class:`~backend.solid.harmonic.HarmonicConfig` (stage 2) and :class:`RestCheck` (stage 6).  Drawing the code at
points is :meth:`SolidTextureModel.evaluate <backend.solid.model.SolidTextureModel.evaluate>` (Eq. 5).

Shapes: photos float32 (H, W, 3) sRGB in [0, 1]; z float32 (z_dim + colour statistics,).
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
from dataclasses import dataclass, field

import numpy as np

from ... import export
from ..errors import SettingError
from ..progress import part, step
from .gaussian_rest import CHECK_SEEDS, MARGIN, MIXES, RENDER, REST_CHOICES, GaussianRest, check_planes, \
    choose_mix, mix_rests, wall_planes
from .harmonic import HARMONIC_SIDE, HarmonicConfig, Harmonics, measure_harmonics, mix_harmonics, remove_harmonics
from .model import SolidTextureModel, TextureCode, slice_points
from .pixels import at_most, one_colour, rgb_pixels
from .refine import refine_code
from .upright import UPRIGHT_GATE, candidates

__all__ = ["PhotoConfig", "RestCheck", "PhotoCode", "measure_harmonics", "photo_code", "gaussian_rest",
           "texture_code", "stage_shares", "STAGE_STEPS"]


@dataclass(frozen=True)
class RestCheck:
    """Stage 6's check (gaussian_rest.py): a rest is kept where it is ``margin`` times as close as the decoder
    alone, at one of ``mixes``, on x, y and z planes at ``seeds`` (walls alone for an upright rest an artist asks
    for); the upright rest is offered where the rest's orientation coherence is above ``upright_gate``."""
    margin: float = MARGIN
    seeds: tuple = CHECK_SEEDS
    mixes: tuple = MIXES
    upright_gate: float = UPRIGHT_GATE

    def planes(self, walls: bool = False) -> tuple:
        """(seed, axis, offset) of the check's planes: x, y and z cuts at each seed, or the walls (x, y) alone."""
        planes = check_planes(self.seeds)
        return wall_planes(planes) if walls else planes


@dataclass(frozen=True)
class PhotoConfig:
    """Which stages run and how: ``periodic`` (stage 2), ``refine`` search steps (stage 4), ``gaussian`` and the
    ``rest`` kind asked for (stage 6: one of REST_CHOICES), with each stage's own config."""
    periodic: bool = True
    refine: int = 0
    gaussian: bool = True
    rest: str = "auto"
    harmonic: HarmonicConfig = field(default_factory=HarmonicConfig)
    check: RestCheck = field(default_factory=RestCheck)


@dataclass(frozen=True)
class PhotoCode:
    """What the stages made of one exemplar: ``code`` the texture code drawn (stages 5 and 6), made of ``z``
    (stage 3, after 4), its harmonic part or None and its Gaussian rest or None; the refinement's distances ([]
    without one), and the pixels read (None for a name)."""
    code: TextureCode
    z: np.ndarray
    harmonics: Harmonics | None
    rest: GaussianRest | None
    history: list
    image: np.ndarray | None


def gaussian_rest(model: SolidTextureModel, image: np.ndarray, code: TextureCode, rest: str = "auto",
                  check: RestCheck = RestCheck(), progress=None, cancel=None) -> GaussianRest | None:
    """Stage 6: the Gaussian share of a photo's rest to mix into ``code`` (the photo's, without one), or None where
    the check keeps the decoder alone (:mod:`backend.solid.gaussian_rest`).  ``rest`` (REST_CHOICES): "auto", the
    check's choice among the rests :func:`~backend.solid.upright.candidates` offers on walls and floors;
    "isotropic"; "upright", checked on walls alone.  Photo models of 3D space only (the rest is a solid).
    ``progress`` and ``cancel`` as :func:`~backend.solid.gaussian_rest.choose_mix`'s."""
    if model.mode != "space" or not model.colour_stats or model.dim != 3 or code.rest is not None:
        return None
    img, ppu = at_most(image, model.px_per_unit, HARMONIC_SIDE)
    h = code.harmonics
    left = remove_harmonics(img, h, ppu) if h is not None and len(h) else img
    offered = candidates(left, ppu, rest, check.upright_gate)      # ValueError naming the choices for another rest

    def layers(seed, axis, offset):
        pts = slice_points(RENDER, model.px_per_unit, axis, offset)
        fixed, dec = model.layers(pts, code, seed)
        return fixed, dec, pts

    return choose_mix(layers, rgb_pixels(image), offered, check.planes(walls=rest == "upright"), check.margin,
                      check.mixes, progress, cancel)


#: the stages' times in steps of the refinement (about 0.2 s each for a 256 px photo on 2 cores), for their shares
#: of a photo's progress: stages 2 to 5 about one, the refinement its steps and about three more (its start and final
#: check), stage 6's check about ten
STAGE_STEPS = {"encode": 1.0, "refine": 3.0, "rest": 10.0}


def stage_shares(config: PhotoConfig) -> tuple:
    """(encode, refine, rest): the shares of :func:`photo_code`'s progress its stages take with ``config``
    (:data:`STAGE_STEPS`); a stage that does not run takes none.

    >>> stage_shares(PhotoConfig(gaussian=False))
    (1.0, 0.0, 0.0)
    >>> [round(s, 3) for s in stage_shares(PhotoConfig(refine=7))]
    [0.048, 0.476, 0.476]
    """
    w = (STAGE_STEPS["encode"], STAGE_STEPS["refine"] + config.refine if config.refine > 0 else 0.0,
         STAGE_STEPS["rest"] if config.gaussian else 0.0)
    return tuple(x / sum(w) for x in w)


def photo_code(model: SolidTextureModel, image: np.ndarray, config: PhotoConfig = PhotoConfig(), progress=None,
               setting: str = "exemplar", cancel=None) -> PhotoCode:
    """Stages 2 to 6 on a photo's pixels float (H, W, 3) sRGB (space models); ``progress(fraction)`` hears them in
    their shares (:func:`stage_shares`), ``cancel()`` -> True stops between their steps (raises
    :class:`~backend.grid.Cancelled`)."""
    img = np.asarray(image, np.float32)
    if img.ndim != 3 or img.shape[2] != 3 or not np.all(np.isfinite(img)):
        raise SettingError(setting, f"expected finite RGB pixels (H, W, 3), got shape {img.shape}")
    enc, ref, _ = stage_shares(config)
    h = model.harmonics(img, config.harmonic) if config.periodic else None                        # 2. measure
    z, history = model.encode(img, h), []                                                           # 3. encode
    step(progress, enc, cancel)
    if config.refine > 0:                                                                           # 4. refine
        z, history = refine_code(model, z, img, steps=config.refine, progress=part(progress, enc, ref),
                                 cancel=cancel, harmonics=h)
    code = model.translate(z, h)                                                                    # 5. translate
    if code.L is not None and one_colour(img):      # nothing varies to draw
        code = dataclasses.replace(code, L=np.zeros_like(code.L))
    r = gaussian_rest(model, img, code, config.rest, config.check, part(progress, enc + ref, 1.0 - enc - ref),
                      cancel) if config.gaussian else None                                          # 6. rest
    step(progress, 1.0, None)
    return PhotoCode(code if r is None else dataclasses.replace(code, rest=r), z, h, r, history, img)


def _exemplar_code(model: SolidTextureModel, exemplar, config: PhotoConfig, setting: str, progress,
                   read=None, cancel=None) -> PhotoCode:
    """Stage 1, then :func:`photo_code` for pixels: a training exemplar's name gives its stored code, part and rest;
    an image file is read (by ``read``, default ``export.read_rgb``); pixels are taken as they are."""
    if isinstance(exemplar, np.ndarray):
        return photo_code(model, exemplar, config, progress, setting, cancel)
    if exemplar in model.codes:
        z, h = model.codes[exemplar], model.code_harmonics.get(exemplar) if config.periodic else None
        r = model.code_rests.get(exemplar) if config.gaussian else None
        code = model.translate(z, h)
        return PhotoCode(code if r is None else dataclasses.replace(code, rest=r), z, h, r, [], None)
    if exemplar is None or not os.path.isfile(exemplar):
        raise SettingError(setting, f"{exemplar!r} is neither an image file nor an exemplar the model knows "
                                    f"({', '.join(model.codes) or 'none'})")
    try:
        img = (read or export.read_rgb)(exemplar)
    except ValueError as exc:
        raise SettingError(setting, str(exc)) from None
    return photo_code(model, img, config, progress, setting, cancel)


def texture_code(model: SolidTextureModel, exemplar=None, to=None, mix: float = 0.0,
                 config: PhotoConfig = PhotoConfig(), where: str = "", progress=None, report=None, read=None,
                 cancel=None):
    """A texture request's code, every stage: (TextureCode, the input images' sha256 or None).

    A single-exemplar model gives its own texture (``to``, ``refine`` and an ``exemplar`` other than its own are
    errors); a space model gives ``exemplar`` (a training exemplar's name, an image file or pixels), mixed with
    ``to`` by ``mix`` in [0, 1] (stage 7).  ``where`` prefixes the setting names in errors ("source." for job
    files, "--" for flags); ``report(name, history)`` hears each refinement's distances; ``read(path)`` decodes
    an image file (default ``export.read_rgb``; a request passes the decoding its checks made); ``progress`` hears
    each exemplar's stages (:func:`photo_code`) in an equal share, and ``cancel`` stops them."""
    def name(key):
        return f"{where}{key}"

    if not np.isfinite(mix) or not 0.0 <= mix <= 1.0:
        raise SettingError(name("mix"), f"must be in [0, 1], got {mix}")
    if config.refine < 0:
        raise SettingError(name("refine"), f"must be >= 0, got {config.refine}")
    if config.rest not in REST_CHOICES:
        raise SettingError(name("rest"), f"must be one of {', '.join(REST_CHOICES)}, got {config.rest!r}")
    if model.mode == "single":  # an exemplar may only name the model's own texture
        own = {model.name, model.exemplar_label} | {str(e) for e in model.config.get("exemplars", [])}
        other = exemplar is not None and (not isinstance(exemplar, str) or exemplar not in own)
        for key, bad, why in (("exemplar", other, "another exemplar"),
                              ("to", to, "interpolation"), ("refine", config.refine, "refining")):
            if bad:
                raise SettingError(name(key), f"model {model.name!r} holds one texture; {why} needs the space model")
        return model.default_code(), None
    if exemplar is None:
        raise SettingError(name("exemplar"), f"the space model needs an exemplar (one of {', '.join(model.codes)}, "
                                             "or an image file)")
    codes, given = [], [(ex, key) for ex, key in ((exemplar, "exemplar"), (to, "to")) if ex is not None]
    for i, (ex, key) in enumerate(given):
        c = _exemplar_code(model, ex, config, name(key), part(progress, i / len(given), 1 / len(given)), read,
                           cancel)
        if c.history and report is not None:
            report(ex, c.history)
        codes.append(c)
    digests = [hashlib.sha256(np.ascontiguousarray(c.image).tobytes()).hexdigest() for c in codes
               if c.image is not None]
    sha = hashlib.sha256("".join(digests).encode()).hexdigest() if digests else None
    if len(codes) == 1:
        return codes[0].code, sha
    a, b = codes                                                                                    # 7. mix
    h, r = mix_harmonics(a.harmonics, b.harmonics, mix), mix_rests(a.rest, b.rest, mix)
    code = model.translate((1.0 - mix) * a.z + mix * b.z, h)
    return (code if r is None else dataclasses.replace(code, rest=r)), sha
