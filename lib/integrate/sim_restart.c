/* Where a run starts and restarts: coordinates and speeds put on the constraints, the stepper
 * (or IDA) made for the state, and the restart after an event or a contact-mode switch
 * (docs/design.md §2). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/body.h"
#include "integrate/sim_int.h"
#include "linalg/linalg.h"
#include "model/model.h"

/* Body models: q0 onto its manifold before anything else. Loop closures open by more than
 * init_tol (m) are refused: closing them would move the configuration that far without a word
 * (assemble q0 with ap_body_project_q first). Otherwise project_q closes them and normalizes
 * the quaternions (rotations use q / |q|: the configuration does not change) into q. */
int ap_drv_consistent_coordinates(ap_sim *s, double t0, const double *q0, double *q) {
  ap_data *d = s->d;
  double phi = 0.0, change = 0.0;
  memcpy(q, q0, sizeof(double) * (size_t)s->n);
  if (!s->m->ev.project_q) return AP_OK;
  d->t = t0;
  memcpy(d->q, q0, sizeof(double) * (size_t)s->n);
  int rc = ap_body_loop_residual(s->m, d, &phi);
  if (rc == AP_OK && phi > s->def.init_tol)
    return ap_drv_fail(s, AP_ERR_INCONSISTENT, "system '%s': the initial coordinates leave the "
                         "loop closures or wheel contacts open by %.3g m, more than init_tol %.3g: "
                         "close them first (ap_body_project_q)", s->m->name, phi, s->def.init_tol);
  if (rc == AP_OK) rc = s->m->ev.project_q(s->m, d, q, ((ap_scratch *)d->internal)->ev, &change);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "initial state: %s",
                                      d->msg);
  return AP_OK;
}

/* Put v on the constraint set; refuse speeds too far off it (when refuse). */
int ap_drv_consistent_speeds(ap_sim *s, double t0, const double *q0, const double *v0,
                              int refuse) {
  ap_data *d = s->d;
  d->t = t0;
  memcpy(d->q, q0, sizeof(double) * (size_t)s->n);
  memcpy(s->v, v0, sizeof(double) * (size_t)s->k);
  if (s->m->b == 0 && s->def.mode != AP_MODE_MINIMAL) return AP_OK;
  /* Rank, redundant rows and which redundancy is structural, in every mode: inconsistent rows
   * are refused with their names; consistent ones are dropped (the partition, the orthonormal
   * basis and the DAE's kept rows make the same choice) and named in the warning. */
  int rc = ap_partition(s->m, d);
  if (rc == AP_OK && refuse) rc = ap_core_refuse_vanishing_rows(s->m, d);
  if (rc != AP_OK) return ap_drv_fail(s, rc, "initial state: %s", d->msg);
  if (s->m->b == 0) return AP_OK;
  if (s->def.mode == AP_MODE_PLAIN && d->redundant_manifold > 0)
    return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "system '%s': plain mode cannot run it: %d "
                       "constraint row%s redundant only where the loops and wheel contacts "
                       "close, and plain mode never puts the speeds back on the constraints: "
                       "as they drift, the dropped rows' gamma leaves the kept rows' "
                       "combination (use minimal, projected or DAE mode)", s->m->name,
                       d->redundant_manifold, d->redundant_manifold == 1 ? " is" : "s are");
  if (refuse && d->rank < s->m->b) snprintf(s->warning, sizeof s->warning, "%s", d->msg);
  rc = ap_fwd_position(s->m, d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "initial state: %s",
                                      d->msg);
  double resid = ap_constraint_residual(d, s->v), size = sqrt(2 * ap_kinetic_energy(d, s->v));
  double change = 0.0;
  rc = ap_project_speeds(s->m, d, s->v, &change);
  if (rc != AP_OK) return ap_drv_fail(s, rc, "initial state: %s", d->msg);
  size = fmax(size, sqrt(2 * ap_kinetic_energy(d, s->v)));
  if (!refuse) return AP_OK;
  s->stats.init_correction = change;
  /* Refused when far off relative to the speeds' size, unless the change is below atol (or
   * 1e-12) in every speed: speeds of round-off size on a mechanism that the constraints lock
   * (a rate prescribed twice; l = 0 at rest) were refused for a change of 5.7e-17
   * (tests/difftest). */
  double dv = 0.0;
  for (int i = 0; i < s->k; i++) dv = fmax(dv, fabs(s->v[i] - v0[i]));
  if (change > s->def.init_tol * size && dv > fmax(s->def.atol, 1e-12))
    return ap_drv_fail(s, AP_ERR_INCONSISTENT, "system '%s': the initial speeds violate the "
                         "constraints (max |A v + a0| = %.3g; the nearest admissible speeds differ "
                         "by %.3g in the metric g, more than init_tol %.3g relative to %.3g)",
                         s->m->name, resid, change, s->def.init_tol, size);
  return AP_OK;
}

/* DAE mode: y = (q, v, lambda, mu), y' = (q', v', 0, 0), from the Appell solve at t0 (mu = 0:
 * on the exact solution the GGL multipliers vanish; lambda: dae.c solves for the multipliers of
 * the independent rows it keeps). */
int ap_drv_setup_dae(ap_sim *s) { return ap_drv_dae_make(s, s->t, s->y, s->ytry); }

/* IDA at (t, y) with the Appell solve's q', v' in the data; yp (ny) is scratch. With contact
 * modes the residual carries the sliding contacts' Coulomb forces (contact_dae.c). */
int ap_drv_dae_make(ap_sim *s, double t, double *y, double *yp) {
  ap_data *d = s->d;
  int nalg = s->b + (s->m->ev.phi ? s->m->nphi : 0);
  s->ny = s->n + s->k + nalg;
  memset(y + s->n + s->k, 0, sizeof(double) * (size_t)nalg);
  memcpy(yp, d->qdot, sizeof(double) * (size_t)s->n);
  memcpy(yp + s->n, d->vdot, sizeof(double) * (size_t)s->k);
  memset(yp + s->n + s->k, 0, sizeof(double) * (size_t)nalg);
  double h0 = s->def.h_init > 0 ? s->def.h_init : ap_drv_dae_h0(s, y, d->vdot);
  ap_step_opts o = {s->def.rtol, s->def.atol, 0.0, h0, s->def.h_max, s->def.max_steps, NULL, NULL};
  if (s->cm) ap_drv_contacts_switched(s);   /* the modes IDA is made for */
  ap_dae_couple cp = ap_drv_dae_couple(s);   /* dae_loads.c */
  int rc = ap_dae_create(s->m, d, t, y, yp, &o, s->def.rank_rtol, s->cm ? &cp : NULL, &s->dae,
                         s->msg, sizeof s->msg);
  if (rc == AP_OK) ap_dae_state(s->dae, y);
  return rc;
}

/* The stepper for s->ny at (t0, s->y) (at creation, and when a contact-mode switch changed the
 * number of free speeds). */
int ap_drv_make_stepper(ap_sim *s, double t0) {
  ap_drv_growth_cap(s, s->d->growth);
  /* h_fixed goes to fixed-step methods only: for an adaptive one it would switch error
   * control off. */
  ap_step_opts o = {s->def.rtol, s->def.atol, s->meth->adaptive ? 0.0 : s->def.h_fixed,
                    s->def.h_init, s->def.h_max, s->def.max_steps, NULL, NULL};
  if (ap_drv_weights_create(s, (size_t)(s->n + s->k)) != AP_OK)
    return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  o.weight = s->wt;
  int nphi = s->m->ev.phi && s->m->ev.project_q ? s->m->nphi : 0;
  if (ap_step_native_projection(s->meth) &&
      ((s->def.mode == AP_MODE_PROJECTED && s->m->b > 0) || nphi > 0)) {
    o.proj = ap_drv_proj;
    s->native_q = nphi > 0;
  }
  if (s->native_q && !s->gn) {          /* gn_project_q's scratch */
    size_t n = (size_t)s->n, np = (size_t)nphi;
    s->gn = calloc(2 * np * n + np + ap_la_work_size(s->n, nphi) + n, sizeof *s->gn);
    s->gn_iwork = calloc(ap_la_iwork_size(s->n, nphi), sizeof *s->gn_iwork);
    if (!s->gn || !s->gn_iwork) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  }
  /* Trial states off the constraints, redundant rows judged at accepted states: CVODE's
   * predictor and Newton iterates, and the stages of the projected and plain modes (v is
   * projected after the step only). Rows whose combination of the others changes with q (a
   * wheel's knife edge beside its rolling rows) differ there by the combination's rate times
   * A v + a0: judged at every stage, a rolling disk with a knife edge stopped at t = 0.0018 in
   * projected mode (tests/scenes/difftest/rolling_knife.yaml). */
  ((ap_scratch *)s->d->internal)->judge_at_accepted =
      s->meth->backend == &ap_step_cvode || s->def.mode != AP_MODE_MINIMAL;
  return ap_step_create(s->meth, s->ny, ap_drv_rhs, s, t0, s->y, &o, &s->st, s->msg,
                        sizeof s->msg);
}

/* The state (q, e') or (q, v) of a simulation from coordinates and speeds on the
 * constraints (the data holds the position stage and the partition there); ny must not
 * change. */
static int state_from(ap_sim *s, double t, double *y) {
  int ny = s->n + (s->def.mode == AP_MODE_MINIMAL ? s->d->l : s->k);
  if (s->dae) ny = s->ny;
  if (ny != s->ny && s->cm) s->ny = ny;   /* a contact-mode switch: restart_state remakes */
  if (ny != s->ny)
    return ap_drv_fail(s, AP_ERR_RANK, "system '%s': the number of free speeds changed from "
                       "%d to %d at t = %.17g (at an event)", s->m->name, s->ny - s->n,
                       ny - s->n, t);
  memcpy(y, s->q, sizeof(double) * (size_t)s->n);
  if (s->def.mode == AP_MODE_MINIMAL)
    for (int j = 0; j < s->d->l; j++) y[s->n + j] = s->v[s->d->perm[s->d->rank + j]];
  else
    memcpy(y + s->n, s->v, sizeof(double) * (size_t)s->k);
  return AP_OK;
}

/* IDA's state (q, v) in y (ny >= n + k) put on every row before a restart with other kept
 * rows: q onto phi = 0 (body models), then v onto A v + a0 = 0, nearest in g. IDA held only
 * the rows it kept; a dropped row drifts by its combination's error, amplified by the inverse
 * pivot of the kept rows as they degrade (the reason they are chosen again). At campaign seed
 * 1001020 (tests/scenes/difftest/dae_rows_restart.yaml) a newly kept row was off by 2.3e-11
 * m/s, twice IDA's atol: IDA's corrector put v onto it in its first step, a jump independent
 * of the step size, and the error test failed down to steps of 3e-11 s. The event restarts
 * project the same way (ap_drv_restart_state). */
int ap_drv_dae_onto_rows(ap_sim *s, double t, double *y) {
  ap_data *d = s->d;
  double change = 0.0;
  int rc = AP_OK;
  ap_drv_load_state(s, t, y);
  if (s->m->ev.project_q)
    rc = s->m->ev.project_q(s->m, d, y, ((ap_scratch *)d->internal)->ev, &change);
  if (rc == AP_OK) {
    ap_drv_load_state(s, t, y);
    d->basis = AP_BASIS_ORTHONORMAL;
    rc = ap_fwd_position(s->m, d);
    if (rc == AP_OK && s->m->b > 0) rc = ap_core_project_here(s->m, d, y + s->n, &change);
    d->basis = AP_BASIS_NONE;
  }
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
  ap_drv_load_state(s, t, y);
  return AP_OK;
}

/* IDA from (t, y): q', v' from the Appell solve there, IDA's multipliers back into y. */
static int restart_dae(ap_sim *s, double t, double *y) {
  ap_data *d = s->d;
  d->basis = AP_BASIS_ORTHONORMAL;
  ap_drv_load_state(s, t, y);
  int rc = ap_forward(s->m, d);
  d->basis = AP_BASIS_NONE;
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  rc = ap_dae_restart(s->dae, t, y, d->qdot, d->vdot, ap_drv_dae_h0(s, y, d->vdot));
  if (rc != AP_OK) return ap_drv_fail(s, rc, "%s", ap_dae_message(s->dae));
  ap_dae_state(s->dae, y);
  return AP_OK;
}

int ap_drv_restart_state(ap_sim *s, double t, const double *q, const double *v) {
  double *y = s->dae ? s->ytry : s->y, *qq = s->yev;   /* yev: free until the next rhs */
  memcpy(qq, q, sizeof(double) * (size_t)s->n);
  s->ev_stamp = -1;
  if (s->dae) s->d->basis = AP_BASIS_ORTHONORMAL;
  int rc = ap_drv_consistent_coordinates(s, t, qq, s->q);
  if (rc == AP_OK) rc = ap_drv_consistent_speeds(s, t, s->q, v, 0);
  if (s->dae) s->d->basis = AP_BASIS_NONE;
  if (rc == AP_OK) rc = state_from(s, t, y);
  if (rc != AP_OK) return rc;
  s->stats.restarts++;
  if (s->dae)
    return s->cm && ap_drv_contacts_switched(s) ? ap_drv_dae_remake(s, t, y) : restart_dae(s, t, y);
  if (s->cm) {   /* contact modes: the state size may have changed with the rows */
    ap_step_free(s->st);
    s->st = NULL;
    return ap_drv_make_stepper(s, t);
  }
  ap_drv_growth_cap(s, s->d->growth);
  rc = ap_step_reset(s->st, t, y);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", ap_step_message(s->st));
}
