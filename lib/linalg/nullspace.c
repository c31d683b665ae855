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
 * Layout: column-major, leading dimension = row count (>= 1 for LAPACK). Nothing allocates: the
 * scratch is the caller's work/iwork, sized by ap_la_work_size / ap_la_iwork_size, and every
 * LAPACK call gets a workspace length fixed by formula (no run-time workspace query). */
#include "linalg/linalg.h"

#include <cblas.h>
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <string.h>

#include "appell/status.h"

#define LA_NB 32 /* LAPACK block size the workspace leaves room for */

static int imin(int a, int b) { return a < b ? a : b; }
static int imax(int a, int b) { return a > b ? a : b; }
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

/* ---- small helpers ------------------------------------------------------------------------ */

static int all_finite(size_t n, const double *x) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

/* max |M_ij| over an m x n block with leading dimension ld (0 when empty; NaN ignored). */
static double max_abs(int m, int n, const double *M, int ld) {
  double v = 0.0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) {
      double a = fabs(M[i + (size_t)j * ld]);
      v = a > v ? a : v;
    }
  return v;
}

/* The r diagonal entries of an upper-triangular R (ld) are finite and |R_ii| > tol (tol = 0:
 * non-zero; a NaN tol fails every entry). */
static int diag_ok(int r, const double *R, int ld, double tol) {
  for (int i = 0; i < r; i++) {
    double d = R[i + (size_t)i * ld];
    if (!(fabs(d) > tol) || !isfinite(d)) return 0;
  }
  return 1;
}

/* Numerical rank from a column-pivoted R (m x n, ld): leading |R_ii| > rtol |R_00|. */
static int qr_rank(int m, int n, const double *R, int ld, double rtol) {
  int mn = imin(m, n), r = 0;
  double r00 = mn > 0 ? fabs(R[0]) : 0.0;
  if (!(r00 > 0.0) || !isfinite(r00)) return 0;
  while (r < mn && fabs(R[r + (size_t)r * ld]) > rtol * r00) r++;
  return r;
}

/* T (n x m, ld n) = M^T for M (m x n, ld m). */
static void transpose(int m, int n, const double *M, double *T) {
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) T[j + (size_t)i * n] = M[i + (size_t)j * m];
}

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

static int bad_args(int b, int k, double rtol) {
  return b < 0 || k < 1 || !(rtol >= 0.0) || !isfinite(rtol);
}

/* ---- native kernels for small sizes --------------------------------------------------------- */

static int small(int b, int k) { return imax(b, k) <= ap_la_small_limit(); }

/* ||x||_2 (n): the plain sum of squares when it is safely inside the normal range (no term that
 * matters can have underflowed, none overflowed), else the scaled sum. NaN propagates. */
static double nrm2(int n, const double *x) {
  double ss = 0.0, mx = 0.0, t = 0.0;
  for (int i = 0; i < n; i++) ss += x[i] * x[i];
  if (ss >= 0x1p-969 && ss <= DBL_MAX) return sqrt(ss);
  if (isnan(ss)) return ss;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(x[i])); /* 0, tiny, huge or infinite */
  if (mx == 0.0 || isinf(mx)) return mx;
  for (int i = 0; i < n; i++) t += (x[i] / mx) * (x[i] / mx);
  return mx * sqrt(t);
}

/* max_j ||M_j||_2 over the n columns of M (m x n, ld m); NaN if any entry is NaN. */
static double max_col_norm(int m, int n, const double *M) {
  double mx = 0.0;
  for (int j = 0; j < n; j++) { /* squared norms first: one square root in the common case */
    const double *Mj = M + (size_t)j * m;
    double ss = 0.0;
    for (int i = 0; i < m; i++) ss += Mj[i] * Mj[i];
    if (!(ss >= 0x1p-969 && ss <= DBL_MAX)) mx = -1.0; /* unsafe or NaN: scaled norms below */
    if (mx >= 0.0 && ss > mx) mx = ss;
  }
  if (mx >= 0.0) return sqrt(mx);
  for (int j = 0; j < n; j++) {
    double c = nrm2(m, M + (size_t)j * m);
    mx = c > mx || isnan(c) ? c : mx;
  }
  return mx;
}

/* Householder vector of x (n), GVL Alg. 5.1.1 with dlarfg's sign: H = I - tau v v^T, v_0 = 1,
 * H x = beta e_0. beta overwrites x_0, v_1.. overwrite x_1..; returns tau (0: H = I).
 * ||x|| from the plain sum of squares when that is safe (as nrm2), else scaled. */
static double house(int n, double *x) {
  if (n <= 1) return 0.0;
  double alpha = x[0], ss = 0.0, beta;
  for (int i = 1; i < n; i++) ss += x[i] * x[i];
  double aa = alpha * alpha + ss;
  if (ss >= 0x1p-969 && aa <= DBL_MAX) {
    beta = sqrt(aa);
  } else {
    double xn = nrm2(n - 1, x + 1);
    if (xn == 0.0) return 0.0;
    beta = hypot(alpha, xn);
  }
  beta = alpha >= 0.0 ? -beta : beta;
  double tau = (beta - alpha) / beta, d = alpha - beta; /* |d| >= |beta| > 0 */
  if (fabs(d) >= 0x1p-1000) {
    double s = 1.0 / d;
    for (int i = 1; i < n; i++) x[i] *= s;
  } else { /* 1 / d would overflow */
    for (int i = 1; i < n; i++) x[i] /= d;
  }
  x[0] = beta;
  return tau;
}

/* c (n) = (I - tau v v^T) c with v_0 = 1 implicit (v_1.. from v). */
static void house_apply(int n, const double *v, double tau, double *c) {
  if (tau == 0.0) return;
  double s = c[0];
  for (int i = 1; i < n; i++) s += v[i] * c[i];
  s *= tau;
  c[0] -= s;
  for (int i = 1; i < n; i++) c[i] -= s * v[i];
}

/* Householder QR of F (m x n, ld m, n <= m) in place, GVL Alg. 5.2.1 (the layout of dgeqrf). */
static void qr_native(int m, int n, double *F, double *tau) {
  for (int i = 0; i < n; i++) {
    double *v = F + i + (size_t)i * m;
    tau[i] = house(m - i, v);
    for (int j = i + 1; j < n; j++) house_apply(m - i, v, tau[i], F + i + (size_t)j * m);
  }
}

/* c (m) = Q^T c = H_{r-1} ... H_0 c for the r reflectors in F (ld m). */
static void qt_apply(int m, int r, const double *F, const double *tau, double *c) {
  for (int i = 0; i < r; i++) house_apply(m - i, F + i + (size_t)i * m, tau[i], c + i);
}

/* c (r) = R^-1 c, R upper triangular (ld), column-oriented back substitution (GVL 3.1.2).
 * rinv (r): the reciprocals 1 / R_jj to multiply by (several right-hand sides), or NULL. */
static void solve_upper(int r, const double *R, int ld, const double *rinv, double *c) {
  for (int j = r - 1; j >= 0; j--) {
    const double *Rj = R + (size_t)j * ld;
    double cj = c[j] = rinv ? c[j] * rinv[j] : c[j] / Rj[j];
    for (int i = 0; i < j; i++) c[i] -= cj * Rj[i];
  }
}

/* c (r) = R^-T c, R upper triangular (ld): forward substitution with R's columns (GVL 3.1.1). */
static void solve_upper_t(int r, const double *R, int ld, double *c) {
  for (int i = 0; i < r; i++) {
    const double *Ri = R + (size_t)i * ld;
    double s = c[i];
    for (int p = 0; p < i; p++) s -= Ri[p] * c[p];
    c[i] = s / Ri[i];
  }
}

/* Each column c of C (m x nc, ld m) becomes Q^T c with rows 0..r-1 then solved by R (the QR of
 * F, tau): R^-1 Q1^T c above, Q2^T c below. The r reciprocals 1 / R_ii (scratch rinv) serve all
 * nc columns, unless one would overflow (then divisions). */
static void qr_solve_native(int m, int r, int nc, const double *F, const double *tau,
                            double *C, double *rinv) {
  for (int i = 0; i < r && rinv; i++) {
    double d = F[i + (size_t)i * m];
    if (fabs(d) < 0x1p-1000) rinv = NULL;
    else rinv[i] = 1.0 / d;
  }
  for (int j = 0; j < nc; j++) {
    qt_apply(m, r, F, tau, C + (size_t)j * m);
    solve_upper(r, F, m, rinv, C + (size_t)j * m);
  }
}

/* Column-pivoted QR of F (m x n, ld m) in place, GVL Alg. 5.4.1 as LAPACK's dlaqp2 does it:
 * the pivot is the first column of largest remaining norm; norms are downdated and recomputed
 * when cancellation has eaten half the digits. jpvt (n): 0-based column order. vn: 2n scratch. */
static void qrp_native(int m, int n, double *F, double *tau, int *jpvt, double *vn) {
  double *vn1 = vn, *vn2 = vn + n, tol3z = sqrt(DBL_EPSILON);
  for (int j = 0; j < n; j++) jpvt[j] = j, vn1[j] = vn2[j] = nrm2(m, F + (size_t)j * m);
  for (int i = 0, mn = imin(m, n); i < mn; i++) {
    int p = i; /* pivot: first largest remaining norm (as idamax) */
    for (int j = i + 1; j < n; j++)
      if (vn1[j] > vn1[p]) p = j;
    if (p != i) {
      double *Fi = F + (size_t)i * m, *Fp = F + (size_t)p * m;
      for (int s = 0; s < m; s++) {
        double t = Fi[s];
        Fi[s] = Fp[s], Fp[s] = t;
      }
      int tj = jpvt[i];
      jpvt[i] = jpvt[p], jpvt[p] = tj, vn1[p] = vn1[i], vn2[p] = vn2[i];
    }
    double *v = F + i + (size_t)i * m;
    tau[i] = house(m - i, v);
    for (int j = i + 1; j < n; j++) {
      double *Fj = F + (size_t)j * m;
      house_apply(m - i, v, tau[i], Fj + i);
      if (vn1[j] == 0.0) continue; /* downdate the norm of rows i+1.. (LAPACK Working Note 176) */
      double t = fabs(Fj[i]) / vn1[j];
      t = fmax(0.0, 1.0 - t * t);
      double t2 = t * (vn1[j] / vn2[j]) * (vn1[j] / vn2[j]);
      if (t2 > tol3z) vn1[j] *= sqrt(t);
      else vn1[j] = vn2[j] = i + 1 < m ? nrm2(m - i - 1, Fj + i + 1) : 0.0;
    }
  }
}

/* Q (n x n, ld n) = H_0 ... H_{m-1} from the m reflectors in F (n x m, ld n), by backward
 * accumulation (GVL 5.1.6, dorg2r): H_i touches rows and columns i.. only. */
static void form_q(int n, int m, const double *F, const double *tau, double *Q) {
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) Q[i + (size_t)j * n] = i == j ? 1.0 : 0.0;
  for (int i = m - 1; i >= 0; i--)
    for (int j = i; j < n; j++)
      house_apply(n - i, F + i + (size_t)i * n, tau[i], Q + i + (size_t)j * n);
}

/* ---- partitioned basis -------------------------------------------------------------------- */

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

int ap_la_partition_basis(int b, int k, int r, const int *perm, const double *A,
                          const double *a0, double *F, double *tau, double *B, double *b0,
                          double *growth, double *rcond, double *resid, double *work,
                          int *iwork) {
  if (b < 0 || k < 1 || r < 0 || r > imin(b, k)) return AP_ERR_ARG;
  int l = k - r, nc = l + (a0 != NULL), nat = small(b, k);
  double *C = work, *lw = work + (size_t)b * nc; /* C = [A_i a0] (b x nc, ld b) */
  int lwn = (int)lq(k + 1);
  /* Ad = A[:, perm[0..r-1]] = Q R11 (in F) */
  for (int i = 0; i < r; i++)
    memcpy(F + (size_t)i * b, A + (size_t)perm[i] * b, sizeof(double) * (size_t)b);
  double cmax = rcond ? 0.0 : max_col_norm(b, r, F); /* scale of the singularity test */
  if (r > 0 && nat) qr_native(b, r, F, tau);
  else if (r > 0 && LAPACKE_dgeqrf_work(LAPACK_COL_MAJOR, b, r, F, b, tau, lw, lwn))
    return AP_ERR_ARG;
  if (!diag_ok(r, F, b, rcond ? 0.0 : 64.0 * DBL_EPSILON * cmax)) return AP_ERR_SINGULAR;
  /* C = Q^T [A_i a0]: rows r..b-1 are the residual; rows 0..r-1 become R11^-1 Q1^T [A_i a0] */
  for (int j = 0; j < l; j++)
    memcpy(C + (size_t)j * b, A + (size_t)perm[r + j] * b, sizeof(double) * (size_t)b);
  if (a0) memcpy(C + (size_t)l * b, a0, sizeof(double) * (size_t)b);
  if (r > 0 && nat) {
    qr_solve_native(b, r, nc, F, tau, C, lw);
  } else if (r > 0 && nc > 0) {
    if (LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'T', b, nc, r, F, b, tau, C, b, lw, lwn) ||
        LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'N', 'N', r, nc, F, b, C, b))
      return AP_ERR_SINGULAR;
  }
  *resid = max_abs(b - r, nc, C + r, b);
  *growth = max_abs(r, l, C, b);
  /* B = P [-X ; I] (k x l, ld k), b0 = P [-x0 ; 0] */
  for (int j = 0; j < l; j++) {
    double *Bj = B + (size_t)j * k;
    for (int i = 0; i < r; i++) Bj[perm[i]] = -C[i + (size_t)j * b];
    for (int i = 0; i < l; i++) Bj[perm[r + i]] = i == j ? 1.0 : 0.0;
  }
  if (a0 && b0) {
    for (int i = 0; i < k; i++) b0[i] = 0.0;
    for (int i = 0; i < r; i++) b0[perm[i]] = -C[i + (size_t)l * b];
  }
  if (!rcond) return AP_OK;
  *rcond = 1.0;
  if (r > 0 && LAPACKE_dtrcon_work(LAPACK_COL_MAJOR, '1', 'U', 'N', r, F, b, rcond, lw, iwork))
    return AP_ERR_ARG;
  return AP_OK;
}

int ap_la_partition_particular(int b, int k, int r, const int *perm, const double *F,
                               const double *tau, const double *gamma, double *w,
                               double *resid, double *work) {
  if (b < 0 || k < 1 || r < 0 || r > imin(b, k)) return AP_ERR_ARG;
  double *c = work, *lw = work + b; /* c = Q^T gamma */
  memcpy(c, gamma, sizeof(double) * (size_t)b);
  if (r > 0) {
    if (!diag_ok(r, F, b, 0.0)) return AP_ERR_SINGULAR;
    if (small(b, k)) {
      qt_apply(b, r, F, tau, c);
      solve_upper(r, F, b, NULL, c);
    } else if (LAPACKE_dormqr_work(LAPACK_COL_MAJOR, 'L', 'T', b, 1, r, F, b, tau, c, b, lw,
                                   (int)lq(1)) ||
               LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'N', 'N', r, 1, F, b, c, b)) {
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
static int orth_solve(int b, int k, int r, const double *F, const int *jpvt, const double *Qf,
                      double sign, const double *c, double *x, double *resid, double *y) {
  if (!diag_ok(r, F, k, 0.0)) return AP_ERR_SINGULAR;
  for (int i = 0; i < r; i++) y[i] = sign * c[jpvt[i]];
  for (int i = 0; i < k; i++) x[i] = 0.0;
  if (r > 0 && small(b, k)) { /* y = R11^-T t_p, x = Q1 y */
    solve_upper_t(r, F, k, y);
    for (int j = 0; j < r; j++)
      for (int i = 0; i < k; i++) x[i] += Qf[i + (size_t)j * k] * y[j];
  } else if (r > 0) {
    if (LAPACKE_dtrtrs_work(LAPACK_COL_MAJOR, 'U', 'T', 'N', r, 1, F, k, y, r))
      return AP_ERR_SINGULAR;
    cblas_dgemv(CblasColMajor, CblasNoTrans, k, r, 1.0, Qf, k, y, 1, 0.0, x, 1);
  }
  double res = 0.0;
  for (int j = r; j < b; j++) {
    double s = -sign * c[jpvt[j]];
    for (int i = 0; i < r; i++) s += F[i + (size_t)j * k] * y[i];
    res = fabs(s) > res ? fabs(s) : res;
  }
  *resid = res;
  return AP_OK;
}

int ap_la_orth_basis(int b, int k, const double *A, const double *a0, double rtol, int *rank,
                     double *F, double *tau, int *jpvt, double *Qf, double *Z, double *b0,
                     double *resid, double *work, int *iwork) {
  (void)iwork;
  int m = imin(k, b), r = 0, fixed = rtol < 0.0 ? *rank : -1;   /* rtol < 0: rank given */
  if (fixed >= 0 && fixed <= m) rtol = 0.0;
  if (bad_args(b, k, rtol)) return AP_ERR_ARG;
  if (!all_finite((size_t)b * k, A)) return AP_ERR_ARG;
  double *y = work, *lw = work + b;
  if (small(b, k)) { /* A^T P = Q R in F (k x b), the full Q (k x k) in Qf */
    if (b > 0) {
      transpose(b, k, A, F);
      qrp_native(k, b, F, tau, jpvt, lw);
      r = qr_rank(k, b, F, k, rtol);
    }
    form_q(k, m, F, tau, Qf);
  } else {
    if (b > 0 && (r = pivoted_qr_t(b, k, A, rtol, F, tau, jpvt, lw)) < 0) return AP_ERR_ARG;
    memcpy(Qf, F, sizeof(double) * (size_t)k * m);
    if (m > 0 && LAPACKE_dorgqr_work(LAPACK_COL_MAJOR, k, k, m, Qf, k, tau, lw,
                                     (int)lq(imax(b, k))))
      return AP_ERR_ARG;
    if (m == 0) /* b == 0: Q = I */
      for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) Qf[i + (size_t)j * k] = i == j ? 1.0 : 0.0;
  }
  if (fixed >= 0) r = fixed;
  memcpy(Z, Qf + (size_t)r * k, sizeof(double) * (size_t)k * (k - r));
  *rank = r;
  *resid = 0.0;
  if (a0 && b0) return orth_solve(b, k, r, F, jpvt, Qf, -1.0, a0, b0, resid, y);
  return AP_OK;
}

int ap_la_orth_particular(int b, int k, int rank, const double *F, const int *jpvt,
                          const double *Qf, const double *gamma, double *w, double *resid,
                          double *work) {
  if (b < 0 || k < 1 || rank < 0 || rank > imin(b, k)) return AP_ERR_ARG;
  return orth_solve(b, k, rank, F, jpvt, Qf, 1.0, gamma, w, resid, work);
}

/* ---- least squares for the reactions ------------------------------------------------------ */

/* A^T P = Q R (pivoted, rank r), truncated to A^T ~ Q1 [R11 R12] P^T. With z = P^T lambda the
 * problem is [R11 R12] z = d = Q1^T rhs (full row rank), whose minimum-norm solution comes from
 * the QR of [R11 R12]^T = Q2 R2: z = Q2 [R2^-T d ; 0]. When r == b: z = R11^-1 d. */
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
