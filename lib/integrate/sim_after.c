/* The work after each accepted step, as one pipeline of named stages called in a fixed order
 * (docs/architecture.md "After a step"). The stages of a simulation are chosen once, by mode,
 * when it is created (ap_drv_pipeline_build) and again when an event is added:
 *
 *   minimal     events, [loop rank], coordinates, partition, redundant rows, event state
 *   projected   events, coordinates, projection, redundant rows, event state
 *   plain       events, coordinates, residual, redundant rows, event state
 *   DAE         events, DAE checks, DAE rows, event state
 *
 * and, once inputs are declared (sim_input.c), "controller" before "event state": at a
 * controller instant it calls the controller and restarts the stepper from the step's state.
 *
 * events (event.c) runs first, on the step exactly as the stepper made it, so that its dense
 * output still describes the step; when it cuts the step at a stop or switch event it moves
 * the time back to the event and the later stages work there. It is in the list only when the
 * simulation has events: without them nothing of it is evaluated; neither is event state,
 * which keeps the state the next step starts from (a cut steps again from it). coordinates
 * puts q back on
 * its manifold (body models); partition re-chooses the minimal mode's independent speeds when
 * the frozen basis degraded; projection puts v back on A v + a0 = 0; residual records it
 * (plain mode); redundant rows judges the consistency of dropped rows at the accepted state.
 * The DAE stages check IDA's state without touching it, and choose IDA's kept rows again when
 * they degraded. The coming contact-mode switches are one more stage after events.
 * Each stage works on s->y (steppers) or s->ytry (IDA) at *t and returns AP_OK, AP_STOPPED
 * (a stop event: the other stages still run) or a failure (the pipeline ends there). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "appell/body.h"
#include "integrate/sim_int.h"

/* DAE mode: IDA keeps q on phi = 0 itself (GGL rows), so nothing is corrected here and IDA's
 * state is never touched. The body model's checks of project_q run on the accepted q (a disk
 * or torus reaching lying flat stops the run); the velocity-constraint residual (all rows) and
 * |phi| are recorded. With redundant rows (IDA keeps only the independent ones chosen at t0)
 * the orthonormal basis stage judges, as in projected mode, that the rank has not changed and
 * that the dropped rows' a0 and gamma stay consistent (rows redundant only where the loops and
 * wheel contacts close: against manifold_rtol, ap_core_judge_redundant). */
static int dropped_phi_rows(ap_sim *s, double t, const double *phi);

static int stage_dae_checks(ap_sim *s, double *tp) {
  double t = *tp;
  ap_data *d = s->d;
  const ap_model *m = s->m;
  int nphi = m->ev.phi ? m->nphi : 0, rc = AP_OK;
  int redundant = m->b > 0 && ap_dae_rows(s->dae, NULL) < m->b;
  ap_drv_load_state(s, t, s->ytry);
  if (m->ev.check_q) rc = m->ev.check_q(m, d, s->ytry, ((ap_scratch *)d->internal)->ev);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
  if (m->b == 0 && nphi == 0) return AP_OK;
  d->basis = redundant ? AP_BASIS_ORTHONORMAL : AP_BASIS_NONE;
  rc = ap_fwd_position(m, d);
  if (rc == AP_OK && redundant && d->rank != ap_dae_rows(s->dae, NULL))
    return ap_drv_fail(s, AP_ERR_RANK, "system '%s': the rank of A changed from %d to %d at "
                       "t = %.17g (DAE mode keeps the independent rows chosen at the start)",
                       m->name, ap_dae_rows(s->dae, NULL), d->rank, t);
  if (rc == AP_OK && redundant) rc = ap_fwd_velocity(m, d);
  if (rc == AP_OK && redundant) rc = ap_core_judge_redundant(m, d);   /* of the manifold */
  d->basis = AP_BASIS_NONE;
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  if (m->b > 0)
    s->stats.max_residual = fmax(s->stats.max_residual, ap_constraint_residual(d, d->v));
  if (nphi == 0) return AP_OK;
  double *phi = s->phi;
  rc = m->ev.phi(m, d, ((ap_scratch *)d->internal)->ev, phi, NULL);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  for (int i = 0; i < nphi; i++) s->stats.max_phi = fmax(s->stats.max_phi, fabs(phi[i]));
  return dropped_phi_rows(s, t, phi);
}

/* ---- DAE mode: redundant rows --------------------------------------------------------------- */

/* Dropped rows of phi must stay closed (within init_tol). */
static int dropped_phi_rows(ap_sim *s, double t, const double *phi) {
  const ap_model *m = s->m;
  int nphi = m->ev.phi ? m->nphi : 0;
  const int *kept = NULL;
  int nk = ap_dae_phi_rows(s->dae, &kept);
  for (int i = 0, c = 0; i < nphi && nk < nphi; i++) {   /* dropped rows of phi: consistent? */
    if (c < nk && kept[c] == i) {
      c++;
      continue;
    }
    if (fabs(phi[i]) > s->def.init_tol)
      return ap_drv_fail(s, AP_ERR_INCONSISTENT, "system '%s': an implicit holonomic row dropped "
                         "as redundant at the start (row %d of phi) is open by %.3g at t = %.17g, "
                         "more than init_tol %.3g: the loop closures became inconsistent",
                         m->name, i, phi[i], t, s->def.init_tol);
  }
  return AP_OK;
}

double ap_drv_dae_h0(const ap_sim *s, const double *q, const double *vdot) {
  double qmax = 0.0, amax = 0.0, rt = ap_dae_rtol(s->def.rtol);
  double at = s->def.atol * rt / s->def.rtol;
  for (int i = 0; i < s->n; i++) qmax = fmax(qmax, fabs(q[i]));
  for (int i = 0; i < s->k; i++) amax = fmax(amax, fabs(vdot[i]));
  return amax > 0 ? sqrt(2.0 * (rt * fmax(1.0, qmax) + at) / amax) : 0.0;
}

/* With redundant rows: when the kept ones degraded (ap_dae_review_rows), restart IDA at the
 * accepted state (s->ytry) put on every row, from the Appell solve there, with the new choice. */
static int stage_dae_rows(ap_sim *s, double *tp) {
  double t = *tp;
  const ap_model *m = s->m;
  ap_data *d = s->d;
  int nphi = m->ev.phi ? m->nphi : 0;
  if (ap_dae_rows(s->dae, NULL) == m->b && ap_dae_phi_rows(s->dae, NULL) == nphi) return AP_OK;
  ap_drv_load_state(s, t, s->ytry);
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_dae_review_rows(s->dae, s->def.rank_rtol);
  if (rc <= 0) return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", d->msg);
  rc = ap_drv_dae_onto_rows(s, t, s->ytry);   /* the newly kept rows hold (sim_restart.c) */
  if (rc != AP_OK) return rc;
  d->basis = AP_BASIS_ORTHONORMAL;   /* the Appell solve gives q', v' */
  rc = ap_forward(m, d);
  d->basis = AP_BASIS_NONE;
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  rc = ap_dae_restart(s->dae, t, s->ytry, d->qdot, d->vdot, ap_drv_dae_h0(s, s->ytry, d->vdot));
  if (rc != AP_OK) return ap_drv_fail(s, rc, "%s", ap_dae_message(s->dae));
  ap_dae_state(s->dae, s->ytry);
  s->stats.restarts++;
  return AP_OK;
}


/* ---- the pipeline ---------------------------------------------------------------------------- */

static const ap_drv_stage stage_events = {"events", ap_drv_stage_events};
static const ap_drv_stage stage_coords = {"coordinates", ap_drv_stage_coordinates};
static const ap_drv_stage stage_partition = {"partition", ap_drv_stage_partition};
static const ap_drv_stage stage_projection = {"projection", ap_drv_stage_projection};
static const ap_drv_stage stage_residual = {"residual", ap_drv_stage_residual};
static const ap_drv_stage stage_redundant = {"redundant rows", ap_drv_stage_redundant};
static const ap_drv_stage stage_dae = {"DAE checks", stage_dae_checks};
static const ap_drv_stage stage_rows = {"DAE rows", stage_dae_rows};
static const ap_drv_stage stage_event_state = {"event state", ap_drv_stage_event_state};
static const ap_drv_stage stage_controller = {"controller", ap_drv_stage_controller};
static const ap_drv_stage stage_contacts = {"contact modes", ap_drv_stage_contacts};
static const ap_drv_stage stage_loop_rank = {"loop rank", ap_drv_stage_loop_rank};

void ap_drv_pipeline_build(ap_sim *s) {
  int n = 0;
  if (s->ev) s->stages[n++] = &stage_events;   /* made by the first ap_sim_add_event */
  if (s->cm) s->stages[n++] = &stage_contacts;   /* contact modes (contact_modes.c) */
  if (s->lr) s->stages[n++] = &stage_loop_rank;  /* models with loops (sim_rank.c) */
  switch (s->def.mode) {
    case AP_MODE_DAE:
      s->stages[n++] = &stage_dae;
      s->stages[n++] = &stage_rows;
      break;
    case AP_MODE_MINIMAL:
      s->stages[n++] = &stage_coords;
      s->stages[n++] = &stage_partition;
      s->stages[n++] = &stage_redundant;
      break;
    case AP_MODE_PLAIN:
      s->stages[n++] = &stage_coords;
      s->stages[n++] = &stage_residual;
      s->stages[n++] = &stage_redundant;
      break;
    default:
      s->stages[n++] = &stage_coords;
      s->stages[n++] = &stage_projection;
      s->stages[n++] = &stage_redundant;
      break;
  }
  if (s->ctrl) s->stages[n++] = &stage_controller;   /* after ap_sim_declare_inputs */
  if (s->ev) s->stages[n++] = &stage_event_state;
  s->nstages = n;
}

int ap_drv_after_step(ap_sim *s, double *t) {
  int stopped = 0;
  for (int i = 0; i < s->nstages; i++) {
    int rc = s->stages[i]->run(s, t);
    if (rc == AP_STOPPED) stopped = 1;
    else if (rc != AP_OK) return rc;
  }
  return stopped ? AP_STOPPED : AP_OK;
}
