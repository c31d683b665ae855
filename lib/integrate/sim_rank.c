/* The loop-rank monitor: a stage of the after-step pipeline (sim_after.c) that stops a run, in
 * every mode, where the constraint matrix A loses a rank along the motion: a singular
 * configuration of the loops, where several motions cross (a bifurcation) and no mode can say
 * which one the model takes (docs/testing.md, tests/scenes/difftest/axle_loop_bifurcation.yaml).
 *
 * Only models with implicit holonomic rows (loops, wheel contacts: m->nhol > 0) are watched, on
 * the dense path and without contact modes. The monitor keeps r independent rows and r columns
 * of A (a square minor M of full rank, r = rank of A, by pivoted QR) and at each accepted step
 * f = det M / s^r, s the largest row norm of M (signed, in [-1, 1], continuous in q and t):
 *   - f changes sign within a step: its root t* is found on the stepper's dense output
 *     (root.c, the events' root finder) and A judged there: A lost a rank when its best
 *     minor at t* is of lower rank, or below LR_DROP of the best at the step's ends: the run
 *     stops, naming the rows of M's left null vector; otherwise M alone was singular and a
 *     new minor is chosen;
 *   - |f| fell below LR_RESELECT of its value when chosen, or of the first minor's: a new
 *     minor is chosen (A's best), and the run stops when the rank fell; a passage whose best
 *     minor falls below near() (LR_NEAR sqrt of the loops' gap, at least sqrt(rank_rtol) of
 *     the first one) stops the run once the best minor no longer falls, at the least one: a
 *     run passes a crossing beside it, at a distance set by its own error (plain mode's
 *     drift: campaign seeds 1006032, 1008416; explicit runs that passed at 3e-7 .. 2e-6 of
 *     the first minor: 1003433, 1008451), so every run stops alike.
 * A minimal-mode partition switch (growth past switch_growth) does not see a vanishing row:
 * every dependent speed's coefficient in it shrinks alike, so the growth of the frozen basis
 * stays bounded through the crossing (campaign seed 1005585). A step that fails next to a drop
 * is reported as the drop (ap_drv_loop_rank_failed), and an initial state where the rank
 * changes a moment along the motion is refused at creation (rank_along). Cost: one r x r
 * elimination per accepted step; the position stage it may make is taken over by the mode's
 * stage (ap_drv_loop_rank_held); nothing for models without loops. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrate/root.h"
#include "integrate/sim_int.h"
#include "linalg/linalg.h"

#define LR_RESELECT 1e-2  /* choose a new minor when |f| falls below this of its chosen value */
#define LR_ITER 200       /* root-finding iterations (bisection bounds them) */
#define LR_DROP 1e-3      /* a minor's root is A's when its best minor there falls below this
                             of the best at the step's ends */

struct ap_drv_lrank {
  int r;              /* rank of A when chosen */
  int rmax;           /* the rank at creation: rows redundant only on the manifold stay so */
  double q_ref;       /* |f| of the best minor at creation */
  long held;          /* the data's stage count after the stage's own position stage */
  double held_t;
  int *rows, *cols;   /* (r) the watched minor */
  int *brows, *bcols; /* (r) a best minor (judging a crossing) */
  int *perm, *rperm;  /* (k), (b) scratch of the selection */
  int *iwork, *ipiv;
  double *M, *AT, *work, *yd, *null;
  double f_prev, t_prev, f_sel;
  double near_t, near_f;  /* a passage below near(): where A's best minor was least (f 0: none) */
  double near_lev;        /* near() there */
};

/* det M / s^r for the minor M = A[rows, cols] (r x r), s its largest row norm: signed, in
 * [-1, 1], continuous along the motion, 0 when M is singular. The LU (partial pivoting) stays
 * in lr->M and lr->ipiv for name_rows. */
static double minor_ratio(ap_drv_lrank *lr, const double *A, int b, int r, const int *rows,
                          const int *cols) {
  double *M = lr->M, f = 1.0, scale = 0.0;
  for (int i = 0; i < r; i++) {
    double sq = 0.0;
    for (int j = 0; j < r; j++) {
      double a = A[rows[i] + (size_t)cols[j] * b];
      M[i + j * r] = a, sq += a * a;
    }
    scale = fmax(scale, sq);
  }
  scale = sqrt(scale);
  if (!(scale > 0)) return 0.0;
  for (int i = 0; i < r * r; i++) M[i] /= scale;
  for (int c = 0; c < r; c++) {
    int p = c;
    for (int i = c + 1; i < r; i++)
      if (fabs(M[i + c * r]) > fabs(M[p + c * r])) p = i;
    lr->ipiv[c] = p;
    if (p != c) {
      f = -f;
      for (int j = 0; j < r; j++) {
        double t = M[c + j * r];
        M[c + j * r] = M[p + j * r], M[p + j * r] = t;
      }
    }
    double piv = M[c + c * r];
    f *= piv;
    if (piv == 0.0) continue;
    for (int i = c + 1; i < r; i++) {
      double l = M[i + c * r] / piv;
      M[i + c * r] = l;
      for (int j = c + 1; j < r; j++) M[i + j * r] -= l * M[c + j * r];
    }
  }
  return f;
}

/* The rows of M's left null vector (M^T y = 0, two steps of inverse iteration on the LU of
 * minor_ratio) with weight above a tenth of the largest, as "'c1.x', 'c2.x'". */
static void name_rows(const ap_model *m, ap_drv_lrank *lr, char *out, size_t len) {
  int r = lr->r;
  double *M = lr->M, *y = lr->null, ymax = 0.0;
  for (int i = 0; i < r; i++) y[i] = 1.0 + 0.1 * i;
  for (int it = 0; it < 2; it++) {
    for (int c = 0; c < r; c++) {   /* U^T z = y */
      double s = y[c];
      for (int i = 0; i < c; i++) s -= M[i + c * r] * y[i];
      double piv = M[c + c * r];
      y[c] = s / (fabs(piv) > DBL_MIN ? piv : DBL_EPSILON);
    }
    for (int c = r - 1; c >= 0; c--) {   /* L^T w = z, then the row swaps back */
      for (int i = c + 1; i < r; i++) y[c] -= M[i + c * r] * y[i];
      int p = lr->ipiv[c];
      double t = y[c];
      y[c] = y[p], y[p] = t;
    }
    ymax = 0.0;
    for (int i = 0; i < r; i++) ymax = fmax(ymax, fabs(y[i]));
    for (int i = 0; ymax > 0 && i < r; i++) y[i] /= ymax;
  }
  size_t used = 0;
  out[0] = '\0';
  for (int i = 0; i < r && used + 40 < len; i++) {
    if (!(fabs(y[i]) > 0.1)) continue;
    int n = snprintf(out + used, len - used, "%s'%s'", used ? ", " : "",
                     m->constraint_names[lr->rows[i]]);
    if (n > 0) used += (size_t)n;
  }
}

/* The position stage at (t, q): A and a0 (no basis). */
static int position_at(ap_sim *s, double t, const double *q) {
  ap_data *d = s->d;
  ap_basis basis = d->basis;
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)s->n);
  d->basis = AP_BASIS_NONE;
  s->ev_stamp = -1;
  int rc = ap_fwd_position(s->m, d);
  d->basis = basis;
  return rc;
}

/* A minor of full rank of the current A: columns by pivoted QR of A, rows by pivoted QR of
 * A[:, cols]^T (rank_rtol). *r: its size, the rank of A. */
static int choose(ap_sim *s, int *r, int *rows, int *cols) {
  ap_drv_lrank *lr = s->lr;
  const double *A = s->d->A;
  int b = s->m->b, k = s->m->k, rc = 0, r2 = 0;
  rc = ap_la_pivot_select(b, k, A, s->def.rank_rtol, lr->perm, r, lr->work, lr->iwork);
  for (int i = 0; rc == AP_OK && i < *r; i++)
    for (int c = 0; c < b; c++) lr->AT[i + (size_t)c * *r] = A[c + (size_t)lr->perm[i] * b];
  if (rc == AP_OK && *r > 0)
    rc = ap_la_pivot_select(*r, b, lr->AT, s->def.rank_rtol, lr->rperm, &r2, lr->work,
                            lr->iwork);
  if (rc != AP_OK) return ap_drv_fail(s, rc, "loop rank: pivoted QR of A failed at t = %.17g",
                                      s->d->t);
  *r = *r < r2 ? *r : r2;
  if (lr->rmax > 0 && *r > lr->rmax) *r = lr->rmax;   /* off the manifold by the drift */
  memcpy(cols, lr->perm, sizeof(int) * (size_t)*r);
  memcpy(rows, lr->rperm, sizeof(int) * (size_t)*r);
  return AP_OK;
}

/* |f| of the best minor of A at (t, q) and the rank there. */
static int best_at(ap_sim *s, double t, const double *q, double *f, int *r) {
  ap_drv_lrank *lr = s->lr;
  int rc = position_at(s, t, q);
  if (rc != AP_OK) return rc;
  rc = choose(s, r, lr->brows, lr->bcols);
  *f = rc == AP_OK ? fabs(minor_ratio(lr, s->d->A, s->m->b, *r, lr->brows, lr->bcols)) : 0.0;
  return rc;
}

/* The run stops at t, the watched minor's LU (at t) naming the rows: A's best minor of the
 * rank it had is f of its size there (0: the rank fell), f_before before. */
static int lost_rank(ap_sim *s, double t, double f, double f_before) {
  char rows[256];
  name_rows(s->m, s->lr, rows, sizeof rows);
  return ap_drv_fail(s, AP_ERR_RANK, "system '%s': constraint rows %s lose rank at t = %.17g "
                     "(a bifurcation of the loop): A's best minor of rank %d is %.3g of its "
                     "size there (%.3g before; rank_rtol %.3g), where several motions cross and "
                     "no mode can say which one the model takes", s->m->name, rows, t,
                     s->lr->r, f, f_before, s->def.rank_rtol);
}

/* q of the dense output of the last step at t into lr->yd. */
static int dense_q(ap_sim *s, double t) {
  int rc = s->dae ? ap_dae_dky(s->dae, t, s->lr->yd) : ap_step_dky(s->st, t, s->lr->yd);
  if (rc != AP_OK)
    return ap_drv_fail(s, rc, "loop rank: %s", s->dae ? ap_dae_message(s->dae)
                                                      : ap_step_message(s->st));
  return AP_OK;
}

/* The watched minor's f at time t of the dense output. */
static int f_dense(ap_sim *s, double t, double *f) {
  ap_drv_lrank *lr = s->lr;
  int rc = dense_q(s, t);
  if (rc == AP_OK) rc = position_at(s, t, lr->yd);
  *f = rc == AP_OK ? minor_ratio(lr, s->d->A, s->m->b, lr->r, lr->rows, lr->cols) : 0.0;
  return rc;
}

static int f_root(void *ctx, double t, double *f) { return f_dense(ctx, t, f); }

/* The watched minor changed sign between (ta, fa) and the step's end (tb, fb), y: its root t*
 * on the dense output (root.c); A lost a rank there when its best minor at t* is
 * of lower rank or below LR_DROP of the best at the step's ends (stop), else the minor alone
 * was singular (AP_OK; the caller chooses a new one). */
static int judge_crossing(ap_sim *s, double ta, double fa, double tb, double fb,
                          const double *y) {
  ap_drv_lrank *lr = s->lr;
  double qa = 0.0, qb = 0.0, qm = 0.0, t0 = ta;
  int ra = 0, rb = 0, rm = 0;
  int rc = best_at(s, tb, y, &qb, &rb);
  if (rc == AP_OK) rc = dense_q(s, ta);
  if (rc == AP_OK) rc = best_at(s, ta, lr->yd, &qa, &ra);
  if (rc == AP_OK)   /* f's sign with 0 negative: the stage's test (f > 0) != (f_prev > 0) */
    rc = ap_drv_root_locate(f_root, s, fa > 0 ? 1 : -1, AP_ROOT_ZERO_NEGATIVE, LR_ITER, ta, fa,
                            tb, fb, &tb);
  if (rc == AP_OK && tb > t0) rc = dense_q(s, tb);
  if (rc == AP_OK) rc = best_at(s, tb, tb > t0 ? lr->yd : y, &qm, &rm);
  if (rc < 0) return rc;
  if (rc != AP_OK) return AP_OK;   /* not evaluable: the mode's own stages report it */
  if (rm >= lr->r && !(qm < LR_DROP * fmax(qa, qb))) return AP_OK;
  minor_ratio(lr, s->d->A, s->m->b, lr->r, lr->rows, lr->cols);   /* its LU at t* */
  return lost_rank(s, tb, rm < lr->r ? 0.0 : qm, fmax(qa, qb));
}

static long count(const ap_data *d) {
  return d->cnt.position + d->cnt.velocity + d->cnt.acceleration + d->cnt.partitions;
}

/* The position stage at the accepted state (t, y) in the mode's basis: the mode's own stage
 * takes it (ap_drv_loop_rank_held) instead of making it again. */
static int position_here(ap_sim *s, double t, const double *y) {
  ap_drv_load_state(s, t, y);
  int rc = ap_fwd_position(s->m, s->d);
  s->lr->held = rc == AP_OK ? count(s->d) : -1, s->lr->held_t = t;
  return rc;
}

int ap_drv_loop_rank_held(const ap_sim *s, double t, const double *y) {
  const ap_data *d = s->d;
  return s->lr && s->lr->held == count(d) && s->lr->held_t == t && d->t == t &&
         memcmp(d->q, y, sizeof(double) * (size_t)s->n) == 0;
}

/* The level of A's best minor (relative to its first value) below which a run cannot tell a
 * crossing of the singular configuration from a passage beside it. Near a simple bifurcation
 * point the loops read phi = x y in the kernel's coordinates (the quadratic normal form), and
 * a state whose loops are open by e (relative to the length scale) lies on x y = e, where the
 * Jacobian (y, x) keeps a norm of at least 2 sqrt(e): such a run passes a crossing at a best
 * minor of about sqrt(e), and a passage beside the crossing looks the same. So the level is
 * LR_NEAR sqrt(e), e = max |phi_r| / lscale over the loop rows at the state (plain mode's drift
 * opens them, the other modes close them), never below sqrt(rank_rtol), the level of a drop
 * itself. Measured at the passages of campaign seeds 1003433 and 1008416 (rtol 1e-8): the
 * least best minor was 0.4 to 4.1 sqrt(e), for e from 2e-13 (explicit, projected) to 1.4e-8
 * (plain bdf). Evaluated only where the watched minor is below LR_RESELECT of its own or
 * of the first minor's value. */
#define LR_NEAR 10.0

static double near(ap_sim *s) {
  const ap_model *m = s->m;
  int nl = m->nhol < m->nphi ? m->nhol : m->nphi;   /* the loop rows come first in phi */
  double e = 0.0;
  double *scratch = ((ap_scratch *)s->d->internal)->ev;
  if (nl > 0 && m->ev.phi && m->ev.phi(m, s->d, scratch, s->phi, NULL) == AP_OK)
    for (int r = 0; r < nl; r++) e = fmax(e, fabs(s->phi[r]) / m->lscale);
  return fmin(LR_RESELECT, fmax(sqrt(s->def.rank_rtol), LR_NEAR * sqrt(e)));
}

/* The run passed closest to a rank drop at lr->near_t, with A's best minor lr->near_f (of its
 * size) there, below near(): it stops, naming the watched minor's rows at t. */
static int passed_near(ap_sim *s, double t) {
  ap_drv_lrank *lr = s->lr;
  char rows[256];
  minor_ratio(lr, s->d->A, s->m->b, lr->r, lr->rows, lr->cols);
  name_rows(s->m, lr, rows, sizeof rows);
  return ap_drv_fail(s, AP_ERR_RANK, "system '%s': constraint rows %s lose rank at t = %.17g "
                     "(a bifurcation of the loop): A's best minor of rank %d falls to %.3g of "
                     "its first value there, below %.3g (10 sqrt of the loops' gap, at least "
                     "sqrt(rank_rtol)), where a run at this tolerance cannot tell a crossing of "
                     "the singular configuration from a passage beside it, and no mode can say "
                     "which motion the model takes (noticed at t = %.17g)", s->m->name, rows,
                     lr->near_t, lr->r, lr->near_f / lr->q_ref, lr->near_lev, t);
}

/* A's best minor fr (rank r) at t, a new minor chosen there: stop where the rank fell, or once
 * a passage below near() has passed its least value (the best minor no longer falls); a
 * crossing within the next step is located by the watched minor's sign (judge_crossing). */
static int judge_best(ap_sim *s, double t, int r, double fr) {
  ap_drv_lrank *lr = s->lr;
  if (r < lr->r) {   /* at the drop */
    minor_ratio(lr, s->d->A, s->m->b, lr->r, lr->rows, lr->cols);
    return lost_rank(s, t, 0.0, fabs(lr->f_sel));
  }
  if (lr->near_f > 0 && !(fr < lr->near_f)) return passed_near(s, t);
  double lev = near(s);
  if (fr < lev * lr->q_ref) lr->near_t = t, lr->near_f = fr, lr->near_lev = lev;
  return AP_OK;
}

/* The stage: after each accepted step, before the mode's own stages (their restarts would end
 * the dense output that a crossing is located on). */
int ap_drv_stage_loop_rank(ap_sim *s, double *tp) {
  ap_drv_lrank *lr = s->lr;
  double t = *tp;
  const double *y = s->dae ? s->ytry : s->y;
  int b = s->m->b, r = lr->r, rc = ap_drv_evaluated_at(s, t, y) ? AP_OK : position_here(s, t, y);
  if (rc != AP_OK || r == 0) return rc < 0 ? rc : AP_OK;   /* the mode's stages report it */
  double f = minor_ratio(lr, s->d->A, b, r, lr->rows, lr->cols);
  if (f == 0.0 || (f > 0) != (lr->f_prev > 0)) {
    rc = judge_crossing(s, lr->t_prev, lr->f_prev, t, f, y);
    if (rc == AP_OK) rc = position_at(s, t, y);
    if (rc != AP_OK) return rc < 0 || rc == AP_ERR_RANK ? rc : AP_OK;
  } else if (!(fabs(f) < LR_RESELECT * fabs(lr->f_sel)) &&
             !(fabs(f) < LR_RESELECT * lr->q_ref) && lr->near_f == 0) {
    lr->f_prev = f, lr->t_prev = t;
    return AP_OK;
  }
  rc = choose(s, &r, lr->brows, lr->bcols);   /* a new minor at t */
  if (rc != AP_OK) return rc;
  double fr = fabs(minor_ratio(lr, s->d->A, b, r, lr->brows, lr->bcols));
  if ((rc = judge_best(s, t, r, fr)) != AP_OK) return rc;
  lr->r = r;
  memcpy(lr->rows, lr->brows, sizeof(int) * (size_t)r);
  memcpy(lr->cols, lr->bcols, sizeof(int) * (size_t)r);
  lr->f_sel = lr->f_prev = minor_ratio(lr, s->d->A, b, r, lr->rows, lr->cols);
  lr->t_prev = t;
  return AP_OK;
}

/* At creation: the rank of A a moment along the motion, at (t0 + tau, q0 + tau N v0) with tau
 * 1e-6 of the time scale max(1 s, |t0|), must be the rank at t0. A rank that changes at the
 * initial state is a singular configuration where the modes part at once (campaign seed
 * 1003091: a slider driven from offset 0 makes a loop's rows vanish at t = 0 only; minimal
 * mode stopped at its first step, the other modes ran): refused at creation, alike in every
 * mode. Off the manifold by tau^2, rows redundant only on it stay below rank_rtol. */
/* The rank of the current A with pivoted QR's relative test and the absolute floor of
 * ap_core_refuse_vanishing_rows: at most the number of rows above rank_rtol times m->lscale. */
static int floored_rank(ap_sim *s, int r) {
  const ap_model *m = s->m;
  int live = 0;
  for (int i = 0; i < m->b; i++) {
    double sq = 0.0;
    for (int c = 0; c < m->k; c++) sq += s->d->A[i + (size_t)c * m->b] * s->d->A[i + (size_t)c * m->b];
    live += sqrt(sq) > s->def.rank_rtol * m->lscale;
  }
  return r < live ? r : live;
}

static int rank_along(ap_sim *s, int r0) {
  ap_drv_lrank *lr = s->lr;
  const ap_data *d = s->d;
  int n = s->n, k = s->k, r1 = 0;
  double tau = 1e-6 * fmax(1.0, fabs(s->t)), *q1 = lr->yd;
  for (int i = 0; i < n; i++) {
    double dq = 0.0;
    for (int c = 0; c < k; c++) dq += d->N[i + (size_t)c * n] * s->v[c];
    q1[i] = s->y[i] + tau * dq;
  }
  int rc = position_at(s, s->t + tau, q1);
  if (rc == AP_OK) rc = choose(s, &r1, lr->brows, lr->bcols);
  if (rc != AP_OK || floored_rank(s, r1) == r0) return rc < 0 ? rc : AP_OK;
  r1 = floored_rank(s, r1);
  char rows[256] = "";
  size_t used = 0;
  for (int i = 0; i < r1 && used + 40 < sizeof rows; i++) {
    int seen = 0;
    for (int j = 0; j < r0; j++) seen |= lr->rows[j] == lr->brows[i];
    int len = seen ? 0 : snprintf(rows + used, sizeof rows - used, "%s'%s'", used ? ", " : "",
                                  s->m->constraint_names[lr->brows[i]]);
    if (len > 0) used += (size_t)len;
  }
  return ap_drv_fail(s, AP_ERR_RANK, "system '%s': the rank of A changes at the initial state: "
                     "%d at t0 = %.17g, %d at t0 + %.3g s along the motion (constraint rows %s): "
                     "a singular configuration of the loops, where the motion is not unique; "
                     "start it elsewhere", s->m->name, r0, s->t, r1, tau,
                     r1 > r0 ? rows : "(those of the lower rank)");
}

/* At creation, at the consistent initial state (s->t, s->y): the first minor. Nothing for
 * models without implicit holonomic rows, on the tree path (it forms no A) or with contact
 * modes (their switches change A's rows). */
int ap_drv_loop_rank_init(ap_sim *s) {
  const ap_model *m = s->m;
  if (m->nhol == 0 || m->b == 0 || ap_core_st(s->d) || s->cm) return AP_OK;
  int b = m->b, k = m->k, mx = b > k ? b : k, ny = s->n + k + b + (m->ev.phi ? m->nphi : 0);
  size_t nw = ap_la_work_size(mx, mx), niw = ap_la_iwork_size(mx, mx);
  ap_drv_lrank *lr = calloc(1, sizeof *lr);
  int *ib = lr ? calloc(4 * (size_t)mx + 2 * (size_t)k + (size_t)b + (size_t)k + niw,
                        sizeof *ib) : NULL;
  double *db = ib ? calloc((size_t)mx * mx + (size_t)k * b + nw + (size_t)ny + k,
                           sizeof *db) : NULL;
  if (!db) {
    free(ib), free(lr);
    return ap_drv_fail(s, AP_ERR_NOMEM, "system '%s': out of memory", m->name);
  }
  lr->rows = ib, lr->cols = ib + mx, lr->brows = lr->cols + mx, lr->bcols = lr->brows + mx;
  lr->perm = lr->bcols + mx, lr->rperm = lr->perm + k, lr->ipiv = lr->rperm + b;
  lr->iwork = lr->ipiv + k;
  lr->M = db, lr->AT = db + (size_t)mx * mx, lr->work = lr->AT + (size_t)k * b;
  lr->yd = lr->work + nw, lr->null = lr->yd + ny;
  s->lr = lr;
  int rc = position_at(s, s->t, s->y);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", s->d->msg);
  rc = choose(s, &lr->r, lr->rows, lr->cols);
  if (rc != AP_OK) return rc;
  lr->f_sel = lr->f_prev = minor_ratio(lr, s->d->A, b, lr->r, lr->rows, lr->cols);
  lr->t_prev = s->t, lr->rmax = lr->r, lr->q_ref = fabs(lr->f_sel);
  rc = rank_along(s, floored_rank(s, lr->r));
  int rp = rc == AP_OK ? position_at(s, s->t, s->y) : AP_OK;   /* the data back at t0 */
  return rc != AP_OK ? rc : rp < 0 ? rp : AP_OK;
}

/* A failed step (status rc, s->msg): when A's best minor at the last accepted state is below LR_RESELECT of its value at creation, the steppers gave up close to a
 * rank drop (IDA's corrector fails there before the monitor sees the drop: campaign seed
 * 1008416 at t = 0.22380, where the minor is 5e-4 of its first value), and the failure is
 * reported as the drop, with the stepper's message after it. Else rc unchanged. */
int ap_drv_loop_rank_failed(ap_sim *s, int rc) {
  ap_drv_lrank *lr = s->lr;
  if (!lr || lr->r == 0 || (rc != AP_ERR_SOLVER && rc != AP_ERR_SINGULAR && rc != AP_ERR_NAN))
    return rc;
  double t = s->t, f = 0.0;   /* the last accepted state */
  int r = 0;
  memcpy(lr->yd, s->y, sizeof(double) * (size_t)s->n);
  if (best_at(s, t, lr->yd, &f, &r) != AP_OK || (r >= lr->r && !(f < LR_RESELECT * lr->q_ref)))
    return rc;
  char rows[256], was[sizeof s->msg];
  memcpy(was, s->msg, sizeof was);
  minor_ratio(lr, s->d->A, s->m->b, lr->r, lr->rows, lr->cols);
  name_rows(s->m, lr, rows, sizeof rows);
  return ap_drv_fail(s, AP_ERR_RANK, "system '%s': constraint rows %s lose rank at t = %.17g "
                     "(a bifurcation of the loop): A's best minor of rank %d is %.3g of its "
                     "first size there, and the next step failed (%.200s)", s->m->name, rows, t,
                     lr->r, r < lr->r ? 0.0 : f / lr->q_ref, was);
}

void ap_drv_loop_rank_free(ap_sim *s) {
  if (!s->lr) return;
  free(s->lr->rows);
  free(s->lr->M);
  free(s->lr);
  s->lr = NULL;
}
