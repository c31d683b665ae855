/* Tests of lib/linalg (docs/design.md §1 "Choosing B"): partitioned and orthonormal null-space
 * bases with their particular solutions, rank decisions and consistency residuals, the
 * reactions' least squares. Cholesky, the congruence, gemv and the comparison of the two paths
 * are in test_linalg_paths.c; the matrices, products and guarded scratch in linalg_problems.c.
 *
 * Two paths: the whole suite runs twice, on the LAPACK/BLAS path (ap_la_set_small_limit(0)) and
 * on the native small-size kernels (limit INT_MAX), from the same generator seed, so both meet
 * the same matrices and the same checks.
 *
 * Every result is checked against its defining property (A B = 0, A b0 = -a0, Z^T Z = I, ...)
 * with plain loops here, not against the library. */
#include <math.h>
#include <string.h>

#include "appell/status.h"
#include "check.h"
#include "linalg_problems.h"

/* ---- small helpers ------------------------------------------------------------------------ */

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

/* Every test above but test_limit, on one path. */
static void one_path(void) {
  test_random();
  test_duplicate_rows();
  test_combination_row();
  test_degenerate();
  test_growth();
  test_rank_tolerance();
  test_singular();
}

int main(void) {
  test_limit();
  both_paths(LINALG_SEED, one_path);
  return ap_check_finish("linalg");
}
