/* Appell linear algebra (internal): null-space bases of the constraint matrix, Cholesky with an
 * optional condition estimate, small dense kernels. Raw column-major arrays and sizes only:
 * nothing here knows about models or data. No routine allocates; every scratch array is passed
 * in and its size is given by ap_la_work_size / ap_la_iwork_size.
 *
 * Two paths with one meaning. The routines called on every evaluation (partition_basis,
 * partition_particular, orth_basis, orth_particular, chol, chol_solve, congruence, gemv,
 * gemv_t) run native unblocked loops when every dimension involved (b and k; l; k; m and n) is
 * <= ap_la_small_limit(), default AP_LA_SMALL_LIMIT, and LAPACKE _work / CBLAS above it. Same
 * storage (F and tau in LAPACK's dgeqrf layout) and the same results up to round-off; LAPACK's
 * per-call overhead costs microseconds on the tiny matrices of a mechanism. pivot_select and
 * lstsq_At always use LAPACK. The condition estimates (dtrcon, dpocon) are LAPACK on both paths
 * and are skipped when rcond is NULL.
 *
 * Notation (docs/design.md §1): A is b x k (b constraint rows, k speeds), r = numerical rank of A,
 * l = k - r free speeds. Return values: AP_OK, or AP_ERR_SINGULAR / AP_ERR_ARG.
 * AP_ERR_ARG: bad sizes, rtol negative or not finite, or a non-finite entry of A in the routines
 * that decide the rank (pivot_select, orth_basis, lstsq_At). AP_ERR_SINGULAR: a triangular
 * pivot that is exactly 0 or not finite (never divided by), below the working-precision bound
 * of ap_la_partition_basis when rcond is NULL, or G not positive definite. */
#ifndef AP_LINALG_H
#define AP_LINALG_H

#include <stddef.h>

/* Doubles of scratch that suffice for every routine below with these sizes (the maximum over
 * the routines; LAPACK gets workspace lengths by formula, never by a run-time query). */
size_t ap_la_work_size(int b, int k);
/* Ints of scratch that suffice for every routine below with these sizes. */
size_t ap_la_iwork_size(int b, int k);

/* ---- Partitioned basis (docs/design.md "Choosing B", the paper's construction) ------------ */

/* Choose dependent and independent speeds by pivoted QR (dgeqp3) of A.
 * perm (k): the column order; perm[0..rank-1] are the dependent speeds (pivot order),
 * perm[rank..k-1] the independent ones (ascending index order).
 * rank: number of i with |R_ii| > rtol * |R_00| (0 when b == 0 or A == 0).
 * Does not modify A. */
int ap_la_pivot_select(int b, int k, const double *A, double rtol, int *perm, int *rank,
                       double *work, int *iwork);

/* With a frozen partition (perm, r): Householder QR (dgeqrf) of Ad = A[:, perm[0..r-1]]
 * (b x r) into F (b x r, ld b) and tau (r); then
 *   B  (k x l, ld k):  row perm[i] (i < r) = -(R11^-1 Q1^T A_i)_i,  row perm[r+j] = unit e_j
 *   b0 (k) if a0 and b0 are not NULL: b0[perm[i]] = -(R11^-1 Q1^T a0)_i, 0 elsewhere
 * where A_i = A[:, perm[r..k-1]] and Q1 = first r columns of Q.
 * growth = max |(R11^-1 Q1^T A_i)_ij| (0 when l == 0 or r == 0);
 * rcond  = reciprocal 1-norm condition estimate of R11 (dtrcon; 1 when r == 0), or NULL: no
 *          estimate (the per-evaluation path; dtrcon costs more than the factorization here);
 * resid  = max |(Q^T [A_i a0])_{r..b-1, :}| : how far the dropped rows are from consistent
 *          (0 when b == r).
 * a0 may be NULL (resid then covers A_i only). B is not written when l == 0.
 * Returns AP_ERR_SINGULAR (outputs unspecified) when some R11_ii is not finite, or is exactly 0
 * (rcond given: the caller judges the estimate), or |R11_ii| <= 64 DBL_EPSILON max_j ||Ad_j||_2
 * (rcond NULL: singular to working precision relative to the largest column of Ad). */
int ap_la_partition_basis(int b, int k, int r, const int *perm, const double *A,
                          const double *a0, double *F, double *tau, double *B, double *b0,
                          double *growth, double *rcond, double *resid, double *work,
                          int *iwork);

/* Particular solution w (k) of A w = gamma with the factorization of ap_la_partition_basis:
 * w[perm[i]] = (R11^-1 (Q^T gamma)_{0..r-1})_i for i < r, 0 elsewhere.
 * resid = max |(Q^T gamma)_{r..b-1}| (0 when b == r). */
int ap_la_partition_particular(int b, int k, int r, const int *perm, const double *F,
                               const double *tau, const double *gamma, double *w,
                               double *resid, double *work);

/* ---- Orthonormal basis ("projected" mode) ------------------------------------------------ */

/* Pivoted QR (dgeqp3) of A^T (k x b): A^T P = Q R. rank as above; or, when rtol < 0, the
 * rank given in *rank (0..min(b, k)): the first *rank pivoted rows span the constraints (a
 * rank decided once, kept while nearly dependent rows drift apart). Forms the full orthogonal
 * Q (k x k, ld k; dorgqr) in Qf and Z = Q[:, rank..k-1] (k x l, ld k).
 * F (k x b, ld k) and tau (min(k,b)) keep the factorization, jpvt (b) the row order of A
 * (0-based), for ap_la_orth_particular.
 * b0 (k) if a0 and b0 are not NULL: the minimum-norm solution of A b0 = -a0.
 * resid = max over dropped rows of |A b0 + a0| (0 when rank == b or a0 is NULL).
 * b == 0 gives rank 0 and Qf = Z = I. iwork is not used. */
int ap_la_orth_basis(int b, int k, const double *A, const double *a0, double rtol, int *rank,
                     double *F, double *tau, int *jpvt, double *Qf, double *Z, double *b0,
                     double *resid, double *work, int *iwork);

/* Minimum-norm particular solution w (k) of A w = gamma from the factorization above.
 * resid = max over dropped rows of |(A w - gamma)_s|. */
int ap_la_orth_particular(int b, int k, int rank, const double *F, const int *jpvt,
                          const double *Qf, const double *gamma, double *w, double *resid,
                          double *work);

/* ---- Cholesky, congruence, least squares -------------------------------------------------- */

/* Cholesky factor G = L L^T in place (lower triangle read and written; dpotrf or the native
 * loop). rcond: the reciprocal 1-norm condition estimate (dlansy + dpocon), or NULL: no estimate.
 * AP_ERR_SINGULAR when a pivot is <= 0 or not finite (G not positive definite, or NaN / Inf in
 * its lower triangle), and, with rcond, when ||G||_1 is not finite. l == 0 is ok (rcond = 1). */
int ap_la_chol(int l, double *G, double *rcond, double *work, int *iwork);

/* Solve G x = rhs in place with the factor from ap_la_chol (dpotrs or forward and back
 * substitution, one right-hand side). */
void ap_la_chol_solve(int l, const double *L, double *x);

/* G = B^T g B (l x l, ld l, full symmetric), with scratch gB (k x l). g is k x k symmetric; only
 * its lower triangle is read. */
void ap_la_congruence(int k, int l, const double *g, const double *B, double *G, double *gB);

/* Minimum-norm least-squares solution of A^T lambda = rhs (A is b x k, rhs has k entries,
 * lambda b entries), rank decided with rtol as above. resid = max |A^T lambda - rhs|.
 * Used for the reactions. Does not modify A or rhs. lambda = 0 when the rank is 0. */
int ap_la_lstsq_At(int b, int k, const double *A, const double *rhs, double rtol,
                   double *lambda, double *resid, double *work, int *iwork);

/* y = M x  (M m x n, column-major, ld m) and y = M^T x. */
void ap_la_gemv(int m, int n, const double *M, const double *x, double *y);
void ap_la_gemv_t(int m, int n, const double *M, const double *x, double *y);

/* ---- size limit of the native kernels ------------------------------------------------------ */

/* Default limit: native when max(b, k) <= 16. Measured with bench/bench_linalg (OpenBLAS 0.3.21,
 * one thread, Xeon 2.5 GHz): for k <= 6 every routine is 2-20x faster natively; the QR
 * routines stay faster up to k ~ 24-40 (partition_basis 1.9x at (16, 32)), while congruence and
 * gemv, which OpenBLAS vectorizes, fall behind from k ~ 10-12 (congruence 0.5x at k = 12-16).
 * Summed over one evaluation's calls the native path is 2.4x faster at (6, 12), 1.5x at
 * (8, 16) and (10, 20), and even around (16, 32): 16 keeps the margin and the mechanism sizes. */
#define AP_LA_SMALL_LIMIT 16

/* The current limit of the calling thread. */
int ap_la_small_limit(void);
/* For tests and benchmarks only: set the calling thread's limit (0: LAPACK/BLAS everywhere; a
 * large value: native everywhere) and return its previous one. Each thread has its own
 * (thread-local, starting at AP_LA_SMALL_LIMIT): other threads are not affected. */
int ap_la_set_small_limit(int n);

/* ---- complex-step variants (linalg/scalar.h) ----------------------------------------------- */

/* The same routines on double _Complex values for complex-step derivatives: same arguments and
 * meaning with double replaced by double _Complex for every value array (A, a0, F, tau, B, b0,
 * gamma, w, G, L, x, y, work, ...), while rank, growth, resid and rcond stay double and come from
 * real parts. Always the native kernels, at every size (no LAPACK: its complex routines
 * conjugate, which is not analytic). Scratch: ap_la_work_size(b, k) elements of double _Complex,
 * ap_la_iwork_size(b, k) ints. rcond must be NULL (AP_ERR_ARG otherwise): condition estimates
 * come from the double routine at the real part. pivot_select_cs decides on the real part of A
 * with the double routine; lstsq_At_cs runs the steps of the double routine natively. */
int ap_la_pivot_select_cs(int b, int k, const double _Complex *A, double rtol, int *perm,
                          int *rank, double _Complex *work, int *iwork);
int ap_la_partition_basis_cs(int b, int k, int r, const int *perm, const double _Complex *A,
                             const double _Complex *a0, double _Complex *F, double _Complex *tau,
                             double _Complex *B, double _Complex *b0, double *growth,
                             double *rcond, double *resid, double _Complex *work, int *iwork);
int ap_la_partition_particular_cs(int b, int k, int r, const int *perm,
                                  const double _Complex *F, const double _Complex *tau,
                                  const double _Complex *gamma, double _Complex *w,
                                  double *resid, double _Complex *work);
int ap_la_orth_basis_cs(int b, int k, const double _Complex *A, const double _Complex *a0,
                        double rtol, int *rank, double _Complex *F, double _Complex *tau,
                        int *jpvt, double _Complex *Qf, double _Complex *Z,
                        double _Complex *b0, double *resid, double _Complex *work, int *iwork);
int ap_la_orth_particular_cs(int b, int k, int rank, const double _Complex *F, const int *jpvt,
                             const double _Complex *Qf, const double _Complex *gamma,
                             double _Complex *w, double *resid, double _Complex *work);
int ap_la_chol_cs(int l, double _Complex *G, double *rcond, double _Complex *work, int *iwork);
void ap_la_chol_solve_cs(int l, const double _Complex *L, double _Complex *x);
void ap_la_congruence_cs(int k, int l, const double _Complex *g, const double _Complex *B,
                         double _Complex *G, double _Complex *gB);
int ap_la_lstsq_At_cs(int b, int k, const double _Complex *A, const double _Complex *rhs,
                      double rtol, double _Complex *lambda, double *resid,
                      double _Complex *work, int *iwork);
void ap_la_gemv_cs(int m, int n, const double _Complex *M, const double _Complex *x,
                   double _Complex *y);
void ap_la_gemv_t_cs(int m, int n, const double _Complex *M, const double _Complex *x,
                     double _Complex *y);

#endif
