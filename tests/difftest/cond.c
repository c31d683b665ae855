/* The conditioning of a model's constraint rows for the differential tester's bounds
 * (docs/testing.md, "Where the bounds come from").
 *
 * Speeds put on A v + a0 = 0 nearest in the metric g move, when A v + a0 changes by dr, by
 * dv = M dr with M = g^-1 A^T (A g^-1 A^T)^+, the pseudo-inverse taken on the r = rank(A)
 * largest eigenvalues of A g^-1 A^T (the rank ap_partition picks there; the smallest floored
 * at eps times the largest, its round-off). ||M||_2 is computed as the square root of the
 * largest eigenvalue of M^T M. The position stage of the model's own data gives g and A. The length scale is the model's own (the lever
 * arm of A's terms; read from lib/core, the only value the tester takes from inside). */
#include "cond.h"

#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"

/* Eigenvalues (ascending) of the symmetric n x n matrix S, with its eigenvectors in S when
 * vec; AP_OK or -1. */
static int eig(int n, double *S, double *w, int vec) {
  return n == 0 || LAPACKE_dsyev(LAPACK_COL_MAJOR, vec ? 'V' : 'N', 'U', n, S, n, w) == 0 ? AP_OK
                                                                                           : -1;
}

/* C = X^T Y (X: r x p, Y: r x q, C: p x q), column-major. */
static void tmul(int r, int p, int q, const double *X, const double *Y, double *C) {
  for (int i = 0; i < p; i++)
    for (int j = 0; j < q; j++) {
      double x = 0;
      for (int l = 0; l < r; l++) x += X[l + i * r] * Y[l + j * r];
      C[i + j * p] = x;
    }
}

/* ||M||_2 with M = Y W^+, Y = g^-1 A^T (k x b), W = A g^-1 A^T = A Y, W^+ on the eigenvectors
 * of its `rank` largest eigenvalues (the smallest floored at eps times the largest). */
static double pinv_norm(int k, int b, int rank, const double *g, const double *A, double *w) {
  double *Lg = w, *Y = Lg + k * k, *At = Y + k * b, *W = At + k * b, *ew = W + b * b;
  double *P = ew + b, *M = P + b * b, *MM = M + k * b;
  memcpy(Lg, g, sizeof(double) * (size_t)(k * k));
  for (int i = 0; i < k; i++)
    for (int r = 0; r < b; r++) At[i + r * k] = Y[i + r * k] = A[r + i * b];
  if (LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'L', k, Lg, k) != 0 ||
      LAPACKE_dpotrs(LAPACK_COL_MAJOR, 'L', k, b, Lg, k, Y, k) != 0)
    return INFINITY;
  tmul(k, b, b, At, Y, W);                           /* W = A g^-1 A^T */
  if (eig(b, W, ew, 1) != AP_OK) return INFINITY;
  double floor = DBL_EPSILON * ew[b - 1];
  for (int i = 0; i < b; i++)                        /* P = W^+ */
    for (int j = 0; j < b; j++) {
      double x = 0;
      for (int e = b - rank; e < b; e++) x += W[i + e * b] * W[j + e * b] / fmax(ew[e], floor);
      P[i + j * b] = x;
    }
  for (int i = 0; i < k; i++)                        /* M = Y P */
    for (int j = 0; j < b; j++) {
      double x = 0;
      for (int l = 0; l < b; l++) x += Y[i + l * k] * P[l + j * b];
      M[i + j * k] = x;
    }
  tmul(k, b, b, M, M, MM);
  return eig(b, MM, ew, 0) == AP_OK ? sqrt(fmax(ew[b - 1], 0)) : INFINITY;
}

int dt_cond_at(const ap_model *m, ap_data *d, double t, const double *q, dt_cond *c) {
  int n = ap_model_n(m), k = ap_model_k(m), b = ap_model_b(m);
  memset(c, 0, sizeof *c);
  c->lscale = m->lscale;
  d->t = t, d->basis = AP_BASIS_NONE;   /* g, A and a0 only */
  memcpy(d->q, q, sizeof(double) * (size_t)n);
  int rc = ap_fwd_position(m, d);
  if (rc != AP_OK || b == 0 || !d->A || !d->g) return rc;
  int rank = ap_partition(m, d) == AP_OK ? d->rank : b;
  if (ap_fwd_position(m, d) != AP_OK || rank == 0) return AP_OK;
  double *w = malloc(sizeof(double) * (size_t)(k * k + 4 * k * b + 3 * b * b + b + 1));
  if (!w) return AP_ERR_NOMEM;
  for (int r = 0; r < b; r++) c->a0 = fmax(c->a0, fabs(d->a0[r]));
  for (int i = 0; i < b * k; i++) c->amax = fmax(c->amax, fabs(d->A[i]));
  c->pinv = pinv_norm(k, b, rank, d->g, d->A, w);
  double *AAt = w, *ew = w + b * b;                  /* ||A||_2 from A A^T */
  for (int r = 0; r < b; r++)
    for (int s2 = 0; s2 < b; s2++) {
      double x = 0;
      for (int i = 0; i < k; i++) x += d->A[r + i * b] * d->A[s2 + i * b];
      AAt[r + s2 * b] = x;
    }
  if (eig(b, AAt, ew, 0) == AP_OK) c->anorm = sqrt(fmax(ew[b - 1], 0));
  free(w);
  return isfinite(c->pinv) ? AP_OK : AP_ERR_SINGULAR;
}
