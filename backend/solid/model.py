"""A neural solid texture at run time: onnxruntime and numpy, no torch (Henzler et al. 2020).

A model folder holds ``solid.json`` and ``decoder.onnx`` (space models also
``encoder.onnx`` and ``translator.onnx``), written by
``training/solid/export.py``.  Loading checks every file's sha256
against the JSON; sessions are created on first use.

    tex = SolidTextureModel("models/solid/gravel_3d")
    code = tex.default_code()                        # TextureCode(e (64,), T (8, 3, 3))
    rgb = tex.evaluate(points, code, seed=0)         # points (N, 3) in units -> float32 (N, 3) sRGB in [0, 1]

Space models also map an exemplar image to a code (``encode``) and codes to
(e, T) (``translate``); codes interpolate linearly in z (Sec. 5, Fig. 1).  An
encoded photo's harmonic part (``harmonics``, harmonic.py: its courses and
weaves, measured, not learned) rides along in the code.
Positions are in texture units: ``px_per_unit`` exemplar pixels per unit.
"""
from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass

import numpy as np

from ..errors import SettingError, check_points
from ..grid import Cancelled
from ..onnx_models import ModelError, SessionCache, load_model_json
from ..paths import solid_models
from .brick import brick_features
from .cellular import cellular_features
from .harmonic import HarmonicConfig, Harmonics, from_json, harmonic_field, measure_harmonics, remove_harmonics
from .pixels import resize_rgb, rgb_pixels
from .value_noise import value_noise, octave_seeds
from .spin import check_mode, spun
from .gaussian_rest import GaussianRest, rest_field, rest_from_json
from .waves import wave_features

__all__ = ["SolidTextureModel", "TextureCode", "exemplar_category", "resize_rgb", "colour_stats", "spectral_gains", "DEFAULT_CHUNK", "load_models", "plane_points", "slice_points", "rgb_pixels"]

_F = np.float32
DEFAULT_CHUNK = 1 << 16   #: points per decoder call (about 40 MiB of activations)
ENCODE_SIDE = 8           #: the encoder reads at most this many crops along each side of a photo ...
ENCODE_BATCH = 16         #: ... this many at a time (a 4096 px photo: 64 crops, not 3969 in one 13 GB batch)


def plane_points(size: int, px_per_unit: float, rows: slice = slice(None)) -> np.ndarray:
    """Pixel centres of a size x size image in texture units, row 0 at the top: float64 (size*size, 2) (u, -v);
    ``rows``: only those rows' (a slice of range(size))."""
    u = (np.arange(size, dtype=np.float64) + 0.5) / px_per_unit
    v = u[rows]
    pts = np.empty((v.size * size, 2))
    pts[:, 0], pts[:, 1] = np.tile(u, v.size), -np.repeat(v, size)
    return pts


def slice_points(size: int, px_per_unit: float, axis: str, offset=(0.0, 0.0, 0.0),
                 rows: slice = slice(None)) -> np.ndarray:
    """Pixel centres of a size x size image of the plane through ``offset`` normal to ``axis`` ("y": x to the right
    and z up; "z": x right, y up; "x": y right, z up), row 0 at the top: float64 (size*size, 3) in units; ``rows``:
    only those rows'."""
    plane = plane_points(size, px_per_unit, rows)
    a, b = {"z": (0, 1), "y": (0, 2), "x": (1, 2)}[axis]
    pts = np.empty((plane.shape[0], 3))
    pts[:] = np.asarray(offset, np.float64)
    pts[:, a] += plane[:, 0]
    pts[:, b] += plane[:, 1]
    return pts


#: pixels an image of a plane is drawn at a time (:func:`plane_image`)
IMAGE_BLOCK = 1 << 16


def plane_image(draw, size: int, px_per_unit: float, axis: str | None = "y", offset=(0.0, 0.0, 0.0),
                progress=None) -> np.ndarray:
    """A (size, size, 3) float32 image of a plane, drawn a block of rows at a time so that its points (24 bytes a
    pixel) and an evaluator's temporaries are never held for the whole image (a 2048^2 front view held 73 bytes a
    pixel).  ``draw(points, rows)`` -> float32 (n, 3) at ``points`` float64 (n, 3), the pixel centres of ``rows``
    (a slice of range(size)) of :func:`slice_points`' plane through ``offset`` normal to ``axis``, or (n, 2) those
    of :func:`plane_points` moved by ``offset[:2]`` where ``axis`` is None (a 2D texture);
    ``progress(fraction)`` after each block."""
    out = np.empty((size, size, 3), _F)
    step = max(1, IMAGE_BLOCK // max(1, size))
    for r in range(0, size, step):
        rows = slice(r, min(size, r + step))
        if axis is None:
            pts = plane_points(size, px_per_unit, rows)
            pts += np.asarray(offset[:2], np.float64)
        else:
            pts = slice_points(size, px_per_unit, axis, offset, rows)
        out[rows] = np.asarray(draw(pts, rows), _F).reshape(-1, size, 3)
        if progress is not None:
            progress(rows.stop / size)
    return out


def load_models(root: str | None = None, threads: int = 0, cache: dict | None = None) -> dict:
    """{folder name: model} of every loadable model folder under ``root`` (default: the shipped models,
    ``backend.paths.solid_models``; incomplete, altered or damaged folders are left out), sorted by name.  ``cache``
    (path -> model or ModelError) avoids re-reading folders."""
    root = root or solid_models()
    out = {}
    for name in sorted(os.listdir(root)) if os.path.isdir(root) else []:
        path = os.path.join(root, name)
        if not os.path.isfile(os.path.join(path, "solid.json")):
            continue
        if cache is not None and path in cache:
            m = cache[path]
        else:
            try:
                m = SolidTextureModel(path, threads)
            except ModelError as exc:
                m = exc
            if cache is not None:
                cache[path] = m
        if not isinstance(m, ModelError):
            out[name] = m
    return out


@dataclass(frozen=True)
class TextureCode:
    """What the sampler needs: the extended code e float32 (E,) and the octave transforms T float32 (m, D, D);
    for photo models (``colour_model`` "affine") also the exemplar's colour: mean ``mu`` float32 (3,) and the
    Cholesky factor ``L`` float32 (3, 3) of its colour covariance (rgb = mu + L d); for spectral models the
    per-octave ``gains`` float32 (m,) measured from the exemplar (:func:`spectral_gains`); for a photo a space model
    encoded, or a single photo model that stores one, the photo's ``harmonics`` (:mod:`backend.solid.harmonic`:
    the periodic part added to the decoder's); for a photo a space model encoded, the Gaussian ``rest``
    (:mod:`backend.solid.gaussian_rest`) mixed with the decoder's part when the encode-time check kept one."""
    e: np.ndarray
    T: np.ndarray
    mu: np.ndarray | None = None
    L: np.ndarray | None = None
    gains: np.ndarray | None = None
    harmonics: Harmonics | None = None
    rest: GaussianRest | None = None


def exemplar_category(name: str) -> str:
    """An exemplar's short name: a shipped exemplar's own ('gravel') or a photo-set file's category, the part of
    its name before '__' ('wood' for ``data/photos/train/wood__oldwood.jpg``)."""
    return os.path.splitext(os.path.basename(name))[0].split("__", 1)[0]


def _colour(c: np.ndarray) -> tuple:
    """(mu (3,), L (3, 3)) of a photo model's 12 colour statistics [mu, L row-major] (:func:`colour_stats`)."""
    return c[:3].copy(), c[3:12].reshape(3, 3).copy()


STATS_CHUNK = 1 << 18   #: pixels per float64 chunk of :func:`colour_stats` (no float64 copy of a 12 MP photo)


def colour_stats(img: np.ndarray, eps: float = 1e-4) -> np.ndarray:
    """Mean colour and Cholesky factor of the colour covariance of an image (H, W, 3): float32 (12,) = [mu, L.ravel()]
    (the numpy twin of ``training.solid.model.colour_stats``)."""
    x = np.reshape(img, (-1, 3))

    def chunks():
        return (np.asarray(x[i:i + STATS_CHUNK], np.float64) for i in range(0, len(x), STATS_CHUNK))

    mu = sum(c.sum(0) for c in chunks()) / len(x)
    cov = sum((c - mu).T @ (c - mu) for c in chunks()) / len(x) + eps * np.eye(3)
    return np.concatenate([mu, np.linalg.cholesky(cov).ravel()]).astype(_F)


GAIN_RANGE = (0.1, 3.0)   #: as training.solid.model.GAIN_RANGE


def spectral_gains(img: np.ndarray, octaves: int = 8, px_per_unit: float = 128.0) -> np.ndarray:
    """Per-octave gains of an image (H, W, 3): float32 (octaves,), the numpy twin of
    ``training.solid.model.spectral_gains`` (the Haar-pyramid share of the luminance's variance at the level
    each noise octave makes, g_i = sqrt(m s_i / sum s), clamped to GAIN_RANGE)."""
    top = int(round(np.log2(px_per_unit)))
    levels = [max(top - i, 0) for i in range(octaves)]
    y = np.asarray(img, np.float64)[..., :3].mean(axis=2)
    g = y - y.mean()
    energy = []
    for _ in range(max(levels) + 1):
        h, w = g.shape[0] // 2 * 2, g.shape[1] // 2 * 2
        if h < 2 or w < 2:          # coarser than the image: the coarsest level it has stands in
            energy.append(energy[-1] if energy else 0.0)
            continue
        g = g[:h, :w]
        c = g.reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3))
        band = g - np.repeat(np.repeat(c, 2, axis=0), 2, axis=1)
        energy.append(float((band ** 2).mean()))
        g = c
    e = np.array([energy[L] for L in levels]) + 1e-12
    return np.clip(np.sqrt(octaves * e / e.sum()), *GAIN_RANGE).astype(_F)


class SolidTextureModel:
    def __init__(self, folder: str, threads: int = 0):
        try:
            self._load(folder, threads)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:     # a field missing or of the wrong kind
            raise ModelError(f"{os.path.join(folder, 'solid.json')} is damaged ({type(exc).__name__}: "
                             f"{str(exc)[:120]}); re-install or re-export the model") from None

    def _load(self, folder: str, threads: int) -> None:
        self.config = load_model_json(folder, "solid.json")
        if self.config.get("model") != "neural_solid_texture":
            raise ModelError(f"{os.path.join(folder, 'solid.json')} is not a neural solid texture model")
        c = self.config
        self.folder, self.threads = folder, threads
        self.name, self.mode, self.dim = c["name"], c["mode"], int(c["dim"])
        self.octaves, self.channels, self.code_dim = int(c["octaves"]), int(c["channels"]), int(c["code_dim"])
        self.px_per_unit = float(c["px_per_unit"]) / float(c.get("exemplar_scale", 1.0))
        self.codes = {k: np.asarray(v, _F) for k, v in c.get("codes", {}).items()}
        #: photo models append the exemplar's colour statistics (12 values) to the encoder's latent z
        self.colour_stats = int(c.get("colour_stats", 0))
        #: spectral models also append the exemplar's per-octave noise gains (``octaves`` values)
        self.spectral_gains = int(c.get("spectral_gains", 0))
        #: the first ``cellular`` octaves also give the decoder Worley features (cellular.py); 0 in older models
        self.cellular = int(c.get("cellular", 0))
        #: ... and brick features (brick.py)
        self.bricks = int(c.get("bricks", 0))
        #: a single-photo model's periodic components (waves.py: rows f_x, f_y, phi, a); none in older models
        self.waves = np.asarray(c.get("waves", []), np.float64).reshape(-1, 4)
        if len(self.waves) and (self.mode != "single" or self.dim != 2):
            raise ModelError(f"model {self.name!r} has waves, which only single 2D models can have")
        #: a single photo model's stored harmonic part (harmonic.py; training/solid/harmonics.py adds it)
        self.stored_harmonics = None
        if "harmonics" in c:
            if self.mode != "single" or not c.get("colour_stats", 0):
                raise ModelError(f"model {self.name!r} stores a harmonic part, which only single photo models can")
            try:
                self.stored_harmonics = from_json(c["harmonics"])
            except ValueError as exc:
                raise ModelError(f"model {self.name!r}: {exc}") from None
        #: a space photo model's named codes' harmonic parts, measured from the photos that name them (export, or
        #: training/solid/harmonics.py): ``code(name)`` draws a name as encoding its photo would
        self.code_harmonics = self._named_parts(c, "code_harmonics", from_json, "a harmonic part")
        #: ... and their Gaussian rests, where the check kept one for the photo (gaussian_rest.py; the same writers)
        self.code_rests = self._named_parts(c, "code_rests", rest_from_json, "a Gaussian rest")
        #: a space model trained on its photos' rests (photo less harmonic part): it encodes a photo's rest when
        #: the photo's part rides along, and draws it at the rest's own colour covariance (k = 1, harmonic.py)
        self.harmonic_rest = bool(c.get("harmonic_rest", False))
        if self.harmonic_rest and (self.mode != "space" or not self.colour_stats):
            raise ModelError(f"model {self.name!r} was trained on harmonic rests, which only space photo models can")
        #: how octaves turn with their seeds (spin.py): "lattice", "octave" or "" (older models: none)
        try:
            self.spin = check_mode(c.get("spin", ""))
        except ValueError as exc:
            raise ModelError(f"model {self.name!r}: {exc}") from None
        self.z_dim = int(c.get("z_dim", 8))
        if self.mode == "single" and self.colour_stats and len(c.get("colour_code", ())) != self.colour_stats:
            raise ModelError(f"model {self.name!r} draws in its exemplar's colours but its solid.json has no "
                             f"colour_code of {self.colour_stats} values (mu and L): re-export it")
        self._session = SessionCache(folder, threads)

    def _named_parts(self, c: dict, key: str, read, what: str) -> dict:
        """solid.json's ``key`` {name: stored part}, read by ``read``; ModelError unless this is a space photo model
        and every name is one of its codes, or when a part is malformed."""
        out = {}
        for k, v in c.get(key, {}).items():
            if self.mode != "space" or not c.get("colour_stats", 0) or k not in self.codes:
                raise ModelError(f"model {self.name!r} stores {what} for code {k!r}, which only a space photo "
                                 "model's named codes can have")
            try:
                out[k] = read(v)
            except ValueError as exc:
                raise ModelError(f"model {self.name!r}, code {k!r}: {exc}") from None
        return out

    @property
    def exemplar_label(self) -> str:
        """The first exemplar's short name (:func:`exemplar_category`)."""
        return exemplar_category(self.config["exemplars"][0])

    # -- codes ----------------------------------------------------------------------------------
    def default_code(self) -> TextureCode:
        """The single-mode texture (with its stored harmonic part, if any), or the space model's first training
        exemplar."""
        if self.mode == "single":
            e, T = np.asarray(self.config["code"], _F), np.asarray(self.config["T"], _F)
            if not self.colour_stats:
                return TextureCode(e, T)
            return TextureCode(e, T, *_colour(np.asarray(self.config["colour_code"], _F)),
                               harmonics=self.stored_harmonics)
        return self.translate(next(iter(self.codes.values())))

    def encode(self, image: np.ndarray, harmonics: Harmonics | None = None) -> np.ndarray:
        """Space mode, Sec. 3 encoder g: image float (H, W, 3) or (H, W) in [0, 1] -> z float32 (z_dim,).

        The mean code of overlapping 128 px crops (the image is first resized
        so its short side is at least 128 px, keeping pixels per unit), at most ``ENCODE_SIDE`` along a side,
        encoded ``ENCODE_BATCH`` at a time.  A model trained on rests
        (``harmonic_rest``) given the image's ``harmonics`` (:meth:`harmonics`) encodes the image less them,
        as it saw its training photos; other models ignore them.
        """
        if self.mode != "space":
            raise SettingError("exemplar", f"model {self.name!r} was fitted to one exemplar and cannot encode images; "
                                           "use a space model")
        img = rgb_pixels(image)
        if self.harmonic_rest and harmonics is not None and len(harmonics):
            img = remove_harmonics(img, harmonics, self.px_per_unit)
        S = int(self.config.get("encoder_size", 128))
        scale = float(self.config.get("exemplar_scale", 1.0))
        if scale != 1.0:        # the encoder saw exemplars resampled by this factor in training
            img = resize_rgb(img, max(1, round(img.shape[0] * scale)), max(1, round(img.shape[1] * scale)))
        if min(img.shape[:2]) < S:
            f = S / min(img.shape[:2])
            img = resize_rgb(img, max(S, round(img.shape[0] * f)), max(S, round(img.shape[1] * f)))
        H, W, _ = img.shape
        # crops at most S/2 apart that cover the whole image; on a photo over (ENCODE_SIDE + 1) S/2 px wide,
        # ENCODE_SIDE crops spread evenly over that side (cost and memory stay those of a 576 px photo)
        ys, xs = (np.unique(np.linspace(0, n - S, min(ENCODE_SIDE, -(-(n - S) // (S // 2)) + 1))
                            .round().astype(int)) for n in (H, W))
        crops = np.stack([img[y:y + S, x:x + S].transpose(2, 0, 1) for y in ys for x in xs]).astype(_F)
        enc = self._session("encoder.onnx")
        z = np.concatenate([enc.run(None, {"exemplar": np.clip(crops[i:i + ENCODE_BATCH], 0.0, 1.0)})[0]
                            for i in range(0, len(crops), ENCODE_BATCH)]).mean(0)
        if self.colour_stats:
            z = np.concatenate([z, colour_stats(img)])
        if self.spectral_gains:   # as training measures them: crop by crop, here averaged over the crops
            ppu = float(self.config["px_per_unit"])
            z = np.concatenate([z, np.mean([spectral_gains(c.transpose(1, 2, 0), self.octaves, ppu)
                                            for c in crops], axis=0)])
        return z.astype(_F)

    def harmonics(self, image: np.ndarray, config: HarmonicConfig = HarmonicConfig()) -> Harmonics | None:
        """A photo's harmonic part at this model's scale (:func:`~backend.solid.harmonic.measure_harmonics`), for
        :meth:`translate`; None for models without the photo's colour (the part is added in its colour frame)."""
        if not self.colour_stats:
            return None
        return measure_harmonics(image, self.px_per_unit, config)

    def translate(self, z, harmonics: Harmonics | None = None) -> TextureCode:
        """Space mode, translator h(z) -> (e, T) (Sec. 3); ``harmonics`` (:meth:`harmonics`) ride along."""
        if self.mode != "space":
            raise SettingError("code", f"model {self.name!r} has no translator (single-exemplar model)")
        z = np.asarray(z, _F).reshape(-1)
        need = self.z_dim + self.colour_stats + self.spectral_gains
        if z.shape[0] != need:
            raise SettingError("code", f"code has {z.shape[0]} values, model {self.name!r} needs {need}")
        e, T = self._session("translator.onnx").run(None, {"z": z[:self.z_dim].reshape(1, -1)})
        if not self.colour_stats:
            return TextureCode(e[0].astype(_F), T[0].astype(_F))
        c = z[self.z_dim:self.z_dim + self.colour_stats]
        gains = z[self.z_dim + self.colour_stats:].copy() if self.spectral_gains else None
        return TextureCode(e[0].astype(_F), T[0].astype(_F), *_colour(c), gains,
                           harmonics if harmonics is not None and len(harmonics) else None)

    def code(self, exemplar: str | None = None, gaussian: bool = True) -> TextureCode:
        """A named training exemplar's code (space models), with the harmonic part of the photo that names it when
        the model stores one (``code_harmonics``) and its Gaussian rest (``code_rests``, unless ``gaussian`` is
        False), or the default code."""
        if exemplar is None:
            return self.default_code()
        if exemplar not in self.codes:
            raise SettingError("exemplar", f"model {self.name!r} knows no exemplar {exemplar!r}"
                                           + (f"; it knows {', '.join(self.codes)}" if self.codes else ""))
        code = self.translate(self.codes[exemplar], self.code_harmonics.get(exemplar))
        r = self.code_rests.get(exemplar) if gaussian else None
        return code if r is None else dataclasses.replace(code, rest=r)

    # -- evaluation ------------------------------------------------------------------------------
    def decode(self, noise: np.ndarray, e: np.ndarray) -> np.ndarray:
        """Decoder f(n | e): noise float32 (N, m*C), e (E,) or (N, E) -> sRGB float32 (N, 3)."""
        e = np.asarray(e, _F).reshape(-1, self.code_dim)
        return self._session("decoder.onnx").run(None, {"noise": np.ascontiguousarray(noise, _F),
                                                        "code": np.ascontiguousarray(e)})[0]

    def evaluate(self, points, code: TextureCode, seed: int = 0, chunk: int = DEFAULT_CHUNK,
                 progress=None, cancel=None) -> np.ndarray:
        """s(x | z) (Eq. 5) at points float (N, D) in texture units -> sRGB float32 (N, 3) in [0, 1].

        Works in chunks of ``chunk`` points (memory stays flat whatever N);
        ``progress(fraction)`` after each chunk (the one progress contract of the core); ``cancel()`` returning True
        stops early with :class:`Cancelled`.  2D points on a 3D model are
        read on the z = 0 plane.  A code with ``harmonics`` adds the photo's harmonic part (harmonic.py), one with
        a ``rest`` its Gaussian rest (gaussian_rest.py): rgb = mu + k sqrt(1 - t) L d + h(x) + sqrt(t) g(x).
        """
        pts = check_points(points, (2, 3))
        if pts.shape[1] > self.dim:
            raise SettingError("points", f"model {self.name!r} is {self.dim}D and cannot be evaluated at 3D points")
        pts = self._padded(pts)
        T = np.asarray(code.T, _F)
        if T.shape != (self.octaves, self.dim, self.dim):
            raise SettingError("code", f"transforms have shape {T.shape}, model needs {(self.octaves, self.dim, self.dim)}")
        N = pts.shape[0]
        out = np.empty((N, 3), _F)
        for a in range(0, N, chunk):
            if cancel is not None and cancel():
                raise Cancelled("cancelled")
            b = min(N, a + chunk)
            d = self._decoded(pts[a:b], code, seed, a, b)
            if self.colour_stats:
                d = self._coloured(pts[a:b], d, code, seed)
            out[a:b] = d
            if progress is not None:
                progress(b / N)
        return out

    def _padded(self, pts: np.ndarray) -> np.ndarray:
        """Points (N, D <= dim) with zeros for the missing coordinates: 2D points on a 3D model lie on z = 0."""
        if pts.shape[1] >= self.dim:
            return pts
        return np.concatenate([pts, np.zeros((pts.shape[0], self.dim - pts.shape[1]), pts.dtype)], axis=1)

    def _decoded(self, pts: np.ndarray, code: TextureCode, seed: int, a: int = 0, b: int | None = None) -> np.ndarray:
        """The decoder's output at points float (n, dim) (rows a:b of a per-point code): float32 (n, 3)."""
        T = np.asarray(code.T, _F)
        if self.spin:
            T = spun(T, octave_seeds(seed, self.octaves), self.spin)
        noise = value_noise(pts, T, seed, self.channels)
        if self.spectral_gains:
            if code.gains is None:
                raise SettingError("code", f"model {self.name!r} needs the exemplar's spectral gains in its code")
            noise *= np.repeat(np.asarray(code.gains, _F), self.channels)   # octave-major: i*C + c
        if self.cellular:
            noise = np.concatenate([noise, cellular_features(pts, T, seed, self.cellular)], axis=1)
        if self.bricks:
            noise = np.concatenate([noise, brick_features(pts, T, seed, self.bricks)], axis=1)
        if len(self.waves):
            noise = np.concatenate([noise, wave_features(pts, self.waves)], axis=1)
        e = code.e if code.e.ndim == 1 else code.e[a:b]
        return self.decode(noise, e)

    def _check_colour(self, code: TextureCode) -> None:
        if code.mu is None or code.L is None:
            raise SettingError("code", f"model {self.name!r} needs the exemplar's colour (mu, L) in its code")

    def _keep(self, code: TextureCode) -> float:
        """The factor on the decoder's coloured part: k = sqrt(1 - share) with a harmonic part (1 for a model
        trained on rests, whose L is already the rest's), times sqrt(1 - t) with a Gaussian rest."""
        k = 1.0 if code.harmonics is None or self.harmonic_rest else code.harmonics.keep
        return k * float(np.sqrt(1.0 - code.rest.mix)) if code.rest is not None else k

    def _parts(self, pts: np.ndarray, d: np.ndarray, code: TextureCode, seed: int) -> tuple:
        """Photo models: the texture before its Gaussian rest and clipping as two float32 (n, 3) parts,
        (mu + h(x), k L d(x)), from the decoder's output d (n, 3) at points (n, dim)."""
        dec = _F(self._keep(code)) * (d @ np.asarray(code.L, _F).T)
        fixed = np.broadcast_to(np.asarray(code.mu, _F), dec.shape).copy()
        if code.harmonics is not None:
            fixed += harmonic_field(pts, code.harmonics, seed)
        return fixed, dec

    def _coloured(self, pts: np.ndarray, d: np.ndarray, code: TextureCode, seed: int) -> np.ndarray:
        """Photo models: rgb = clip(mu + h(x) + k L d + sqrt(t) g(x)) (harmonic.py, gaussian_rest.py): float32 (n, 3)."""
        self._check_colour(code)
        fixed, dec = self._parts(pts, d, code, seed)
        out = fixed + dec
        if code.rest is not None:
            out += rest_field(pts, code.rest, seed)
        return np.clip(out, 0.0, 1.0)

    def layers(self, points: np.ndarray, code: TextureCode, seed: int = 0) -> tuple:
        """Photo models, a code without a Gaussian rest: the two parts of :meth:`evaluate` before clipping, float32
        (N, 3) each: (mu + h(x), k L d(x)) (what the Gaussian rest's check mixes; points as :meth:`evaluate`'s)."""
        self._check_colour(code)
        if code.rest is not None:
            raise SettingError("code", "layers takes a code without a Gaussian rest")
        pts = self._padded(np.asarray(points))
        return self._parts(pts, self._decoded(pts, code, seed, 0, pts.shape[0]), code, seed)

    def image(self, size: int, code: TextureCode, seed: int = 0, scale: float = 1.0, offset=(0.0, 0.0, 0.0),
              axis: str = "y", **kw) -> np.ndarray:
        """A (size, size, 3) float32 image of the plane through ``offset`` normal to ``axis``,
        at exemplar resolution times ``scale`` (pixel centres; row 0 at the top).  The default, "y", is the front
        view (x to the right, z up), where models trained with ``fixed_axis`` "rows" and an encoded photo's
        harmonic part (harmonic.py) show the photo upright; "z" looks down (x right, y up), "x" from the side
        (y right, z up)."""
        progress = kw.pop("progress", None)

        def draw(pts, rows):
            e = code.e if code.e.ndim == 1 else code.e[rows.start * size: rows.stop * size]   # a code per pixel
            return self.evaluate(pts, code if e is code.e else dataclasses.replace(code, e=e), seed, **kw)

        return plane_image(draw, size, self.px_per_unit * scale, None if self.dim == 2 else axis, offset, progress)
