"""Radial amplitude profiles A(f) of wave noise (Guehl et al. 2025, Sec. 4 and 7.3).

Frequencies are in cycles per unit of the evaluation space.  A profile gives the
amplitude of the n-D spectrum at radius ``f``; its power spectral density is
``A(f)**2``.  All profiles are zero outside their band.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SettingError

__all__ = ["Spectrum", "SPECTRUM_KINDS"]

SPECTRUM_KINDS = ("gaussian", "white", "blue", "brown", "fractal", "bandpass", "twolevel", "custom")


@dataclass(frozen=True)
class Spectrum:
    """An isotropic amplitude profile.

    kind      one of :data:`SPECTRUM_KINDS`:
              gaussian  Gaussian bump centred on the band, sigma = (fmax - fmin) / 6
              white     flat amplitude on (0, fmax]  (fmin ignored)
              blue      amplitude rising linearly with f on [fmin, fmax]  (PSD ~ f^2)
              brown     amplitude ~ 1/f on [fmin, fmax]  (PSD ~ 1/f^2)
              fractal   amplitude ~ f^-exponent on [fmin, fmax]
              bandpass  flat amplitude on [fmin, fmax]
              twolevel  flat at 1 on the lower ``split`` fraction of the band, ``ratio`` above
              custom    ``samples`` are amplitudes on a uniform grid over [fmin, fmax]
    fmin, fmax   band limits, cycles per unit
    """

    kind: str = "gaussian"
    fmin: float = 2.0
    fmax: float = 8.0
    exponent: float = 1.0
    split: float = 0.25
    ratio: float = 0.35
    samples: tuple = field(default=())

    def validate(self) -> "Spectrum":
        if self.kind not in SPECTRUM_KINDS:
            raise SettingError("spectrum", f"unknown kind {self.kind!r}; choose one of {', '.join(SPECTRUM_KINDS)}")
        if not (np.isfinite(self.fmin) and np.isfinite(self.fmax)):
            raise SettingError("fmin/fmax", "must be finite numbers")
        if not np.isfinite(self.exponent):
            raise SettingError("exponent", f"must be a finite number, got {self.exponent}")
        if self.kind == "twolevel" and not np.isfinite(self.ratio):
            raise SettingError("ratio", f"must be a finite number, got {self.ratio}")
        if self.fmax <= 0:
            raise SettingError("fmax", f"must be positive, got {self.fmax:g}")
        if self.fmin < 0:
            raise SettingError("fmin", f"must be >= 0, got {self.fmin:g}")
        if self.fmin > self.fmax:
            raise SettingError("fmin", f"{self.fmin:g} is greater than fmax {self.fmax:g}")
        if self.kind == "gaussian" and self.fmin == self.fmax:
            raise SettingError("fmin", "gaussian needs fmin < fmax")
        if self.kind == "twolevel" and not 0.0 < self.split < 1.0:
            raise SettingError("split", f"must lie in (0, 1), got {self.split:g}")
        if self.kind == "custom":
            s = np.asarray(self.samples, dtype=np.float64)
            if s.ndim != 1 or len(s) < 2 or not np.all(np.isfinite(s)) or np.any(s < 0):
                raise SettingError("samples", "custom spectrum needs >= 2 finite, non-negative amplitudes")
        return self

    def amplitude(self, f: np.ndarray) -> np.ndarray:
        """Amplitude A(f) for frequencies ``f`` (float64 array, cycles/unit)."""
        self.validate()
        f = np.asarray(f, dtype=np.float64)
        lo, hi = self.fmin, self.fmax
        inside = (f >= lo) & (f <= hi) & (f > 0)
        k = self.kind
        if k == "gaussian":
            sigma = (hi - lo) / 6.0
            a = np.exp(-0.5 * ((f - 0.5 * (lo + hi)) / sigma) ** 2)
        elif k == "white":
            inside = (f > 0) & (f <= hi)
            a = np.ones_like(f)
        elif k == "blue":
            a = f / hi
        elif k == "brown":
            a = np.divide(lo if lo > 0 else 1.0, f, out=np.zeros_like(f), where=f > 0)
        elif k == "fractal":
            a = np.power(np.where(f > 0, f, 1.0) / max(lo, 1e-12), -self.exponent)
        elif k == "bandpass":
            a = np.ones_like(f)
        elif k == "twolevel":
            cut = lo + self.split * (hi - lo)
            a = np.where(f < cut, 1.0, self.ratio)
        else:  # custom
            s = np.asarray(self.samples, dtype=np.float64)
            a = np.interp(f, np.linspace(lo, hi, len(s)), s)
        return np.where(inside, a, 0.0)

    @property
    def top(self) -> float:
        """Highest frequency with non-zero amplitude (cycles/unit)."""
        return self.fmax
