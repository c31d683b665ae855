/* Complex-step variants of the lib/linalg kernels (linalg/scalar.h): derivatives exact to
 * round-off, checked against closed forms and against Ridders' extrapolated differences of the
 * double routines.
 *
 * For a direction dX of the inputs, a routine run on X + i h dX (h = AP_CS_STEP) gives
 * Im(out) / h = d out. Checks, on fixed-seed random problems (b x k, b <= k <= 12):
 *  - real parts equal the double routine's results to a few ulps;
 *  - partitioned basis B, b0 and particular w: d(-Ad^-1 Ai), d(-Ad^-1 a0), d(Ad^-1 gamma) in
 *    closed form (b == rank), to 1e-13 relative; with redundant rows against Ridders;
 *  - the exact-zero case: Ad has exact zeros below its diagonal while dA does not there (the
 *    Householder shortcut tau = 0 must not drop the perturbation);
 *  - Cholesky and solve: d(G^-1 r) = G^-1 (dr - dG x); congruence d(B^T g B); gemv;
 *  - orthonormal basis: b0 = -A^+ a0 (smooth at full row rank) and the projector Z Z^T against
 *    Ridders; least squares lambda = (A^T)^+ rhs against Ridders (full rank and duplicated rows);
 *  - Ridders agrees with the closed forms within its own error estimate (the estimate bounds
 *    the true error), and the complex step agrees with Ridders within Ridders' estimate;
 *  - pivot_select_cs decides as the double routine on the real part; rcond != NULL is refused. */
#include <complex.h>
#undef I
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "appell/status.h"
#include "check.h"
#include "linalg/linalg.h"
#include "linalg/scalar.h"
#include "testrand.h"

typedef double _Complex cplx;

#define H AP_CS_STEP
#define NMAX 12

static uint64_t rng = 0x2545F4914F6CDD1Dull;

static void fill(size_t n, double *x) {
  for (size_t i = 0; i < n; i++) x[i] = ap_test_srand(&rng); /* uniform in [-1, 1) */
}

static void seed(size_t n, const double *x, const double *dx, cplx *z) {
  for (size_t i = 0; i < n; i++) z[i] = x[i] + (dx ? dx[i] * H : 0.0) * _Complex_I;
}

static double dmax(size_t n, const double *x) {
  double m = 0.0;
  for (size_t i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* |Im z / h - ref| <= tol max(1, |ref|) for every entry; real parts equal re within 8 ulp
 * (the same native algorithm) or re_tol (another algorithm: LAPACK). */
static double re_tol = 8 * DBL_EPSILON;

static void check_deriv(size_t n, const cplx *z, const double *re, const double *ref,
                        double tol) {
  double scale = fmax(1.0, dmax(n, ref)), worst = 0.0, rworst = 0.0;
  for (size_t i = 0; i < n; i++) {
    worst = fmax(worst, fabs(cimag(z[i]) / H - ref[i]));
    if (re) rworst = fmax(rworst, fabs(creal(z[i]) - re[i]) / fmax(1.0, fabs(re[i])));
  }
  AP_CHECK_LE(worst, tol * scale);
  if (re) AP_CHECK_LE(rworst, re_tol);
}

/* ---- closed forms ---------------------------------------------------------------------- */

/* x = M^-1 y for a small square M (n x n, column-major) by Gaussian elimination with partial
 * pivoting on copies; several right-hand sides in Y (n x nr). */
static void gsolve(int n, const double *M, int nr, const double *Y, double *X) {
  double A[NMAX * NMAX] = {0}, B[NMAX * (NMAX + 2)] = {0};
  memcpy(A, M, sizeof *A * (size_t)n * n), memcpy(B, Y, sizeof *B * (size_t)n * nr);
  for (int c = 0; c < n; c++) {
    int p = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(A[r + c * n]) > fabs(A[p + c * n])) p = r;
    for (int j = 0; j < n; j++) {
      double t = A[c + j * n];
      A[c + j * n] = A[p + j * n], A[p + j * n] = t;
    }
    for (int j = 0; j < nr; j++) {
      double t = B[c + j * n];
      B[c + j * n] = B[p + j * n], B[p + j * n] = t;
    }
    for (int r = c + 1; r < n; r++) {
      double f = A[r + c * n] / A[c + c * n];
      for (int j = c; j < n; j++) A[r + j * n] -= f * A[c + j * n];
      for (int j = 0; j < nr; j++) B[r + j * n] -= f * B[c + j * n];
    }
  }
  for (int j = 0; j < nr; j++)
    for (int r = n - 1; r >= 0; r--) {
      double s = B[r + j * n];
      for (int c = r + 1; c < n; c++) s -= A[r + c * n] * X[c + j * n];
      X[r + j * n] = s / A[r + r * n];
    }
}

typedef struct part {
  int b, k, r, perm[NMAX];
  double A[NMAX * NMAX], dA[NMAX * NMAX], a0[NMAX], da0[NMAX], gam[NMAX], dgam[NMAX];
} part;

/* Closed-form derivatives of B, b0, w for b == r: with X = Ad^-1 [Ai a0 gamma],
 * dX = Ad^-1 ([dAi da0 dgamma] - dAd X). */
static void part_closed(const part *P, double *dB, double *db0, double *dw) {
  int b = P->b, k = P->k, r = P->r, l = k - r, nc = l + 2;
  double Ad[NMAX * NMAX] = {0}, dAd[NMAX * NMAX] = {0}, R[NMAX * (NMAX + 2)] = {0};
  double X[NMAX * (NMAX + 2)] = {0}, dR[NMAX * (NMAX + 2)] = {0}, T[NMAX * (NMAX + 2)] = {0};
  for (int i = 0; i < r; i++)
    for (int s = 0; s < b; s++)
      Ad[s + i * b] = P->A[s + P->perm[i] * b], dAd[s + i * b] = P->dA[s + P->perm[i] * b];
  for (int s = 0; s < b; s++) {
    for (int j = 0; j < l; j++)
      R[s + j * b] = P->A[s + P->perm[r + j] * b], dR[s + j * b] = P->dA[s + P->perm[r + j] * b];
    R[s + l * b] = P->a0[s], dR[s + l * b] = P->da0[s];
    R[s + (l + 1) * b] = P->gam[s], dR[s + (l + 1) * b] = P->dgam[s];
  }
  gsolve(b, Ad, nc, R, X);
  for (int j = 0; j < nc; j++)
    for (int s = 0; s < b; s++) {
      double t = dR[s + j * b];
      for (int c = 0; c < r; c++) t -= dAd[s + c * b] * X[c + j * b];
      T[s + j * b] = t;
    }
  gsolve(b, Ad, nc, T, X);   /* X = dX now */
  memset(dB, 0, sizeof *dB * (size_t)k * l), memset(db0, 0, sizeof *db0 * (size_t)k);
  memset(dw, 0, sizeof *dw * (size_t)k);
  for (int i = 0; i < r; i++) {
    for (int j = 0; j < l; j++) dB[P->perm[i] + j * k] = -X[i + j * b];
    db0[P->perm[i]] = -X[i + l * b], dw[P->perm[i]] = X[i + (l + 1) * b];
  }
}

static void random_part(part *P, int b, int k) {
  P->b = b, P->k = k;
  fill((size_t)b * k, P->A), fill((size_t)b * k, P->dA);
  fill(b, P->a0), fill(b, P->da0), fill(b, P->gam), fill(b, P->dgam);
  double work[4096];
  int iwork[64];
  AP_CHECK_EQ_INT(ap_la_pivot_select(b, k, P->A, 1e-10, P->perm, &P->r, work, iwork), AP_OK);
}

/* The complex-step partition: B, b0, w at A + i h dA etc. */
static int part_cs(const part *P, cplx *B, cplx *b0, cplx *w) {
  int b = P->b, k = P->k;
  cplx A[NMAX * NMAX], a0[NMAX], gam[NMAX], F[NMAX * NMAX], tau[NMAX], work[4096];
  int iwork[64];
  double growth, resid;
  seed((size_t)b * k, P->A, P->dA, A), seed(b, P->a0, P->da0, a0), seed(b, P->gam, P->dgam, gam);
  int rc = ap_la_partition_basis_cs(b, k, P->r, P->perm, A, a0, F, tau, B, b0, &growth, NULL,
                                    &resid, work, iwork);
  if (rc == AP_OK)
    rc = ap_la_partition_particular_cs(b, k, P->r, P->perm, F, tau, gam, w, &resid, work);
  return rc;
}

static void part_double(const part *P, double t, double *B, double *b0, double *w) {
  int b = P->b, k = P->k;
  double A[NMAX * NMAX], a0[NMAX], gam[NMAX], F[NMAX * NMAX], tau[NMAX], work[4096];
  int iwork[64];
  double growth, resid;
  for (int i = 0; i < b * k; i++) A[i] = P->A[i] + t * P->dA[i];
  for (int i = 0; i < b; i++) a0[i] = P->a0[i] + t * P->da0[i], gam[i] = P->gam[i] + t * P->dgam[i];
  AP_CHECK_EQ_INT(ap_la_partition_basis(b, k, P->r, P->perm, A, a0, F, tau, B, b0, &growth,
                                        NULL, &resid, work, iwork), AP_OK);
  AP_CHECK_EQ_INT(ap_la_partition_particular(b, k, P->r, P->perm, F, tau, gam, w, &resid, work),
                  AP_OK);
}

/* ---- Ridders along a direction ------------------------------------------------------------ */

typedef void (*path_fn)(const void *prob, double t, double *out);

typedef struct path {
  path_fn f;
  const void *prob;
} path;

static int path_eval(const double *x, double *f, void *user) {
  const path *p = user;
  p->f(p->prob, x[0], f);
  return AP_OK;
}

/* d out / dt at t = 0 by Ridders (m outputs) with its error estimates. */
static double ridders_h = 0.01;
static double ridders_epsf = AP_AN_EPSF;   /* relative accuracy of the function values */
static double worst_ratio = 0.0;   /* largest |complex step - Ridders| / Ridders' estimate */

static void ridders(path_fn f, const void *prob, int m, double *df, double *err) {
  path p = {f, prob};
  double x = 0.0, *scratch = malloc(sizeof *scratch * ap_an_ridders_scratch(m));
  AP_CHECK(scratch != NULL);
  AP_CHECK_EQ_INT(ap_an_ridders(path_eval, &p, 1, &x, 0, ridders_h, ridders_epsf, NULL, m, df,
                                err, scratch), AP_OK);
  free(scratch);
}

/* The complex step agrees with Ridders within RIDDERS_K times Ridders' estimate plus 16 ulps
 * of the scale (the estimate is a heuristic with a round-off floor: the largest measured ratio
 * is printed). */
#define RIDDERS_K 2.0

static void check_vs_ridders(int m, const cplx *z, const double *df, const double *err) {
  double scale = fmax(1.0, dmax((size_t)m, df)), worst = 0.0, floor = 16 * DBL_EPSILON * scale;
  for (int i = 0; i < m; i++) {
    double d = fabs(cimag(z[i]) / H - df[i]);
    worst = fmax(worst, (d - floor) / (RIDDERS_K * err[i]));
    if (d > floor) worst_ratio = fmax(worst_ratio, d / err[i]);
  }
  AP_CHECK_LE(worst, 1.0);
}

/* ---- partitioned basis ---------------------------------------------------------------------- */

static void part_path(const void *prob, double t, double *out) {
  const part *P = prob;
  int k = P->k, l = k - P->r;
  part_double(P, t, out, out + (size_t)k * l, out + (size_t)k * l + k);
}

static void test_partition(void) {
  static const int sizes[][2] = {{1, 3}, {2, 5}, {3, 6}, {4, 4 + 3}, {6, 12}, {5, 9}};
  for (size_t s = 0; s < sizeof sizes / sizeof *sizes; s++) {
    part P;
    random_part(&P, sizes[s][0], sizes[s][1]);
    int k = P.k, l = k - P.r, m = k * l + 2 * k;
    AP_CHECK_EQ_INT(P.r, P.b);
    cplx Bc[NMAX * NMAX + 2 * NMAX];
    double re[NMAX * NMAX + 2 * NMAX], ref[NMAX * NMAX + 2 * NMAX];
    double df[NMAX * NMAX + 2 * NMAX], err[NMAX * NMAX + 2 * NMAX];
    AP_CHECK_EQ_INT(part_cs(&P, Bc, Bc + (size_t)k * l, Bc + (size_t)k * l + k), AP_OK);
    part_double(&P, 0.0, re, re + (size_t)k * l, re + (size_t)k * l + k);
    part_closed(&P, ref, ref + (size_t)k * l, ref + (size_t)k * l + k);
    check_deriv((size_t)m, Bc, re, ref, 1e-13);
    ridders(part_path, &P, m, df, err);
    check_vs_ridders(m, Bc, df, err);
    /* Ridders' own estimate bounds its true error (against the closed form) the same way */
    double worst = 0.0, floor = 16 * DBL_EPSILON * fmax(1.0, dmax((size_t)m, ref));
    for (int i = 0; i < m; i++) worst = fmax(worst, (fabs(df[i] - ref[i]) - floor) / err[i]);
    AP_CHECK_LE(worst, RIDDERS_K);
  }
}

/* Ad with exact zeros below the diagonal (upright mechanisms give such A), perturbed there. */
static void test_exact_zeros(void) {
  part P;
  random_part(&P, 3, 6);
  for (int i = 0; i < 3; i++)
    for (int s = 0; s < 3; s++) P.A[s + P.perm[i] * 3] = s == i ? 1.0 + i : (s < i ? 0.5 : 0.0);
  for (int i = 0; i < 3 * 6; i++) P.dA[i] = 1.0;   /* every entry moves, the zeros too */
  int k = P.k, l = k - P.r, m = k * l + 2 * k;
  cplx Bc[NMAX * NMAX + 2 * NMAX];
  double ref[NMAX * NMAX + 2 * NMAX];
  AP_CHECK_EQ_INT(part_cs(&P, Bc, Bc + (size_t)k * l, Bc + (size_t)k * l + k), AP_OK);
  part_closed(&P, ref, ref + (size_t)k * l, ref + (size_t)k * l + k);
  check_deriv((size_t)m, Bc, NULL, ref, 1e-13);
}

/* Redundant rows: row 3 = row 0 + row 1 (a0, gamma consistent), perturbed consistently. */
static void test_redundant(void) {
  part P;
  random_part(&P, 4, 8);
  for (int j = 0; j < 8; j++) {
    P.A[3 + 4 * j] = P.A[0 + 4 * j] + P.A[1 + 4 * j];
    P.dA[3 + 4 * j] = P.dA[0 + 4 * j] + P.dA[1 + 4 * j];
  }
  P.a0[3] = P.a0[0] + P.a0[1], P.da0[3] = P.da0[0] + P.da0[1];
  P.gam[3] = P.gam[0] + P.gam[1], P.dgam[3] = P.dgam[0] + P.dgam[1];
  double work[4096];
  int iwork[64];
  AP_CHECK_EQ_INT(ap_la_pivot_select(4, 8, P.A, 1e-10, P.perm, &P.r, work, iwork), AP_OK);
  AP_CHECK_EQ_INT(P.r, 3);
  int k = P.k, l = k - P.r, m = k * l + 2 * k;
  cplx Bc[NMAX * NMAX + 2 * NMAX];
  double df[NMAX * NMAX + 2 * NMAX], err[NMAX * NMAX + 2 * NMAX];
  AP_CHECK_EQ_INT(part_cs(&P, Bc, Bc + (size_t)k * l, Bc + (size_t)k * l + k), AP_OK);
  ridders(part_path, &P, m, df, err);
  check_vs_ridders(m, Bc, df, err);
}

/* ---- Cholesky, congruence, gemv ------------------------------------------------------------- */

static void test_chol(void) {
  for (int l = 1; l <= 8; l += 3) {
    double M[NMAX * NMAX], G[NMAX * NMAX], dG[NMAX * NMAX], rhs[NMAX], drhs[NMAX], x[NMAX];
    double t[NMAX], ref[NMAX];
    fill((size_t)l * l, M), fill(l, rhs), fill(l, drhs), fill((size_t)l * l, dG);
    for (int i = 0; i < l; i++)   /* G = M^T M + l I, dG symmetric */
      for (int j = 0; j < l; j++) {
        double s = i == j ? l : 0.0;
        for (int p = 0; p < l; p++) s += M[p + i * l] * M[p + j * l];
        G[i + j * l] = s;
      }
    for (int i = 0; i < l; i++)
      for (int j = 0; j < i; j++) dG[j + i * l] = dG[i + j * l];
    cplx Gc[NMAX * NMAX], xc[NMAX], work[64];
    int iwork[16];
    seed((size_t)l * l, G, dG, Gc), seed(l, rhs, drhs, xc);
    double rc = 0.0;
    AP_CHECK_EQ_INT(ap_la_chol_cs(l, Gc, &rc, work, iwork), AP_ERR_ARG);   /* rcond refused */
    seed((size_t)l * l, G, dG, Gc);
    AP_CHECK_EQ_INT(ap_la_chol_cs(l, Gc, NULL, work, iwork), AP_OK);
    ap_la_chol_solve_cs(l, Gc, xc);
    gsolve(l, G, 1, rhs, x);   /* dx = G^-1 (drhs - dG x) */
    for (int i = 0; i < l; i++) {
      t[i] = drhs[i];
      for (int j = 0; j < l; j++) t[i] -= dG[i + j * l] * x[j];
    }
    gsolve(l, G, 1, t, ref);
    check_deriv(l, xc, x, ref, 1e-13);
  }
}

static void test_congruence_gemv(void) {
  int k = 7, l = 4;
  double g[NMAX * NMAX], dg[NMAX * NMAX], B[NMAX * NMAX], dB[NMAX * NMAX], ref[NMAX * NMAX];
  fill((size_t)k * k, g), fill((size_t)k * k, dg), fill((size_t)k * l, B), fill((size_t)k * l, dB);
  for (int i = 0; i < k; i++)
    for (int j = 0; j < i; j++) g[j + i * k] = g[i + j * k], dg[j + i * k] = dg[i + j * k];
  cplx gc[NMAX * NMAX], Bc[NMAX * NMAX], Gc[NMAX * NMAX], gB[NMAX * NMAX], y[NMAX];
  seed((size_t)k * k, g, dg, gc), seed((size_t)k * l, B, dB, Bc);
  ap_la_congruence_cs(k, l, gc, Bc, Gc, gB);
  for (int i = 0; i < l; i++)   /* dG = dB^T g B + B^T dg B + B^T g dB */
    for (int j = 0; j < l; j++) {
      double s = 0.0;
      for (int p = 0; p < k; p++)
        for (int q = 0; q < k; q++)
          s += dB[p + i * k] * g[p + q * k] * B[q + j * k] + B[p + i * k] * dg[p + q * k] *
               B[q + j * k] + B[p + i * k] * g[p + q * k] * dB[q + j * k];
      ref[i + j * l] = s;
    }
  check_deriv((size_t)l * l, Gc, NULL, ref, 1e-13);
  double x[NMAX], dx[NMAX];
  cplx xc[NMAX];
  fill(l, x), fill(l, dx), seed(l, x, dx, xc);
  ap_la_gemv_cs(k, l, Bc, xc, y);   /* d(B x) = dB x + B dx */
  for (int i = 0; i < k; i++) {
    ref[i] = 0.0;
    for (int j = 0; j < l; j++) ref[i] += dB[i + j * k] * x[j] + B[i + j * k] * dx[j];
  }
  check_deriv(k, y, NULL, ref, 1e-14);
  cplx yt[NMAX];
  seed(k, ref, NULL, y);
  ap_la_gemv_t_cs(k, l, Bc, y, yt);   /* d(B^T y) = dB^T y, y real */
  for (int j = 0; j < l; j++) {
    double s = 0.0;
    for (int i = 0; i < k; i++) s += dB[i + j * k] * ref[i];
    x[j] = s;
  }
  check_deriv(l, yt, NULL, x, 1e-14);
}

/* ---- orthonormal basis, least squares ------------------------------------------------------ */

typedef struct orth {
  int b, k;
  double A[NMAX * NMAX], dA[NMAX * NMAX], a0[NMAX], da0[NMAX], gam[NMAX], dgam[NMAX];
} orth;

/* out = [b0 (k), Z Z^T (k x k), w (k)] of the double routines at t. */
static void orth_path(const void *prob, double t, double *out) {
  const orth *O = prob;
  int b = O->b, k = O->k, rank = 0;
  double A[NMAX * NMAX], a0[NMAX], gam[NMAX], F[NMAX * NMAX], tau[NMAX], Qf[NMAX * NMAX];
  double Z[NMAX * NMAX], work[4096], resid;
  int jpvt[NMAX], iwork[64];
  for (int i = 0; i < b * k; i++) A[i] = O->A[i] + t * O->dA[i];
  for (int i = 0; i < b; i++) a0[i] = O->a0[i] + t * O->da0[i], gam[i] = O->gam[i] + t * O->dgam[i];
  AP_CHECK_EQ_INT(ap_la_orth_basis(b, k, A, a0, 1e-10, &rank, F, tau, jpvt, Qf, Z, out, &resid,
                                   work, iwork), AP_OK);
  for (int i = 0; i < k; i++)
    for (int j = 0; j < k; j++) {
      double s = 0.0;
      for (int c = 0; c < k - rank; c++) s += Z[i + c * k] * Z[j + c * k];
      out[k + i + j * k] = s;
    }
  AP_CHECK_EQ_INT(ap_la_orth_particular(b, k, rank, F, jpvt, Qf, gam, out + k + k * k, &resid,
                                        work), AP_OK);
}

static void test_orth(void) {
  for (int s = 0; s < 3; s++) {
    orth O = {1 + 2 * s, 3 + 3 * s, {0}, {0}, {0}, {0}, {0}, {0}};
    int b = O.b, k = O.k, rank = 0, m = 2 * k + k * k;
    fill((size_t)b * k, O.A), fill((size_t)b * k, O.dA), fill(b, O.a0), fill(b, O.da0);
    fill(b, O.gam), fill(b, O.dgam);
    cplx A[NMAX * NMAX], a0[NMAX], gam[NMAX], F[NMAX * NMAX], tau[NMAX], Qf[NMAX * NMAX];
    cplx Z[NMAX * NMAX], out[2 * NMAX + NMAX * NMAX], work[4096];
    double re[2 * NMAX + NMAX * NMAX], df[2 * NMAX + NMAX * NMAX], err[2 * NMAX + NMAX * NMAX];
    double resid;
    int jpvt[NMAX], iwork[64];
    seed((size_t)b * k, O.A, O.dA, A), seed(b, O.a0, O.da0, a0), seed(b, O.gam, O.dgam, gam);
    AP_CHECK_EQ_INT(ap_la_orth_basis_cs(b, k, A, a0, 1e-10, &rank, F, tau, jpvt, Qf, Z, out,
                                        &resid, work, iwork), AP_OK);
    AP_CHECK_EQ_INT(rank, b);
    for (int i = 0; i < k; i++)
      for (int j = 0; j < k; j++) {
        cplx t = 0.0;
        for (int c = 0; c < k - rank; c++) t += Z[i + c * k] * Z[j + c * k];
        out[k + i + j * k] = t;
      }
    AP_CHECK_EQ_INT(ap_la_orth_particular_cs(b, k, rank, F, jpvt, Qf, gam, out + k + k * k,
                                             &resid, work), AP_OK);
    orth_path(&O, 0.0, re);
    ridders(orth_path, &O, m, df, err);
    check_vs_ridders(m, out, df, err);
    re_tol = 1e-13;
    check_deriv((size_t)m, out, re, df, 1e-8);   /* real parts; Ridders to its typical 1e-8 */
    re_tol = 8 * DBL_EPSILON;
  }
}

typedef struct lsq {
  int b, k;
  double A[NMAX * NMAX], dA[NMAX * NMAX], rhs[NMAX], drhs[NMAX];
} lsq;

static void lsq_path(const void *prob, double t, double *out) {
  const lsq *P = prob;
  double A[NMAX * NMAX], rhs[NMAX], work[4096], resid;
  int iwork[64];
  for (int i = 0; i < P->b * P->k; i++) A[i] = P->A[i] + t * P->dA[i];
  for (int i = 0; i < P->k; i++) rhs[i] = P->rhs[i] + t * P->drhs[i];
  AP_CHECK_EQ_INT(ap_la_lstsq_At(P->b, P->k, A, rhs, 1e-10, out, &resid, work, iwork), AP_OK);
}

static void test_lstsq(void) {
  for (int dup = 0; dup < 2; dup++) {
    lsq P = {4, 7, {0}, {0}, {0}, {0}};
    fill(28, P.A), fill(28, P.dA), fill(7, P.rhs), fill(7, P.drhs);
    for (int j = 0; dup && j < 7; j++)   /* row 3 repeats row 0: minimum norm decides */
      P.A[3 + 4 * j] = P.A[4 * j], P.dA[3 + 4 * j] = P.dA[4 * j];
    cplx A[NMAX * NMAX], rhs[NMAX], lam[NMAX], work[4096];
    double re[NMAX], df[NMAX], err[NMAX], resid;
    int iwork[64];
    seed(28, P.A, P.dA, A), seed(7, P.rhs, P.drhs, rhs);
    AP_CHECK_EQ_INT(ap_la_lstsq_At_cs(4, 7, A, rhs, 1e-10, lam, &resid, work, iwork), AP_OK);
    lsq_path(&P, 0.0, re);
    /* the accuracy of these values: LAPACK's and the native algorithm's results differ by their
     * round-off; take the larger of that (relative) and the default model */
    ridders_epsf = AP_AN_EPSF;
    for (int i = 0; i < 4; i++)
      ridders_epsf = fmax(ridders_epsf, fabs(creal(lam[i]) - re[i]) / fabs(re[i]));
    ridders(lsq_path, &P, 4, df, err);
    ridders_epsf = AP_AN_EPSF;
    check_vs_ridders(4, lam, df, err);
    re_tol = 1e-13;
    check_deriv(4, lam, re, df, 1e-8);
    re_tol = 8 * DBL_EPSILON;
  }
}

static void test_pivot(void) {
  double A[NMAX * NMAX], dA[NMAX * NMAX], work[4096];
  cplx Ac[NMAX * NMAX], workc[4096];
  int perm[NMAX], permc[NMAX], r = 0, rc = 0, iwork[64];
  fill(30, A), fill(30, dA), seed(30, A, dA, Ac);
  AP_CHECK_EQ_INT(ap_la_pivot_select(3, 10, A, 1e-10, perm, &r, work, iwork), AP_OK);
  AP_CHECK_EQ_INT(ap_la_pivot_select_cs(3, 10, Ac, 1e-10, permc, &rc, workc, iwork), AP_OK);
  AP_CHECK_EQ_INT(rc, r);
  for (int i = 0; i < 10; i++) AP_CHECK_EQ_INT(permc[i], perm[i]);
}

int main(void) {
  test_partition();
  test_exact_zeros();
  test_redundant();
  test_chol();
  test_congruence_gemv();
  test_orth();
  test_lstsq();
  test_pivot();
  printf("linalg_cs: largest |complex step - Ridders| / Ridders' estimate: %.2f\n",
         worst_ratio);
  return ap_check_finish("linalg_cs");
}
