/* Tests of lib/linalg, second part (docs/design.md §1 "Choosing B"): Cholesky with its
 * condition estimate, the congruence B^T g B and gemv, on each path; then both paths on the same
 * inputs. The bases, ranks and least squares are in test_linalg.c; the matrices, products and
 * guarded scratch in linalg_problems.c.
 *
 * Two paths: test_chol, test_congruence and test_gemv run on the LAPACK/BLAS path
 * (ap_la_set_small_limit(0)) and on the native small-size kernels (limit INT_MAX) from the same
 * generator state. test_paths then runs both paths on the same inputs and compares their
 * results (B, b0, w, spans Z Z^T, G, Cholesky factors and solves, ranks) within round-off scaled
 * by condition estimates; test_no_rcond covers rcond = NULL (no estimate, the singularity
 * thresholds instead); test_scaling, entries near underflow and overflow.
 *
 * The generator continues from where test_linalg.c's bases tests leave it (LINALG_CHOL_STATE),
 * so every test here meets the matrices it met when both files were one program. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <string.h>

#include "appell/status.h"
#include "check.h"
#include "linalg_problems.h"

/* linalg_rng after test_linalg.c's run_suite, from LINALG_SEED: test_random through
 * test_singular draw the same numbers on either path, so this state is fixed. */
#define LINALG_CHOL_STATE 0x9123D3EBF7B3AE39ull

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
  printf("linalg_paths: largest native - LAPACK difference: %.3g of its round-off bound\n",
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

/* The tests of this file that run on one path. */
static void one_path(void) {
  test_chol();
  test_congruence();
  test_gemv();
}

int main(void) {
  both_paths(LINALG_CHOL_STATE, one_path);
  test_paths();
  test_no_rcond();
  test_scaling();
  return ap_check_finish("linalg_paths");
}
