/* Appell linear algebra: the small dense kernels of the Appell solve.
 *
 * docs/design.md §1: G e'' = Phi - B^T (h + g w) with G = B^T g B (l x l, SPD). This file forms G
 * (ap_la_congruence, G made exactly symmetric), factors it G = L L^T (ap_la_chol, with a
 * reciprocal condition estimate on request: dlansy for ||G||_1 before factoring, dpocon after),
 * solves with the factor, and computes y = M x and y = M^T x.
 * Two paths: up to ap_la_small_limit() (rows and columns) native loops, the textbook algorithms
 * (Golub & Van Loan, Matrix Computations, 4th ed.: Cholesky-Banachiewicz, row by row, 4.2;
 * forward and back substitution 3.1; congruence as g B then B^T (g B), lower triangle then
 * mirrored); above it BLAS and LAPACK (dsymm and dgemm, dpotrf, dpotrs, dgemv), whose per-call
 * overhead (argument checks, ilaenv, buffer locks) dwarfs the arithmetic on tiny matrices.
 * Both paths read only the lower triangle of g and of G, and agree to round-off.
 * Layout: column-major, leading dimension = row count; only the lower triangle of the factor is
 * meaningful. Nothing allocates: scratch comes from the caller (ap_la_work_size covers 4 l).
 * Generic scalar (linalg/scalar.h): the native kernels are written in ap_sc; dense_cs.c compiles
 * this file again as the complex-step variants (*_cs: always native, no condition estimate). */
#include "linalg/linalg.h"

#include <math.h>

#include "appell/status.h"
#include "linalg/scalar.h"

#ifndef AP_SC_COMPLEX
#include <cblas.h>
#include <lapacke.h>

/* The size limit of the native kernels; tests and benchmarks move it (ap_la_set_small_limit).
 * One per thread: a thread that moves it changes its own calls only, never those of a
 * simulation running in another thread (no process-wide writable state). */
static _Thread_local int small_limit = AP_LA_SMALL_LIMIT;

int ap_la_small_limit(void) { return small_limit; }

int ap_la_set_small_limit(int n) {
  int old = small_limit;
  small_limit = n < 0 ? 0 : n;
  return old;
}
#endif

/* ---- native kernels ----------------------------------------------------------------------- */

/* G = L L^T in place (lower triangle, ld l), row by row (Cholesky-Banachiewicz):
 * L_ij = (G_ij - sum_{p<j} L_ip L_jp) / L_jj, L_ii = sqrt(G_ii - sum_{p<i} L_ip^2).
 * Returns 0, or -1 at the first pivot that is <= 0 or not finite. */
static int chol_native(int l, ap_sc *G) {
  for (int i = 0; i < l; i++) {
    for (int j = 0; j <= i; j++) {
      ap_sc s = G[i + (size_t)j * l];
      for (int p = 0; p < j; p++) s -= G[i + (size_t)p * l] * G[j + (size_t)p * l];
      if (j < i) {
        G[i + (size_t)j * l] = s / G[j + (size_t)j * l];
      } else {
        if (!(SC_RE(s) > 0.0) || !SC_FINITE(s)) return -1;
        G[i + (size_t)i * l] = SC_SQRT(s);
      }
    }
  }
  return 0;
}

/* x = (L L^T)^-1 x: L y = x forward by rows, then L^T x = y backward by L's columns. */
static void chol_solve_native(int l, const ap_sc *L, ap_sc *x) {
  for (int i = 0; i < l; i++) {
    ap_sc s = x[i];
    for (int p = 0; p < i; p++) s -= L[i + (size_t)p * l] * x[p];
    x[i] = s / L[i + (size_t)i * l];
  }
  for (int i = l - 1; i >= 0; i--) {
    const ap_sc *Li = L + (size_t)i * l;
    ap_sc s = x[i];
    for (int p = i + 1; p < l; p++) s -= Li[p] * x[p];
    x[i] = s / Li[i];
  }
}

/* y (m) = M x, M (m x n, n >= 1): y starts as M_0 x_0, then accumulates four columns at a time
 * (one pass over y per four). */
static void gemv_native(int m, int n, const ap_sc *restrict M, const ap_sc *restrict x,
                        ap_sc *restrict y) {
  int j = 1;
  for (int i = 0; i < m; i++) y[i] = M[i] * x[0];
  for (; j + 3 < n; j += 4) {
    const ap_sc *M0 = M + (size_t)j * m, *M1 = M0 + m, *M2 = M1 + m, *M3 = M2 + m;
    ap_sc x0 = x[j], x1 = x[j + 1], x2 = x[j + 2], x3 = x[j + 3];
    for (int i = 0; i < m; i++) y[i] += (M0[i] * x0 + M1[i] * x1) + (M2[i] * x2 + M3[i] * x3);
  }
  for (; j < n; j++) {
    const ap_sc *Mj = M + (size_t)j * m;
    ap_sc xj = x[j];
    for (int i = 0; i < m; i++) y[i] += Mj[i] * xj;
  }
}

/* y (n) = M^T x, M (m x n): four dot products at a time (four independent sums). */
static void gemv_t_native(int m, int n, const ap_sc *restrict M, const ap_sc *restrict x,
                          ap_sc *restrict y) {
  int j = 0;
  for (; j + 3 < n; j += 4) {
    const ap_sc *M0 = M + (size_t)j * m, *M1 = M0 + m, *M2 = M1 + m, *M3 = M2 + m;
    ap_sc s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (int i = 0; i < m; i++) {
      ap_sc xi = x[i];
      s0 += M0[i] * xi, s1 += M1[i] * xi, s2 += M2[i] * xi, s3 += M3[i] * xi;
    }
    y[j] = s0, y[j + 1] = s1, y[j + 2] = s2, y[j + 3] = s3;
  }
  for (; j < n; j++) {
    const ap_sc *Mj = M + (size_t)j * m;
    ap_sc s = 0.0;
    for (int i = 0; i < m; i++) s += Mj[i] * x[i];
    y[j] = s;
  }
}

/* gB (k x l) = g B with g's lower triangle: g_ip = g[i + p k] for p < i (row i), g[p + i k]
 * for p >= i (column i). Dot products, four columns of B at a time (four independent sums). */
static void symm_lower(int k, int l, const ap_sc *restrict g, const ap_sc *restrict B,
                       ap_sc *restrict gB) {
  int j = 0;
  for (; j + 3 < l; j += 4) {
    const ap_sc *B0 = B + (size_t)j * k, *B1 = B0 + k, *B2 = B1 + k, *B3 = B2 + k;
    for (int i = 0; i < k; i++) {
      const ap_sc *gi = g + (size_t)i * k;
      ap_sc s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0, t;
      for (int p = 0; p < i; p++)
        t = g[i + (size_t)p * k], s0 += t * B0[p], s1 += t * B1[p], s2 += t * B2[p],
        s3 += t * B3[p];
      for (int p = i; p < k; p++)
        t = gi[p], s0 += t * B0[p], s1 += t * B1[p], s2 += t * B2[p], s3 += t * B3[p];
      ap_sc *y = gB + i + (size_t)j * k;
      y[0] = s0, y[k] = s1, y[2 * (size_t)k] = s2, y[3 * (size_t)k] = s3;
    }
  }
  for (; j < l; j++) {
    const ap_sc *Bj = B + (size_t)j * k;
    for (int i = 0; i < k; i++) {
      const ap_sc *gi = g + (size_t)i * k;
      ap_sc s = 0.0;
      for (int p = 0; p < i; p++) s += g[i + (size_t)p * k] * Bj[p];
      for (int p = i; p < k; p++) s += gi[p] * Bj[p];
      gB[i + (size_t)j * k] = s;
    }
  }
}

/* gB = g B, then G_ij = B_i . gB_j for i >= j (M^T x on the columns j..l-1 of B), mirrored to
 * the upper triangle. */
static void congruence_native(int k, int l, const ap_sc *g, const ap_sc *B, ap_sc *G,
                              ap_sc *gB) {
  symm_lower(k, l, g, B, gB);
  for (int j = 0; j < l; j++) {
    gemv_t_native(k, l - j, B + (size_t)j * k, gB + (size_t)j * k, G + j + (size_t)j * l);
    for (int i = j + 1; i < l; i++) G[j + (size_t)i * l] = G[i + (size_t)j * l];
  }
}

/* ---- the routines, double build: native up to small_limit, LAPACK / BLAS above ----------- */

#ifndef AP_SC_COMPLEX
int ap_la_chol(int l, double *G, double *rcond, double *work, int *iwork) {
  if (l < 0) return AP_ERR_ARG;
  if (rcond) *rcond = 1.0;
  if (l == 0) return AP_OK;
  double anorm = 0.0;
  if (rcond) {
    anorm = LAPACKE_dlansy_work(LAPACK_COL_MAJOR, '1', 'L', l, G, l, work);
    if (!isfinite(anorm)) return AP_ERR_SINGULAR;
  }
  if (l <= small_limit) {
    if (chol_native(l, G)) return AP_ERR_SINGULAR;
  } else {
    if (LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, 'L', l, G, l) != 0) return AP_ERR_SINGULAR;
    for (int i = 0; i < l; i++) /* dpotrf lets an infinite pivot pass */
      if (!isfinite(G[i + (size_t)i * l])) return AP_ERR_SINGULAR;
  }
  if (rcond && LAPACKE_dpocon_work(LAPACK_COL_MAJOR, 'L', l, G, l, anorm, rcond, work, iwork))
    return AP_ERR_ARG;
  return AP_OK;
}

void ap_la_chol_solve(int l, const double *L, double *x) {
  if (l <= 0) return;
  if (l <= small_limit) chol_solve_native(l, L, x);
  else LAPACKE_dpotrs_work(LAPACK_COL_MAJOR, 'L', l, 1, L, l, x, l);
}

void ap_la_congruence(int k, int l, const double *g, const double *B, double *G, double *gB) {
  if (l <= 0) return;
  if (k <= 0) {
    for (int i = 0; i < l * l; i++) G[i] = 0.0;
    return;
  }
  if (k <= small_limit) {
    congruence_native(k, l, g, B, G, gB);
    return;
  }
  cblas_dsymm(CblasColMajor, CblasLeft, CblasLower, k, l, 1.0, g, k, B, k, 0.0, gB, k);
  cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, l, l, k, 1.0, B, k, gB, k, 0.0, G, l);
  for (int j = 0; j < l; j++) /* exact symmetry: upper triangle = lower triangle */
    for (int i = j + 1; i < l; i++) G[j + (size_t)i * l] = G[i + (size_t)j * l];
}

void ap_la_gemv(int m, int n, const double *M, const double *x, double *y) {
  if (m <= 0) return;
  if (n <= 0) { /* empty product */
    for (int i = 0; i < m; i++) y[i] = 0.0;
  } else if (m <= small_limit && n <= small_limit) {
    gemv_native(m, n, M, x, y);
  } else {
    cblas_dgemv(CblasColMajor, CblasNoTrans, m, n, 1.0, M, m, x, 1, 0.0, y, 1);
  }
}

void ap_la_gemv_t(int m, int n, const double *M, const double *x, double *y) {
  if (n <= 0) return;
  if (m <= 0 || (m <= small_limit && n <= small_limit)) gemv_t_native(m, n, M, x, y);
  else cblas_dgemv(CblasColMajor, CblasTrans, m, n, 1.0, M, m, x, 1, 0.0, y, 1);
}

#else /* ---- the routines, complex-step build: always native ------------------------------- */

int ap_la_chol_cs(int l, ap_sc *G, double *rcond, ap_sc *work, int *iwork) {
  (void)work, (void)iwork;
  if (l < 0 || rcond) return AP_ERR_ARG;
  return l == 0 || !chol_native(l, G) ? AP_OK : AP_ERR_SINGULAR;
}

void ap_la_chol_solve_cs(int l, const ap_sc *L, ap_sc *x) {
  if (l > 0) chol_solve_native(l, L, x);
}

void ap_la_congruence_cs(int k, int l, const ap_sc *g, const ap_sc *B, ap_sc *G, ap_sc *gB) {
  if (l <= 0) return;
  if (k <= 0)
    for (int i = 0; i < l * l; i++) G[i] = 0.0;
  else
    congruence_native(k, l, g, B, G, gB);
}

void ap_la_gemv_cs(int m, int n, const ap_sc *M, const ap_sc *x, ap_sc *y) {
  if (m <= 0) return;
  if (n <= 0)
    for (int i = 0; i < m; i++) y[i] = 0.0;
  else
    gemv_native(m, n, M, x, y);
}

void ap_la_gemv_t_cs(int m, int n, const ap_sc *M, const ap_sc *x, ap_sc *y) {
  if (n > 0) gemv_t_native(m, n, M, x, y);
}
#endif
