"""Inverse design (Maesumi et al. 2024, Fig. 8): class weights, parameters and a seed whose generation matches an
image, found with the runtime's sampler alone (numpy + onnxruntime: no torch, no downloaded weights).

The match is a stationary texture statistic of the project's own (:func:`describe`), so that an image and a
generation with another layout of the same texture are close:

    spectrum   the share of the power spectrum in half-octave radial bands from 1/N to 1/2 cycle per pixel,
               square-rooted (feature size)
    levels     9 grey-level quantiles (histogram: contrast, bias, binary against smooth)
    edges      3 quantiles of the gradient magnitude over the image's spread (sharp cells against soft blobs)
    coherence  the mean local orientation coherence of the structure tensor (fibres and bands against isotropic)

and the distance (:func:`distance`) sums each group's Euclidean distance times its weight (:data:`WEIGHTS`).

The search (:func:`fit`) evaluates the model in batches at the fit size with few sampler steps:

    1. with the bank (:func:`load_bank`: the statistic of zoo images of known class and parameters), the nearest
       bank image of each class; the ``keep + 2`` classes nearest the target are generated with their bank
       image's parameters; without a bank, every trained class at the middle of its parameter ranges
                                                                         -> the best ``keep`` classes
    2. for each kept class, ``rounds`` rounds of a (1 + λ) evolution strategy on its normalised parameters
       (λ Gaussian perturbations of the best so far, σ halving every round, clipped to the ranges)
    3. constant blends of the two best (class, parameters) at weights 1/4, 1/2, 3/4 (embeddings slerped, as a
       blend map does): the class weights
    4. ``seeds`` seeds of the winner (a seed changes the layout; the statistic barely cares, the picture does)

The target's statistic is the mean over up to five crops of the fit size (centre and corners) at the target's
own pixel scale: the zoo's lengths are in pixels (128 px a unit), so fitted scale parameters hold for an output of
any size.  Images: float32 (H, W) in [0, 1].
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import SettingError
from . import conditioning as C
from .generate import DEFAULT_SPACING
from .sampler import initial_noise, sample

__all__ = ["FitResult", "WEIGHTS", "describe", "distance", "target_statistic", "fit", "prepare_target",
           "fitted_conditioning", "load_bank", "bank_nearest", "render"]

_F = np.float32
#: weights of the statistic's groups in :func:`distance`
WEIGHTS = dict(spectrum=2.0, levels=1.0, edges=0.5, coherence=1.0)
_QUANT = np.linspace(0.1, 0.9, 9)


def _box(a: np.ndarray, r: int) -> np.ndarray:
    """Mean over a (2r+1)² window, wrapping at the borders (a: (H, W))."""
    out = np.zeros_like(a)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out += np.roll(a, (dy, dx), (0, 1))
    return out / (2 * r + 1) ** 2


def describe(img: np.ndarray) -> dict:
    """The texture statistic of a float (H, W) image in [0, 1] (H, W >= 16): a dict of float64 vectors."""
    a = np.asarray(img, np.float64)
    H, W = a.shape
    spread = a.std() + 1e-6
    P = np.abs(np.fft.fft2(a - a.mean())) ** 2
    fy, fx = np.meshgrid(np.fft.fftfreq(H), np.fft.fftfreq(W), indexing="ij")
    r = np.hypot(fy, fx)  # cycles per pixel, 0 .. 0.707
    nb = max(2, int(round(2 * np.log2(min(H, W) / 2))))  # half-octave bands from 1/N to 0.5 cycles/px
    inner = 0.5 * 2.0 ** (-np.arange(nb - 1, 0, -1) / 2)
    band = np.digitize(r, inner)  # 0 .. nb-1 (the corners beyond 0.5 join the last band)
    power = np.bincount(band.ravel(), P.ravel(), minlength=nb)[:nb]
    spectrum = np.sqrt(power / max(power.sum(), 1e-12))
    gy, gx = np.gradient(a)
    mag = np.hypot(gx, gy) / spread
    Jxx, Jyy, Jxy = _box(gx * gx, 3), _box(gy * gy, 3), _box(gx * gy, 3)
    coh = np.sqrt((Jxx - Jyy) ** 2 + 4 * Jxy ** 2) / (Jxx + Jyy + 1e-9)
    return dict(spectrum=spectrum, levels=np.quantile(a, _QUANT), edges=np.quantile(mag, [0.25, 0.5, 0.9]) / 4.0,
                coherence=np.array([coh.mean()]))


def distance(s: dict, t: dict) -> float:
    """Weighted sum of the groups' Euclidean distances between two statistics of :func:`describe`."""
    return float(sum(w * np.linalg.norm(s[k] - t[k]) for k, w in WEIGHTS.items()))


def load_bank(folder: str) -> dict:
    """The inverse-design bank of ``folder`` (fit_bank.json + bank.npz, sha256-checked; built by
    ``training.fit_bank``): {classes, size, cls int (N,), u float32 (N, 4), one float32 (N, n) array per
    statistic group}."""
    from ..onnx_models import load_model_json

    doc = load_model_json(folder, "fit_bank.json")
    with np.load(os.path.join(folder, "bank.npz")) as z:
        arrays = {k: z[k] for k in z.files}
    return dict(arrays, classes=list(doc["classes"]), size=int(doc["size"]))


def bank_nearest(bank: dict, target: dict) -> dict:
    """{class: (distance, normalised parameters float64 (4,))}: each class's bank image nearest ``target``."""
    d = sum(w * np.linalg.norm(bank[k] - target[k][None].astype(np.float32), axis=1) for k, w in WEIGHTS.items())
    out = {}
    for ci, name in enumerate(bank["classes"]):
        rows = np.flatnonzero(bank["cls"] == ci)
        if rows.size:
            i = rows[np.argmin(d[rows])]
            out[name] = (float(d[i]), bank["u"][i].astype(np.float64))
    return out


def _crops(img: np.ndarray, size: int) -> list:
    H, W = img.shape
    if H <= size and W <= size:
        return [img]
    ys = sorted({0, (H - size) // 2, H - size})
    xs = sorted({0, (W - size) // 2, W - size})
    picks = [((H - size) // 2, (W - size) // 2)] + [(y, x) for y in (ys[0], ys[-1]) for x in (xs[0], xs[-1])]
    return [img[y:y + size, x:x + size] for y, x in dict.fromkeys(picks)]


def target_statistic(img: np.ndarray, size: int) -> dict:
    """The mean statistic of up to five size² crops of ``img`` (centre first, then the corners)."""
    stats = [describe(c) for c in _crops(img, size)]
    return {k: np.mean([s[k] for s in stats], axis=0) for k in stats[0]}


def prepare_target(img: np.ndarray, multiple: int, where: str = "image") -> tuple:
    """(grey float32 (H, W) in [0, 1], notes): colour (H, W, 3|4) becomes the mean of its channels with a note;
    the grey levels are stretched so that the 1st and 99th percentiles become 0 and 1 (the zoo's noises span
    [0, 1], and a pale, low-contrast photo should be matched by its pattern, not its exposure; a note says so
    when the stretch is large); an image smaller than 16 px or than the model's multiple, or flat, is refused."""
    a = np.asarray(img, np.float32)
    notes = []
    if a.ndim == 3:
        if a.shape[2] in (2, 4):
            a = a[..., :-1]
        if a.shape[2] > 1:
            notes.append(f"{where}: colour converted to grey (the mean of its {a.shape[2]} channels)")
        a = a.mean(axis=2)
    if a.ndim != 2:
        raise SettingError(where, f"expected an image, got an array of shape {a.shape}")
    H, W = a.shape
    least = max(16, multiple)
    if H < least or W < least:
        raise SettingError(where, f"{W}x{H} px; fitting needs at least {least}x{least} px")
    if not np.all(np.isfinite(a)):
        raise SettingError(where, "the image holds NaN or infinite values")
    lo, hi = (float(v) for v in np.percentile(a, [1, 99]))
    if hi - lo < 1e-4:
        raise SettingError(where, "the image is flat (one grey level): there is no texture to fit")
    if hi - lo < 0.9 or lo < -0.05 or hi > 1.05:  # the zoo's noises span [0, 1]: compare patterns, not exposure
        notes.append(f"{where}: grey levels stretched from [{lo:.3g}, {hi:.3g}] (1st-99th percentile) to [0, 1]")
    return np.clip((a - lo) / (hi - lo), 0.0, 1.0).astype(np.float32), notes


@dataclass(frozen=True)
class FitResult:
    """classes: {name: weight} (one or two, weights summing to 1); params: {name: {parameter: value}} in the
    class's units; seed; distance of the best generation's statistic to the target's; evaluations: model
    generations the search ran; fit_size: side of the fitted window; notes: what was done to the input."""

    classes: dict
    params: dict
    seed: int
    distance: float
    evaluations: int
    fit_size: int
    notes: tuple = ()
    trace: tuple = field(default=(), compare=False)

    def to_json(self) -> dict:
        return dict(classes=self.classes, params=self.params, seed=self.seed, distance=round(self.distance, 5),
                    evaluations=self.evaluations, fit_size=self.fit_size, notes=list(self.notes),
                    command=self.command())

    def command(self) -> str:
        """The ``omninoise neural`` flags that regenerate the fit (a blend is not a uniform flag: the dominant
        class is given)."""
        name = max(self.classes, key=self.classes.get)
        flags = " ".join(f"--param {k}={v:.4g}" for k, v in self.params[name].items())
        # the seed was chosen on the deterministic sampler's images: the command keeps it deterministic
        return f"omninoise neural --noise {name} {flags} --seed {self.seed} --eta 0".replace("  ", " ")


def _physical(model, name: str, u: np.ndarray) -> dict:
    spec = model.class_params[name]["params"]
    return {p["name"]: float(p["min"] + float(np.clip(uu, 0, 1)) * (p["max"] - p["min"])) for p, uu in zip(spec, u)}


def fitted_conditioning(model, result: FitResult, H: int, W: int) -> np.ndarray:
    """The conditioning grid (E + P, H, W) of a fit: uniform, or the constant blend of its two classes."""
    names = list(result.classes)
    if len(names) == 1:
        return C.uniform(model, (names[0], result.params[names[0]]), H, W)
    a, b = names
    return C.blend(model, (a, result.params[a]), (b, result.params[b]),
                   np.full((H, W), result.classes[b], np.float64))


def render(model, cands: list, S: int, steps: int = 6, sampler: str = "dpmpp_2m", eps=None) -> np.ndarray:
    """One batch of candidates (spec_a, spec_b | None, blend weight of b, seed) -> images float32 (B, S, S)."""
    eps = model.eps_fn(False) if eps is None else eps
    conds = np.stack([C.uniform(model, a, S, S) if b is None else
                      C.blend(model, a, b, np.full((S, S), w, np.float64)) for a, b, w, _ in cands])
    x_T = np.concatenate([initial_noise(s, (1, 1, S, S)) for *_, s in cands])
    x0 = sample(sampler, eps, x_T, conds, steps, alphas_cumprod=model.alphas_cumprod, spacing=DEFAULT_SPACING[sampler])
    return np.clip((x0[:, 0] + 1.0) * 0.5, 0.0, 1.0).astype(_F)


def check_fit_size(size: int, multiple: int, where: str = "fit size") -> None:
    """SettingError naming ``where`` unless ``size`` (the side of the windows compared, px) is a multiple of the
    model's ``multiple`` of at least 16 (a larger one than the image is cut to the image)."""
    if size % multiple or size < 16:
        raise SettingError(where, f"must be a multiple of {multiple} of at least 16, got {size}")


def fit(model, image: np.ndarray, size: int = 64, steps: int = 6, sampler: str = "dpmpp_2m", keep: int = 3,
        rounds: int = 3, population: int = 4, seeds: int = 3, seed: int = 0, batch: int = 8,
        bank: dict | None = None, rng: np.random.Generator | None = None, progress: Callable[[float], None] | None = None,
        cancel: Callable[[], bool] | None = None) -> FitResult:
    """Fit class weights, parameters and seed to ``image`` (grey float (H, W) in [0, 1], see
    :func:`prepare_target`); see the module doc for the search.  Deterministic for a given ``rng``
    (default: ``np.random.default_rng(seed)``).  ``bank`` (:func:`load_bank`) is used when it was built at the
    fit size, else stage 1 tries every class at mid-range parameters."""
    k = model.multiple_of
    check_fit_size(size, k)
    img, notes = prepare_target(image, k)
    S = min(size, (min(img.shape) // k) * k)
    target = target_statistic(img, S)
    rng = np.random.default_rng(seed) if rng is None else rng
    names = list(model.config.get("trained_classes") or model.classes)
    dims = {n: len(model.class_params[n]["params"]) for n in names}
    use_bank = bank is not None and bank["size"] == S
    first = min(keep + 2, len(names)) if use_bank else len(names)
    total = first + keep * rounds * population + 3 + seeds
    done = [0]
    trace = []
    eps = model.eps_fn(False)

    def evaluate(cands: list) -> list:
        """cands: (spec_a, spec_b | None, w, seed) -> distances, in batches."""
        out = []
        for i in range(0, len(cands), batch):
            if cancel is not None and cancel():
                from ..grid import Cancelled

                raise Cancelled("cancelled")
            part = cands[i:i + batch]
            out += [distance(describe(g), target) for g in render(model, part, S, steps, sampler, eps)]
            done[0] += len(part)
            if progress is not None:
                progress(min(1.0, done[0] / total))
        return out

    # 1. the nearest classes of the bank at their bank parameters, or every class at mid-range parameters
    if use_bank:
        near = {n: v for n, v in bank_nearest(bank, target).items() if n in dims}
        tried = sorted(near, key=lambda n: near[n][0])[:first]
        start = {n: near[n][1][:dims[n]] for n in tried}
        trace.append(dict(stage="bank", distances={n: round(near[n][0], 4) for n in tried}))
    else:
        tried, start = names, {n: np.full(dims[n], 0.5) for n in names}
    d1 = evaluate([((n, _physical(model, n, start[n])), None, 0.0, seed) for n in tried])
    trace.append(dict(stage="classes", distances={n: round(d, 4) for n, d in zip(tried, d1)}))
    ranked = [tried[i] for i in np.argsort(d1)]
    best = {n: (d1[tried.index(n)], start[n]) for n in ranked[:keep]}
    # 2. (1 + λ) evolution strategy per kept class, σ halving every round
    for r in range(rounds):
        sigma = 0.25 / 2 ** r
        cands, who = [], []
        for n in ranked[:keep]:
            if dims[n] == 0:
                continue
            for _ in range(population):
                u = np.clip(best[n][1] + sigma * rng.standard_normal(dims[n]), 0.0, 1.0)
                cands.append(((n, _physical(model, n, u)), None, 0.0, seed))
                who.append((n, u))
        for (n, u), d in zip(who, evaluate(cands)):
            if d < best[n][0]:
                best[n] = (d, u)
        trace.append(dict(stage=f"parameters, round {r + 1}", sigma=sigma,
                          distances={n: round(best[n][0], 4) for n in ranked[:keep]}))
    order = sorted(best, key=lambda n: best[n][0])
    a = order[0]
    spec_a = (a, _physical(model, a, best[a][1]))
    choice = (best[a][0], {a: 1.0}, None, 0.0)
    # 3. constant blends of the two best classes
    if len(order) > 1:
        b = order[1]
        spec_b = (b, _physical(model, b, best[b][1]))
        ws = (0.25, 0.5, 0.75)
        for w, d in zip(ws, evaluate([(spec_a, spec_b, w, seed) for w in ws])):
            if d < choice[0]:
                choice = (d, {a: round(1.0 - w, 4), b: w}, spec_b, w)
        trace.append(dict(stage="blend", classes=[a, b], best=round(choice[0], 4)))
    # 4. seeds of the winner
    d_best, weights, spec_b, w = choice
    seed_best = seed
    others = [seed + 1 + i for i in range(seeds)]
    for s, d in zip(others, evaluate([(spec_a, spec_b, w, s) for s in others])):
        if d < d_best:
            d_best, seed_best = d, s
    trace.append(dict(stage="seeds", seed=seed_best, best=round(d_best, 4)))
    params = {a: spec_a[1]}
    if spec_b is not None:
        params[spec_b[0]] = spec_b[1]
    if progress is not None:
        progress(1.0)
    return FitResult(classes=weights, params=params, seed=int(seed_best), distance=float(d_best),
                     evaluations=done[0], fit_size=S, notes=tuple(notes), trace=tuple(trace))
