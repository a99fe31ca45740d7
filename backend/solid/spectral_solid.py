"""Random phase noise as a solid: a periodic Gaussian voxel tile whose axis slices carry a photo's colour
cross-spectrum as closely as a solid can, numpy only.

Random phase noise (Galerne, Gousseau & Morel 2011, IEEE T-IP 20(1)) keeps a photo's Fourier amplitudes and draws
new phases: a stationary Gaussian texture with the photo's power spectrum and colour correlations.  Drawn as a 2D
image per cut it is closer to the held-out photos than any solid the project had drawn.  The texture-space model's
Gaussian rest (gaussian_rest.py) lifts it to 3D as a sum of 512 plane waves, whose cuts are far from it even on
photos without orientation (three rock photos: 88.5, 89.3, 96.4 against 55.1, 59.2, 69.2 by the held-out patch
distance).  This module lifts it on a grid of every frequency instead (the same photos: 66.4, 67.9 and 98.2, the
last 72.8 with another draw: a tile holds few of a photo's longest waves, and the distance's low-pass level
sees which; on the 35 structured held-out photos, docs/decisions/solid.md):

- **Power** (the projection-slice theorem).  A slice normal to an axis through a stationary Gaussian solid has
  the solid's 3D power spectrum P summed along that axis as its 2D spectrum.  On a periodic grid of n^3
  frequencies (n = ``period`` px), the slices normal to x, y and z are to carry the photo's power T (n x n:
  :func:`slice_spectrum`), upright on walls (rows along z) and on floors (rows along y):

      sum_x P(z, y, x) = T(z, y),   sum_y P(z, y, x) = T(z, x),   sum_z P(z, y, x) = T(y, x).

  On an oriented photo no P meets all three (``training.solid.photo_eval.axis_imbalance``).  The multiplicative
  EM update of emission tomography (Shepp & Vardi 1982, IEEE TMI 1(2), Eq. 2.13; Richardson 1972 and Lucy 1974
  for one projection), P <- P * (1/3) sum_a B_a(T_a / A_a P), with A_a the sum along axis a and B_a its
  back-projection, keeps P >= 0 and the total power and converges to the P whose projections are closest to the
  targets in Kullback-Leibler divergence (:func:`solid_power`).  Power on the three coordinate axes (a field
  constant over planes normal to one axis) moves whole slices' means, which the photo's power at zero frequency
  (none) forbids; those lines stay at zero (without that, a low-contrast brick photo's slices came out 0.7
  standard deviations off its mean colour).
- **An isotropic start**.  Three projections leave most of P free, and EM settles on the solution nearest its
  start.  From flat power it put a photo's strong low frequencies at 3D frequencies with one large component
  (the first update is T(z, y) + T(z, x) + T(y, x), large wherever any one of the three is): sheets along the
  axes that an axis cut shows at low frequency, but a cut at another angle shows at a middle one, as faint plaid.
  So :func:`solid_power` first runs EM over radial profiles (P a function of |k|: each shell of frequencies takes
  its power-weighted mean update), which finds the isotropic solid behind isotropic targets (a 1/f^3 solid: 11 %
  off where the flat start is 26 % off, tested), then the free EM fits what is not isotropic (cuts at random orientations come closer to the photos; see
  docs/decisions/solid.md).
- **Colour**.  Each 3D frequency takes the power-weighted mean of its three projections' colour cross-spectra
  (3 x 3, normalised to unit trace); its coefficient is sqrt(P) L w, L the Cholesky factor and w complex white
  noise per channel, so every slice keeps the photo's colour correlations scale by scale
  (:func:`colour_factors`).
- **Reading it anywhere**.  A slice through the tile passes between voxel centres.  Read from voxels at the
  photo's resolution, the finest scales lose power: on the three rock photos the finest pyramid level's distance
  was 85, 107 and 106 with cubic B-splines (random phase noise: 31, 32, 32), and worse trilinearly.  So the field
  is sampled OVERSAMPLE times finer than the photo's pixels (its spectrum zero-padded) and stored as cubic
  B-spline coefficients (the interpolation prefilter applied in the Fourier domain: divided by the B-spline's
  DFT, :func:`bspline_prefilter`; Unser 1999, IEEE Signal Processing Magazine 16(6)); :class:`SplineField` reads
  it with 4 x 4 x 4 taps.  The same three photos then score 34, 31 and 31 there.

- **Marginals**.  A Gaussian field's values have Gaussian marginals; a photo's seldom do (dark cracks between
  stones, bright specks in gravel skew them).  As Heeger and Bergen match histograms after every pass (SIGGRAPH
  1995, Sec. 3.3), the tile's values are mapped along the photo's principal colour axes, one monotone function
  per axis, from their own quantiles to the photo's (:class:`Marginals`, fitted by :func:`fit_marginals`): a
  pointwise map, so every cut through the solid gets it.  The photo's quantiles are scaled to the tile's own
  spread on each axis: the tile holds nothing longer than its period, so its variance is a little below the
  photo's, and matching the photo's whole variance instead amplifies the finer bands (docs/decisions/solid.md).
  Fitting takes about 0.3 s, the map 0.12 s per million points.

With ``harmonics`` (the request's ``periodic``, on by default) the photo's harmonic part, its isolated spectral
peaks (courses, head joints, plank seams: :mod:`backend.solid.harmonic`), is taken out of the photo before its
spectrum is read and added back by :class:`SplineField` upright on walls, as the neural texture adds it.

The tile repeats every ``period`` photo pixels (``period / PX_PER_UNIT`` units) along x, y and z; nothing longer
than the period is drawn.  What its cuts still lose to random phase noise is mostly the low-pass residue, and
there the period is not the cause: a 256 px period (8 times the memory) moved five rock and paving photos from
73.4, 92.9, 66.4, 86.6, 98.0 to 68.9, 81.4, 63.2, 89.0, 91.8 (random phase noise 61.9, 87.5, 55.1, 67.5, 69.2).
A Gaussian texture's Fourier amplitudes vary from draw to draw, random phase noise keeps the photo's: Gaussian
spot noise drawn as a 2D image per cut (``photo_eval.gaussian_noise``) is no closer than this solid (model card
"Marginals").  At the default period the tile is 256^3 x 3 float32 (200 MB), drawn in about 6 s on 2 cores
(peak 1.3 GB), and read at about 1.5 s per million points along a cut (about 6 s for points scattered at random
through the tile, whose reads then miss the cache).  Another seed draws other phases: another texture with the
same spectrum.  A Gaussian texture has no stones, courses or planks, and on an oriented photo the three cuts'
compromise shows as plaid (bridge wood's walls).

Conventions as :mod:`backend.solid.synthesis`: tiles indexed (z, y, x), z up; colours sRGB in [0, 1]; points
float64 (P, 3) in texture units at PX_PER_UNIT photo px per unit; fields float32 (P, 3).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import SettingError, check_points
from ..grid import Cancelled
from ..periodic import periodic_component
from .model import plane_image
from .pixels import one_colour
from .synthesis import PX_PER_UNIT

__all__ = ["PERIOD", "OVERSAMPLE", "ITERATIONS", "ISOTROPIC_ITERATIONS", "MIN_PHOTO", "MAX_READ", "QUANTILES",
           "check_photo", "slice_spectrum", "solid_power", "colour_factors", "photo_rest", "spectral_tile",
           "spectral_field", "fit_marginals", "Marginals", "SplineField", "SpectralTexture", "bspline_weights",
           "bspline_prefilter"]

PERIOD = 128       #: photo px per repeat of the tile along each axis (the design's grid of PERIOD^3 frequencies)
OVERSAMPLE = 2     #: voxels per photo px along each axis: PERIOD * OVERSAMPLE voxels a side
ITERATIONS = 100   #: EM iterations of solid_power (the projections' error stops falling after about 20)
ISOTROPIC_ITERATIONS = 30   #: solid_power's EM iterations over radial profiles first (its isotropic start)
MIN_PHOTO = 32     #: the shortest photo side read, px
#: the longest photo side read, px: a larger photo's spectrum is read from its central crop of this size (at its own
#: pixel scale; each of the 128^2 bins still averages 64 of its Fourier coefficients), which keeps a 4096^2 photo
#: to seconds and under 1.5 GB
MAX_READ = 1024
QUANTILES = 257    #: levels of the marginal tables (Marginals), from the least value to the greatest
MARGINAL_SAMPLES = 1 << 16   #: points of the tile read to measure its marginals
_SALT = 0x67617573  #: the draw's stream, beside the seed
_MARGINAL_SALT = 0x6d617267  #: the stream of the points the marginals are measured at


def slice_spectrum(photo: np.ndarray, n: int) -> np.ndarray:
    """The colour cross-spectrum a slice is to carry: float64 (n, n, 3, 3), real, indexed (row frequency, column
    frequency) of an n-periodic grid, the rows running up (the photo's rows run down, so its row frequencies are
    negated).  From the whole photo's periodic component (Moisan 2011: no false cross from its borders), mean
    removed, its Fourier coefficients F scaled so that the power sums to the variance, each summed into the n-grid
    bin nearest its frequency; zero at zero frequency.  A photo whose sides differ from n gives the same power in
    cycles per px."""
    u = np.asarray(photo, np.float64)[..., :3]
    H, W = u.shape[:2]
    F = np.fft.fft2(periodic_component((u - u.reshape(-1, 3).mean(0)).transpose(2, 0, 1))) / (H * W)  # (3, H, W)
    kr = np.round(-np.fft.fftfreq(H) * n).astype(np.int64) % n             # negated: rows run up
    kc = np.round(np.fft.fftfreq(W) * n).astype(np.int64) % n
    bins = (kr[:, None] * n + kc[None, :]).ravel()
    out = np.zeros((n, n, 3, 3))
    for a in range(3):          # the real cross-spectrum, summed into bins (a large photo: no (H, W, 3, 3) array)
        for b in range(a, 3):
            v = np.bincount(bins, (F[a].real * F[b].real + F[a].imag * F[b].imag).ravel(), n * n).reshape(n, n)
            out[..., a, b] = out[..., b, a] = v
    out[0, 0] = 0.0
    return out


def solid_power(T: np.ndarray, iterations: int = ITERATIONS, tick=None,
                isotropic_iterations: int = ISOTROPIC_ITERATIONS) -> np.ndarray:
    """The solid's power float64 (n, n, n) indexed (z, y, x) whose sums along x, y and z come closest to T
    (n, n) as (z, y), (z, x) and (y, x) (module doc: EM, the coordinate axes held at zero), from an isotropic
    start: ``isotropic_iterations`` EM steps over radial profiles first (each shell of 3D frequencies, |k| rounded
    to whole cycles per period, takes the power-weighted mean of its frequencies' updates, so P stays a function
    of |k|), then ``iterations`` free ones; ``isotropic_iterations`` 0 starts the free ones from flat power.
    ``tick()`` after each iteration; returning True stops with Cancelled."""
    T = np.asarray(T, np.float64)
    n = T.shape[0]
    P = np.full((n, n, n), T.sum() / n ** 3)
    if isotropic_iterations > 0:
        k = (np.arange(n) + n // 2) % n - n // 2
        shell = np.rint(np.sqrt(k[:, None, None] ** 2 + k[None, :, None] ** 2 + k[None, None, :] ** 2))
        shell = shell.astype(np.int64).ravel()
        shells = int(shell.max()) + 1
    for it in range(int(isotropic_iterations) + int(iterations)):
        r = (T / np.maximum(P.sum(2), 1e-300))[:, :, None] + (T / np.maximum(P.sum(1), 1e-300))[:, None, :]
        r += (T / np.maximum(P.sum(0), 1e-300))[None, :, :]
        r *= 1.0 / 3.0
        if it < isotropic_iterations:     # one factor per shell: the power-weighted mean of r over it
            pr = np.bincount(shell, (P * r).ravel(), shells)
            r = (pr / np.maximum(np.bincount(shell, P.ravel(), shells), 1e-300))[shell].reshape(P.shape)
        P *= r
        P[0, 0, :] = P[0, :, 0] = P[:, 0, 0] = 0.0
        if tick is not None and tick():
            raise Cancelled("cancelled")
    return P


def colour_factors(P: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Cholesky factors float32 (n, n, n, 3, 3) of each 3D frequency's colour (module doc): its three projections'
    cross-spectra S (n, n, 3, 3), each normalised to unit trace, weighted by the share of that projection's power
    the frequency carries, normalised to unit trace."""
    n = P.shape[0]
    tr = np.trace(S, axis1=2, axis2=3)
    Cn = (S / np.maximum(tr, 1e-300)[..., None, None]).astype(np.float32)
    L = np.empty((n, n, n, 3, 3), np.float32)
    shares = [P / np.maximum(P.sum(2), 1e-300)[:, :, None], P / np.maximum(P.sum(1), 1e-300)[:, None, :],
              P / np.maximum(P.sum(0), 1e-300)[None, :, :]]
    eye = 1e-6 * np.eye(3, dtype=np.float32)
    for z in range(n):        # a slab at a time: (n, n, 3, 3) each
        C = (shares[0][z][..., None, None] * Cn[z][:, None]).astype(np.float32)   # (y, x, 3, 3): of (z, y)
        C += shares[1][z][..., None, None] * Cn[z][None, :]                        # of (z, x)
        C += shares[2][z][..., None, None] * Cn                                    # of (y, x)
        C /= np.maximum(np.trace(C, axis1=2, axis2=3), 1e-30)[..., None, None]
        L[z] = np.linalg.cholesky(C + eye)
    return L


def check_photo(photo) -> np.ndarray:
    """``photo`` as float32 (H, W, 3 or 4); SettingError naming what is wrong with it for a spectral solid."""
    img = np.asarray(photo, np.float32)
    if img.ndim != 3 or img.shape[2] not in (3, 4):
        raise SettingError("photo", f"the photo must be an RGB image (H, W, 3), got shape {img.shape}")
    if not np.isfinite(img).all():
        raise SettingError("photo", "the photo has non-finite values")
    if min(img.shape[:2]) < MIN_PHOTO:
        raise SettingError("photo", f"the photo is {img.shape[1]} x {img.shape[0]} px; a spectral solid needs at "
                                    f"least {MIN_PHOTO} px a side")
    return img


def photo_rest(photo: np.ndarray, harmonics=None) -> np.ndarray:
    """What the solid draws of ``photo`` (H, W, 3+): float32 (h, w, 3) in [0, 1], its central crop of at most
    MAX_READ px a side less its harmonic part ``harmonics`` where given (at the crop's pixel centres, as
    :func:`backend.solid.harmonic.harmonic_field` places it on the photo)."""
    img = np.asarray(photo, np.float32)
    H, W = img.shape[:2]
    y0, x0 = max(0, (H - MAX_READ) // 2), max(0, (W - MAX_READ) // 2)
    crop = np.clip(img[y0:y0 + MAX_READ, x0:x0 + MAX_READ, :3], 0.0, 1.0)
    if harmonics is not None and len(harmonics):       # the rest: the part at the crop's pixel centres, taken out
        from .harmonic import harmonic_field

        h, w = crop.shape[:2]
        rr, cc = np.meshgrid(np.arange(h, dtype=np.float64) + y0, np.arange(w, dtype=np.float64) + x0, indexing="ij")
        pts = np.stack([(cc.ravel() + 0.5) / PX_PER_UNIT, -(rr.ravel() + 0.5) / PX_PER_UNIT], axis=1)
        crop = np.clip(crop - harmonic_field(pts, harmonics).reshape(h, w, 3), 0.0, 1.0)
    return crop


def spectral_tile(photo: np.ndarray, seed: int = 0, period: int | None = None, oversample: int = OVERSAMPLE,
                  iterations: int = ITERATIONS, progress=None, cancel=None, harmonics=None,
                  isotropic_iterations: int = ISOTROPIC_ITERATIONS) -> np.ndarray:
    """Cubic B-spline coefficients float32 (M, M, M, 3), M = period * oversample (period None: PERIOD, read when
    called), of a periodic Gaussian solid
    with zero mean whose axis slices carry ``photo``'s (H, W, 3) colour cross-spectrum (module doc; a photo larger
    than MAX_READ is read from its central crop); add the photo's mean colour to the field :class:`SplineField`
    reads.  ``harmonics``: the photo's harmonic part (:func:`backend.solid.harmonic.measure_harmonics` at PX_PER_UNIT),
    taken out of the photo first, so the solid draws only the rest (:class:`SplineField` adds the part back).
    ``progress(fraction)`` as the work goes; ``cancel()`` returning True stops with Cancelled.
    ``iterations``, ``isotropic_iterations``: :func:`solid_power`'s."""
    img = check_photo(photo)
    period = PERIOD if period is None else period
    if period < 8 or period % 2 or oversample < 1:
        raise SettingError("period", f"period must be an even number >= 8 and oversample >= 1, got {period}, "
                                     f"{oversample}")
    # the work's shares, as measured (128 px period, AMD EPYC): the power's iterations a quarter, the colours a
    # quarter, each channel's inverse FFT a sixth
    done = [0.0]

    def tick(share: float = 0.25 / max(iterations + isotropic_iterations, 1)) -> bool:
        done[0] += share
        if progress is not None:
            progress(min(1.0, done[0]))
        return cancel is not None and bool(cancel())

    n, M = int(period), int(period) * int(oversample)
    S = slice_spectrum(photo_rest(img, harmonics), n)
    P = solid_power(np.trace(S, axis1=2, axis2=3), iterations, tick, isotropic_iterations)
    L = colour_factors(P, S)
    amp = np.sqrt(P).astype(np.float32)
    rng = np.random.default_rng([int(seed), _SALT])
    w = (rng.standard_normal((n, n, n, 3), np.float32) + 1j * rng.standard_normal((n, n, n, 3), np.float32))
    w *= np.float32(np.sqrt(0.5))
    if tick(0.25):
        raise Cancelled("cancelled")
    ks = np.r_[0:n // 2, M - n // 2:M]               # the n-grid's frequencies on the M-grid
    b = bspline_prefilter(M)
    pre = 1.0 / (b[ks][:, None, None] * b[ks][None, :, None] * b[ks][None, None, :])   # B-spline prefilter
    # Re of the sum of complex coefficients of power P has half its variance: times sqrt(2); ifftn divides by M^3
    gain = np.sqrt(2.0) * M ** 3
    out = np.empty((M, M, M, 3), np.float32)
    for c in range(3):
        Y = np.zeros((M, M, M), np.complex128)
        Y[np.ix_(ks, ks, ks)] = amp * np.einsum("...j,...j->...", L[..., c, :], w) * pre
        out[..., c] = np.real(np.fft.ifftn(Y)) * gain
        del Y
        if tick(0.5 / 3.0):
            raise Cancelled("cancelled")
    return out


def bspline_prefilter(M: int) -> np.ndarray:
    """The cubic B-spline's DFT on an M-periodic grid, float64 (M,): (4 + 2 cos(2 pi k / M)) / 6 (its values 1/6,
    2/3, 1/6 at the taps -1, 0, 1).  Samples' DFT divided by it per axis gives the coefficients whose B-spline
    passes through the samples (Unser 1999)."""
    return (4.0 + 2.0 * np.cos(2.0 * np.pi * np.arange(M) / M)) / 6.0


def bspline_weights(t: np.ndarray) -> np.ndarray:
    """The cubic B-spline's weights float32 (P, 4) of the taps at offsets -1, 0, 1, 2 for fractions t (P,) in
    [0, 1)."""
    t = np.asarray(t, np.float32)
    t2, t3 = t * t, t * t * t
    return np.stack([(1.0 - t) ** 3, 3.0 * t3 - 6.0 * t2 + 4.0, -3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0, t3], -1) / 6.0


@dataclasses.dataclass(frozen=True)
class Marginals:
    """Monotone maps of a zero-mean colour field's values onto a photo's marginals (module doc): along each column
    of ``basis`` (float32 (3, 3), the photo's principal colour axes), values at the quantiles ``source`` (float32
    (QUANTILES, 3), non-decreasing: the field's) go to ``target`` (float32 (QUANTILES, 3): the photo's, scaled to
    the field's spread), piecewise linearly between them; beyond the ends they stay at the ends."""

    basis: np.ndarray
    source: np.ndarray
    target: np.ndarray

    def apply(self, values: np.ndarray) -> np.ndarray:
        """values float (P, 3), zero-mean field values -> float32 (P, 3) mapped."""
        y = np.asarray(values, np.float32) @ self.basis
        for k in range(3):
            y[:, k] = np.interp(y[:, k], self.source[:, k], self.target[:, k])
        return y @ self.basis.T


def fit_marginals(rest: np.ndarray, field: "SplineField", seed: int = 0) -> Marginals:
    """The maps taking ``field``'s values (its B-spline alone: no mean, part or marginals) onto the marginals of
    ``rest`` (float (h, w, 3) or (N, 3): the photo's colours the field draws, :func:`photo_rest`) along the rest's
    principal colour axes, each scaled to the field's spread on that axis (module doc); the field read at
    MARGINAL_SAMPLES uniform points of its period (their stream from ``seed``).  An axis on which the photo or the
    field barely varies (a grey photo's chroma) keeps its values."""
    r = np.asarray(rest, np.float64).reshape(-1, 3)
    r = r - r.mean(0)
    _, U = np.linalg.eigh(np.cov(r.T) + 1e-12 * np.eye(3))
    rng = np.random.default_rng([int(seed), _MARGINAL_SALT])
    v = field.spline(rng.uniform(0.0, field.period, (MARGINAL_SAMPLES, 3))).astype(np.float64) @ U
    yp = r @ U
    levels = np.linspace(0.0, 1.0, QUANTILES)
    src, dst = np.quantile(v, levels, axis=0), np.quantile(yp, levels, axis=0)
    sf, sp = v.std(0), yp.std(0)
    for k in range(3):
        if sp[k] > 1e-3 * sp.max() and sp[k] > 1e-6 and sf[k] > 1e-3 * sf.max() and sf[k] > 1e-6:
            dst[:, k] *= sf[k] / sp[k]
        else:   # keep: the identity over any value a colour field takes
            src[:, k] = dst[:, k] = np.linspace(-2.0, 2.0, QUANTILES)
    return Marginals(U.astype(np.float32), src.astype(np.float32), dst.astype(np.float32))


def spectral_field(photo: np.ndarray, seed: int = 0, harmonics=None, progress=None, cancel=None,
                   marginals: bool = True, isotropic_iterations: int = ISOTROPIC_ITERATIONS) -> "SplineField":
    """Method "spectral"'s texture of ``photo`` (H, W, 3): :func:`spectral_tile` drawn with ``seed``, read as a
    :class:`SplineField` around the photo's mean colour, with the photo's harmonic part ``harmonics`` added back,
    and (``marginals``) its values mapped onto the marginals of the photo's rest (:func:`fit_marginals`).
    ``progress``, ``cancel`` and ``isotropic_iterations`` as :func:`spectral_tile`'s."""
    img = check_photo(photo)
    colours = np.clip(img[..., :3], 0.0, 1.0).reshape(-1, 3)
    if one_colour(colours):      # no power to lift: the solid is the colour
        if progress is not None:
            progress(1.0)
        return SplineField(np.zeros((4, 4, 4, 3), np.float32), colours[0], seed=seed)
    rest = photo_rest(img, harmonics)       # once: the tile's spectrum and the marginals both read it
    coeffs = spectral_tile(rest, seed, progress=progress, cancel=cancel,     # the rest has no part left to take out
                           isotropic_iterations=isotropic_iterations)
    mean = colours.astype(np.float64).mean(0)
    field = SplineField(coeffs, mean, harmonics=harmonics, seed=seed)
    if not marginals:
        return field
    return SplineField(coeffs, mean, harmonics=harmonics, seed=seed, marginals=fit_marginals(rest, field, seed))


class SplineField:
    """A periodic solid as a colour field over texture space: ``mean`` (3,) plus the cubic B-spline of
    ``coeffs`` (M, M, M, 3) indexed (z, y, x), voxel centres at (i + 1/2) / voxels_per_unit, ``voxels_per_unit``
    = PX_PER_UNIT * oversample (the photo's scale), plus the photo's harmonic part ``harmonics`` where given (upright
    on walls, moved by ``seed``: :func:`backend.solid.harmonic.harmonic_field`, as the neural texture draws it),
    the B-spline's values mapped by ``marginals`` (:class:`Marginals`) where given.  ``evaluate(points)`` reads it
    anywhere with wrap-around, clipped to [0, 1]."""

    dim = 3

    def __init__(self, coeffs: np.ndarray, mean, oversample: int = OVERSAMPLE, px_per_unit: float = PX_PER_UNIT,
                 harmonics=None, seed: int = 0, marginals: Marginals | None = None):
        c = np.asarray(coeffs, np.float32)
        if c.ndim != 4 or c.shape[-1] != 3 or len(set(c.shape[:3])) != 1:
            raise SettingError("coeffs", f"coefficients are (M, M, M, 3), got shape {c.shape}")
        self.coeffs, self.mean = c, np.asarray(mean, np.float32).reshape(3)
        self.harmonics = harmonics if harmonics is not None and len(harmonics) else None
        self.seed = int(seed)
        self.marginals = marginals
        self.px_per_unit = float(px_per_unit)
        self.voxels_per_unit = float(px_per_unit) * int(oversample)

    @property
    def period(self) -> float:
        """Texture units per repeat along each axis."""
        return self.coeffs.shape[0] / self.voxels_per_unit

    def evaluate(self, points: np.ndarray, chunk: int = 1 << 16, progress=None, cancel=None) -> np.ndarray:
        """points float (P, 2 or 3) in texture units (x, y[, z]; 2D points lie on z = 0) -> float32 (P, 3), in chunks
        of ``chunk`` points: ``progress(fraction)`` after each, ``cancel()`` returning True raises Cancelled."""
        pts = self._points(points)
        out = np.empty((pts.shape[0], 3), np.float32)
        for a in range(0, pts.shape[0], chunk):
            if cancel is not None and cancel():
                raise Cancelled("cancelled")
            acc = self.spline(pts[a:a + chunk])
            out[a:a + chunk] = acc if self.marginals is None else self.marginals.apply(acc)
            if progress is not None:
                progress(min(1.0, (a + chunk) / pts.shape[0]))
        if self.harmonics is not None:
            from .harmonic import harmonic_field

            out += harmonic_field(pts, self.harmonics, self.seed)
        return np.clip(out + self.mean, 0.0, 1.0)

    @staticmethod
    def _points(points) -> np.ndarray:
        """points float (P, 2 or 3) -> float64 (P, 3) (2D points on z = 0); SettingError for another shape."""
        pts = check_points(points, (2, 3), np.float64)
        if pts.shape[1] == 2:
            pts = np.concatenate([pts, np.zeros((pts.shape[0], 1))], axis=1)
        return pts

    def spline(self, points) -> np.ndarray:
        """The B-spline of the coefficients alone (zero mean: no mean colour, harmonic part, marginals or
        clipping) at points float (P, 2 or 3) in texture units -> float32 (P, 3); 4 x 4 x 4 taps, wrapping."""
        pts = self._points(points)
        c, M = self.coeffs, self.coeffs.shape[0]
        u = pts[:, ::-1] * self.voxels_per_unit - 0.5       # (z, y, x) in voxels
        i0 = np.floor(u)
        wz, wy, wx = (bspline_weights((u[:, k] - i0[:, k]).astype(np.float32)) for k in range(3))
        i0 = i0.astype(np.int64) - 1
        iz, iy, ix = ((i0[:, k][:, None] + np.arange(4)) % M for k in range(3))      # (p, 4) each
        acc = np.zeros((u.shape[0], 3), np.float32)
        for p in range(4):
            for q in range(4):
                wpq = wz[:, p] * wy[:, q]
                for r in range(4):
                    acc += (wpq * wx[:, r])[:, None] * c[iz[:, p], iy[:, q], ix[:, r]]
        return acc

    def image(self, size: int, scale: float = 1.0) -> np.ndarray:
        """A (size, size, 3) float32 image of the plane z = 0 (x right, y up; row 0 at the top) at ``scale``
        output pixels per photo pixel."""
        return plane_image(lambda pts, rows: self.evaluate(pts), size, self.px_per_unit * scale, None)


class SpectralTexture:
    """Method "spectral" seen as a texture model (what the Blender panel's preview and surface bakes call of
    :class:`~backend.solid.model.SolidTextureModel`): its "code" is the drawn :class:`SplineField` (the request's
    ``spectral_field()``), the seed is already in it.  ``request``: the checked
    :class:`~backend.solid.request.SolidRequest` it draws (a volume bake's key reads it)."""

    dim = 3
    name = "spectral"
    px_per_unit = PX_PER_UNIT

    def __init__(self, request):
        self.request = request

    def evaluate(self, points, code: SplineField, seed: int = 0, chunk: int = 1 << 16, progress=None,
                 cancel=None) -> np.ndarray:
        """points float (N, 2 or 3) in texture units -> sRGB float32 (N, 3): :meth:`SplineField.evaluate`, in
        chunks with ``progress(fraction)`` after each and ``cancel()`` returning True raising Cancelled."""
        return code.evaluate(points, chunk, progress, cancel)

    def image(self, size: int, code: SplineField, seed: int = 0, scale: float = 1.0, offset=(0.0, 0.0, 0.0),
              axis: str = "y", **kw) -> np.ndarray:
        """A (size, size, 3) image of the plane through ``offset`` normal to ``axis`` (as SolidTextureModel.image:
        "y", the default, is the front view, x right and z up)."""
        progress = kw.pop("progress", None)
        return plane_image(lambda pts, rows: self.evaluate(pts, code, seed, **kw), size, self.px_per_unit * scale,
                           axis, offset, progress)
