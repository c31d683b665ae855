/* The reduced equations x' = F(x) of the linearization, x = (independent chart coordinates,
 * independent heading-frame speeds), with both partitions frozen.
 *
 * One evaluation: (1) the chart coordinates delta: independent ones from x, dependent ones by
 * Newton on the holonomic rows phi(q(delta)) = 0 (the model's loop closures; unit-quaternion
 * rows hold identically in the chart and drop out as zero rows), each step the least-squares
 * solution of Jh_D d_D = -phi with Jh = Phi_q dq/ddelta, factored with the frozen column
 * partition; (2) q = chart(q_ref, delta) and the core's position stage; (3) the speeds: the
 * constraint rows on heading-frame speeds A S^T u + a0 = 0 with the independent u from x, by
 * the partitioned basis of A S^T (frozen partition), then v = S^T u; (4) the core's velocity and
 * acceleration stages (v given, v' from the Appell solve with the core's own partition);
 * (5) the rates: chart rates from v (body models) or q' = N v (math-level), and
 * u' = S v' + S' v. F(x) picks the rates of the states.
 *
 * Generic in the scalar (linalg/scalar.h): reduced_cs.c compiles this file again into
 * ap_an_rates_cs, F on complex-step states x0 + i h dx with the model's complex-step build
 * (exact Jacobian columns, linearize.c). Newton on complex numbers: the real parts follow the
 * real Newton iteration exactly, and the imaginary parts follow its linearization, which at the
 * converged real part is one linear solve Jh_D d(delta_D) = -(d phi), the derivative of the
 * implicit function; so the iteration stops when both parts have converged (the imaginary
 * residual at round-off of its first value), never on the real part alone. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "linalg/linalg.h"

#define HOLO_ITER 30

/* The build's workspace and data. */
#define WS(L) (&(L)->AP_SC(ws))

static double max_abs(const double *x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* Largest |Re x_i| and |Im x_i|. */
static void max_parts(const ap_sc *x, int n, double *re, double *im) {
  *re = *im = 0.0;
  for (int i = 0; i < n; i++) *re = fmax(*re, SC_MAG(x[i])), *im = fmax(*im, fabs(SC_IM(x[i])));
}

/* Holonomic rows and their chart Jacobian Jh (nphi x nc) at delta: w->phi, w->Jh. */
static int holonomic(ap_lin *L) {
  const ap_model *m = L->m;
  AP_SC(an_ws) *w = WS(L);
  AP_SC(ap_data) *d = w->d;
  int n = L->n, nc = L->ch.nc, np = L->nphi;
  ap_an_chart_apply(&L->ch, n, L->q_ref, w->delta, d->q);
  d->basis = AP_BASIS_NONE;
  int rc = AP_SC(ap_fwd_position)(m, d);
  d->basis = AP_BASIS_PARTITIONED;
  if (rc != AP_OK) return rc;
  ap_sc *Phi_q = w->Phi_q;  /* nphi x n */
  memset(Phi_q, 0, sizeof *Phi_q * (size_t)np * n);
  rc = m->ev.AP_SC(phi)(m, d, ((AP_SC(ap_scratch) *)d->internal)->ev, w->phi, Phi_q);
  if (rc != AP_OK) return rc;
  ap_an_chart_jacobian(&L->ch, n, d->q, w->delta, w->dq);
  for (int c = 0; c < nc; c++)     /* Jh = Phi_q dq */
    for (int r = 0; r < np; r++) {
      ap_sc s = 0.0;
      for (int i = 0; i < n; i++) s += Phi_q[r + (size_t)i * np] * w->dq[i + (size_t)c * n];
      w->Jh[r + (size_t)c * np] = s;
    }
  return AP_OK;
}

/* Newton on the dependent chart coordinates until phi reaches round-off: the real part below
 * 8 eps max(1, |q_ref|) (or stalled below 1e-9), the imaginary part below 8 eps of its first
 * value (or stalled below 1e-7 of it) - zero in the double build. */
static int solve_holonomic(ap_lin *L) {
  AP_SC(an_ws) *w = WS(L);
  int np = L->nphi, nc = L->ch.nc;
  double r = 0.0, r_prev = HUGE_VAL, ri = 0.0, ri_prev = HUGE_VAL, ri0 = -1.0, growth, resid;
  double tol = 8.0 * DBL_EPSILON * fmax(1.0, max_abs(L->q_ref, L->n));
  for (int it = 0; it <= HOLO_ITER; it++) {
    int rc = holonomic(L);
    if (rc != AP_OK) return rc;
    max_parts(w->phi, np, &r, &ri);
    if (ri0 < 0.0) ri0 = ri;
    int re_done = r <= tol || (r <= 1e-9 && r > 0.25 * r_prev);
    int im_done = ri <= 8.0 * DBL_EPSILON * ri0 || (ri <= 1e-7 * ri0 && ri > 0.25 * ri_prev);
    if (re_done && im_done) return AP_OK;
    if (it == HOLO_ITER) break;
    rc = AP_SC(ap_la_partition_basis)(np, nc, L->rh, L->cperm, w->Jh, w->phi, w->F, w->tau,
                                      w->dd, w->b0u, &growth, NULL, &resid, w->work, L->iwork);
    if (rc != AP_OK) break;
    for (int i = 0; i < L->rh; i++) w->delta[L->cperm[i]] += w->b0u[L->cperm[i]];
    r_prev = r, ri_prev = ri;
  }
  ap_an_msg(L, "the holonomic rows cannot be solved for the dependent coordinates: residual "
            "%.3g after %d Newton steps", r, HOLO_ITER);
  return AP_ERR_SINGULAR;
}

/* The independent speeds from x and the dependent ones from A S^T u + a0 = 0. */
static int speeds(ap_lin *L, const ap_sc *x) {
  AP_SC(an_ws) *w = WS(L);
  AP_SC(ap_data) *d = w->d;
  int k = L->k, b = L->b, nci = L->nci;
  double growth, resid;
  if (b == 0 || L->ru == 0) {
    memset(w->u, 0, sizeof *w->u * (size_t)k);
    for (int j = 0; j < L->l; j++) w->u[L->uperm[L->ru + j]] = x[nci + j];
  } else {
    ap_an_frame_matrix(&L->ch, w->delta, b, d->A, w->Au);
    int rc = AP_SC(ap_la_partition_basis)(b, k, L->ru, L->uperm, w->Au, d->a0, w->F, w->tau,
                                          w->Bu, w->b0u, &growth, NULL, &resid, w->work,
                                          L->iwork);
    if (rc != AP_OK) {
      ap_an_msg(L, "the dependent speeds cannot be solved: the frozen partition of the "
                "constraint rows is singular here");
      return AP_ERR_SINGULAR;
    }
    AP_SC(ap_la_gemv)(k, L->l, w->Bu, x + nci, w->u);   /* u = Bu u_I + b0u */
    for (int i = 0; i < k; i++) w->u[i] += w->b0u[i];
  }
  ap_an_frame_to_v(&L->ch, w->delta, w->u, d->v);
  return AP_OK;
}

int ap_an_state(ap_lin *L, const ap_sc *x) {
  AP_SC(an_ws) *w = WS(L);
  AP_SC(ap_data) *d = w->d;
  memset(w->delta, 0, sizeof *w->delta * (size_t)L->ch.nc);
  for (int i = 0; i < L->nci; i++) w->delta[L->xvar[i]] = x[i];
  d->t = L->t;
  if (L->nphi > 0 && L->rh > 0) {
    int rc = solve_holonomic(L);
    if (rc != AP_OK) return rc;
  }
  ap_an_chart_apply(&L->ch, L->n, L->q_ref, w->delta, d->q);
  d->basis = AP_BASIS_PARTITIONED;
  d->speeds_from_e = 0;
  int rc = AP_SC(ap_fwd_position)(L->m, d);
  if (rc != AP_OK) {
    ap_an_msg(L, "position stage failed: %s", d->msg);
    return rc;
  }
  return speeds(L, x);
}

int ap_an_rates_full(ap_lin *L, const ap_sc *x, ap_sc *full) {
  AP_SC(an_ws) *w = WS(L);
  AP_SC(ap_data) *d = w->d;
  int rc = ap_an_state(L, x);
  if (rc == AP_OK) rc = AP_SC(ap_fwd_velocity)(L->m, d);
  if (rc == AP_OK) rc = AP_SC(ap_fwd_acceleration)(L->m, d);
  if (rc != AP_OK) {
    if (!L->msg[0]) ap_an_msg(L, "the Appell solve failed: %s", d->msg);
    return rc;
  }
  int nc = L->ch.nc;
  if (L->ch.body) ap_an_chart_rates(&L->ch, w->delta, d->v, full);
  else memcpy(full, d->qdot, sizeof *full * (size_t)nc);
  ap_an_frame_rates(&L->ch, w->delta, full, d->v, d->vdot, full + nc);
  for (int i = 0; i < nc + L->k; i++)
    if (!SC_FINITE(full[i])) {
      ap_an_msg(L, "the rate of '%s' is %g", ap_an_var_name(L, i), SC_RE(full[i]));
      return AP_ERR_NAN;
    }
  return AP_OK;
}

int ap_an_rates(ap_lin *L, const ap_sc *x, ap_sc *f) {
  AP_SC(an_ws) *w = WS(L);
  int rc = ap_an_rates_full(L, x, w->full);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < L->nx; i++) f[i] = w->full[L->xvar[i]];
  return AP_OK;
}
