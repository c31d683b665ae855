/* The Appell solve: from (t, q, v or e') to e'', v', q' (and the multipliers on request).
 *
 * docs/design.md §1: with a basis B of the null space of A (A B = 0), b0 (A b0 = -a0) and
 * w (A w = gamma), the speeds are v = B e' + b0, and Appell's equations in covariant form are
 *
 *     G e'' = Phi - B^T (h + g w),    G = B^T g B,   Phi = B^T Q,    v' = B e'' + w.
 *
 * The stages run in a fixed order (ap_forward): position (g, N, A, a0, basis), velocity
 * (v, h, Q, gamma, w), acceleration (G, Phi, Cholesky, e'', v', q'), then reactions if asked
 * (A^T lambda = g v' + h - Q). Stages that nothing needs are skipped: no constraints means no
 * QR and B = I; no force callback means Q = 0. Nothing here allocates.
 *
 * Generic in the scalar (linalg/scalar.h): forward_cs.c compiles this file again into
 * ap_fwd_position_cs ... ap_forward_cs on the mirror ap_data_cs (core/core.h), for exact
 * derivatives of the solve. That build runs only the body layer's evaluator (math-level
 * callbacks are functions of doubles), only the partitioned basis with the partition given
 * (copied from a double data), and no reactions. Choosing the partition (partition.c) and
 * projecting speeds (project.c) exist in the double build only. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/core.h"
#include "core/structured.h"
#include "linalg/linalg.h"

#define SCRATCH(d) ((ap_scratch *)(d)->internal)  /* first member of the data block */

/* ---- messages and checks ---------------------------------------------------------------- */

#ifndef AP_SC_COMPLEX
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
#endif

int AP_SC(ap_core_check_finite)(const ap_model *m, ap_data *d, const char *what,
                                const ap_sc *x, int rows, int cols) {
  ap_sc z = 0.0;                       /* x * 0 is 0, or NaN when x is Inf or NaN: one pass */
  double mx = 0.0;
  for (size_t i = 0, len = (size_t)rows * (size_t)cols; i < len; i++) {
    double a = SC_MAG(x[i]);
    z += x[i] * 0.0, mx = a > mx ? a : mx;   /* and the magnitude (AP_HUGE) */
  }
  if (z == 0.0 && mx <= AP_HUGE) return AP_OK;
  for (int j = 0; j < cols; j++)
    for (int i = 0; i < rows; i++) {
      ap_sc xi = x[i + (size_t)j * rows];
      if (SC_MAG(xi) <= AP_HUGE && SC_IM_FINITE(xi)) continue;
      const char *why = SC_FINITE(xi) ? " (more than 1e150 in magnitude: too large to integrate)"
                                      : "";
      if (cols == 1)
        AP_SC(ap_core_msg)(d, "system '%s': callback '%s' produced %g in entry %d at "
                           "t = %.17g%s", m->name, what, SC_RE(xi), i, d->t, why);
      else
        AP_SC(ap_core_msg)(d, "system '%s': callback '%s' produced %g in entry (%d, %d) at "
                           "t = %.17g%s", m->name, what, SC_RE(xi), i, j, d->t, why);
      return AP_ERR_NAN;
    }
  return AP_OK;
}

static double max_abs(const ap_sc *x, size_t len) {
  double mx = 0.0;
  for (size_t i = 0; i < len; i++) mx = fmax(mx, SC_MAG(x[i]));
  return mx;
}

double AP_SC(ap_core_row_scale)(const ap_model *m, const ap_data *d, int of_gamma) {
  const ap_sc *x = of_gamma ? d->gamma : d->a0, *y = of_gamma ? d->vdot : d->v;
  double mx = 0.0, fl = of_gamma ? AP_ROW_FLOOR_PER_S2 : AP_ROW_FLOOR_PER_S;
  for (int r = 0; r < m->b; r++) {   /* t_r + f_r (core.h) */
    double t = SC_MAG(x[r]);
    for (int c = 0; c < m->k; c++) {
      ap_sc a = d->A[r + (size_t)c * m->b];
      t += SC_MAG(a * y[c]) + fl * SC_MAG(a) * (m->vscale ? m->vscale[c] : 1.0);
    }
    mx = fmax(mx, t);
  }
  return AP_TERMS_TINY + mx;
}

/* ---- position stage ---------------------------------------------------------------------- */

static int basis_partitioned(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  double resid = 0.0;
  double *rcond = d->estimate_cond ? &d->rcond_R : NULL;   /* not in the hot path */
  if (!rcond) d->rcond_R = 1.0;
  int rc = AP_ERR_UNSUPPORTED;
#ifndef AP_SC_COMPLEX
  if (!rcond && m->ev.basis) rc = m->ev.basis(m, d, &resid);   /* a compiled model's */
#endif
  if (rc == AP_ERR_UNSUPPORTED)
    rc = AP_SC(ap_la_partition_basis)(m->b, m->k, d->rank, d->perm, d->A, d->a0, s->F, s->tau,
                                      d->B, d->b0, &d->growth, rcond, &resid, s->work,
                                      s->iwork);
  d->cnt.qr++;
  d->resid_a0 = resid;
  if (rc != AP_OK || d->rcond_R < 1e-14) {
    AP_SC(ap_core_msg)(d, "system '%s': the dependent-speed block R11 of the partition is "
                       "singular to working precision at t = %.17g: re-partition needed",
                       m->name, d->t);
    return AP_RECOVERABLE;
  }
  return AP_OK;
}

#ifndef AP_SC_COMPLEX
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
#endif

/* The compiled model's promise to write its outputs in full (double build; core.h). */
#ifdef AP_SC_COMPLEX
#define FILLS(m) 0
#else
#define FILLS(m) ((m)->ev.fills)
#endif

/* g, N, A, a0 from a compiled evaluator (body models). N is rewritten only when the model has
 * its own kinematics; otherwise it stays the identity written by ap_data_create. */
static int position_evaluator(const ap_model *m, ap_data *d) {
  size_t kk = (size_t)m->k * m->k;
  if (!(FILLS(m) & AP_EV_FILLS_POSITION)) {   /* zeroed, unless a compiled model writes all */
    memset(d->g, 0, sizeof(ap_sc) * kk);
    if (m->n != m->k || m->sys.kinematic) memset(d->N, 0, sizeof(ap_sc) * (size_t)m->n * m->k);
    memset(d->A, 0, sizeof(ap_sc) * (size_t)m->b * m->k);
    memset(d->a0, 0, sizeof(ap_sc) * (size_t)m->b);
  }
  int rc = m->ev.AP_SC(position)(m, d, SCRATCH(d)->ev);
  if (rc != AP_OK) return rc;
#ifndef AP_SC_COMPLEX
  if (m->ev.finite && m->ev.finite(m, d, 0)) return AP_OK;   /* a compiled model's one check */
#endif
  rc = AP_SC(ap_core_check_finite)(m, d, "metric", d->g, m->k, m->k);
  if (rc == AP_OK) rc = AP_SC(ap_core_check_finite)(m, d, "constraint", d->A, m->b, m->k);
  if (rc == AP_OK) rc = AP_SC(ap_core_check_finite)(m, d, "constraint (a0)", d->a0, m->b, 1);
  return rc;
}

#ifdef AP_SC_COMPLEX
/* The complex-step build evaluates body models only, in the partitioned basis. */
static int unsupported(const ap_model *m, ap_data *d) {
  if (!m->ev.position_cs) {
    ap_core_msg_cs(d, "system '%s': a math-level system (C callbacks of doubles) has no "
                   "complex-step evaluation", m->name);
    return AP_ERR_UNSUPPORTED;
  }
  if (d->basis == AP_BASIS_ORTHONORMAL || d->estimate_cond || d->want_reactions) {
    ap_core_msg_cs(d, "system '%s': the complex-step evaluation has the partitioned basis "
                   "only, without condition estimates or reactions", m->name);
    return AP_ERR_UNSUPPORTED;
  }
  return AP_OK;
}
#endif

/* The position stage without the basis: g, N, A, a0 (partition.c uses it at nearby states). */
int AP_SC(ap_core_position_objects)(const ap_model *m, ap_data *d) {
#ifdef AP_SC_COMPLEX
  int rc = unsupported(m, d);
  return rc == AP_OK ? position_evaluator(m, d) : rc;
#else
  return m->ev.position ? position_evaluator(m, d) : position_callbacks(m, d);
#endif
}

static int fwd_position(const ap_model *m, ap_data *d) {
#ifndef AP_SC_COMPLEX
  /* the tree path (m->ops): a basis always (AP_BASIS_NONE as projected mode: g and A are never
   * formed, so the DAE mode refuses such models) */
  if (ap_core_st(d)) return ap_st_position(m, d, ap_core_st(d));
#endif
  d->cnt.position++;
  int rc = AP_SC(ap_core_position_objects)(m, d);
  if (rc != AP_OK || m->b == 0 || d->basis == AP_BASIS_NONE) return rc;  /* b == 0: B = I */
#ifdef AP_SC_COMPLEX
  rc = basis_partitioned(m, d);
#else
  rc = d->basis == AP_BASIS_ORTHONORMAL ? basis_orthonormal(m, d) : basis_partitioned(m, d);
#endif
  if (rc != AP_OK || d->redundant_manifold || SCRATCH(d)->judge_at_accepted)
    return rc;                                            /* judged at accepted states */
  /* the scale is at least max|a0|: below that no scale is needed (and none is computed) */
  if (d->resid_a0 > 0.0 &&   /* rows of full rank: 0, and no scale is needed */
      d->resid_a0 > AP_CONSISTENCY_RTOL * (AP_TERMS_TINY + max_abs(d->a0, (size_t)m->b)) &&
      d->resid_a0 > AP_CONSISTENCY_RTOL * AP_SC(ap_core_row_scale)(m, d, 0)) {
    AP_SC(ap_core_msg)(d, "system '%s': redundant constraint rows became inconsistent at "
                       "t = %.17g (a0 residual %.3g)", m->name, d->t, d->resid_a0);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}

/* ---- velocity stage ---------------------------------------------------------------------- */

#ifndef AP_SC_COMPLEX
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

/* h, Q, gamma from the user's callbacks. */
static int velocity_callbacks(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k;
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
  else if (s->input_Q) memset(d->Q, 0, sizeof(double) * (size_t)k);   /* inputs add to it */
  if (m->b == 0 || d->basis == AP_BASIS_NONE) return AP_OK;   /* w = 0, or not needed */
  CALL(gamma, d->gamma, m->b, 1, m->sys.gamma(d->t, d->q, d->v, d->gamma, m->sys.user));
  return AP_OK;
}
#endif

/* h, Q, gamma from a compiled evaluator (body models). */
static int velocity_evaluator(const ap_model *m, ap_data *d) {
  int k = m->k;
  if (!(FILLS(m) & AP_EV_FILLS_VELOCITY)) {
    memset(d->h, 0, sizeof(ap_sc) * (size_t)k);
    memset(d->Q, 0, sizeof(ap_sc) * (size_t)k);
    memset(d->gamma, 0, sizeof(ap_sc) * (size_t)m->b);
  }
  int rc = m->ev.AP_SC(velocity)(m, d, SCRATCH(d)->ev);
#ifndef AP_SC_COMPLEX
  if (rc == AP_OK && m->ev.finite && m->ev.finite(m, d, 1)) return AP_OK;   /* one check */
#endif
  if (rc == AP_OK) rc = AP_SC(ap_core_check_finite)(m, d, "bias", d->h, k, 1);
  if (rc == AP_OK) rc = AP_SC(ap_core_check_finite)(m, d, "force", d->Q, k, 1);
  if (rc == AP_OK) rc = AP_SC(ap_core_check_finite)(m, d, "gamma", d->gamma, m->b, 1);
  return rc;
}

static int particular(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int rc = AP_ERR_UNSUPPORTED;
#ifndef AP_SC_COMPLEX
  if (d->basis == AP_BASIS_PARTITIONED && m->ev.particular) rc = m->ev.particular(m, d);
  if (d->basis == AP_BASIS_ORTHONORMAL)
    rc = ap_la_orth_particular(m->b, m->k, d->rank, s->F, s->jpvt, s->Qf, d->gamma, d->w,
                               &d->resid_gamma, s->work);
#endif
  if (rc == AP_ERR_UNSUPPORTED)   /* not a compiled model's (lib/codegen) */
    rc = AP_SC(ap_la_partition_particular)(m->b, m->k, d->rank, d->perm, s->F, s->tau,
                                           d->gamma, d->w, &d->resid_gamma, s->work);
  if (rc != AP_OK || d->redundant_manifold || SCRATCH(d)->judge_at_accepted)
    return rc;                                            /* judged at accepted states */
  if (d->resid_gamma > 0.0 &&
      d->resid_gamma > AP_CONSISTENCY_RTOL * (AP_TERMS_TINY + max_abs(d->gamma, (size_t)m->b)) &&
      d->resid_gamma > AP_CONSISTENCY_RTOL * AP_SC(ap_core_row_scale)(m, d, 1)) {
    AP_SC(ap_core_msg)(d, "system '%s': redundant constraint rows have inconsistent gamma at "
                       "t = %.17g (residual %.3g)", m->name, d->t, d->resid_gamma);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}

void AP_SC(ap_core_speeds)(const ap_model *m, ap_data *d) {
#ifndef AP_SC_COMPLEX
  if (ap_core_st(d)) return ap_st_speeds(m, d, ap_core_st(d));
#endif
  AP_SC(ap_la_gemv)(m->k, d->l, d->B, d->e, d->v);     /* v = B e' + b0 */
  for (int i = 0; i < m->k; i++) d->v[i] += d->b0[i];
}

static int fwd_velocity(const ap_model *m, ap_data *d) {
#ifndef AP_SC_COMPLEX
  if (ap_core_st(d)) return ap_st_velocity(m, d, ap_core_st(d));
#endif
  d->cnt.velocity++;
  if (d->speeds_from_e && d->basis == AP_BASIS_PARTITIONED) AP_SC(ap_core_speeds)(m, d);
#ifdef AP_SC_COMPLEX
  int rc = unsupported(m, d);
  if (rc == AP_OK) rc = velocity_evaluator(m, d);
#else
  int rc = m->ev.velocity ? velocity_evaluator(m, d) : velocity_callbacks(m, d);
  if (rc == AP_OK) ap_core_add_inputs(m, d);
#endif
  if (rc != AP_OK || m->b == 0 || d->basis == AP_BASIS_NONE) return rc;  /* w = 0 or unused */
  return particular(m, d);
}

/* ---- acceleration stage ------------------------------------------------------------------- */

static int fwd_acceleration(const ap_model *m, ap_data *d) {
#ifndef AP_SC_COMPLEX
  if (ap_core_st(d)) return ap_st_acceleration(m, d, ap_core_st(d));
#endif
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l;
  d->cnt.acceleration++;
#ifndef AP_SC_COMPLEX
  int rc_acc = m->ev.acceleration ? m->ev.acceleration(m, d) : AP_ERR_UNSUPPORTED;
  if (rc_acc != AP_ERR_UNSUPPORTED) return rc_acc;   /* a compiled model's (lib/codegen) */
#endif
  /* tk2 = Q - h - g w ; Phi = B^T Q ; edd = B^T tk2 (the right-hand side) */
  AP_SC(ap_la_gemv)(k, k, d->g, d->w, s->tk1);
  for (int i = 0; i < k; i++) s->tk2[i] = d->Q[i] - d->h[i] - s->tk1[i];
  if (m->b == 0) {
    memcpy(d->G, d->g, sizeof(ap_sc) * (size_t)k * k);
    memcpy(d->Phi, d->Q, sizeof(ap_sc) * (size_t)k);
    memcpy(d->edd, s->tk2, sizeof(ap_sc) * (size_t)k);
  } else {
    AP_SC(ap_la_congruence)(k, l, d->g, d->B, d->G, s->gB);
    AP_SC(ap_la_gemv_t)(k, l, d->B, d->Q, d->Phi);
    AP_SC(ap_la_gemv_t)(k, l, d->B, s->tk2, d->edd);
  }
  double *rcond = d->estimate_cond ? &d->rcond_G : NULL;   /* not in the hot path */
  if (!rcond) d->rcond_G = 1.0;
  int rc = AP_SC(ap_la_chol)(l, d->G, rcond, s->work, s->iwork);
  if (rc != AP_OK) {
    AP_SC(ap_core_msg)(d, "system '%s': G = B^T g B (%d x %d) is not positive definite at "
                       "t = %.17g: the metric g is not positive definite on the free speeds",
                       m->name, l, l, d->t);
    return AP_ERR_SINGULAR;
  }
  AP_SC(ap_la_chol_solve)(l, d->G, d->edd);
  rc = AP_SC(ap_core_check_finite)(m, d, "Appell solve (e'')", d->edd, l, 1);
  if (rc != AP_OK) return rc;
  if (m->b == 0) memcpy(d->vdot, d->edd, sizeof(ap_sc) * (size_t)k);
  else {
    AP_SC(ap_la_gemv)(k, l, d->B, d->edd, d->vdot);     /* v' = B e'' + w */
    for (int i = 0; i < k; i++) d->vdot[i] += d->w[i];
  }
  AP_SC(ap_la_gemv)(m->n, k, d->N, d->v, d->qdot);      /* q' = N v */
  return AP_OK;
}

/* ---- optional stages ---------------------------------------------------------------------- */

#ifndef AP_SC_COMPLEX
static int fwd_reactions(const ap_model *m, ap_data *d) {
  if (ap_core_st(d)) return ap_st_reactions(m, d, ap_core_st(d));
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
#endif

/* ---- the stages' entry points -------------------------------------------------------------
 * Each checks its data, runs the stage and, in the guard build (core/arena.h), the guard words
 * of the data's blocks after it. */

int AP_SC(ap_fwd_position)(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  return AP_CORE_GUARDED(m, d, "position", fwd_position(m, d));
}

int AP_SC(ap_fwd_velocity)(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  return AP_CORE_GUARDED(m, d, "velocity", fwd_velocity(m, d));
}

int AP_SC(ap_fwd_acceleration)(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  return AP_CORE_GUARDED(m, d, "acceleration", fwd_acceleration(m, d));
}

#ifndef AP_SC_COMPLEX
int ap_fwd_reactions(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  return AP_CORE_GUARDED(m, d, "reactions", fwd_reactions(m, d));
}
#endif

int AP_SC(ap_forward)(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  d->cnt.forward++;
  int rc = AP_SC(ap_fwd_position)(m, d);
  if (rc == AP_OK) rc = AP_SC(ap_fwd_velocity)(m, d);
  if (rc == AP_OK) rc = AP_SC(ap_fwd_acceleration)(m, d);
#ifndef AP_SC_COMPLEX
  if (rc == AP_OK && d->want_reactions) rc = ap_fwd_reactions(m, d);
#endif
  return rc;
}
