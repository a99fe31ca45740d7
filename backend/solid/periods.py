"""The periods of a photo whose pattern repeats only a few times in its frame, found from its autocorrelation, and
the harmonic part on their lattice, numpy only.

harmonic.py finds a photo's periods as peaks of its spectrum, each standing ``PROMINENCE`` times over the ring of
bins around it (up to ``WINDOW`` bins away), and motif.py fits a lattice to those peaks.  Both need the lattice's
points farther apart than the ring: a pattern repeated 10 times across the photo puts its peaks 10 bins apart.  A
texture library's tiles repeat their pattern two to four times (Sweet Home 3D's 256 x 166 px tile of two courses
of two bricks; its octagon floor tiles, two by two): their peaks lie one to three bins apart, every peak's ring
holds its neighbours, and no peak stands out.  On those tiles the harmonic part found the courses alone, or
nothing, and the solids lost their head joints and tiles.

In the image domain the same pattern is plain: the photo matches itself shifted by a period.  So:

1. **Autocorrelation.**  R(t) = sum u(x) . u(x + t) / sqrt(sum u(x)^2 sum u(x + t)^2), the sums over the part of
   the photo a shift t keeps (not wrapping round: a photograph is not a tile), for shifts up to ``REACH`` of the
   frame, through zero-padded FFTs (:func:`autocorrelation`); a photo over ``SIDE`` px is measured on its block
   means (periods that repeat a few times are long).
2. **Translations.**  Local maxima of R of at least ``CORRELATION`` that are returns, not ridges: on the straight
   path from 0 to t, R falls at least ``DIP`` below R(t) (a smooth texture correlates all the way to a short
   shift), and R(t) stands ``ISOLATION`` above the ring ``RING`` px around t (a shift along a course of flat bricks
   or along a plank correlates all along the course: a ridge whose wiggles are no periods; :func:`translations`).
   Each is refined to a fraction of a pixel by a parabola through R along each axis.
3. **The lattice.**  Pairs of translations span a lattice with at least ``MIN_REPEATS`` cells in the photo; it
   counts where its reduced basis t1, t2 and t1 +- t2 are periods too (R and the dip, for those within the
   reach: two nearly parallel translations span a fine false lattice whose short vectors fail them).  Of
   those, the finest (the smallest cell: the motif) whose weaker basis vector correlates within ``CLOSE`` of the
   best lattice's (:func:`period_lattice`): a tile's two courses give wiggles on the course ridge that span finer
   lattices than the bond, at lower R.  Stripes alone (planks, courses without head joints) are a ridge, not a
   lattice, and stay with the peak test.
4. **The harmonic part.**  On the DFT's grid (a tileable photo: every reciprocal basis vector whole), each lattice
   point (motif.py's :func:`~backend.solid.motif.lattice_points`) is a bin, exact; it is kept where its power stands
   ``PROMINENCE`` times over the mean power of the bins around it that are *not* lattice points (the ring test,
   with the pattern's own other harmonics taken out of the ring: :func:`lattice_bins`).  A bin of Gaussian noise
   passes with probability e^-8, 3 in 10 000, where a 256 px tile of four cells has some 8 000 lattice bins.

5. **Lines straight across the frame.**  A tile that holds its pattern once (one floor tile framed by its grout) or
   a floor of planks of irregular widths repeats nothing inside the frame, yet its joints and seams are the pattern.
   A row is such a line where its mean colour stands ``LINE_STRENGTH`` times the photo's RMS off the median of the
   row means within ``LINE_WIDTH`` rows (the local level, so that shading and broad bands are not lines) and
   ``LINE_SAME`` of its pixels lie past the midpoint towards it (a joint runs the whole width; a row of a face's
   texture holds pixels on both sides); columns likewise (:func:`frame_lines`).  The lines' profile, zero on every
   other row, is read as waves along the spectrum's axes.  A first version kept the axis bins standing over the
   bins beside them: every axis bin also carries the row or column mean of the tile's face, and the faces' shading
   came along as a plaid (docs/decisions/solid.md).

harmonic.py uses this part only where the lattice lies on the grid and is finer than its ring can see (a
reciprocal basis vector shorter than ``WINDOW`` + 1 bins), counted from one cycle per photo (the lattice, not a
lone peak, says the low harmonics repeat), and where it holds more of the photo's variance than the peaks and the
motif do.  A photograph whose few repeats lie off the grid is left to them.  It adds the lines that the part
chosen leaves in the photo, where they hold at least ``FEW_MARGIN`` of its variance.

Shapes: photos float (3, H, W) mean-free; translations float64 (K, 2) pixels (x right along columns, y down along
rows); reciprocal bases float64 (r, 2) cycles per photo (fx along columns, fy along rows).
"""
from __future__ import annotations

import numpy as np

from .motif import box_sums, lattice_points

__all__ = ["autocorrelation", "translations", "period_lattice", "lattice_bins", "frame_lines", "SIDE", "REACH",
           "CORRELATION", "DIP", "RING", "ISOLATION", "CLOSE", "MIN_REPEATS", "PROMINENCE", "WINDOW", "LINE_SAME",
           "LINE_STRENGTH", "LINE_WIDTH", "TRANSLATIONS"]

SIDE = 256           #: periods are sought at most this many px wide (block means of a larger photo)
REACH = 0.6          #: shifts up to this share of the frame along each axis
CORRELATION = 0.5    #: a period's autocorrelation at least this
DIP = 0.2            #: ... and at least this much above the lowest autocorrelation on the way to it
MIN_REPEATS = 2.0    #: the photo holds at least this many cells of the lattice
TRANSLATIONS = 24    #: the strongest local maxima considered
RING = 6             #: a period's R stands above the square ring of this half side (px) around it ...
ISOLATION = 0.03     #: ... by this much (a shift along a course or a plank is a ridge of R, not a peak)
CLOSE = 0.05         #: lattices whose basis correlates within this of the best one's compete on fineness
PROMINENCE = 8.0     #: a lattice bin's power over the mean power of the non-lattice bins around it
WINDOW = 3           #: ... within this many bins
LINE_SAME = 0.9      #: a row is a line straight across the photo where this share of its pixels lie past ...
LINE_STRENGTH = 0.5  #: ... the midpoint to its mean colour, which stands this many times the photo's RMS off ...
LINE_WIDTH = 8       #: ... the median of the row means within this many rows (px) around it
LINE_LENGTH = 16     #: a line runs at least this many px across (a column of a strip 3 px high is no line)


def autocorrelation(u: np.ndarray, reach: float = REACH) -> tuple:
    """(R float64 (2H, 2W), tx, ty int64 broadcastable shifts in px): the normalised autocorrelation of u (C, H, W)
    over the overlap of the photo and its shift (module doc, step 1); shifts beyond ``reach`` of the frame get -1."""
    C, H, W = u.shape
    shape = (2 * H, 2 * W)
    U = np.fft.rfft2(u, shape)
    num = np.fft.irfft2((U * U.conj()).sum(0), shape)
    one = np.fft.rfft2(np.ones((H, W)), shape)
    sq = np.fft.rfft2((u * u).sum(0), shape)
    here = np.fft.irfft2(one * sq.conj(), shape)      # sum of |u(x)|^2 over x with x + t inside
    there = np.fft.irfft2(sq * one.conj(), shape)     # sum of |u(x + t)|^2 over the same x
    R = num / np.sqrt(np.maximum(here * there, 1e-300))
    ty = np.fft.fftfreq(2 * H, 1.0 / (2 * H)).astype(np.int64)[:, None]
    tx = np.fft.fftfreq(2 * W, 1.0 / (2 * W)).astype(np.int64)[None, :]
    inside = (np.abs(tx) <= reach * W) & (np.abs(ty) <= reach * H)
    return np.where(inside, R, -1.0), tx, ty


def _dip(R: np.ndarray, t: np.ndarray, steps: int = 32) -> float:
    """R(t) less the lowest R on the straight path from 0 to t (nearest samples)."""
    h, w = R.shape
    s = np.linspace(0.0, 1.0, steps + 1)[1:-1]
    xs = np.round(s * t[0]).astype(np.int64) % w
    ys = np.round(s * t[1]).astype(np.int64) % h
    end = R[int(round(t[1])) % h, int(round(t[0])) % w]
    return float(end - R[ys, xs].min()) if len(s) else 0.0


def _ring_max(R: np.ndarray, iy: int, ix: int, r: int = RING) -> float:
    """The largest R on the square ring of half side r around (iy, ix)."""
    h, w = R.shape
    o = np.arange(-r, r + 1)
    ys = np.concatenate([np.full(2 * r + 1, -r), np.full(2 * r + 1, r), o, o]) + iy
    xs = np.concatenate([o, o, np.full(2 * r + 1, -r), np.full(2 * r + 1, r)]) + ix
    return float(R[ys % h, xs % w].max())


def translations(R: np.ndarray, tx: np.ndarray, ty: np.ndarray, correlation: float = CORRELATION,
                 dip: float = DIP, isolation: float = ISOLATION, k: int = TRANSLATIONS) -> tuple:
    """(t float64 (K, 2) px, r float64 (K,) their R): the local maxima of R (one of each pair t, -t) of at least
    ``correlation`` that dip ``dip`` on the way from 0 and stand ``isolation`` over the ring around them (module
    doc, step 2), of the strongest ``k``, each refined by parabolas along x and y."""
    h, w = R.shape
    peak = np.ones(R.shape, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                peak &= R >= np.roll(R, (dy, dx), (0, 1))
    half = (ty > 0) | ((ty == 0) & (tx > 0))
    idx = np.flatnonzero((peak & half & (R >= correlation)).ravel())
    idx = idx[np.argsort(-R.ravel()[idx], kind="stable")][:k]
    out, val = [], []
    for i in idx:
        iy, ix = divmod(int(i), w)
        t = np.array([float(tx[0, ix]), float(ty[iy, 0])])          # tx (1, w), ty (h, 1)
        if _dip(R, t) < dip or _ring_max(R, iy, ix) > R[iy, ix] - isolation:
            continue

        def offset(lo, mid, hi):
            den = lo - 2.0 * mid + hi
            return 0.0 if den >= 0 else float(np.clip(0.5 * (lo - hi) / den, -0.5, 0.5))

        t[0] += offset(R[iy, (ix - 1) % w], R[iy, ix], R[iy, (ix + 1) % w])
        t[1] += offset(R[(iy - 1) % h, ix], R[iy, ix], R[(iy + 1) % h, ix])
        out.append(t)
        val.append(float(R[iy, ix]))
    return np.array(out, np.float64).reshape(-1, 2), np.array(val, np.float64)


def _reduce(a: np.ndarray, b: np.ndarray) -> tuple:
    """The Lagrange-Gauss reduced basis of the lattice a, b: its two shortest independent vectors."""
    if a @ a > b @ b:
        a, b = b, a
    while True:
        m = round(float(a @ b) / float(a @ a))
        b = b - m * a
        if b @ b >= a @ a:
            return a, b
        a, b = b, a


def period_lattice(u: np.ndarray, min_repeats: float = MIN_REPEATS) -> tuple:
    """(reciprocal basis float64 (2, 2) in cycles per photo, translations float64 (2, 2) px), or (None, None): the
    lattice of the photo u (C, H, W)'s periods (module doc, step 3)."""
    C, H0, W0 = u.shape
    if min(H0, W0) < 2 * MIN_REPEATS:           # too few rows or columns to hold two cells of a lattice
        return None, None
    k = max(1, -(-max(H0, W0) // SIDE))          # a large photo's periods are sought on its k x k block means ...
    k = min(k, int(min(H0, W0) // (2 * MIN_REPEATS)))      # ... keeping a strip's short side able to hold them
    u = u[:, :H0 // k * k, :W0 // k * k].reshape(C, H0 // k, k, W0 // k, k).mean((2, 4))
    _, H, W = u.shape
    R, tx, ty = autocorrelation(u)
    T, r = translations(R, tx, ty)
    if len(T) == 0:
        return None, None
    h, w = R.shape

    def holds(v):           # a shift beyond the reach is not asked; one within it must be a period too
        if abs(v[0]) > REACH * W or abs(v[1]) > REACH * H:
            return True
        return bool(R[int(round(v[1])) % h, int(round(v[0])) % w] >= CORRELATION and _dip(R, v) >= DIP)

    found = []              # (the weaker basis vector's R, cell area, basis)
    for i in range(len(T)):
        for j in range(i + 1, len(T)):
            cell = abs(T[i, 0] * T[j, 1] - T[i, 1] * T[j, 0])
            if cell < 1.0 or H * W / cell < min_repeats:
                continue
            a, b = _reduce(T[i], T[j])
            if all(holds(v) for v in (a, b, a + b, a - b)):
                found.append((min(r[i], r[j]), cell, np.stack([T[i], T[j]])))
    best = None
    if found:               # the finest of the lattices whose basis correlates about as well as the best's
        top = max(f[0] for f in found)
        best = min((f for f in found if f[0] >= top - CLOSE), key=lambda f: f[1])[2]
    if best is None:
        return None, None
    best = best * k                                 # px of the photo
    B = np.linalg.inv(best).T                       # rows: reciprocal vectors, cycles per px
    return B * np.array([W0, H0], np.float64), best


def lattice_bins(P: np.ndarray, B: np.ndarray, min_cycles: float, prominence: float = PROMINENCE,
                 window: int = WINDOW) -> np.ndarray:
    """Flat bins of the power spectrum P (H, W) at the points of the on-grid lattice B (r, 2) (cycles per photo)
    that stand ``prominence`` times over the mean power of the non-lattice bins within ``window`` (module doc,
    step 4), one of each conjugate pair, strongest first."""
    H, W = P.shape
    pts = np.round(lattice_points(B, H, W, min_cycles)).astype(np.int64)
    on = np.zeros((H, W), bool)
    on[pts[:, 1] % H, pts[:, 0] % W] = True
    on[(-pts[:, 1]) % H, (-pts[:, 0]) % W] = True
    off = ~on
    off[0, 0] = False
    env = box_sums(P * off, window) / np.maximum(box_sums(off.astype(np.float64), window), 1.0)
    by, bx = pts[:, 1] % H, pts[:, 0] % W
    keep = P[by, bx] >= prominence * env[by, bx]
    idx = (by * W + bx)[keep]
    return idx[np.argsort(-P.ravel()[idx], kind="stable")]


def _line_profile(rest: np.ndarray, same: float, strength: float, width: int) -> np.ndarray:
    """The profile (C, H) of the rows of rest (C, H, W) that are lines straight across it: a row's mean colour less
    the median of the row means within ``width`` rows around it (the local level: shading and broad bands are not
    lines), where that stands ``strength`` times the rest's RMS off zero and ``same`` of the row's pixels lie past
    the midpoint from the local level towards it (a grout joint or a plank seam runs the whole width; a row of a
    face's texture holds pixels on both sides); zero on every other row, and on every row shorter than LINE_LENGTH."""
    m = rest.mean(2)                                                             # (C, H)
    if rest.shape[2] < LINE_LENGTH:
        return np.zeros_like(m)
    near = np.lib.stride_tricks.sliding_window_view(np.pad(m, ((0, 0), (width, width)), mode="wrap"),
                                                    2 * width + 1, axis=1)
    level = np.median(near, axis=2)                                              # (C, H)
    d = m - level
    d2 = (d * d).sum(0)
    proj = ((rest - level[:, :, None]) * d[:, :, None]).sum(0) / np.maximum(d2, 1e-30)[:, None]
    rms = float(np.sqrt((rest * rest).sum(0).mean()))
    line = ((proj > 0.5).mean(1) >= same) & (np.sqrt(d2) >= strength * rms)
    return np.where(line[None, :], d, 0.0)


def frame_lines(rest: np.ndarray, same: float = LINE_SAME, strength: float = LINE_STRENGTH,
                width: int = LINE_WIDTH) -> tuple:
    """(fx, fy float64 (K,) cycles per photo, A complex128 (K, 3)): the waves of the lines straight across the
    photo's rest (C, H, W) (its rows, then its columns, less the rows' field: a crossing counts once), one of each
    conjugate pair, the strongest first: rest(r, c) ~ sum Re(A exp(2 pi i (fx c / W + fy r / H)))."""
    C, H, W = rest.shape
    rows = _line_profile(rest, same, strength, width)                            # (C, H)
    cols = _line_profile((rest - rows[:, :, None]).transpose(0, 2, 1), same, strength, width)     # (C, W)
    out = []
    for prof, n, horizontal in ((rows, H, True), (cols, W, False)):
        if not prof.any():
            continue
        k = np.arange(1, (n + 1) // 2)                                           # below Nyquist, one of each pair
        A = (2.0 / n) * np.fft.fft(prof, axis=1)[:, k].T                         # (K, C)
        zero = np.zeros(len(k))
        out.append((zero, k.astype(np.float64), A) if horizontal else (k.astype(np.float64), zero, A))
    if not out:
        return np.zeros(0), np.zeros(0), np.zeros((0, C), np.complex128)
    fx, fy, A = (np.concatenate(v) for v in zip(*out))
    order = np.argsort(-(np.abs(A) ** 2).sum(1), kind="stable")
    return fx[order], fy[order], A[order]

