"""The numba kernels of :mod:`.fast` (imported on first use, so that importing the engine does not load numba).

Point kernel ``_kernel`` (any points) and grid-row kernel ``_rows_kernel`` (see :class:`.fast.GridPlan`); the
row kernel is the reference of the C kernel in ``rows.c``.
"""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, fastmath=False, inline="always")
def _cos_half_pi(s):
    # cos(pi/2 s), s in [0, 1]: Taylor series of cos to x^12 (error < 5e-7)
    x = np.float32(1.5707963267948966) * s
    x2 = x * x
    return np.float32(1.0) + x2 * (np.float32(-0.5) + x2 * (np.float32(1.0 / 24) + x2 * (
        np.float32(-1.0 / 720) + x2 * (np.float32(1.0 / 40320) + x2 * (
            np.float32(-1.0 / 3628800) + x2 * np.float32(1.0 / 479001600))))))


@numba.njit(parallel=True, cache=True, fastmath=False, nogil=True)
def _kernel(x, sdirs, soffs, amps, nmin, slpos, omega, zeta, tab, inv_period, shift, out_re, out_im):
    P, D = x.shape
    K = sdirs.shape[0]
    N = tab.shape[0] - 2
    fN = np.float32(N)
    half = np.float32(0.5)
    for i in numba.prange(P):
        zr = np.float32(0.0)
        zi = np.float32(0.0)
        for k in range(K):
            acc = np.float32(0.0)
            for d in range(D):
                acc += x[i, d] * sdirs[k, d]
            p = acc + soffs[k]
            n = np.floor(p)
            f = p - n
            r = np.int64(n - nmin[k])
            u = (f - slpos[k, r]) * np.float32(0.5 / 0.3) + half
            if u < 0:
                u = np.float32(0.0)
            elif u > 1:
                u = np.float32(1.0)
            s = u * u * (np.float32(3.0) - np.float32(2.0) * u)
            w0 = _cos_half_pi(s)
            w1 = _cos_half_pi(np.float32(1.0) - s)
            br = np.float32(0.0)
            bi = np.float32(0.0)
            for side in range(2):
                rr = r + side
                dot = np.float32(0.0)
                for d in range(D):
                    dot += x[i, d] * omega[k, rr, d]
                c = (dot - shift) * inv_period + zeta[k, rr]
                c = c - np.floor(c)
                j = c * fN - half
                j0 = np.floor(j)
                t = j - j0
                idx = np.int64(j0) + 1
                ar = tab[idx, 0] + (tab[idx + 1, 0] - tab[idx, 0]) * t
                ai = tab[idx, 1] + (tab[idx + 1, 1] - tab[idx, 1]) * t
                w = w0 if side == 0 else w1
                br += w * ar
                bi += w * ai
            zr += amps[k] * br
            zi += amps[k] * bi
        out_re[i] = zr
        out_im[i] = zi


# ---------------------------------------------------------------------------
# Grid rows: the same sum, walked along x.
#
# On a regular grid every row is a line x_j = x0 + j h.  Along it the slice
# coordinate p = x . s_k + o_k and every wave coordinate are affine in x.  Slice
# n's border ramp towards n + 1, where u = (f - slpos) / 0.6 + 1/2 lies in
# [0, 1], sits inside slice n (slpos in [0.3, 0.7], half-width 0.3); between two
# ramps one slice is alone with weight exactly 1, so a single table lookup
# suffices there.  Per stratum a row is therefore a sequence of segments in
# slice order, pure(n), blend(n, n+1), pure(n+1), ..., whose ends come from the
# affine form, and each slice's affine texel coordinate is computed once.  A
# sample a rounding away from a segment end gets the same value to 1e-7 either
# way, because the ramp saturates there.  The inner loops are branch-free and
# the index loops vectorise.
# ---------------------------------------------------------------------------

# Each segment (samples o .. o+m-1 of the row) is done in loops indexed from 0: j into
# the scratch arrays, o + j into the row.  Indices are unsigned, so numba emits no
# negative-index wrap-around and the first loop, branch-free, vectorises (array views
# would cost reference counting per segment).  It turns positions into texel indices,
# fractions and weights; the second gathers table texels, which has to stay scalar.


@numba.njit(cache=True, fastmath=False, inline="always")
def _texels(xs, o, m, a, b, fN, inv_N, I, T):
    # texel coordinate tau = x a + b -> wrapped texel index I (padded table) and fraction T
    for j in range(np.uint64(m)):
        tau = xs[o + j] * a + b
        j0 = np.floor(tau)
        I[j] = np.int32(j0 - fN * np.floor(j0 * inv_N)) + np.int32(1)  # j0 mod N, exact below 2^24
        T[j] = tau - j0


@numba.njit(cache=True, fastmath=False, inline="always")
def _gather(I, T, W, tab, out, o, m):
    # out[o + j] += W[j] * lerp(tab[I], tab[I + 1], T)
    one = np.uint32(1)
    for j in range(np.uint64(m)):
        i = np.uint32(I[j])
        v = tab[i]
        out[o + j] += W[j] * (v + (tab[i + one] - v) * T[j])


@numba.njit(cache=True, fastmath=False, inline="always")
def _gather_amp(I, T, amp, tab, out, o, m):
    # out[o + j] += amp * lerp(tab[I], tab[I + 1], T)
    one = np.uint32(1)
    for j in range(np.uint64(m)):
        i = np.uint32(I[j])
        v = tab[i]
        out[o + j] += amp * (v + (tab[i + one] - v) * T[j])


@numba.njit(cache=True, fastmath=False, inline="always")
def _pure(xs, o, m, a, b, amp, tre, tim, fN, inv_N, ore, oim, want_imag, I, T):
    # one slice alone (its weight is exactly 1): amp * T(x a + b)
    _texels(xs, o, m, a, b, fN, inv_N, I, T)
    _gather_amp(I, T, amp, tre, ore, o, m)
    if want_imag:
        _gather_amp(I, T, amp, tim, oim, o, m)


@numba.njit(cache=True, fastmath=False, inline="always")
def _blend(xs, o, m, sx, q, fn, sp, a0, b0, a1, b1, amp, tre, tim, fN, inv_N, ore, oim, want_imag,
           I0, I1, T0, T1, W0, W1):
    # border ramp: amp * (cos(pi/2 s) T(x a0 + b0) + sin(pi/2 s) T(x a1 + b1))
    c = np.float32(0.5 / 0.3)
    for j in range(np.uint64(m)):
        u = ((xs[o + j] * sx + q) - fn - sp) * c + np.float32(0.5)
        u = min(max(u, np.float32(0.0)), np.float32(1.0))
        s = u * u * (np.float32(3.0) - np.float32(2.0) * u)
        W0[j] = amp * _cos_half_pi(s)
        W1[j] = amp * _cos_half_pi(np.float32(1.0) - s)
    _texels(xs, o, m, a0, b0, fN, inv_N, I0, T0)
    _texels(xs, o, m, a1, b1, fN, inv_N, I1, T1)
    _gather(I0, T0, W0, tre, ore, o, m)
    _gather(I1, T1, W1, tre, ore, o, m)
    if want_imag:
        _gather(I0, T0, W0, tim, oim, o, m)
        _gather(I1, T1, W1, tim, oim, o, m)


@numba.njit(cache=True, fastmath=False, inline="always")
def _row_affine(p, shift, inv_period, zeta, fN):
    # texel coordinate offset b of x * a + b, reduced mod N in float64 so it stays small
    c = ((np.float64(p) - np.float64(shift)) * np.float64(inv_period) + np.float64(zeta)) * np.float64(fN)
    c = c - np.float64(fN) * np.floor(c / np.float64(fN))
    return np.float32(c - 0.5)


@numba.njit(parallel=True, cache=True, fastmath=False, nogil=True)
def _rows_kernel(xs, others, sdirs, soffs, amps, nmin, slpos, omega, zeta, tre, tim, inv_period, shift,
                 want_imag, blocks, out_re, out_im):
    R = others.shape[0]
    Nx = xs.shape[0]
    K, D = sdirs.shape
    fN = np.float32(tre.shape[0] - 2)
    inv_N = np.float32(1.0) / fN
    x0 = xs[0]
    h = (np.float64(xs[Nx - 1]) - np.float64(x0)) / (Nx - 1) if Nx > 1 else 1.0
    nblk = max(1, min(R, blocks))
    for blk in numba.prange(nblk):
        # scratch, once per block of rows: texel indices, fractions and weights of two slices
        I0 = np.empty(Nx, np.int32)
        I1 = np.empty(Nx, np.int32)
        T0 = np.empty(Nx, np.float32)
        T1 = np.empty(Nx, np.float32)
        W0 = np.empty(Nx, np.float32)
        W1 = np.empty(Nx, np.float32)
        for r in range(blk * R // nblk, (blk + 1) * R // nblk):
            ore = out_re[r]
            oim = out_im[r] if want_imag else out_im[0]
            ore[:] = 0.0
            if want_imag:
                oim[:] = 0.0
            for k in range(K):
                sx = sdirs[k, 0]
                q = np.float32(0.0)
                for d in range(1, D):
                    q += others[r, d - 1] * sdirs[k, d]
                q = q + soffs[k]
                _stratum_row(xs, x0, h, sx, q, k, r, others, amps[k], nmin, slpos, omega, zeta, tre, tim,
                             inv_period, shift, fN, inv_N, ore, oim, want_imag, I0, I1, T0, T1, W0, W1)


@numba.njit(cache=True, fastmath=False, inline="always")
def _slice_affine(k, r, ri, others, omega, zeta, shift, inv_period, fN):
    # texel coordinate of slice record ri along the row: x * a + b
    D = omega.shape[2]
    p = np.float32(0.0)
    for d in range(1, D):
        p += others[r, d - 1] * omega[k, ri, d]
    return omega[k, ri, 0] * (inv_period * fN), _row_affine(p, shift, inv_period, zeta[k, ri], fN)


@numba.njit(cache=True, fastmath=False, inline="always")
def _stratum_row(xs, x0, h, sx, q, k, r, others, amp, nmin, slpos, omega, zeta, tre, tim, inv_period, shift,
                 fN, inv_N, ore, oim, want_imag, I0, I1, T0, T1, W0, W1):
    """Stratum k's waves along one row, in segments ordered by slice.

    Along the row p = x s_x + q is affine.  Slice m's border ramp towards m + 1 covers
    p in [m + slpos_m - 0.3, m + slpos_m + 0.3], inside slice m; between two ramps
    one slice is alone (weight exactly 1).  So the row is: pure(m), blend(m, m+1),
    pure(m+1), blend(m+1, m+2), ... and every slice's affine texel coordinate
    is computed once.  A sample a rounding away from a segment end gets the same
    value to 1e-7 either way, because the ramp saturates there.
    """
    Nx = xs.shape[0]
    hs = h * np.float64(sx)
    if hs == 0.0 or Nx == 1:  # one slice coordinate for the whole row: the general ramp
        n = np.floor(xs[0] * sx + q)
        ri = np.int64(n - nmin[k])
        a0, b0 = _slice_affine(k, r, ri, others, omega, zeta, shift, inv_period, fN)
        a1, b1 = _slice_affine(k, r, ri + 1, others, omega, zeta, shift, inv_period, fN)
        _blend(xs, np.uint64(0), Nx, sx, q, n, slpos[k, ri], a0, b0, a1, b1, amp, tre, tim, fN, inv_N, ore, oim,
               want_imag, I0, I1, T0, T1, W0, W1)
        return
    P0 = np.float64(x0) * np.float64(sx) + np.float64(q)
    inv_hs = 1.0 / hs
    pa = xs[0] * sx + q
    pb = xs[Nx - 1] * sx + q
    nlo = np.floor(min(pa, pb))
    nhi = np.floor(max(pa, pb))
    lo_ri = np.int64(nlo - nmin[k]) - 1  # record of slice nlo - 1 (records start one slice early)
    hi_ri = np.int64(nhi - nmin[k])
    up = hs > 0.0
    cur = 0
    # slices in the order the row meets them; (a, b) of the slice met last is carried over
    m_ri = lo_ri if up else hi_ri + 1
    am, bm = _slice_affine(k, r, m_ri, others, omega, zeta, shift, inv_period, fN)
    count = hi_ri - lo_ri + 1
    for step in range(count):
        ri = lo_ri + step if up else hi_ri - step  # the ramp between records ri and ri + 1
        n = nmin[k] + np.float32(ri)
        sp = slpos[k, ri]
        e_lo = np.float64(n) + np.float64(sp) - 0.3
        e_hi = np.float64(n) + np.float64(sp) + 0.3
        j_lo = min(max(np.int64(np.ceil((e_lo - P0) * inv_hs)), 0), Nx)
        j_hi = min(max(np.int64(np.ceil((e_hi - P0) * inv_hs)), 0), Nx)
        j_in, j_out = (j_lo, j_hi) if up else (j_hi, j_lo)
        if up:
            a_lo, b_lo = am, bm  # record ri, met before the ramp
            a_hi, b_hi = _slice_affine(k, r, ri + 1, others, omega, zeta, shift, inv_period, fN)
            an, bn = a_hi, b_hi
        else:
            a_hi, b_hi = am, bm  # record ri + 1, met before the ramp
            a_lo, b_lo = _slice_affine(k, r, ri, others, omega, zeta, shift, inv_period, fN)
            an, bn = a_lo, b_lo
        if j_in > cur:  # the slice met before this ramp, alone
            _pure(xs, np.uint64(cur), j_in - cur, am, bm, amp, tre, tim, fN, inv_N, ore, oim, want_imag, I0, T0)
            cur = j_in
        if j_out > cur:
            _blend(xs, np.uint64(cur), j_out - cur, sx, q, n, sp, a_lo, b_lo, a_hi, b_hi, amp, tre, tim, fN,
                   inv_N, ore, oim, want_imag, I0, I1, T0, T1, W0, W1)
            cur = j_out
        am, bm = an, bn
    if cur < Nx:  # the last slice, alone to the row's end
        _pure(xs, np.uint64(cur), Nx - cur, am, bm, amp, tre, tim, fN, inv_N, ore, oim, want_imag, I0, T0)
