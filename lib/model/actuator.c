/* Joint forces and motors: generalized forces on one joint speed, and the inputs they read.
 *
 * A joint force or motor effect adds tau to Q_i, i the global index of the speed v_i it acts
 * on. That is the generalized force of a torque (or force) tau along the joint's motion column,
 * acting on the child and -tau on the parent: its virtual power is tau (w_child - w_parent) .
 * axis = tau v_i (for a revolute joint; likewise for every column of every kind), with no
 * component on any other speed (docs/bodies.md "Joint forces and motors"):
 *
 *   joint force     tau = F                                    F = state_fn(t, x), value_fn(t)
 *   motor, rate     tau = sat(kd (s - v_i))                        or value; s likewise
 *   motor, angle    tau = sat(kp (s - q_i) + kd (s' - v_i))    s' = d value_fn / dt, else 0
 *   sat(u)          = max(-M, min(M, u)),  M = max_effort
 *
 * The inputs x of a state function are gathered from q and v through indices resolved at
 * compile time (in_idx, in_v), in the order declared. Partial derivatives of tau follow by the
 * chain rule from the function's own partials df; while saturated they vanish.
 * An input may also be a body quantity (AP_STATE_BODY: position, velocity, angles, angular
 * velocity; body_qty.c), read from the kinematics the stages left in the scratch (both paths
 * run the velocity stage before the effects).
 * Invariant: ap_act_force reads only t, q, v and those kinematics; it runs none itself.
 * Generic in the scalar (model/model.h; actuator_cs.c): in the complex-step build a state
 * function is called at the real parts of its inputs with df asked for, and its value becomes
 * F + sum_i dF/dx_i (x_i - Re x_i), the exact first-order continuation (the imaginary parts of
 * a complex step are first order); time functions give real values. Compile and the public
 * partials are double build only. */
#include <stdlib.h>
#include <string.h>

#include "model/builder.h"
#include "model/setpoint.h"
#ifndef AP_SC_COMPLEX
#include "model/tree_model.h"
#endif

/* ---- compile ------------------------------------------------------------------------------ */
#ifndef AP_SC_COMPLEX

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

static const char *what(const ap_effect_def *d) {
  return d->kind == AP_EFFECT_MOTOR ? "motor" : "joint force";
}

/* Input i of the state function: joint, kind of scalar, local index -> global index. */
static int resolve_input(ap_builder *b, const ap_bmodel *M, ap_meff *ef, int i) {
  const ap_state_input *in = &ef->def.inputs[i];
  const char *nm = ef->name;
  if (in->speed == AP_STATE_BODY) {
    if (in->joint < 0 || in->joint >= M->nb || in->index < 0 || in->index >= AP_BODY_QTY_COUNT)
      FAIL("effect '%s': input %d reads quantity %d of body %d (%d bodies, %d quantities)", nm,
           i, in->index, in->joint, M->nb, AP_BODY_QTY_COUNT);
    ef->in_idx[i] = in->joint * AP_BODY_QTY_COUNT + in->index, ef->in_v[i] = AP_STATE_BODY;
    return AP_OK;
  }
  if (in->speed != 0 && in->speed != 1)
    FAIL("effect '%s': input %d has speed = %d (0: a coordinate, 1: a speed, %d: a body "
         "quantity)", nm, i, in->speed, AP_STATE_BODY);
  if (in->joint < 0 || in->joint >= M->nj)
    FAIL("effect '%s': input %d reads joint %d, which does not exist (%d joints)", nm, i,
         in->joint, M->nj);
  const ap_mjoint *J = &M->joints[M->joint_topo[in->joint]];
  int count = in->speed ? J->nv : J->nq;
  if (in->index < 0 || in->index >= count)
    FAIL("effect '%s': input %d reads %s %d of joint '%s', which has %d (a %s joint)", nm, i,
         in->speed ? "speed" : "coordinate", in->index, J->name, count,
         ap_joint_kind_name(J->kind));
  int g = in->speed ? J->vidx[in->index] : J->qidx[in->index];
  if (g < 0)
    FAIL("effect '%s': input %d reads %s '%s' of joint '%s', which is driven (a function of "
         "time, not part of the state): use that function instead", nm, i,
         in->speed ? "speed" : "coordinate",
         in->speed ? ap_joint_speed_name(J->kind, in->index)
                   : ap_joint_coord_name(J->kind, in->index),
         J->name);
  ef->in_idx[i] = g, ef->in_v[i] = in->speed != 0;
  return AP_OK;
}

static int check_motor(ap_builder *b, const ap_mjoint *J, ap_meff *ef) {
  const ap_effect_def *d = &ef->def;
  const char *nm = ef->name;
  if (d->motor != AP_MOTOR_RATE && d->motor != AP_MOTOR_ANGLE)
    FAIL("effect '%s': unknown motor mode %d", nm, (int)d->motor);
  if (!(d->kp >= 0) || !(d->kd >= 0) || !isfinite(d->kp + d->kd))
    FAIL("effect '%s': motor gains kp %g and kd %g must be finite and >= 0", nm, d->kp, d->kd);
  if (!(d->max_effort > 0))
    FAIL("effect '%s': motor max_effort %g must be positive (HUGE_VAL for no limit)", nm,
         d->max_effort);
  if (d->motor == AP_MOTOR_RATE) {
    if (!(d->kd > 0)) FAIL("effect '%s': a rate motor needs kd > 0 (got %g)", nm, d->kd);
    if (d->kp != 0)
      FAIL("effect '%s': a rate motor has no angle to hold: kp must be 0 (got %g)", nm, d->kp);
    return AP_OK;
  }
  if (d->speed >= J->ndrivable)
    FAIL("effect '%s': speed '%s' of the %s joint '%s' is not the rate of a coordinate, so an "
         "angle motor cannot hold it (use a rate motor)", nm,
         ap_joint_speed_name(J->kind, d->speed), ap_joint_kind_name(J->kind), J->name);
  if (!(d->kp + d->kd > 0)) FAIL("effect '%s': an angle motor needs kp > 0 or kd > 0", nm);
  ef->qcol = J->qidx[d->speed];   /* not driven: it is driven together with its speed */
  return AP_OK;
}

int ap_act_compile(ap_builder *b, const ap_bmodel *M, ap_meff *ef) {
  const ap_effect_def *d = &ef->def;
  const char *nm = ef->name;
  ef->qcol = -1, ef->index = (int)(ef - M->effs);
  if (d->joint < 0 || d->joint >= M->nj)
    FAIL("effect '%s': joint %d does not exist (%d joints)", nm, d->joint, M->nj);
  const ap_mjoint *J = &M->joints[M->joint_topo[d->joint]];
  if (d->speed < 0 || d->speed >= J->nv)
    FAIL("effect '%s': the %s joint '%s' has %d speeds, not speed %d", nm,
         ap_joint_kind_name(J->kind), J->name, J->nv, d->speed);
  if (J->vidx[d->speed] < 0)
    FAIL("effect '%s': speed '%s' of joint '%s' is driven (eliminated from the state): a %s "
         "on it has no degree of freedom to act on (remove the drive or the effect)", nm,
         ap_joint_speed_name(J->kind, d->speed), J->name, what(d));
  ef->col = J->vidx[d->speed];
  if (!isfinite(d->value)) FAIL("effect '%s': value %g is not finite", nm, d->value);
  if (d->ninputs < 0 || d->ninputs > AP_STATE_MAX_INPUTS)
    FAIL("effect '%s': %d inputs (0 to %d allowed)", nm, d->ninputs, AP_STATE_MAX_INPUTS);
  if (d->ninputs > 0 && !d->state_fn)
    FAIL("effect '%s': %d inputs declared but no state_fn to read them", nm, d->ninputs);
  for (int i = 0; i < d->ninputs; i++) {
    int rc = resolve_input(b, M, ef, i);
    if (rc != AP_OK) return rc;
  }
  return d->kind == AP_EFFECT_MOTOR ? check_motor(b, J, ef) : AP_OK;
}
#endif

/* ---- evaluation --------------------------------------------------------------------------- */

static int callback_fail(const ap_model *m, ap_data *d, const ap_meff *ef, const char *fn,
                         int rc, double t) {
  AP_BM_MSG(d, "model '%s': effect '%s': the %s %s (returned %d) at t = %.17g", m->name,
            ef->name, fn, rc > 0 ? "asked for a smaller step" : "failed", rc, t);
  return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
}

static int not_finite(const ap_model *m, ap_data *d, const ap_meff *ef, const char *fn,
                      double t) {
  AP_BM_MSG(d, "model '%s': effect '%s': the %s gave a non-finite value at t = %.17g", m->name,
            ef->name, fn, t);
  return AP_ERR_NAN;
}

/* Input i of the state function at (q, v): a coordinate, a speed or a body quantity. */
static ap_sc input(const ap_model *m, ap_data *d, const ap_meff *ef, int i, const ap_sc *q,
                   const ap_sc *v) {
  int g = ef->in_idx[i];
  if (ef->in_v[i] != AP_STATE_BODY) return ef->in_v[i] ? v[g] : q[g];
#ifdef AP_SC_COMPLEX
  const ap_bmodel *M = ap_bm(m);
#else
  const ap_bmodel *M = ap_tree_layout(m);
#endif
  return ap_bq_value(M, ap_bm_scratch(d), g / AP_BODY_QTY_COUNT, g % AP_BODY_QTY_COUNT);
}

#ifdef AP_SC_COMPLEX
/* The state function's q and v: the real parts, in the data's n-vector scratch (2n doubles,
 * which the complex-step stages leave unused; n >= k for a body model). */
static void real_state(const ap_model *m, ap_data *d, const ap_sc *q, const ap_sc *v,
                       const double **qr, const double **vr) {
  double *buf = (double *)((ap_scratch *)d->internal)->tn;
  for (int i = 0; i < m->n; i++) buf[i] = SC_RE(q[i]);
  for (int i = 0; i < m->k; i++) buf[m->n + i] = SC_RE(v[i]);
  *qr = buf, *vr = buf + m->n;
}

/* f = F(Re x) + sum_i dF/dx_i (x_i - Re x_i): the state function's value continued to the
 * complex inputs through its exact partials (AP_ERR_UNSUPPORTED when it gives none). */
static int state_cs(const ap_model *m, ap_data *d, const ap_meff *ef, double t, const ap_sc *q,
                    const ap_sc *v, ap_sc *f) {
  const ap_effect_def *e = &ef->def;
  double x[AP_STATE_MAX_INPUTS], df[1 + AP_STATE_MAX_INPUTS], f0 = 0.0;
  const double *qr, *vr;
  ap_sc xc[AP_STATE_MAX_INPUTS];
  for (int i = 0; i < e->ninputs; i++) xc[i] = input(m, d, ef, i, q, v), x[i] = SC_RE(xc[i]);
  for (int i = 0; i <= e->ninputs; i++) df[i] = NAN;
  real_state(m, d, q, v, &qr, &vr);
  ap_state_args a = {t, x, e->ninputs, qr, vr};
  int rc = e->state_fn(&a, &f0, df, e->user);
  if (rc != 0) return callback_fail(m, d, ef, "state function", rc, t);
  if (!isfinite(f0)) return not_finite(m, d, ef, "state function", t);
  *f = f0;
  for (int i = 0; i < e->ninputs; i++) {
    if (!isfinite(df[1 + i])) {
      AP_BM_MSG(d, "model '%s': effect '%s': its state function gives no finite partial "
                "derivative df[%d] (%g) at t = %.17g, which the complex-step evaluation needs",
                m->name, ef->name, 1 + i, df[1 + i], t);
      return AP_ERR_UNSUPPORTED;
    }
    *f += df[1 + i] * (xc[i] - SC_RE(xc[i]));
  }
  return AP_OK;
}
#endif

/* The value F (joint force) or set-point s (motor): f[0], and f[1], f[2] its first and second
 * time derivatives when it is a function of time alone (0 otherwise). With df (1 + ninputs
 * entries; double build), the partial derivatives: the state function's, or df[0] = f[1] for a
 * function of time (0 for a constant). */
static int source(const ap_model *m, ap_data *d, const ap_meff *ef, double t, const ap_sc *q,
                  const ap_sc *v, ap_sc f[3], double *df) {
  const ap_effect_def *e = &ef->def;
  f[0] = e->value, f[1] = f[2] = 0.0;
  if (df) memset(df, 0, (size_t)(1 + e->ninputs) * sizeof *df);
#ifndef AP_SC_COMPLEX
  const double *in = ((const ap_scratch *)d->internal)->setpoint_in;
  if (in && !isnan(in[ef->index])) return f[0] = in[ef->index], AP_OK;   /* an input, held */
#endif
  if (e->state_fn) {
#ifdef AP_SC_COMPLEX
    return state_cs(m, d, ef, t, q, v, f);
#else
    double x[AP_STATE_MAX_INPUTS];
    for (int i = 0; i < e->ninputs; i++) x[i] = input(m, d, ef, i, q, v);
    ap_state_args a = {t, x, e->ninputs, q, v};
    int rc = e->state_fn(&a, &f[0], df, e->user);
    if (rc != 0) return callback_fail(m, d, ef, "state function", rc, t);
    int ok = isfinite(f[0]);
    for (int i = 0; df && i <= e->ninputs; i++) ok = ok && isfinite(df[i]);
    return ok ? AP_OK : not_finite(m, d, ef, "state function", t);
#endif
  }
  if (!e->value_fn) return AP_OK;
  double fv[3] = {e->value, 0.0, 0.0};   /* a function of the real time */
  int rc = e->value_fn(t, fv, e->user);
  if (rc != 0) return callback_fail(m, d, ef, "value function", rc, t);
  if (!isfinite(fv[0]) || !isfinite(fv[1]) || !isfinite(fv[2]))
    return not_finite(m, d, ef, "value function", t);
  f[0] = fv[0], f[1] = fv[1], f[2] = fv[2];
  if (df) df[0] = fv[1];
  return AP_OK;
}

/* tau from the source value; *sat = 1 when the motor's limit holds it (the decision is taken
 * on the real part: a saturated torque is constant). */
static ap_sc law(const ap_meff *ef, const ap_sc *q, const ap_sc *v, const ap_sc f[3],
                 int *sat) {
  const ap_effect_def *e = &ef->def;
  *sat = 0;
  if (e->kind == AP_EFFECT_JOINT_FORCE) return f[0];
  ap_sc u = e->motor == AP_MOTOR_RATE
                ? e->kd * (f[0] - v[ef->col])
                : e->kp * (f[0] - q[ef->qcol]) + e->kd * (f[1] - v[ef->col]);
  if (SC_MAG(u) > e->max_effort) *sat = 1, u = copysign(e->max_effort, SC_RE(u));
  return u;
}

int ap_act_force(const ap_model *m, ap_data *d, const ap_meff *ef, double t, const ap_sc *q,
                 const ap_sc *v, ap_sc *Q) {
  ap_sc f[3];
  int sat, rc = source(m, d, ef, t, q, v, f, NULL);
  if (rc != AP_OK) return rc;
  Q[ef->col] += law(ef, q, v, f, &sat);
  return AP_OK;
}

/* ---- partial derivatives -------------------------------------------------------------------- */
#ifndef AP_SC_COMPLEX

/* dtau = g dF + (the PD law's own terms); g = 1 (joint force), kd (rate), kp (angle). */
static void chain(const ap_meff *ef, const double f[3], const double *df, double *dq,
                  double *dv, double *dt) {
  const ap_effect_def *e = &ef->def;
  int motor = e->kind == AP_EFFECT_MOTOR, angle = motor && e->motor == AP_MOTOR_ANGLE;
  double g = !motor ? 1.0 : angle ? e->kp : e->kd;
  for (int i = 0; i < e->ninputs; i++) (ef->in_v[i] ? dv : dq)[ef->in_idx[i]] += g * df[1 + i];
  *dt = g * df[0] + (angle ? e->kd * f[2] : 0.0);
  if (motor) dv[ef->col] -= e->kd;
  if (angle) dq[ef->qcol] -= e->kp;
}

int ap_body_actuator_partials(const ap_model *m, ap_data *d, int effect, int *col, double *tau,
                              double *dtau_dq, double *dtau_dv, double *dtau_dt) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || effect < 0 ||
      effect >= ap_bm(m)->ne)
    return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(m);
  const ap_meff *ef = &M->effs[effect];
  if (ef->def.kind != AP_EFFECT_JOINT_FORCE && ef->def.kind != AP_EFFECT_MOTOR) return AP_ERR_ARG;
  for (int i = 0; i < ef->def.ninputs; i++)
    if (ef->in_v[i] == AP_STATE_BODY) {
      AP_BM_MSG(d, "model '%s': effect '%s' reads a body quantity (input %d): its partial "
                "derivatives come from the complex-step evaluation (ap_linearize), not from "
                "this function", m->name, ef->name, i);
      return AP_ERR_UNSUPPORTED;
    }
  double f[3], df[1 + AP_STATE_MAX_INPUTS], *dq = calloc((size_t)M->n + (size_t)M->k + 1,
                                                        sizeof *dq);
  if (!dq) return AP_ERR_NOMEM;
  double *dv = dq + M->n, dt = 0.0;
  int sat, rc = source(m, d, ef, d->t, d->q, d->v, f, df);
  double u = rc == AP_OK ? law(ef, d->q, d->v, f, &sat) : 0.0;
  if (rc == AP_OK && !sat) chain(ef, f, df, dq, dv, &dt);
  if (rc == AP_OK) {
    if (col) *col = ef->col;
    if (tau) *tau = u;
    if (dtau_dq) memcpy(dtau_dq, dq, (size_t)M->n * sizeof *dq);
    if (dtau_dv) memcpy(dtau_dv, dv, (size_t)M->k * sizeof *dv);
    if (dtau_dt) *dtau_dt = dt;
  }
  free(dq);
  return rc;
}

/* ---- set-points as inputs (setpoint.h) ------------------------------------------------------ */

static const ap_meff *motor_of(const ap_model *m, int e) {
  if (!m || !ap_model_is_body_model(m) || e < 0 || e >= ap_bm(m)->ne) return NULL;
  const ap_meff *ef = &ap_bm(m)->effs[e];
  return ef->def.kind == AP_EFFECT_MOTOR ? ef : NULL;
}

int ap_act_effect_count(const ap_model *m) {
  return m && ap_model_is_body_model(m) ? ap_bm(m)->ne : 0;
}

double ap_act_setpoint_value(const ap_model *m, int e) {
  const ap_meff *ef = motor_of(m, e);
  return ef ? ef->def.value : 0.0;
}

int ap_act_find_setpoint(const ap_model *m, const char *name) {
  static const char suffix[] = ".setpoint";
  size_t len = name ? strlen(name) : 0, ls = sizeof suffix - 1;
  if (len <= ls || strcmp(name + len - ls, suffix) != 0) return -1;
  for (int e = 0; e < ap_act_effect_count(m); e++) {
    const ap_meff *ef = motor_of(m, e);
    if (ef && strlen(ef->name) == len - ls && strncmp(ef->name, name, len - ls) == 0)
      return ef->def.value_fn || ef->def.state_fn ? -1 : e;
  }
  return -1;
}

int ap_act_setpoint_gain(const ap_model *m, ap_data *d, int e, int *col, double *g) {
  const ap_meff *ef = motor_of(m, e);
  if (!ef || !ap_core_data_ok(m, d)) return AP_ERR_ARG;
  double f[3];
  int sat, rc = source(m, d, ef, d->t, d->q, d->v, f, NULL);
  if (rc != AP_OK) return rc;
  (void)law(ef, d->q, d->v, f, &sat);
  *col = ef->col;
  *g = sat ? 0.0 : ef->def.motor == AP_MOTOR_RATE ? ef->def.kd : ef->def.kp;
  return AP_OK;
}
#endif
