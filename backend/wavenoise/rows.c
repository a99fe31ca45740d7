/* Wave noise on grid rows: the compiled kernel of backend/wavenoise/fast.py (GridPlan.rows) in C.
 *
 * The same sum as the numba row kernel, which stays the reference (Guehl et al. 2025, Alg. 1): along a
 * row, stratum k's slice coordinate p = x s_x + q is affine; slice n's wave is read from the complex
 * table at the affine texel coordinate tau = x a_n + b_n and linearly interpolated (Eq. 8), and inside
 * slice n's border ramp (half-width 0.3 around n + slpos_n) slices n and n + 1 are blended with the
 * weights cos(pi/2 s) and cos(pi/2 (1 - s)).  Two ways along a row:
 *
 *   segment walk (stratum_row)  pure(n), blend(n, n+1), pure(n+1), ...: segment ends from the affine
 *                               form in float64, a single table read where a slice is alone.  Used
 *                               where slices have SEGMENT_WALK (16) samples or more and on CPUs
 *                               without AVX2.  The scalar loops are numba's operations one for one (no
 *                               fused multiply-adds): the same bits.  The AVX2 loops compute texel
 *                               coordinates the same way, fuse the lerps, the ramp's weights and
 *                               sums, and write a stratum's terms into a scratch row (pure_avx2).
 *   blocks (stratum_blocks)     eight samples at a time, each lane finding its own slice and blending
 *                               n and n + 1 with weights that are exactly (amp, 0) or (0, amp) outside
 *                               the ramp: no per-segment bookkeeping, which dominates very short
 *                               slices (small grids).  Texel coordinates as the reference; fused
 *                               multiply-adds in the lerps, weights and sums, and the weights' cosine
 *                               from a shorter (minimax) polynomial: within 1e-6 of it.
 *
 * The AVX2 loops count operations (each one saved was measurable on a 3D grid): a power-of-two
 * table size wraps texel indices with an integer and, the tables are addressed from their texel 1, the
 * amplitude multiplies the blended sum once, and the walk's bookkeeping is compiled for AVX2 too (its
 * float64 floor and ceil become single instructions).
 *
 * Table reads, which numba leaves scalar, in one of two ways (the same texels, so the same bits; the
 * caller picks the faster on its CPU, see ckernel.py): "window", where the eight texels of one read lie
 * within 16 consecutive texels (usually: the texel step per sample is small on a grid) two vector loads
 * and a permute, elsewhere a gather; or "gather", an AVX2 gather always.  A lerp reads the value T[i] and
 * the forward difference D[i] = T[i+1] - T[i] (the reference computes that difference in float32 too).
 *
 * Arrays (all C-contiguous, float32 unless said):
 *   xs (Nx) ascending uniform row coordinates; others (R, D-1) the row's other coordinates;
 *   sdirs (K, D), soffs (K), amps (K): strata; nmin (K), slpos (K, S), omega (K, S, D), zeta (K, S):
 *   slice records (see fast._slice_records); tre, tim, dre, dim: (N + 2 + PAD) padded table values
 *   and differences, texel i + 1 holds T[i mod N]; out_re, out_im (R, Nx).
 *
 * Points (omni_points): the same sum at any points, one point at a time, numba's point kernel
 * (fast_kernels._kernel) operation for operation, without fused multiply-adds: the same bits (compiled for AVX2
 * too, where floor is one instruction, and chosen at run time).  Arrays: x (P, D) points;
 * strata and slice records as above; tab (N + 2, 2) the padded table as (re, im) pairs, texel i + 1 holding
 * T[i mod N] (fast._padded_table); out_re, out_im (P).
 *
 * Cells (omni_cells): the distance loop of backend/solid/procedural/cells.voronoi, F1 and F2 of a jittered grid
 * (Worley 1996) over a batch of neighbour cubes, numpy's float32 operations one for one: the same bits.  Arrays:
 * local (P, 3) each point's position in its cube; back (P) int64 its cube's row in hashes; near (B, 3) the batch's
 * neighbour offsets; hashes (B, C, 3) each neighbour cube's feature point offset (before the jitter); f1, f2 (P)
 * and which (P) int64, the nearest feature point's neighbour index, updated in place.
 *
 * Build: tools/build_kernel.py (cc -O3 -ffp-contract=off -shared -fPIC; the AVX2 loops carry a target
 * attribute and are chosen at run time, so the library runs on any x86-64 CPU, and elsewhere scalar).
 * Loaded by ctypes; the call releases the GIL, so Python threads split the rows.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#if defined(__x86_64__) || defined(_M_X64)
#define OMNI_X86 1
#include <cpuid.h>
#include <immintrin.h>
#define AVX2 __attribute__((target("avx2,fma")))
#endif

#define OMNI_ABI 2
#ifdef _WIN32
#define OMNI_API __declspec(dllexport)
#else
#define OMNI_API __attribute__((visibility("default")))
#endif
/* Slices of at least this many samples take the segment walk, shorter ones the blocks.  Since the walk writes
 * scratch rows (pure_avx2), 16 was as fast as any of 0, 8, 16 and 24 at 3D 128³ and 64³ and faster than 48
 * (128³: 11.6 against 14.2-14.7 ns per sample, and 16.7 against 18.4 with gathered table reads), while at 32³
 * (slices of 6 to 9 samples) the blocks were faster than the walk (AMD EPYC, 2 threads).
 * It was 48 when the walk added into the output in place (Sapphire Rapids). */
#ifndef SEGMENT_WALK
#define SEGMENT_WALK 16
#endif

typedef struct {
  const float *xs;
  const float *others, *sdirs, *soffs, *amps;
  const float *nmin, *slpos, *omega, *zeta;
  const float *tre, *tim, *dre, *dim;
  float *out_re, *out_im;
  int64_t Nx, K, D, S;
  float fN, inv_N, inv_period, shift;
  int want_imag, vector, gather, pow2;
} job_t;

static inline void slice_affine(const job_t *J, int64_t k, int64_t r, int64_t ri, float *a, float *b);

/* numba's float32 constants: the double rounded to float (a float literal could round differently) */
#define C_HALF_PI ((float)1.5707963267948966)
#define C_24 ((float)(1.0 / 24))
#define C_720 ((float)(-1.0 / 720))
#define C_40320 ((float)(1.0 / 40320))
#define C_3628800 ((float)(-1.0 / 3628800))
#define C_479001600 ((float)(1.0 / 479001600))

/* cos(pi/2 s), s in [0, 1]: Taylor series of cos to x^12 (error < 5e-7), fast._cos_half_pi */
static inline float cos_half_pi(float s) {
  float x = C_HALF_PI * s, x2 = x * x;
  return 1.0f + x2 * (-0.5f + x2 * (C_24 + x2 * (C_720 + x2 * (C_40320 + x2 * (C_3628800 + x2 * C_479001600)))));
}

/* texel coordinate -> padded texel index and fraction (fast._texels) */
static inline int32_t texel(float tau, float fN, float inv_N, float *t) {
  float j0 = floorf(tau);
  *t = tau - j0;
  return (int32_t)(j0 - fN * floorf(j0 * inv_N)) + 1;
}

static void pure_scalar(const job_t *J, int64_t o, int64_t m, float a, float b, float amp, float *ore, float *oim) {
  for (int64_t j = o; j < o + m; j++) {
    float t;
    int32_t i = texel(J->xs[j] * a + b, J->fN, J->inv_N, &t);
    ore[j] += amp * (J->tre[i] + J->dre[i] * t);
    if (J->want_imag) oim[j] += amp * (J->tim[i] + J->dim[i] * t);
  }
}

static void blend_scalar(const job_t *J, int64_t o, int64_t m, float sx, float q, float fn, float sp, float a0,
                         float b0, float a1, float b1, float amp, float *ore, float *oim) {
  const float c = (float)(0.5 / 0.3);
  for (int64_t j = o; j < o + m; j++) {
    float x = J->xs[j];
    float u = ((x * sx + q) - fn - sp) * c + 0.5f;
    u = fminf(fmaxf(u, 0.0f), 1.0f);
    float s = u * u * (3.0f - 2.0f * u);
    float w0 = amp * cos_half_pi(s), w1 = amp * cos_half_pi(1.0f - s), t0, t1;
    int32_t i0 = texel(x * a0 + b0, J->fN, J->inv_N, &t0), i1 = texel(x * a1 + b1, J->fN, J->inv_N, &t1);
    ore[j] += w0 * (J->tre[i0] + J->dre[i0] * t0);
    ore[j] += w1 * (J->tre[i1] + J->dre[i1] * t1);
    if (J->want_imag) {
      oim[j] += w0 * (J->tim[i0] + J->dim[i0] * t0);
      oim[j] += w1 * (J->tim[i1] + J->dim[i1] * t1);
    }
  }
}

#ifdef OMNI_X86
/* lanes < m of eight samples (m < 8: the row's last ones) */
AVX2 static inline __m256i lane_mask(int64_t m) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32((int)m), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

/* cos(pi/2 s), s in [0, 1], as an even polynomial 1 + y (c1 + y (c2 + y (c3 + y c4))) in y = s^2 with
 * minimax coefficients (fitted by Lawson's iteration on 20001 Chebyshev points; the constant exactly 1, so
 * a weight before the ramp is exactly amp): error 5.3e-8 against cos, about float32's rounding, where
 * cos_half_pi's Taylor series takes three operations more */
#define CM1 (-1.23369888e+00f)
#define CM2 (2.53653209e-01f)
#define CM3 (-2.08139667e-02f)
#define CM4 (8.59690055e-04f)
AVX2 static inline __m256 cos_half_pi8(__m256 s) {
  __m256 y = _mm256_mul_ps(s, s);
  __m256 p = _mm256_fmadd_ps(y, _mm256_set1_ps(CM4), _mm256_set1_ps(CM3));
  p = _mm256_fmadd_ps(y, p, _mm256_set1_ps(CM2));
  p = _mm256_fmadd_ps(y, p, _mm256_set1_ps(CM1));
  return _mm256_fmadd_ps(y, p, _mm256_set1_ps(1.0f));
}

/* The border ramp's position u = (p - n - sp) c + 1/2 (c = 1/(2 * 0.3)) as (p - n) c + ramp_offset(sp): the offset
 * of slice n's ramp centre sp, once per slice record instead of once per sample */
static inline float ramp_offset(float sp) { return 0.5f - sp * (float)(0.5 / 0.3); }

/* Eight texels: with ``gather`` 0, from two loads and a permute where the lanes' texels lie within 16
 * consecutive ones (the texel step per sample is small on a grid), else a gather; with ``gather`` 1 a
 * gather always (faster on CPUs with fast gathers, such as Intel's Sapphire Rapids). */
typedef struct { __m256i i, rel; __m256 hi; int base, win; } texels8;

AVX2 static inline texels8 texels(const job_t *J, __m256 tau, __m256 fN, __m256 inv_N, __m256 *t) {
  texels8 T;
  __m256 j0 = _mm256_floor_ps(tau);  /* texel() in eight lanes: the same texel, less the padding's + 1 */
  *t = _mm256_sub_ps(tau, j0);
  if (J->pow2) {  /* j0 mod N for N = 2^k (|j0| < 2^24): an integer and gives what texel()'s floats give */
    T.i = _mm256_and_si256(_mm256_cvttps_epi32(j0), _mm256_set1_epi32(J->pow2 - 1));
  } else {
    T.i = _mm256_cvttps_epi32(_mm256_sub_ps(j0, _mm256_mul_ps(fN, _mm256_floor_ps(_mm256_mul_ps(j0, inv_N)))));
  }
  if (J->gather) {
    T.rel = T.i, T.hi = _mm256_setzero_ps(), T.base = 0, T.win = 0;
    return T;
  }
  __m256i base = _mm256_min_epi32(_mm256_permutevar8x32_epi32(T.i, _mm256_setzero_si256()),
                                  _mm256_permutevar8x32_epi32(T.i, _mm256_set1_epi32(7)));
  T.rel = _mm256_sub_epi32(T.i, base);
  __m256i bad = _mm256_or_si256(_mm256_cmpgt_epi32(T.rel, _mm256_set1_epi32(15)),
                                _mm256_cmpgt_epi32(_mm256_setzero_si256(), T.rel));
  T.win = _mm256_testz_si256(bad, bad);
  T.base = _mm256_cvtsi256_si32(base);
  T.hi = _mm256_castsi256_ps(_mm256_cmpgt_epi32(T.rel, _mm256_set1_epi32(7)));
  return T;
}

AVX2 static inline __m256 fetch(const float *tab, const texels8 *T) {
  if (T->win)
    return _mm256_blendv_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(tab + T->base), T->rel),
                            _mm256_permutevar8x32_ps(_mm256_loadu_ps(tab + T->base + 8), T->rel), T->hi);
  return _mm256_i32gather_ps(tab, T->i, 4);
}

/* one record per lane: from registers when the row has at most eight records, else from memory */
AVX2 static inline __m256 pick(const float *rec, __m256 reg, int regs, __m256i idx) {
  return regs ? _mm256_permutevar8x32_ps(reg, idx) : _mm256_i32gather_ps(rec, idx, 4);
}

/* out[j .. j + m) += the first m lanes of v (m < 8: the row's last samples) */
AVX2 static inline void add_out(float *out, int64_t j, int64_t m, __m256 v) {
  if (m >= 8) {
    _mm256_storeu_ps(out + j, _mm256_add_ps(_mm256_loadu_ps(out + j), v));
  } else {
    __m256i k = lane_mask(m);
    _mm256_maskstore_ps(out + j, k, _mm256_add_ps(_mm256_maskload_ps(out + j, k), v));
  }
}

/* T(tau) and, if wanted, its imaginary part: value + difference * fraction, the texels read by fetch() */
AVX2 static inline void lerp8(const job_t *J, __m256 tau, __m256 fN, __m256 inv_N, __m256 *re, __m256 *im) {
  __m256 t;
  texels8 T = texels(J, tau, fN, inv_N, &t);  /* indices from the tables' texel 1: T[0] */
  *re = _mm256_fmadd_ps(fetch(J->dre + 1, &T), t, fetch(J->tre + 1, &T));
  if (J->want_imag) *im = _mm256_fmadd_ps(fetch(J->dim + 1, &T), t, fetch(J->tim + 1, &T));
}

/* The segment walk's loops (stratum_row_avx2), eight samples at a time.  They write a stratum's terms into a
 * scratch row (Nx + 8 floats) with full-width stores and no loads: a segment's last, partial block writes past
 * the segment's end, and the next segment (the walk goes left to right) overwrites those lanes; the row's
 * coordinates are padded (omni_rows), so every load is a full one too.  The scratch row is added to the output
 * row one stratum later (omni_rows), when its stores have left the store buffer.  The earlier loops added into
 * the output row segment by segment with masked loads and stores at the segments' ends, and each segment's
 * first block loaded what the previous segment's last masked store had just written, partly: a load the CPU
 * cannot forward from a store, so it waited for the store to complete.  Texel coordinates and the ramp's
 * position p = x s_x + q exactly as the reference computes them; the lerps, the ramp's weights and sums with
 * fused multiply-adds, the amplitude applied once (within 2e-6 of the reference, tested). */
AVX2 static inline __attribute__((always_inline)) void pure_avx2(const job_t *J, int64_t o, int64_t m, float a,
                                                                 float b, float amp, float *sre, float *sim) {
  const __m256 va = _mm256_set1_ps(a), vb = _mm256_set1_ps(b), vamp = _mm256_set1_ps(amp);
  const __m256 fN = _mm256_set1_ps(J->fN), inv_N = _mm256_set1_ps(J->inv_N);
  for (int64_t j = o; j < o + m; j += 8) {
    __m256 x = _mm256_loadu_ps(J->xs + j), re, im;  /* the padded coordinates (omni_rows) */
    lerp8(J, _mm256_add_ps(_mm256_mul_ps(x, va), vb), fN, inv_N, &re, &im);
    _mm256_storeu_ps(sre + j, _mm256_mul_ps(vamp, re));
    if (J->want_imag) _mm256_storeu_ps(sim + j, _mm256_mul_ps(vamp, im));
  }
}

AVX2 static inline __attribute__((always_inline)) void blend_avx2(const job_t *J, int64_t o, int64_t m, float sx,
                                                                  float q, float fn, float sp, float a0, float b0,
                                                                  float a1, float b1, float amp, float *sre,
                                                                  float *sim) {
  const __m256 vsx = _mm256_set1_ps(sx), vq = _mm256_set1_ps(q), vfn = _mm256_set1_ps(fn);
  const __m256 voff = _mm256_set1_ps(ramp_offset(sp));
  const __m256 c = _mm256_set1_ps((float)(0.5 / 0.3)), one = _mm256_set1_ps(1.0f);
  const __m256 two = _mm256_set1_ps(2.0f), three = _mm256_set1_ps(3.0f);
  const __m256 vamp = _mm256_set1_ps(amp), fN = _mm256_set1_ps(J->fN), inv_N = _mm256_set1_ps(J->inv_N);
  const __m256 va0 = _mm256_set1_ps(a0), vb0 = _mm256_set1_ps(b0), va1 = _mm256_set1_ps(a1), vb1 = _mm256_set1_ps(b1);
  for (int64_t j = o; j < o + m; j += 8) {
    __m256 x = _mm256_loadu_ps(J->xs + j), re0, im0, re1, im1;
    __m256 u = _mm256_fmadd_ps(_mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(x, vsx), vq), vfn), c, voff);
    /* min(max(u, 0), 1) as numba's: NaN cannot occur (finite coordinates) */
    u = _mm256_min_ps(_mm256_max_ps(u, _mm256_setzero_ps()), one);
    __m256 s = _mm256_mul_ps(_mm256_mul_ps(u, u), _mm256_fnmadd_ps(two, u, three));
    __m256 w0 = cos_half_pi8(s), w1 = cos_half_pi8(_mm256_sub_ps(one, s));
    lerp8(J, _mm256_add_ps(_mm256_mul_ps(x, va0), vb0), fN, inv_N, &re0, &im0);
    lerp8(J, _mm256_add_ps(_mm256_mul_ps(x, va1), vb1), fN, inv_N, &re1, &im1);
    _mm256_storeu_ps(sre + j, _mm256_mul_ps(vamp, _mm256_fmadd_ps(w1, re1, _mm256_mul_ps(w0, re0))));
    if (J->want_imag)
      _mm256_storeu_ps(sim + j, _mm256_mul_ps(vamp, _mm256_fmadd_ps(w1, im1, _mm256_mul_ps(w0, im0))));
  }
}

/* out row (Nx) += scratch row */
AVX2 static void walk_add(int64_t Nx, const float *sc, float *out) {
  int64_t j = 0;
  for (; j + 8 <= Nx; j += 8)
    _mm256_storeu_ps(out + j, _mm256_add_ps(_mm256_loadu_ps(out + j), _mm256_loadu_ps(sc + j)));
  if (j < Nx) add_out(out, j, Nx - j, _mm256_loadu_ps(sc + j));
}

/* adds a walked stratum's scratch rows (re at pend, im at pend + Nx + 8) to the output row, if any; returns NULL */
AVX2 static float *add_pending(const job_t *J, float *pend, float *ore, float *oim) {
  if (pend) {
    walk_add(J->Nx, pend, ore);
    if (J->want_imag) walk_add(J->Nx, pend + J->Nx + 8, oim);
  }
  return 0;
}

/* Stratum k's waves along row r, eight samples at a time.  Every lane finds its slice n = floor(p) and
 * blends slices n and n + 1 by n's border ramp (Alg. 1).  Before the ramp (u <= 0) the weights are exactly
 * (amp, 0) and after it (u >= 1) exactly (0, amp), so a lane outside the ramp gets its single slice's
 * amp T(tau) as in the reference's pure segments; what differs from the segment walk (stratum_row) is
 * the rounding of the fused multiply-adds of the weights and the sums (< 1e-6), and a sample a rounding
 * apart from a saturated ramp end.  Texel coordinates are computed exactly as the reference does.
 * A, B, SP: scratch of at least (the row's records) + 9 floats each. */
AVX2 static void stratum_blocks(const job_t *J, float sx, float q, int64_t k, int64_t r, float amp, float *ore,
                                float *oim, float *A, float *B, float *SP) {
  const int64_t Nx = J->Nx;
  const float *xs = J->xs, *slp = J->slpos + k * J->S, nmk = J->nmin[k];
  const int imag = J->want_imag;
  float pa = xs[0] * sx + q, pb = xs[Nx - 1] * sx + q;
  float nlo = floorf(pa < pb ? pa : pb), nhi = floorf(pa > pb ? pa : pb);
  int64_t ri0 = (int64_t)(nlo - nmk), cnt = (int64_t)(nhi - nlo) + 2;  /* records of slices nlo .. nhi + 1 */
  for (int64_t i = 0; i < cnt; i++) {
    slice_affine(J, k, r, ri0 + i, &A[i], &B[i]);
    SP[i] = ramp_offset(slp[ri0 + i]);
  }
  for (int64_t i = cnt; i < cnt + 9; i++) A[i] = B[i] = SP[i] = 0.0f;
  const int regs = cnt <= 8;
  const __m256 a0t = _mm256_loadu_ps(A), b0t = _mm256_loadu_ps(B), a1t = _mm256_loadu_ps(A + 1);
  const __m256 b1t = _mm256_loadu_ps(B + 1), spt = _mm256_loadu_ps(SP);
  const __m256 vsx = _mm256_set1_ps(sx), vq = _mm256_set1_ps(q), vnlo = _mm256_set1_ps(nlo);
  const __m256 c = _mm256_set1_ps((float)(0.5 / 0.3)), one = _mm256_set1_ps(1.0f);
  const __m256 zero = _mm256_setzero_ps(), vamp = _mm256_set1_ps(amp);
  const __m256 fN = _mm256_set1_ps(J->fN), inv_N = _mm256_set1_ps(J->inv_N);
  for (int64_t j = 0; j < Nx; j += 8) {
    int64_t m = Nx - j;
    __m256i km = lane_mask(m < 8 ? m : 8);
    __m256 x;
    if (m >= 8) {
      x = _mm256_loadu_ps(xs + j);
    } else {  /* lanes past the row repeat its last sample: valid slices and texels */
      x = _mm256_blendv_ps(_mm256_set1_ps(xs[Nx - 1]), _mm256_maskload_ps(xs + j, km), _mm256_castsi256_ps(km));
    }
    __m256 p = _mm256_add_ps(_mm256_mul_ps(x, vsx), vq), n = _mm256_floor_ps(p);
    __m256i idx = _mm256_cvttps_epi32(_mm256_sub_ps(n, vnlo)), idx1 = _mm256_add_epi32(idx, _mm256_set1_epi32(1));
    __m256 sp = pick(SP, spt, regs, idx);
    __m256 u = _mm256_fmadd_ps(_mm256_sub_ps(p, n), c, sp);
    u = _mm256_min_ps(_mm256_max_ps(u, zero), one);
    __m256 s = _mm256_mul_ps(_mm256_mul_ps(u, u), _mm256_fnmadd_ps(_mm256_set1_ps(2.0f), u, _mm256_set1_ps(3.0f)));
    __m256 w0 = _mm256_andnot_ps(_mm256_cmp_ps(u, one, _CMP_GE_OQ), cos_half_pi8(s));
    __m256 w1 = _mm256_andnot_ps(_mm256_cmp_ps(u, zero, _CMP_LE_OQ), cos_half_pi8(_mm256_sub_ps(one, s)));
    __m256 tau0 = _mm256_add_ps(_mm256_mul_ps(x, pick(A, a0t, regs, idx)), pick(B, b0t, regs, idx));
    __m256 tau1 = _mm256_add_ps(_mm256_mul_ps(x, regs ? _mm256_permutevar8x32_ps(a1t, idx) : pick(A, a1t, 0, idx1)),
                                regs ? _mm256_permutevar8x32_ps(b1t, idx) : pick(B, b1t, 0, idx1));
    __m256 l0, l1, li0 = zero, li1 = zero;
    lerp8(J, tau0, fN, inv_N, &l0, &li0);
    lerp8(J, tau1, fN, inv_N, &l1, &li1);
    __m256 acc = m >= 8 ? _mm256_loadu_ps(ore + j) : _mm256_maskload_ps(ore + j, km);
    acc = _mm256_fmadd_ps(vamp, _mm256_fmadd_ps(w1, l1, _mm256_mul_ps(w0, l0)), acc);
    if (m >= 8) _mm256_storeu_ps(ore + j, acc); else _mm256_maskstore_ps(ore + j, km, acc);
    if (imag) {
      acc = m >= 8 ? _mm256_loadu_ps(oim + j) : _mm256_maskload_ps(oim + j, km);
      acc = _mm256_fmadd_ps(vamp, _mm256_fmadd_ps(w1, li1, _mm256_mul_ps(w0, li0)), acc);
      if (m >= 8) _mm256_storeu_ps(oim + j, acc); else _mm256_maskstore_ps(oim + j, km, acc);
    }
  }
}
#endif

/* b of tau = x a + b, reduced mod N in float64 (fast._row_affine) */
static inline float row_affine(float p, float shift, float inv_period, float zeta, float fN) {
  double c = (((double)p - (double)shift) * (double)inv_period + (double)zeta) * (double)fN;
  c = c - (double)fN * floor(c / (double)fN);
  return (float)(c - 0.5);
}

/* slice record ri of stratum k on row r: a and b (fast._slice_affine) */
static inline void slice_affine(const job_t *J, int64_t k, int64_t r, int64_t ri, float *a, float *b) {
  const float *om = J->omega + (k * J->S + ri) * J->D, *oth = J->others + r * (J->D - 1);
  float p = 0.0f;
  for (int64_t d = 1; d < J->D; d++) p += oth[d - 1] * om[d];
  *a = om[0] * (J->inv_period * J->fN);
  *b = row_affine(p, J->shift, J->inv_period, J->zeta[k * J->S + ri], J->fN);
}

static inline int64_t clamp_index(double v, int64_t Nx) {
  int64_t j = (int64_t)ceil(v);
  return j < 0 ? 0 : (j > Nx ? Nx : j);
}

typedef void (*pure_fn)(const job_t *, int64_t, int64_t, float, float, float, float *, float *);
typedef void (*blend_fn)(const job_t *, int64_t, int64_t, float, float, float, float, float, float, float, float,
                         float, float *, float *);

/* stratum k's waves along row r (fast._stratum_row), its segments by pure_seg and blend_seg: the scalar loops,
 * which add into ore, oim, or the AVX2 ones, which write scratch rows there */
static inline __attribute__((always_inline)) void stratum_row_(const job_t *J, double h, float x0, float sx, float q,
                                                               int64_t k, int64_t r, float amp, float *ore,
                                                               float *oim, pure_fn pure_seg, blend_fn blend_seg) {
  const int64_t Nx = J->Nx;
  const float *xs = J->xs, *slp = J->slpos + k * J->S, nmk = J->nmin[k];
  double hs = h * (double)sx;
  if (hs == 0.0 || Nx == 1) {
    float n = floorf(xs[0] * sx + q), a0, b0, a1, b1;
    int64_t ri = (int64_t)(n - nmk);
    slice_affine(J, k, r, ri, &a0, &b0);
    slice_affine(J, k, r, ri + 1, &a1, &b1);
    blend_seg(J, 0, Nx, sx, q, n, slp[ri], a0, b0, a1, b1, amp, ore, oim);
    return;
  }
  double P0 = (double)x0 * (double)sx + (double)q, inv_hs = 1.0 / hs;
  float pa = xs[0] * sx + q, pb = xs[Nx - 1] * sx + q;
  float nlo = floorf(pa < pb ? pa : pb), nhi = floorf(pa > pb ? pa : pb);
  int64_t lo_ri = (int64_t)(nlo - nmk) - 1, hi_ri = (int64_t)(nhi - nmk);
  int up = hs > 0.0;
  int64_t cur = 0, count = hi_ri - lo_ri + 1;
  float am, bm;
  slice_affine(J, k, r, up ? lo_ri : hi_ri + 1, &am, &bm);
  for (int64_t step = 0; step < count; step++) {
    int64_t ri = up ? lo_ri + step : hi_ri - step;
    float n = nmk + (float)ri, sp = slp[ri];
    double e_lo = (double)n + (double)sp - 0.3, e_hi = (double)n + (double)sp + 0.3;
    int64_t j_lo = clamp_index((e_lo - P0) * inv_hs, Nx), j_hi = clamp_index((e_hi - P0) * inv_hs, Nx);
    int64_t j_in = up ? j_lo : j_hi, j_out = up ? j_hi : j_lo;
    float a_lo, b_lo, a_hi, b_hi, an, bn;
    if (up) {
      a_lo = am, b_lo = bm;
      slice_affine(J, k, r, ri + 1, &a_hi, &b_hi);
      an = a_hi, bn = b_hi;
    } else {
      a_hi = am, b_hi = bm;
      slice_affine(J, k, r, ri, &a_lo, &b_lo);
      an = a_lo, bn = b_lo;
    }
    if (j_in > cur) {
      pure_seg(J, cur, j_in - cur, am, bm, amp, ore, oim);
      cur = j_in;
    }
    if (j_out > cur) {
      blend_seg(J, cur, j_out - cur, sx, q, n, sp, a_lo, b_lo, a_hi, b_hi, amp, ore, oim);
      cur = j_out;
    }
    am = an, bm = bn;
  }
  if (cur < Nx) pure_seg(J, cur, Nx - cur, am, bm, amp, ore, oim);
}

static void stratum_row(const job_t *J, double h, float x0, float sx, float q, int64_t k, int64_t r, float amp,
                        float *ore, float *oim) { stratum_row_(J, h, x0, sx, q, k, r, amp, ore, oim, pure_scalar, blend_scalar); }
#ifdef OMNI_X86
/* the same walk compiled for AVX2 CPUs (its float64 floor and ceil become single instructions), writing the
 * stratum's terms into the scratch rows sre, sim (Nx + 8 floats each; see pure_avx2) */
AVX2 static void stratum_row_avx2(const job_t *J, double h, float x0, float sx, float q, int64_t k, int64_t r,
                                  float amp, float *sre, float *sim) {
  stratum_row_(J, h, x0, sx, q, k, r, amp, sre, sim, pure_avx2, blend_avx2);
}
#endif

OMNI_API int omni_abi(void) { return OMNI_ABI; }

/* 1 where this CPU and its OS run the AVX2 + FMA loops: CPUID and XGETBV read directly (the compilers'
 * __builtin_cpu_supports needs a runtime that cross-compiled libraries may lack) */
OMNI_API int omni_vector(void) {
#ifdef OMNI_X86
  unsigned a, b, c, d, lo, hi;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return 0;
  if (!((c >> 27) & 1) || !((c >> 28) & 1) || !((c >> 12) & 1)) return 0;  /* OSXSAVE, AVX, FMA */
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
  if ((lo & 6) != 6) return 0;  /* the OS saves the YMM registers */
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return 0;
  return (b >> 5) & 1;  /* AVX2 */
#else
  return 0;
#endif
}

/* Rows r0 .. r1 - 1 (fast._rows_kernel).  vector: 0 the scalar loops; 1 the AVX2 loops with windowed table
 * reads, 2 with gathered ones (1 and 2 only where omni_vector()). */
OMNI_API void omni_rows(const float *xs, int64_t Nx, const float *others, int64_t r0, int64_t r1, const float *sdirs,
               const float *soffs, const float *amps, int64_t K, int64_t D, const float *nmin, const float *slpos,
               const float *omega, const float *zeta, int64_t S, const float *tre, const float *tim,
               const float *dre, const float *dim, int64_t N, float inv_period, float shift, int want_imag,
               int vector, float *out_re, float *out_im) {
  job_t J = {xs, others, sdirs, soffs, amps, nmin, slpos, omega, zeta, tre, tim, dre, dim, out_re, out_im,
             Nx, K, D, S, (float)N, 0.0f, inv_period, shift, want_imag, vector != 0, vector == 2, 0};
  J.pow2 = N > 0 && (N & (N - 1)) == 0 ? (int)N : 0;
  J.inv_N = 1.0f / J.fN;
  float x0 = xs[0], *A = 0;
  /* scratch: the blocks' records (3 (S + 16)), two pairs of scratch rows for the walk's terms (re, im) and the
   * padded row coordinates (Nx + 8 each) */
  const int64_t W = Nx + 8;
#ifdef OMNI_X86
  if (vector && !(A = malloc((3 * (S + 16) + 5 * W) * sizeof(float)))) vector = J.vector = J.gather = 0;  /* no memory */
#endif
  double h = Nx > 1 ? ((double)xs[Nx - 1] - (double)x0) / (double)(Nx - 1) : 1.0;
  float *scratch = A ? A + 3 * (S + 16) : 0;
  if (vector && scratch) {  /* the row's coordinates padded with its last one: the walk's blocks load eight */
    float *xp = scratch + 4 * W;
    for (int64_t j = 0; j < W; j++) xp[j] = xs[j < Nx ? j : Nx - 1];
    J.xs = xp;
  }
  for (int64_t r = r0; r < r1; r++) {
    float *ore = out_re + r * Nx, *oim = want_imag ? out_im + r * Nx : 0;
    for (int64_t j = 0; j < Nx; j++) ore[j] = 0.0f;
    if (want_imag)
      for (int64_t j = 0; j < Nx; j++) oim[j] = 0.0f;
    float *pend = 0;  /* the last walked stratum's scratch rows, added after the next stratum (strata in order) */
    for (int64_t k = 0; k < K; k++) {
      float q = 0.0f;
      for (int64_t d = 1; d < D; d++) q += others[r * (D - 1) + d - 1] * sdirs[k * D + d];
      q = q + soffs[k];
#ifdef OMNI_X86
      /* long slices (SEGMENT_WALK samples or more): the segment walk; else eight samples at a time */
      if (vector && !(fabs(h * (double)sdirs[k * D]) * SEGMENT_WALK < 1.0)) {
        pend = add_pending(&J, pend, ore, oim);
        stratum_blocks(&J, sdirs[k * D], q, k, r, amps[k], ore, oim, A, A + S + 16, A + 2 * (S + 16));
        continue;
      }
      if (vector) {
        float *sc = pend == scratch ? scratch + 2 * W : scratch;  /* the pair not pending */
        stratum_row_avx2(&J, h, x0, sdirs[k * D], q, k, r, amps[k], sc, sc + W);
        add_pending(&J, pend, ore, oim);
        pend = sc;
        continue;
      }
#endif
      stratum_row(&J, h, x0, sdirs[k * D], q, k, r, amps[k], ore, oim);
    }
#ifdef OMNI_X86
    add_pending(&J, pend, ore, oim);
#endif
  }
  free(A);
}

/* Points i0 .. i1 - 1 of x (P, D) (fast_kernels._kernel): out_re[i] + i out_im[i] the noise at x[i]. */
static inline __attribute__((always_inline)) void points_(const float *x, int64_t i0, int64_t i1, int64_t D,
    const float *sdirs, const float *soffs, const float *amps, int64_t K, const float *nmin, const float *slpos,
    const float *omega, const float *zeta, int64_t S, const float *tab, int64_t N, float inv_period, float shift,
    float *out_re, float *out_im) {
  const float fN = (float)N, half = 0.5f;
  for (int64_t i = i0; i < i1; i++) {
    const float *xi = x + i * D;
    float zr = 0.0f, zi = 0.0f;
    for (int64_t k = 0; k < K; k++) {
      float acc = 0.0f;
      for (int64_t d = 0; d < D; d++) acc += xi[d] * sdirs[k * D + d];
      float p = acc + soffs[k];
      float n = floorf(p);
      float f = p - n;
      int64_t r = (int64_t)(n - nmin[k]);
      float u = (f - slpos[k * S + r]) * (float)(0.5 / 0.3) + half;
      if (u < 0.0f) u = 0.0f;
      else if (u > 1.0f) u = 1.0f;
      float s = u * u * (3.0f - 2.0f * u);
      float w0 = cos_half_pi(s), w1 = cos_half_pi(1.0f - s);
      float br = 0.0f, bi = 0.0f;
      for (int side = 0; side < 2; side++) {
        int64_t rr = r + side;
        float dot = 0.0f;
        for (int64_t d = 0; d < D; d++) dot += xi[d] * omega[(k * S + rr) * D + d];
        float c = (dot - shift) * inv_period + zeta[k * S + rr];
        c = c - floorf(c);
        float j = c * fN - half;
        float j0 = floorf(j);
        float t = j - j0;
        int64_t idx = (int64_t)j0 + 1;
        float ar = tab[2 * idx] + (tab[2 * idx + 2] - tab[2 * idx]) * t;
        float ai = tab[2 * idx + 1] + (tab[2 * idx + 3] - tab[2 * idx + 1]) * t;
        float w = side == 0 ? w0 : w1;
        br += w * ar;
        bi += w * ai;
      }
      zr += amps[k] * br;
      zi += amps[k] * bi;
    }
    out_re[i] = zr;
    out_im[i] = zi;
  }
}

#define POINTS_ARGS const float *x, int64_t i0, int64_t i1, int64_t D, const float *sdirs, const float *soffs, \
    const float *amps, int64_t K, const float *nmin, const float *slpos, const float *omega, const float *zeta, \
    int64_t S, const float *tab, int64_t N, float inv_period, float shift, float *out_re, float *out_im
#define POINTS_CALL x, i0, i1, D, sdirs, soffs, amps, K, nmin, slpos, omega, zeta, S, tab, N, inv_period, shift, \
    out_re, out_im

#ifdef OMNI_X86
/* the same operations compiled for AVX2 CPUs: floor becomes one instruction (no fused multiply-adds: the same
 * bits) */
AVX2 static void points_avx2(POINTS_ARGS) { points_(POINTS_CALL); }
#endif

/* vector: 1 for the AVX2 build where omni_vector(), 0 for the scalar one (the same bits) */
OMNI_API void omni_points(POINTS_ARGS, int vector) {
#ifdef OMNI_X86
  if (vector && omni_vector()) {
    points_avx2(POINTS_CALL);
    return;
  }
#endif
  points_(POINTS_CALL);
}

/* Points i0 .. i1 - 1 against neighbours a0 .. a0 + B - 1 (cells.voronoi's loop): nearer feature points replace
 * F1 (and push it to F2) in neighbour order, as np.where(d < f1, ...) does. */
OMNI_API void omni_cells(const float *local, const int64_t *back, int64_t i0, int64_t i1, const float *near,
                         const float *hashes, int64_t B, int64_t C, int64_t a0, float jitter, float *f1, float *f2,
                         int64_t *which) {
  for (int64_t i = i0; i < i1; i++) {
    const float *l = local + 3 * i;
    float g1 = f1[i], g2 = f2[i];
    int64_t w = which[i];
    for (int64_t b = 0; b < B; b++) {
      const float *h = hashes + 3 * (b * C + back[i]), *n = near + 3 * b;
      float v0 = n[0] + h[0] * jitter - l[0], v1 = n[1] + h[1] * jitter - l[1], v2 = n[2] + h[2] * jitter - l[2];
      float d = sqrtf(v0 * v0 + v1 * v1 + v2 * v2);
      if (d < g1) {
        g2 = g1;
        g1 = d;
        w = a0 + b;
      } else if (d < g2) {
        g2 = d;
      }
    }
    f1[i] = g1;
    f2[i] = g2;
    which[i] = w;
  }
}
