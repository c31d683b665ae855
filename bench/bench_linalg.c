/* bench_linalg: the cost of each per-evaluation linear-algebra routine on its native small-size
 * path and on its LAPACK/BLAS path, side by side in the same run, for the sizes of mechanisms
 * (b constraint rows, k speeds, l = k - b free speeds; A random of full rank b, g random SPD).
 * It is the measurement behind AP_LA_SMALL_LIMIT (lib/linalg/linalg.h).
 *
 * Method (as bench_eval): warm up, then time blocks of `reps` calls with CLOCK_MONOTONIC; the
 * native and the LAPACK block alternate (ap_la_set_small_limit), so drift hits both alike.
 * Reports the median over `blocks` blocks and the spread (min, max) in nanoseconds per call, and
 * the ratio of medians LAPACK / native. Routines that work in place (chol, chol_solve) restore
 * their input with a copy inside the timed loop, on both paths. "+rcond" rows ask for the
 * condition estimate (LAPACK on both paths); the others pass rcond = NULL.
 * Usage: bench_linalg [--csv FILE] [--reps N] [--blocks N] [--size B K]...  (--size replaces
 * the default sizes (1,3) (2,5) (3,6) (6,12) (20,40); reps is for k <= 4 and shrinks as k^2).
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/status.h"
#include "benchutil.h"
#include "linalg/linalg.h"

typedef struct timing {
  double median, lo, hi;       /* ns per call */
} timing;

static uint64_t rng = 0x9E3779B97F4A7C15ull;

static double urand(void) { /* xorshift64*, uniform in [-1, 1) */
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 2685821657736338717ull) >> 11) * 0x1.0p-52 - 1.0;
}

/* ---- one problem and its outputs ---------------------------------------------------------- */

typedef struct prob {
  int b, k, l, r, rank;
  double *A, *a0, *gamma, *g, *F, *tau, *B, *b0, *w, *Qf, *Z, *Fo, *tauo, *G0, *G, *L, *gB;
  double *x, *y, *work, growth, rcond, resid;
  int *perm, *jpvt, *iwork;
} prob;

static double *dalloc(size_t n) {
  double *p = calloc(n ? n : 1, sizeof(double));
  if (!p) abort();
  return p;
}

static void check(int rc, const char *what) {
  if (rc == AP_OK) return;
  fprintf(stderr, "bench_linalg: %s returned %d\n", what, rc);
  exit(1);
}

static prob prob_new(int b, int k) {
  prob p = {.b = b, .k = k};
  size_t kk = (size_t)k * k, bk = (size_t)b * k;
  p.A = dalloc(bk), p.a0 = dalloc((size_t)b), p.gamma = dalloc((size_t)b), p.g = dalloc(kk);
  p.F = dalloc(bk), p.tau = dalloc((size_t)k), p.B = dalloc(kk), p.b0 = dalloc((size_t)k);
  p.w = dalloc((size_t)k), p.Qf = dalloc(kk), p.Z = dalloc(kk), p.Fo = dalloc(bk);
  p.tauo = dalloc((size_t)k), p.G0 = dalloc(kk), p.G = dalloc(kk), p.L = dalloc(kk);
  p.gB = dalloc(kk), p.x = dalloc((size_t)k), p.y = dalloc((size_t)k);
  p.work = dalloc(ap_la_work_size(b, k));
  p.perm = calloc((size_t)k, sizeof(int)), p.jpvt = calloc((size_t)b + 1, sizeof(int));
  p.iwork = calloc(ap_la_iwork_size(b, k), sizeof(int));
  if (!p.perm || !p.jpvt || !p.iwork) abort();
  for (size_t i = 0; i < bk; i++) p.A[i] = urand();
  for (int i = 0; i < b; i++) p.a0[i] = urand(), p.gamma[i] = urand();
  for (int i = 0; i < k; i++) p.x[i] = urand();
  double *M = dalloc(kk); /* g = M^T M + k I */
  for (size_t i = 0; i < kk; i++) M[i] = urand();
  for (int j = 0; j < k; j++)
    for (int i = 0; i < k; i++) {
      double s = i == j ? k : 0.0;
      for (int t = 0; t < k; t++) s += M[t + (size_t)i * k] * M[t + (size_t)j * k];
      p.g[i + (size_t)j * k] = s;
    }
  free(M);
  check(ap_la_pivot_select(b, k, p.A, 1e-9, p.perm, &p.r, p.work, p.iwork), "pivot_select");
  p.l = k - p.r;
  check(ap_la_partition_basis(b, k, p.r, p.perm, p.A, p.a0, p.F, p.tau, p.B, p.b0, &p.growth,
                              NULL, &p.resid, p.work, p.iwork), "partition_basis");
  check(ap_la_orth_basis(b, k, p.A, p.a0, 1e-9, &p.rank, p.Fo, p.tauo, p.jpvt, p.Qf, p.Z, p.b0,
                         &p.resid, p.work, p.iwork), "orth_basis");
  ap_la_congruence(k, p.l, p.g, p.B, p.G0, p.gB);
  memcpy(p.L, p.G0, sizeof(double) * (size_t)p.l * p.l);
  check(ap_la_chol(p.l, p.L, NULL, p.work, p.iwork), "chol");
  return p;
}

static void prob_free(prob *p) {
  double *d[] = {p->A, p->a0, p->gamma, p->g, p->F, p->tau, p->B, p->b0, p->w, p->Qf, p->Z,
                 p->Fo, p->tauo, p->G0, p->G, p->L, p->gB, p->x, p->y, p->work};
  for (size_t i = 0; i < sizeof d / sizeof *d; i++) free(d[i]);
  free(p->perm), free(p->jpvt), free(p->iwork);
}

/* ---- the timed calls ---------------------------------------------------------------------- */

static void r_partition(prob *p) {
  check(ap_la_partition_basis(p->b, p->k, p->r, p->perm, p->A, p->a0, p->F, p->tau, p->B, p->b0,
                              &p->growth, NULL, &p->resid, p->work, p->iwork), "partition_basis");
  bench_sink += p->B[0];
}
static void r_partition_rc(prob *p) {
  check(ap_la_partition_basis(p->b, p->k, p->r, p->perm, p->A, p->a0, p->F, p->tau, p->B, p->b0,
                              &p->growth, &p->rcond, &p->resid, p->work, p->iwork),
        "partition_basis");
  bench_sink += p->B[0];
}
static void r_particular(prob *p) {
  check(ap_la_partition_particular(p->b, p->k, p->r, p->perm, p->F, p->tau, p->gamma, p->w,
                                   &p->resid, p->work), "partition_particular");
  bench_sink += p->w[0];
}
static void r_orth(prob *p) {
  check(ap_la_orth_basis(p->b, p->k, p->A, p->a0, 1e-9, &p->rank, p->Fo, p->tauo, p->jpvt, p->Qf,
                         p->Z, p->b0, &p->resid, p->work, p->iwork), "orth_basis");
  bench_sink += p->Z[0];
}
static void r_orth_particular(prob *p) {
  check(ap_la_orth_particular(p->b, p->k, p->rank, p->Fo, p->jpvt, p->Qf, p->gamma, p->w,
                              &p->resid, p->work), "orth_particular");
  bench_sink += p->w[0];
}
static void r_chol(prob *p) {
  memcpy(p->G, p->G0, sizeof(double) * (size_t)p->l * p->l);
  check(ap_la_chol(p->l, p->G, NULL, p->work, p->iwork), "chol");
  bench_sink += p->G[0];
}
static void r_chol_rc(prob *p) {
  memcpy(p->G, p->G0, sizeof(double) * (size_t)p->l * p->l);
  check(ap_la_chol(p->l, p->G, &p->rcond, p->work, p->iwork), "chol");
  bench_sink += p->G[0];
}
static void r_chol_solve(prob *p) {
  memcpy(p->y, p->x, sizeof(double) * (size_t)p->l); /* solving in place: a fresh rhs */
  ap_la_chol_solve(p->l, p->L, p->y);
  bench_sink += p->y[0];
}
static void r_congruence(prob *p) {
  ap_la_congruence(p->k, p->l, p->g, p->B, p->G, p->gB);
  bench_sink += p->G[0];
}
static void r_gemv(prob *p) {
  ap_la_gemv(p->k, p->k, p->g, p->x, p->y);
  bench_sink += p->y[0];
}
static void r_gemv_t(prob *p) {
  ap_la_gemv_t(p->k, p->l, p->B, p->x, p->y);
  bench_sink += p->y[0];
}

typedef struct routine {
  const char *name, *shape; /* shape: which sizes it runs on */
  void (*call)(prob *p);
} routine;

static const routine routines[] = {
    {"partition_basis", "b x k", r_partition},
    {"partition_basis+rcond", "b x k", r_partition_rc},
    {"partition_particular", "b x k", r_particular},
    {"orth_basis", "b x k", r_orth},
    {"orth_particular", "b x k", r_orth_particular},
    {"chol", "l x l", r_chol},
    {"chol+rcond", "l x l", r_chol_rc},
    {"chol_solve", "l x l", r_chol_solve},
    {"congruence", "k, l", r_congruence},
    {"gemv", "k x k", r_gemv},
    {"gemv_t", "k x l", r_gemv_t},
};

/* Alternating blocks: native (limit INT_MAX) then LAPACK (limit 0). */
static void time_both(int blocks, int reps, const routine *rt, prob *p, timing *nat,
                      timing *lap) {
  double *ns = malloc(sizeof(double) * 2 * (size_t)blocks);
  if (!ns) abort();
  for (int path = 0; path < 2; path++) { /* warm-up */
    ap_la_set_small_limit(path ? 0 : INT_MAX);
    for (int i = 0; i < reps; i++) rt->call(p);
  }
  for (int b = 0; b < blocks; b++)
    for (int path = 0; path < 2; path++) {
      ap_la_set_small_limit(path ? 0 : INT_MAX);
      double t0 = bench_mono_ns();
      for (int i = 0; i < reps; i++) rt->call(p);
      ns[path * blocks + b] = (bench_mono_ns() - t0) / reps;
    }
  for (int path = 0; path < 2; path++) {
    double *v = ns + path * blocks;
    qsort(v, (size_t)blocks, sizeof *v, bench_cmp_double);
    timing t = {v[blocks / 2], v[0], v[blocks - 1]};
    *(path ? lap : nat) = t;
  }
  free(ns);
}

int main(int argc, char **argv) {
  int reps = 20000, blocks = 31, nsz = 0, sizes[32][2];
  const int defaults[5][2] = {{1, 3}, {2, 5}, {3, 6}, {6, 12}, {20, 40}};
  const char *csv = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blocks") && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--size") && i + 2 < argc && nsz < 32) {
      sizes[nsz][0] = atoi(argv[i + 1]), sizes[nsz][1] = atoi(argv[i + 2]);
      if (sizes[nsz][0] < 0 || sizes[nsz][1] <= sizes[nsz][0]) return 2; /* need l >= 1 */
      nsz++, i += 2;
    } else {
      fprintf(stderr, "usage: bench_linalg [--csv FILE] [--reps N] [--blocks N] "
                      "[--size B K]...\n");
      return 2;
    }
  }
  if (reps < 1 || blocks < 1) return 2;
  if (nsz == 0)
    for (nsz = 0; nsz < 5; nsz++) memcpy(sizes[nsz], defaults[nsz], sizeof sizes[nsz]);

  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (csv && !out) {
    fprintf(stderr, "bench_linalg: cannot write %s\n", csv);
    return 1;
  }
  if (out) fprintf(out, "b,k,l,routine,native_ns,native_lo,native_hi,lapack_ns,lapack_lo,"
                        "lapack_hi,ratio\n");
  int limit0 = ap_la_small_limit();
  printf("native limit: %d (AP_LA_SMALL_LIMIT); ratio = LAPACK / native\n", limit0);
  printf("%2s %2s %2s %-22s %10s %20s %10s %20s %7s\n", "b", "k", "l", "routine", "native ns",
         "(min..max)", "LAPACK ns", "(min..max)", "ratio");
  for (int s = 0; s < nsz; s++) {
    prob p = prob_new(sizes[s][0], sizes[s][1]);
    int kk = p.k * p.k, n = kk <= 16 ? reps : (int)((double)reps * 16 / kk);
    if (n < 10) n = 10;
    for (size_t i = 0; i < sizeof routines / sizeof *routines; i++) {
      timing tn, tl;
      time_both(blocks, n, &routines[i], &p, &tn, &tl);
      printf("%2d %2d %2d %-22s %10.1f (%7.1f..%9.1f) %10.1f (%7.1f..%9.1f) %7.1f\n", p.b, p.k,
             p.l, routines[i].name, tn.median, tn.lo, tn.hi, tl.median, tl.lo, tl.hi,
             tl.median / tn.median);
      if (out)
        fprintf(out, "%d,%d,%d,%s,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.3f\n", p.b, p.k, p.l,
                routines[i].name, tn.median, tn.lo, tn.hi, tl.median, tl.lo, tl.hi,
                tl.median / tn.median);
    }
    prob_free(&p);
  }
  ap_la_set_small_limit(limit0);
  if (out) fclose(out);
  return 0;
}
