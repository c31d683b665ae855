/* The DAE cross-check: SUNDIALS IDA with Lagrange multipliers (docs/design.md §1, "The DAE
 * cross-check").
 *
 * Variables y = (q, v, Lambda, M), n + k + bs + nps of them, and the residual
 *
 *     F_q   = q' - N(q) v - Phi_s^T M'
 *     F_v   = g v' + h - Q - A_s^T Lambda'
 *     F_c   = A_s v + a0_s
 *     F_phi = phi_s(q, t)
 *
 * The multipliers lambda = Lambda' and mu = M' enter through their integrals, the impulses
 * Lambda and M (which appear only differentiated: IDA's BDF formula gives their derivatives,
 * and the impulses themselves are whatever integrates them). In Newton's iteration a change
 * dLambda of an impulse changes lambda by cj dLambda and v by g^-1 A_s^T dLambda, whatever
 * the step size: the impulses are scaled like v and q, where the multipliers themselves
 * scale like v / h (see "Scaling").
 *
 * With coupled forces (ap_dae_couple: a sliding contact's Coulomb force, contact_dae.c) F_v
 * has - W_s Lambda' besides, W (k x b) the generalized force per unit multiplier of each row,
 * and the Newton matrix's multiplier columns are -cj (A_s^T + W_s).
 *
 * A_s, a0_s are the bs independent rows of A, a0, and phi_s, Phi_s the nps independent rows of
 * phi and of its Jacobian Phi_q ("kept rows", below). The last rows are the
 * implicit holonomic constraints (loop closures, unit-quaternion norms) of a body model in the
 * stabilized index-2 form of Gear, Gupta and Leimkuhler (1985): their velocity form is already
 * among the rows of A (loops) or holds identically (quaternions, Phi_q N = 0), and the extra
 * multipliers mu = M' move q along Phi_q^T, the gradient of phi in q, which Phi_q Phi_q^T
 * (non-singular for independent rows) turns into a correction of phi. On the exact solution
 * mu = 0; numerically mu is what keeps phi = 0 at each step instead of letting it drift with the
 * integrated velocity rows. Phi_q is the Jacobian in q (not in v): for N != I this is what
 * makes Phi_q^T mu a vector of q-space, and it lets the quaternion rows |p|^2 - 1 (whose
 * gradient 2 p is normal to every N v) correct the norm.
 *
 * Kept rows. Redundant rows (two wheels on one axle, a loop closure written twice) would make
 * IDA's Newton matrix singular. At creation the row-pivoted QR of A^T (the factorization
 * ap_partition uses to find and name redundant rows) picks the rank-many independent rows of A,
 * and the same on Phi_q^T those of phi (rows of phi whose gradient is round-off, such as the
 * height of a wheel held by the tree, are dropped too); IDA carries multipliers for those only.
 * The choice is held along the motion unless it degrades (ap_dae_review_rows: then IDA
 * restarts with a new choice); the driver checks after every step that the rank has not changed
 * and that the dropped rows stay consistent. The multipliers of dropped rows are reported as
 * 0.
 *
 * Scaling (measured: without it IDA's Newton iteration failed at rtol 1e-12 on every model with
 * a plane contact or a loop). The impulses are algebraic (IDASetId 0) and out of the error test
 * (IDASetSuppressAlg), as index-2 variables must be, but they still weigh in the Newton
 * convergence test. Each is weighed by what it does to v or q: v moves by M dLambda with
 * M = g^-1 A_s^T, so the change of Lambda that moves v by dv along the constraint forces is
 * Pl dv with Pl = (A_s M)^-1 A_s (Pl M = I), and Lambda_c's tolerance is sum_i |Pl_ci| tol(v_i);
 * likewise M_r's is sum_i |Pm_ri| tol(q_i) with Pm = (Phi_s Phi_s^T)^-1 Phi_s. These do not
 * depend on the step size. The earlier form, with the multipliers themselves as variables
 * weighed by h times the largest effect on a v (or q), set the weights with the step IDA was
 * about to try and kept them when IDA cut the step after a failure: each cut by 4 made a
 * multiplier's weighted round-off 4 times larger, and once a component of v crossed zero (its
 * tolerance then atol alone) Newton's iteration could not converge at any step: the axle of
 * loop closures (examples/scenes/diff_drive_loops.yaml) stopped at t = 17.66 s at rtol 1e-10.
 *
 * The Newton matrix dF/dy + cj dF/dy' is assembled in dae_res.c: exact where F is linear
 * (the multipliers' columns, N, A_s, Phi_q, cj diag(I, g, 0, 0)), forward differences
 * elsewhere with increments sqrt(eps) times the component's typical size. IDA's own difference
 * quotients use an increment of 1/ewt, i.e. atol, for a component near zero, which at tight
 * tolerances left only round-off in the quotient.
 *
 * Tolerances. IDA controls the local error of each BDF step; its global error on the example
 * motions came out 4 to 720 times rtol where the Runge-Kutta methods of the Appell modes stay
 * at 0.1 to 30 times (bench/dae_accuracy.c, docs/architecture.md). So that the
 * cross-check compares like with like, IDA runs at rtol / AP_DAE_TOL_FACTOR (and atol scaled
 * alike), but not below rtol 1e-12, where BDF's error test begins to see round-off. Nor does
 * atol go below AP_DAE_ATOL_EPS ulps of the typical |q| (|v|) at the start: Newton's iteration
 * holds A_s v + a0_s = 0 only to the round-off of its terms, and a component of v near zero
 * with a tolerance below that round-off never passes the convergence test (the bicycle at
 * atol 1e-14, i.e. 1e-15 for IDA, failed at t = 3.59 s with steps of 6e-15 s).
 *
 * Consistent initial values come from the Appell solve (v' known exactly there; the impulses
 * start at 0 with derivatives lambda for the kept rows by least squares on
 * A_s^T lambda = g v' + h - Q, and mu = 0), so IDACalcIC is never called. The residual runs
 * the core's position and velocity stages with AP_BASIS_NONE: no null-space basis is built. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrate/dae_int.h"
#include "integrate/nvpool.h"
#include "integrate/sunctx.h"
#include "linalg/linalg.h"

/* ---- creation ------------------------------------------------------------------------------ */

double ap_dae_rtol(double rtol) { return fmax(rtol / AP_DAE_TOL_FACTOR, fmin(rtol, 1e-12)); }

/* Row-pivoted QR of M^T (M rows x cols) in the scratch: the rank, the row order (jpvt: the
 * first rank rows are the independent ones, as ap_partition chooses them) and the quality
 * |R_rr|, the last kept pivot (1 when rank is 0), in the units of M's rows: review compares it
 * with the best choice's of the same M. (Relative to the choice's own first pivot, as it was,
 * one kept row always had quality 1: a loop locking a joint keeps one of its three rows, whose
 * norm fell to zero as the mechanism turned, and IDA stopped at t = 0.2591 with steps of 5e-16
 * s: tests/scenes/difftest/dae_locked_loop.yaml.) With floor,
 * pivots below rank_rtol times the model's length scale m->lscale (core/core.h: the scale of
 * the gradients of phi) do not count either: rows of phi that vanish identically (a wheel
 * contact whose height is fixed by the tree) have gradients of round-off size, and a test
 * relative to the largest pivot would keep one of them as noise. */
static int row_qr(ap_dae *s, int rows, int cols, const double *M, double rank_rtol, int floor,
                  int *rank, double *quality) {
  int mx = rows > cols ? rows : cols;
  double *F = s->qr, *tau = F + (size_t)cols * rows, *Qf = tau + mx, *Z = Qf + (size_t)cols * cols;
  double resid = 0.0;
  *rank = 0, *quality = 1.0;
  if (rows == 0) return AP_OK;
  int rc = ap_la_orth_basis(rows, cols, M, NULL, rank_rtol, rank, F, tau, s->jpvt, Qf, Z, NULL,
                            &resid, Z + (size_t)cols * cols, s->jpvt + rows);
  while (rc == AP_OK && floor && *rank > 0 &&
         !(fabs(F[(*rank - 1) + (size_t)(*rank - 1) * cols]) > rank_rtol * s->m->lscale))
    (*rank)--;
  if (rc == AP_OK && *rank > 0) *quality = fabs(F[(*rank - 1) + (size_t)(*rank - 1) * cols]);
  return rc;
}

/* The independent rows of M into keep (ascending), their number into *nkeep, and the quality
 * of that choice (row_qr). */
static int independent_rows(ap_dae *s, int rows, int cols, const double *M, double rank_rtol,
                            int floor, int *keep, int *nkeep, double *quality) {
  int rank = 0, rc = row_qr(s, rows, cols, M, rank_rtol, floor, &rank, quality);
  for (int i = 0; rc == AP_OK && i < rank; i++) {          /* insertion sort of jpvt[0..rank) */
    int x = s->jpvt[i], j = i;
    for (; j > 0 && keep[j - 1] > x; j--) keep[j] = keep[j - 1];
    keep[j] = x;
  }
  if (rc == AP_OK) *nkeep = rank;
  return rc;
}

/* The quality of the rows keep (nkeep of M's rows): row_qr of that submatrix; 0 when they have
 * become dependent. */
static int kept_quality(ap_dae *s, int rows, int cols, const double *M, const int *keep,
                        int nkeep, double rank_rtol, int floor, double *quality) {
  double *sub = s->qr_sub;
  int rank = 0;
  for (int c = 0; c < nkeep; c++)
    for (int j = 0; j < cols; j++) sub[c + (size_t)j * nkeep] = M[keep[c] + (size_t)j * rows];
  int rc = row_qr(s, nkeep, cols, sub, rank_rtol, floor, &rank, quality);
  if (rc == AP_OK && rank < nkeep) *quality = 0.0;
  return rc;
}

/* The kept rows of A and of phi at the data's state (the position stage at t0). */
static int choose_rows(ap_dae *s, double rank_rtol) {
  double quality = 1.0;
  int rc = independent_rows(s, s->b, s->k, s->d->A, rank_rtol, 0, s->rows, &s->bs, &quality);
  if (rc != AP_OK || s->nphi == 0) return rc;
  memset(s->Phi_q, 0, sizeof(double) * (size_t)s->nphi * s->n);
  rc = s->m->ev.phi(s->m, s->d, ((ap_scratch *)s->d->internal)->ev, s->phi, s->Phi_q);
  if (rc == AP_OK)
    rc = independent_rows(s, s->nphi, s->n, s->Phi_q, rank_rtol, 1, s->prows, &s->nps,
                          &quality);
  return rc;
}

/* The impulses start at 0 and their derivatives at the multipliers: lambda for the kept rows by
 * least squares on A_s^T lambda = g v' + h - Q (= F_v at lambda = 0), mu = 0. Called at
 * creation and at every restart (ap_dae_restart, mid-run): its vector is made at the first
 * call, and the solve's LAPACK workspace is row_qr's (s->qr, s->jpvt: sized for
 * max(b, nphi) x max(n, k) >= bs x k, unused between row choices), so a restart allocates
 * nothing and cannot fail for memory. */
static int initial_multipliers(ap_dae *s, double t0) {
  int n = s->n, k = s->k, bs = s->bs;
  if (!s->rr) s->rr = N_VNew_Serial(s->ny, s->ctx);   /* N_VClone crashes when out of memory */
  if (!s->rr) return AP_ERR_NOMEM;
  N_Vector rr = s->rr;
  double *y = N_VGetArrayPointer(s->yy), *y1 = N_VGetArrayPointer(s->yp);
  double *r = N_VGetArrayPointer(rr);
  memset(y + n + k, 0, sizeof(double) * (size_t)(bs + s->nps));
  memset(y1 + n + k, 0, sizeof(double) * (size_t)(bs + s->nps));
  int rc = ap_dae_residual(t0, s->yy, s->yp, rr, s) == 0 ? AP_OK : s->res_status;
  if (rc == AP_OK && bs > 0) {
    for (int c = 0; c < bs; c++)
      for (int i = 0; i < k; i++)
        s->jA[c + (size_t)i * bs] = s->d->A[s->rows[c] + (size_t)i * s->b] +
                                    (s->cp.fn ? s->W[i + (size_t)s->rows[c] * k] : 0.0);
    rc = ap_dae_load_lin(s, s->jA);   /* + the loads' force in lambda (dae_res.c) */
    double resid = 0.0;
    if (rc == AP_OK)
      rc = ap_la_lstsq_At(bs, k, s->jA, r + n, 0.0, y1 + n + k, &resid, s->qr, s->jpvt);
  }
  if (rc == AP_OK) ap_dae_multiplier_scales(s);
  if (rc != AP_OK && !s->msg[0])
    snprintf(s->msg, sizeof s->msg, "initial multipliers: %s",
             s->res_status ? s->res_msg : "least-squares solve failed");
  return rc;
}

static int alloc_arrays(ap_dae *s) {
  size_t n = (size_t)s->n, k = (size_t)s->k, b = (size_t)s->b, np = (size_t)s->nphi;
  s->rows = calloc(2 * (b + np) + 3, sizeof *s->rows);
  size_t rmax = b > np ? b : np, cmax = n > k ? n : k, mx = rmax > cmax ? rmax : cmax;
  s->Phi_q = calloc(np * n + np + k * k + n * k + b * k + np * n + k * b + k * k + b * k +
                    np * n + rmax * rmax + rmax + 1, sizeof *s->Phi_q);
  if (!s->rows || !s->Phi_q) return AP_ERR_NOMEM;
  s->prows = s->rows + b + 1, s->cand = s->prows + np + 1;
  s->qr = calloc(cmax * rmax + mx + 2 * cmax * cmax + ap_la_work_size((int)rmax, (int)cmax) +
                 rmax * cmax + 1, sizeof *s->qr);
  s->jpvt = calloc(rmax + ap_la_iwork_size((int)rmax, (int)cmax) + 1, sizeof *s->jpvt);
  s->W = calloc(2 * k * b + 1, sizeof *s->W);
  if (s->cp.load) s->lamf = calloc(2 * b + 3 * k + k * k + k * b + 1, sizeof *s->lamf);
  if (!s->qr || !s->jpvt || !s->W || (s->cp.load && !s->lamf)) return AP_ERR_NOMEM;
  s->jW = s->W + k * b;
  if (s->lamf) s->lF = s->lamf + b, s->lw = s->lF + k, s->lFv = s->lw + b + 2 * k;
  if (s->lamf) s->lFl = s->lFv + k * k;
  s->qr_sub = s->qr + cmax * rmax + mx + 2 * cmax * cmax + ap_la_work_size((int)rmax, (int)cmax);
  s->phi = s->Phi_q + np * n, s->jg = s->phi + np, s->jN = s->jg + k * k;
  s->jA = s->jN + n * k;
  s->jP = s->jA + b * k, s->Ms = s->jP + np * n, s->gf = s->Ms + k * b;
  s->Pl = s->gf + k * k, s->Pm = s->Pl + b * k, s->Sf = s->Pm + np * n;
  s->colw = s->Sf + rmax * rmax;
  return AP_OK;
}

/* IDA with its options; returns 1 when every call succeeded. */
static int setup_ida(ap_dae *s, double t0, const ap_step_opts *o) {
  int ok = (s->mem = IDACreate(s->ctx)) != NULL;
  ok = ok && IDASetErrHandlerFn(s->mem, ap_dae_err_handler, s) == IDA_SUCCESS &&
       IDAInit(s->mem, ap_dae_residual, t0, s->yy, s->yp) == IDA_SUCCESS &&
       IDASetUserData(s->mem, s) == IDA_SUCCESS &&
       IDAWFtolerances(s->mem, ap_dae_weights) == IDA_SUCCESS &&
       IDASetId(s->mem, s->id) == IDA_SUCCESS &&
       IDASetSuppressAlg(s->mem, SUNTRUE) == IDA_SUCCESS &&
       IDASetMaxNumSteps(s->mem, o->max_steps > 0 ? o->max_steps : 100000) == IDA_SUCCESS &&
       IDASetInitStep(s->mem, o->h_init) == IDA_SUCCESS;
  if (ok && o->h_max > 0) ok = IDASetMaxStep(s->mem, o->h_max) == IDA_SUCCESS;
  /* Newton's convergence test: 0.03 instead of IDA's 0.33 (the corrector's error then stays out
   * of the error estimate: 10 to 55% fewer steps on the example scenes at rtol 1e-6 .. 1e-12),
   * but not below what round-off lets the corrector reach (1e3 eps / rtol: at 0.01 and rtol
   * 1e-12 the rattleback's Newton iteration failed). */
  if (ok) ok = IDASetNonlinConvCoef(s->mem, fmin(0.33, fmax(0.03, 1e3 * DBL_EPSILON / s->rtol))) ==
               IDA_SUCCESS;
  if (ok) {
    s->J = SUNDenseMatrix(s->ny, s->ny, s->ctx);
    s->LS = s->J ? SUNLinSol_Dense(s->yy, s->J, s->ctx) : NULL;
    ok = s->LS && IDASetLinearSolver(s->mem, s->LS, s->J) == IDA_SUCCESS &&
         IDASetJacFn(s->mem, ap_dae_jacobian) == IDA_SUCCESS;
  }
  return ok;
}

static int ap_dae_nomem(const ap_model *m, char *msg, size_t msg_len) {
  if (msg && msg_len) snprintf(msg, msg_len, "IDA setup for system '%s': out of memory", m->name);
  return AP_ERR_NOMEM;
}

int ap_dae_create(const ap_model *m, ap_data *d, double t0, const double *y0,
                  const double *yp0, const ap_step_opts *o, double rank_rtol,
                  const ap_dae_couple *cp, ap_dae **out, char *msg, size_t msg_len) {
  *out = NULL;
  ap_dae *s = calloc(1, sizeof *s);
  if (!s) return ap_dae_nomem(m, msg, msg_len);
  s->m = m, s->d = d, s->n = m->n, s->k = m->k, s->b = m->b;
  s->rtol = ap_dae_rtol(o->rtol), s->atol = o->atol * s->rtol / o->rtol;
  s->nphi = m->ev.phi ? m->nphi : 0;
  if (cp) s->cp = *cp;
  int rc = alloc_arrays(s);
  if (rc == AP_OK) rc = choose_rows(s, rank_rtol);
  if (rc != AP_OK) {
    ap_dae_free(s);
    return rc == AP_ERR_NOMEM ? ap_dae_nomem(m, msg, msg_len) : rc;
  }
  int n = s->n, k = s->k, nd = n + k;
  s->ny = nd + s->bs + s->nps;
  for (int i = 0; i < n; i++) s->qtyp = fmax(s->qtyp, fabs(y0[i]));
  for (int i = 0; i < k; i++) s->vtyp = fmax(s->vtyp, fabs(y0[n + i]));
  if (!(s->qtyp > 0)) s->qtyp = 1.0;
  if (!(s->vtyp > 0)) s->vtyp = 1.0;
  int ok = ap_ctx_take(&s->ctx) == AP_OK;   /* sunctx.c */
  if (ok) ok = ap_nvp_create(s->ny, AP_DAE_POOL, s->ctx, &s->pool) == AP_OK;
  if (ok) {
    s->yy = ap_nvp_take(s->pool), s->yp = ap_nvp_take(s->pool), s->id = ap_nvp_take(s->pool);
    ok = s->yy && s->yp && s->id;
  }
  if (ok) {
    double *y = N_VGetArrayPointer(s->yy), *y1 = N_VGetArrayPointer(s->yp);
    double *id = N_VGetArrayPointer(s->id);
    memset(y, 0, sizeof(double) * (size_t)s->ny);
    memset(y1, 0, sizeof(double) * (size_t)s->ny);
    memcpy(y, y0, sizeof(double) * (size_t)nd);
    memcpy(y1, yp0, sizeof(double) * (size_t)nd);
    for (int i = 0; i < s->ny; i++) id[i] = i < nd ? 1.0 : 0.0;
    rc = initial_multipliers(s, t0);
    ok = rc == AP_OK && setup_ida(s, t0, o) && !ap_nvp_nomem(s->pool);
  }
  if (!ok) {   /* no message from IDA: an object could not be allocated */
    if (rc == AP_OK) rc = s->nomem || !s->msg[0] ? AP_ERR_NOMEM : AP_ERR_SOLVER;
    if (msg && msg_len)
      snprintf(msg, msg_len, "IDA setup failed for system '%s': %.300s", m->name,
               s->msg[0] ? s->msg : "out of memory");
    ap_dae_free(s);
    return rc;
  }
  *out = s;
  return AP_OK;
}

/* ---- stepping ------------------------------------------------------------------------------ */

/* y (n + k + b + nphi) from IDA's state: q and v, and the multipliers, which are the impulses'
 * derivatives; those of dropped rows are 0. */
void ap_dae_state(const ap_dae *s, double *y) {
  const double *x = N_VGetArrayPointer(s->yp);
  int nd = s->n + s->k;
  memcpy(y, N_VGetArrayPointer(s->yy), sizeof(double) * (size_t)nd);
  memset(y + nd, 0, sizeof(double) * (size_t)s->b);
  memset(y + nd + s->b, 0, sizeof(double) * (size_t)s->nphi);
  for (int c = 0; c < s->bs; c++) y[nd + s->rows[c]] = x[nd + c];
  for (int c = 0; c < s->nps; c++) y[nd + s->b + s->prows[c]] = x[nd + s->bs + c];
}

/* IDA's steps shrank to the round-off of t without a failing evaluation: a model that stops
 * being defined just ahead (a drive that turns NaN past some time) is approached forever and
 * never evaluated. Evaluate the residual at the current state at t + 2 h, t + 4 h, ... up to
 * tout; the first failure is the cause, reported with its own message and status. */
static int probe_ahead(ap_dae *s, double t, double tout, double h) {
  N_Vector rr = N_VNew_Serial(s->ny, s->ctx);   /* N_VClone crashes when it cannot allocate */
  if (!rr) return AP_OK;
  int rc = AP_OK;
  for (double dt = 2.0 * h; rc == AP_OK && dt < 2.0 * (tout - t); dt *= 2.0) {
    s->res_status = AP_OK;
    if (ap_dae_residual(fmin(t + dt, tout), s->yy, s->yp, rr, s) != 0 && s->res_status < 0)
      rc = s->res_status;
  }
  N_VDestroy(rr);
  if (rc != AP_OK)
    snprintf(s->msg, sizeof s->msg, "%.700s (IDA's steps had shrunk to %.3g s at t = %.17g "
             "approaching it)", s->res_msg, h, t);
  return rc;
}

/* IDA's step failed at tret: the residual's own failure when it stopped IDA, else IDA's
 * message; when the step had fallen to hmin, what a probe ahead finds first. */
static int step_failed(ap_dae *s, double tret, double tout, double hmin) {
  if (s->res_status < 0) {
    snprintf(s->msg, sizeof s->msg, "%s", s->res_msg);
    return s->res_status;
  }
  double hl = 0.0;
  IDAGetCurrentStep(s->mem, &hl);
  int tiny = hmin > 0 && fabs(hl) <= 2.0 * hmin;
  if (tiny) {
    int rc = probe_ahead(s, tret, tout, fabs(hl));
    if (rc != AP_OK) return rc;
  }
  char tmp[256];
  memcpy(tmp, s->msg, sizeof tmp);   /* the handler's text, cut to fit */
  tmp[sizeof tmp - 1] = '\0';
  snprintf(s->msg, sizeof s->msg, "IDA failed at t = %.17g for system '%s': %.200s%s%.200s%s",
           tret, s->m->name, tmp, s->res_status > 0 ? "; last residual failure: " : "",
           s->res_status > 0 ? s->res_msg : "", tiny ? " (the step size fell to the round-off "
           "of t: the solution is not smooth there)" : "");
  return AP_ERR_SOLVER;
}

int ap_dae_one(ap_dae *s, double tout, double *t, double *y) {
  s->res_status = AP_OK;
  /* Never leave a sliver before tout: when the next step h would stop short of tout by less
   * than h, stop halfway instead (two steps of (tout - t)/2 where there would have been h and
   * a remainder, possibly of round-off size, on which the index-2 Newton iteration fails). The
   * smallest step allowed is a few ulps of t: below that t + h == t, and IDA would go on
   * "stepping" forever towards a point the solution cannot pass (a drive that stops being
   * defined there). */
  double h = 0.0, stop = tout, rem = tout - *t;
  if (IDAGetCurrentStep(s->mem, &h) == IDA_SUCCESS && h > 0 && rem > h && rem < 2.0 * h)
    stop = *t + 0.5 * rem;
  double hmin = 8.0 * DBL_EPSILON * fabs(*t);
  if (IDASetStopTime(s->mem, stop) != IDA_SUCCESS ||
      IDASetMinStep(s->mem, hmin) != IDA_SUCCESS)
    return AP_ERR_SOLVER;
  double tret = *t;
  int flag = IDASolve(s->mem, stop, &tret, s->yy, s->yp, IDA_ONE_STEP);
  if (ap_nvp_nomem(s->pool)) {   /* IDA ran with the pool's spare vector: void */
    snprintf(s->msg, sizeof s->msg, "IDA: out of memory (work vectors) at t = %.17g", *t);
    return AP_ERR_NOMEM;
  }
  if (flag < 0) {
    int rc = step_failed(s, tret, tout, hmin);
    return flag == IDA_MEM_FAIL && rc == AP_ERR_SOLVER ? AP_ERR_NOMEM : rc;
  }
  *t = tret;
  ap_dae_state(s, y);
  return AP_OK;
}

/* ---- the kept rows along the motion -------------------------------------------------------- */

/* The rows kept at the start can degrade along the motion: on the differential-drive robots
 * (examples/scenes/diff_drive*.yaml) the kept rows' smallest relative pivot falls linearly to
 * zero each time the heading passes a multiple of pi / 2, where the kept rows become dependent.
 * They are chosen again when their last pivot has fallen below 0.1 of that of the rows the QR
 * would pick now (a restart about every 2 s there). At 1e-3, as before, the caster robot reached kept rows of
 * relative pivot 1e-5, and IDA's restart there failed (t = 17.67 s at rtol 1e-10): the state's
 * error along the nearly dependent direction is amplified by the inverse pivot. */
static int review(ap_dae *s, int rows, int cols, const double *M, double rank_rtol, int floor,
                  int *keep, int nkeep, int *changed) {
  double best = 1.0, now = 1.0;
  int nbest = 0, rc = AP_OK;
  if (nkeep == rows) return AP_OK;
  rc = kept_quality(s, rows, cols, M, keep, nkeep, rank_rtol, floor, &now);
  if (rc != AP_OK) return rc;
  rc = independent_rows(s, rows, cols, M, rank_rtol, floor, s->cand, &nbest, &best);
  if (rc != AP_OK || nbest != nkeep || !(now < 0.1 * best)) return rc;
  memcpy(keep, s->cand, sizeof(int) * (size_t)nkeep);
  *changed = 1;
  return AP_OK;
}

int ap_dae_review_rows(ap_dae *s, double rank_rtol) {
  int changed = 0, rc = AP_OK;
  if (s->bs < s->b) rc = review(s, s->b, s->k, s->d->A, rank_rtol, 0, s->rows, s->bs, &changed);
  if (rc == AP_OK && s->nps < s->nphi) {
    memset(s->Phi_q, 0, sizeof(double) * (size_t)s->nphi * s->n);
    rc = s->m->ev.phi(s->m, s->d, ((ap_scratch *)s->d->internal)->ev, s->phi, s->Phi_q);
    if (rc == AP_OK)
      rc = review(s, s->nphi, s->n, s->Phi_q, rank_rtol, 1, s->prows, s->nps, &changed);
  }
  return rc != AP_OK ? rc : changed;
}

int ap_dae_restart(ap_dae *s, double t, const double *y, const double *qdot, const double *vdot,
                   double h0) {
  double *x = N_VGetArrayPointer(s->yy), *x1 = N_VGetArrayPointer(s->yp);
  memset(x, 0, sizeof(double) * (size_t)s->ny);
  memset(x1, 0, sizeof(double) * (size_t)s->ny);
  memcpy(x, y, sizeof(double) * (size_t)(s->n + s->k));
  memcpy(x1, qdot, sizeof(double) * (size_t)s->n);
  memcpy(x1 + s->n, vdot, sizeof(double) * (size_t)s->k);
  s->res_status = AP_OK;
  int rc = initial_multipliers(s, t);
  long v = 0;
  if (IDAGetNumSteps(s->mem, &v) == IDA_SUCCESS) s->base_steps += v;   /* IDAReInit zeroes them */
  if (IDAGetNumErrTestFails(s->mem, &v) == IDA_SUCCESS) s->base_netf += v;
  if (IDAGetNumNonlinSolvConvFails(s->mem, &v) == IDA_SUCCESS) s->base_ncf += v;
  if (rc == AP_OK && (IDAReInit(s->mem, t, s->yy, s->yp) != IDA_SUCCESS ||
                      (h0 > 0 && IDASetInitStep(s->mem, h0) != IDA_SUCCESS)))
    rc = AP_ERR_SOLVER;
  if (rc != AP_OK) {
    char tmp[400];
    snprintf(tmp, sizeof tmp, "%.300s", s->msg);
    snprintf(s->msg, sizeof s->msg, "IDA could not restart at t = %.17g after choosing other "
             "independent rows: %s", t, tmp);
  }
  return rc;
}

/* ---- queries ------------------------------------------------------------------------------- */

int ap_dae_rows(const ap_dae *s, const int **rows) {
  if (rows) *rows = s->rows;
  return s->bs;
}

int ap_dae_phi_rows(const ap_dae *s, const int **rows) {
  if (rows) *rows = s->prows;
  return s->nps;
}

void ap_dae_stats(const ap_dae *s, ap_step_stats *st) {
  long v = 0;
  memset(st, 0, sizeof *st);
  if (IDAGetNumSteps(s->mem, &v) == IDA_SUCCESS) st->steps = s->base_steps + v;
  st->rhs_evals = s->nres;
  if (IDAGetNumErrTestFails(s->mem, &v) == IDA_SUCCESS) st->err_fails = s->base_netf + v;
  if (IDAGetNumNonlinSolvConvFails(s->mem, &v) == IDA_SUCCESS) st->rhs_fails = s->base_ncf + v;
  double h = 0;
  if (IDAGetLastStep(s->mem, &h) == IDA_SUCCESS) st->h_last = h;
}

void ap_dae_carry_stats(ap_dae *to, const ap_dae *from) {
  ap_step_stats st;
  ap_dae_stats(from, &st);
  to->base_steps += st.steps, to->base_netf += st.err_fails, to->base_ncf += st.rhs_fails;
  to->nres += from->nres;
}

int ap_dae_multipliers(ap_dae *s, double t, double *lam) {
  int kused = 0, nd = s->n + s->k;
  const double *x = N_VGetArrayPointer(s->yp);
  if (IDAGetLastOrder(s->mem, &kused) == IDA_SUCCESS && kused > 0) {
    if (!s->dk) s->dk = N_VNew_Serial(s->ny, s->ctx);
    if (!s->dk) return AP_ERR_NOMEM;
    int flag = IDAGetDky(s->mem, t, 1, s->dk);
    if (flag != IDA_SUCCESS) {
      snprintf(s->msg, sizeof s->msg, "IDA: no multipliers at t = %.17g (flag %d)", t, flag);
      return flag == IDA_BAD_T ? AP_ERR_ARG : AP_ERR_SOLVER;
    }
    x = N_VGetArrayPointer(s->dk);
  }
  memset(lam, 0, sizeof(double) * (size_t)(s->b + s->nphi));
  for (int c = 0; c < s->bs; c++) lam[s->rows[c]] = x[nd + c];
  for (int c = 0; c < s->nps; c++) lam[s->b + s->prows[c]] = x[nd + s->bs + c];
  return AP_OK;
}

const char *ap_dae_message(const ap_dae *s) { return s->msg; }

int ap_dae_dky(ap_dae *s, double t, double *y) {
  if (!s->dk) s->dk = N_VNew_Serial(s->ny, s->ctx);   /* once, at the first event */
  if (!s->dk) return AP_ERR_NOMEM;
  int flag = IDAGetDky(s->mem, t, 0, s->dk);
  if (flag != IDA_SUCCESS) {
    snprintf(s->msg, sizeof s->msg, "IDA: no dense output at t = %.17g (flag %d)", t, flag);
    return flag == IDA_BAD_T ? AP_ERR_ARG : AP_ERR_SOLVER;
  }
  memcpy(y, N_VGetArrayPointer(s->dk), sizeof(double) * (size_t)(s->n + s->k));
  memset(y + s->n + s->k, 0, sizeof(double) * (size_t)(s->b + s->nphi));
  return AP_OK;
}

void ap_dae_free(ap_dae *s) {
  if (!s) return;
  if (s->mem) IDAFree(&s->mem);
  if (s->LS) SUNLinSolFree(s->LS);
  if (s->J) SUNMatDestroy(s->J);
  if (s->yy) N_VDestroy(s->yy);
  if (s->yp) N_VDestroy(s->yp);
  if (s->id) N_VDestroy(s->id);
  if (s->dk) N_VDestroy(s->dk);
  if (s->rr) N_VDestroy(s->rr);
  ap_nvp_free(s->pool);
  ap_ctx_give(s->ctx);
  free(s->Phi_q);
  free(s->rows);
  free(s->qr);
  free(s->jpvt);
  free(s->W);
  free(s->lamf);
  free(s);
}
