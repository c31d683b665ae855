/* Simulation drivers, per mode: the right-hand side handed to the stepper and the work after
 * each accepted step (docs/design.md §1 "Choosing B"; the modes are described in sim.c).
 *
 * Minimal: re-partition when the frozen basis has degraded (growth past switch_growth) and
 * restart from e'_new. Projected: v onto A v + a0 = 0 nearest in g (inside CVODE's step via
 * ap_drv_proj, after the step for one-step methods). Plain: residual only. DAE: checks and
 * residuals only; IDA's state is never touched. Body models first get q back on its manifold
 * (unit quaternions, loop closures). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "appell/body.h"
#include "integrate/sim_int.h"

/* ---- the right-hand side ------------------------------------------------------------------ */

/* Load y = (q, e') or (q, v) into the data at time t. */
void ap_drv_load_state(ap_sim *s, double t, const double *y) {
  ap_data *d = s->d;
  d->t = t;
  memcpy(d->q, y, sizeof(double) * (size_t)s->n);
  if (s->def.mode == AP_MODE_MINIMAL) {
    memcpy(d->e, y + s->n, sizeof(double) * (size_t)d->l);
    d->speeds_from_e = 1;
  } else {
    memcpy(d->v, y + s->n, sizeof(double) * (size_t)s->k);
    d->speeds_from_e = 0;
  }
}

/* Pipeline stages run on the data so far: unchanged while the data holds one evaluation. */
static long stage_count(const ap_data *d) {
  return d->cnt.position + d->cnt.velocity + d->cnt.acceleration + d->cnt.partitions;
}

int ap_drv_rhs(double t, const double *y, double *ydot, void *user) {
  ap_sim *s = user;
  ap_data *d = s->d;
  ap_drv_load_state(s, t, y);
  int rc = ap_forward(s->m, d);
  if (rc != AP_OK) {
    s->rhs_status = rc;
    memcpy(s->rhs_msg, d->msg, sizeof s->rhs_msg);
    return rc > 0 ? 1 : -1;
  }
  if (s->def.mode == AP_MODE_MINIMAL && s->m->b > 0 && d->growth > s->growth_cap) {
    s->rhs_status = 1;
    snprintf(s->rhs_msg, sizeof s->rhs_msg, "system '%s': the partitioned basis degrades "
             "within a step (growth %.3g > %.3g at t = %.17g)", s->m->name, d->growth,
             s->growth_cap, t);
    return 1;                                    /* recoverable: a shorter step */
  }
  memcpy(ydot, d->qdot, sizeof(double) * (size_t)s->n);
  if (s->def.mode == AP_MODE_MINIMAL)
    memcpy(ydot + s->n, d->edd, sizeof(double) * (size_t)d->l);
  else
    memcpy(ydot + s->n, d->vdot, sizeof(double) * (size_t)s->k);
  s->ev_stamp = stage_count(d), s->ev_t = t;    /* the data now describes (t, y) */
  memcpy(s->yev, y, sizeof(double) * (size_t)s->ny);
  return 0;
}

/* 1 when the data still holds a successful evaluation at exactly (t, y): after an accepted
 * step, the first-same-as-last stage evaluated at the new state (dop853 always ends its step
 * with it; ARKODE's FSAL tables when that stage equals the returned state bit for bit). Its
 * position stage (g, A, B, growth), v = B e' + b0 and derivatives describe the new state. */
static int evaluated_at(const ap_sim *s, double t, const double *y) {
  return s->ev_stamp == stage_count(s->d) && s->ev_t == t &&
         memcmp(s->yev, y, sizeof(double) * (size_t)s->ny) == 0;
}

/* ---- after each accepted step ------------------------------------------------------------ */

/* Body models: unit quaternions and loop closures back on their manifold after each step. The
 * stepper restarts only when something moved. */
static int project_coordinates(ap_sim *s, double t) {
  if (!s->m->ev.project_q) return AP_OK;
  double change = 0.0, *q = s->ytry;   /* project a copy: it may not be applied */
  ap_data *d = s->d;
  ap_drv_load_state(s, t, s->y);
  memcpy(q, s->y, sizeof(double) * (size_t)s->n);
  int rc = s->m->ev.project_q(s->m, d, q, ((ap_scratch *)d->internal)->ev, &change);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  if (change == 0.0) return AP_OK;
  if (s->meth->backend == &ap_step_cvode) {
    /* A restart drops CVODE to order 1 with a tiny step: apply the correction only once it
     * exceeds a tenth of the tolerance (measured: the rolling disk took 1.48 million steps
     * when its quaternion was re-normalized and CVODE restarted after every step). */
    double qmax = 0.0;
    for (int i = 0; i < s->n; i++) qmax = fmax(qmax, fabs(s->y[i]));
    if (change <= 0.1 * (s->def.rtol * qmax + s->def.atol)) return AP_OK;
  }
  memcpy(s->y, q, sizeof(double) * (size_t)s->n);
  s->stats.restarts++;
  rc = ap_step_reset(s->st, t, s->y);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", ap_step_message(s->st));
}

/* Minimal mode: the largest basis growth a stage of the next step may reach, from the growth
 * g at its start. The partition is frozen during a step and re-chosen only between steps; a
 * step that runs far past switch_growth integrates coordinates that are close to singular
 * (e.g. the knife edge's dependent speed ~ tan(phi) near 90 degrees), and the error estimates,
 * DOP853's in particular, can miss it (measured: the spinning knife at rtol 1e-8 ended 400
 * times off its tolerance with dop853, steps ending at growth up to 94). Such a stage fails
 * recoverably, so the step is shortened and the switch happens in time; the cap is never
 * below 2 g, so short enough steps always pass. */
void ap_drv_growth_cap(ap_sim *s, double g) {
  s->growth_cap = fmax(AP_DRV_GROWTH_CAP * s->def.switch_growth, 2.0 * g);
}

/* Minimal mode: re-partition when the frozen basis has degraded. The position stage and the
 * speeds at the new state come from the step's last evaluation when it was made there (no
 * second position stage per step), else they are computed here. A new partition is a change
 * of coordinates on the same trajectory: the stepper continues with its step size, and with
 * the derivative in the new coordinates when it is known (v' is the same whichever speeds are
 * independent, so e''_new = v'[new independent speeds]). */
static int after_step_minimal(ap_sim *s, double t) {
  ap_data *d = s->d;
  int n = s->n, fresh = evaluated_at(s, t, s->y), rc;
  if (!fresh) {
    ap_drv_load_state(s, t, s->y);
    rc = ap_fwd_position(s->m, d);
    if (rc < 0) return ap_drv_fail(s, rc, "%s", d->msg);
    if (rc != AP_OK)
      return ap_drv_fail(s, AP_ERR_SINGULAR, "%s (at an accepted step; lower switch_growth)",
                         d->msg);
  }
  if (s->m->b == 0) return AP_OK;
  if (!fresh) ap_core_speeds(s->m, d);           /* v = B e' + b0 at the new state */
  s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(d, d->v));
  ap_drv_growth_cap(s, d->growth);
  if (d->growth <= s->def.switch_growth) return AP_OK;

  double old_growth = d->growth, *vdot = s->yev;
  int old_rank = d->rank;
  memcpy(s->v, d->v, sizeof(double) * (size_t)s->k);
  if (fresh) {                                   /* q', v' of the evaluation at this state */
    memcpy(s->ydot, d->qdot, sizeof(double) * (size_t)n);
    memcpy(vdot, d->vdot, sizeof(double) * (size_t)s->k);
  }
  s->ev_stamp = -1;                              /* yev holds v' now */
  int *old_perm = (int *)s->ytry;               /* k ints fit in the trial buffer */
  memcpy(old_perm, d->perm, sizeof(int) * (size_t)s->k);
  rc = ap_partition(s->m, d);
  if (rc == AP_OK && d->rank != old_rank)
    return ap_drv_fail(s, AP_ERR_RANK, "system '%s': the rank of A changed from %d to %d at "
                         "t = %.17g: the number of free speeds changed", s->m->name, old_rank,
                         d->rank, t);
  if (rc == AP_OK) rc = ap_fwd_position(s->m, d);
  if (rc < 0) return ap_drv_fail(s, rc, "%s", d->msg);
  if (rc != AP_OK || d->growth >= old_growth) { /* no better partition: keep the old one */
    memcpy(d->perm, old_perm, sizeof(int) * (size_t)s->k);
    return AP_OK;
  }
  for (int j = 0; j < d->l; j++) {
    s->y[n + j] = s->v[d->perm[d->rank + j]];
    if (fresh) s->ydot[n + j] = vdot[d->perm[d->rank + j]];
  }
  s->stats.partition_switches++;
  s->stats.restarts++;
  ap_drv_growth_cap(s, d->growth);
  rc = ap_step_restart(s->st, t, s->y, fresh ? s->ydot : NULL);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", ap_step_message(s->st));
}

/* CVODE's projection hook (projected mode): v onto A v + a0 = 0 nearest in g, and the error
 * estimate onto the tangent space, inside CVODE's step so its history stays consistent. */
int ap_drv_proj(double t, const double *y, double *corr, double *err, void *user) {
  ap_sim *s = user;
  ap_data *d = s->d;
  ap_drv_load_state(s, t, y);
  int rc = ap_fwd_position(s->m, d);
  double change = 0.0, *v = corr + s->n;
  memset(corr, 0, sizeof(double) * (size_t)s->n);
  memcpy(v, y + s->n, sizeof(double) * (size_t)s->k);
  if (rc == AP_OK) rc = ap_core_project_here(s->m, d, v, &change);
  if (rc != AP_OK) {
    s->rhs_status = rc;
    memcpy(s->rhs_msg, d->msg, sizeof s->rhs_msg);
    return rc > 0 ? 1 : -1;
  }
  for (int i = 0; i < s->k; i++) v[i] -= y[s->n + i];
  if (err) ap_core_project_tangent(s->m, d, err + s->n);
  s->stats.projections++;
  s->stats.max_projection = fmax(s->stats.max_projection, change);
  return 0;
}

/* Plain mode: nothing is projected; only the residual is recorded. */
static int after_step_plain(ap_sim *s, double t) {
  if (s->m->b == 0) return AP_OK;
  ap_drv_load_state(s, t, s->y);
  int rc = ap_fwd_position(s->m, s->d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", s->d->msg);
  s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(s->d, s->d->v));
  return AP_OK;
}

/* Projected mode: put v back on the constraint set, nearest in the metric g. One-step methods
 * project after every accepted step and restart (it costs them one evaluation); CVODE
 * projects inside its own step through ap_drv_proj (a restart would drop it to order 1). */
static int after_step_projected(ap_sim *s, double t) {
  ap_data *d = s->d;
  if (s->m->b == 0) return AP_OK;
  ap_drv_load_state(s, t, s->y);
  double change = 0.0, *v = s->y + s->n;
  int rc = ap_fwd_position(s->m, d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
  if (s->meth->backend == &ap_step_cvode) {   /* CVODE projected inside the step (ap_drv_proj) */
    s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(d, v));
    return AP_OK;
  }
  rc = ap_core_project_here(s->m, d, v, &change);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
  s->stats.projections++;
  s->stats.max_projection = fmax(s->stats.max_projection, change);
  s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(d, v));
  if (change == 0.0) return AP_OK;
  s->stats.restarts++;
  rc = ap_step_reset(s->st, t, s->y);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", ap_step_message(s->st));
}

/* DAE mode: IDA keeps q on phi = 0 itself (GGL rows), so nothing is corrected here and IDA's
 * state is never touched. The body model's checks of project_q run on the accepted q (a disk
 * or torus reaching lying flat stops the run); the velocity-constraint residual and |phi| are
 * recorded. */
int ap_drv_after_step_dae(ap_sim *s, double t) {
  ap_data *d = s->d;
  const ap_model *m = s->m;
  int nphi = m->ev.phi ? m->nphi : 0, rc = AP_OK;
  ap_drv_load_state(s, t, s->y);
  if (m->ev.check_q) rc = m->ev.check_q(m, d, s->y, ((ap_scratch *)d->internal)->ev);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
  if (m->b == 0 && nphi == 0) return AP_OK;
  d->basis = AP_BASIS_NONE;
  rc = ap_fwd_position(m, d);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  if (m->b > 0)
    s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(d, d->v));
  if (nphi == 0) return AP_OK;
  double *phi = s->ytry;                        /* free between steps */
  rc = m->ev.phi(m, d, ((ap_scratch *)d->internal)->ev, phi, NULL);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  for (int i = 0; i < nphi; i++) s->stats.max_phi = fmax(s->stats.max_phi, fabs(phi[i]));
  return AP_OK;
}

/* Rows redundant only on the holonomic manifold are not judged at trial states (they lie off
 * it); here, at the accepted and projected state, their residuals must be within
 * manifold_rtol. */
static int judge_redundant(ap_sim *s, double t) {
  ap_data *d = s->d;
  ap_drv_load_state(s, t, s->y);
  int rc = ap_fwd_position(s->m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(s->m, d);
  if (rc == AP_OK) rc = ap_core_judge_redundant(s->m, d);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
}

int ap_drv_after_step(ap_sim *s, double t) {
  int rc = project_coordinates(s, t);
  if (rc != AP_OK) return rc;
  switch (s->def.mode) {
    case AP_MODE_MINIMAL: rc = after_step_minimal(s, t); break;
    case AP_MODE_PLAIN: rc = after_step_plain(s, t); break;
    default: rc = after_step_projected(s, t); break;
  }
  return rc == AP_OK && s->d->redundant_manifold ? judge_redundant(s, t) : rc;
}

/* Condition of the solves at an output: warn (once) when cond * eps exceeds rtol, since the
 * requested accuracy is then out of reach of the linear algebra itself. */
static void check_condition(ap_sim *s) {
  const ap_data *d = s->d;
  int partitioned = s->def.mode == AP_MODE_MINIMAL && s->m->b > 0;
  double rc = partitioned ? fmin(d->rcond_G, d->rcond_R) : d->rcond_G;
  s->stats.min_rcond = fmin(s->stats.min_rcond, rc);
  if (s->warning[0] || rc * s->def.rtol >= DBL_EPSILON) return;
  const char *what = partitioned && d->rcond_R < d->rcond_G ? "the dependent-speed block R11"
                                                              : "G = B^T g B";
  snprintf(s->warning, sizeof s->warning, "system '%s': %s has condition number %.3g at "
           "t = %.17g; with rtol = %.3g the linear solves lose about %.0f digits, so results "
           "may miss the requested accuracy%s", s->m->name, what, 1.0 / rc, s->t,
           s->def.rtol, log10(1.0 / rc),
           s->def.mode == AP_MODE_PROJECTED ? " (the orthonormal basis inherits cond(g); "
           "minimal mode's partitioned basis may be better conditioned)" : "");
}

/* Evaluate the whole pipeline at the accepted state so ap_sim_data and q, v describe it. */
int ap_drv_evaluate_current(ap_sim *s) {
  s->d->basis = s->def.mode == AP_MODE_MINIMAL ? AP_BASIS_PARTITIONED : AP_BASIS_ORTHONORMAL;
  s->d->estimate_cond = 1;
  int rc = ap_drv_rhs(s->t, s->y, s->ytry, s);
  s->d->estimate_cond = 0;
  if (rc != 0) return ap_drv_fail(s, s->rhs_status, "%s", s->rhs_msg);
  check_condition(s);
  memcpy(s->q, s->d->q, sizeof(double) * (size_t)s->n);
  memcpy(s->v, s->d->v, sizeof(double) * (size_t)s->k);
  return AP_OK;
}
