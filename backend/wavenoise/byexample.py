"""Wave noise by example (Guehl et al. 2025, Sec. 4.4, Fig. 6 and 13).

The FFT power spectrum of a grayscale exemplar is split into S angular sectors
of the half plane [0, pi); each sector's radially averaged amplitude becomes one
row of a ``sectors`` WaveTable (all rows share their random phases, so rows can
be interpolated by angle without interference).  In 3D the sectors extend into
wedges around the chosen plane (XY, XZ or YZ).
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingError
from .spectra import Spectrum
from .tables import WaveTable, build_axis_table

__all__ = ["check_example", "sector_spectra", "example_table", "PLANES"]

#: plane name -> (a, b, normal) axis indices
PLANES = {"xy": (0, 1, 2), "xz": (0, 2, 1), "yz": (1, 2, 0)}


def check_example(image) -> np.ndarray:
    """A by-example image as float64 (H, W), zero mean: SettingError naming ``example`` unless it is a grey image
    of finite numbers, at least 16 x 16 px, that is not one value (whose spectrum would be empty)."""
    img = np.asarray(image)
    if img.dtype.kind not in "fiu":
        raise SettingError("example", f"needs a grayscale image of numbers, got {img.dtype}")
    img = img.astype(np.float64)
    if img.ndim != 2 or min(img.shape) < 16:
        raise SettingError("example", f"needs a 2D grayscale image of at least 16x16, got shape {img.shape}")
    if not np.all(np.isfinite(img)):
        raise SettingError("example", "the image holds NaN or infinite values")
    img = img - img.mean()
    if not np.any(img):
        raise SettingError("example", "the image is constant; its spectrum is empty")
    return img


def sector_spectra(image: np.ndarray, sectors: int, extent: float) -> tuple[list[Spectrum], float]:
    """Radial amplitude profile of each angular sector of ``image``'s power spectrum.

    image: float (H, W) grayscale; extent: world units spanned by the image width.
    Returns one ``custom`` Spectrum per sector (amplitudes on [0, fmax]) and fmax.
    """
    img = check_example(image)
    if not sectors >= 1:
        raise SettingError("sectors", f"must be >= 1, got {sectors}")
    h, w = img.shape
    # Hann window against the spectral cross of non-periodic borders
    win = np.outer(np.hanning(h), np.hanning(w))
    power = np.abs(np.fft.fft2(img * win)) ** 2
    fy = np.fft.fftfreq(h, d=extent / w)   # square pixels: pixel size extent / w
    fx = np.fft.fftfreq(w, d=extent / w)
    FY, FX = np.meshgrid(fy, fx, indexing="ij")
    radius = np.hypot(FX, FY)
    angle = np.mod(np.arctan2(FY, FX), np.pi)
    sector = np.minimum((angle / np.pi * sectors).astype(int), sectors - 1)
    df = 1.0 / extent
    fmax = min(0.5 * w, 0.5 * h) * df
    nb = int(fmax / df)
    rbin = np.rint(radius / df).astype(int)
    ok = (rbin >= 1) & (rbin <= nb)
    spectra = []
    for s in range(sectors):
        m = ok & (sector == s)
        tot = np.bincount(rbin[m], weights=power[m], minlength=nb + 1)
        cnt = np.bincount(rbin[m], minlength=nb + 1)
        psd = np.divide(tot, cnt, out=np.zeros_like(tot), where=cnt > 0)
        # fill empty bins (small radii of narrow sectors) from neighbours
        good = cnt > 0
        good[0] = False
        if good.any():
            idx = np.arange(nb + 1)
            psd = np.interp(idx, idx[good], psd[good])
        psd[0] = 0.0
        spectra.append(Spectrum("custom", 0.0, nb * df, samples=tuple(np.sqrt(psd))))
    return spectra, nb * df


def example_table(image: np.ndarray, dim: int, rng: np.random.Generator, sectors: int = 8,
                  extent: float = 1.0, size: int | None = None) -> WaveTable:
    """A ``sectors`` WaveTable reproducing the exemplar's anisotropic spectrum."""
    spectra, fmax = sector_spectra(image, sectors, extent)
    # period 4 x extent: harmonics 4x finer than the exemplar's frequency bins
    period = 4.0 * extent
    need = int(np.ceil(2.0 * fmax * period)) + 2
    size = size or max(1024, 1 << int(np.ceil(np.log2(need))))
    # the 2D weighting (f^(1/2)) also for 3D: waves stay near the plane
    return build_axis_table(spectra, 2, rng, size=size, period=period, mode="sectors")
