/* The Appell solve: from (t, q, v or e') to e'', v', q' (and the multipliers on request).
 *
 * DESIGN.md §1: with a basis B of the null space of A (A B = 0), b0 (A b0 = -a0) and
 * w (A w = gamma), the speeds are v = B e' + b0, and Appell's equations in covariant form are
 *
 *     G e'' = Phi - B^T (h + g w),    G = B^T g B,   Phi = B^T Q,    v' = B e'' + w.
 *
 * The stages run in a fixed order (ap_forward): position (g, N, A, a0, basis), velocity
 * (v, h, Q, gamma, w), acceleration (G, Phi, Cholesky, e'', v', q'), then reactions if asked
 * (A^T lambda = g v' + h - Q). Stages that nothing needs are skipped: no constraints means no
 * QR and B = I; no force callback means Q = 0. Nothing here allocates. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/core.h"
#include "linalg/linalg.h"

#define SCRATCH(d) ((ap_scratch *)(d)->internal)  /* first member of the data block */

/* Relative size beyond which a redundant constraint row is called inconsistent when the
 * redundancy holds for every q (structural: the residual is round-off) and the rows are judged
 * at every evaluation. Redundancy that holds only on the manifold of the implicit holonomic
 * rows (loops, wheel contacts) is judged against d->manifold_rtol at accepted states instead:
 * a stepper's trial states lie off that manifold by O(h^2), and there the dropped rows are
 * neither dependent nor consistent (least squares over all rows keeps the solve smooth). */
static const double consistency_rtol = 1e-8;

/* ---- messages and checks ---------------------------------------------------------------- */

int ap_core_callback_status(const ap_model *m, ap_data *d, const char *what, int rc) {
  if (rc == 0) return AP_OK;
  if (rc > 0) {
    ap_core_msg(d, "system '%s': callback '%s' asked for a smaller step (returned %d) at "
                "t = %.17g", m->name, what, rc, d->t);
    return AP_RECOVERABLE;
  }
  ap_core_msg(d, "system '%s': callback '%s' failed (returned %d) at t = %.17g", m->name,
              what, rc, d->t);
  return AP_ERR_CALLBACK;
}

int ap_core_check_finite(const ap_model *m, ap_data *d, const char *what, const double *x,
                         int rows, int cols) {
  double z = 0.0, mx = 0.0;            /* x * 0 is 0, or NaN when x is Inf or NaN: one pass */
  for (size_t i = 0, len = (size_t)rows * (size_t)cols; i < len; i++) {
    double a = fabs(x[i]);
    z += x[i] * 0.0, mx = a > mx ? a : mx;   /* and the magnitude (AP_HUGE) */
  }
  if (z == 0.0 && mx <= AP_HUGE) return AP_OK;
  for (int j = 0; j < cols; j++)
    for (int i = 0; i < rows; i++) {
      double xi = x[i + (size_t)j * rows];
      if (fabs(xi) <= AP_HUGE) continue;
      const char *why = isfinite(xi) ? " (more than 1e150 in magnitude: too large to integrate)"
                                     : "";
      if (cols == 1)
        ap_core_msg(d, "system '%s': callback '%s' produced %g in entry %d at t = %.17g%s",
                    m->name, what, xi, i, d->t, why);
      else
        ap_core_msg(d, "system '%s': callback '%s' produced %g in entry (%d, %d) at "
                    "t = %.17g%s", m->name, what, xi, i, j, d->t, why);
      return AP_ERR_NAN;
    }
  return AP_OK;
}

/* Zero out, call, then check: the pattern every callback goes through. */
#define CALL(name, out, rows, cols, expr)                                                  \
  do {                                                                                     \
    memset((out), 0, sizeof(double) * (size_t)(rows) * (size_t)(cols));                   \
    d->cnt.name++;                                                                         \
    int rc_ = ap_core_callback_status(m, d, #name, (expr));                               \
    if (rc_ != AP_OK) return rc_;                                                          \
    rc_ = ap_core_check_finite(m, d, #name, (out), (rows), (cols));                        \
    if (rc_ != AP_OK) return rc_;                                                          \
  } while (0)

static double max_abs(const double *x, size_t len) {
  double mx = 0.0;
  for (size_t i = 0; i < len; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

/* Names of the constraint rows a pivoted QR of A^T puts after the rank: the redundant ones. */
static void name_redundant(const ap_model *m, ap_data *d, const int *jpvt, int r,
                           const char *verdict, double resid) {
  char rows[256] = "";
  size_t used = 0;
  for (int s = r; s < m->b && used + 40 < sizeof rows; s++) {
    int len = snprintf(rows + used, sizeof rows - used, "%s'%s'", s > r ? ", " : "",
                       m->constraint_names[jpvt[s]]);
    if (len > 0) used += (size_t)len;
  }
  ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant (%s) at t = %.17g: %s "
              "is a combination of the others; residual %.3g", m->name, m->b - r, m->b,
              verdict, d->t, rows, resid);
}

/* The dropped rows that contradict the kept ones, each with its own residual: from the pivoted
 * QR A^T P = Q R of ap_la_orth_basis (R in the upper triangle of F, ld k), dropped row j is the
 * combination c = R11^-1 R12[:, j] of the kept rows, and x_j - c . x_kept is its disagreement
 * (x = a0 or gamma). Rows within tol are listed as consistent. work: b doubles. */
static int name_inconsistent(const ap_model *m, ap_data *d, const double *F, const int *jpvt,
                             int r, const double *x, double tol, const char *what,
                             double *work) {
  int k = m->k, nbad = 0;
  char bad[320] = "";
  size_t used = 0;
  for (int j = r; j < m->b; j++) {
    double *c = work, res = x[jpvt[j]];
    for (int i = r - 1; i >= 0; i--) {   /* R11 c = R12[:, j] */
      double t = F[i + (size_t)j * k];
      for (int l = i + 1; l < r; l++) t -= F[i + (size_t)l * k] * c[l];
      c[i] = t / F[i + (size_t)i * k];
    }
    for (int i = 0; i < r; i++) res -= c[i] * x[jpvt[i]];
    if (!(fabs(res) > tol)) continue;
    nbad++;
    if (used + 60 >= sizeof bad) continue;
    int len = snprintf(bad + used, sizeof bad - used, "%s'%s' (by %.3g)", used ? ", " : "",
                       m->constraint_names[jpvt[j]], res);
    if (len > 0) used += (size_t)len;
  }
  if (nbad)
    ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant and %d of them "
                "inconsistent at t = %.17g: %s disagree%s with the combination of the others "
                "(%s)", m->name, m->b - r, m->b, nbad, d->t, bad, nbad == 1 ? "s" : "", what);
  return nbad;
}

/* ---- partition ---------------------------------------------------------------------------- */

static int position_callbacks(const ap_model *m, ap_data *d);
static int position_evaluator(const ap_model *m, ap_data *d);

static int position_any(const ap_model *m, ap_data *d) {
  return m->ev.position ? position_evaluator(m, d) : position_callbacks(m, d);
}

/* Rank of A at a nearby state q + eps N xi off the holonomic manifold (xi a fixed spread of
 * directions, eps 1e-6 of the size of q): redundancy that holds for every q survives there,
 * redundancy of the manifold does not. The position stage at q is restored (d->perm is
 * overwritten). Returns the rank, -1 when the nearby state cannot be evaluated, -2 when q
 * cannot. */
static int nearby_rank(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int n = m->n, k = m->k, r = -1;
  double qmax = fmax(1.0, max_abs(d->q, (size_t)n)), step = 0.0;
  for (int c = 0; c < k; c++) s->tk1[c] = sin(1.3 + 2.1 * c);
  ap_la_gemv(n, k, d->N, s->tk1, s->tn);   /* tn = N xi */
  step = max_abs(s->tn, (size_t)n);
  if (!(step > 0)) return -1;
  for (int i = 0; i < n; i++) {
    double qi = d->q[i];
    d->q[i] += 1e-6 * qmax / step * s->tn[i];
    s->tn[i] = qi;
  }
  if (position_any(m, d) == AP_OK &&
      ap_la_pivot_select(m->b, k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork) != AP_OK)
    r = -1;
  memcpy(d->q, s->tn, sizeof(double) * (size_t)n);
  if (position_any(m, d) != AP_OK) return -2;
  return r;
}

int ap_partition(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  d->cnt.partitions++;
  if (m->b == 0) {
    d->rank = 0, d->l = m->k;
    for (int i = 0; i < m->k; i++) d->perm[i] = i;
    return AP_OK;
  }
  int rc = position_any(m, d);
  if (rc != AP_OK) return rc;
  int r = 0;
  rc = ap_la_pivot_select(m->b, m->k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': pivoted QR of A failed at t = %.17g", m->name, d->t);
    return rc;
  }
  d->rank = r, d->l = m->k - r, d->redundant = m->b - r, d->redundant_manifold = 0;
  if (r == m->b) return AP_OK;
  if (m->nhol > 0) {   /* structural or of the manifold? */
    int rn = nearby_rank(m, d);
    if (rn == -2) return AP_ERR_INTERNAL;   /* the state itself evaluated a moment ago */
    d->redundant_manifold = rn > r ? rn - r : 0;
    rc = ap_la_pivot_select(m->b, m->k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork);
    if (rc != AP_OK) return rc;
  }
  /* Which rows are redundant, and are they consistent? The row-pivoted QR of A^T says. */
  double resid = 0.0;
  int rr = 0;
  rc = ap_la_orth_basis(m->b, m->k, d->A, d->a0, d->rank_rtol, &rr, s->F, s->tau, s->jpvt,
                        s->Qf, s->gB, s->tk1, &resid, s->work, s->iwork);
  if (rc != AP_OK) return rc;
  double scale = fmax(1.0, fmax(max_abs(d->a0, (size_t)m->b), max_abs(d->A,
                                                                       (size_t)m->b * m->k)));
  double tol = d->redundant_manifold ? d->manifold_rtol : consistency_rtol;
  if (resid > tol * scale) {
    name_inconsistent(m, d, s->F, s->jpvt, rr, d->a0, tol * scale, "the free terms a0",
                      s->work);
    return AP_ERR_INCONSISTENT;
  }
  name_redundant(m, d, s->jpvt, rr, !d->redundant_manifold ? "consistent, dropped"
                 : d->redundant_manifold == d->redundant ? "consistent, dropped; only where "
                 "the loops and contacts close" : "consistent, dropped; some only where the "
                 "loops and contacts close", resid);
  return AP_OK;
}

/* ---- position stage ---------------------------------------------------------------------- */

static int basis_partitioned(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  double resid = 0.0;
  double *rcond = d->estimate_cond ? &d->rcond_R : NULL;   /* not in the hot path */
  if (!rcond) d->rcond_R = 1.0;
  int rc = ap_la_partition_basis(m->b, m->k, d->rank, d->perm, d->A, d->a0, s->F, s->tau,
                                 d->B, d->b0, &d->growth, rcond, &resid, s->work, s->iwork);
  d->cnt.qr++;
  d->resid_a0 = resid;
  if (rc != AP_OK || d->rcond_R < 1e-14) {
    ap_core_msg(d, "system '%s': the dependent-speed block R11 of the partition is singular "
                "to working precision at t = %.17g: re-partition needed", m->name, d->t);
    return AP_RECOVERABLE;
  }
  return AP_OK;
}

/* The rank is decided here at every evaluation, except when some rows are redundant only on
 * the holonomic manifold: then the rank of ap_partition is kept (off the manifold those rows
 * look independent, and a rank that rose at a trial state would lose a free speed). */
static int basis_orthonormal(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int r = d->rank;
  double resid = 0.0, rtol = d->redundant_manifold ? -1.0 : d->rank_rtol;
  int rc = ap_la_orth_basis(m->b, m->k, d->A, d->a0, rtol, &r, s->F, s->tau, s->jpvt, s->Qf,
                            d->B, d->b0, &resid, s->work, s->iwork);
  d->cnt.qr++;
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': QR of A^T failed at t = %.17g", m->name, d->t);
    return rc;
  }
  d->rank = r, d->l = m->k - r, d->resid_a0 = resid, d->growth = 1.0, d->rcond_R = 1.0;
  return AP_OK;
}

/* g, N, A, a0 from the user's callbacks. */
static int position_callbacks(const ap_model *m, ap_data *d) {
  CALL(metric, d->g, m->k, m->k, m->sys.metric(d->t, d->q, d->g, m->sys.user));
  if (m->sys.kinematic)
    CALL(kinematic, d->N, m->n, m->k, m->sys.kinematic(d->t, d->q, d->N, m->sys.user));
  if (m->b == 0) return AP_OK;
  memset(d->a0, 0, sizeof(double) * (size_t)m->b);
  CALL(constraint, d->A, m->b, m->k, m->sys.constraint(d->t, d->q, d->A, d->a0, m->sys.user));
  return ap_core_check_finite(m, d, "constraint (a0)", d->a0, m->b, 1);
}

/* g, N, A, a0 from a compiled evaluator (body models). N is rewritten only when the model has
 * its own kinematics; otherwise it stays the identity written by ap_data_create. */
static int position_evaluator(const ap_model *m, ap_data *d) {
  size_t kk = (size_t)m->k * m->k;
  memset(d->g, 0, sizeof(double) * kk);
  if (m->n != m->k || m->sys.kinematic) memset(d->N, 0, sizeof(double) * (size_t)m->n * m->k);
  memset(d->A, 0, sizeof(double) * (size_t)m->b * m->k);
  memset(d->a0, 0, sizeof(double) * (size_t)m->b);
  int rc = m->ev.position(m, d, SCRATCH(d)->ev);
  if (rc != AP_OK) return rc;
  rc = ap_core_check_finite(m, d, "metric", d->g, m->k, m->k);
  if (rc == AP_OK) rc = ap_core_check_finite(m, d, "constraint", d->A, m->b, m->k);
  if (rc == AP_OK) rc = ap_core_check_finite(m, d, "constraint (a0)", d->a0, m->b, 1);
  return rc;
}

int ap_fwd_position(const ap_model *m, ap_data *d) {
  d->cnt.position++;
  int rc = m->ev.position ? position_evaluator(m, d) : position_callbacks(m, d);
  if (rc != AP_OK || m->b == 0 || d->basis == AP_BASIS_NONE) return rc;  /* b == 0: B = I */
  rc = d->basis == AP_BASIS_ORTHONORMAL ? basis_orthonormal(m, d) : basis_partitioned(m, d);
  if (rc != AP_OK || d->redundant_manifold) return rc;   /* judged at accepted states */
  double scale = fmax(1.0, max_abs(d->a0, (size_t)m->b));
  if (d->resid_a0 > consistency_rtol * scale) {
    ap_core_msg(d, "system '%s': redundant constraint rows became inconsistent at "
                "t = %.17g (a0 residual %.3g)", m->name, d->t, d->resid_a0);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}

/* Rows redundant only on the holonomic manifold, at an accepted state (core.h). The residuals
 * scale like the distance from the manifold: relative to the largest entry of A, a0 (resp.
 * gamma). Which rows: the row-pivoted QR of A^T names them (as ap_partition). */
int ap_core_judge_redundant(const ap_model *m, ap_data *d) {
  if (!d->redundant_manifold) return AP_OK;
  ap_scratch *s = SCRATCH(d);
  double sa = fmax(1.0, fmax(max_abs(d->a0, (size_t)m->b), max_abs(d->A, (size_t)m->b * m->k)));
  double sg = fmax(1.0, max_abs(d->gamma, (size_t)m->b)), tol = d->manifold_rtol;
  int bad_a = d->resid_a0 > tol * sa, bad_g = !bad_a && d->resid_gamma > tol * sg;
  if (!bad_a && !bad_g) return AP_OK;
  double resid = 0.0;
  int rr = d->rank;
  if (ap_la_orth_basis(m->b, m->k, d->A, d->a0, -1.0, &rr, s->F, s->tau, s->jpvt, s->Qf, s->gB,
                       s->tk1, &resid, s->work, s->iwork) != AP_OK)
    return AP_ERR_INCONSISTENT;
  if (!name_inconsistent(m, d, s->F, s->jpvt, rr, bad_a ? d->a0 : d->gamma,
                         tol * (bad_a ? sa : sg), bad_a ? "the free terms a0" : "gamma",
                         s->work)) {
    char verdict[160];
    snprintf(verdict, sizeof verdict, "inconsistent along the motion: %s by %.3g relative, "
             "more than manifold_rtol %.3g", bad_a ? "the rows drifted apart" : "gamma",
             bad_a ? d->resid_a0 / sa : d->resid_gamma / sg, tol);
    name_redundant(m, d, s->jpvt, rr, verdict, bad_a ? d->resid_a0 : d->resid_gamma);
  }
  return AP_ERR_INCONSISTENT;
}

/* ---- velocity stage ---------------------------------------------------------------------- */

/* h_a = sum_c v^c (dg_c v)_a - 1/2 v^T dg_a v: the Christoffel terms of Lagrange's equations
 * when v = q' (the covariant form of the founding paper). */
static void christoffel_bias(int k, const double *dg, const double *v, double *h, double *tmp) {
  for (int a = 0; a < k; a++) h[a] = 0.0;
  for (int c = 0; c < k; c++) {
    const double *dgc = dg + (size_t)c * k * k;
    ap_la_gemv(k, k, dgc, v, tmp);                /* tmp = dg_c v */
    double vdgv = 0.0;
    for (int a = 0; a < k; a++) {
      h[a] += v[c] * tmp[a];
      vdgv += v[a] * tmp[a];
    }
    h[c] -= 0.5 * vdgv;
  }
}

static int particular(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int rc;
  if (d->basis == AP_BASIS_ORTHONORMAL)
    rc = ap_la_orth_particular(m->b, m->k, d->rank, s->F, s->jpvt, s->Qf, d->gamma, d->w,
                               &d->resid_gamma, s->work);
  else
    rc = ap_la_partition_particular(m->b, m->k, d->rank, d->perm, s->F, s->tau, d->gamma,
                                    d->w, &d->resid_gamma, s->work);
  if (rc != AP_OK || d->redundant_manifold) return rc;   /* judged at accepted states */
  double scale = fmax(1.0, max_abs(d->gamma, (size_t)m->b));
  if (d->resid_gamma > consistency_rtol * scale) {
    ap_core_msg(d, "system '%s': redundant constraint rows have inconsistent gamma at "
                "t = %.17g (residual %.3g)", m->name, d->t, d->resid_gamma);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}

void ap_core_speeds(const ap_model *m, ap_data *d) {
  ap_la_gemv(m->k, d->l, d->B, d->e, d->v);     /* v = B e' + b0 */
  for (int i = 0; i < m->k; i++) d->v[i] += d->b0[i];
}

int ap_fwd_velocity(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k;
  d->cnt.velocity++;
  if (d->speeds_from_e && d->basis == AP_BASIS_PARTITIONED) ap_core_speeds(m, d);
  if (m->ev.velocity) {
    memset(d->h, 0, sizeof(double) * (size_t)k);
    memset(d->Q, 0, sizeof(double) * (size_t)k);
    memset(d->gamma, 0, sizeof(double) * (size_t)m->b);
    int rc = m->ev.velocity(m, d, s->ev);
    if (rc == AP_OK) rc = ap_core_check_finite(m, d, "bias", d->h, k, 1);
    if (rc == AP_OK) rc = ap_core_check_finite(m, d, "force", d->Q, k, 1);
    if (rc == AP_OK) rc = ap_core_check_finite(m, d, "gamma", d->gamma, m->b, 1);
    if (rc != AP_OK) return rc;
    return m->b == 0 || d->basis == AP_BASIS_NONE ? AP_OK : particular(m, d);
  }
  switch (m->sys.bias_source) {
    case AP_BIAS_CALLBACK:
      CALL(bias, d->h, k, 1, m->sys.bias(d->t, d->q, d->v, d->h, m->sys.user));
      break;
    case AP_BIAS_CHRISTOFFEL:
      CALL(bias, s->dg, k * k, m->n, m->sys.metric_deriv(d->t, d->q, s->dg, m->sys.user));
      christoffel_bias(k, s->dg, d->v, d->h, s->tk1);
      break;
    case AP_BIAS_ZERO:
      break;   /* h stays zero from ap_data_create */
  }
  if (m->sys.force) CALL(force, d->Q, k, 1, m->sys.force(d->t, d->q, d->v, d->Q, m->sys.user));
  if (m->b == 0 || d->basis == AP_BASIS_NONE) return AP_OK;   /* w = 0, or not needed */
  CALL(gamma, d->gamma, m->b, 1, m->sys.gamma(d->t, d->q, d->v, d->gamma, m->sys.user));
  return particular(m, d);
}

/* ---- acceleration stage ------------------------------------------------------------------- */

int ap_fwd_acceleration(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l;
  d->cnt.acceleration++;
  /* tk2 = Q - h - g w ; Phi = B^T Q ; edd = B^T tk2 (the right-hand side) */
  ap_la_gemv(k, k, d->g, d->w, s->tk1);
  for (int i = 0; i < k; i++) s->tk2[i] = d->Q[i] - d->h[i] - s->tk1[i];
  if (m->b == 0) {
    memcpy(d->G, d->g, sizeof(double) * (size_t)k * k);
    memcpy(d->Phi, d->Q, sizeof(double) * (size_t)k);
    memcpy(d->edd, s->tk2, sizeof(double) * (size_t)k);
  } else {
    ap_la_congruence(k, l, d->g, d->B, d->G, s->gB);
    ap_la_gemv_t(k, l, d->B, d->Q, d->Phi);
    ap_la_gemv_t(k, l, d->B, s->tk2, d->edd);
  }
  double *rcond = d->estimate_cond ? &d->rcond_G : NULL;   /* not in the hot path */
  if (!rcond) d->rcond_G = 1.0;
  int rc = ap_la_chol(l, d->G, rcond, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': G = B^T g B (%d x %d) is not positive definite at "
                "t = %.17g: the metric g is not positive definite on the free speeds",
                m->name, l, l, d->t);
    return AP_ERR_SINGULAR;
  }
  ap_la_chol_solve(l, d->G, d->edd);
  rc = ap_core_check_finite(m, d, "Appell solve (e'')", d->edd, l, 1);
  if (rc != AP_OK) return rc;
  if (m->b == 0) memcpy(d->vdot, d->edd, sizeof(double) * (size_t)k);
  else {
    ap_la_gemv(k, l, d->B, d->edd, d->vdot);     /* v' = B e'' + w */
    for (int i = 0; i < k; i++) d->vdot[i] += d->w[i];
  }
  ap_la_gemv(m->n, k, d->N, d->v, d->qdot);      /* q' = N v */
  return AP_OK;
}

/* ---- optional stages ---------------------------------------------------------------------- */

int ap_fwd_reactions(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k;
  d->cnt.reactions++;
  if (m->b == 0) return AP_OK;
  ap_la_gemv(k, k, d->g, d->vdot, s->tk1);       /* tk1 = g v' + h - Q */
  for (int i = 0; i < k; i++) s->tk1[i] += d->h[i] - d->Q[i];
  double resid = 0.0;
  int rc = ap_la_lstsq_At(m->b, k, d->A, s->tk1, d->rank_rtol, d->lambda, &resid, s->work,
                          s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': reaction solve A^T lambda = g v' + h - Q failed at "
                "t = %.17g", m->name, d->t);
    return rc;
  }
  return AP_OK;
}

int ap_forward(const ap_model *m, ap_data *d) {
  d->cnt.forward++;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(m, d);
  if (rc == AP_OK) rc = ap_fwd_acceleration(m, d);
  if (rc == AP_OK && d->want_reactions) rc = ap_fwd_reactions(m, d);
  return rc;
}

/* ---- projection and diagnostics ---------------------------------------------------------- */

int ap_project_speeds(const ap_model *m, ap_data *d, double *v, double *change) {
  int rc = ap_fwd_position(m, d);
  return rc == AP_OK ? ap_core_project_here(m, d, v, change) : rc;
}

/* a + sum x_i y_i with the products' and the sums' rounding errors carried along (fma and
 * Neumaier's compensation): the result is as accurate as if computed in twice the precision,
 * then rounded. A constraint residual is a small difference of large terms. */
static double dot_compensated(int len, const double *x, int incx, const double *y, double a,
                              double *mag) {
  double sum = a, c = 0.0, m = fabs(a);
  for (int i = 0; i < len; i++) {
    double p = x[(size_t)i * incx] * y[i], pe = fma(x[(size_t)i * incx], y[i], -p);
    double t = sum + p;
    c += fabs(sum) >= fabs(p) ? (sum - t) + p : (p - t) + sum;
    c += pe;
    sum = t, m += fabs(p);
  }
  if (mag) *mag = m;
  return sum + c;
}

/* The correction that takes v onto A v + a0 = 0, nearest in g, computed from the residual
 * r = A v + a0 alone (so a state on the constraints is not touched, and the rounding of the
 * correction is relative to the correction, not to v):
 *
 *     d0 = particular solution of A d0 = -r (the basis stage's factorization),
 *     d  = d0 - B G^-1 B^T g d0      (remove d0's g-projection onto the null space of A).
 *
 * v <- v + d. Rows whose residual is within the round-off of their own terms
 * (|r_s| <= 4 eps sum |A_sj v_j| + |a0_s|) count as satisfied; when all are, v is left as is. */
int ap_core_project_here(const ap_model *m, ap_data *d, double *v, double *change) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l, b = m->b, rc, any = 0;
  if (change) *change = 0.0;
  if (b == 0) return AP_OK;
  double *r = s->work + ap_la_work_size(b, k) - (size_t)b;  /* the last b doubles of work */
  for (int i = 0; i < b; i++) {
    double mag = 0.0;
    r[i] = -dot_compensated(k, d->A + i, b, v, d->a0[i], &mag);
    if (fabs(r[i]) > 4.0 * DBL_EPSILON * mag) any = 1;
  }
  if (!any) return AP_OK;
  double resid = 0.0;
  if (d->basis == AP_BASIS_ORTHONORMAL)
    rc = ap_la_orth_particular(b, k, d->rank, s->F, s->jpvt, s->Qf, r, s->tk1, &resid, s->work);
  else
    rc = ap_la_partition_particular(b, k, d->rank, d->perm, s->F, s->tau, r, s->tk1, &resid,
                                    s->work);
  if (rc != AP_OK) return rc;
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);                    /* tk2 = g d0 */
  ap_la_gemv_t(k, l, d->B, s->tk2, s->tl);                   /* tl = B^T g d0 */
  ap_la_congruence(k, l, d->g, d->B, d->G, s->gB);
  rc = ap_la_chol(l, d->G, NULL, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': G = B^T g B is not positive definite at t = %.17g (speed "
                "projection)", m->name, d->t);
    return AP_ERR_SINGULAR;
  }
  ap_la_chol_solve(l, d->G, s->tl);
  ap_la_gemv(k, l, d->B, s->tl, s->tk2);                     /* tk2 = B G^-1 B^T g d0 */
  for (int i = 0; i < k; i++) {
    s->tk1[i] -= s->tk2[i];                                  /* the correction d */
    v[i] += s->tk1[i];
  }
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);
  double c2 = 0.0;
  for (int i = 0; i < k; i++) c2 += s->tk1[i] * s->tk2[i];
  if (change) *change = sqrt(fmax(c2, 0.0));
  return AP_OK;
}

void ap_core_project_tangent(const ap_model *m, ap_data *d, double *x) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l;
  ap_la_gemv(k, k, d->g, x, s->tk1);                         /* tk1 = g x */
  ap_la_gemv_t(k, l, d->B, s->tk1, s->tl);                   /* tl = B^T g x */
  ap_la_chol_solve(l, d->G, s->tl);                          /* G^-1 B^T g x */
  ap_la_gemv(k, l, d->B, s->tl, x);                          /* x = B G^-1 B^T g x */
}

double ap_constraint_residual(const ap_data *d, const double *v) {
  double mx = 0.0;
  for (int s = 0; s < d->b; s++) {
    double r = d->a0[s];
    for (int j = 0; j < d->k; j++) r += d->A[s + (size_t)j * d->b] * v[j];
    mx = fmax(mx, fabs(r));
  }
  return mx;
}

double ap_kinetic_energy(const ap_data *d, const double *v) {
  double e = 0.0;
  for (int j = 0; j < d->k; j++)
    for (int i = 0; i < d->k; i++) e += v[i] * d->g[i + (size_t)j * d->k] * v[j];
  return 0.5 * e;
}
