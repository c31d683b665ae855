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
 * u' = S v' + S' v. F(x) picks the rates of the states. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "linalg/linalg.h"

#define HOLO_ITER 30

static double max_abs(const double *x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* Holonomic rows and their chart Jacobian Jh (nphi x nc) at delta: L->phi, L->Jh. */
static int holonomic(ap_lin *L) {
  const ap_model *m = L->m;
  ap_data *d = L->d;
  int n = L->n, nc = L->ch.nc, np = L->nphi;
  ap_an_chart_apply(&L->ch, n, L->q_ref, L->delta, d->q);
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(m, d);
  d->basis = AP_BASIS_PARTITIONED;
  if (rc != AP_OK) return rc;
  double *Phi_q = L->Bu;  /* nphi x n, scratch */
  memset(Phi_q, 0, sizeof *Phi_q * (size_t)np * n);
  rc = m->ev.phi(m, d, ((ap_scratch *)d->internal)->ev, L->phi, Phi_q);
  if (rc != AP_OK) return rc;
  ap_an_chart_jacobian(&L->ch, n, d->q, L->delta, L->dq);
  for (int c = 0; c < nc; c++)     /* Jh = Phi_q dq */
    for (int r = 0; r < np; r++) {
      double s = 0.0;
      for (int i = 0; i < n; i++) s += Phi_q[r + (size_t)i * np] * L->dq[i + (size_t)c * n];
      L->Jh[r + (size_t)c * np] = s;
    }
  return AP_OK;
}

/* Newton on the dependent chart coordinates until phi reaches round-off. */
static int solve_holonomic(ap_lin *L) {
  int np = L->nphi, nc = L->ch.nc;
  double r = 0.0, r_prev = HUGE_VAL, growth, resid;
  double tol = 8.0 * DBL_EPSILON * fmax(1.0, max_abs(L->q_ref, L->n));
  for (int it = 0; it <= HOLO_ITER; it++) {
    int rc = holonomic(L);
    if (rc != AP_OK) return rc;
    r = max_abs(L->phi, np);
    if (r <= tol || (r <= 1e-9 && r > 0.25 * r_prev)) return AP_OK;
    if (it == HOLO_ITER) break;
    rc = ap_la_partition_basis(np, nc, L->rh, L->cperm, L->Jh, L->phi, L->F, L->tau, L->dd,
                               L->b0u, &growth, NULL, &resid, L->work, L->iwork);
    if (rc != AP_OK) break;
    for (int i = 0; i < L->rh; i++) L->delta[L->cperm[i]] += L->b0u[L->cperm[i]];
    r_prev = r;
  }
  ap_an_msg(L, "the holonomic rows cannot be solved for the dependent coordinates: residual "
            "%.3g after %d Newton steps", r, HOLO_ITER);
  return AP_ERR_SINGULAR;
}

/* The independent speeds from x and the dependent ones from A S^T u + a0 = 0. */
static int speeds(ap_lin *L, const double *x) {
  ap_data *d = L->d;
  int k = L->k, b = L->b, nci = L->nci;
  double growth, resid;
  if (b == 0 || L->ru == 0) {
    memset(L->u, 0, sizeof *L->u * (size_t)k);
    for (int j = 0; j < L->l; j++) L->u[L->uperm[L->ru + j]] = x[nci + j];
  } else {
    ap_an_frame_matrix(&L->ch, L->delta, b, d->A, L->Au);
    int rc = ap_la_partition_basis(b, k, L->ru, L->uperm, L->Au, d->a0, L->F, L->tau, L->Bu,
                                   L->b0u, &growth, NULL, &resid, L->work, L->iwork);
    if (rc != AP_OK) {
      ap_an_msg(L, "the dependent speeds cannot be solved: the frozen partition of the "
                "constraint rows is singular here");
      return AP_ERR_SINGULAR;
    }
    ap_la_gemv(k, L->l, L->Bu, x + nci, L->u);   /* u = Bu u_I + b0u */
    for (int i = 0; i < k; i++) L->u[i] += L->b0u[i];
  }
  ap_an_frame_to_v(&L->ch, L->delta, L->u, d->v);
  return AP_OK;
}

int ap_an_state(ap_lin *L, const double *x) {
  ap_data *d = L->d;
  memset(L->delta, 0, sizeof *L->delta * (size_t)L->ch.nc);
  for (int i = 0; i < L->nci; i++) L->delta[L->xvar[i]] = x[i];
  d->t = L->t;
  if (L->nphi > 0 && L->rh > 0) {
    int rc = solve_holonomic(L);
    if (rc != AP_OK) return rc;
  }
  ap_an_chart_apply(&L->ch, L->n, L->q_ref, L->delta, d->q);
  d->basis = AP_BASIS_PARTITIONED;
  d->speeds_from_e = 0;
  int rc = ap_fwd_position(L->m, d);
  if (rc != AP_OK) {
    ap_an_msg(L, "position stage failed: %s", d->msg);
    return rc;
  }
  return speeds(L, x);
}

int ap_an_rates_full(ap_lin *L, const double *x, double *full) {
  ap_data *d = L->d;
  int rc = ap_an_state(L, x);
  if (rc == AP_OK) rc = ap_fwd_velocity(L->m, d);
  if (rc == AP_OK) rc = ap_fwd_acceleration(L->m, d);
  if (rc != AP_OK) {
    if (!L->msg[0]) ap_an_msg(L, "the Appell solve failed: %s", d->msg);
    return rc;
  }
  int nc = L->ch.nc;
  if (L->ch.body) ap_an_chart_rates(&L->ch, L->delta, d->v, full);
  else memcpy(full, d->qdot, sizeof *full * (size_t)nc);
  ap_an_frame_rates(&L->ch, L->delta, full, d->v, d->vdot, full + nc);
  for (int i = 0; i < nc + L->k; i++)
    if (!isfinite(full[i])) {
      ap_an_msg(L, "the rate of '%s' is %g", ap_an_var_name(L, i), full[i]);
      return AP_ERR_NAN;
    }
  return AP_OK;
}

int ap_an_rates(ap_lin *L, const double *x, double *f) {
  int rc = ap_an_rates_full(L, x, L->f2);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < L->nx; i++) f[i] = L->f2[L->xvar[i]];
  return AP_OK;
}
