"""Refine a texture code against its exemplar without torch (Henzler et al. 2020, Sec. 3 encoder, refined).

The encoder g gives a code z in one pass; this module then improves z for the
given exemplar by a derivative-free search, since the runtime has no
gradients: a (1+1) evolution strategy with the 1/5th success rule (Rechenberg)
over the 8-D z, each candidate rendered through the translator and sampler
at 64² px with two seeds and compared with the exemplar by classical texture
statistics that need no network:

- colour quantiles (16 per channel): the histogram;
- the log radially averaged luminance power spectrum (16 bands): scale;
- the energy of luminance derivatives along x, y and both diagonals,
  normalised: orientation.

A candidate replaces z only when it lowers the distance, so the result is never
worse than the encoder's code under this measure.  Photo models carry the
exemplar's measured colour (mean and covariance) after the latent: the search
moves only the latent, so refinement never changes the colours.

Shapes: images float32 (H, W, 3) sRGB values in [0, 1].
"""
from __future__ import annotations

import os

import numpy as np

from .._export import export
from ..errors import SettingError
from ..grid import Cancelled
from .harmonic import mix_harmonics
from .model import resize_rgb

__all__ = ["texture_stats", "stats_distance", "refine_code", "exemplar_z", "RENDER_SIZE"]

RENDER_SIZE = 64


def texture_stats(img: np.ndarray, bands: int = 16) -> np.ndarray:
    """Statistics vector float64 of an image (H, W, 3) (see module doc)."""
    a = np.asarray(img, np.float64)
    q = np.quantile(a.reshape(-1, 3), np.linspace(0.03, 0.97, 16), axis=0).T.ravel()
    y = a.mean(2)
    y = y - y.mean()
    P = np.abs(np.fft.fft2(y)) ** 2
    fy = np.fft.fftfreq(y.shape[0])[:, None]
    fx = np.fft.fftfreq(y.shape[1])[None, :]
    R = np.hypot(fy, fx) / 0.5                      # 0 .. ~1.41, 1 = Nyquist
    idx = np.clip((R * bands).astype(int), 0, bands - 1)
    psd = np.bincount(idx.ravel(), P.ravel(), bands) / np.maximum(np.bincount(idx.ravel(), minlength=bands), 1)
    psd = np.log(psd / max(psd.sum(), 1e-12) + 1e-9)
    g = np.array([np.mean((y[:, 1:] - y[:, :-1]) ** 2), np.mean((y[1:] - y[:-1]) ** 2),
                  np.mean((y[1:, 1:] - y[:-1, :-1]) ** 2), np.mean((y[1:, :-1] - y[:-1, 1:]) ** 2)])
    g = g / max(g.sum(), 1e-12)
    return np.concatenate([q * 4.0, psd * 0.25, g * 4.0])


def stats_distance(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def _exemplar_crops(exemplar: np.ndarray, scale: float, n: int = 4) -> list:
    """The exemplar resampled to the model's training resolution, cut into up to n square crops."""
    img = np.asarray(exemplar, np.float32)
    if scale != 1.0:
        img = resize_rgb(img, max(RENDER_SIZE, round(img.shape[0] * scale)), max(RENDER_SIZE, round(img.shape[1] * scale)))
    H, W, _ = img.shape
    S = min(H, W, 128)
    ys = np.linspace(0, H - S, 2).astype(int)
    xs = np.linspace(0, W - S, 2).astype(int)
    return [img[y:y + S, x:x + S] for y in ys for x in xs][:n]


def refine_code(model, z0, exemplar: np.ndarray, steps: int = 40, seed: int = 0, sigma: float = 0.3,
                progress=None, cancel=None, harmonics=None):
    """(z, distances): z float32 (z_dim,) after ``steps`` candidates; distances[i] the best after candidate i
    (distances[0]: the start).  ``model`` is a space :class:`SolidTextureModel`; candidates are rendered with the
    exemplar's ``harmonics`` (:meth:`SolidTextureModel.harmonics`) when given, as the texture will be."""
    rng = np.random.default_rng(seed)
    target = np.mean([texture_stats(c) for c in _exemplar_crops(exemplar, float(model.config.get("exemplar_scale", 1.0)))],
                     axis=0)

    def cost(z):
        code = model.translate(z, harmonics)
        imgs = [model.image(RENDER_SIZE, code, s, scale=float(model.config.get("exemplar_scale", 1.0)),
                            offset=(7.0 * s, 3.0 * s, 1.0 * s)) for s in (0, 1)]
        return stats_distance(np.mean([texture_stats(i) for i in imgs], axis=0), target)

    z = np.asarray(z0, np.float32).copy()
    best = cost(z)
    hist = [best]
    k = int(getattr(model, "z_dim", z.shape[0]))       # the latent; photo models' colour statistics stay
    step = float(sigma) * max(float(np.std(z[:k])), 1e-3)
    for i in range(int(steps)):
        if cancel is not None and cancel():
            raise Cancelled("cancelled")
        cand = z.copy()
        cand[:k] = (z[:k] + rng.normal(0.0, step, k)).astype(np.float32)
        c = cost(cand)
        if c < best:
            z, best = cand, c
            step *= 1.5          # 1/5th rule: grow on success ...
        else:
            step *= 1.5 ** -0.25  # ... shrink on failure (balance at one success in five)
        hist.append(best)
        if progress is not None:
            progress((i + 1) / steps)
    return z, hist


def exemplar_z(model: "SolidTextureModel", exemplar: str, refine: int = 0, setting: str = "exemplar",
               progress=None, periodic: bool = True):
    """A space model's z for a training exemplar's name, an image file or pixels float (H, W, 3) (encoded, then
    refined by ``refine`` search steps): (z float32 (z_dim,), the image float32 (H, W, 3) or None, refinement
    distances or [], the image's harmonic part or None (``periodic`` False: None))."""
    if isinstance(exemplar, np.ndarray):  # pixels already read (the Blender panel): float (H, W, 3) sRGB in [0, 1]
        img = np.asarray(exemplar, np.float32)
        if img.ndim != 3 or img.shape[2] != 3 or not np.all(np.isfinite(img)):
            raise SettingError(setting, f"expected finite RGB pixels (H, W, 3), got shape {img.shape}")
        return _encoded(model, img, refine, progress, periodic)
    if exemplar in model.codes:
        return model.codes[exemplar], None, [], None
    if exemplar is None or not os.path.isfile(exemplar):
        raise SettingError(setting, f"{exemplar!r} is neither an image file nor an exemplar the model knows "
                                    f"({', '.join(model.codes) or 'none'})")
    try:
        img = export.read_rgb(exemplar)
    except ValueError as exc:
        raise SettingError(setting, str(exc)) from None
    return _encoded(model, img, refine, progress, periodic)


def _encoded(model, img: np.ndarray, refine: int, progress, periodic: bool):
    """:func:`exemplar_z` of pixels: encode, measure the harmonic part, refine with it."""
    h = model.harmonics(img) if periodic else None
    z, hist = model.encode(img, h), []
    if refine > 0:
        z, hist = refine_code(model, z, img, steps=refine, progress=progress, harmonics=h)
    return z, img, hist, h


def texture_code(model: "SolidTextureModel", exemplar: str | None = None, to: str | None = None, mix: float = 0.0,
                 refine: int = 0, where: str = "", progress=None, report=None, periodic: bool = True):
    """The one place a texture request becomes a code, for the command line, job files and the farm:
    (TextureCode, the input images' sha256 or None).

    A single-exemplar model gives its own texture (``to``, ``refine`` and an ``exemplar`` other than its own are
    errors); a space model
    gives ``exemplar`` (a training exemplar's name or an image file, refined by ``refine`` steps), mixed with
    ``to`` by ``mix`` in [0, 1] (Henzler et al. 2020, Sec. 4: interpolation in the latent space; an image's harmonic
    part, :mod:`backend.solid.harmonic`, comes along unless ``periodic`` is False, mixed by
    :func:`~backend.solid.harmonic.mix_harmonics`). ``where``
    prefixes the setting names in errors ("source." for job files, "--" for flags); ``report(name, history)``
    hears each refinement's distances."""
    import hashlib

    def name(key):
        return f"{where}{key}"

    if not np.isfinite(mix) or not 0.0 <= mix <= 1.0:
        raise SettingError(name("mix"), f"must be in [0, 1], got {mix}")
    if refine < 0:
        raise SettingError(name("refine"), f"must be >= 0, got {refine}")
    if model.mode == "single":  # an exemplar may only name the model's own texture
        own = {model.name, model.exemplar_label} | {str(e) for e in model.config.get("exemplars", [])}
        other = exemplar is not None and (not isinstance(exemplar, str) or exemplar not in own)
        for key, bad, why in (("exemplar", other, "another exemplar"),
                              ("to", to, "interpolation"), ("refine", refine, "refining")):
            if bad:
                raise SettingError(name(key), f"model {model.name!r} holds one texture; {why} needs the space model")
        return model.default_code(), None
    if exemplar is None:
        raise SettingError(name("exemplar"), f"the space model needs an exemplar (one of {', '.join(model.codes)}, "
                                             "or an image file)")
    digests = []

    def z_of(ex, key):
        z, img, hist, h = exemplar_z(model, ex, refine, name(key), progress, periodic)
        if img is not None:
            digests.append(hashlib.sha256(np.ascontiguousarray(img).tobytes()).hexdigest())
        if hist and report is not None:
            report(ex, hist)
        return z, h

    z, h = z_of(exemplar, "exemplar")
    if to is not None:
        z2, h2 = z_of(to, "to")
        z, h = (1.0 - mix) * z + mix * z2, mix_harmonics(h, h2, mix)
    sha = hashlib.sha256("".join(digests).encode()).hexdigest() if digests else None
    return model.translate(z, h), sha
