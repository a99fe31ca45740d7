"""The harmonic part of a photo's texture, measured when the texture-space model encodes the photo.

A homogeneous texture splits into a harmonic part, a sum of plane waves at isolated spectral peaks, and an
indeterministic rest (the Wold decomposition of homogeneous random fields; Francos, Meiri & Porat 1993, IEEE
T-IP 2(1); Liu & Picard 1996, IEEE T-PAMI 18(7)).  Brick courses, plank seams, woven rows and drilled grids are
harmonic; the texture-space model's decoder, which reads value-noise octaves, draws only the rest.  So an encoded
photo also keeps its harmonic part, measured from its pixels (nothing is learned), and the texture becomes

    rgb(x) = clip(mu + k L d(x) + h(x)),   h(x) = sum_j Re(A_j exp(2 pi i f_j . q(x))),   k = sqrt(1 - s)

with the decoder's whitened output d, the photo's mean colour mu and colour Cholesky factor L
(``model.colour_stats``), A_j in C^3 the photo's colour amplitude and phase at peak j, f_j its frequency in
cycles per texture unit, and s the share of the photo's colour variance the peaks carry (k keeps the total
variance the photo's).

Peaks: local maxima of the photo's colour power spectrum (the sum of its three channels' powers, ``DETECT``) on
its periodic component (Moisan 2011, so the jump at the border adds no cross of false peaks), one of each
conjugate pair, at least ``MIN_CYCLES`` cycles per photo, with at least ``FLOOR`` of the photo's power, and at
least ``PROMINENCE`` times the mean power around
them (the ring between the 3 x 3 core and the (2 ``WINDOW`` + 1)^2 square).  Only a peak that stands alone
counts: a period repeats, so its power collects in one bin; an aperiodic line or edge spreads over a ridge, and
the spectrum of grass, sand or rock is smooth.  JPEG's 8 x 8 blocks draw peaks of their own, at whole multiples
of 1/8 cycle per pixel; there a peak counts only as a harmonic of a peak elsewhere.  The price: a pattern whose
own period divides 8 px along both of the photo's axes (stripes exactly 8 or 4 px apart, square to the photo) is
taken for compression and left to the decoder (unless its stripes run straight across the whole frame: the
lines reading below takes them); a period of 16 px or one a little off 8 keeps its peaks (tested).
At most ``COUNT`` peaks, the strongest first (the cap binds on brick, metal plates and tiles; see
docs/decisions/solid.md); 256 waves cost about 0.7 s per million points (the decoder: 1.1 s).  Main lobes: a period that is not a whole fraction of the photo (rows 24.3 px apart in a 256 px photo)
falls between bins and spreads its power over the bins around the nearest one (a sinc: at half a bin off, its
neighbour holds as much as it), so each peak brings the bins within ``LOBE`` of it that hold at least
1 / ``LOBE_DEPTH`` of its power (and ``FLOOR`` of the photo's), each bin once.  A period that is a whole fraction
keeps its one bin, and the weak bins around a strong peak (noise, or the periodic component's correction near
the axes) stay out (tested).  Chosen on the training split ("lobes" in the same JSON).  A lobe's bins add up to
the photo inside its frame but beat beyond it, so where the peaks lie on a lattice off the grid (a photograph
of bricks, tiles or a weave, whose periods do not divide its frame) the part is read as that lattice's motif
instead, one wave at each lattice point at its own frequency, wherever it holds at least the share of the photo's
variance the bins hold (:mod:`backend.solid.motif`; ``HarmonicConfig(motif=False)`` reads the bins alone).  A tileable
photo's lattice lies on the grid, and its part is read from the bins as before.  A tile whose pattern repeats
only two to four times (a texture library's bricks: two courses of two bricks in 256 x 166 px) puts its peaks
one to three bins apart, each inside the others' rings, and the peak test finds the courses at most; there the
part is read at the lattice of the tile's periods, found from its autocorrelation, each bin measured against the
bins around it that are not lattice points (:mod:`backend.solid.periods`; ``HarmonicConfig(periods=False)``),
wherever that holds ``FEW_MARGIN`` more of the photo's variance than the peaks or the motif.  Lines straight
across the photo that the part leaves (a single floor tile's grout, plank seams, slab joints: rows and columns that
stand off their neighbours all along) are added where they hold ``FEW_MARGIN`` of its variance (``lines=False``).  The price: a photograph with one straight line across its whole frame (a cable, a crack square
to the frame) gets it once per frame's width on a solid's walls; ``--no-periodic`` leaves the whole part out.
Every constant was chosen on the training split, and each reading's worth is measured by leaving it out
(docs/decisions/solid.md).  Peaks are sought in the colour spectrum, not luminance: a motif drawn in colours of
about one luminance (a carpet's red diamonds on olive) leaves almost nothing in the luminance spectrum.

Placement: on 2D points (2D models) q = p, the photo's plane (row 0 at the top as ``model.plane_points``).  On 3D
points the photo stands upright and is extruded along the horizontal diagonal (1, -1, 0): q(x, y, z) = (x + y, z),
so every vertical plane normal to x or to y (a wall seen from the front or from the side, and the 2D image of a 3D
model, ``model.image``'s front view) shows the harmonic part unchanged, courses level and planks upright at the
photo's pitch, and a horizontal cut shows it in profile (a brick wall's cut takes one course's colour, as a real
one does; plank seams become lines).  A plane wave keeps its frequency on every plane whose section it is, so
the texture stays one solid.  This is the placement for scenes with z up (a building's walls face x or y in
object coordinates), not the one the pooled slice evaluation prefers (floors exact, which would put diagonal
stripes on every wall facing x; docs/decisions/solid.md).

Shapes: photos float (H, W, 3) sRGB in [0, 1]; points float (N, 2) or (N, 3) in texture units; fields float32
(N, 3).  Phases are computed in float64 and reduced modulo one cycle before the float32 cosines (at |x| ~ 64 units
and f ~ 60 cycles per unit the argument reaches ~2.4e4 rad, where float32 would lose ~2e-3 rad).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..periodic import periodic_component
from .motif import box_sums, motif_waves, on_grid
from .periods import frame_lines, lattice_bins, period_lattice
from .pixels import at_most

__all__ = ["Harmonics", "HarmonicConfig", "PhotoSpectrum", "WaveSet", "photo_spectrum", "choose_waves", "READINGS",
           "read_peaks", "read_motif", "read_few_repeats", "read_lines", "photo_harmonics", "measure_harmonics",
           "HARMONIC_SIDE", "harmonic_field", "wave_sum", "remove_harmonics", "seed_shift",
           "mix_harmonics", "mix_waves", "to_json", "from_json", "read_waves", "COUNT", "PROMINENCE", "WINDOW",
           "MIN_CYCLES", "LOBE", "LOBE_DEPTH", "FEW_GRID", "FEW_MARGIN", "FEW_MIN_CYCLES"]

COUNT = 256         #: at most this many peaks
PROMINENCE = 16.0   #: a peak's power over the mean power of the bins around it
WINDOW = 3          #: ... in the (2 WINDOW + 1)^2 square, less the 3 x 3 core
MIN_CYCLES = 2      #: no peak below this many cycles per photo (shading and vignetting, not texture)
FLOOR = 1e-4        #: nor one with less than this share of the photo's power (rounding, not texture)
LOBE = 1            #: each peak brings the bins within this many of it (its main lobe) ...
LOBE_DEPTH = 16.0   #: ... that hold at least 1 / LOBE_DEPTH of its power
FEW_GRID = 0.2      #: a lattice of periods within this many bins of whole frequencies is a tile's (periods.py)
FEW_MARGIN = 0.05   #: ... read there where it holds this much more of the variance than the peaks or the motif
FEW_MIN_CYCLES = 1  #: its points count from one cycle per photo (the lattice, not a lone peak, says they repeat)
HARMONIC_SIDE = 1024  #: photos are measured at most this many pixels wide (measure_harmonics)
DETECTS = ("luminance", "colour")
DETECT = "colour"     #: peaks are sought in this power spectrum (module doc)


@dataclass(frozen=True)
class Harmonics:
    """A photo's harmonic part: ``freq`` float64 (K, 2) cycles per texture unit in the photo's plane (u, v),
    ``amp`` complex128 (K, 3) colour amplitudes with the photo's phases, ``share`` in [0, 1) the share of the
    photo's colour variance they carry."""
    freq: np.ndarray
    amp: np.ndarray
    share: float

    @property
    def keep(self) -> float:
        """The factor k = sqrt(1 - share) on the decoder's part (module doc)."""
        return float(np.sqrt(max(0.0, 1.0 - self.share)))

    def __len__(self) -> int:
        return int(self.freq.shape[0])

    def values(self) -> np.ndarray:
        """Every number of the part, float64 (5 K,): frequencies, then the real and imaginary amplitudes (what bake
        keys digest)."""
        return np.concatenate([self.freq.ravel(), self.amp.real.ravel(), self.amp.imag.ravel()])


def _without_jpeg_grid(idx: np.ndarray, kx: np.ndarray, ky: np.ndarray, H: int, W: int) -> np.ndarray:
    """``idx`` less the peaks on JPEG's block lattice (whole multiples of 1/8 cycle per pixel on both axes: the
    edges of its 8 x 8 blocks) that are not harmonics of a peak off it: a brick course of 16 px keeps its second
    harmonic at 1/8 cycle per pixel, a grid that only the compression drew is dropped."""
    if H % 8 or W % 8:
        return idx
    fx, fy = kx[idx].astype(np.int64), ky[idx].astype(np.int64)
    grid = (fx % (W // 8) == 0) & (fy % (H // 8) == 0)
    if not grid.any():
        return idx
    gx, gy = fx[~grid], fy[~grid]
    keep = ~grid
    for i in np.flatnonzero(grid):
        collinear = fx[i] * gy - fy[i] * gx == 0
        dot, norm = fx[i] * gx + fy[i] * gy, gx * gx + gy * gy
        keep[i] = bool(np.any(collinear & (np.abs(dot) >= 2 * norm) & (dot % np.maximum(norm, 1) == 0)))
    return idx[keep]


def _main_lobes(idx: np.ndarray, lobe: int, keep: np.ndarray, P: np.ndarray, H: int, W: int) -> np.ndarray:
    """The flat bins within ``lobe`` of each peak in ``idx`` that hold at least 1 / LOBE_DEPTH of its power P
    (flat, H * W) (peaks in their order, each bin once, as the representative of its conjugate pair that
    ``keep`` (H * W,) marks eligible, which also holds the bins' other tests)."""
    iy, ix = np.divmod(idx, W)
    bins = np.stack([((iy + dy) % H) * W + (ix + dx) % W for dy in range(-lobe, lobe + 1)
                     for dx in range(-lobe, lobe + 1)], axis=1)
    bins = bins[P[bins] * LOBE_DEPTH >= P[idx][:, None]]           # the peak's own bin always passes
    by, bx = np.divmod(bins, W)
    bins = np.where(keep[bins], bins, ((-by) % H) * W + (-bx) % W)     # the other half's bin: its conjugate's
    bins = bins[keep[bins]]
    _, first = np.unique(bins, return_index=True)
    return bins[np.sort(first)]


@dataclass(frozen=True)
class HarmonicConfig:
    """How a photo's harmonic part is read (module doc): the peak test's settings, and a switch per reading that
    may replace or extend the peaks' part (each left out in turn by the ablation, docs/decisions/solid.md)."""
    count: int = COUNT              #: at most this many waves from the peaks
    prominence: float = PROMINENCE  #: a peak's power over the ring's mean
    window: int = WINDOW            #: the ring's half side, bins
    min_cycles: int = MIN_CYCLES    #: no peak below this many cycles per photo
    lobe: int = LOBE                #: each peak brings its main lobe's bins within this many (0: its own alone)
    detect: str = DETECT            #: the power spectrum peaks are sought in: one of DETECTS
    motif: bool = True              #: peaks on a lattice off the grid: the lattice's motif (motif.py)
    periods: bool = True            #: a tile's few repeats: the lattice of its periods (periods.py)
    lines: bool = True              #: lines straight across the frame that the part leaves (periods.py)

    def __post_init__(self):
        if self.detect not in DETECTS:
            raise ValueError(f"detect must be one of {DETECTS}, not {self.detect!r}")


@dataclass(frozen=True)
class PhotoSpectrum:
    """What every reading of the harmonic part reads, measured once: ``u`` float64 (3, H, W) the photo less its mean
    colour; ``F`` complex128 (3, H, W) the DFT of its periodic component (Moisan 2011); ``P`` float64 (H, W) the
    power the peaks are sought in (``detect``); ``kx``, ``ky`` (H, W) each bin's cycles per photo along columns and
    rows; ``strong`` bool (H, W) the bins a wave may take (one of each conjugate pair, at least ``min_cycles``,
    above FLOOR); ``total`` the variance's power (F's less the mean's); ``peaks`` int (K,) the flat bins that pass
    the peak test, strongest first, less JPEG's grid, at most ``count``."""
    u: np.ndarray
    F: np.ndarray
    P: np.ndarray
    kx: np.ndarray
    ky: np.ndarray
    strong: np.ndarray
    total: float
    peaks: np.ndarray

    @property
    def shape(self) -> tuple:
        return self.P.shape


@dataclass(frozen=True)
class WaveSet:
    """Waves in the photo's own frame, what every reading returns: ``fx``, ``fy`` float64 (K,) cycles per photo
    along its columns and rows, ``A`` complex128 (K, 3) amplitudes (the part is sum_j Re(A_j exp(2 pi i (fx_j c / W
    + fy_j r / H))) at pixel (r, c)), ``share`` the share of the photo's variance they carry."""
    fx: np.ndarray
    fy: np.ndarray
    A: np.ndarray
    share: float

    def plus(self, other: "WaveSet") -> "WaveSet":
        return WaveSet(np.concatenate([self.fx, other.fx]), np.concatenate([self.fy, other.fy]),
                       np.concatenate([self.A, other.A]), self.share + other.share)


def photo_spectrum(img: np.ndarray, cfg: HarmonicConfig = HarmonicConfig()) -> PhotoSpectrum:
    """Stage 1 of the harmonic part: the photo's spectrum and the peak test (module doc) on img float (H, W, 3)."""
    a = np.asarray(img, np.float64)[..., :3]
    H, W, _ = a.shape
    F = np.fft.fft2(periodic_component((a - a.mean((0, 1))).transpose(2, 0, 1)))      # (3, H, W)
    P = np.abs(F.mean(0)) ** 2 if cfg.detect == "luminance" else (np.abs(F) ** 2).sum(0)    # (H, W) power
    ky = np.broadcast_to(np.fft.fftfreq(H, d=1.0 / H)[:, None], (H, W))                # cycles per photo
    kx = np.broadcast_to(np.fft.fftfreq(W, d=1.0 / W)[None, :], (H, W))
    peak = np.ones((H, W), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                peak &= P > np.roll(P, (dy, dx), axis=(0, 1))
    ring, n = box_sums(P, cfg.window) - box_sums(P, 1), (2 * cfg.window + 1) ** 2 - 9
    half = (ky > 0) | ((ky == 0) & (kx > 0))                       # one of each conjugate pair
    far = np.hypot(kx / W, ky / H) * min(H, W) >= cfg.min_cycles
    strong = half & far & (P >= FLOOR * max(P.sum() - P[0, 0], 1e-300))
    idx = np.flatnonzero((peak & strong & (P >= cfg.prominence * ring / max(n, 1))).ravel())
    idx = idx[np.argsort(-P.ravel()[idx], kind="stable")]
    idx = _without_jpeg_grid(idx, kx.ravel(), ky.ravel(), H, W)[:cfg.count]
    total = float((np.abs(F) ** 2).sum() - (np.abs(F[:, 0, 0]) ** 2).sum())
    return PhotoSpectrum((a - a.mean((0, 1))).transpose(2, 0, 1), F, P, kx, ky, strong, total, idx)


def _bins(s: PhotoSpectrum, flat: np.ndarray) -> WaveSet:
    """The waves at the flat DFT bins ``flat``, with the share of the variance they hold."""
    H, W = s.shape
    Fc = s.F.reshape(3, -1)[:, flat].T                                                 # (K, 3)
    share = float(2.0 * (np.abs(Fc) ** 2).sum() / s.total) if s.total > 0 else 0.0
    return WaveSet(s.kx.ravel()[flat], s.ky.ravel()[flat], (2.0 / (H * W)) * Fc, share)


# -- the readings: reading(spectrum, config) -> WaveSet, or None where it finds nothing ---------------------------
def read_peaks(s: PhotoSpectrum, cfg: HarmonicConfig) -> WaveSet:
    """The peaks standing alone, each with the bins of its main lobe (within ``lobe`` bins)."""
    H, W = s.shape
    idx = _main_lobes(s.peaks, cfg.lobe, s.strong.ravel(), s.P.ravel(), H, W) if cfg.lobe else s.peaks
    return _bins(s, idx)


def read_motif(s: PhotoSpectrum, cfg: HarmonicConfig) -> WaveSet | None:
    """The peaks' lattice off the DFT's grid read as its motif, one wave at each lattice point (motif.py)."""
    H, W = s.shape
    found = motif_waves(s.u, s.peaks, s.P.ravel()[s.peaks], cfg.min_cycles, cfg.count, FLOOR)
    if found is None:
        return None
    share = float(2.0 * (np.abs(found.dtft) ** 2).sum() * (H * W) ** 2 / s.total)
    return WaveSet(found.fx, found.fy, 2.0 * found.dtft, share)


def read_few_repeats(s: PhotoSpectrum, cfg: HarmonicConfig) -> WaveSet | None:
    """A tileable photo's pattern that repeats too few times for the peak test (periods.py): the bins of its lattice
    of periods, where that lattice lies on the grid with a reciprocal vector shorter than ``window`` + 1 bins."""
    B, _ = period_lattice(s.u)
    if B is None or not on_grid(B, FEW_GRID) or np.linalg.norm(B, axis=1).min() >= cfg.window + 1:
        return None
    idx = lattice_bins(s.P, np.round(B), FEW_MIN_CYCLES)
    idx = idx[s.P.ravel()[idx] >= FLOOR * s.total][:cfg.count]
    return _bins(s, idx) if len(idx) else None


def read_lines(s: PhotoSpectrum, cfg: HarmonicConfig, part: WaveSet) -> WaveSet | None:
    """Lines straight across the photo that ``part`` leaves (periods.py), where they hold FEW_MARGIN of it."""
    H, W = s.shape
    lx, ly, LA = frame_lines(s.u - _grid_field(part.fx, part.fy, part.A, H, W))
    keep = (np.abs(LA) ** 2).sum(1) / 2.0 >= 2.0 * FLOOR * s.total / (H * W) ** 2     # as P >= FLOOR total
    lx, ly, LA = lx[keep][:cfg.count // 2], ly[keep][:cfg.count // 2], LA[keep][:cfg.count // 2]
    share = float((np.abs(LA) ** 2).sum() / 2.0 * (H * W) ** 2 / s.total)
    return WaveSet(lx, ly, LA, share) if share >= FEW_MARGIN else None


#: the readings that may replace the peaks' part, in turn: (switch in HarmonicConfig, reading, the margin of the
#: variance's share by which it must hold more than the part so far)
READINGS = (("motif", read_motif, 0.0), ("periods", read_few_repeats, FEW_MARGIN))


def choose_waves(s: PhotoSpectrum, cfg: HarmonicConfig = HarmonicConfig()) -> WaveSet:
    """Stage 2, the chooser: the peaks' part, replaced by each of READINGS that is switched on where it holds its
    margin more of the variance, then the lines it leaves added (``lines``)."""
    part = read_peaks(s, cfg)
    if s.total <= 0:
        return part
    for switch, read, margin in READINGS:
        other = read(s, cfg) if getattr(cfg, switch) else None
        if other is not None and other.share >= part.share + margin:
            part = other
    lines = read_lines(s, cfg, part) if cfg.lines else None
    return part if lines is None else part.plus(lines)


def _grid_field(fx: np.ndarray, fy: np.ndarray, A: np.ndarray, H: int, W: int) -> np.ndarray:
    """sum_j Re(A_j exp(2 pi i (fx_j c / W + fy_j r / H))) at every pixel (r, c) for A (K, C): float64 (C, H, W)
    (separable; zeros for K = 0)."""
    ex = np.exp(2j * np.pi * np.outer(fx, np.arange(W)) / W)                   # (K, W)
    ey = np.exp(2j * np.pi * np.outer(fy, np.arange(H)) / H)                   # (K, H)
    return np.stack([np.real(ey.T @ (A[:, c, None] * ex)) for c in range(A.shape[1])])


def photo_harmonics(img: np.ndarray, px_per_unit: float, config: HarmonicConfig = HarmonicConfig()) -> Harmonics:
    """The harmonic part of a photo (H, W, 3) shown at ``px_per_unit`` pixels per texture unit (module doc): its
    spectrum (:func:`photo_spectrum`), the chooser's waves among the readings (:func:`choose_waves`), placed in
    texture units; no waves (K = 0, share 0) for a photo without a period."""
    s = photo_spectrum(img, config)
    H, W = s.shape
    w = choose_waves(s, config)
    # pixel (r, c) sits at p = ((c + 1/2) / u, -(r + 1/2) / u): exp(2 pi i (fx c / W + fy r / H)) =
    # exp(i (2 pi f . p - pi (fx / W + fy / H))) with f = u (fx / W, -fy / H); both halves of a pair: 2 Re(.)
    amp = w.A * np.exp(-1j * np.pi * (w.fx / W + w.fy / H))[:, None]
    freq = np.stack([px_per_unit * w.fx / W, -px_per_unit * w.fy / H], axis=1)
    return Harmonics(freq.astype(np.float64), amp.astype(np.complex128), min(w.share, 0.999))


def measure_harmonics(image: np.ndarray, px_per_unit: float,
                      config: HarmonicConfig = HarmonicConfig()) -> Harmonics:
    """A photo's harmonic part (:func:`photo_harmonics`) at ``px_per_unit`` pixels per texture unit: image float
    (H, W, 3) or (H, W) in [0, 1]; a photo over HARMONIC_SIDE px is measured at that size, its waves kept at their
    frequency in texture units.  The one measurement the runtime, the export and the harmonics tool share."""
    return photo_harmonics(*at_most(image, px_per_unit, HARMONIC_SIDE), config)


def remove_harmonics(img: np.ndarray, h: Harmonics, px_per_unit: float) -> np.ndarray:
    """The photo's indeterministic rest: img float (H, W, 3) less its harmonic part h (as :func:`photo_harmonics`
    measured it from this photo at ``px_per_unit``) at its pixel centres p = ((c + 1/2) / u, -(r + 1/2) / u),
    clipped to [0, 1]: float32 (H, W, 3).  A model trained on photos' rests (``harmonic_rest`` in its solid.json)
    encodes this, and its decoder draws only what the part does not (module doc)."""
    a = np.asarray(img, np.float32)[..., :3]
    if len(h) == 0:
        return np.clip(a, 0.0, 1.0)
    H, W, _ = a.shape
    u = float(px_per_unit)
    rr, cc = np.meshgrid(np.arange(H, dtype=np.float64), np.arange(W, dtype=np.float64), indexing="ij")
    pts = np.stack([(cc.ravel() + 0.5) / u, -(rr.ravel() + 0.5) / u], axis=1)
    return np.clip(a - harmonic_field(pts, h).reshape(H, W, 3), 0.0, 1.0)


def seed_shift(seed: int) -> np.ndarray:
    """Where a seed moves the harmonic part in the photo's plane: float64 (2,) texture units, (0, 0) for seed 0
    (the photo's own placement), else uniform in [0, 64)^2 from the seed.  Another seed is another texture of the
    same kind: the courses elsewhere, not the same courses under other noise."""
    if int(seed) == 0:
        return np.zeros(2)
    return np.random.default_rng([int(seed), 0x6861726D]).uniform(0.0, 64.0, 2)


FIELD_BLOCK = 1 << 20   #: harmonic_field works on at most this many point-wave pairs at a time (about 20 MB)


def wave_sum(q: np.ndarray, freq: np.ndarray, amp: np.ndarray) -> np.ndarray:
    """sum_j Re(amp_j exp(2 pi i freq_j . q)) at points q float64 (N, D), freq float64 (K, D) cycles per unit, amp
    complex (K, 3): float32 (N, 3).  Points go in blocks of FIELD_BLOCK / K, so memory stays flat whatever the
    number of waves; phases are reduced modulo one cycle in float64 (module doc), the trigonometry is float32 and
    the sum over the waves float64: a float32 sum of 512 waves is off by up to 5e-5, and BLAS's float32 kernels
    round it differently for blocks of different sizes (the field would depend on how a bake splits its points;
    seen on an AMD EPYC).  The float64 sum costs about 20 % more per point."""
    out = np.zeros((q.shape[0], 3), np.float32)
    if len(freq) == 0:
        return out
    re, im = (x.astype(np.float32).astype(np.float64) for x in (amp.real, amp.imag))
    step = max(1, FIELD_BLOCK // len(freq))
    for a in range(0, q.shape[0], step):
        c = q[a:a + step] @ freq.T                                                     # (n, K) cycles, float64
        t = ((c - np.floor(c)) * (2.0 * np.pi)).astype(np.float32)   # the phase mod 2 pi, then float32 trigonometry
        out[a:a + step] = np.cos(t) @ re - np.sin(t) @ im
    return out


def harmonic_field(points: np.ndarray, h: Harmonics, seed: int = 0) -> np.ndarray:
    """h at points float (N, 2) (the photo's plane) or (N, 3) (q = (x + y, z); module doc), moved by
    :func:`seed_shift`: float32 (N, 3) (:func:`wave_sum`)."""
    x = np.asarray(points, np.float64)
    if len(h) == 0:
        return np.zeros((x.shape[0], 3), np.float32)
    q = (x if x.shape[1] == 2 else np.stack([x[:, 0] + x[:, 1], x[:, 2]], axis=1)) + seed_shift(seed)
    return wave_sum(q, h.freq, h.amp)


def mix_waves(parts: list, dim: int) -> tuple | None:
    """The power-weighted union of wave sets ``parts`` [(freq (K, dim), amp complex (K, 3), value, w)], w >= 0:
    (freq (sum K, dim), amp (sum K, 3), sum of w * value), amplitudes times sqrt(w) so that powers are weighted
    by w; sets of weight 0 add nothing and are left out; None when none is left.  What interpolating two codes
    does to their harmonic parts (:func:`mix_harmonics`) and Gaussian rests (spectral.mix_rests)."""
    parts = [p for p in parts if p[3] > 0.0]
    if not parts:
        return None
    return (np.concatenate([f for f, _, _, _ in parts]).reshape(-1, dim),
            np.concatenate([a * np.sqrt(w) for _, a, _, w in parts]).reshape(-1, 3),
            float(sum(v * w for _, _, v, w in parts)))


def mix_harmonics(a: Harmonics | None, b: Harmonics | None, t: float) -> Harmonics | None:
    """The harmonic part of a code interpolated by ``t`` from a to b: both sets of waves, their powers weighted
    (1 - t) and t (amplitudes by the square roots), so the share interpolates linearly; None when neither is
    left (:func:`mix_waves`)."""
    m = mix_waves([(h.freq, h.amp, h.share, w) for h, w in ((a, 1.0 - t), (b, t)) if h is not None], 2)
    return None if m is None else Harmonics(*m)


def to_json(h: Harmonics) -> dict:
    """A model folder's stored harmonic part (solid.json "harmonics"): freq rows [f_x, f_y], amp rows
    [re R, im R, re G, im G, re B, im B], share; float64 values, read back exactly by :func:`from_json`."""
    amp = np.stack([h.amp.real, h.amp.imag], axis=2).reshape(-1, 6)
    return dict(freq=h.freq.astype(float).tolist(), amp=amp.astype(float).tolist(), share=float(h.share))


def read_waves(d, dim: int, scalar: str, ok, rule: str, what: str) -> tuple:
    """(freq float64 (K, dim), amp complex128 (K, 3), d[scalar]) of stored waves (freq rows of ``dim`` values, amp
    rows [re R, im R, re G, im G, re B, im B]: harmonic parts here, Gaussian rests in gaussian_rest.py); ValueError
    naming ``what`` unless they hold numbers of those shapes, as many of each, finite, and ``ok(d[scalar])`` (the
    ``rule`` the message states)."""
    try:
        freq = np.asarray(d["freq"], np.float64).reshape(-1, dim)
        amp = np.asarray(d["amp"], np.float64).reshape(-1, 6)
        value = float(d[scalar])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{what} must hold freq (K x {dim}), amp (K x 6) and {scalar}: {exc}") from None
    if len(freq) != len(amp) or not (np.all(np.isfinite(freq)) and np.all(np.isfinite(amp))) or not ok(value):
        raise ValueError(f"{what}: {len(freq)} frequencies, {len(amp)} amplitudes, {scalar} {value}: "
                         f"need as many of each, finite, and {rule}")
    a = amp.reshape(-1, 3, 2)
    return freq, a[..., 0] + 1j * a[..., 1], value


def from_json(d) -> Harmonics:
    """:func:`to_json`'s dict -> Harmonics; ValueError naming what is wrong."""
    return Harmonics(*read_waves(d, 2, "share", lambda s: 0.0 <= s < 1.0, "a share in [0, 1)", "harmonics"))
