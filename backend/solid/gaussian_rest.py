"""A Gaussian share of a photo's indeterministic rest, drawn as a solid.

The texture-space model's decoder draws the rest (the photo less its harmonic part, harmonic.py) from value-noise
octaves; on photos whose middle scales it cannot draw (rock faces, sand, dunes, wood grain) random phase noise,
a stationary Gaussian texture with the photo's colour cross-spectrum (Galerne, Gousseau & Morel 2011, IEEE T-IP
20(1)), is closer to the photo.  This module lifts that Gaussian texture to a solid and lets the runtime mix it in
when, and only as much as, a check on rendered planes says it brings the texture closer to the photo:

    rgb(x) = clip(mu + sqrt(1 - t) k L d(x) + sqrt(t) g(x) + h(x))

with the decoder's part k L d and harmonic part h of harmonic.py, and g the Gaussian rest below (its variance the
rest's, so the total stays the photo's for every t).

The solid: spectral synthesis as a sum of random plane waves (Lewis 1989, "Algorithms for solid noise
synthesis", SIGGRAPH; the waves of Guehl et al. 2025 without their tables):
g(x) = sum_j Re(c_j exp(2 pi i k_j . x)), COUNT waves with isotropic directions.  A plane cut of an isotropic
solid whose waves have magnitude R shows them at R sin(theta): the cut's radial power spectrum is the solid's
projected (an Abel transform; the fraction of R that falls in [a, b] is sqrt(1 - (a/R)^2) - sqrt(1 - (b/R)^2)).
So the magnitudes are drawn from the solid's radial power p3, found from the photo's radial power p2 (BINS
annuli of the rest's periodic component, Moisan 2011) by Richardson-Lucy iterations of p2 = K p3 (Richardson
1972, Lucy 1974: multiplicative, so p3 stays non-negative), and a slice's radial spectrum is the photo's.  Each
wave's colour c_j is the colour of a Fourier coefficient of the rest drawn from the same annulus by power (so
colour correlations per scale are the photo's), with a random phase and |c_j|^2 = 2 V / COUNT (V the rest's
variance summed over channels).  Isotropic: a photo's orientation (a rock face's strata) is not kept; the
harmonic part keeps its periods, and the decoder, where it is kept, its own structure.  upright.py draws a second
kind that keeps it on walls (each wave's vertical frequency on z), offered beside this one for oriented photos.

The mix t: at encode time the texture is rendered on CHECK_PLANES (x, y and z cuts at two seeds, not the planes the
held-out evaluation cuts), with t = 0 (the decoder alone) and each of MIXES for each kind offered, and compared
with the photo by :func:`~backend.solid.band_distance.band_distance`; the closest (kind, t) is kept if its distance
is at most MARGIN times that of t = 0, else the texture is the decoder's as before. An artist may ask for one kind
(REST_CHOICES); asking for the upright one checks it on the walls alone (WALL_PLANES). The check's renders vary by
more than 10 % from one set of planes to the next on many photos (structure at the scale of a 128² window), and the
margin is what keeps that chance from choosing. Every annulus with power gets waves (half of them spread evenly
over the annuli, their amplitudes weighted so each annulus keeps its power), so a few strong waves cannot move a
low-contrast photo's windows off its mean, and nothing below MIN_CYCLES cycles per photo is drawn (shading, as
harmonic.py leaves it out). MARGIN and COUNT were chosen on the training split (docs/decisions/solid.md); 512
waves cost about 2 s per million points on top of the decoder's 1.2 s, only for codes that carry a rest.

Shapes: photos float (H, W, 3) sRGB in [0, 1]; points float64 (N, 3) texture units; fields float32 (N, 3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..periodic import periodic_component
from ..progress import step
from .band_distance import BandReference
from .harmonic import mix_waves, read_waves, wave_sum

__all__ = ["GaussianRest", "rest_waves", "rest_field", "choose_mix", "mix_rests", "rest_to_json", "rest_from_json",
           "rest_spectrum", "deproject", "wave_sampling", "colour_picks", "wave_amplitudes",
           "COUNT", "MIXES", "MARGIN", "CHECK_PLANES", "CHECK_SEEDS", "check_planes", "wall_planes", "WALL_PLANES",
           "BINS", "KINDS", "KIND_WORDS", "REST_CHOICES", "seed_shift3"]

COUNT = 512             #: waves in the Gaussian rest (module doc)
BINS = 64               #: radial annuli of the spectrum
ITERATIONS = 300        #: Richardson-Lucy iterations of the deprojection
MIXES = (0.25, 0.5, 0.75, 1.0)   #: the shares t of the rest's variance tried against t = 0
MARGIN = 0.92           #: a mix is kept only if its check distance is at most MARGIN times the decoder's alone
RENDER = 128            #: px per check plane


def check_planes(seeds) -> tuple:
    """(seed, axis, offset) of check planes: x, y and z cuts at each of ``seeds``, each seed's through its own point
    (none of the held-out evaluation's planes)."""
    return tuple((int(s), a, (13.0 + s, 17.0, 19.0)) for s in seeds for a in "xyz")


def wall_planes(planes) -> tuple:
    """The walls (x and y cuts) of check ``planes``: where an artist asks for the upright rest, floors are not its
    concern."""
    return tuple(p for p in planes if p[1] != "z")


CHECK_SEEDS = (6, 7)    #: the check's seeds
#: (seed, axis, offset) of the check's planes: x, y and z cuts at CHECK_SEEDS
CHECK_PLANES = check_planes(CHECK_SEEDS)
#: the check's walls alone (wall_planes)
WALL_PLANES = wall_planes(CHECK_PLANES)
WAVE_SEED = 0x72657374  #: the waves' draw (fixed: the same photo gives the same texture)
MIN_CYCLES = 2          #: no power below this many cycles per photo (shading and vignetting, as harmonic.py)
KINDS = ("isotropic", "upright", "mixed")   #: GaussianRest.kind
#: what an artist may ask for: the check's choice among the rests offered (upright.py's gate), or one kind
REST_CHOICES = ("auto", "isotropic", "upright")
#: what each kind draws, in words for the artist (CLI and panel)
KIND_WORDS = {"isotropic": "an isotropic Gaussian solid",
              "upright": "an upright Gaussian solid (the image's layers on walls)",
              "mixed": "a blend of isotropic and upright Gaussian solids"}


@dataclass(frozen=True)
class GaussianRest:
    """The Gaussian rest as mixed in: ``freq`` float64 (M, 3) cycles per unit, ``amp`` complex128 (M, 3) colour
    amplitudes already scaled by sqrt(mix), ``mix`` in (0, 1] the share t of the rest's variance it carries
    (the decoder's part is scaled by sqrt(1 - t))."""
    freq: np.ndarray
    amp: np.ndarray
    mix: float
    kind: str = "isotropic"   #: which solid the waves draw: one of KINDS ("mixed": an interpolation of two kinds)

    def __len__(self) -> int:
        return int(self.freq.shape[0])

    def values(self) -> np.ndarray:
        """Every number, float64 (9 M + 1,) (what bake keys digest)."""
        return np.concatenate([self.freq.ravel(), self.amp.real.ravel(), self.amp.imag.ravel(), [self.mix]])


def _sphere_inside(a: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The fraction of waves of magnitude R, their directions uniform on the sphere, whose plane cut shows above a:
    a cut shows R sin(theta) with cos(theta) uniform, so sqrt(1 - (a / R)^2)."""
    return np.sqrt(np.clip(1.0 - (np.minimum(a, R) / R) ** 2, 0.0, 1.0))


def deproject(p2: np.ndarray, edges: np.ndarray, iterations: int = ITERATIONS, inside=_sphere_inside) -> np.ndarray:
    """The solid's power per bin float64 (..., B) whose cuts have the power p2 (..., B) along the last axis
    (module doc: Richardson-Lucy on p2 = K p3; ``inside(a, R)`` is the fraction of a wave of magnitude R whose cut
    shows above a: :func:`_sphere_inside` for plane cuts of an isotropic solid, upright.py's circle_inside for walls
    of an upright one)."""
    R = 0.5 * (edges[:-1] + edges[1:])[None, :]
    K = inside(edges[:-1, None], R) - inside(edges[1:, None], R)      # (B cut, B solid)
    p3 = p2 + 1e-300
    norm = np.maximum(K.sum(0), 1e-300)
    for _ in range(iterations):
        p3 = p3 * ((p2 / np.maximum(p3 @ K.T, 1e-300)) @ K) / norm
    return p3


def rest_spectrum(residual: np.ndarray, px_per_unit: float):
    """The rest's spectrum as both solids draw it: (F complex128 (H W, 3) Fourier coefficients of its periodic
    component (Moisan 2011), scaled so that its variance is the sum of |F|^2; P float64 (H W,) their power summed
    over channels, zero below MIN_CYCLES; fx, fy float64 (H W,) cycles per unit along the photo's columns and rows;
    V the variance), or None for a flat photo."""
    a = np.asarray(residual, np.float64)[..., :3]
    H, W, _ = a.shape
    u = periodic_component((a - a.mean((0, 1))).transpose(2, 0, 1))
    F = np.fft.fft2(u).reshape(3, -1).T / (H * W)                 # (H W, 3): mean square = sum |F|^2
    P = (np.abs(F) ** 2).sum(1)
    fy, fx = (f.ravel() * px_per_unit for f in np.meshgrid(np.fft.fftfreq(H), np.fft.fftfreq(W), indexing="ij"))
    P[np.hypot(fy, fx) < MIN_CYCLES * px_per_unit / min(H, W)] = 0.0   # shading and vignetting, not texture
    V = float(P.sum())
    if not V > 1e-12:
        return None
    return F, P, fx, fy, V


def wave_sampling(share: np.ndarray) -> np.ndarray:
    """The probabilities waves are drawn with from bins with the power shares ``share`` (sums to 1): half by power,
    half evenly over the bins with power (module doc: a few strong waves of long period must not carry a photo)."""
    return 0.5 * share + 0.5 * (share > 0) / np.count_nonzero(share)


def colour_picks(F: np.ndarray, P: np.ndarray, groups: np.ndarray, kb: np.ndarray, rng) -> np.ndarray:
    """Which photo coefficient each wave takes its colour from: int64 (count,) indices into F, drawn by power
    among the coefficients of the wave's bin ``kb`` (``groups``: each coefficient's bin, numbered row by row in
    rows of BINS), from the nearest bin with power where its own has none (the nearest in the same row first)."""
    filled = np.unique(groups[P > 0])
    fr, fc = np.divmod(filled, BINS)
    pick = np.empty(len(kb), np.int64)
    for k in np.unique(kb):
        kr, kc = divmod(int(k), BINS)
        src = filled[np.argmin(np.abs(fr - kr) * 2 * BINS + np.abs(fc - kc))]
        idx = np.flatnonzero(groups == src)
        sel = np.flatnonzero(kb == k)
        pick[sel] = idx[rng.choice(len(idx), size=len(sel), p=P[idx] / P[idx].sum())]
    return pick


def wave_amplitudes(F, P, pick, weight, rng) -> np.ndarray:
    """The waves' colour amplitudes complex128 (count, 3): the picked coefficients' colours at |c|^2 = weight
    (importance weights, 2 V share / (count q)), each with a random phase."""
    return F[pick] / np.sqrt(P[pick])[:, None] * (np.sqrt(weight)[:, None]
                                                   * np.exp(2j * np.pi * rng.uniform(size=(len(pick), 1))))


def rest_waves(residual: np.ndarray, px_per_unit: float, count: int = COUNT, seed: int = WAVE_SEED, spectrum=None):
    """The isotropic Gaussian rest of a photo's ``residual`` (H, W, 3; the photo less its harmonic part) seen at ``px_per_unit`` px per unit (module doc):
    (freq float64 (count, 3), amp complex128 (count, 3)) at full variance (t = 1); None for a flat photo.
    ``spectrum``: :func:`rest_spectrum` of the same rest and scale where the caller has it already."""
    spec = rest_spectrum(residual, px_per_unit) if spectrum is None else spectrum
    if spec is None:
        return None
    F, P, fx, fy, V = spec
    r = np.hypot(fx, fy)
    top = r.max() * (1.0 + 1e-9)
    edges = np.linspace(0.0, top, BINS + 1)
    b = np.minimum((r / top * BINS).astype(np.int64), BINS - 1)
    p3 = deproject(np.bincount(b, P, BINS), edges)
    rng = np.random.default_rng(seed)
    share = p3 / p3.sum()
    q = wave_sampling(share)
    kb = rng.choice(BINS, size=count, p=q)
    R = rng.uniform(edges[kb], edges[kb + 1])
    d = rng.standard_normal((count, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pick = colour_picks(F, P, b, kb, rng)
    return d * R[:, None], wave_amplitudes(F, P, pick, 2.0 * V * share[kb] / (count * q[kb]), rng)


def seed_shift3(seed: int) -> np.ndarray:
    """Where a seed moves the Gaussian rest: float64 (3,) units, (0, 0, 0) for seed 0, else uniform in [0, 64)^3
    (another seed, another draw of the same Gaussian texture)."""
    if int(seed) == 0:
        return np.zeros(3)
    return np.random.default_rng([int(seed), 0x72657374]).uniform(0.0, 64.0, 3)


def rest_field(points: np.ndarray, r: GaussianRest, seed: int = 0) -> np.ndarray:
    """sqrt(t) g at points float (N, 3) (module doc), moved by :func:`seed_shift3`: float32 (N, 3)."""
    x = np.asarray(points, np.float64)
    if x.shape[1] == 2:
        x = np.concatenate([x, np.zeros((len(x), 1))], axis=1)
    return wave_sum(x + seed_shift3(seed), r.freq, r.amp)


def choose_mix(layers, photo: np.ndarray, offered: dict, planes=CHECK_PLANES, margin: float = MARGIN,
               mixes: tuple = MIXES, progress=None, cancel=None) -> GaussianRest | None:
    """The Gaussian rest to mix in, or None (module doc). ``layers(seed, axis, offset)`` gives a check plane's (fixed,
    decoder, points): parts float32 (RENDER^2, 3) (fixed: mean colour plus harmonic part; decoder: k L d) and the
    plane's points float64 (RENDER^2, 3); ``offered`` is :func:`~backend.solid.upright.candidates`' result ({kind:
    (freq, amp)}, empty: nothing to mix). Every kind at every t of ``mixes`` meets the check; the closest is kept if
    it is ``margin`` times as close as the decoder alone (ties go to the kind offered first), on ``planes`` ((seed,
    axis, offset) as CHECK_PLANES). ``progress(fraction)`` hears each plane, rest and distance (about 2 s in all for
    one kind on 2 cores); ``cancel()`` -> True stops between them (:class:`~backend.grid.Cancelled`)."""
    if not offered:
        return None
    steps, done = len(planes) + 1 + len(offered) * (len(planes) + len(mixes)), 0

    def tick(value):
        nonlocal done
        done += 1
        step(progress, done / steps, cancel)
        return value

    planes = [tick(layers(seed, axis, offset) + (seed,)) for seed, axis, offset in planes]

    def renders(g, t):
        return [np.clip(f + np.float32(np.sqrt(1.0 - t)) * d + np.float32(np.sqrt(t)) * gi, 0.0, 1.0)
                .reshape(RENDER, RENDER, 3) for (f, d, _, _), gi in zip(planes, g)]

    ref = BandReference(photo)          # the photo's side of the distances once
    base = tick(ref.distance(renders([0.0] * len(planes), 0.0)))
    best = None
    for kind, (freq, amp) in offered.items():
        full = GaussianRest(freq, amp, 1.0, kind)
        g = [tick(rest_field(pts, full, seed)) for _, _, pts, seed in planes]
        for t in mixes:
            dist = tick(ref.distance(renders(g, t)))
            if best is None or dist < best[0]:
                best = (dist, kind, t)
    dist, kind, t = best
    if dist > margin * base:
        return None
    freq, amp = offered[kind]
    return GaussianRest(freq, amp * np.sqrt(t), float(t), kind)


def _digits(a: np.ndarray, n: int) -> list:
    return [float(f"{x:.{n}g}") for x in np.asarray(a, np.float64).ravel()]


def rest_to_json(r: GaussianRest) -> dict:
    """A named code's stored Gaussian rest (solid.json "code_rests"): freq rows [f_x, f_y, f_z], amp rows
    [re R, im R, re G, im G, re B, im B], mix; frequencies to ten significant digits (a phase error under 1e-5
    cycles at 100 units for 90 cycles per unit), amplitudes to six (the field to about 1e-5 of its spread)."""
    amp = np.stack([r.amp.real, r.amp.imag], axis=2).reshape(-1, 6)
    return dict(freq=np.reshape(_digits(r.freq, 10), (-1, 3)).tolist(),
                amp=np.reshape(_digits(amp, 6), (-1, 6)).tolist(), mix=float(r.mix), kind=r.kind)


def rest_from_json(d) -> GaussianRest:
    """:func:`rest_to_json`'s dict -> GaussianRest; ValueError naming what is wrong (at least one wave; a kind of
    KINDS, "isotropic" where none is stored: files written before the upright rest)."""
    kind = d.get("kind", "isotropic") if isinstance(d, dict) else "isotropic"
    if kind not in KINDS:
        raise ValueError(f"a Gaussian rest: kind {kind!r} is not one of {', '.join(KINDS)}")
    r = GaussianRest(*read_waves(d, 3, "mix", lambda t: 0.0 < t <= 1.0, "a mix in (0, 1]", "a Gaussian rest"), kind)
    if not len(r):
        raise ValueError("a Gaussian rest: no waves")
    return r


def mix_rests(a: GaussianRest | None, b: GaussianRest | None, s: float) -> GaussianRest | None:
    """The Gaussian rest of a code interpolated by ``s`` from a to b: both sets of waves, powers weighted (1 - s)
    and s, the mix interpolating linearly (as :func:`~backend.solid.harmonic.mix_harmonics`); None when both are."""
    parts = [(r, w) for r, w in ((a, 1.0 - s), (b, s)) if r is not None and w > 0.0]
    m = mix_waves([(r.freq, r.amp, r.mix, w) for r, w in parts], 3)
    if m is None:
        return None
    kinds = {r.kind for r, _ in parts}
    return GaussianRest(*m, kinds.pop() if len(kinds) == 1 else "mixed")
