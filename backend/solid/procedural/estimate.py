"""What the photo says before any search: the orientation of its structure and its repeat lengths, the starts of
every family's search.

- **Orientation**: the structure tensor of the luminance's gradient (Bigün & Granlund 1987; summed over the
  photo): its main eigenvector is the direction across the stripes, the wave vector's.
- **Repeats**: the autocorrelation of the luminance band-passed between BAND px (a difference of Gaussians, which
  keeps neither the JPEG blocks' edges nor the photo's layout; Wiener-Khinchin: the inverse FFT of its power), read
  along x, along z, along the wave vector and along both diagonals (a herringbone's): its first peak beyond MIN_LAG
  px within FUNDAMENTAL of the highest (a course's height, a plank's width, a tile's side: a lattice correlates
  again at every multiple of its repeat, and the highest of those peaks is as often two tiles as one), or, where it
  has none above PEAK, CORRELATION_SCALE times the distance over which it falls to a half (a stone's, a blotch's
  size).
- **Courses**: how the units of a wall repeat up, read off the same autocorrelation.  A stack bond repeats every
  course, straight up: its peak at (0, spacing_z) is the course's.  A running bond repeats straight up every second
  course, and every course half a unit along; a raking bond by a third every third.  So where the autocorrelation
  a third (else a half) of the repeat up, at its highest along a unit's length, is at least FUNDAMENTAL of that at
  (0, spacing_z), the courses are that high, each shifted along x by where that highest is, else they are
  spacing_z high and stacked (as where the photo has no peak up: no courses to read).
- **Dark gaps**: whether the luminance's skewness (its third standardised moment) is negative, its long thin tail
  dark.  Grout, mortar, cracks and the gaps between stones are a minority of the photo's pixels: dark grout skews
  it dark, pale mortar bright.  The gapped families (cells, bonds) give their gaps the ramp's dark end where it is
  (``flip`` off), its bright end where not; the fit's loss alone laid pale joints on a dark-grouted tile photo.

Shapes: photo float (H, W, 3) sRGB, top row first; the photo stands on the wall x-z (x right, z up).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ramp import luminance

__all__ = ["Estimates", "estimate", "repeat_length", "courses", "repeats", "grid_repeat", "at_lag", "band_transfer",
           "GRID", "CORRELATION_SCALE", "BAND"]

CORRELATION_SCALE = 4.0    #: a repeat where the autocorrelation has no peak: this many of its half-fall lengths
BAND = (1.5, 24.0)         #: the band-pass's Gaussians, sigma in px
MIN_LAG = 6                #: shorter repeats are grain
PEAK = 0.1                 #: a peak lower than this is chance
FUNDAMENTAL = 0.8          #: the repeat is the first peak at least this share of the highest
COURSES = (3, 2)           #: the courses a wall's repeat up may hold, most first (raking bonds, running bonds)
GRID = 0.5                 #: a photo whose :func:`grid_repeat` is at least this repeats as a grid


@dataclass(frozen=True)
class Estimates:
    """``spacing`` (units) along, and ``angle`` (radians from +x towards +z) of, the wave vector across the
    photo's stripes; ``spacing_x`` and ``spacing_z``: the repeats along x and along z, units; ``diagonals``: the
    repeats along the diagonals at 45 and 135 degrees from +x, units; ``courses``: (a course's height, units; each
    course's shift along x, in units of ``spacing_x``, in [0, 1)); ``dark_gaps``: the luminance skews dark."""
    spacing: float
    angle: float
    spacing_x: float
    spacing_z: float
    diagonals: tuple
    courses: tuple
    dark_gaps: bool


def repeat_length(profile: np.ndarray) -> float:
    """The repeat of a 1D autocorrelation (lag 0 first, normalised to 1 there), in lags (module doc)."""
    c = np.asarray(profile, np.float64)
    inner = c[1:-1]
    peaks = np.flatnonzero((inner > c[:-2]) & (inner >= c[2:]) & (inner > PEAK)) + 1
    peaks = peaks[peaks >= MIN_LAG]
    if len(peaks):
        return float(peaks[np.argmax(c[peaks] >= FUNDAMENTAL * c[peaks].max())])
    half = np.flatnonzero(c < 0.5)
    return float(CORRELATION_SCALE * (half[0] if len(half) else len(c)))


def at_lag(ac: np.ndarray, dx, dz) -> np.ndarray:
    """The autocorrelation (centred at [0, 0], wrapping) at lags (dx, dz) px, z up = rows up, read bilinearly
    (rounded positions would wobble the lags and raise false peaks)."""
    r, c = np.broadcast_arrays(-np.asarray(dz, np.float64), np.asarray(dx, np.float64))
    r0, c0 = np.floor(r), np.floor(c)
    fr, fc = r - r0, c - c0
    i, j = r0.astype(np.int64), c0.astype(np.int64)
    h, w = ac.shape

    def at(dr, dcol):
        return ac[(i + dr) % h, (j + dcol) % w]

    return (1 - fr) * ((1 - fc) * at(0, 0) + fc * at(0, 1)) + fr * ((1 - fc) * at(1, 0) + fc * at(1, 1))


def _ray(ac: np.ndarray, angle: float, n: int) -> np.ndarray:
    """The autocorrelation along a ray at ``angle`` (radians from +x towards +z), n lags one px apart."""
    t = np.arange(n)
    return at_lag(ac, t * np.cos(angle), t * np.sin(angle))


def courses(ac: np.ndarray, across: float, up: float) -> tuple:
    """(a course's height, each course's shift along x in units of ``across``, in [0, 1)) from the
    autocorrelation ``ac`` and the repeats ``across`` and ``up``, px (module doc): the height in px."""
    top = float(at_lag(ac, 0.0, up))
    lags = np.arange(max(int(round(across)), 1), dtype=np.float64)
    for k in COURSES:
        row = at_lag(ac, lags, up / k)
        if up / k >= MIN_LAG and top > PEAK and row.max() >= FUNDAMENTAL * top:
            # a course up, the photo reads as itself shifted back by the courses' shift: the peak is at -shift
            return up / k, float(-lags[int(np.argmax(row))] / max(across, 1.0)) % 1.0
    return up, 0.0


def band_transfer(H: int, W: int) -> np.ndarray:
    """The band-pass's transfer on an (H, W) FFT grid (module doc: the difference of Gaussians of BAND) -> (H, W)."""
    fy, fx = np.fft.fftfreq(H)[:, None], np.fft.fftfreq(W)[None, :]
    f2 = (2 * np.pi) ** 2 * (fy ** 2 + fx ** 2)
    return np.exp(-0.5 * f2 * BAND[0] ** 2) - np.exp(-0.5 * f2 * BAND[1] ** 2)


def _autocorrelation(lum: np.ndarray) -> np.ndarray:
    """The autocorrelation of a luminance (H, W) less its mean, band-passed (module doc), 1 at lag (0, 0)."""
    ac = np.real(np.fft.ifft2(np.abs(np.fft.fft2(lum) * band_transfer(*lum.shape)) ** 2))
    return ac / max(ac[0, 0], 1e-12)


def _repeats(ac: np.ndarray) -> tuple:
    """(across, up): the repeats along x and along z of an autocorrelation, px."""
    H, W = ac.shape
    return repeat_length(ac[0, :W // 2]), repeat_length(ac[:H // 2, 0])


def repeats(photo: np.ndarray) -> tuple:
    """(across, up): the photo's repeats along x and along z, px (module doc)."""
    lum = luminance(photo)
    return _repeats(_autocorrelation(lum - lum.mean()))


def grid_repeat(photo: np.ndarray) -> float:
    """How much the photo repeats as a grid, as brick courses and tile joints do: its band-passed autocorrelation one
    repeat across and one repeat up, the lower of the two (1: the photo is itself shifted by either).  Of the photo
    set's and the structured set's 582 photos (at most 256 px a side), the grids of bricks, tiles, paving and metal
    plates read 0.53 to 0.93, the rows of ploughed fields 0.65 to 0.69, a patterned carpet 0.55 and every other
    photo 0.48 at most: at least :data:`GRID`, the interfaces suggest bonds (the default kinds draw stones or
    blotches on a wall)."""
    lum = luminance(photo)
    ac = _autocorrelation(lum - lum.mean())
    across, up = _repeats(ac)
    return float(min(at_lag(ac, across, 0.0), at_lag(ac, 0.0, up)))


def estimate(photo: np.ndarray, px_per_unit: float) -> Estimates:
    """The :class:`Estimates` of a photo at ``px_per_unit`` photo pixels per texture unit."""
    lum = luminance(photo)
    lum = lum - lum.mean()
    dark_gaps = bool(np.mean(lum ** 3) <= 0.0)
    H, W = lum.shape
    gz, gx = -np.gradient(lum, axis=0), np.gradient(lum, axis=1)          # z up
    tensor = np.array([[np.sum(gx * gx), np.sum(gx * gz)], [np.sum(gx * gz), np.sum(gz * gz)]])
    w, v = np.linalg.eigh(tensor)
    angle = float(np.arctan2(v[1, 1], v[0, 1]))
    ac = _autocorrelation(lum)
    n = min(H, W) // 2
    across, up = _repeats(ac)
    height, shift = courses(ac, across, up)
    return Estimates(repeat_length(_ray(ac, angle, n)) / px_per_unit, angle, across / px_per_unit, up / px_per_unit,
                     tuple(repeat_length(_ray(ac, a, n)) / px_per_unit for a in (0.25 * np.pi, 0.75 * np.pi)),
                     (height / px_per_unit, shift), dark_gaps)
