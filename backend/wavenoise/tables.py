"""Complex 1D wave tables T (Guehl et al. 2025, Eq. 7) and their lookup (Eq. 8/9).

A :class:`WaveTable` stores ``rows`` complex tables of ``size`` samples covering
one period of ``period`` world units.  Row modes:

* ``single``  one isotropic table;
* ``axes``    one table per coordinate axis, shared phases, interpolated by the
              squared direction components (anisotropy, Fig. 5 left);
* ``sectors`` one table per angular sector of a plane, shared phases, linearly
              interpolated by the direction's angle in that plane (by example, Sec. 4.4).

Eq. 7 samples harmonics ``l / period`` with random phases phi_l:

    T[j] = sum_l a_l exp(i (2 pi l j / size + phi_l)),

computed as one inverse FFT, and normalised to unit mean power (mean |T|^2 = 1).
For random phases powers add, so the amplitude that reproduces an n-D power
spectrum A(f)^2 with waves spread over the sphere is ``a_l = A(f_l) f_l^((n-1)/2)``
(Eq. 7 writes the deterministic Jacobian f^(n-1); its square root is the
statistically matching weight for random phases).

Lookups follow GPU texture conventions so a Blender Image Texture node with
Linear interpolation and Repeat extension returns the same value: texel i is
centred at ``(i + 0.5) / size``.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ..errors import SettingError
from .spectra import Spectrum

__all__ = ["WaveTable", "build_table", "build_axis_table", "build_waveform_table",
           "table_lookup", "WAVEFORMS", "DEFAULT_SIZE"]

DEFAULT_SIZE = 1024
#: Default number of harmonics below the band top when the period is automatic (N_f).
DEFAULT_HARMONICS = 256
WAVEFORMS = ("gaussian", "crystal", "wired", "custom")
_FORMAT = "omninoise-wavetable"
_VERSION = 1


@dataclass
class WaveTable:
    """values: complex64 (rows, size); period: world units per table period."""

    values: np.ndarray
    period: float
    mode: str = "single"
    dim: int = 3
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        self.values = np.ascontiguousarray(np.atleast_2d(self.values), dtype=np.complex64)
        if self.mode not in ("single", "axes", "sectors"):
            raise SettingError("table mode", f"unknown mode {self.mode!r}")

    @property
    def rows(self) -> int:
        return self.values.shape[0]

    @property
    def size(self) -> int:
        return self.values.shape[1]

    @property
    def nyquist(self) -> float:
        """Highest frequency (cycles/unit) the table can represent."""
        return self.size / (2.0 * self.period)

    def mean_frequency(self) -> float:
        """Power-weighted mean frequency (cycles/unit) over all rows."""
        p = np.abs(np.fft.fft(self.values.astype(np.complex128), axis=1)) ** 2
        p = p.sum(axis=0)
        f = np.fft.fftfreq(self.size, d=1.0 / self.size) / self.period
        return float(np.sum(np.abs(f) * p) / max(np.sum(p), 1e-30))

    # -- persistence ---------------------------------------------------
    def save(self, path: str) -> None:
        """Write ``.npz`` (values + JSON metadata) atomically."""
        header = dict(format=_FORMAT, version=_VERSION, period=self.period, mode=self.mode,
                      dim=self.dim, meta=self.meta)
        from ... import export

        with export.atomic_path(path, ".npz") as tmp:
            np.savez(tmp, values=self.values, header=np.frombuffer(json.dumps(header).encode(), np.uint8))

    @classmethod
    def load(cls, path: str) -> "WaveTable":
        try:
            with np.load(path, allow_pickle=False) as z:
                header = json.loads(bytes(z["header"]).decode())
                values = z["values"]
        except (OSError, KeyError, ValueError) as exc:
            raise SettingError("table", f"cannot read wave table {path!r}: {exc}") from None
        if header.get("format") != _FORMAT:
            raise SettingError("table", f"{path!r} is not an OmniNoise wave table")
        return cls(values, float(header["period"]), header["mode"], int(header["dim"]), header.get("meta", {}))


def _auto_period(fmax: float, harmonics: int = DEFAULT_HARMONICS) -> float:
    return (harmonics - 1) / fmax


def _check_nyquist(top: float, size: int, period: float) -> None:
    if size < 8:
        raise SettingError("table size", f"must be >= 8, got {size}")
    nyq = size / (2.0 * period)
    if top >= nyq:
        raise SettingError("fmax", f"{top:g} cycles/unit is at or above the wave table's Nyquist limit "
                                   f"{nyq:g} (table size {size} / (2 x period {period:g}))")


def _harmonic_amplitudes(spectrum: Spectrum, dim: int, size: int, period: float) -> np.ndarray:
    """a_l for l = 0..size-1 (float64); zero at DC and above Nyquist."""
    l = np.arange(size, dtype=np.float64)
    f = l / period
    a = spectrum.amplitude(f) * np.power(f, 0.5 * (dim - 1))
    a[0] = 0.0
    a[size // 2:] = 0.0
    return a


def _synthesise(amps: np.ndarray, phases: np.ndarray) -> np.ndarray:
    """Eq. 7 for each row of amps (rows, size) with shared phases (size,) -> complex128."""
    c = amps * np.exp(1j * phases)[None, :]
    return np.fft.ifft(c, axis=1) * amps.shape[1]


def _normalise(t: np.ndarray) -> np.ndarray:
    power = float(np.mean(np.abs(t) ** 2))
    if not power > 0:
        raise SettingError("spectrum", "the band holds no table harmonic; widen [fmin, fmax] or raise the period")
    return t / np.sqrt(power)


def build_table(spectrum: Spectrum, dim: int, rng: np.random.Generator, size: int = DEFAULT_SIZE,
                period: float | None = None) -> WaveTable:
    """Isotropic table for ``spectrum`` in ``dim`` dimensions (Eq. 7)."""
    spectrum.validate()
    period = _auto_period(spectrum.top) if period is None else float(period)
    _check_nyquist(spectrum.top, size, period)
    phases = rng.uniform(0.0, 2.0 * np.pi, size)
    amps = _harmonic_amplitudes(spectrum, dim, size, period)[None, :]
    t = _normalise(_synthesise(amps, phases))
    return WaveTable(t, period, "single", dim, dict(spectrum=spectrum.kind, fmin=spectrum.fmin, fmax=spectrum.fmax))


def build_axis_table(spectra: list[Spectrum], dim: int, rng: np.random.Generator, size: int = DEFAULT_SIZE,
                     period: float | None = None, mode: str = "axes") -> WaveTable:
    """Rows of tables with identical random phases (Sec. 4.3, uni-phase waves).

    One row per spectrum; the rows are normalised together so their relative
    energies are kept.  ``mode`` is ``axes`` (one row per coordinate axis) or
    ``sectors`` (rows for angular sectors, used by :mod:`backend.wavenoise.byexample`).
    """
    if mode == "axes" and len(spectra) != dim:
        raise SettingError("anisotropy", f"per-axis anisotropy needs {dim} spectra, got {len(spectra)}")
    for s in spectra:
        s.validate()
    top = max(s.top for s in spectra)
    period = _auto_period(top) if period is None else float(period)
    _check_nyquist(top, size, period)
    phases = rng.uniform(0.0, 2.0 * np.pi, size)
    amps = np.stack([_harmonic_amplitudes(s, dim, size, period) for s in spectra])
    t = _normalise(_synthesise(amps, phases))
    return WaveTable(t, period, mode, dim, dict(spectra=[s.kind for s in spectra]))


def build_waveform_table(waveform: str, rng: np.random.Generator, feature_frequency: float, dim: int,
                         size: int = DEFAULT_SIZE, features: int = 16, sharpness: float = 8.0,
                         profile: np.ndarray | None = None) -> WaveTable:
    """Non-Gaussian waveforms (Sec. 6.2): the table's real part is a spatial profile.

    crystal  random steps (piecewise-constant levels at random breakpoints);
    wired    narrow impulses at random positions (web / wire patterns);
    custom   ``profile``: any 1D array, resampled over one period.
    ``features`` steps or impulses fill one period of ``features / feature_frequency``
    units.  The complex table is the analytic signal of the profile (imaginary
    part = Hilbert transform), band-limited with Lanczos sigma factors.
    """
    if waveform not in ("crystal", "wired", "custom"):
        raise SettingError("waveform", f"unknown waveform {waveform!r}; choose one of {', '.join(WAVEFORMS)}")
    if not feature_frequency > 0:
        raise SettingError("fmax", "feature frequency must be positive")
    period = features / feature_frequency
    x = (np.arange(size) + 0.5) / size
    if waveform == "crystal":
        edges = np.sort(rng.uniform(0.0, 1.0, features))
        levels = rng.uniform(-1.0, 1.0, features)
        idx = np.searchsorted(edges, x) % features
        p = levels[idx - 1]
    elif waveform == "wired":
        centres = rng.uniform(0.0, 1.0, features)
        width = 1.0 / (features * sharpness)
        d = np.abs(x[:, None] - centres[None, :])
        d = np.minimum(d, 1.0 - d)
        p = np.exp(-0.5 * (d / width) ** 2).sum(axis=1)
    else:
        if profile is None:
            raise SettingError("profile", "custom waveform needs a 1D profile array")
        prof = np.asarray(profile, dtype=np.float64).ravel()
        if len(prof) < 2 or not np.all(np.isfinite(prof)):
            raise SettingError("profile", "custom waveform needs >= 2 finite samples")
        src = (np.arange(len(prof)) + 0.5) / len(prof)
        p = np.interp(x, src, prof, period=1.0)
    spec = np.fft.fft(p - p.mean())
    l = np.arange(size)
    half = size // 2
    sigma = np.sinc(l / half)  # Lanczos sigma factors against Gibbs ringing
    c = np.where((l >= 1) & (l < half), 2.0 * spec * sigma, 0.0)
    t = _normalise(np.fft.ifft(c)[None, :])
    return WaveTable(t, period, "single", dim, dict(waveform=waveform, features=features))


def table_lookup(values: np.ndarray, row: np.ndarray | int, coord: np.ndarray) -> np.ndarray:
    """Linear, periodic lookup of ``values[row]`` at ``coord`` (table periods).

    values: complex64 (rows, size); row: int array broadcastable to coord;
    coord: float32 (P,) in table periods.  Returns complex64 (P,).
    Texel i is centred at (i + 0.5) / size, as in GPU and Blender image textures.
    """
    size = values.shape[1]
    u = coord - np.floor(coord)
    j = u * np.float32(size) - np.float32(0.5)
    j0 = np.floor(j)
    w = (j - j0).astype(np.float32)
    i0 = j0.astype(np.int64) % size
    i1 = (i0 + 1) % size
    flat = values.reshape(-1)
    base = np.asarray(row, dtype=np.int64) * size
    a = flat[base + i0]
    b = flat[base + i1]
    return a + (b - a) * w
