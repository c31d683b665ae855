/* Inputs and controllers of a simulation (include/appell/control.h, docs/control.md).
 *
 * An input j is a generalized force u_j on model speed speed[j]; the simulation keeps the
 * force vector tau (k entries, tau[speed[j]] = u_j), which the core's velocity stage adds to Q
 * (ap_scratch.input_Q): the inputs enter the Appell solve where the linearizer's B says they
 * do, and every mode (minimal, projected, DAE, the tree path) sees them.
 *
 * An input may also be a motor's set-point ("MOTOR.setpoint", model/setpoint.h): speed[j] is
 * then -1 - e (e the motor's effect index) and the value goes to sp[e], which the motor reads
 * in place of its own set-point (ap_scratch.setpoint_in); it starts at that set-point.
 *
 * Zero-order hold. A change of a value makes the right-hand side jump, so the stepper (or IDA)
 * is restarted at the current state (ap_drv_restart_state), either before the next advance
 * (ap_sim_set_input: pending) or at a controller instant. A controller is a stage of the
 * after-step pipeline (sim_after.c), after the stages that put the state back on its manifold
 * and before the events' "event state": at an accepted step that reached the next instant
 * t_c = t_set + j period (the driver stops the stepper there: ap_drv_stop_time) it evaluates
 * the pipeline at the step's state, calls the controller, checks its values and restarts.
 * Invariant: tau holds exactly the values in force since the last restart. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/control.h"
#include "integrate/sim_int.h"
#include "model/setpoint.h"

struct ap_sim_ctrl {
  int nu;
  int *speed;              /* (nu) model speed of each input, or -1 - e: motor e's set-point */
  char **names;            /* (nu) the input names */
  double *sp;              /* (effects) motor set-points in force; NaN: not an input */
  double *u;               /* (nu) the values in force */
  double *unew;            /* (nu) the controller's output before it is checked */
  double *tau;             /* (k) generalized forces: u scattered onto the speeds */
  double *ybuf;            /* (n + k + b + nphi) scratch: a right-hand side, q and v copies */
  int pending;             /* values changed since the last restart */
  ap_sim_controller_fn fn;
  void *user;
  double period, t_set;
  long j_next;             /* the next instant is t_set + j_next period */
};

static void ctrl_free(ap_sim_ctrl *c) {
  if (!c) return;
  for (int j = 0; c->names && j < c->nu; j++) free(c->names[j]);
  free(c->names), free(c->sp);
  free(c->speed), free(c->u), free(c->unew), free(c->tau), free(c->ybuf);
  free(c);
}

void ap_drv_ctrl_free(ap_sim *s) {
  if (s) ctrl_free(s->ctrl), s->ctrl = NULL;
}

static int speed_index(const ap_model *m, const char *name) {
  for (int i = 0; i < m->k; i++)
    if (strcmp(m->speed_names[i], name) == 0) return i;
  return -1;
}

/* Input name -> *idx: its speed index, or -1 - e for motor e's set-point; 0 when it is
 * neither. */
static int input_index(const ap_model *m, const char *name, int *idx) {
  int i = speed_index(m, name), e = i < 0 ? ap_act_find_setpoint(m, name) : -1;
  *idx = i >= 0 ? i : -1 - e;
  return i >= 0 || e >= 0;
}

/* The list checked: every name a speed or a motor's set-point, none twice. */
static int check_names(ap_sim *s, const char *const *names, int *nu) {
  const ap_model *m = s->m;
  int count = 0;
  for (; names[count]; count++) {
    int i;
    if (!input_index(m, names[count], &i)) {
      const char *near = ap_suggest(names[count], (const char *const *)m->speed_names, m->k);
      return ap_drv_fail(s, AP_ERR_ARG, "inputs: '%s' is not a speed of model '%s' nor "
                         "MOTOR.setpoint of a motor with a constant set-point%s%s%s",
                         names[count], m->name, near ? " (did you mean '" : "",
                         near ? near : "", near ? "'?)" : "");
    }
    for (int j = 0; j < count; j++)
      if (strcmp(names[j], names[count]) == 0)
        return ap_drv_fail(s, AP_ERR_ARG, "inputs: '%s' is listed twice", names[count]);
  }
  *nu = count;
  return AP_OK;
}

static ap_sim_ctrl *ctrl_alloc(const ap_sim *s, int nu) {
  ap_sim_ctrl *c = calloc(1, sizeof *c);
  size_t ny = (size_t)(s->n + s->k + s->b + (s->m->ev.phi ? s->m->nphi : 0));
  if (!c) return NULL;
  c->nu = nu;
  c->speed = calloc((size_t)nu + 1, sizeof *c->speed);
  c->u = calloc((size_t)nu + 1, sizeof *c->u);
  c->unew = calloc((size_t)nu + 1, sizeof *c->unew);
  c->tau = calloc((size_t)s->k + 1, sizeof *c->tau);
  c->ybuf = calloc(ny + (size_t)(s->n + s->k) + 1, sizeof *c->ybuf);
  c->names = calloc((size_t)nu + 1, sizeof *c->names);
  c->sp = calloc((size_t)ap_act_effect_count(s->m) + 1, sizeof *c->sp);
  if (c->speed && c->u && c->unew && c->tau && c->ybuf && c->names && c->sp) return c;
  ctrl_free(c);
  return NULL;
}

int ap_sim_declare_inputs(ap_sim *s, const char *const *names) {
  if (!s) return AP_ERR_ARG;
  if (!names) return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_declare_inputs: names is NULL");
  int nu = 0, rc = check_names(s, names, &nu);
  if (rc != AP_OK) return rc;
  ap_sim_ctrl *c = ctrl_alloc(s, nu);
  if (!c) return ap_drv_fail(s, AP_ERR_NOMEM, "ap_sim_declare_inputs: out of memory");
  for (int e = 0; e < ap_act_effect_count(s->m); e++) c->sp[e] = NAN;
  for (int j = 0; j < nu; j++) {
    input_index(s->m, names[j], &c->speed[j]);
    if (!(c->names[j] = malloc(strlen(names[j]) + 1)))
      return ctrl_free(c), ap_drv_fail(s, AP_ERR_NOMEM, "ap_sim_declare_inputs: out of memory");
    strcpy(c->names[j], names[j]);
    if (c->speed[j] < 0) {   /* a set-point starts at the motor's own */
      int e = -1 - c->speed[j];
      c->u[j] = c->sp[e] = ap_act_setpoint_value(s->m, e);
    }
  }
  c->pending = s->ctrl != NULL;   /* the old inputs' forces go away */
  ap_drv_ctrl_free(s);
  s->ctrl = c;
  ((ap_scratch *)s->d->internal)->input_Q = c->tau;
  ((ap_scratch *)s->d->internal)->setpoint_in = c->sp;
  ap_drv_pipeline_build(s);
  return AP_OK;
}

int ap_sim_input_count(const ap_sim *s) { return s && s->ctrl ? s->ctrl->nu : 0; }

const char *ap_sim_input_name(const ap_sim *s, int j) {
  if (!s || !s->ctrl || j < 0 || j >= s->ctrl->nu) return NULL;
  return s->ctrl->names[j];
}

int ap_sim_find_input(const ap_sim *s, const char *name) {
  for (int j = 0; name && j < ap_sim_input_count(s); j++)
    if (strcmp(ap_sim_input_name(s, j), name) == 0) return j;
  return -1;
}

const double *ap_sim_inputs(const ap_sim *s) {
  return s && s->ctrl && s->ctrl->nu > 0 ? s->ctrl->u : NULL;
}

/* u_j = x from now on (checked finite); a change leaves a restart pending. */
static int put(ap_sim *s, int j, double x, const char *who) {
  ap_sim_ctrl *c = s->ctrl;
  if (!isfinite(x))
    return ap_drv_fail(s, AP_ERR_NAN, "%s: input '%s' is %g at t = %.17g; an input must be "
                       "finite", who, ap_sim_input_name(s, j), x, s->t);
  if (x != c->u[j]) c->pending = 1;
  c->u[j] = x;
  if (c->speed[j] >= 0) c->tau[c->speed[j]] = x;
  else c->sp[-1 - c->speed[j]] = x;
  return AP_OK;
}

int ap_sim_set_input(ap_sim *s, const char *name, double value) {
  if (!s) return AP_ERR_ARG;
  int j = ap_sim_find_input(s, name);
  if (j >= 0) return put(s, j, value, "ap_sim_set_input");
  if (!s->ctrl || s->ctrl->nu == 0)
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_set_input: no input '%s': the simulation has "
                       "no inputs (declare them: ap_sim_declare_inputs, or the scene's "
                       "inputs: section)", name ? name : "(null)");
  const char **names = calloc((size_t)s->ctrl->nu, sizeof *names);
  for (int i = 0; names && i < s->ctrl->nu; i++) names[i] = ap_sim_input_name(s, i);
  const char *near = names && name ? ap_suggest(name, names, s->ctrl->nu) : NULL;
  int rc = ap_drv_fail(s, AP_ERR_ARG, "ap_sim_set_input: no input '%s' (the inputs are %s%s)%s%s%s",
                       name ? name : "(null)", ap_sim_input_name(s, 0),
                       s->ctrl->nu > 1 ? ", ..." : "", near ? "; did you mean '" : "",
                       near ? near : "", near ? "'?" : "");
  free(names);
  return rc;
}

int ap_sim_set_inputs(ap_sim *s, const double *u) {
  if (!s) return AP_ERR_ARG;
  if (!u) return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_set_inputs: u is NULL");
  for (int j = 0; j < ap_sim_input_count(s); j++)
    if (!isfinite(u[j])) return put(s, j, u[j], "ap_sim_set_inputs");   /* nothing changed */
  for (int j = 0; j < ap_sim_input_count(s); j++) put(s, j, u[j], "ap_sim_set_inputs");
  return AP_OK;
}

int ap_sim_set_controller(ap_sim *s, ap_sim_controller_fn fn, double period, void *user) {
  if (!s) return AP_ERR_ARG;
  if (fn && (!s->ctrl || s->ctrl->nu == 0))
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_set_controller: the simulation has no inputs "
                       "(declare them first: ap_sim_declare_inputs, or the scene's inputs:)");
  if (fn && !(period > 0 && isfinite(period)))
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_set_controller: the period must be a finite "
                       "number > 0 (got %g)", period);
  if (!s->ctrl) return AP_OK;   /* removing none */
  ap_sim_ctrl *c = s->ctrl;
  c->fn = fn, c->user = user, c->period = period, c->t_set = s->t, c->j_next = 0;
  ap_drv_pipeline_build(s);
  return AP_OK;
}

/* ---- the driver's side ------------------------------------------------------------------- */

static double next_instant(const ap_sim_ctrl *c) {
  return c->t_set + (double)c->j_next * c->period;
}

double ap_drv_stop_time(const ap_sim *s, double tout) {
  double t = s->t, stop = s->t_ahead > t ? fmin(tout, s->t_ahead) : tout;
  if (s->ctrl && s->ctrl->fn) {
    double tc = next_instant(s->ctrl);
    if (tc > t) stop = fmin(stop, tc);
  }
  return stop;
}

/* The instant t_c is reached at t when t is past it or within 4 ulps of it. */
static int due(const ap_sim_ctrl *c, double t) {
  double tc = next_instant(c);
  return c->fn && t >= tc - 4.0 * 2.220446049250313e-16 * fmax(fabs(tc), 1.0);
}

/* The controller at (t, y), the state of an accepted step: evaluate there (the simulation's
 * q, v, data and time describe it while fn runs), call fn, check its values. */
static int call_controller(ap_sim *s, double t, const double *y) {
  ap_sim_ctrl *c = s->ctrl;
  ap_data *d = s->d;
  ap_basis keep = d->basis;
  d->basis = s->def.mode == AP_MODE_MINIMAL ? AP_BASIS_PARTITIONED : AP_BASIS_ORTHONORMAL;
  int rc = s->dae || !ap_drv_evaluated_at(s, t, y) ? ap_drv_rhs(t, y, c->ybuf, s) : 0;
  d->basis = keep;
  if (rc != 0) return ap_drv_fail(s, s->rhs_status ? s->rhs_status : AP_ERR_SOLVER, "%s",
                                  s->rhs_msg);
  s->t = t;
  memcpy(s->q, d->q, sizeof(double) * (size_t)s->n);
  memcpy(s->v, d->v, sizeof(double) * (size_t)s->k);
  memcpy(c->unew, c->u, sizeof(double) * (size_t)c->nu);
  int ret = c->fn(t, s->q, s->v, c->unew, c->user);
  if (ret != 0)
    return ap_drv_fail(s, AP_ERR_CALLBACK, "the controller returned %d at t = %.17g: stopped",
                       ret, t);
  for (int j = 0; j < c->nu; j++)
    if (!isfinite(c->unew[j]))
      return ap_drv_fail(s, AP_ERR_NAN, "the controller gave input '%s' = %g at t = %.17g; an "
                         "input must be finite", ap_sim_input_name(s, j), c->unew[j], t);
  for (int j = 0; j < c->nu; j++) put(s, j, c->unew[j], "controller");
  c->j_next = (long)floor((t - c->t_set) / c->period + 1e-9) + 1;
  return AP_OK;
}

/* Restart at the accepted state (t, q, v) of the simulation when values changed: a stepper
 * continues from the same state with the new f (ap_step_jump: its step size kept); IDA is
 * restarted from the Appell solve there (its q', v' jumped). */
static int restart_if_pending(ap_sim *s, double t) {
  ap_sim_ctrl *c = s->ctrl;
  if (!c->pending) return AP_OK;
  c->pending = 0;
  s->ev_inputs_old = 1;   /* the data's evaluation had the old inputs (its position stage holds) */
  if (s->dae) s->ev_stamp = -1;
  if (!s->dae) {
    int rc = ap_step_jump(s->st, t, s->y);
    s->stats.restarts++;
    return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "%s", ap_step_message(s->st));
  }
  double *q = c->ybuf + s->n + s->k + s->b + (s->m->ev.phi ? s->m->nphi : 0), *v = q + s->n;
  memcpy(q, s->q, sizeof(double) * (size_t)s->n);
  memcpy(v, s->v, sizeof(double) * (size_t)s->k);
  return ap_drv_restart_state(s, t, q, v);
}

int ap_drv_stage_controller(ap_sim *s, double *t) {
  if (!s->ctrl || !due(s->ctrl, *t)) return AP_OK;
  int rc = call_controller(s, *t, s->dae ? s->ytry : s->y);
  return rc == AP_OK ? restart_if_pending(s, *t) : rc;
}

int ap_drv_inputs_before_advance(ap_sim *s) {
  if (!s->ctrl || (!s->ctrl->pending && !due(s->ctrl, s->t))) return AP_OK;
  int rc = due(s->ctrl, s->t) ? call_controller(s, s->t, s->y) : AP_OK;   /* at t_set */
  if (rc == AP_OK) rc = restart_if_pending(s, s->t);
  if (rc == AP_OK && s->dae) memcpy(s->y, s->ytry, sizeof(double) * (size_t)s->ny);
  return rc == AP_OK ? ap_drv_evaluate_current(s) : rc;   /* with the new values */
}
