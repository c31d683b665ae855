/* Tests of lib/linalg (docs/design.md §1 "Choosing B"): partitioned and orthonormal null-space
 * bases with their particular solutions, rank decisions and consistency residuals, Cholesky with
 * its condition estimate, the congruence B^T g B, the reactions' least squares, gemv.
 *
 * Two paths: the whole suite runs twice, on the LAPACK/BLAS path (ap_la_set_small_limit(0)) and
 * on the native small-size kernels (limit INT_MAX), from the same generator seed, so both meet
 * the same matrices and the same checks. test_paths then runs both paths on the same inputs and
 * compares their results (B, b0, w, spans Z Z^T, G, Cholesky factors and solves, ranks) within
 * round-off scaled by condition estimates; test_no_rcond covers rcond = NULL (no estimate, the
 * singularity thresholds instead).
 *
 * Matrices come from a fixed-seed generator, and every result is checked against its defining
 * property (A B = 0, A b0 = -a0, Z^T Z = I, ...) with plain loops here, not against the library.
 * Scratch arrays are exactly ap_la_work_size / ap_la_iwork_size long, filled with NaN (reading
 * scratch before writing it poisons the results) and followed by guard values that must survive
 * (the sizes suffice). */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "check.h"
#include "linalg/linalg.h"

#define RTOL 1e-9   /* rank tolerance */
#define TOL 1e-13   /* round-off, relative to the scale of the quantities involved */
#define NMAX 16     /* largest b or k used */
#define NGUARD 32   /* guard entries after each scratch array */
#define GUARD_D 12345.678
#define GUARD_I 424242

/* ---- fixed-seed generator and small helpers ----------------------------------------------- */

static uint64_t rng = 0x9E3779B97F4A7C15ull;

static double urand(void) { /* xorshift64*, uniform in [-1, 1) */
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 2685821657736338717ull) >> 11) * 0x1.0p-52 - 1.0;
}

static void rand_fill(size_t n, double *x) {
  for (size_t i = 0; i < n; i++) x[i] = urand();
}

static double max_abs(size_t n, const double *x) {
  double v = 0.0;
  for (size_t i = 0; i < n; i++) v = fmax(v, fabs(x[i]));
  return v;
}

/* C (m x p) = op(A) B with op(A) m x n; A stored m x n (trans 0) or n x m (trans 1). */
static void mul(int trans, int m, int n, int p, const double *A, const double *B, double *C) {
  for (int j = 0; j < p; j++)
    for (int i = 0; i < m; i++) {
      double s = 0.0;
      for (int t = 0; t < n; t++)
        s += (trans ? A[t + (size_t)i * n] : A[i + (size_t)t * m]) * B[t + (size_t)j * n];
      C[i + (size_t)j * m] = s;
    }
}

/* y (m) = A x + c for A (m x n). */
static void affine(int m, int n, const double *A, const double *x, const double *c, double *y) {
  mul(0, m, n, 1, A, x, y);
  for (int i = 0; i < m; i++) y[i] += c[i];
}

/* max |M^T M - I| for M (m x n). */
static double orth_err(int m, int n, const double *M) {
  double MtM[NMAX * NMAX];
  mul(1, n, m, n, M, M, MtM);
  for (int i = 0; i < n; i++) MtM[i + (size_t)i * n] -= 1.0;
  return max_abs((size_t)n * n, MtM);
}

static int is_perm(int n, const int *p) {
  int seen[NMAX] = {0};
  for (int i = 0; i < n; i++) {
    if (p[i] < 0 || p[i] >= n || seen[p[i]]) return 0;
    seen[p[i]] = 1;
  }
  return 1;
}

/* ---- scratch with guards ------------------------------------------------------------------ */

typedef struct scratch {
  double *w;
  int *iw;
  size_t nw, niw;
} scratch;

static scratch scratch_new(int b, int k) {
  scratch s;
  s.nw = ap_la_work_size(b, k), s.niw = ap_la_iwork_size(b, k);
  s.w = malloc(sizeof(double) * (s.nw + NGUARD));
  s.iw = malloc(sizeof(int) * (s.niw + NGUARD));
  if (!s.w || !s.iw) abort();
  for (size_t i = 0; i < s.nw + NGUARD; i++) s.w[i] = i < s.nw ? NAN : GUARD_D;
  for (size_t i = 0; i < s.niw + NGUARD; i++) s.iw[i] = i < s.niw ? -777 : GUARD_I;
  return s;
}

/* Checks the guards, then frees. */
static void scratch_done(scratch *s) {
  int ok = 1;
  for (size_t i = 0; i < NGUARD; i++)
    ok = ok && s->w[s->nw + i] == GUARD_D && s->iw[s->niw + i] == GUARD_I;
  AP_CHECK(ok);
  free(s->w), free(s->iw);
}

/* ---- problems ----------------------------------------------------------------------------- */

/* A constraint set with free terms. dist = 0 when a0 and gamma are in the range of A (the
 * redundant rows are consistent); otherwise both are at least dist from range(A) (2-norm). */
typedef struct problem {
  int b, k, rank;
  double dist;
  double A[NMAX * NMAX], a0[NMAX], gamma[NMAX];
} problem;

/* a0 = -A x0 and gamma = A x1 (consistent), random x0, x1. */
static void consistent_terms(problem *p) {
  double x[NMAX], zero[NMAX] = {0};
  rand_fill((size_t)p->k, x);
  affine(p->b, p->k, p->A, x, zero, p->a0);
  rand_fill((size_t)p->k, x);
  affine(p->b, p->k, p->A, x, zero, p->gamma);
}

/* Add a unit vector orthogonal to range(A) (a null vector of A^T) to a0 and gamma. */
static void make_inconsistent(problem *p) {
  double At[NMAX * NMAX], F[NMAX * NMAX], tau[NMAX], Qf[NMAX * NMAX], Z[NMAX * NMAX];
  int jpvt[NMAX], r = 0;
  scratch s = scratch_new(p->k, p->b);
  for (int i = 0; i < p->b; i++)
    for (int j = 0; j < p->k; j++) At[j + (size_t)i * p->k] = p->A[i + (size_t)j * p->b];
  AP_CHECK_EQ_INT(ap_la_orth_basis(p->k, p->b, At, NULL, RTOL, &r, F, tau, jpvt, Qf, Z, NULL,
                                   &(double){0}, s.w, s.iw), AP_OK);
  AP_CHECK_EQ_INT(r, p->rank);
  for (int i = 0; i < p->b; i++) p->a0[i] += Z[i], p->gamma[i] -= Z[i];
  p->dist = 1.0;
  scratch_done(&s);
}

/* Random A (b x k) of rank r0 = L R, with consistent free terms. */
static problem random_problem(int b, int k, int r0) {
  problem p = {.b = b, .k = k, .rank = r0};
  double L[NMAX * NMAX], R[NMAX * NMAX];
  if (r0 == (b < k ? b : k)) {
    rand_fill((size_t)b * k, p.A);
  } else {
    rand_fill((size_t)b * r0, L), rand_fill((size_t)r0 * k, R);
    mul(0, b, r0, k, L, R, p.A);
  }
  consistent_terms(&p);
  return p;
}

/* ---- partitioned basis -------------------------------------------------------------------- */

static void check_partition(const problem *p) {
  int b = p->b, k = p->k, perm[NMAX], r = -1;
  double F[NMAX * NMAX], tau[NMAX], B[NMAX * NMAX], b0[NMAX], w[NMAX], y[NMAX];
  double growth = -1, rcond = -1, resid = -1, resid_w = -1;
  scratch s = scratch_new(b, k);
  AP_CHECK_EQ_INT(ap_la_pivot_select(b, k, p->A, RTOL, perm, &r, s.w, s.iw), AP_OK);
  AP_CHECK_EQ_INT(r, p->rank);
  AP_CHECK(is_perm(k, perm));
  int l = k - r, ascending = 1;
  for (int j = r + 1; j < k; j++) ascending = ascending && perm[j - 1] < perm[j];
  AP_CHECK(ascending);

  AP_CHECK_EQ_INT(ap_la_partition_basis(b, k, r, perm, p->A, p->a0, F, tau, B, b0, &growth,
                                        &rcond, &resid, s.w, s.iw), AP_OK);
  /* A B = 0; rows perm[r..] of B are the identity; growth is the largest dependent entry */
  double nA = max_abs((size_t)b * k, p->A), nB = max_abs((size_t)k * l, B);
  double AB[NMAX * NMAX];
  mul(0, b, k, l, p->A, B, AB);
  AP_CHECK_LE(max_abs((size_t)b * l, AB), TOL * k * nA * fmax(1.0, nB));
  int unit = 1;
  double gmax = 0.0;
  for (int j = 0; j < l; j++) {
    for (int i = 0; i < l; i++) unit = unit && B[perm[r + i] + (size_t)j * k] == (i == j);
    for (int i = 0; i < r; i++) gmax = fmax(gmax, fabs(B[perm[i] + (size_t)j * k]));
  }
  AP_CHECK(unit);
  AP_CHECK_NEAR(growth, gmax, 0.0);
  AP_CHECK(rcond > 0.0 && rcond <= 1.0);
  if (r == 0) AP_CHECK_NEAR(rcond, 1.0, 0.0);
  { /* no estimate (rcond NULL): the same factorization and outputs, bit for bit */
    double F2[NMAX * NMAX], tau2[NMAX], B2[NMAX * NMAX], b02[NMAX], g2 = -1, res2 = -1;
    AP_CHECK_EQ_INT(ap_la_partition_basis(b, k, r, perm, p->A, p->a0, F2, tau2, B2, b02, &g2,
                                          NULL, &res2, s.w, s.iw), AP_OK);
    AP_CHECK(memcmp(F2, F, sizeof(double) * (size_t)b * r) == 0);
    AP_CHECK(memcmp(tau2, tau, sizeof(double) * (size_t)r) == 0);
    AP_CHECK(memcmp(B2, B, sizeof(double) * (size_t)k * l) == 0);
    AP_CHECK(memcmp(b02, b0, sizeof(double) * (size_t)k) == 0);
    AP_CHECK(g2 == growth && res2 == resid);
  }

  /* b0 and w vanish on the independent speeds; A b0 = -a0, A w = gamma when consistent */
  AP_CHECK_EQ_INT(ap_la_partition_particular(b, k, r, perm, F, tau, p->gamma, w, &resid_w, s.w),
                  AP_OK);
  double zi = 0.0;
  for (int j = r; j < k; j++) zi = fmax(zi, fabs(b0[perm[j]]) + fabs(w[perm[j]]));
  AP_CHECK_NEAR(zi, 0.0, 0.0);
  double sa = TOL * (k * nA * max_abs((size_t)k, b0) + max_abs((size_t)b, p->a0));
  double sg = TOL * (k * nA * max_abs((size_t)k, w) + max_abs((size_t)b, p->gamma));
  if (p->dist == 0.0) {
    affine(b, k, p->A, b0, p->a0, y);
    AP_CHECK_LE(max_abs((size_t)b, y), sa);
    AP_CHECK_LE(resid, sa);
    double mg[NMAX] = {0};
    for (int i = 0; i < b; i++) mg[i] = -p->gamma[i];
    affine(b, k, p->A, w, mg, y);
    AP_CHECK_LE(max_abs((size_t)b, y), sg);
    AP_CHECK_LE(resid_w, sg);
  } else { /* |Q2^T a0| >= dist, spread over b - r rows */
    AP_CHECK(resid >= 0.99 * p->dist / sqrt(b - r));
    AP_CHECK(resid_w >= 0.99 * p->dist / sqrt(b - r));
  }
  scratch_done(&s);
}

/* ---- orthonormal basis -------------------------------------------------------------------- */

/* y = A x - t over the rows; kept rows jpvt[0..r-1] must be ~0, returns max over dropped rows. */
static double orth_rows(const problem *p, const int *jpvt, int r, const double *x,
                        const double *t, double tol) {
  double y[NMAX], kept = 0.0, dropped = 0.0;
  mul(0, p->b, p->k, 1, p->A, x, y);
  for (int i = 0; i < p->b; i++) {
    double e = fabs(y[jpvt[i]] - t[jpvt[i]]);
    if (i < r) kept = fmax(kept, e);
    else dropped = fmax(dropped, e);
  }
  AP_CHECK_LE(kept, tol);
  return dropped;
}

static void check_orth(const problem *p) {
  int b = p->b, k = p->k, jpvt[NMAX], r = -1;
  double F[NMAX * NMAX], tau[NMAX], Qf[NMAX * NMAX], Z[NMAX * NMAX], b0[NMAX], w[NMAX];
  double resid = -1, resid_w = -1, ma0[NMAX];
  scratch s = scratch_new(b, k);
  AP_CHECK_EQ_INT(ap_la_orth_basis(b, k, p->A, p->a0, RTOL, &r, F, tau, jpvt, Qf, Z, b0, &resid,
                                   s.w, s.iw), AP_OK);
  AP_CHECK_EQ_INT(r, p->rank);
  if (b > 0) AP_CHECK(is_perm(b, jpvt));
  int l = k - r;
  double nA = max_abs((size_t)b * k, p->A), AZ[NMAX * NMAX];
  AP_CHECK_LE(orth_err(k, k, Qf), TOL);
  AP_CHECK_LE(orth_err(k, l, Z), TOL);
  AP_CHECK(memcmp(Z, Qf + (size_t)r * k, sizeof(double) * (size_t)k * l) == 0);
  mul(0, b, k, l, p->A, Z, AZ);
  AP_CHECK_LE(max_abs((size_t)b * l, AZ), TOL * k * nA);

  /* minimum norm: b0 and w are orthogonal to Z; kept rows solved, resid = dropped rows */
  AP_CHECK_EQ_INT(ap_la_orth_particular(b, k, r, F, jpvt, Qf, p->gamma, w, &resid_w, s.w),
                  AP_OK);
  double zb[NMAX];
  mul(1, l, k, 1, Z, b0, zb);
  AP_CHECK_LE(max_abs((size_t)l, zb), TOL * max_abs((size_t)k, b0) * k);
  mul(1, l, k, 1, Z, w, zb);
  AP_CHECK_LE(max_abs((size_t)l, zb), TOL * max_abs((size_t)k, w) * k);
  for (int i = 0; i < b; i++) ma0[i] = -p->a0[i];
  double sa = TOL * (k * nA * max_abs((size_t)k, b0) + max_abs((size_t)b, p->a0));
  double sg = TOL * (k * nA * max_abs((size_t)k, w) + max_abs((size_t)b, p->gamma));
  double da = orth_rows(p, jpvt, r, b0, ma0, sa), dg = orth_rows(p, jpvt, r, w, p->gamma, sg);
  AP_CHECK_NEAR(resid, da, sa);
  AP_CHECK_NEAR(resid_w, dg, sg);
  if (p->dist == 0.0) {
    AP_CHECK_LE(resid, sa);
    AP_CHECK_LE(resid_w, sg);
  } else { /* A x - t, non-zero on the b - r dropped rows only, is >= dist in 2-norm */
    AP_CHECK(resid >= 0.99 * p->dist / sqrt(b - r));
    AP_CHECK(resid_w >= 0.99 * p->dist / sqrt(b - r));
  }
  scratch_done(&s);
}

/* ---- least squares for the reactions ------------------------------------------------------ */

/* rhs = A^T lambda0: full row rank gives lambda0 back; redundant rows give the minimum-norm
 * solution (orthogonal to the null space of A^T, no longer than lambda0). */
static void check_lstsq(const problem *p) {
  int b = p->b, k = p->k;
  double lam0[NMAX], lam[NMAX], rhs[NMAX], res[NMAX], resid = -1;
  scratch s = scratch_new(b, k);
  rand_fill((size_t)b, lam0);
  mul(1, k, b, 1, p->A, lam0, rhs);
  AP_CHECK_EQ_INT(ap_la_lstsq_At(b, k, p->A, rhs, RTOL, lam, &resid, s.w, s.iw), AP_OK);
  mul(1, k, b, 1, p->A, lam, res);
  for (int i = 0; i < k; i++) res[i] -= rhs[i];
  double nA = max_abs((size_t)b * k, p->A), sc = TOL * b * nA * max_abs((size_t)b, lam0);
  AP_CHECK_NEAR(resid, max_abs((size_t)k, res), sc);
  AP_CHECK_LE(resid, sc);
  if (p->rank == b) {
    for (int i = 0; i < b; i++) res[i] = lam[i] - lam0[i];
    AP_CHECK_LE(max_abs((size_t)b, res), 1e-9);
  } else { /* null vectors of A^T from the orthonormal basis of A^T (checked above) */
    double At[NMAX * NMAX], F[NMAX * NMAX], tau[NMAX], Qf[NMAX * NMAX], N[NMAX * NMAX], nl[NMAX];
    int jpvt[NMAX], r = 0;
    scratch s2 = scratch_new(k, b);
    for (int i = 0; i < b; i++)
      for (int j = 0; j < k; j++) At[j + (size_t)i * k] = p->A[i + (size_t)j * b];
    AP_CHECK_EQ_INT(ap_la_orth_basis(k, b, At, NULL, RTOL, &r, F, tau, jpvt, Qf, N, NULL,
                                     &(double){0}, s2.w, s2.iw), AP_OK);
    mul(1, b - r, b, 1, N, lam, nl);
    AP_CHECK_LE(max_abs((size_t)(b - r), nl), 1e-12 * max_abs((size_t)b, lam0));
    double n0 = 0, n1 = 0;
    for (int i = 0; i < b; i++) n0 += lam0[i] * lam0[i], n1 += lam[i] * lam[i];
    AP_CHECK(n1 < n0);
    scratch_done(&s2);
  }
  scratch_done(&s);
}

/* A rhs outside the range of A^T (b < k): the normal equations A (A^T lambda - rhs) = 0. */
static void check_lstsq_inconsistent(int b, int k) {
  problem p = random_problem(b, k, b);
  double rhs[NMAX], lam[NMAX], res[NMAX], ne[NMAX], resid = -1;
  scratch s = scratch_new(b, k);
  rand_fill((size_t)k, rhs);
  AP_CHECK_EQ_INT(ap_la_lstsq_At(b, k, p.A, rhs, RTOL, lam, &resid, s.w, s.iw), AP_OK);
  mul(1, k, b, 1, p.A, lam, res);
  for (int i = 0; i < k; i++) res[i] -= rhs[i];
  mul(0, b, k, 1, p.A, res, ne);
  AP_CHECK_LE(max_abs((size_t)b, ne), TOL * 10 * k);
  AP_CHECK_NEAR(resid, max_abs((size_t)k, res), TOL);
  AP_CHECK(resid > 1e-3); /* a random rhs is not in range(A^T) */
  scratch_done(&s);
}

/* ---- the sizes and the constructed rank-deficient cases ----------------------------------- */

static void check_all(problem *p) {
  check_partition(p);
  check_orth(p);
  check_lstsq(p);
}

static void test_random(void) {
  const int bs[] = {0, 1, 2, 3, 5};
  for (int ib = 0; ib < 5; ib++)
    for (int k = 1; k <= 9; k++) {
      int b = bs[ib], m = b < k ? b : k;
      problem p = random_problem(b, k, m); /* full rank; b > k: consistent redundant rows */
      check_all(&p);
      if (b > m) make_inconsistent(&p), check_partition(&p), check_orth(&p);
      if (m >= 2) { /* rank m - 1: redundant rows, free speeds */
        p = random_problem(b, k, m - 1);
        check_all(&p);
        make_inconsistent(&p), check_partition(&p), check_orth(&p);
      }
    }
  for (int k = 2; k <= 9; k += 3) check_lstsq_inconsistent(k - 1, k);
}

/* Row 2 duplicates row 0 (two wheels on one axle). Inconsistent: a0[2] = a0[0] + 1, so the
 * dropped row misses by exactly 1 (orthonormal) and a0 is 1/sqrt(2) from range(A). */
static void test_duplicate_rows(void) {
  problem p = random_problem(3, 5, 3);
  for (int j = 0; j < 5; j++) p.A[2 + 3 * j] = p.A[0 + 3 * j];
  p.rank = 2;
  consistent_terms(&p);
  check_all(&p);
  p.a0[2] = p.a0[0] + 1.0;
  p.gamma[2] = p.gamma[0] - 1.0;
  p.dist = sqrt(0.5);
  check_partition(&p);
  check_orth(&p);
  int perm[5], r = 0, jpvt[3];
  double F[15], tau[5], B[15], b0[5], Qf[25], Z[25], growth, rcond, resid = -1;
  scratch s = scratch_new(3, 5);
  AP_CHECK_EQ_INT(ap_la_pivot_select(3, 5, p.A, RTOL, perm, &r, s.w, s.iw), AP_OK);
  AP_CHECK_EQ_INT(ap_la_partition_basis(3, 5, r, perm, p.A, p.a0, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_OK);
  AP_CHECK_NEAR(resid, sqrt(0.5), 1e-13);
  AP_CHECK_EQ_INT(ap_la_orth_basis(3, 5, p.A, p.a0, RTOL, &r, F, tau, jpvt, Qf, Z, b0, &resid,
                                   s.w, s.iw), AP_OK);
  AP_CHECK_NEAR(resid, 1.0, 1e-13);
  AP_CHECK(jpvt[2] == 0 || jpvt[2] == 2); /* the dropped row is one of the pair */
  scratch_done(&s);
}

/* Row 3 = 2 row 0 - 0.5 row 1. */
static void test_combination_row(void) {
  problem p = random_problem(4, 6, 4);
  for (int j = 0; j < 6; j++) p.A[3 + 4 * j] = 2.0 * p.A[4 * j] - 0.5 * p.A[1 + 4 * j];
  p.rank = 3;
  consistent_terms(&p);
  check_all(&p);
  make_inconsistent(&p);
  check_partition(&p);
  check_orth(&p);
}

/* A = 0: rank 0, B = I, b0 = 0, and the residual is all of a0. No constraints (b = 0) and a
 * square full-rank A (l = 0) go through the generic checks too. */
static void test_degenerate(void) {
  problem p = {.b = 2, .k = 3, .rank = 0, .dist = 1.5, .a0 = {0.5, -2.0}, .gamma = {0.25, 1.5}};
  check_partition(&p);
  check_orth(&p);
  check_lstsq(&p);
  int perm[3], r = -1, jpvt[2];
  double F[6], tau[3], B[9], b0[3], Qf[9], Z[9], growth = -1, rcond = -1, resid = -1;
  scratch s = scratch_new(2, 3);
  AP_CHECK_EQ_INT(ap_la_pivot_select(2, 3, p.A, RTOL, perm, &r, s.w, s.iw), AP_OK);
  AP_CHECK(r == 0 && perm[0] == 0 && perm[1] == 1 && perm[2] == 2);
  AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 0, perm, p.A, p.a0, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_OK);
  AP_CHECK_NEAR(resid, 2.0, 0.0);
  AP_CHECK_NEAR(growth, 0.0, 0.0);
  AP_CHECK_EQ_INT(ap_la_orth_basis(2, 3, p.A, p.a0, RTOL, &r, F, tau, jpvt, Qf, Z, b0, &resid,
                                   s.w, s.iw), AP_OK);
  AP_CHECK_NEAR(resid, 2.0, 0.0);
  AP_CHECK_NEAR(max_abs(3, b0), 0.0, 0.0);
  scratch_done(&s);

  problem q = {.b = 0, .k = 4, .rank = 0}; /* no constraints: B = Z = I */
  scratch s0 = scratch_new(0, 4);
  double B0[16], F0[1], Z0[16], Q0[16], w0[4];
  int perm0[4];
  check_all(&q);
  AP_CHECK_EQ_INT(ap_la_pivot_select(0, 4, q.A, RTOL, perm0, &r, s0.w, s0.iw), AP_OK);
  AP_CHECK_EQ_INT(ap_la_partition_basis(0, 4, 0, perm0, q.A, q.a0, F0, tau, B0, w0, &growth,
                                        &rcond, &resid, s0.w, s0.iw), AP_OK);
  double I4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  AP_CHECK(memcmp(B0, I4, sizeof I4) == 0);
  AP_CHECK_EQ_INT(ap_la_orth_basis(0, 4, q.A, q.a0, RTOL, &r, F0, tau, jpvt, Q0, Z0, w0, &resid,
                                   s0.w, s0.iw), AP_OK);
  AP_CHECK(memcmp(Z0, I4, sizeof I4) == 0);
  scratch_done(&s0);

  problem sq = random_problem(4, 4, 4); /* r == k: l = 0, b0 = -A^-1 a0 */
  check_all(&sq);
}

/* A = [sin p, -cos p, 0] (the knife edge), dependent speed 0: B = [cos p / sin p, 0; 1 0; 0 1]
 * and growth |cos p / sin p|. The pivoted QR picks the larger of |sin p|, |cos p|. */
static void test_growth(void) {
  const double ps[] = {0.3, 1.0, 1.2, 2.5, -0.7, 1e-3};
  for (int i = 0; i < 6; i++) {
    double p = ps[i], A[3] = {sin(p), -cos(p), 0.0}, a0[1] = {0.0};
    double F[1], tau[1], B[6], b0[3], growth = -1, rcond = -1, resid = -1, c = cos(p) / sin(p);
    int perm[3] = {0, 1, 2}, sel[3], r = 0;
    scratch s = scratch_new(1, 3);
    AP_CHECK_EQ_INT(ap_la_partition_basis(1, 3, 1, perm, A, a0, F, tau, B, b0, &growth, &rcond,
                                          &resid, s.w, s.iw), AP_OK);
    AP_CHECK_NEAR(growth, fabs(c), 4e-16 * fabs(c));
    AP_CHECK_NEAR(B[0], c, 4e-16 * fabs(c));
    AP_CHECK(B[1] == 1.0 && B[2] == 0.0 && B[3] == 0.0 && B[4] == 0.0 && B[5] == 1.0);
    AP_CHECK_NEAR(rcond, 1.0, 0.0);
    AP_CHECK_EQ_INT(ap_la_pivot_select(1, 3, A, RTOL, sel, &r, s.w, s.iw), AP_OK);
    AP_CHECK_EQ_INT(sel[0], fabs(sin(p)) > fabs(cos(p)) ? 0 : 1);
    scratch_done(&s);
  }
}

/* A = [1 0 0; 0 1e-6 0]: |R_11| / |R_00| = 1e-6, so the rank is 2 below that tolerance and 1
 * above it, in every routine that decides it. A2 has R11 = [1 1; 0 1e-4]:
 * rcond = 1 / (1.0001 * 2e4), growth 1e4. */
static void test_rank_tolerance(void) {
  double A[6] = {1, 0, 0, 1e-6, 0, 0}, rhs[3] = {1, 1, 0}, lam[2], resid = -1;
  double F[6], tau[3], Qf[9], Z[9];
  int perm[3], jpvt[2], r = -1;
  scratch s = scratch_new(2, 3);
  for (int t = 0; t < 2; t++) {
    double rtol = t == 0 ? 1e-7 : 1e-5;
    int expect = t == 0 ? 2 : 1;
    AP_CHECK_EQ_INT(ap_la_pivot_select(2, 3, A, rtol, perm, &r, s.w, s.iw), AP_OK);
    AP_CHECK_EQ_INT(r, expect);
    AP_CHECK_EQ_INT(ap_la_orth_basis(2, 3, A, NULL, rtol, &r, F, tau, jpvt, Qf, Z, NULL, &resid,
                                     s.w, s.iw), AP_OK);
    AP_CHECK_EQ_INT(r, expect);
    AP_CHECK_EQ_INT(ap_la_lstsq_At(2, 3, A, rhs, rtol, lam, &resid, s.w, s.iw), AP_OK);
    AP_CHECK_NEAR(lam[0], 1.0, 1e-15);
    AP_CHECK_NEAR(lam[1], t == 0 ? 1e6 : 0.0, 1e-9);
    AP_CHECK_NEAR(resid, t == 0 ? 0.0 : 1.0, 1e-15);
  }
  double A2[6] = {1, 0, 1, 1e-4, 0, 1}, B[3], b0[3], growth, rcond = -1;
  int p2[3] = {0, 1, 2};
  AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 2, p2, A2, NULL, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_OK);
  AP_CHECK_NEAR(rcond, 1.0 / (1.0001 * 2e4), 1e-12); /* ||R11||_1 ||R11^-1||_1 */
  AP_CHECK_NEAR(growth, 1e4, 1e-10);
  scratch_done(&s);
}

/* Zero and non-finite pivots are refused, never divided by. */
static void test_singular(void) {
  double A[6] = {0, 0, 1, 0, 0, 1}; /* 2 x 3: column 0 is zero */
  double a0[2] = {1, 1}, gam[2] = {1, 1}, F[6], tau[3], B[9], b0[3], w[3];
  double growth, rcond, resid;
  int perm[3] = {0, 1, 2}, r = -1;
  scratch s = scratch_new(2, 3);
  AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 1, perm, A, a0, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_ERR_SINGULAR);
  AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 3, perm, A, a0, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_ERR_ARG); /* r > min(b, k) */
  F[0] = 0.0;
  AP_CHECK_EQ_INT(ap_la_partition_particular(2, 3, 1, perm, F, tau, gam, w, &resid, s.w),
                  AP_ERR_SINGULAR);
  A[0] = NAN;
  AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 1, perm, A, a0, F, tau, B, b0, &growth, &rcond,
                                        &resid, s.w, s.iw), AP_ERR_SINGULAR);
  AP_CHECK_EQ_INT(ap_la_pivot_select(2, 3, A, RTOL, perm, &r, s.w, s.iw), AP_ERR_ARG);
  A[0] = 0.0;
  AP_CHECK_EQ_INT(ap_la_pivot_select(2, 3, A, -1.0, perm, &r, s.w, s.iw), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_la_pivot_select(2, 3, A, RTOL, perm, &r, s.w, s.iw), AP_OK);
  AP_CHECK(r == 2 && perm[2] == 0); /* the zero column is independent */
  scratch_done(&s);
}

/* ---- Cholesky, congruence, gemv ----------------------------------------------------------- */

/* Factor G (copy), solve G x = rhs, check the residual and return rcond. */
static double chol_roundtrip(int l, const double *G, int expect) {
  double L[NMAX * NMAX], L2[NMAX * NMAX], x[NMAX], rhs[NMAX], y[NMAX], rcond = -1;
  scratch s = scratch_new(l, l);
  memcpy(L, G, sizeof(double) * (size_t)l * l);
  memcpy(L2, G, sizeof(double) * (size_t)l * l);
  AP_CHECK_EQ_INT(ap_la_chol(l, L, &rcond, s.w, s.iw), expect);
  AP_CHECK_EQ_INT(ap_la_chol(l, L2, NULL, s.w, s.iw), expect); /* no estimate: same verdict */
  if (expect == AP_OK) {
    int same = 1; /* and the same factor, bit for bit (lower triangle) */
    for (int j = 0; j < l; j++)
      for (int i = j; i < l; i++) same = same && L[i + (size_t)j * l] == L2[i + (size_t)j * l];
    AP_CHECK(same);
    rand_fill((size_t)l, rhs);
    memcpy(x, rhs, sizeof(double) * (size_t)l);
    ap_la_chol_solve(l, L, x);
    mul(0, l, l, 1, G, x, y);
    for (int i = 0; i < l; i++) y[i] -= rhs[i];
    double scale = l * max_abs((size_t)l * l, G) * max_abs((size_t)l, x);
    AP_CHECK_LE(max_abs((size_t)l, y), TOL * scale);
  }
  scratch_done(&s);
  return rcond;
}

static void test_chol(void) {
  double I[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  AP_CHECK_NEAR(chol_roundtrip(4, I, AP_OK), 1.0, 1e-15);
  AP_CHECK_NEAR(chol_roundtrip(0, I, AP_OK), 1.0, 0.0);

  double M[36], G[36]; /* random SPD: M^T M + I/2 */
  rand_fill(36, M);
  mul(1, 6, 6, 6, M, M, G);
  for (int i = 0; i < 6; i++) G[i * 7] += 0.5;
  double rc = chol_roundtrip(6, G, AP_OK);
  AP_CHECK(rc > 1e-4 && rc < 1.0);

  /* cond 1e12: G = H diag(s) H, H a Householder reflector, s from 1 to 1e-12 */
  double v[4], H[16], D[16] = {0}, HD[16], G4[16], vv = 0;
  rand_fill(4, v);
  for (int i = 0; i < 4; i++) vv += v[i] * v[i];
  for (int j = 0; j < 4; j++)
    for (int i = 0; i < 4; i++) H[i + 4 * j] = (i == j) - 2.0 * v[i] * v[j] / vv;
  for (int i = 0; i < 4; i++) D[i * 5] = pow(10.0, -4.0 * i);
  mul(0, 4, 4, 4, H, D, HD);
  mul(0, 4, 4, 4, HD, H, G4);
  for (int j = 0; j < 4; j++) /* exactly symmetric */
    for (int i = j + 1; i < 4; i++) G4[j + 4 * i] = G4[i + 4 * j];
  rc = chol_roundtrip(4, G4, AP_OK);
  AP_CHECK(rc > 1e-13 && rc < 1e-11);
  for (int i = 0; i < 16; i++) G4[i] *= 1e6; /* rcond does not depend on the scale */
  AP_CHECK_NEAR(chol_roundtrip(4, G4, AP_OK), rc, 1e-3 * rc);
  double Dg[9] = {4e6, 0, 0, 0, 1e6, 0, 0, 0, 0.25e6}; /* diagonal: rcond = 0.25 / 4 */
  AP_CHECK_NEAR(chol_roundtrip(3, Dg, AP_OK), 1.0 / 16.0, 1e-15);

  double Nspd[4] = {1, 2, 2, 1}, Ind[9] = {1, 0, 0, 0, -1, 0, 0, 0, 1}, Nan[4] = {1, 0, 0, NAN};
  double Inf[4] = {1, 0, 0, INFINITY}, Inf10[4] = {1, INFINITY, INFINITY, 1};
  double Zero[4] = {1, 0, 0, 0};
  chol_roundtrip(2, Nspd, AP_ERR_SINGULAR);
  chol_roundtrip(3, Ind, AP_ERR_SINGULAR);
  chol_roundtrip(2, Nan, AP_ERR_SINGULAR);
  chol_roundtrip(2, Inf, AP_ERR_SINGULAR);   /* infinite pivot */
  chol_roundtrip(2, Inf10, AP_ERR_SINGULAR); /* infinite off-diagonal: pivot 1 - inf^2 */
  chol_roundtrip(2, Zero, AP_ERR_SINGULAR);  /* zero pivot */
}

static void test_congruence(void) {
  for (int k = 1; k <= 9; k += 4)
    for (int l = 1; l <= k; l += 2) {
      double M[NMAX * NMAX], g[NMAX * NMAX], B[NMAX * NMAX], G[NMAX * NMAX], gB[NMAX * NMAX];
      double ref[NMAX * NMAX];
      rand_fill((size_t)k * k, M), rand_fill((size_t)k * l, B);
      mul(1, k, k, k, M, M, g);
      mul(0, k, k, l, g, B, gB);
      mul(1, l, k, l, B, gB, ref);
      ap_la_congruence(k, l, g, B, G, gB);
      int sym = 1;
      for (int j = 0; j < l; j++)
        for (int i = 0; i < l; i++) sym = sym && G[i + j * l] == G[j + i * l];
      AP_CHECK(sym);
      for (int i = 0; i < l * l; i++) ref[i] -= G[i];
      AP_CHECK_LE(max_abs((size_t)l * l, ref), TOL * k * k * max_abs((size_t)k * k, g));
    }
}

static void test_gemv(void) {
  double M[12], x[4], y[4], ref[4];
  rand_fill(12, M), rand_fill(4, x);
  ap_la_gemv(3, 4, M, x, y);
  mul(0, 3, 4, 1, M, x, ref);
  for (int i = 0; i < 3; i++) ref[i] -= y[i];
  AP_CHECK_LE(max_abs(3, ref), 1e-15 * 4);
  ap_la_gemv_t(3, 4, M, x, y);
  mul(1, 4, 3, 1, M, x, ref);
  for (int i = 0; i < 4; i++) ref[i] -= y[i];
  AP_CHECK_LE(max_abs(4, ref), 1e-15 * 4);
  y[0] = y[1] = NAN;
  ap_la_gemv(2, 0, M, x, y); /* empty product: zeros */
  AP_CHECK(y[0] == 0.0 && y[1] == 0.0);
}

/* ---- both paths on the same inputs -------------------------------------------------------- */

/* The result of every per-evaluation routine on one problem, on one path. */
typedef struct results {
  int perm[NMAX], r, rank, jpvt[NMAX];
  double F[NMAX * NMAX], tau[NMAX], B[NMAX * NMAX], b0[NMAX], w[NMAX], growth, rcond, resid;
  double resid_w, Fo[NMAX * NMAX], tauo[NMAX], Qf[NMAX * NMAX], Z[NMAX * NMAX], ZZt[NMAX * NMAX];
  double ob0[NMAX], ow[NMAX], oresid, oresid_w, G[NMAX * NMAX], L[NMAX * NMAX], rcond_G;
  double x[NMAX], gx[NMAX], Btx[NMAX];
} results;

/* Runs the routines with the small-size limit `limit`; g (k x k) SPD, rhs (k) for the solves. */
static void run_path(const problem *p, int limit, const double *g, const double *rhs,
                     results *o) {
  int b = p->b, k = p->k, old = ap_la_set_small_limit(limit);
  double gB[NMAX * NMAX], glow[NMAX * NMAX]; /* g with NaN above the diagonal: never read */
  scratch s = scratch_new(b, k);
  for (int j = 0; j < k; j++)
    for (int i = 0; i < k; i++) glow[i + (size_t)j * k] = i >= j ? g[i + (size_t)j * k] : NAN;
  AP_CHECK_EQ_INT(ap_la_pivot_select(b, k, p->A, RTOL, o->perm, &o->r, s.w, s.iw), AP_OK);
  int l = k - o->r;
  AP_CHECK_EQ_INT(ap_la_partition_basis(b, k, o->r, o->perm, p->A, p->a0, o->F, o->tau, o->B,
                                        o->b0, &o->growth, &o->rcond, &o->resid, s.w, s.iw),
                  AP_OK);
  AP_CHECK_EQ_INT(ap_la_partition_particular(b, k, o->r, o->perm, o->F, o->tau, p->gamma, o->w,
                                             &o->resid_w, s.w), AP_OK);
  AP_CHECK_EQ_INT(ap_la_orth_basis(b, k, p->A, p->a0, RTOL, &o->rank, o->Fo, o->tauo, o->jpvt,
                                   o->Qf, o->Z, o->ob0, &o->oresid, s.w, s.iw), AP_OK);
  AP_CHECK_EQ_INT(ap_la_orth_particular(b, k, o->rank, o->Fo, o->jpvt, o->Qf, p->gamma, o->ow,
                                        &o->oresid_w, s.w), AP_OK);
  for (int i = 0; i < k; i++) /* Z Z^T: the projector on the null space, basis-free */
    for (int j = 0; j < k; j++) {
      double t = 0.0;
      for (int c = 0; c < k - o->rank; c++) t += o->Z[i + (size_t)c * k] * o->Z[j + (size_t)c * k];
      o->ZZt[i + (size_t)j * k] = t;
    }
  ap_la_congruence(k, l, glow, o->B, o->G, gB);
  memcpy(o->L, o->G, sizeof(double) * (size_t)l * l);
  AP_CHECK_EQ_INT(ap_la_chol(l, o->L, &o->rcond_G, s.w, s.iw), AP_OK);
  memcpy(o->x, rhs, sizeof(double) * (size_t)l);
  ap_la_chol_solve(l, o->L, o->x);
  ap_la_gemv(k, k, g, rhs, o->gx);
  ap_la_gemv_t(k, l, o->B, rhs, o->Btx);
  scratch_done(&s);
  ap_la_set_small_limit(old);
}

/* max |x - y| over n entries. */
static double max_diff(size_t n, const double *x, const double *y) {
  double v = 0.0;
  for (size_t i = 0; i < n; i++) v = fmax(v, fabs(x[i] - y[i]));
  return v;
}

/* Largest error seen, in units of its round-off bound (reported; must stay <= 1). */
static double worst_ratio = 0.0;

static void check_same(double diff, double bound) {
  AP_CHECK_LE(diff, bound);
  worst_ratio = fmax(worst_ratio, diff / bound);
}

/* Both paths on p: every output agrees within c eps kappa |x|, kappa a condition estimate. */
static void compare_paths(const problem *p) {
  static results n, a; /* native, LAPACK */
  int b = p->b, k = p->k;
  double M[NMAX * NMAX], g[NMAX * NMAX], rhs[NMAX];
  rand_fill((size_t)k * k, M), rand_fill((size_t)k, rhs);
  mul(1, k, k, k, M, M, g);
  for (int i = 0; i < k; i++) g[i * (k + 1)] += 1.0;
  run_path(p, INT_MAX, g, rhs, &n);
  run_path(p, 0, g, rhs, &a);
  AP_CHECK_EQ_INT(n.r, a.r);
  AP_CHECK(memcmp(n.perm, a.perm, sizeof(int) * (size_t)k) == 0); /* same pivot_select */
  AP_CHECK_EQ_INT(n.rank, a.rank);
  AP_CHECK(b == 0 || memcmp(n.jpvt, a.jpvt, sizeof(int) * (size_t)b) == 0);
  int r = a.r, l = k - r;
  double e = 16 * DBL_EPSILON * k;
  /* partitioned: R11 and the reflectors, B, b0, w, growth, residuals; rcond to its digits */
  double kR = 1.0 / a.rcond, nA = fmax(1.0, max_abs((size_t)b * k, p->A));
  double sB = fmax(1.0, max_abs((size_t)k * l, a.B));
  check_same(max_diff((size_t)b * r, n.F, a.F), e * kR * nA);
  check_same(max_diff((size_t)r, n.tau, a.tau), e * kR);
  check_same(max_diff((size_t)k * l, n.B, a.B), e * kR * sB);
  check_same(fabs(n.growth - a.growth), e * kR * sB);
  check_same(max_diff((size_t)k, n.b0, a.b0), e * kR * fmax(1.0, max_abs((size_t)k, a.b0)));
  check_same(max_diff((size_t)k, n.w, a.w), e * kR * fmax(1.0, max_abs((size_t)k, a.w)));
  check_same(fabs(n.resid - a.resid), e * kR * nA * fmax(sB, max_abs((size_t)k, a.b0)));
  check_same(fabs(n.resid_w - a.resid_w), e * kR * nA * fmax(1.0, max_abs((size_t)k, a.w)));
  AP_CHECK_NEAR(n.rcond, a.rcond, 1e-6 * a.rcond);
  /* orthonormal: spans Z Z^T, minimum-norm solutions, residuals; kappa = |R_00| / |R_r-1| */
  double kO = a.rank > 0 ? fabs(a.Fo[0]) / fabs(a.Fo[(a.rank - 1) * (k + 1)]) : 1.0;
  check_same(max_diff((size_t)k * k, n.ZZt, a.ZZt), e * kO);
  check_same(max_diff((size_t)k, n.ob0, a.ob0), e * kO * fmax(1.0, max_abs((size_t)k, a.ob0)));
  check_same(max_diff((size_t)k, n.ow, a.ow), e * kO * fmax(1.0, max_abs((size_t)k, a.ow)));
  check_same(fabs(n.oresid - a.oresid), e * kO * nA * fmax(1.0, max_abs((size_t)k, a.ob0)));
  check_same(fabs(n.oresid_w - a.oresid_w), e * kO * nA * fmax(1.0, max_abs((size_t)k, a.ow)));
  /* G = B^T g B, its factor and a solve (kappa = 1 / rcond of G), g x and B^T x */
  double sG = max_abs((size_t)l * l, a.G), kG = 1.0 / a.rcond_G, sg = max_abs((size_t)k * k, g);
  check_same(max_diff((size_t)l * l, n.G, a.G), e * kR * sB * sB * sg);
  double dL = 0.0;
  for (int j = 0; j < l; j++)
    for (int i = j; i < l; i++) dL = fmax(dL, fabs(n.L[i + j * l] - a.L[i + j * l]));
  check_same(dL, e * kG * sqrt(sG));
  check_same(max_diff((size_t)l, n.x, a.x), e * kG * kR * max_abs((size_t)l, a.x));
  AP_CHECK_NEAR(n.rcond_G, a.rcond_G, 1e-6 * a.rcond_G);
  check_same(max_diff((size_t)k, n.gx, a.gx), e * sg * max_abs((size_t)k, rhs));
  check_same(max_diff((size_t)l, n.Btx, a.Btx), e * sB * max_abs((size_t)k, rhs));
}

static void test_paths(void) {
  const int bs[] = {0, 1, 2, 3, 5, 8, 12};
  for (int ib = 0; ib < 7; ib++)
    for (int k = 1; k <= NMAX; k++) {
      int b = bs[ib], m = b < k ? b : k;
      if (m == k) continue; /* l >= 1: a mechanism has a free speed */
      problem p = random_problem(b, k, m);
      compare_paths(&p);
      if (b > m) make_inconsistent(&p), compare_paths(&p);
      if (m >= 2) {
        p = random_problem(b, k, m - 1);
        compare_paths(&p);
        make_inconsistent(&p), compare_paths(&p);
      }
    }
  problem d = random_problem(3, 5, 3); /* duplicate rows: ties in the pivoting (first wins) */
  for (int j = 0; j < 5; j++) d.A[2 + 3 * j] = d.A[3 * j];
  d.rank = 2;
  consistent_terms(&d);
  compare_paths(&d);
  d = random_problem(4, 6, 4); /* rows 1 and 3 duplicate, and the larger */
  for (int j = 0; j < 6; j++) d.A[1 + 4 * j] = d.A[3 + 4 * j] = 4.0 * d.A[1 + 4 * j];
  d.rank = 3;
  consistent_terms(&d);
  compare_paths(&d);
  printf("linalg: largest native - LAPACK difference: %.3g of its round-off bound\n",
         worst_ratio);
}

/* rcond = NULL: no estimate, so a nearly singular R11 is refused by the threshold
 * |R11_ii| <= 64 eps max ||Ad_j||, on both paths; with rcond it passes and rcond tells. */
static void test_no_rcond(void) {
  /* Ad = [1 1; 1 1 + 1e-15]: |R11_11| ~ 7e-16 < 64 eps sqrt(2) ~ 2e-14 */
  double A[6] = {1, 1, 1, 1 + 1e-15, 0.5, -0.5}, a0[2] = {0, 0};
  double F[6], tau[3], B[3], b0[3], growth, rcond = -1, resid;
  int perm[3] = {0, 1, 2};
  scratch s = scratch_new(2, 3);
  for (int path = 0; path < 2; path++) {
    int old = ap_la_set_small_limit(path ? 0 : INT_MAX);
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 2, perm, A, a0, F, tau, B, b0, &growth, NULL,
                                          &resid, s.w, s.iw), AP_ERR_SINGULAR);
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 2, perm, A, a0, F, tau, B, b0, &growth, &rcond,
                                          &resid, s.w, s.iw), AP_OK);
    AP_CHECK(rcond < 1e-14);
    double A2[6] = {1, 1, 1, 1 + 1e-12, 0.5, -0.5}; /* 3.5e-13 apart: kept */
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 2, perm, A2, a0, F, tau, B, b0, &growth, NULL,
                                          &resid, s.w, s.iw), AP_OK);
    double Az[6] = {0, 0, 1, 0, 0, 1}, An[6] = {NAN, 0, 1, 0, 0, 1}; /* zero, NaN column */
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 1, perm, Az, a0, F, tau, B, b0, &growth, NULL,
                                          &resid, s.w, s.iw), AP_ERR_SINGULAR);
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 3, 1, perm, An, a0, F, tau, B, b0, &growth, NULL,
                                          &resid, s.w, s.iw), AP_ERR_SINGULAR);
    double Au[4] = {1, 0, NAN, 1}; /* NaN above the diagonal of R11 only: still refused */
    AP_CHECK_EQ_INT(ap_la_partition_basis(2, 2, 2, perm, Au, NULL, F, tau, NULL, NULL, &growth,
                                          NULL, &resid, s.w, s.iw), AP_ERR_SINGULAR);
    double Ok[4] = {4, 2, 2, 3}, Neg[4] = {4, 2, 2, 1}, L[4], rc = -1; /* 4 - 1 - 1 < 0 */
    memcpy(L, Ok, sizeof L);
    AP_CHECK_EQ_INT(ap_la_chol(2, L, NULL, s.w, s.iw), AP_OK);
    AP_CHECK_NEAR(L[0], 2.0, 0.0);
    AP_CHECK_NEAR(L[3], sqrt(2.0), 4e-16);
    AP_CHECK_EQ_INT(ap_la_chol(0, L, NULL, s.w, s.iw), AP_OK);
    AP_CHECK_EQ_INT(ap_la_chol(0, L, &rc, s.w, s.iw), AP_OK);
    AP_CHECK_NEAR(rc, 1.0, 0.0);
    memcpy(L, Neg, sizeof L);
    AP_CHECK_EQ_INT(ap_la_chol(2, L, NULL, s.w, s.iw), AP_ERR_SINGULAR);
    ap_la_set_small_limit(old);
  }
  scratch_done(&s);
}

/* A scaled by 2^-560 (squares underflow) and 2^560 (squares overflow): the norms take their
 * scaled fallbacks, and B, b0, w, Z Z^T and the ranks are those of the unscaled problem. At
 * 2^-1040 the entries are subnormal (about 34 bits left): the native path gives the same results
 * to 1e-7 (OpenBLAS's dtrsm multiplies by 1 / R_ii, which overflows there, and dtrcon returns 0:
 * that scale is for the native path only). */
static void test_scaling(void) {
  const double scales[3] = {0x1p-560, 0x1p560, 0x1p-1040};
  problem ps[2] = {random_problem(3, 6, 3), random_problem(4, 7, 3)};
  for (int ip = 0; ip < 2; ip++)
    for (int path = 0; path < 2; path++) {
      static results ref, o;
      const problem *p = &ps[ip];
      double g[NMAX * NMAX] = {0}, rhs[NMAX] = {0};
      int b = p->b, k = p->k;
      for (int i = 0; i < k; i++) g[i * (k + 1)] = 1.0;
      run_path(p, path ? 0 : INT_MAX, g, rhs, &ref);
      for (int is = 0; is < (path ? 2 : 3); is++) {
        problem q = *p;
        for (int i = 0; i < b * k; i++) q.A[i] *= scales[is];
        for (int i = 0; i < b; i++) q.a0[i] *= scales[is], q.gamma[i] *= scales[is];
        run_path(&q, path ? 0 : INT_MAX, g, rhs, &o);
        int l = k - ref.r;
        double t0 = is < 2 ? 1e-13 : 1e-7, tz = is < 2 ? 1e-12 : 1e-7;
        double tol = t0 * fmax(1.0, max_abs((size_t)k * l, ref.B)) / ref.rcond;
        AP_CHECK_EQ_INT(o.r, ref.r);
        AP_CHECK_EQ_INT(o.rank, ref.rank);
        AP_CHECK_LE(max_diff((size_t)k * l, o.B, ref.B), tol);
        AP_CHECK_LE(max_diff((size_t)k, o.b0, ref.b0), tol * fmax(1.0, max_abs(k, ref.b0)));
        AP_CHECK_LE(max_diff((size_t)k, o.w, ref.w), tol * fmax(1.0, max_abs(k, ref.w)));
        AP_CHECK_LE(max_diff((size_t)k * k, o.ZZt, ref.ZZt), tz);
        AP_CHECK_LE(max_diff((size_t)k, o.ob0, ref.ob0), tz * fmax(1.0, max_abs(k, ref.ob0)));
        if (is < 2) AP_CHECK_NEAR(o.rcond, ref.rcond, 1e-6 * ref.rcond);
      }
    }
}

/* The limit is a setting that reads back; the default is AP_LA_SMALL_LIMIT. */
static void test_limit(void) {
  AP_CHECK_EQ_INT(ap_la_small_limit(), AP_LA_SMALL_LIMIT);
  int old = ap_la_set_small_limit(3);
  AP_CHECK_EQ_INT(old, AP_LA_SMALL_LIMIT);
  AP_CHECK_EQ_INT(ap_la_small_limit(), 3);
  AP_CHECK_EQ_INT(ap_la_set_small_limit(-5), 3);
  AP_CHECK_EQ_INT(ap_la_small_limit(), 0);
  ap_la_set_small_limit(old);
}

/* Every test above, on the path the limit selects. */
static void run_suite(int limit) {
  int old = ap_la_set_small_limit(limit);
  rng = 0x9E3779B97F4A7C15ull; /* the same matrices on both paths */
  test_random();
  test_duplicate_rows();
  test_combination_row();
  test_degenerate();
  test_growth();
  test_rank_tolerance();
  test_singular();
  test_chol();
  test_congruence();
  test_gemv();
  ap_la_set_small_limit(old);
}

int main(void) {
  test_limit();
  run_suite(0);       /* LAPACK / BLAS */
  run_suite(INT_MAX); /* native kernels */
  test_paths();
  test_no_rcond();
  test_scaling();
  return ap_check_finish("linalg");
}
