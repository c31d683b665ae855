/* Simulation drivers: minimal, projected, plain and DAE modes (docs/design.md §1 "Choosing B",
 * "The DAE cross-check", §2).
 *
 * Minimal mode integrates y = (q, e') with the partitioned basis frozen during a step. After
 * every accepted step the driver looks at the growth max|R11^-1 R12| of the basis at the new
 * state; past def.switch_growth it re-partitions by pivoted QR and restarts the stepper from
 * e'_new = the new independent speeds. The velocity constraints hold to round-off throughout.
 *
 * Projected mode integrates y = (q, v) with the orthonormal basis and, after every accepted
 * step, replaces v by its nearest point on A v + a0 = 0 in the metric g, then restarts the
 * stepper from the projected state.
 *
 * DAE mode hands y = (q, v, lambda, mu) to IDA (dae.c) from consistent values of the Appell
 * solve; after each IDA step it only checks (lying flat) and records residuals, never
 * touching IDA's state.
 *
 * The stepper (lib/integrate/stepper.h) stops exactly at each requested output time. A failed
 * ap_sim_advance leaves (t, q, v) at the last accepted step. The right-hand side and the work
 * after each accepted step, per mode, are in sim_step.c. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/body.h"
#include "core/defcheck.h"
#include "integrate/sim_int.h"
#include "linalg/linalg.h"
#include "model/model.h"

int ap_drv_fail(ap_sim *s, int status, const char *fmt, ...) {
       va_list ap;
  va_start(ap, fmt);
  vsnprintf(s->msg, sizeof s->msg, fmt, ap);
  va_end(ap);
  return status;
}

ap_sim_def ap_sim_def_default(void) {
  ap_sim_def def;
  memset(&def, 0, sizeof def);
  def.mode = AP_MODE_MINIMAL;
  def.method = "dopri5";
  def.rtol = 1e-8;
  def.atol = 1e-10;
  def.h_fixed = 1e-3;
  def.max_steps = 1000000;
  def.rank_rtol = 1e-10;
  def.switch_growth = 2.0;
  def.init_tol = 1e-6;
  def.internal_check = AP_DEF_CHECK;
  return def;
}


/* ---- creation ----------------------------------------------------------------------------- */

static int check_def(ap_sim *s, const ap_sim_def *def) {
  if (def->internal_check != AP_DEF_CHECK)
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_def " AP_DEF_NOT_DEFAULT("ap_sim_def"));
  if (def->mode != AP_MODE_MINIMAL && def->mode != AP_MODE_PROJECTED &&
      def->mode != AP_MODE_DAE && def->mode != AP_MODE_PLAIN)
    return ap_drv_fail(s, AP_ERR_ARG, "unknown mode %d", (int)def->mode);
  s->meth = ap_step_method_find(def->mode == AP_MODE_DAE ? "bdf" : def->method ? def->method : "");
  if (!s->meth)
    return ap_drv_fail(s, AP_ERR_ARG, "unknown method '%s' (see ap_method_get for the list)",
                         def->method ? def->method : "(null)");
  if (def->mode == AP_MODE_DAE && s->m->ops)   /* the tree path forms no g or A */
    return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "system '%s' is on the tree path, which forms "
                         "no g or A: the DAE mode needs the dense path (path: dense)",
                         s->m->name);
  if (def->mode == AP_MODE_PROJECTED && s->meth->backend == &ap_step_cvode &&
      !ap_step_native_projection(s->meth))
    return ap_drv_fail(s, AP_ERR_UNSUPPORTED, "method '%s' cannot run in projected mode: CVODE "
                         "projects only with BDF (use method 'bdf', an ERK method, or minimal "
                         "mode)", s->meth->name);
  if (!(def->rtol > 0) || !(def->atol > 0))
    return ap_drv_fail(s, AP_ERR_ARG, "tolerances must be positive (rtol %g, atol %g)",
                         def->rtol, def->atol);
  if (!s->meth->adaptive && !(def->h_fixed > 0))
    return ap_drv_fail(s, AP_ERR_ARG, "method '%s' needs a positive h_fixed (got %g)",
                         s->meth->name, def->h_fixed);
  if (!(def->h_init >= 0 && def->h_init <= HUGE_VAL) ||
      !(def->h_max >= 0 && def->h_max <= HUGE_VAL))
    return ap_drv_fail(s, AP_ERR_ARG, "h_init and h_max must be >= 0 (0: none; got %g, %g)",
                       def->h_init, def->h_max);
  if (!(def->rank_rtol > 0 && def->rank_rtol < 1))
    return ap_drv_fail(s, AP_ERR_ARG, "rank_rtol = %g: the relative rank tolerance must lie in "
                       "(0, 1) (default 1e-10)", def->rank_rtol);
  if (!(def->switch_growth >= 1.0) || def->max_steps < 1 || !(def->init_tol > 0))
    return ap_drv_fail(s, AP_ERR_ARG, "switch_growth must be >= 1 (got %g), init_tol positive "
                         "(%g), max_steps >= 1 (%ld)", def->switch_growth, def->init_tol,
                         def->max_steps);
  return AP_OK;
}

/* "NaN", "+Inf" or "-Inf" for a value that is not finite (printf's "-nan" hides what it is). */
static const char *nonfinite(double x) { return isnan(x) ? "NaN" : x > 0 ? "+Inf" : "-Inf"; }

static int check_initial(ap_sim *s, double t0, const double *q0, const double *v0) {
  if (!isfinite(t0))
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_create: the initial time t0 is %s; it must be a "
                       "finite number", nonfinite(t0));
  for (int i = 0; i < s->n; i++)
    if (!isfinite(q0[i]))
      return ap_drv_fail(s, AP_ERR_ARG, "initial coordinate '%s' is %g",
                           ap_model_coord_name(s->m, i), q0[i]);
  for (int i = 0; i < s->k; i++)
    if (!isfinite(v0[i]))
      return ap_drv_fail(s, AP_ERR_ARG, "initial speed '%s' is %g", ap_model_speed_name(s->m, i),
                           v0[i]);
  return AP_OK;
}

static int setup(ap_sim *s, double t0, const double *q0, const double *v0) {
  int rc = check_initial(s, t0, q0, v0);
  ap_drv_pipeline_build(s);
  if (rc == AP_OK) rc = ap_data_create(s->m, &s->d);
  if (rc != AP_OK) return rc == AP_ERR_NOMEM ? ap_drv_fail(s, rc, "out of memory") : rc;
  s->d->rank_rtol = s->def.rank_rtol;
  /* Rows redundant only where the loops and wheel contacts close: judged at accepted states,
   * which lie off that manifold by the projection tolerance or, for CVODE, by up to a tenth of
   * the step tolerance (docs/vehicles.md "Redundant rows"). */
  s->d->manifold_rtol = 100 * (s->def.rtol + 1e-12);
  s->d->basis = s->def.mode == AP_MODE_MINIMAL ? AP_BASIS_PARTITIONED : AP_BASIS_ORTHONORMAL;
  rc = ap_drv_contacts_init(s, t0, q0, v0);       /* contact modes: before the projections */
  if (rc == AP_OK) rc = ap_drv_consistent_coordinates(s, t0, q0, s->q);  /* s->q: free until then */
  if (rc == AP_OK) rc = ap_drv_consistent_speeds(s, t0, s->q, v0, 1);
  if (rc != AP_OK) return rc;
  q0 = s->q;
  s->t = t0;
  memcpy(s->y, q0, sizeof(double) * (size_t)s->n);
  if (s->def.mode == AP_MODE_MINIMAL) {
    for (int j = 0; j < s->d->l; j++) s->y[s->n + j] = s->v[s->d->perm[s->d->rank + j]];
    s->ny = s->n + s->d->l;
  } else {
    memcpy(s->y + s->n, s->v, sizeof(double) * (size_t)s->k);
    s->ny = s->n + s->k;
  }
  /* Rows redundant only where the loops close are judged at accepted states, and the
   * assembled initial state is one: contradictory rows are refused here, not after the first
   * step, where the modes had already taken different initial accelerations from them (a
   * prescribed speed against a loop that locks its joint: tests/scenes/difftest/seed_400.yaml,
   * v' differed by 0.17 between minimal and projected mode). */
  rc = s->d->redundant_manifold ? ap_drv_judge_state(s, t0, s->y) : AP_OK;
  if (rc == AP_OK) rc = ap_drv_loop_rank_init(s);   /* then its stage joins the pipeline */
  if (rc == AP_OK) rc = ap_drv_evaluate_current(s);
  if (rc != AP_OK) return rc;
  ap_drv_pipeline_build(s);
  if (s->def.mode == AP_MODE_DAE) return ap_drv_setup_dae(s);
  return ap_drv_make_stepper(s, t0);
}

int ap_sim_create(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                  const double *v0, ap_sim **out, char *msg, size_t msg_len) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  if (!m || !def || !q0 || !v0) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_sim_create: NULL argument");
    return AP_ERR_ARG;
  }
  ap_sim *s = calloc(1, sizeof *s);
  size_t nk = (size_t)(m->n + m->k + m->b + (m->ev.phi ? m->nphi : 0));
  size_t nphi = (size_t)(m->ev.phi ? m->nphi : 0);
  double *buf = s ? calloc(4 * nk + 2 * (size_t)(m->n + m->k) + 1 + nphi, sizeof *buf) : NULL;
  if (!buf) {
    free(s);
    if (msg && msg_len) snprintf(msg, msg_len, "system '%s': out of memory", m->name);
    return AP_ERR_NOMEM;
  }
  s->m = m, s->n = m->n, s->k = m->k, s->b = m->b;
  s->stats.min_rcond = 1.0;
  s->y = buf, s->ytry = buf + nk, s->yev = buf + 2 * nk, s->ydot = buf + 3 * nk;
  s->q = buf + 4 * nk, s->v = s->q + m->n, s->ev_stamp = -1, s->growth_cap = INFINITY;
  s->t_ahead = INFINITY;
  s->phi = s->v + m->k;
  s->fail_state = s->phi + nphi;
  int rc = check_def(s, def);
  if (rc == AP_OK) {
    s->def = *def;
    s->def.method = def->mode == AP_MODE_DAE ? "ida" : s->meth->name;
    rc = setup(s, t0, q0, v0);
    if (rc == AP_OK) rc = ap_drv_contacts_events(s);
  }
  if (rc != AP_OK) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s", s->msg);
    ap_sim_free(s);
    return rc;
  }
  *out = s;
  return AP_OK;
}

void ap_sim_free(ap_sim *s) {
  if (!s) return;
  ap_step_free(s->st);
  ap_dae_free(s->dae);
  ap_drv_events_free(s);
  ap_drv_loop_rank_free(s);
  ap_drv_ctrl_free(s);
  ap_drv_contacts_free(s);
  ap_data_free(s->d);
  free(s->gn);
  free(s->gn_iwork);
  free(s->wt);
  free(s->y);
  free(s);
}

/* ---- advancing ----------------------------------------------------------------------------- */

/* A motor, spring or damper of a body model, or NULL: the usual source of stiffness. */
static const ap_meff *stiff_effect(const ap_model *m) {
  if (!ap_model_is_body_model(m)) return NULL;
  const ap_bmodel *M = ap_bm(m);
  for (int i = 0; i < M->ne; i++) {
    const ap_effect_def *e = &M->effs[i].def;
    if (e->kind == AP_EFFECT_MOTOR || e->kind == AP_EFFECT_JOINT_DAMPING ||
        (e->kind == AP_EFFECT_SPRING && (e->stiffness > 0 || e->damping > 0)))
      return &M->effs[i];
  }
  return NULL;
}

/* Did the failing evaluation's state grow far past the last accepted one (more than 1e3 times
 * its largest entry, and 1e3)? A function of the model (a scene expression) that is not
 * finite at a state like the accepted one is no sign of stiffness: fly.angle^0.5 once the
 * angle is negative, a drive past its domain. */
static int grown(const ap_sim *s) {
  double ref = 1.0, big = 0.0;
  for (int i = 0; i < s->ny; i++) ref = fmax(ref, fabs(s->y[i]));
  for (int i = 0; i < s->n; i++) big = fmax(big, fabs(s->d->q[i]));
  for (int i = 0; i < s->k; i++) big = fmax(big, fabs(s->d->v[i]));
  return !(big <= 1e3 * ref);
}

/* A failed step (status rc, message in s->msg): when the integrator gave up (max_steps, the step
 * size collapsed) or the solution blew up with an explicit or Adams method on a model with a
 * motor, spring or damper, append the hint to try BDF. The status is unchanged. */
static int stiff_hint(ap_sim *s, int rc) {
  int diverged = rc == AP_ERR_SOLVER || (rc == AP_ERR_NAN && (s->rhs_diverged || grown(s)));
  const ap_meff *e = diverged ? stiff_effect(s->m) : NULL;
  if (!e || s->dae || strcmp(s->meth->name, "bdf") == 0) return rc;
  const char *kind = e->def.kind == AP_EFFECT_MOTOR ? "motor"
                     : e->def.kind == AP_EFFECT_SPRING ? "spring" : "damper";
  size_t len = strlen(s->msg);
  snprintf(s->msg + len, sizeof s->msg - len, "; the model has the %s '%s': large gains make "
           "it stiff, which explicit methods such as %s can only follow in tiny steps: try "
           "--method bdf (simulation.method: bdf)", kind, e->name, s->meth->name);
  return rc;
}

/* tout must be a finite time at or after the current one. */
static int check_tout(ap_sim *s, double tout) {
  if (!isfinite(tout))
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_advance: the output time tout is %s; it must be "
                       "a finite number", nonfinite(tout));
  if (!(tout >= s->t))
    return ap_drv_fail(s, AP_ERR_ARG, "ap_sim_advance: the output time tout = %.17g is before "
                       "the current time t = %.17g", tout, s->t);
  return AP_OK;
}

/* One step towards tout of the stepper or IDA; AP_OK or the failure with s->msg set. */
static int advance_one(ap_sim *s, double tout) {
  double t = s->t;
  s->rhs_status = AP_OK, s->rhs_diverged = 0;
  if (s->dae) {
    int rc = ap_dae_one(s->dae, ap_drv_stop_time(s, tout), &t, s->ytry);
    if (rc != AP_OK) return ap_drv_fail(s, rc, "%s", ap_dae_message(s->dae));
    rc = ap_drv_after_step(s, &t);
    if (rc != AP_OK && rc != AP_STOPPED) return s->failed = rc;   /* IDA went on; we cannot */
    s->t = t;
    memcpy(s->y, s->ytry, sizeof(double) * (size_t)s->ny);
    return rc;
  }
  int rc = ap_step_one(s->st, ap_drv_stop_time(s, tout), &t, s->ytry);
  if (rc != AP_OK) {
    if (s->rhs_status < 0) return stiff_hint(s, ap_drv_fail(s, s->rhs_status, "%s", s->rhs_msg));
    return stiff_hint(s, ap_drv_fail(s, rc, "%s%s%s", ap_step_message(s->st),
                                     s->rhs_status > 0 ? "; last right-hand-side failure: " : "",
                                     s->rhs_status > 0 ? s->rhs_msg : ""));
  }
  rc = ap_drv_judge_trial(s, t);   /* a failure keeps the state of the last step */
  if (rc != AP_OK) return rc;
  s->t = t;
  memcpy(s->y, s->ytry, sizeof(double) * (size_t)s->ny);
  rc = ap_drv_after_step(s, &t);
  s->t = t;                                      /* a stop or switch event moved it back */
  return rc;
}

/* The stepper's last step size (0 in DAE mode). */
static double last_h(const ap_sim *s) {
  if (s->dae) return 0.0;
  ap_step_stats st;
  ap_step_get_stats(s->st, &st);
  return fabs(st.h_last);
}

/* max_steps reached short of tout. When the step size kept shrinking (the last step below
 * half the one at half of max_steps: near a pole of a drive, h falls like the square of the
 * distance left), raising max_steps is the wrong advice: say that the equations may be
 * singular ahead. A stiff model keeps a small but steady step and gets the stiffness hint. */
static int max_steps_failure(ap_sim *s, double t_start, double tout, double h_mid) {
  double h = last_h(s);
  if (h > 0 && h < 0.5 * h_mid)
    return ap_drv_fail(s, AP_ERR_SOLVER, "system '%s': max_steps = %ld steps from t = %.17g "
                       "reached only t = %.17g, short of the output time %.17g, with a step "
                       "size that kept shrinking (%.3g at half of them, %.3g at the end): the "
                       "equations may be singular ahead (a drive, force or set-point with a "
                       "pole?); check them before raising max_steps", s->m->name,
                       s->def.max_steps, t_start, s->t, tout, h_mid, h);
  return stiff_hint(s, ap_drv_fail(s, AP_ERR_SOLVER, "system '%s': max_steps = %ld steps "
                                   "from t = %.17g reached only t = %.17g, short of the "
                                   "output time %.17g (raise max_steps, in a scene "
                                   "simulation.max_steps)", s->m->name, s->def.max_steps,
                                   t_start, s->t, tout));
}

/* A failed advance: keep the state of the model's last evaluation (where an expression may
 * be at fault: ap_sim_failed_state), then evaluate the last accepted state so that
 * ap_sim_time, ap_sim_q, ap_sim_v and ap_sim_data describe one state. The failure's message
 * stays; so does its status when that evaluation fails too. */
static int advance_failed(ap_sim *s, int rc) {
  const ap_data *d = s->d;
  s->fail_state[0] = d->t;
  memcpy(s->fail_state + 1, d->q, sizeof(double) * (size_t)s->n);
  memcpy(s->fail_state + 1 + s->n, d->v, sizeof(double) * (size_t)s->k);
  s->has_fail = 1;
  rc = ap_drv_loop_rank_failed(s, rc);   /* a failure at a bifurcation of the loops */
  char msg[sizeof s->msg];
  memcpy(msg, s->msg, sizeof msg);
  ap_drv_evaluate_current(s);
  memcpy(s->msg, msg, sizeof msg);
  return rc;
}

int ap_sim_failed_state(const ap_sim *s, double *t, const double **q, const double **v) {
  if (!s || !s->has_fail) return AP_ERR_ARG;
  if (t) *t = s->fail_state[0];
  if (q) *q = s->fail_state + 1;
  if (v) *v = s->fail_state + 1 + s->n;
  return AP_OK;
}

int ap_sim_advance(ap_sim *s, double tout) {
  if (!s) return AP_ERR_ARG;
  if (s->failed) return s->failed;              /* s->msg still says why */
  int rc = check_tout(s, tout);
  if (rc == AP_OK) rc = ap_drv_inputs_before_advance(s);
  if (rc != AP_OK) return rc;
  s->has_fail = 0;
  double t_start = s->t, h_mid = 0.0;
  for (long steps = 0; s->t < tout; steps++) {
    int stop = s->poll ? s->poll(s->t, s->poll_user) : 0;
    if (stop) {
      rc = ap_drv_evaluate_current(s);
      return rc != AP_OK ? rc : ap_drv_fail(s, AP_ERR_INTERRUPTED, "interrupted at t = %.17g "
                                            "(the poll function returned %d)", s->t, stop);
    }
    if (steps == s->def.max_steps / 2) h_mid = last_h(s);
    if (steps >= s->def.max_steps)
      return advance_failed(s, max_steps_failure(s, t_start, tout, h_mid));
    rc = advance_one(s, tout);
    if (rc == AP_STOPPED) break;
    if (rc != AP_OK) return advance_failed(s, rc);
  }
  int ev = ap_drv_evaluate_current(s);
  return ev != AP_OK ? ev : rc;
}

/* ---- queries ------------------------------------------------------------------------------ */

double ap_sim_time(const ap_sim *s) { return s ? s->t : NAN; }
const double *ap_sim_q(const ap_sim *s) { return s ? s->q : NULL; }
const double *ap_sim_v(const ap_sim *s) { return s ? s->v : NULL; }
const ap_data *ap_sim_data(const ap_sim *s) { return s ? s->d : NULL; }
const char *ap_sim_message(const ap_sim *s) { return s ? s->msg : ""; }
const char *ap_sim_warning(const ap_sim *s) { return s ? s->warning : ""; }

void ap_sim_set_poll(ap_sim *s, ap_sim_poll_fn poll, void *user) {
  if (!s) return;
  s->poll = poll, s->poll_user = user;
}

int ap_sim_reactions(ap_sim *s, const double **lambda) {
  if (!s) return AP_ERR_ARG;
  if (s->dae) {   /* IDA's own multipliers: the cross-check compares them with Appell's */
    if (lambda) *lambda = s->y + s->n + s->k;
    return AP_OK;
  }
  int rc = ap_fwd_reactions(s->m, s->d);   /* the pipeline holds the current state */
  if (rc != AP_OK) return ap_drv_fail(s, rc, "%s", s->d->msg);
  if (lambda) *lambda = s->d->lambda;
  return AP_OK;
}

void ap_sim_get_stats(const ap_sim *s, ap_sim_stats *st) {
  if (!st) return;
  if (!s) {
    memset(st, 0, sizeof *st);
    return;
  }
  ap_step_stats ss;
  if (s->dae) ap_dae_stats(s->dae, &ss);
  else ap_step_get_stats(s->st, &ss);
  *st = s->stats;
  st->steps = ss.steps;
  st->rhs_evals = ss.rhs_evals;
  st->err_fails = ss.err_fails;
  st->rhs_fails = ss.rhs_fails;
}

/* ---- methods ------------------------------------------------------------------------------ */

static int fill_info(const ap_step_method *meth, ap_method_info *info) {
  if (!meth || !info) return AP_ERR_ARG;
  info->name = meth->name;
  info->summary = meth->summary;
  info->order = meth->order;
  info->adaptive = meth->adaptive;
  info->rtol_floor = ap_step_rtol_floor(meth->name);
  return AP_OK;
}

int ap_method_count(void) { return ap_step_method_count(); }
int ap_method_get(int i, ap_method_info *info) {
  if (i < 0 || i >= ap_step_method_count()) return AP_ERR_ARG;
  return fill_info(ap_step_method_get(i), info);
}
int ap_method_find(const char *name, ap_method_info *info) {
  return fill_info(name ? ap_step_method_find(name) : NULL, info);
}
