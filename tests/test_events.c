/* Events (include/appell/event.h) against closed forms.
 *
 * 1. Event times: the knife edge on an inclined plane (docs/references.md §1, a nonholonomic
 *    constraint with an exact solution) reaching y = Y, located in every mode and with every
 *    stepper family, against the root of the exact y(t) (bisection on the closed form to
 *    machine precision). The error of a located time is the dense output's state error over
 *    the event's rate: it is bounded per family below, at rtol 1e-12.
 * 2. The rules, on the oscillator x'' = -x, x = cos t: crossings logged at pi/2 + j pi;
 *    a falling-only event; an event zero at the start that does not fire there (v = -sin t
 *    fires first at pi); two events at one time both reported; the first of two stop events
 *    wins and the other is found on the next advance; a switch hook (an elastic bounce at
 *    x = 0: the motion becomes |cos t|); events of t alone (of_time) hit to their 4-ulp
 *    bracket, a log, a switch (a bounce in time) and a stop; the argument checks. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "refsys.h"

/* ---- the oscillator ----------------------------------------------------------------------- */

static int osc_metric(double t, const double *q, double *g, void *user) {
  (void)t, (void)q, (void)user;
  g[0] = 1.0;
  return 0;
}

static int osc_force(double t, const double *q, const double *v, double *Q, void *user) {
  (void)t, (void)v, (void)user;
  Q[0] = -q[0];
  return 0;
}

static ap_model *osc_model;   /* shared by the oscillator tests; freed at the end */

static ap_model *oscillator(void) {
  if (osc_model) return osc_model;
  ap_system_def def = ap_system_def_default();
  def.name = "oscillator", def.n = 1, def.k = 1;
  def.metric = osc_metric, def.force = osc_force, def.bias_source = AP_BIAS_ZERO;
  ap_model *m = NULL;
  AP_CHECK(ap_model_from_system(&def, &m, NULL, 0) == AP_OK);
  return osc_model = m;
}

/* e = scale (q[0] - level) or, with level NAN, e = v[0]. */
typedef struct lin_ev {
  double scale, level;
} lin_ev;

static int ev_x(double t, const double *q, const double *v, const ap_data *d, void *user,
                double *f) {
  (void)t, (void)d;
  const lin_ev *e = user;
  *f = isnan(e->level) ? v[0] : e->scale * (q[0] - e->level);
  return 0;
}

static ap_sim *osc_sim(ap_mode mode, const char *method, double rtol) {
  ap_model *m = oscillator();
  ap_sim_def def = ap_sim_def_default();
  def.mode = mode, def.method = method, def.rtol = rtol, def.atol = rtol;
  double q0 = 1.0, v0 = 0.0;
  ap_sim *s = NULL;
  char msg[256];
  int rc = ap_sim_create(m, &def, 0.0, &q0, &v0, &s, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "create: %s\n", msg);
  AP_CHECK(rc == AP_OK);
  return s;
}

static void osc_free(ap_sim *s) { ap_sim_free(s); }

static int add(ap_sim *s, const char *name, lin_ev *e, int dir, int action) {
  ap_event_def ev = ap_event_def_default();
  ev.name = name, ev.fn = ev_x, ev.user = e, ev.direction = dir, ev.action = action;
  return ap_sim_add_event(s, &ev);
}

/* Logged crossings of x = 0 at pi/2 + j pi; falling only at pi/2 + 2 j pi. */
static void test_log(const char *method) {
  ap_model *m = oscillator();
  ap_sim_def def = ap_sim_def_default();
  def.method = method, def.rtol = def.atol = 1e-12;
  double q0 = 1.0, v0 = 0.0;
  ap_sim *s = NULL;
  AP_CHECK(ap_sim_create(m, &def, 0.0, &q0, &v0, &s, NULL, 0) == AP_OK);
  lin_ev zero = {1.0, 0.0}, speed = {1.0, NAN};
  AP_CHECK(add(s, "x0", &zero, AP_EVENT_EITHER, AP_EVENT_LOG) == AP_OK);
  AP_CHECK(add(s, "x0_falling", &zero, AP_EVENT_FALLING, AP_EVENT_LOG) == AP_OK);
  AP_CHECK(add(s, "v0", &speed, AP_EVENT_EITHER, AP_EVENT_LOG) == AP_OK);
  AP_CHECK(ap_sim_advance(s, 10.0) == AP_OK);
  int nx = 0, nf = 0, nv = 0, n = ap_sim_event_count(s);
  double worst = 0.0;
  for (int i = 0; i < n; i++) {
    ap_event_record r;
    AP_CHECK(ap_sim_event_get(s, i, &r) == AP_OK);
    if (strcmp(r.name, "x0") == 0) {
      worst = fmax(worst, fabs(r.t - (RS_PI / 2 + nx * RS_PI)));
      AP_CHECK_EQ_INT(r.direction, nx % 2 ? 1 : -1);
      nx++;
    } else if (strcmp(r.name, "x0_falling") == 0) {
      worst = fmax(worst, fabs(r.t - (RS_PI / 2 + 2 * nf * RS_PI)));
      nf++;
    } else {   /* v = -sin t: 0 at the start does not fire; pi, 2 pi, 3 pi */
      nv++;
      worst = fmax(worst, fabs(r.t - nv * RS_PI));
      AP_CHECK_NEAR(r.v[0], 0.0, 1e-9);
    }
    AP_CHECK_NEAR(r.q[0], cos(r.t), 1e-10);
  }
  printf("%-9s logged x = 0, v = 0 over 10 s: %d + %d + %d crossings, worst time error %.2e\n",
         method, nx, nf, nv, worst);
  AP_CHECK_EQ_INT(nx, 3);
  AP_CHECK_EQ_INT(nf, 2);
  AP_CHECK_EQ_INT(nv, 3);
  AP_CHECK_LE(worst, 1e-10 * 10.0);
  ap_event_record r;
  AP_CHECK(ap_sim_event_get(s, n, &r) == AP_ERR_ARG);
  AP_CHECK(ap_sim_event_get(s, -1, &r) == AP_ERR_ARG);
  ap_sim_free(s);
}

/* Stop events: the first wins; two at one time both reported; the run goes on after. */
static void test_stop(void) {
  ap_model *m = oscillator();
  ap_sim_def def = ap_sim_def_default();
  def.method = "dop853", def.rtol = def.atol = 1e-12, def.h_init = 2.0;
  double q0 = 1.0, v0 = 0.0;
  ap_sim *s = NULL;
  AP_CHECK(ap_sim_create(m, &def, 0.0, &q0, &v0, &s, NULL, 0) == AP_OK);
  lin_ev half = {1.0, 0.5}, zero = {1.0, 0.0}, zero2 = {2.0, 0.0};
  AP_CHECK(add(s, "zero", &zero, AP_EVENT_EITHER, AP_EVENT_STOP) == AP_OK);
  AP_CHECK(add(s, "half", &half, AP_EVENT_FALLING, AP_EVENT_STOP) == AP_OK);
  AP_CHECK(add(s, "zero2", &zero2, AP_EVENT_EITHER, AP_EVENT_STOP) == AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 3.0), AP_STOPPED);
  AP_CHECK_NEAR(ap_sim_time(s), RS_PI / 3, 1e-10);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 0.5, 1e-10);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 3.0), AP_STOPPED);
  AP_CHECK_NEAR(ap_sim_time(s), RS_PI / 2, 1e-10);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 3);   /* zero and zero2, at one time */
  ap_event_record a, b;
  AP_CHECK(ap_sim_event_get(s, 1, &a) == AP_OK && ap_sim_event_get(s, 2, &b) == AP_OK);
  AP_CHECK(strcmp(a.name, "zero") == 0 && strcmp(b.name, "zero2") == 0);
  AP_CHECK(a.t == b.t && a.t == ap_sim_time(s));
  AP_CHECK_EQ_INT(ap_sim_advance(s, 3.0), AP_OK);   /* nothing more before 3 */
  AP_CHECK_NEAR(ap_sim_q(s)[0], cos(3.0), 1e-10);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 3);
  ap_sim_free(s);
}

/* An elastic bounce at x = 0: v -> -v, so x(t) = |cos t|. */
static int bounce(const ap_event_record *ev, double *q, double *v, void *user) {
  (void)ev, (void)q, (void)user;
  v[0] = -v[0];
  return 0;
}

static void test_switch(ap_mode mode, const char *method) {
  ap_sim *s = osc_sim(mode, method, 1e-12);
  lin_ev zero = {1.0, 0.0};
  ap_event_def ev = ap_event_def_default();
  ev.name = "floor", ev.fn = ev_x, ev.user = &zero, ev.action = AP_EVENT_SWITCH;
  ev.on_switch = bounce, ev.direction = AP_EVENT_FALLING;
  AP_CHECK(ap_sim_add_event(s, &ev) == AP_OK);
  double worst = 0.0;
  for (int i = 1; i <= 100; i++) {
    double t = 0.1 * i;
    AP_CHECK_EQ_INT(ap_sim_advance(s, t), AP_OK);
    worst = fmax(worst, fabs(ap_sim_q(s)[0] - fabs(cos(t))));
  }
  printf("%-9s bounce x = |cos t| to t = 10: %d bounces, max |x - |cos t|| %.2e\n", method,
         ap_sim_event_count(s), worst);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 3);
  AP_CHECK_LE(worst, 1e-9);
  osc_free(s);
}

/* Events of t alone (of_time): e = t - level; the stepper stops just before each. */
static int ev_time(double t, const double *q, const double *v, const ap_data *d, void *user,
                   double *f) {
  (void)q, (void)v, (void)d;
  *f = t - *(const double *)user;
  return 0;
}

static void test_of_time(const char *method, ap_mode mode) {
  ap_sim *s = osc_sim(mode, method, 1e-12);
  static const double at[3] = {0.75, 1.5, 2.0};
  const char *names[3] = {"log", "switch", "stop"};
  for (int i = 0; i < 3; i++) {
    ap_event_def ev = ap_event_def_default();
    ev.name = names[i], ev.fn = ev_time, ev.user = (void *)&at[i], ev.of_time = 1;
    ev.action = i == 0 ? AP_EVENT_LOG : i == 1 ? AP_EVENT_SWITCH : AP_EVENT_STOP;
    ev.on_switch = i == 1 ? bounce : NULL;   /* v -> -v at t = 1.5 */
    AP_CHECK(ap_sim_add_event(s, &ev) == AP_OK);
  }
  AP_CHECK_EQ_INT(ap_sim_advance(s, 3.0), AP_STOPPED);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 3);
  for (int i = 0; i < 3 && i < ap_sim_event_count(s); i++) {
    ap_event_record r;
    AP_CHECK(ap_sim_event_get(s, i, &r) == AP_OK && strcmp(r.name, names[i]) == 0);
    AP_CHECK_NEAR(r.t, at[i], 4 * DBL_EPSILON * at[i]);   /* the bracket of 4 ulps */
  }
  /* after the bounce at 1.5: x = cos(3 - t), the mirror image in time */
  AP_CHECK_NEAR(ap_sim_time(s), 2.0, 4 * DBL_EPSILON * 2.0);
  AP_CHECK_NEAR(ap_sim_q(s)[0], cos(1.0), 1e-10);
  ap_sim_free(s);
}

static void test_args(void) {
  ap_sim *s = osc_sim(AP_MODE_MINIMAL, "dopri5", 1e-8);
  ap_event_def ev = ap_event_def_default();
  AP_CHECK(ap_sim_add_event(s, &ev) == AP_ERR_ARG);   /* no function */
  AP_CHECK(strstr(ap_sim_message(s), "fn") != NULL);
  lin_ev zero = {1.0, 0.0};
  ev.fn = ev_x, ev.user = &zero, ev.action = AP_EVENT_SWITCH;
  AP_CHECK(ap_sim_add_event(s, &ev) == AP_ERR_ARG);   /* no hook */
  ev.action = 7;
  AP_CHECK(ap_sim_add_event(s, &ev) == AP_ERR_ARG);
  AP_CHECK(ap_sim_add_event(NULL, &ev) == AP_ERR_ARG);
  AP_CHECK(ap_sim_add_event(s, NULL) == AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_sim_event_count(NULL), 0);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 0);
  AP_CHECK(strcmp(ap_strerror(AP_STOPPED), "stopped by an event") == 0);
  osc_free(s);
}

/* ---- the knife edge ---------------------------------------------------------------------- */

static const double knife_Y = 1.0;

static int ev_knife_y(double t, const double *q, const double *v, const ap_data *d, void *user,
                      double *f) {
  (void)t, (void)v, (void)d, (void)user;
  *f = q[1] - knife_Y;
  return 0;
}

/* The exact time y(t) = Y by bisection on the closed form (y rises through Y once there). */
static double knife_exact_time(const rs_knife *p, const double *q0, const double *v0, double a,
                               double b) {
  for (int i = 0; i < 200 && b - a > 0; i++) {
    double m = 0.5 * (a + b), q[3];
    if (m <= a || m >= b) break;
    rs_knife_exact(p, q0, v0, m, q, NULL, NULL);
    if (q[1] < knife_Y) a = m;
    else b = m;
  }
  return b;
}

static void test_knife(ap_mode mode, const char *method, double bound) {
  rs_knife p = {1.0, 0.1, 9.81, 0.3};
  ap_system_def sys;
  rs_knife_system(&p, &sys);
  ap_model *m = NULL;
  AP_CHECK(ap_model_from_system(&sys, &m, NULL, 0) == AP_OK);
  double q0[3], v0[3];
  rs_knife_initial(0.0, 0.0, 0.2, 1.0, 2.0, q0, v0);
  ap_sim_def def = ap_sim_def_default();
  def.mode = mode, def.method = method, def.rtol = 1e-12, def.atol = 1e-12;
  ap_sim *s = NULL;
  char msg[512];
  int rc = ap_sim_create(m, &def, 0.0, q0, v0, &s, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  AP_CHECK(rc == AP_OK);
  ap_event_def ev = ap_event_def_default();
  ev.name = "y=1", ev.fn = ev_knife_y, ev.direction = AP_EVENT_RISING;
  AP_CHECK(s && ap_sim_add_event(s, &ev) == AP_OK);
  rc = s ? ap_sim_advance(s, 20.0) : AP_ERR_ARG;
  AP_CHECK_EQ_INT(rc, AP_STOPPED);
  double te = ap_sim_time(s), tx = knife_exact_time(&p, q0, v0, 0.0, te + 1.0);
  ap_event_record r;
  AP_CHECK(ap_sim_event_get(s, 0, &r) == AP_OK && r.t == te && r.direction == 1);
  double err = fabs(te - tx) / tx;
  printf("knife %-9s %-8s event time %.15f, exact %.15f, relative error %.2e (bound %.0e)\n",
         mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_PROJECTED ? "projected" : "dae",
         method, te, tx, err, bound);
  AP_CHECK_LE(err, bound);
  AP_CHECK_NEAR(r.q[1], knife_Y, 1e-9);
  ap_sim_free(s);
  ap_model_free(m);
}

int main(void) {
  test_args();
  test_log("dop853");
  test_log("dopri5");
  test_log("adams");
  test_stop();
  test_switch(AP_MODE_MINIMAL, "dop853");
  test_switch(AP_MODE_PROJECTED, "verner6");
  test_switch(AP_MODE_DAE, "ida");
  test_of_time("dop853", AP_MODE_MINIMAL);
  test_of_time("dopri5", AP_MODE_PROJECTED);
  test_of_time("bdf", AP_MODE_MINIMAL);
  test_of_time("ida", AP_MODE_DAE);
  /* Event-time bounds at rtol 1e-12 (relative): the crossing located on the dense output, then
   * stepped to with the method itself and refined by regula falsi on its own states
   * (event.c), so every family reaches the step tolerance: measured 1.2e-14 .. 9.3e-12. */
  const char *methods[] = {"dop853", "dopri5", "verner6", "fehlberg8", "bdf"};
  for (int i = 0; i < 5; i++) {
    test_knife(AP_MODE_MINIMAL, methods[i], 1e-10);
    test_knife(AP_MODE_PROJECTED, methods[i], 1e-10);
  }
  test_knife(AP_MODE_MINIMAL, "adams", 1e-10);   /* CVODE projects only with BDF */
  test_knife(AP_MODE_DAE, "ida", 1e-10);
  ap_model_free(osc_model);
  return ap_check_finish("events");
}
