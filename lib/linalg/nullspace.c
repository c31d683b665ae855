/* Appell linear algebra: bases of the null space of the constraint matrix, by QR.
 *
 * docs/design.md §1 "Choosing B". Admissible speeds v = B e' + b0 with A B = 0 and A b0 = -a0;
 * accelerations v' = B e'' + w with A w = gamma. A is b x k, r = rank A, l = k - r.
 *  - Partitioned basis (the paper's construction). A pivoted QR of A chooses the r dependent
 *    speeds (ap_la_pivot_select). With the partition frozen, the QR of the dependent columns
 *    alone, Ad = A[:, perm[0..r-1]] = Q R11, gives
 *      B = P [-R11^-1 Q1^T A_i ; I],  b0 = P [-R11^-1 Q1^T a0 ; 0],  w = P [R11^-1 Q1^T gamma ; 0]
 *    (docs/design.md's P [-R11^-1 R12 ; I] when b == r). Invariant: rows perm[r..k-1] of B are the
 *    identity, so e' = v_i. Rows r..b-1 of Q^T [A_i a0] measure the redundant rows' consistency.
 *  - Orthonormal basis: pivoted QR of A^T, A^T P = Q R; Z = Q[:, r..k-1]; the particular
 *    solutions are minimum-norm, x = Q1 R11^-T (P^T rhs)_{0..r-1}.
 *  - Reactions: minimum-norm least squares of A^T lambda = rhs (second QR when rows are redundant).
 * Rank: the number of leading |R_ii| > rtol |R_00| of a column-pivoted QR (|R_ii| non-increasing).
 * Two paths, same storage: when max(b, k) <= ap_la_small_limit() the per-evaluation routines
 * (partition_basis, partition_particular, orth_basis, orth_particular) run native unblocked
 * kernels (Golub & Van Loan, Matrix Computations, 4th ed.: Householder vectors 5.1.2, Householder
 * QR 5.2.1, column pivoting 5.4.1 with LAPACK's norm downdating, backward accumulation of Q
 * 5.1.6, triangular solves 3.1); larger sizes call LAPACK (dgeqrf, dgeqp3, dormqr, dorgqr,
 * dtrtrs). The reflectors follow dlarfg's convention (v_0 = 1 implicit, beta = -sign(alpha) ||x||,
 * tau = 0 when x_1.. = 0), so F and tau mean the same on both paths and agree to round-off.
 * pivot_select and lstsq_At (not per evaluation) always use LAPACK.
 * Generic scalar (linalg/scalar.h): the kernels (householder.inc) and the routines are written in
 * ap_sc; nullspace_cs.c compiles this file again as the complex-step variants (*_cs), which always
 * run the native kernels (lstsq_At_cs too) and make the partition decision (pivot_select_cs) on
 * the real part with the double routine.
 * Layout: column-major, leading dimension = row count (>= 1 for LAPACK). Nothing allocates: the
 * scratch is the caller's work/iwork, sized by ap_la_work_size / ap_la_iwork_size, and every
 * LAPACK call gets a workspace length fixed by formula (no run-time workspace query). */
#include "linalg/linalg.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "appell/status.h"
#include "linalg/scalar.h"

#ifndef AP_SC_COMPLEX
#include <cblas.h>
#include <lapacke.h>
#endif

#define LA_NB 32 /* LAPACK block size the workspace leaves room for */

static int imin(int a, int b) { return a < b ? a : b; }
static int imax(int a, int b) { return a > b ? a : b; }

#ifndef AP_SC_COMPLEX
static size_t zmax(size_t a, size_t b) { return a > b ? a : b; }

/* LAPACK workspace (doubles) for the QR-family routines on at most n columns: dgeqp3 needs
 * 3n+1 (blocked: 2n + (n+1) NB), dgeqrf, dormqr (side L) and dorgqr need n (blocked: n NB),
 * dtrcon and dpocon 3n. With less than the blocked size LAPACK falls back to unblocked code. */
static size_t lq(int n) { return (size_t)(n + 1) * LA_NB + 2 * (size_t)n + 1; }

static size_t work_pivot(int b, int k) { return (size_t)b * k + (size_t)imin(b, k) + lq(k); }
static size_t work_partition(int b, int k) { return (size_t)b * (k + 1) + lq(k + 1); }
static size_t work_particular(int b) { return (size_t)b + lq(1); }
static size_t work_orth(int b, int k) { return (size_t)b + lq(imax(b, k)); }
static size_t work_lstsq(int b, int k) {
  size_t m = (size_t)imin(b, k);
  return (size_t)k * b + m + (size_t)k + (size_t)b * m + m + (size_t)b + lq(imax(b, k));
}

size_t ap_la_work_size(int b, int k) {
  if (b < 0) b = 0;
  if (k < 0) k = 0;
  size_t w = zmax(work_pivot(b, k), work_partition(b, k));
  w = zmax(w, zmax(work_particular(b), work_orth(b, k)));
  w = zmax(w, work_lstsq(b, k));
  return zmax(w, 4 * (size_t)k + 1); /* ap_la_chol (l <= k): dlansy l, dpocon 3l */
}

/* dgeqp3 jpvt (k or b) plus marks (k) in ap_la_pivot_select; dtrcon and dpocon need n. */
size_t ap_la_iwork_size(int b, int k) {
  if (b < 0) b = 0;
  if (k < 0) k = 0;
  return 2 * (size_t)imax(b, k) + 1;
}
#endif

/* ---- small helpers ------------------------------------------------------------------------ */

static int all_finite(size_t n, const ap_sc *x) {
  for (size_t i = 0; i < n; i++)
    if (!SC_FINITE(x[i])) return 0;
  return 1;
}

/* max |Re M_ij| over an m x n block with leading dimension ld (0 when empty; NaN ignored). */
static double max_abs(int m, int n, const ap_sc *M, int ld) {
  double v = 0.0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) {
      double a = SC_MAG(M[i + (size_t)j * ld]);
      v = a > v ? a : v;
    }
  return v;
}

/* The r diagonal entries of an upper-triangular R (ld) are finite and |R_ii| > tol (tol = 0:
 * non-zero; a NaN tol fails every entry). */
static int diag_ok(int r, const ap_sc *R, int ld, double tol) {
  for (int i = 0; i < r; i++) {
    ap_sc d = R[i + (size_t)i * ld];
    if (!(SC_MAG(d) > tol) || !SC_FINITE(d)) return 0;
  }
  return 1;
}

/* Numerical rank from a column-pivoted R (m x n, ld): leading |R_ii| > rtol |R_00|. */
static int qr_rank(int m, int n, const ap_sc *R, int ld, double rtol) {
  int mn = imin(m, n), r = 0;
  double r00 = mn > 0 ? SC_MAG(R[0]) : 0.0;
  if (!(r00 > 0.0) || !isfinite(r00)) return 0;
  while (r < mn && SC_MAG(R[r + (size_t)r * ld]) > rtol * r00) r++;
  return r;
}

/* T (n x m, ld n) = M^T for M (m x n, ld m). */
static void transpose(int m, int n, const ap_sc *M, ap_sc *T) {
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) T[j + (size_t)i * n] = M[i + (size_t)j * m];
}

#ifndef AP_SC_COMPLEX
/* Column-pivoted QR of M^T in place in F (n x m, ld n, n >= 1): M^T P = Q R. jpvt (m) gets the
 * 0-based column order of M^T (the row order of M), the return value the numerical rank. */
static int pivoted_qr_t(int m, int n, const double *M, double rtol, double *F, double *tau,
                        int *jpvt, double *lw) {
  transpose(m, n, M, F);
  for (int j = 0; j < m; j++) jpvt[j] = 0;
  if (LAPACKE_dgeqp3_work(LAPACK_COL_MAJOR, n, m, F, n, jpvt, tau, lw, (int)lq(imax(m, n))))
    return -1;
  for (int j = 0; j < m; j++) jpvt[j]--;
  return qr_rank(n, m, F, n, rtol);
}
#endif

static int bad_args(int b, int k, double rtol) {
  return b < 0 || k < 1 || !(rtol >= 0.0) || !isfinite(rtol);
}

/* ---- native kernels for small sizes --------------------------------------------------------- */

#ifndef AP_SC_COMPLEX
static int small(int b, int k) { return imax(b, k) <= ap_la_small_limit(); }
#define LA(call) (call) /* a LAPACK / BLAS call: compiled in the double build only */
#else
static int small(int b, int k) { return (void)b, (void)k, 1; }
/* never reached: the complex-step build is always native. A function, not the constant -1:
 * clang's -Wconstant-logical-operand (an error with -Werror) rejects `r > 0 && (-1)`. */
static int la_native_only(void) { return -1; }
#define LA(call) la_native_only()
#endif

#include "linalg/householder.inc"

/* ---- partitioned basis -------------------------------------------------------------------- */

#ifndef AP_SC_COMPLEX
int ap_la_pivot_select(int b, int k, const double *A, double rtol, int *perm, int *rank,
                       double *work, int *iwork) {
  if (bad_args(b, k, rtol)) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  int r = 0, *jpvt = iwork, *used = iwork + k;
  if (b > 0) { /* dgeqp3 of a copy of A: R in work, tau after it */
    double *R = work, *tau = work + (size_t)b * k;
    memcpy(R, A, sizeof(double) * (size_t)b * k);
    for (int j = 0; j < k; j++) jpvt[j] = 0;
    if (LAPACKE_dgeqp3_work(LAPACK_COL_MAJOR, b, k, R, b, jpvt, tau, tau + imin(b, k),
                            (int)lq(k)))
      return AP_ERR_ARG;
    r = qr_rank(b, k, R, b, rtol);
  }
  for (int j = 0; j < k; j++) used[j] = 0;
  for (int i = 0; i < r; i++) perm[i] = jpvt[i] - 1, used[perm[i]] = 1; /* dependent: pivots */
  for (int j = 0, n = r; j < k; j++)                                     /* independent: rest */
    if (!used[j]) perm[n++] = j;
  *rank = r;
  return AP_OK;
}
#else
/* The partition is a decision: made by the double routine on the real part of A (copied into
 * the first b k doubles of work; the double routine's scratch follows it). */
int ap_la_pivot_select_cs(int b, int k, const ap_sc *A, double rtol, int *perm, int *rank,
                          ap_sc *work, int *iwork) {
  if (b < 0 || k < 1) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  double *Ar = (double *)work;
  for (size_t i = 0; i < (size_t)b * k; i++) Ar[i] = SC_RE(A[i]);
  return ap_la_pivot_select(b, k, Ar, rtol, perm, rank, Ar + (size_t)b * k, iwork);
}
#endif

int AP_SC(ap_la_partition_basis)(int b, int k, int r, const int *perm, const ap_sc *A,
                                 const ap_sc *a0, ap_sc *F, ap_sc *tau, ap_sc *B, ap_sc *b0,
                                 double *growth, double *rcond, double *resid, ap_sc *work,
                                 int *iwork) {
  if (b < 0 || k < 1 || r < 0 || r > imin(b, k)) return AP_ERR_ARG;
#ifdef AP_SC_COMPLEX
  (void)iwork;
  if (rcond) return AP_ERR_ARG;
#endif
  int l = k - r, nc = l + (a0 != NULL), nat = small(b, k);
  ap_sc *C = work, *lw = work + (size_t)b * nc; /* C = [A_i a0] (b x nc, ld b) */
  /* Ad = A[:, perm[0..r-1]] = Q R11 (in F) */
  for (int i = 0; i < r; i++)
    memcpy(F + (size_t)i * b, A + (size_t)perm[i] * b, sizeof(ap_sc) * (size_t)b);
  double cmax = rcond ? 0.0 : max_col_norm(b, r, F); /* scale of the singularity test */
  if (r > 0 && nat) qr_native(b, r, F, tau);
  else if (r > 0 &&
           LA(LAPACKE_dgeqrf_work(LAPACK_COL_MAJOR, b, r, F, b, tau, lw, (int)lq(k + 1))))
    return AP_ERR_ARG;
  if (!diag_ok(r, F, b, rcond ? 0.0 : 64.0 * DBL_EPSILON * cmax)) return AP_ERR_SINGULAR;
  /* C = Q^T [A_i a0]: rows r..b-1 are the residual; rows 0..r-1 become R11^-1 Q1^T [A_i a0] */
  for (int j = 0; j < l; j++)
    memcpy(C + (size_t)j * b, A + (size_t)perm[r + j] * b, sizeof(ap_sc) * (size_t)b);
  if (a0) memcpy(C + (size_t)l * b, a0, sizeof(ap_sc) * (size_t)b);
  if (r > 0 && nat) {
    qr_solve_native(b, r, nc, F, tau, C, lw);
  } else if (r > 0 && nc > 0) {
    if (LA(LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'T', b, nc, r, F, b, tau, C, b, lw,
                               (int)lq(k + 1))) ||
        LA(LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'N', 'N', r, nc, F, b, C, b)))
      return AP_ERR_SINGULAR;
  }
  *resid = max_abs(b - r, nc, C + r, b);
  *growth = max_abs(r, l, C, b);
  /* B = P [-X ; I] (k x l, ld k), b0 = P [-x0 ; 0] */
  for (int j = 0; j < l; j++) {
    ap_sc *Bj = B + (size_t)j * k;
    for (int i = 0; i < r; i++) Bj[perm[i]] = -C[i + (size_t)j * b];
    for (int i = 0; i < l; i++) Bj[perm[r + i]] = i == j ? 1.0 : 0.0;
  }
  if (a0 && b0) {
    for (int i = 0; i < k; i++) b0[i] = 0.0;
    for (int i = 0; i < r; i++) b0[perm[i]] = -C[i + (size_t)l * b];
  }
  if (!rcond) return AP_OK;
  *rcond = 1.0;
  if (r > 0 &&
      LA(LAPACKE_dtrcon_work(LAPACK_COL_MAJOR, '1', 'U', 'N', r, F, b, rcond, lw, iwork)))
    return AP_ERR_ARG;
  return AP_OK;
}

int AP_SC(ap_la_partition_particular)(int b, int k, int r, const int *perm, const ap_sc *F,
                                      const ap_sc *tau, const ap_sc *gamma, ap_sc *w,
                                      double *resid, ap_sc *work) {
  if (b < 0 || k < 1 || r < 0 || r > imin(b, k)) return AP_ERR_ARG;
  ap_sc *c = work; /* c = Q^T gamma; LAPACK's scratch after it */
  memcpy(c, gamma, sizeof(ap_sc) * (size_t)b);
  if (r > 0) {
    if (!diag_ok(r, F, b, 0.0)) return AP_ERR_SINGULAR;
    if (small(b, k)) {
      qt_apply(b, r, F, tau, c);
      solve_upper(r, F, b, NULL, c);
    } else if (LA(LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'T', b, 1, r, F, b, tau, c, b,
                                      work + b, (int)lq(1))) ||
               LA(LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'N', 'N', r, 1, F, b, c, b))) {
      return AP_ERR_SINGULAR;
    }
  }
  for (int i = 0; i < k; i++) w[i] = 0.0;
  for (int i = 0; i < r; i++) w[perm[i]] = c[i];
  *resid = max_abs(b - r, 1, c + r, imax(b, 1));
  return AP_OK;
}

/* ---- orthonormal basis -------------------------------------------------------------------- */

/* Minimum-norm x (k) with (A x)_s = t_s on the kept rows s = jpvt[0..r-1], t = sign * c:
 * A_p = P^T A = R^T Q^T, so x = Q1 y with R11^T y = t_p, and (A x)_{jpvt[j]} = (R12^T y)_j.
 * resid = max over the dropped rows j >= r of |(R12^T y)_j - t_{jpvt[j]}|. y: scratch (b). */
static int orth_solve(int b, int k, int r, const ap_sc *F, const int *jpvt, const ap_sc *Qf,
                      double sign, const ap_sc *c, ap_sc *x, double *resid, ap_sc *y) {
  if (!diag_ok(r, F, k, 0.0)) return AP_ERR_SINGULAR;
  for (int i = 0; i < r; i++) y[i] = sign * c[jpvt[i]];
  for (int i = 0; i < k; i++) x[i] = 0.0;
  if (r > 0 && small(b, k)) { /* y = R11^-T t_p, x = Q1 y */
    solve_upper_t(r, F, k, y);
    for (int j = 0; j < r; j++)
      for (int i = 0; i < k; i++) x[i] += Qf[i + (size_t)j * k] * y[j];
  } else if (r > 0) {
    if (LA(LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'T', 'N', r, 1, F, k, y, r)))
      return AP_ERR_SINGULAR;
    (void)LA((cblas_dgemv(CblasColMajor, CblasNoTrans, k, r, 1.0, Qf, k, y, 1, 0.0, x, 1), 0));
  }
  double res = 0.0;
  for (int j = r; j < b; j++) {
    ap_sc s = -sign * c[jpvt[j]];
    for (int i = 0; i < r; i++) s += F[i + (size_t)j * k] * y[i];
    res = SC_MAG(s) > res ? SC_MAG(s) : res;
  }
  *resid = res;
  return AP_OK;
}

int AP_SC(ap_la_orth_basis)(int b, int k, const ap_sc *A, const ap_sc *a0, double rtol,
                            int *rank, ap_sc *F, ap_sc *tau, int *jpvt, ap_sc *Qf, ap_sc *Z,
                            ap_sc *b0, double *resid, ap_sc *work, int *iwork) {
  (void)iwork;
  int m = imin(k, b), r = 0, fixed = rtol < 0.0 ? *rank : -1;   /* rtol < 0: rank given */
  if (fixed >= 0 && fixed <= m) rtol = 0.0;
  if (bad_args(b, k, rtol)) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  ap_sc *y = work, *lw = work + b;
  if (small(b, k)) { /* A^T P = Q R in F (k x b), the full Q (k x k) in Qf */
    if (b > 0) {
      transpose(b, k, A, F);
      qrp_native(k, b, F, tau, jpvt, (double *)lw);
      r = qr_rank(k, b, F, k, rtol);
    }
    form_q(k, m, F, tau, Qf);
  } else {
    if (b > 0 && (r = LA(pivoted_qr_t(b, k, A, rtol, F, tau, jpvt, lw))) < 0) return AP_ERR_ARG;
    memcpy(Qf, F, sizeof(ap_sc) * (size_t)k * m);
    if (m > 0 && LA(LAPACKE_dorgqr_work(LAPACK_COL_MAJOR, k, k, m, Qf, k, tau, lw,
                                        (int)lq(imax(b, k)))))
      return AP_ERR_ARG;
    if (m == 0) /* b == 0: Q = I */
      for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) Qf[i + (size_t)j * k] = i == j ? 1.0 : 0.0;
  }
  if (fixed >= 0) r = fixed;
  memcpy(Z, Qf + (size_t)r * k, sizeof(ap_sc) * (size_t)k * (k - r));
  *rank = r;
  *resid = 0.0;
  if (a0 && b0) return orth_solve(b, k, r, F, jpvt, Qf, -1.0, a0, b0, resid, y);
  return AP_OK;
}

int AP_SC(ap_la_orth_particular)(int b, int k, int rank, const ap_sc *F, const int *jpvt,
                                 const ap_sc *Qf, const ap_sc *gamma, ap_sc *w, double *resid,
                                 ap_sc *work) {
  if (b < 0 || k < 1 || rank < 0 || rank > imin(b, k)) return AP_ERR_ARG;
  return orth_solve(b, k, rank, F, jpvt, Qf, 1.0, gamma, w, resid, work);
}

/* ---- least squares for the reactions ------------------------------------------------------ */

/* A^T P = Q R (pivoted, rank r), truncated to A^T ~ Q1 [R11 R12] P^T. With z = P^T lambda the
 * problem is [R11 R12] z = d = Q1^T rhs (full row rank), whose minimum-norm solution comes from
 * the QR of [R11 R12]^T = Q2 R2: z = Q2 [R2^-T d ; 0]. When r == b: z = R11^-1 d.
 * The double build uses LAPACK at every size; the complex-step build the same steps natively. */
#ifndef AP_SC_COMPLEX
int ap_la_lstsq_At(int b, int k, const double *A, const double *rhs, double rtol,
                   double *lambda, double *resid, double *work, int *iwork) {
  if (bad_args(b, k, rtol)) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  int m = imin(k, b), r = 0, lwn = (int)lq(imax(b, k)), ldz = imax(b, 1);
  double *F = work, *tau = F + (size_t)k * b, *d = tau + m, *T = d + k;
  double *tau2 = T + (size_t)b * m, *z = tau2 + m, *lw = z + b;
  if (b > 0 && (r = pivoted_qr_t(b, k, A, rtol, F, tau, iwork, lw)) < 0) return AP_ERR_ARG;
  if (!diag_ok(r, F, k, 0.0)) return AP_ERR_SINGULAR;
  for (int j = 0; j < b; j++) z[j] = 0.0;
  if (r > 0) { /* d = Q1^T rhs (the first r reflectors suffice) */
    memcpy(d, rhs, sizeof(double) * (size_t)k);
    if (LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'T', k, 1, r, F, k, tau, d, k, lw, lwn))
      return AP_ERR_ARG;
    memcpy(z, d, sizeof(double) * (size_t)r);
  }
  if (r > 0 && r == b) { /* full row rank: z = R11^-1 d */
    if (LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'N', 'N', r, 1, F, k, z, ldz))
      return AP_ERR_SINGULAR;
  } else if (r > 0) { /* redundant rows: T = [R11 R12]^T (b x r) = Q2 R2 */
    for (int i = 0; i < r; i++)
      for (int j = 0; j < b; j++) T[j + (size_t)i * b] = j >= i ? F[i + (size_t)j * k] : 0.0;
    if (LAPACKE_dgeqrf_work(LAPACK_COL_MAJOR, b, r, T, b, tau2, lw, lwn)) return AP_ERR_ARG;
    if (!diag_ok(r, T, b, 0.0)) return AP_ERR_SINGULAR;
    if (LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'T', 'N', r, 1, T, b, z, ldz) ||
        LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'N', b, 1, r, T, b, tau2, z, ldz, lw, lwn))
      return AP_ERR_SINGULAR;
  }
  for (int j = 0; j < b; j++) lambda[iwork[j]] = z[j];
  /* resid = max |A^T lambda - rhs| */
  memcpy(d, rhs, sizeof(double) * (size_t)k);
  if (b > 0) cblas_dgemv(CblasColMajor, CblasTrans, b, k, 1.0, A, b, lambda, 1, -1.0, d, 1);
  *resid = max_abs(k, 1, d, k);
  return AP_OK;
}
#else
int ap_la_lstsq_At_cs(int b, int k, const ap_sc *A, const ap_sc *rhs, double rtol,
                      ap_sc *lambda, double *resid, ap_sc *work, int *iwork) {
  if (bad_args(b, k, rtol)) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  int m = imin(k, b), r = 0;
  ap_sc *F = work, *tau = F + (size_t)k * b, *d = tau + m, *T = d + k;
  ap_sc *tau2 = T + (size_t)b * m, *z = tau2 + m, *lw = z + b;
  if (b > 0) { /* A^T P = Q R in F (k x b) */
    transpose(b, k, A, F);
    qrp_native(k, b, F, tau, iwork, (double *)lw);
    r = qr_rank(k, b, F, k, rtol);
  }
  if (!diag_ok(r, F, k, 0.0)) return AP_ERR_SINGULAR;
  for (int j = 0; j < b; j++) z[j] = 0.0;
  if (r > 0) { /* d = Q1^T rhs */
    memcpy(d, rhs, sizeof(ap_sc) * (size_t)k);
    qt_apply(k, r, F, tau, d);
    memcpy(z, d, sizeof(ap_sc) * (size_t)r);
  }
  if (r > 0 && r == b) { /* full row rank: z = R11^-1 d */
    solve_upper(r, F, k, NULL, z);
  } else if (r > 0) { /* redundant rows: T = [R11 R12]^T (b x r) = Q2 R2, z = Q2 [R2^-T d; 0] */
    for (int i = 0; i < r; i++)
      for (int j = 0; j < b; j++) T[j + (size_t)i * b] = j >= i ? F[i + (size_t)j * k] : 0.0;
    qr_native(b, r, T, tau2);
    if (!diag_ok(r, T, b, 0.0)) return AP_ERR_SINGULAR;
    solve_upper_t(r, T, b, z);
    for (int i = r - 1; i >= 0; i--) house_apply(b - i, T + i + (size_t)i * b, tau2[i], z + i);
  }
  for (int j = 0; j < b; j++) lambda[iwork[j]] = z[j];
  /* resid = max |A^T lambda - rhs| */
  for (int i = 0; i < k; i++) {
    ap_sc t = -rhs[i];
    for (int j = 0; j < b; j++) t += A[j + (size_t)i * b] * lambda[j];
    d[i] = t;
  }
  *resid = max_abs(k, 1, d, k);
  return AP_OK;
}
#endif
