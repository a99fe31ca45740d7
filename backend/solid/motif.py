"""The repeating motif of a photo whose period is not a whole fraction of its frame: its lattice of spectral peaks
found off the DFT's grid, and the photo's colour amplitude at every point of that lattice, numpy only.

harmonic.py reads a photo's harmonic part from the bins of its discrete Fourier transform.  That is exact for a
tileable texture, whose periods divide the frame (the photo set's game textures), and not for a photograph: a
brick wall whose courses are 21.3 px apart in a 232 px photo puts each harmonic between bins, where its power
spreads over a sinc's lobes.  Read bin by bin, a harmonic becomes a few waves at the neighbouring whole
frequencies; they add up to the photo inside its frame, but beyond it (on a solid's walls, 128 px further on)
they beat, and the weaker harmonics that draw the head joints do not stand out of the leakage at all.  On
interior crops of the two held-out brick photos (224 x 232, 200 x 245, 250 x 200 px) the walls lost the beige
wall's bricks altogether and drew the red wall's head joints as ragged streaks.

A periodic pattern's spectrum is a lattice: every peak is m b1 + n b2 for whole m, n, with b1, b2 the reciprocal
basis of the pattern's translations (two for bricks, tiles and weaves; one for stripes, courses and planks).  So:

1. **Peaks off the grid.**  The strongest peaks harmonic.py finds are located between bins on the photo's
   Hann-windowed spectrum: for one sinusoid under a periodic Hann window the offset from the largest bin k is
   exactly 2 (|X(k+1)| - |X(k-1)|) / (|X(k-1)| + 2 |X(k)| + |X(k+1)|) of a bin (the window's kernel is a sum of
   three Dirichlet kernels; :func:`refine_peaks`, tested against synthetic sinusoids), along each axis.
2. **The lattice.**  The basis is the coarsest pair of vectors (the largest reciprocal cell, i.e. the smallest
   motif) drawn from the refined peaks and their differences whose whole combinations hold at least
   ``EXPLAINED`` of the refined peaks' power and ``EXPLAINED_COUNT`` of the peaks within ``TOLERANCE`` bins,
   repeated at least ``MIN_CELLS`` times in the photo (stripes at least its square root of times), then fitted
   to all of them by least squares (:func:`fit_lattice`).  Collinear peaks give one vector (stripes).  Peaks
   that no lattice explains (two unrelated periods) leave the photo to harmonic.py's bins.
3. **The motif.**  Every lattice point up to the photo's Nyquist frequency is a candidate wave; its colour
   amplitude is the windowed discrete-time Fourier transform at that exact frequency over the window's sum
   (D = A e^(i phi) / 2 for a sinusoid A cos(2 pi f . x + phi), whatever f), i.e. the average over the photo's
   unit cells, weighted by the window.  A point is kept when its power stands ``PROMINENCE`` times over the
   windowed spectrum's mean around it (lower than harmonic.py's 16: the lattice already says where a peak
   must be), the strongest ``count`` first (:func:`motif_waves`).

A photo whose lattice lies on the grid (within ``ON_GRID`` bins at every basis vector: a tileable texture) is
left to harmonic.py as before, whose bins are then exact; so are photos with fewer than ``MIN_PEAKS`` peaks on a
lattice (fewer peaks drew false stripes on paving and rock photos; see docs/decisions/solid.md, whose evidence
is ``python -m bench solid_motif``).

Shapes: photos float (3, H, W) with their mean removed; frequencies in cycles per photo along x (columns, fx)
and y (rows, fy), float64; amplitudes complex128 (K, 3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Motif", "box_sums", "windowed_magnitude", "refine_peaks", "fit_lattice", "lattice_points", "on_grid",
           "motif_waves", "windowed_dtft", "hann", "TOLERANCE", "EXPLAINED", "EXPLAINED_COUNT", "ON_GRID",
           "PROMINENCE", "PEAKS", "MIN_CELLS", "MIN_PEAKS", "CANDIDATES"]

CANDIDATES = 24     #: the shortest distinct peaks and differences tried as basis vectors
MIN_CELLS = 4.0     #: the photo holds at least this many repeats of a motif (the reciprocal cell's area, bins^2;
                    #: stripes repeat at least its square root of times: the vector's length, bins)
MIN_PEAKS = (8, 8)  #: peaks a lattice of one or two vectors must hold (module doc)
PEAKS = 24          #: the strongest peaks of harmonic.py's detection the lattice is sought from
TOLERANCE = 0.3     #: a peak lies on a lattice when it is within this many bins of a lattice point
EXPLAINED = 0.9     #: ... and a lattice is taken when its points hold this share of the peaks' power
EXPLAINED_COUNT = 0.75  #: ... and this share of the peaks (so that a strong course alone does not pick the lattice)
ON_GRID = 0.05      #: a lattice whose basis lies within this many bins of whole frequencies: a tileable photo
PROMINENCE = 4.0    #: a lattice point's power over the windowed spectrum's mean around it (5 x 5, less 3 x 3)
_RING = 2           #: the ring's half side (bins)


@dataclass(frozen=True)
class Motif:
    """A photo's motif (:func:`motif_waves`): ``fx``, ``fy`` float64 (K,) the waves' frequencies in cycles per photo
    along its columns and rows, ``dtft`` complex128 (K, 3) their windowed transforms (a wave's colour amplitude is
    2 dtft), ``basis`` float64 (r, 2) the lattice they lie on (rows (fx, fy); r = 1 for stripes)."""
    fx: np.ndarray
    fy: np.ndarray
    dtft: np.ndarray
    basis: np.ndarray


def hann(n: int) -> np.ndarray:
    """The periodic Hann window of n samples, float64 (n,)."""
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def box_sums(P: np.ndarray, r: int) -> np.ndarray:
    """Sums of P (H, W) over the (2 r + 1)^2 squares around each bin, the spectrum wrapping round (cumulative
    sums along each axis): harmonic.py's peak test and the motif's both measure a bin against the ring around
    it."""
    for axis in (0, 1):
        p = np.pad(P, [(r, r) if a == axis else (0, 0) for a in (0, 1)], mode="wrap")
        c = np.concatenate([np.zeros_like(np.take(p, [0], axis=axis)), np.cumsum(p, axis=axis)], axis=axis)
        n = P.shape[axis]
        P = np.take(c, np.arange(2 * r + 1, 2 * r + 1 + n), axis=axis) - np.take(c, np.arange(n), axis=axis)
    return P


def windowed_dtft(u: np.ndarray, fx: np.ndarray, fy: np.ndarray, chunk: int = 256) -> np.ndarray:
    """D complex128 (K, C): the Hann-windowed discrete-time Fourier transform of u (C, H, W) at the frequencies
    (fx, fy) (K,) cycles per photo, over the window's sum: sum_rc w(r, c) u(r, c) exp(-2 pi i (fx c / W + fy r /
    H)) / sum w.  Separable: (W, K) and (H, K) exponentials, ``chunk`` frequencies at a time."""
    C, H, W = u.shape
    wy, wx = hann(H), hann(W)
    wu = u * wy[None, :, None] * wx[None, None, :]
    out = np.empty((len(fx), C), np.complex128)
    for s in range(0, len(fx), chunk):
        ex = np.exp(-2j * np.pi * np.outer(np.arange(W), np.asarray(fx[s:s + chunk], np.float64) / W))
        ey = np.exp(-2j * np.pi * np.outer(np.arange(H), np.asarray(fy[s:s + chunk], np.float64) / H))
        for c in range(C):
            out[s:s + chunk, c] = np.einsum("hk,hk->k", ey, wu[c] @ ex)
    return out / (wy.sum() * wx.sum())


def windowed_magnitude(u: np.ndarray) -> np.ndarray:
    """The Hann-windowed colour magnitude spectrum sqrt(sum_c |X_c|^2), float64 (H, W)."""
    _, H, W = u.shape
    wu = u * hann(H)[None, :, None] * hann(W)[None, None, :]
    return np.sqrt((np.abs(np.fft.fft2(wu)) ** 2).sum(0))


def refine_peaks(M: np.ndarray, iy: np.ndarray, ix: np.ndarray) -> tuple:
    """(fx, fy) float64 (K,), signed cycles per photo, of the peaks near bins (iy, ix) of the windowed magnitude
    spectrum M (H, W): each from the largest bin of M within one of it, moved by the Hann window's exact offset
    along each axis (module doc, step 1)."""
    H, W = M.shape
    best = np.stack([M[(iy + dy) % H, (ix + dx) % W] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=1)
    b = np.argmax(best, axis=1)
    jy, jx = (iy + b // 3 - 1) % H, (ix + b % 3 - 1) % W

    def offset(lo, mid, hi):
        return 2.0 * (hi - lo) / np.maximum(lo + 2.0 * mid + hi, 1e-300)

    kx = np.fft.fftfreq(W, 1.0 / W)[jx]
    ky = np.fft.fftfreq(H, 1.0 / H)[jy]
    fx = kx + offset(M[jy, (jx - 1) % W], M[jy, jx], M[jy, (jx + 1) % W])
    fy = ky + offset(M[(jy - 1) % H, jx], M[jy, jx], M[(jy + 1) % H, jx])
    return fx, fy


def _explained(B: np.ndarray, F: np.ndarray, w: np.ndarray, tol: float) -> tuple:
    """(share of the weights w (K,) whose peaks F (K, 2) lie within tol of a whole combination of the rows of B
    (r, 2), the whole coordinates (K, r))."""
    coef, *_ = np.linalg.lstsq(B.T, F.T, rcond=None)                # (r, K)
    n = np.round(coef.T)
    err = np.linalg.norm(n @ B - F, axis=1)
    ok = err <= tol
    return float(w[ok].sum() / max(w.sum(), 1e-300)), n, ok


def fit_lattice(F: np.ndarray, w: np.ndarray, tol: float = TOLERANCE, explained: float = EXPLAINED,
                explained_count: float = EXPLAINED_COUNT):
    """The reciprocal lattice of peaks F (K, 2) in bins (signed cycles per photo along x and y) of powers w (K,):
    float64 (r, 2) basis rows, r = 2 (a pattern repeating in two directions) or 1 (stripes), or None when no
    lattice holds ``explained`` of the power and ``explained_count`` of the peaks within ``tol`` bins (module doc,
    step 2)."""
    F = np.asarray(F, np.float64)
    w = np.asarray(w, np.float64)
    if len(F) == 0:
        return None
    # candidates: the peaks and their differences, one of each sign, not shorter than a bin and a half
    c = np.concatenate([F, (F[:, None, :] - F[None, :, :]).reshape(-1, 2)])
    c = c[np.linalg.norm(c, axis=1) >= 1.5]
    c = np.where(((c[:, 1] < 0) | ((c[:, 1] == 0) & (c[:, 0] < 0)))[:, None], -c, c)
    if len(c) == 0:
        return None
    c = c[np.argsort(np.linalg.norm(c, axis=1), kind="stable")]
    keep = [c[0]]                      # distinct candidates, shortest first
    for v in c[1:]:
        if all(np.linalg.norm(v - k) > tol for k in keep):
            keep.append(v)
        if len(keep) == CANDIDATES:
            break

    def refit(B):
        """B refitted by least squares to the peaks nearest its points, from small whole coordinates to large:
        a candidate's error grows with the multiple, so the low harmonics fix it before the high ones count."""
        for limit in (2, 4, 8, None):
            coef, *_ = np.linalg.lstsq(B.T, F.T, rcond=None)
            n = np.round(coef.T)
            sel = np.linalg.norm(n @ B - F, axis=1) <= 0.45
            if limit is not None:
                sel &= np.abs(n).max(axis=1) <= limit
            if sel.sum() < B.shape[0] + 1 or np.linalg.matrix_rank(n[sel]) < B.shape[0]:
                continue
            fit, *_ = np.linalg.lstsq(n[sel], F[sel], rcond=None)
            if np.linalg.matrix_rank(fit) == B.shape[0]:
                B = fit
        return B

    def fits(B):       # and more peaks than the basis needs: any two peaks are a lattice of their own
        share, n, ok = _explained(B, F, w, tol)
        return share >= explained and ok.mean() >= explained_count and ok.sum() >= MIN_PEAKS[B.shape[0] - 1]

    best, best_area = None, 0.0        # the coarsest lattice (largest reciprocal cell) that holds the peaks
    for i, a in enumerate(keep):
        for b in keep[i + 1:]:
            area = abs(a[0] * b[1] - a[1] * b[0])
            if area < MIN_CELLS or area <= best_area:     # too fine, or no coarser than the best so far
                continue
            B = refit(np.stack([a, b]))
            area = abs(B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0])
            if area >= MIN_CELLS and area > best_area and fits(B):
                best, best_area = B, area
    if best is None:                   # stripes: the longest vector whose multiples hold the peaks
        for a in keep[::-1]:
            B = refit(a[None, :])
            if np.linalg.norm(B) >= np.sqrt(MIN_CELLS) and fits(B):
                best = B
                break
        if best is None:
            return None
    share, n, ok = _explained(best, F, w, tol)
    # least squares over the peaks that lie on it, weighted by their power's square root
    s = np.sqrt(w[ok])[:, None]
    fit, *_ = np.linalg.lstsq(n[ok] * s, F[ok] * s, rcond=None)
    return fit if np.linalg.matrix_rank(fit) == fit.shape[0] else best


def lattice_points(B: np.ndarray, H: int, W: int, min_cycles: float) -> np.ndarray:
    """Every point m b1 (+ n b2) of the lattice B (r, 2) within the photo's Nyquist band (|fx| < W / 2, |fy| < H / 2
    cycles per photo), at least ``min_cycles`` cycles per photo from zero (as harmonic.py measures it), one of
    each conjugate pair: float64 (K, 2)."""
    r = B.shape[0]
    corners = np.array([[sx * W / 2.0, sy * H / 2.0] for sx in (-1, 1) for sy in (-1, 1)])
    c, *_ = np.linalg.lstsq(B.T, corners.T, rcond=None)            # (r, 4): a linear map's extremes
    lim = np.ceil(np.abs(c).max(axis=1)).astype(np.int64) + 1
    if r == 1:
        n = np.arange(1, lim[0] + 1)[:, None]
    else:
        mm, nn = np.meshgrid(np.arange(-lim[0], lim[0] + 1), np.arange(-lim[1], lim[1] + 1), indexing="ij")
        n = np.stack([mm.ravel(), nn.ravel()], 1)
    P = n @ B
    if r == 2:      # one of each conjugate pair, as harmonic.py keeps them
        P = P[(P[:, 1] > 1e-9) | ((np.abs(P[:, 1]) <= 1e-9) & (P[:, 0] > 0))]
    inside = (np.abs(P[:, 0]) < W / 2.0) & (np.abs(P[:, 1]) < H / 2.0)
    far = np.hypot(P[:, 0] / W, P[:, 1] / H) * min(H, W) >= min_cycles
    return P[inside & far]


def on_grid(B: np.ndarray, tol: float = ON_GRID) -> bool:
    """Whether every basis vector of B (r, 2) lies within ``tol`` bins of whole frequencies (a tileable photo)."""
    return bool(np.all(np.abs(B - np.round(B)) <= tol))


def motif_waves(u: np.ndarray, peaks: np.ndarray, powers: np.ndarray, min_cycles: float, count: int,
                floor: float, prominence: float = PROMINENCE, npeaks: int = PEAKS) -> Motif | None:
    """The photo's motif where its lattice lies off the grid (module doc): u (3, H, W) mean-free, ``peaks`` flat
    bins of harmonic.py's detection (strongest first) with their ``powers``.  The strongest ``count`` lattice points
    that stand ``prominence`` over their surroundings and hold at least ``floor`` of the photo's variance, as a
    :class:`Motif`; None when the peaks fit no lattice or it lies on the grid (harmonic.py's bins then hold it)."""
    _, H, W = u.shape
    if len(peaks) == 0:
        return None
    M = windowed_magnitude(u)
    iy, ix = np.divmod(np.asarray(peaks[:npeaks]), W)
    fx, fy = refine_peaks(M, iy, ix)
    B = fit_lattice(np.stack([fx, fy], 1), np.asarray(powers[:npeaks], np.float64))
    if B is None or on_grid(B):
        return None
    P = lattice_points(B, H, W, min_cycles)
    if len(P) == 0:
        return None
    # screen by the windowed spectrum at the nearest bin (a point between bins keeps at least ~0.4 of its peak
    # there), then the exact transform at the strongest 2 count
    by, bx = np.round(P[:, 1]).astype(np.int64) % H, np.round(P[:, 0]).astype(np.int64) % W
    M2 = M ** 2
    ring = (box_sums(M2, _RING) - box_sums(M2, 1)) / ((2 * _RING + 1) ** 2 - 9)
    order = np.argsort(-M[by, bx], kind="stable")[:2 * count]
    P, by, bx = P[order], by[order], bx[order]
    D = windowed_dtft(u, P[:, 0], P[:, 1])
    power = (np.abs(D) ** 2).sum(1)                          # per wave: its variance is 2 power
    scale = (hann(H).sum() * hann(W).sum()) ** 2            # D's power over the window's: comparable with M^2
    variance = float((u ** 2).sum() / (H * W))
    keep = (power * scale >= prominence * ring[by, bx]) & (2.0 * power >= floor * variance)
    idx = np.flatnonzero(keep)
    idx = idx[np.argsort(-power[idx], kind="stable")][:count]
    return Motif(P[idx, 0], P[idx, 1], D[idx], B)
