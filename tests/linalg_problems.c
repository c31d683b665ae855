/* Shared by test_linalg.c and test_linalg_paths.c (linalg_problems.h): the fixed-seed matrices,
 * plain-loop products, scratch arrays with guards, and the constraint problems (random A of a
 * chosen rank, consistent or inconsistent free terms). */
#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "appell/status.h"
#include "check.h"
#include "linalg_problems.h"
#include "testrand.h"

uint64_t linalg_rng = LINALG_SEED;

void rand_fill(size_t n, double *x) {
  for (size_t i = 0; i < n; i++) x[i] = ap_test_srand(&linalg_rng);
}

double max_abs(size_t n, const double *x) {
  double v = 0.0;
  for (size_t i = 0; i < n; i++) v = fmax(v, fabs(x[i]));
  return v;
}

/* C (m x p) = op(A) B with op(A) m x n; A stored m x n (trans 0) or n x m (trans 1). */
void mul(int trans, int m, int n, int p, const double *A, const double *B, double *C) {
  for (int j = 0; j < p; j++)
    for (int i = 0; i < m; i++) {
      double s = 0.0;
      for (int t = 0; t < n; t++)
        s += (trans ? A[t + (size_t)i * n] : A[i + (size_t)t * m]) * B[t + (size_t)j * n];
      C[i + (size_t)j * m] = s;
    }
}

/* y (m) = A x + c for A (m x n). */
void affine(int m, int n, const double *A, const double *x, const double *c, double *y) {
  mul(0, m, n, 1, A, x, y);
  for (int i = 0; i < m; i++) y[i] += c[i];
}

scratch scratch_new(int b, int k) {
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
void scratch_done(scratch *s) {
  int ok = 1;
  for (size_t i = 0; i < NGUARD; i++)
    ok = ok && s->w[s->nw + i] == GUARD_D && s->iw[s->niw + i] == GUARD_I;
  AP_CHECK(ok);
  free(s->w), free(s->iw);
}

/* a0 = -A x0 and gamma = A x1 (consistent), random x0, x1. */
void consistent_terms(problem *p) {
  double x[NMAX], zero[NMAX] = {0};
  rand_fill((size_t)p->k, x);
  affine(p->b, p->k, p->A, x, zero, p->a0);
  rand_fill((size_t)p->k, x);
  affine(p->b, p->k, p->A, x, zero, p->gamma);
}

/* Add a unit vector orthogonal to range(A) (a null vector of A^T) to a0 and gamma. */
void make_inconsistent(problem *p) {
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
problem random_problem(int b, int k, int r0) {
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

void both_paths(uint64_t state, void (*tests)(void)) {
  const int limits[2] = {0, INT_MAX}; /* LAPACK / BLAS, native kernels */
  for (int i = 0; i < 2; i++) {
    int old = ap_la_set_small_limit(limits[i]);
    linalg_rng = state;
    tests();
    ap_la_set_small_limit(old);
  }
}
