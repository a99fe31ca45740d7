"""Animated neural noise: conditioning that moves between keyframes (Maesumi et al. 2024, Fig. 11).

A frame's conditioning is interpolated between the two keyframes around it, as spatial blends are
(:func:`backend.neural.conditioning.blend`): class embeddings along the sphere (slerp), parameters linearly.
The sampler is deterministic (DPM-Solver++ or DDIM with η = 0), so the image is a continuous function of
the conditioning and of the initial latent x_T; keeping x_T smooth over time keeps the frames coherent
instead of flickering. Three latent motions:

    fixed   one x_T for every frame (the first keyframe's seed): only the conditioning moves
    slerp   x_T(t) = slerp(x_T(seed_a), x_T(seed_b), w) between the keyframes' own seeds; two independent
            Gaussian latents are nearly orthogonal, and the great-circle path between them keeps the norm,
            so every frame's latent is again a plausible standard normal sample
    drift   x_T(t) = cos(θ) n₀ + sin(θ) n₁ with θ = speed · (frame - first frame): a latent that circles
            at a constant angular speed (radians per frame) even where the conditioning stands still

Keyframes come from a TOML file (:func:`read_keys`)::

    [[key]]
    frame = 1
    noise = "perlin"
    params = {scale = 4}
    seed = 0          # optional (default 0): the latent of this key for latent = "slerp"

    [[key]]
    frame = 48
    noise = "cells_f1"
    params = {scale = 10}

Shapes: conditioning float32 (E + P, H, W), latents float32 (H', W'), images float32 (H, W) in [0, 1].
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator

import numpy as np

from ..errors import SettingError
from . import conditioning as C
from .generate import generate
from .sampler import initial_noise

__all__ = ["Keyframe", "LATENT_MODES", "read_keys", "parse_keys", "even_keys", "frame_weight", "frame_cond", "frame_latent", "frame_image",
           "animate", "temporal_coherence"]

LATENT_MODES = ("fixed", "slerp", "drift")
_F = np.float32


@dataclass(frozen=True)
class Keyframe:
    frame: int
    noise: str
    params: dict = field(default_factory=dict)
    seed: int = 0

    @property
    def spec(self) -> tuple:
        return self.noise, dict(self.params)


def parse_keys(doc: dict, where: str = "keys") -> list:
    """A TOML document ({"key": [...]}) -> keyframes sorted by frame; SettingError naming what is wrong."""
    unknown = sorted(set(doc) - {"key"})
    if unknown:
        raise SettingError(where, f"unknown top-level key {unknown[0]!r}; a keyframe file has [[key]] tables")
    keys = doc.get("key")
    if not isinstance(keys, list) or not keys:
        raise SettingError(where, "no [[key]] tables: an animation needs at least one keyframe")
    out = []
    for i, k in enumerate(keys):
        label = f"{where}: key {i + 1}"
        if not isinstance(k, dict):
            raise SettingError(label, f"expected a [[key]] table, got {k!r}")
        bad = sorted(set(k) - {"frame", "noise", "params", "seed"})
        if bad:
            raise SettingError(label, f"unknown key {bad[0]!r}; known: frame, noise, params, seed")
        frame, noise, params, seed = k.get("frame"), k.get("noise"), k.get("params", {}), k.get("seed", 0)
        if not isinstance(frame, int) or isinstance(frame, bool):
            raise SettingError(label, f"frame: expected a whole number, got {frame!r}")
        if not isinstance(noise, str) or not noise:
            raise SettingError(label, f"noise: expected a class name, got {noise!r}")
        if not isinstance(params, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                   and np.isfinite(v) for v in params.values()):
            raise SettingError(label, f"params: expected a table of finite numbers, got {params!r}")
        if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2 ** 32:
            raise SettingError(label, f"seed: expected a whole number in [0, 2^32), got {seed!r}")
        out.append(Keyframe(frame, noise, {str(n): float(v) for n, v in params.items()}, seed))
    out.sort(key=lambda k: k.frame)
    dup = [a.frame for a, b in zip(out, out[1:]) if a.frame == b.frame]
    if dup:
        raise SettingError(where, f"two keyframes at frame {dup[0]}")
    return out


def even_keys(specs: list, first: int, last: int, seed: int = 0) -> list:
    """Keyframes that visit ``specs`` ((class, params) pairs, in order) evenly over frames ``first``..``last``:
    the first on ``first``, the last on ``last``, key i with seed ``seed + i`` (its latent for "slerp").
    One spec gives one keyframe (a still conditioning; only the latent may move)."""
    if not specs:
        raise SettingError("keys", "no classes to animate: add a swatch first")
    if last < first:
        raise SettingError("frames", f"expected FIRST <= LAST, got {first} {last}")
    n = len(specs)
    if n > 1 and last - first + 1 < n:
        raise SettingError("frames", f"{n} keyframes need at least {n} frames, got {last - first + 1}")
    frames = [first] if n == 1 else [first + round(i * (last - first) / (n - 1)) for i in range(n)]
    return [Keyframe(int(f), name, {str(k): float(v) for k, v in params.items()}, (int(seed) + i) % 2 ** 32)
            for i, (f, (name, params)) in enumerate(zip(frames, specs))]


def read_keys(path: str, where: str = "--keys") -> list:
    """Keyframes of a TOML file (see the module doc); ``where`` names the file in errors (a flag, a job's key)."""
    from ..documents import read_document

    return parse_keys(read_document(path, where, "toml"), where)


def check_keys(model, keys: list, where: str = "--keys") -> None:
    """Each keyframe's class and parameters against ``model``, before any frame is drawn: SettingError naming the
    keyframe by its frame."""
    for k in keys:
        try:
            model.param_vector(*k.spec)
        except SettingError as exc:
            raise SettingError(f"{where}: key at frame {k.frame}", exc.message) from None


def frame_weight(keys: list, frame: float) -> tuple:
    """(a, b, w): the keyframes around ``frame`` and the weight of b (0 at a, 1 at b); held before the
    first keyframe and after the last."""
    if frame <= keys[0].frame:
        return keys[0], keys[0], 0.0
    if frame >= keys[-1].frame:
        return keys[-1], keys[-1], 0.0
    for a, b in zip(keys, keys[1:]):
        if a.frame <= frame <= b.frame:
            return a, b, (frame - a.frame) / (b.frame - a.frame)
    raise AssertionError("unreachable: keys are sorted")


def frame_cond(model, keys: list, frame: float, H: int, W: int) -> np.ndarray:
    """The conditioning grid (E + P, H, W) of ``frame``: embeddings slerped, parameters lerped (as a blend
    whose weight map is the constant w)."""
    a, b, w = frame_weight(keys, frame)
    if a is b or w == 0.0:
        return C.uniform(model, a.spec, H, W)
    return C.blend(model, a.spec, b.spec, np.full((H, W), w, np.float64))


def _slerp_latent(x: np.ndarray, y: np.ndarray, w: float) -> np.ndarray:
    """Great-circle interpolation of two latents (flattened as one vector)."""
    xa, ya = x.ravel().astype(np.float64), y.ravel().astype(np.float64)
    cos = float(xa @ ya / max(np.linalg.norm(xa) * np.linalg.norm(ya), 1e-12))
    om = np.arccos(np.clip(cos, -1.0, 1.0))
    if np.sin(om) < 1e-6:
        return ((1 - w) * x + w * y).astype(_F)
    return ((np.sin((1 - w) * om) * x + np.sin(w * om) * y) / np.sin(om)).astype(_F)


def frame_latent(keys: list, frame: float, shape: tuple, mode: str = "fixed", speed: float = 0.05) -> np.ndarray:
    """x_T float32 ``shape`` of ``frame`` for latent motion ``mode`` (see the module doc)."""
    if mode not in LATENT_MODES:
        raise SettingError("latent", f"unknown latent motion {mode!r}; choose one of {', '.join(LATENT_MODES)}")
    noise = lambda seed: initial_noise(seed, (1, 1) + tuple(shape))[0, 0]  # noqa: E731
    if mode == "fixed":
        return noise(keys[0].seed)
    if mode == "slerp":
        a, b, w = frame_weight(keys, frame)
        return noise(a.seed) if a.seed == b.seed else _slerp_latent(noise(a.seed), noise(b.seed), w)
    theta = float(speed) * (frame - keys[0].frame)
    n0, n1 = noise(keys[0].seed), noise((keys[0].seed + 0x9E3779B9) % 2 ** 32)
    return (np.cos(theta) * n0 + np.sin(theta) * n1).astype(_F)


def animate(model, keys: list, frames: tuple, H: int, W: int, latent: str = "fixed", speed: float = 0.05,
            cancel: Callable[[], bool] | None = None, **generate_kw) -> Iterator[tuple]:
    """(frame, image float32 (H, W)) for every frame of ``frames`` = (first, last), inclusive, in order.

    ``generate_kw`` go to :func:`backend.neural.generate.generate` (steps, sampler, tileable, callback ...);
    the sampler must be deterministic (η = 0) for coherent frames.
    """
    first, last = int(frames[0]), int(frames[1])
    if last < first:
        raise SettingError("--frames", f"expected FIRST LAST with LAST >= FIRST, got {first} {last}")
    for k in keys:
        model.param_vector(*k.spec)  # unknown classes or parameters fail before the first frame
    if latent == "drift" and not np.isfinite(speed):
        raise SettingError("--drift", f"must be a finite number, got {speed}")
    for f in range(first, last + 1):
        if cancel is not None and cancel():
            from ..grid import Cancelled

            raise Cancelled("cancelled")
        yield f, frame_image(model, keys, f, H, W, latent, speed, **generate_kw)


def frame_image(model, keys: list, frame: float, H: int, W: int, latent: str = "fixed", speed: float = 0.05,
                **generate_kw) -> np.ndarray:
    """One frame (any real frame number) of a keyframed sequence: float32 (H, W); the one path of
    :func:`animate` and of animated bakes (``backend.sources.NeuralSource``)."""
    if generate_kw.get("eta"):
        raise SettingError("--eta", "animation needs a deterministic sampler (eta = 0): step noise flickers")
    generate_kw["eta"] = 0.0       # whatever the sampler's default: every frame follows its latent
    k = model.multiple_of
    shape = (-(-H // k) * k, -(-W // k) * k)
    return generate(model, frame_cond(model, keys, frame, H, W), x_T=frame_latent(keys, frame, shape, latent, speed),
                    **generate_kw)


def temporal_coherence(frames: list, independent: float) -> dict:
    """Frame-to-frame change of a sequence of images (H, W): mean and median absolute step, the largest step
    over the median (a jump, if far above 1; the README's target is at most 3), and the mean step over
    ``independent`` (the mean absolute difference of two images of the same conditioning from independent
    seeds: what a flickering animation would show every frame)."""
    steps = np.array([float(np.abs(b - a).mean()) for a, b in zip(frames, frames[1:])])
    med = float(np.median(steps)) if steps.size else 0.0
    return dict(mean_step=round(float(steps.mean()), 5) if steps.size else 0.0, median_step=round(med, 5),
                max_over_median=round(float(steps.max() / med), 3) if med > 0 else 0.0,
                step_over_independent=round(float(steps.mean() / independent), 4) if independent > 0 else 0.0,
                independent=round(float(independent), 5))
