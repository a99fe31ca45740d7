"""How good is a neural noise model?  Our stand-in for Table 2 of Maesumi et al. 2024.

No pretrained Inception or VGG weights are available, so the measuring
instrument is trained here too: a small CNN classifier on the zoo.  Per class:

    fd          Fréchet distance between generated and zoo samples in the classifier's
                penultimate features (64-D): |μ₁ - μ₂|² + tr(Σ₁ + Σ₂ - 2 (Σ₁Σ₂)^½)
    acc         the classifier's accuracy on generated samples (zoo accuracy for reference)
    psd         mean |log10 P_gen(f) - log10 P_zoo(f)| of radially averaged power spectra
    response    for the class's first parameter: spectral centroid ratio hi/lo of the model
                against the zoo's, |r_model / r_zoo - 1|
    psd_low     the PSD error on the lowest frequencies only (wavelengths S/8 to S): long-range
                structure (bands, fibre runs) that a local texture statistic misses
    coherence   |c_gen - c_zoo| of the mean orientation coherence (structure tensor, Bigün and
                Granlund 1987) measured over the whole image: 1 when all gradients are parallel
                (damascus bands, aligned fibres), 0 when isotropic; a model that keeps local
                texture but loses the long-range orientation scores near 0 where the zoo is near 1
    direction_error   for classes with a direction parameter (ORIENTED): the mean angle (degrees)
                between the dominant gradient direction of generated images and of the zoo's at
                0/45/90/135 degrees: 0 when the model follows the parameter, about 45 when it
                draws a direction of its own

and overall:

    seam        tileable output: mean |I(:, 0) - I(:, -1)| across the wrap, over the mean
                difference of neighbouring interior columns (1 = as smooth as the inside)
    locality    a half/half mask blend of two classes: how often the classifier names the
                right class on crops away from the border (the CutMix ablation of Fig. 13)

Run: ``python -m bench neural-eval --model models/neural_noise`` (see that script).
"""
from __future__ import annotations

import math
import time

import numpy as np
import torch
from torch import nn
import torch.nn.functional as F

from omninoise.backend.periodic import periodic_component

from . import zoo

__all__ = ["Classifier", "train_classifier", "cached_classifier", "known_params", "frechet", "radial_psd", "psd_error",
           "orientation_coherence", "gradient_direction", "angle_difference", "direction_error", "oriented_params", "ORIENTED",
           "evaluate"]


class Classifier(nn.Module):
    """(B, 1, S, S) in [0, 1] -> class logits; ``features`` are the mean and standard deviation of the last
    layer's channels (4 * width values).  ``stages`` stride-2 stages: 2 see 21 px (the 32² instrument), 3 see
    45 px; each further stage about doubles the receptive field, for larger evaluation sizes and long-range classes."""

    def __init__(self, n: int, width: int = 32, stages: int = 2):
        super().__init__()
        w = width
        layers = [nn.Conv2d(1, w, 3, padding=1), nn.GELU(), nn.Conv2d(w, w, 3, padding=1, stride=2), nn.GELU(),
                  nn.Conv2d(w, 2 * w, 3, padding=1), nn.GELU()]
        for _ in range(stages - 1):
            layers += [nn.Conv2d(2 * w, 2 * w, 3, padding=1, stride=2), nn.GELU(),
                       nn.Conv2d(2 * w, 2 * w, 3, padding=1), nn.GELU()]
        self.body = nn.Sequential(*layers)
        self.head = nn.Linear(4 * w, n)

    def features(self, x):
        h = self.body(x * 2.0 - 1.0)
        return torch.cat([h.mean(dim=(2, 3)), h.std(dim=(2, 3))], 1)  # (B, 4w): first and second moments

    def forward(self, x):
        return self.head(self.features(x))


def train_classifier(classes, size: int, steps: int = 600, batch: int = 64, seed: int = 0, log=None,
                     stages: int = 2):
    """A classifier over ``classes`` trained on fresh zoo samples -> (model, held-out accuracy)."""
    torch.manual_seed(seed)
    clf = Classifier(len(classes), stages=stages)
    opt = torch.optim.AdamW(clf.parameters(), lr=2e-3)
    # stages > 2 (the sharper instrument): the learning rate decays to a tenth (cosine), which the longer
    # runs it is trained with need to settle; the 2-stage instrument keeps its constant rate (reproducible)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, steps, eta_min=2e-4) if stages > 2 else None
    sampler = zoo.ZooSampler(size, classes, rng=np.random.default_rng(seed))
    index = {zoo.CLASS_NAMES.index(c): i for i, c in enumerate(classes)}
    for step in range(steps):
        imgs, ids, _ = sampler.batch(batch)
        y = torch.tensor([index[int(i)] for i in ids])
        loss = F.cross_entropy(clf(imgs), y)
        opt.zero_grad()
        loss.backward()
        opt.step()
        if sched is not None:
            sched.step()
        if log and step % 100 == 0:
            log(f"classifier step {step}: loss {float(loss.detach()):.3f}")
    clf.eval()
    test = zoo.ZooSampler(size, classes, rng=np.random.default_rng(seed + 999), sets_per_class=512)
    imgs, ids, _ = test.batch(512)
    with torch.no_grad():
        pred = clf(imgs).argmax(1)
    acc = float((pred == torch.tensor([index[int(i)] for i in ids])).float().mean())
    return clf, acc


def frechet(a: np.ndarray, b: np.ndarray) -> float:
    """Fréchet distance of Gaussians fitted to feature sets a (n, d) and b (m, d)."""
    mu1, mu2 = a.mean(0), b.mean(0)
    s1, s2 = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    # tr((s1 s2)^1/2) through the eigenvalues of s1^1/2 s2 s1^1/2 (symmetric, PSD)
    w, v = np.linalg.eigh(s1)
    r1 = (v * np.sqrt(np.clip(w, 0, None))) @ v.T
    m = r1 @ s2 @ r1
    tr = np.sqrt(np.clip(np.linalg.eigvalsh((m + m.T) / 2), 0, None)).sum()
    return float(((mu1 - mu2) ** 2).sum() + np.trace(s1) + np.trace(s2) - 2 * tr)


def radial_psd(imgs: np.ndarray) -> np.ndarray:
    """Mean radially averaged power spectrum of images (n, S, S) -> (S // 2,)."""
    S = imgs.shape[-1]
    F_ = np.abs(np.fft.fft2(imgs - imgs.mean(axis=(1, 2), keepdims=True))) ** 2
    f = np.fft.fftfreq(S) * S
    r = np.rint(np.hypot(*np.meshgrid(f, f, indexing="ij"))).astype(int)
    out = np.zeros(S // 2)
    for k in range(1, S // 2 + 1):
        out[k - 1] = F_[:, r == k].mean()
    return out


def psd_error(gen: np.ndarray, real: np.ndarray, low: bool = False) -> float:
    """Mean |log10 P_gen(k) - log10 P_real(k)| of the radial spectra of images (n, S, S); with ``low`` only over
    k = 1 .. max(2, S // 8), i.e. wavelengths from S down to S/8 px (the long-range structure)."""
    d = np.abs(np.log10(radial_psd(gen) + 1e-12) - np.log10(radial_psd(real) + 1e-12))
    return float(d[: max(2, gen.shape[-1] // 8)].mean() if low else d.mean())


def _structure_tensor(imgs: np.ndarray):
    """J = mean(∇I ∇Iᵀ) over each image (n, S, S), central differences -> Jxx, Jyy, Jxy float64 (n,)."""
    x = np.asarray(imgs, np.float64)
    gy = 0.5 * (x[:, 2:, 1:-1] - x[:, :-2, 1:-1])
    gx = 0.5 * (x[:, 1:-1, 2:] - x[:, 1:-1, :-2])
    return (gx * gx).mean((1, 2)), (gy * gy).mean((1, 2)), (gx * gy).mean((1, 2))


def gradient_direction(imgs: np.ndarray) -> np.ndarray:
    """The dominant gradient direction of images (n, S, S) -> (n,) degrees in [0, 180), 0 along +x (array
    columns), 90 along the rows: the structure tensor's leading eigenvector, ½ atan2(2 Jxy, Jxx - Jyy)."""
    jxx, jyy, jxy = _structure_tensor(imgs)
    return np.degrees(0.5 * np.arctan2(2 * jxy, jxx - jyy)) % 180.0


def orientation_coherence(imgs: np.ndarray) -> np.ndarray:
    """Global orientation coherence of images (n, S, S) -> (n,) in [0, 1].

    The structure tensor averaged over the whole image, J = mean(∇I ∇Iᵀ) (central differences), and
    (λ1 - λ2) / (λ1 + λ2) = sqrt((Jxx - Jyy)² + 4 Jxy²) / (Jxx + Jyy) of its eigenvalues (Bigün and Granlund
    1987): 1 when every gradient in the image is parallel (straight bands), 0 for isotropic texture.
    Flat images give 0.
    """
    jxx, jyy, jxy = _structure_tensor(imgs)
    tr = jxx + jyy
    return np.where(tr > 1e-12, np.sqrt((jxx - jyy) ** 2 + 4 * jxy ** 2) / np.maximum(tr, 1e-12), 0.0)


#: log-spaced radial frequency bins and value quantiles of :func:`look`
LOOK_BINS, LOOK_QUANTILES = 24, 32


def look(imgs: np.ndarray, floor: float = 0.0) -> dict:
    """What a set of images (n, S, S) in [0, 1] looks like, for :func:`look_distance`: the shape of its
    radially averaged power spectrum (log10 of the power in LOOK_BINS log-spaced bands from 1 to S/2 cycles
    per image, normalised to total power 1, so contrast is left to the histogram) and its value histogram
    (LOOK_QUANTILES quantiles of all pixels).

    The spectrum is that of each image's :func:`periodic_component`, so an image that tiles (five zoo classes
    do) and one that does not (a model's image, a crop) are compared on their content: the jumps at the borders
    of one that does not tile put about 10^-4 of the power into each of the top bands, more than the whole content
    of a smooth class has there (48² crops of 64² zoo gaussians: 10^-3.4 to 10^-3.8; the whole, tiling images:
    10^-5.8 to 10^-7.2).

    ``floor`` > 0 raises every band's share to at least ``floor`` before the log: bands holding less of the power
    than that (1e-4: an amplitude under 1 % of the image's standard deviation) then count as equal, whereas on the
    plain log scale a band at 1e-7 and one at 1e-5 of the power differ as much as 10 % and 0.1 %."""
    x = np.asarray(imgs, np.float64)
    p = radial_psd(periodic_component(x))
    k = np.arange(1, len(p) + 1)
    edges = np.geomspace(1, len(p) + 1, LOOK_BINS + 1)
    band = np.array([p[(k >= lo) & (k < hi)].sum() for lo, hi in zip(edges[:-1], edges[1:])])
    spec = np.log10(np.maximum(band / max(band.sum(), 1e-20), floor) + 1e-12)
    q = np.quantile(x, (np.arange(LOOK_QUANTILES) + 0.5) / LOOK_QUANTILES)
    return dict(spectrum=spec, histogram=q)


def look_distance(a: dict, b: dict, scale=(1.0, 1.0)) -> float:
    """Mean |Δ| of two :func:`look` spectra over ``scale[0]`` plus mean |Δ| of their quantiles over ``scale[1]``
    (the scales put both terms in units of a typical distance between two zoo classes)."""
    return float(np.abs(a["spectrum"] - b["spectrum"]).mean() / scale[0]
                 + np.abs(a["histogram"] - b["histogram"]).mean() / scale[1])


def look_scales(refs: dict) -> tuple:
    """Median spectrum and histogram distances over all pairs of reference looks {class: look}."""
    names = sorted(refs)
    ds, dh = [], []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            ds.append(np.abs(refs[a]["spectrum"] - refs[b]["spectrum"]).mean())
            dh.append(np.abs(refs[a]["histogram"] - refs[b]["histogram"]).mean())
    return float(np.median(ds)), float(np.median(dh))


def nearest_looks(probe: dict, refs: dict, scale) -> list:
    """[(class, distance), ...] of the reference looks sorted by distance from ``probe``."""
    return sorted(((c, look_distance(probe, r, scale)) for c, r in refs.items()), key=lambda t: t[1])


def _centroid(imgs):
    p = radial_psd(imgs)
    k = np.arange(1, len(p) + 1)
    return float((p * k).sum() / p.sum())


#: classes whose parameter sets a direction: (that parameter, settings that make the direction unambiguous)
ORIENTED = {"fibers": ("orientation", {}), "phasor": ("orientation", {"spread": 0.2}),
            "gabor": ("orientation", {"bandwidth": 0.05}), "gabor_texture": ("Orientation", {"Anisotropy": 1.0})}
#: the directions (degrees) at which :func:`direction_error` asks for each oriented class
DIRECTIONS = (0.0, 45.0, 90.0, 135.0)


def oriented_params(name: str, theta) -> dict:
    """The settings at which class ``name`` of :data:`ORIENTED` is asked for direction ``theta`` (radians, a number
    or an array): its other parameters at mid-range, but for the listed settings that make the direction clear."""
    pname, extra = ORIENTED[name]
    return dict(zoo.default_params(name), **extra, **{pname: theta})


def angle_difference(a, b) -> np.ndarray:
    """|a - b| between directions in degrees modulo 180 -> values in [0, 90]; 45 on average for unrelated ones."""
    d = np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64)) % 180.0
    return np.minimum(d, 180.0 - d)


def direction_error(name: str, sample, size: int, seeds: int = 4) -> dict:
    """Does the model draw the direction its parameter asks for?  For each direction of :data:`DIRECTIONS`
    (class ``name`` of :data:`ORIENTED`, its other parameters at mid-range but for the listed settings) ``seeds``
    images from ``sample(spec, count, seed0)`` -> (count, S, S) are compared with the zoo's images of the same
    settings: the mean :func:`angle_difference` of their dominant gradient directions (degrees; 0 follows the
    parameter, about 45 ignores it) and the same between the zoo's seeds and their mean direction (its own
    spread)."""
    errs, zoo_spread = [], []
    for deg in DIRECTIONS:
        params = oriented_params(name, math.radians(deg))
        real = zoo.generate(name, {k: np.full(seeds, v) for k, v in params.items()}, torch.arange(seeds) + 31_000,
                            size).numpy()
        gen = sample((name, params), seeds, 4000)
        dz, dg = gradient_direction(real), gradient_direction(gen)
        ref = float(np.degrees(0.5 * np.angle(np.exp(2j * np.radians(dz)).mean())) % 180.0)  # the zoo's mean
        errs.append(angle_difference(dg, ref))
        zoo_spread.append(angle_difference(dz, ref))
    return dict(direction_error=round(float(np.mean(errs)), 1), direction_error_zoo=round(float(np.mean(zoo_spread)), 1),
                direction_param=ORIENTED[name][0])


def known_params(model, name: str, params: dict) -> dict:
    """The zoo parameters of ``name`` that ``model`` was trained with: a model exported before a class gained a
    parameter (fibers' and phasor's orientation) is not told it and draws its own, which the zoo's images then
    measure."""
    own = {p["name"] for p in model.class_params[name]["params"]}
    return {k: v for k, v in params.items() if k in own}


def _images_description() -> dict:
    """:func:`zoo.describe` without what does not change the zoo's images (a parameter's conditioning period)."""
    out = zoo.describe()
    for c in out.values():
        c["params"] = [{k: v for k, v in p.items() if k != "period"} for p in c["params"]]
    return out


def cached_classifier(classes, size: int, steps: int, cache: str | None = None, log=None, stages: int = 2,
                      threads: int | None = None):
    """:func:`train_classifier`, or the one saved in folder ``cache`` for the same classes, size, steps
    and thread count (training is reproducible for a fixed count), so that runs that compare
    samplers or models use one instrument without training it again.  ``threads``: train with this many
    torch threads (and key the cache by it) whatever the caller's own count, so an instrument trained
    beside other work can be reused by evaluations that use every core."""
    if threads:
        saved = torch.get_num_threads()
        torch.set_num_threads(int(threads))
        try:
            return cached_classifier(classes, size, steps, cache, log, stages)
        finally:
            torch.set_num_threads(saved)
    if not cache:
        return train_classifier(classes, size, steps, log=log, stages=stages)
    import hashlib
    import json
    import os

    key = dict(classes=list(classes), size=size, steps=steps, threads=torch.get_num_threads(),
               # the zoo's classes and parameters: a classifier of the zoo before a change is another instrument;
               # a parameter's period is left out: it changes the conditioning, not the images a classifier sees
               zoo=hashlib.sha256(json.dumps(_images_description(), sort_keys=True).encode()).hexdigest()[:16])
    if stages != 2:
        key["stages"] = stages  # only where it is not 2, the default the key was first written without
    key = json.dumps(key)
    path = os.path.join(cache, "classifier_" + hashlib.sha256(key.encode()).hexdigest()[:16] + ".pt")
    if os.path.isfile(path):
        saved = torch.load(path, weights_only=False)
        clf = Classifier(len(classes), stages=stages)
        clf.load_state_dict(saved["state"])
        return clf.eval(), saved["accuracy"]
    from omninoise import export

    clf, acc = train_classifier(classes, size, steps, log=log, stages=stages)
    os.makedirs(cache, exist_ok=True)
    with export.atomic_path(path) as tmp:
        torch.save(dict(state=clf.state_dict(), accuracy=acc, key=key), tmp)
    return clf, acc


def evaluate(model, classes, n: int = 32, steps: int = 30, clf_steps: int = 600, log=print,
             sampler: str = "ddim", spacing: str | None = None, classifier_cache: str | None = None,
             size: int | None = None, clf_stages: int = 2, clf_threads: int | None = None,
             only: tuple | None = None, eta: float = 0.0) -> dict:
    """The table above for an exported model (a :class:`backend.neural.model.NeuralNoiseModel`),
    sampled by ``sampler`` with ``steps`` timesteps (the same seeds for every sampler) at ``size``² px
    (default: the model's training size; two models compare only at one size, with one classifier).
    The n samples of a class are generated as one batch, each from its own seed as before.
    ``only``: rows for these of ``classes`` alone, measured by the classifier of all ``classes`` (the same
    instrument, the same samples as a full run with this n) and without the seam and locality measures (None).
    ``eta`` > 0: the sampler's stochastic form; every batch's step noise starts from one seed."""
    from omninoise.backend.neural import conditioning as C
    from omninoise.backend.neural.generate import generate as _generate
    from omninoise.backend.neural.sampler import initial_noise, sample as _run_sampler, step_noise_rng

    from omninoise.backend.neural.sampler import DEFAULT_SPACING

    spacing = DEFAULT_SPACING[sampler] if spacing is None else spacing

    def generate(*args, **kw):
        return _generate(*args, sampler=sampler, spacing=spacing, eta=eta, **kw)

    def _sample(*args, **kw):  # the sampler, with its step noise seeded when eta > 0
        return _run_sampler(*args, **kw, **(dict(eta=eta, rng=step_noise_rng(0)) if eta else {}))

    S = int(size or model.config["train_size"])
    clf, zoo_acc = cached_classifier(classes, S, clf_steps, classifier_cache, log=log, stages=clf_stages,
                                     threads=clf_threads)
    index = {c: i for i, c in enumerate(classes)}
    rng = np.random.default_rng(123)
    rows = {}
    eps_fn = model.eps_fn(False)

    def sample(spec, count, seed0):
        cond = np.repeat(C.uniform(model, (spec[0], known_params(model, *spec)), S, S)[None], count, 0)
        x = _sample(sampler, eps_fn, initial_noise(seed0, (count, 1, S, S)), cond, steps,
                    alphas_cumprod=model.alphas_cumprod, spacing=spacing)
        return (x[:, 0] + 1) * 0.5

    def feats(imgs):
        with torch.no_grad():
            t = torch.from_numpy(np.ascontiguousarray(imgs, np.float32))[:, None]
            return clf.features(t).numpy(), clf(t).argmax(1).numpy()

    for name in classes:
        sets = rng.integers(0, 16384, size=n)
        if only is not None and name not in only:
            continue  # its draw is made all the same: the classes after it get the samples of a full run
        params = zoo.sample_params(name, sets)
        real = zoo.generate(name, params, torch.arange(n) + 77_000, S).numpy()
        specs = [(name, known_params(model, name, {k: float(v[i]) for k, v in params.items()})) for i in range(n)]
        cond = np.stack([C.uniform(model, spec, S, S) for spec in specs])
        x0 = np.concatenate([initial_noise(1000 + i, (1, 1, S, S)) for i in range(n)])
        gen = (_sample(sampler, eps_fn, x0, cond, steps, alphas_cumprod=model.alphas_cumprod,
                       spacing=spacing)[:, 0] + 1) * 0.5
        fr, _ = feats(real)
        fg, pg = feats(gen)
        p0 = zoo.CLASSES[name].params[0]
        lo, hi = p0.lo + 0.2 * (p0.hi - p0.lo), p0.lo + 0.8 * (p0.hi - p0.lo)
        mid = zoo.default_params(name)
        zr = [_centroid(zoo.generate(name, dict(mid, **{p0.name: v}), torch.arange(8), S).numpy()) for v in (lo, hi)]
        mr = [_centroid(sample((name, dict(mid, **{p0.name: v})), 8, 50)) for v in (lo, hi)]
        rows[name] = dict(
            fd=round(frechet(fr, fg), 3), acc=round(float((pg == index[name]).mean()), 3),
            psd=round(psd_error(gen, real), 3), psd_low=round(psd_error(gen, real, low=True), 3),
            coherence=round(abs(float(orientation_coherence(gen).mean() - orientation_coherence(real).mean())), 3),
            coherence_zoo=round(float(orientation_coherence(real).mean()), 3),
            response=round(abs((mr[1] / mr[0]) / (zr[1] / zr[0]) - 1.0), 3), param=p0.name)
        if name in ORIENTED and ORIENTED[name][0] in {p["name"] for p in model.class_params[name]["params"]}:
            rows[name].update(direction_error(name, sample, S))
        log(f"{name}: {rows[name]}")
    if only is not None:
        return dict(classes=rows, size=S, classifier=dict(steps=clf_steps, stages=clf_stages, threads=clf_threads),
                    zoo_accuracy=round(zoo_acc, 3), seam_tileable=None, seam_plain=None, locality=None)
    # tileable seams
    tile = generate(model, C.uniform(model, (classes[0], {}), S * 2, S * 2), seed=5, steps=steps, tileable=True)
    plain = generate(model, C.uniform(model, (classes[0], {}), S * 2, S * 2), seed=5, steps=steps, tileable=False)

    def seam(img):
        inner = np.abs(np.diff(img, axis=1)).mean()
        return float(np.abs(img[:, 0] - img[:, -1]).mean() / inner)

    # blend locality: left half class A, right half class B; classify crops away from the border
    hits, total = 0, 0
    for a, b in [(classes[i], classes[(i + 1) % len(classes)]) for i in range(len(classes))]:
        w = np.zeros((S, 3 * S), np.float32)
        w[:, int(1.5 * S):] = 1.0
        img = generate(model, C.blend(model, (a, {}), (b, {}), C.mask_weight(w > 0.5, 8.0, 2.0)), seed=9,
                       steps=steps)
        _, pred = feats(np.stack([img[:, : S], img[:, -S:]]))
        hits += int(pred[0] == index[a]) + int(pred[1] == index[b])
        total += 2
    return dict(classes=rows, size=S, classifier=dict(steps=clf_steps, stages=clf_stages, threads=clf_threads),
                zoo_accuracy=round(zoo_acc, 3), seam_tileable=round(seam(tile), 3),
                seam_plain=round(seam(plain), 3), locality=round(hits / total, 3))


def step_seconds(model_folder: str, size: int = 256, reps: int = 3) -> dict:
    """Seconds per DDIM step (one ε evaluation) at size², onnxruntime vs torch with the same weights.

    The torch network is rebuilt from the export itself (:func:`.warm_start.torch_from_export`);
    its output is checked against onnxruntime's first (max |Δε| reported), so both time the
    same network.
    """
    from omninoise.backend.neural.model import NeuralNoiseModel
    from .warm_start import torch_from_export

    m = NeuralNoiseModel(model_folder)
    C = m.embedding.shape[1] + len(m.params)
    x = np.random.default_rng(0).standard_normal((1, 1, size, size)).astype(np.float32)
    t = np.array([500.0], np.float32)
    cond = np.zeros((1, C, size, size), np.float32)
    eps = m.eps_fn(False)
    eps(x, t, cond)
    t0 = time.perf_counter()
    for _ in range(reps):
        eps(x, t, cond)
    ort_s = (time.perf_counter() - t0) / reps
    tm = torch_from_export(model_folder)
    with torch.no_grad():
        args = (torch.from_numpy(x), torch.from_numpy(t), torch.from_numpy(cond))
        diff = float(np.abs(tm(*args).numpy() - eps(x, t, cond)).max())
        if diff > 1e-3:
            raise RuntimeError(f"torch and onnxruntime disagree on {model_folder} (max |Δε| {diff:.2g})")
        t0 = time.perf_counter()
        for _ in range(reps):
            tm(*args)
    torch_s = (time.perf_counter() - t0) / reps
    return dict(size=size, onnxruntime_s=round(ort_s, 4), torch_s=round(torch_s, 4), ratio=round(torch_s / ort_s, 2),
                max_eps_difference=diff)
