/* Appell linear algebra: the small dense kernels of the Appell solve.
 *
 * DESIGN.md §1: G e'' = Phi - B^T (h + g w) with G = B^T g B (l x l, SPD). This file forms G
 * (ap_la_congruence: dsymm then dgemm, G made exactly symmetric), factors it G = L L^T with a
 * reciprocal condition estimate (ap_la_chol: dlansy for ||G||_1 before factoring, dpotrf,
 * dpocon), solves with the factor (dpotrs), and wraps dgemv.
 * Layout: column-major, leading dimension = row count; only the lower triangle of the factor is
 * meaningful. Nothing allocates: scratch comes from the caller (ap_la_work_size covers 4 l). */
#include "linalg/linalg.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>

#include "appell/status.h"

int ap_la_chol(int l, double *G, double *rcond, double *work, int *iwork) {
  if (l < 0) return AP_ERR_ARG;
  *rcond = 1.0;
  if (l == 0) return AP_OK;
  double anorm = LAPACKE_dlansy_work(LAPACK_COL_MAJOR, '1', 'L', l, G, l, work);
  if (!isfinite(anorm)) return AP_ERR_SINGULAR;
  if (LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, 'L', l, G, l) != 0) return AP_ERR_SINGULAR;
  if (LAPACKE_dpocon_work(LAPACK_COL_MAJOR, 'L', l, G, l, anorm, rcond, work, iwork) != 0)
    return AP_ERR_ARG;
  return AP_OK;
}

void ap_la_chol_solve(int l, const double *L, double *x) {
  if (l <= 0) return;
  LAPACKE_dpotrs_work(LAPACK_COL_MAJOR, 'L', l, 1, L, l, x, l);
}

void ap_la_congruence(int k, int l, const double *g, const double *B, double *G, double *gB) {
  if (l <= 0) return;
  if (k <= 0) {
    for (int i = 0; i < l * l; i++) G[i] = 0.0;
    return;
  }
  cblas_dsymm(CblasColMajor, CblasLeft, CblasLower, k, l, 1.0, g, k, B, k, 0.0, gB, k);
  cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, l, l, k, 1.0, B, k, gB, k, 0.0, G, l);
  for (int j = 0; j < l; j++) /* exact symmetry: upper triangle = lower triangle */
    for (int i = j + 1; i < l; i++) G[j + (size_t)i * l] = G[i + (size_t)j * l];
}

void ap_la_gemv(int m, int n, const double *M, const double *x, double *y) {
  if (m <= 0) return;
  if (n <= 0) {
    for (int i = 0; i < m; i++) y[i] = 0.0;
    return;
  }
  cblas_dgemv(CblasColMajor, CblasNoTrans, m, n, 1.0, M, m, x, 1, 0.0, y, 1);
}

void ap_la_gemv_t(int m, int n, const double *M, const double *x, double *y) {
  if (n <= 0) return;
  if (m <= 0) {
    for (int j = 0; j < n; j++) y[j] = 0.0;
    return;
  }
  cblas_dgemv(CblasColMajor, CblasTrans, m, n, 1.0, M, m, x, 1, 0.0, y, 1);
}
