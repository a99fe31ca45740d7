/* The floor of wave noise on a CPU grid: hand-vectorised AVX2 inner loops, no Python.
 *
 * Each sample of a K-direction wave noise reads, per direction, the complex table at an
 * affine coordinate and linearly interpolates it (Guehl et al. 2025, Eq. 8); inside a
 * slice's border ramp (60 % of a slice with the ramp half-width 0.3) it reads two slices
 * and weights them by cos / sin (Alg. 1).  This program times two idealised rows:
 *
 *   pure   one lerp per direction per sample, no weights, no slice bookkeeping:
 *          a lower bound for any exact kernel (every sample in a saturated ramp);
 *   blend  two lerps and both weights on every sample, slice records picked per lane
 *          from registers (vpermps): what a branch-free row kernel does everywhere.
 *
 * Lookups come in two forms, both timed: "window", a 16-texel register window (two loads,
 * vpermps, blend) where the eight lanes' texels fit and AVX2 gathers elsewhere, and "gather",
 * AVX2 gathers always (faster on CPUs with fast gathers); the floor of a row is the faster.
 * The table's value and forward difference are separate arrays, so a lerp is one fetch of
 * each.  Rows of N samples at a texel step of `step` per sample, K = 16, all threads busy;
 * prints JSON ns per sample: "<grid> pure|blend" (the faster form) and each form's own time.
 *
 *   cc -O3 -pthread bench/lookup_floor.c -o floor -lm && ./floor THREADS
 */
#include <immintrin.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define AVX2 __attribute__((target("avx2,fma")))
#define TABLE 1024
#define K 16

static float *tab_v, *tab_d;
static int gather_only;  /* 1: the "gather" form */

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* cos(pi/2 s), s in [0, 1]: the kernel's polynomial (rows.c, cos_half_pi8), 1 + y (c1 + y (c2 + y (c3 + y c4)))
 * in y = s^2, error 5.3e-8 */
AVX2 static inline __m256 cos_half_pi(__m256 s) {
  __m256 y = _mm256_mul_ps(s, s);
  __m256 p = _mm256_fmadd_ps(y, _mm256_set1_ps(8.59690055e-04f), _mm256_set1_ps(-2.08139667e-02f));
  p = _mm256_fmadd_ps(y, p, _mm256_set1_ps(2.53653209e-01f));
  p = _mm256_fmadd_ps(y, p, _mm256_set1_ps(-1.23369888e+00f));
  return _mm256_fmadd_ps(y, p, _mm256_set1_ps(1.0f));
}

/* lerp of the periodic table at texel coordinates tau (8 lanes) */
AVX2 static inline __m256 lerp(__m256 tau) {
  tau = _mm256_fnmadd_ps(_mm256_set1_ps((float)TABLE),
                         _mm256_floor_ps(_mm256_mul_ps(tau, _mm256_set1_ps(1.0f / TABLE))), tau);
  __m256 f = _mm256_floor_ps(tau), t = _mm256_sub_ps(tau, f);
  __m256i i = _mm256_cvtps_epi32(f);
  __m256i base = _mm256_min_epi32(_mm256_permutevar8x32_epi32(i, _mm256_setzero_si256()),
                                  _mm256_permutevar8x32_epi32(i, _mm256_set1_epi32(7)));
  __m256i rel = _mm256_sub_epi32(i, base);
  __m256 v, d;
  if (!gather_only && !_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(rel, _mm256_set1_epi32(15))))) {
    int b = _mm256_extract_epi32(base, 0);
    __m256 hi = _mm256_castsi256_ps(_mm256_cmpgt_epi32(rel, _mm256_set1_epi32(7)));
    v = _mm256_blendv_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(tab_v + b), rel),
                         _mm256_permutevar8x32_ps(_mm256_loadu_ps(tab_v + b + 8), rel), hi);
    d = _mm256_blendv_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(tab_d + b), rel),
                         _mm256_permutevar8x32_ps(_mm256_loadu_ps(tab_d + b + 8), rel), hi);
  } else {
    v = _mm256_i32gather_ps(tab_v, i, 4);
    d = _mm256_i32gather_ps(tab_d, i, 4);
  }
  return _mm256_fmadd_ps(t, d, v);
}

/* one direction along a row: x (n), per-slice records in registers (<= 8 slices per row) */
AVX2 static void row(const float *xs, int n, float sx, float q, const float *rec, int blend, float *out) {
  __m256 a0t = _mm256_loadu_ps(rec), b0t = _mm256_loadu_ps(rec + 8), a1t = _mm256_loadu_ps(rec + 16);
  __m256 b1t = _mm256_loadu_ps(rec + 24), spt = _mm256_loadu_ps(rec + 32);
  __m256 vsx = _mm256_set1_ps(sx), vq = _mm256_set1_ps(q), one = _mm256_set1_ps(1.0f);
  for (int j = 0; j < n; j += 8) {
    __m256 x = _mm256_loadu_ps(xs + j), p = _mm256_fmadd_ps(x, vsx, vq), fl = _mm256_floor_ps(p);
    __m256i r = _mm256_cvtps_epi32(fl);
    __m256 a0 = _mm256_permutevar8x32_ps(a0t, r), b0 = _mm256_permutevar8x32_ps(b0t, r), acc;
    if (blend) {
      __m256 sp = _mm256_permutevar8x32_ps(spt, r);
      __m256 u = _mm256_fmadd_ps(_mm256_sub_ps(_mm256_sub_ps(p, fl), sp), _mm256_set1_ps(0.5f / 0.3f),
                                 _mm256_set1_ps(0.5f));
      u = _mm256_min_ps(_mm256_max_ps(u, _mm256_setzero_ps()), one);
      __m256 s = _mm256_mul_ps(_mm256_mul_ps(u, u), _mm256_fnmadd_ps(_mm256_set1_ps(2.0f), u, _mm256_set1_ps(3.0f)));
      __m256 l1 = lerp(_mm256_fmadd_ps(x, _mm256_permutevar8x32_ps(a1t, r), _mm256_permutevar8x32_ps(b1t, r)));
      acc = _mm256_fmadd_ps(cos_half_pi(s), lerp(_mm256_fmadd_ps(x, a0, b0)),
                            _mm256_mul_ps(cos_half_pi(_mm256_sub_ps(one, s)), l1));
    } else {
      acc = lerp(_mm256_fmadd_ps(x, a0, b0));
    }
    _mm256_storeu_ps(out + j, _mm256_fmadd_ps(_mm256_set1_ps(0.25f), acc, _mm256_loadu_ps(out + j)));
  }
}

typedef struct { int n, rows, blend; float step; double seconds; } job_t;

static void *work(void *arg) {
  job_t *jb = arg;
  int n = jb->n;
  float *xs = aligned_alloc(32, n * 4), *out = aligned_alloc(32, n * 4), rec[40];
  for (int j = 0; j < n; j++) xs[j] = (float)j, out[j] = 0.0f;
  unsigned seed = 12345;
  for (int i = 0; i < 40; i++) rec[i] = (float)(rand_r(&seed) % TABLE);
  for (int i = 0; i < 8; i++) {
    rec[i] = jb->step * (0.6f + 0.05f * i);      /* texel step of slice i's wave along the row */
    rec[16 + i] = -jb->step * (0.5f + 0.05f * i);
    rec[32 + i] = 0.3f + 0.05f * i;
  }
  float sx = 4.0f / n;  /* about four slices per row, as in the bench's grids */
  double t = now();
  for (int r = 0; r < jb->rows; r++)
    for (int k = 0; k < K; k++) row(xs, n, sx, 0.01f * k, rec, jb->blend, out);
  jb->seconds = now() - t;
  free(xs);
  free(out);
  return NULL;
}

int main(int argc, char **argv) {
  int threads = argc > 1 ? atoi(argv[1]) : 1;
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
    printf("{\"error\": \"no AVX2/FMA on this CPU\"}\n");
    return 0;
  }
  tab_v = aligned_alloc(32, (TABLE + 32) * 4);
  tab_d = aligned_alloc(32, (TABLE + 32) * 4);
  for (int i = 0; i < TABLE + 32; i++) tab_v[i] = sinf(0.37f * i) + 0.5f * cosf(0.11f * i);
  for (int i = 0; i < TABLE + 31; i++) tab_d[i] = tab_v[i + 1] - tab_v[i];
  const struct { int n; float step; const char *name; } grids[] = {
      {1024, 0.25f, "2D_1024"}, {128, 2.0f, "3D_128"}, {256, 1.0f, "3D_256"}};
  printf("{");
  int first = 1;
  for (int g = 0; g < 3; g++) {
    for (int blend = 0; blend < 2; blend++) {
      double best = 0.0;
      for (int form = 0; form < 2; form++) {
        long samples = 1L << 22;
        job_t jobs[64];
        pthread_t tid[64];
        gather_only = form;
        double t = now();
        for (int i = 0; i < threads; i++) {
          jobs[i] = (job_t){grids[g].n, (int)(samples / threads / grids[g].n), blend, grids[g].step, 0};
          pthread_create(&tid[i], NULL, work, &jobs[i]);
        }
        for (int i = 0; i < threads; i++) pthread_join(tid[i], NULL);
        double ns = (now() - t) / samples * 1e9;
        best = form == 0 || ns < best ? ns : best;
        printf("%s\"%s %s (%s)\": %.2f", first ? "" : ", ", grids[g].name, blend ? "blend" : "pure",
               form ? "gather" : "window", ns);
        first = 0;
      }
      printf(", \"%s %s\": %.2f", grids[g].name, blend ? "blend" : "pure", best);
    }
  }
  printf("}\n");
  return 0;
}
