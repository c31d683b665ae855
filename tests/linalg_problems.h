/* The inputs and helpers shared by the lib/linalg tests (test_linalg.c: bases, ranks, least
 * squares; test_linalg_paths.c: Cholesky, congruence, gemv and the native / LAPACK comparison).
 *
 * Matrices come from one fixed-seed generator whose state, linalg_rng, each program sets before
 * a run (so a run meets the same matrices wherever it is made). Products are plain loops,
 * independent of the library. Scratch arrays are exactly ap_la_work_size / ap_la_iwork_size
 * long, filled with NaN (reading scratch before writing it poisons the results) and followed by
 * guard values that must survive (the sizes suffice). Dense matrices are column-major. */
#ifndef AP_TESTS_LINALG_PROBLEMS_H
#define AP_TESTS_LINALG_PROBLEMS_H

#include <stddef.h>
#include <stdint.h>

#include "linalg/linalg.h"

#define RTOL 1e-9   /* rank tolerance */
#define TOL 1e-13   /* round-off, relative to the scale of the quantities involved */
#define NMAX 16     /* largest b or k used */
#define NGUARD 32   /* guard entries after each scratch array */
#define GUARD_D 12345.678
#define GUARD_I 424242

/* The generator's first state; every run of the bases tests starts from it. */
#define LINALG_SEED 0x9E3779B97F4A7C15ull

/* The state of the generator (tests/testrand.h) behind rand_fill. */
extern uint64_t linalg_rng;

/* x[0..n) uniform in [-1, 1). */
void rand_fill(size_t n, double *x);

/* max |x_i| over n entries. */
double max_abs(size_t n, const double *x);

/* C (m x p) = op(A) B with op(A) m x n; A stored m x n (trans 0) or n x m (trans 1). */
void mul(int trans, int m, int n, int p, const double *A, const double *B, double *C);

/* y (m) = A x + c for A (m x n). */
void affine(int m, int n, const double *A, const double *x, const double *c, double *y);

/* Scratch for the routines at b constraint rows and k speeds, NaN-filled, guards after. */
typedef struct scratch {
  double *w;
  int *iw;
  size_t nw, niw;
} scratch;

scratch scratch_new(int b, int k);

/* Checks the guards (one AP_CHECK), then frees. */
void scratch_done(scratch *s);

/* A constraint set with free terms. dist = 0 when a0 and gamma are in the range of A (the
 * redundant rows are consistent); otherwise both are at least dist from range(A) (2-norm). */
typedef struct problem {
  int b, k, rank;
  double dist;
  double A[NMAX * NMAX], a0[NMAX], gamma[NMAX];
} problem;

/* a0 = -A x0 and gamma = A x1 (consistent), random x0, x1. */
void consistent_terms(problem *p);

/* Add a unit vector orthogonal to range(A) (a null vector of A^T) to a0 and gamma; checks the
 * rank found on the way (AP_CHECKs counted by the calling program). */
void make_inconsistent(problem *p);

/* Random A (b x k) of rank r0 = L R, with consistent free terms. */
problem random_problem(int b, int k, int r0);

/* Runs tests on the LAPACK/BLAS path (ap_la_set_small_limit(0)), then on the native small-size
 * kernels (limit INT_MAX), each time from generator state `state`: both paths meet the same
 * matrices and the same checks. The limit is restored after. */
void both_paths(uint64_t state, void (*tests)(void));

#endif
