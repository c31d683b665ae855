/* The Whipple bicycle with tyre friction (docs/vehicles.md "The bicycle with tyre friction"):
 * examples/scenes/bicycle_turn.yaml, the benchmark bicycle at 4.6 m/s with a constant steer
 * torque T, both tyres with friction {mu} (the wheel contacts of a free rear frame: their
 * normal forces are the contact rows' multipliers).
 *
 *  T = 0.15 N m: the weave decays and the bicycle settles into a steady left turn (lean 0.118
 *    rad, friction ratio 0.119 at 20 s). With mu = 0.8 the tyres hold: no event, both contacts
 *    rolling, and the state after 10 s is the frictionless run's to round-off (8e-13 in
 *    coordinates of up to 40 m and speeds of 15 rad/s; bounded by 1e-10, rtol 1e-11: the
 *    contact with modes evaluates its rows in another order).
 *  T = 0.3 N m: the turn steepens (the bicycle spirals into a fall) and the friction it needs
 *    grows past 0.8 near 8.9 s. The frictionless run locates t*, where the larger of the two
 *    tyres' friction_ratio reaches mu, with an event on max(ratio) - mu (rising, reactions
 *    stage, located to 1e-11 relative); the run with mu = 0.8 must record that tyre's slip
 *    event at t* (1e-9 relative) and slide after it. (Only 1e-8 s past it: at slip speeds
 *    near 0 the front tyre's slip direction turns at a rate ~ 1 / |s| and the explicit
 *    steppers crawl, docs/vehicles.md.)
 *  T = 0.15 N m with mu = 0.1, below the 0.129 the turn-in transient needs: the same at the
 *    first crossing (near 0.8 s). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define RTOL 1e-11

typedef struct tyres {
  const ap_model *m;
  int c[2];   /* rear_contact, front_contact */
  double mu;
} tyres;

static void find_tyres(runner *r, tyres *ty) {
  ty->m = ap_scene_model(r->sc);
  ty->c[0] = ty->c[1] = -1;
  for (int i = 0; i < ap_scene_count(r->sc, AP_SCENE_CONSTRAINTS); i++) {
    const char *n = ap_scene_element_name(r->sc, AP_SCENE_CONSTRAINTS, i);
    if (strcmp(n, "rear_contact") == 0) ty->c[0] = i;
    if (strcmp(n, "front_contact") == 0) ty->c[1] = i;
  }
  AP_CHECK(ty->c[0] >= 0 && ty->c[1] >= 0);
}

static int max_ratio_minus_mu(double t, const double *q, const double *v, const ap_data *d,
                              void *user, double *out) {
  const tyres *ty = user;
  double r = -INFINITY;
  (void)t, (void)q, (void)v;
  for (int i = 0; i < 2; i++) {
    ap_contact_force f;
    if (ap_body_contact_force(ty->m, d, d->lambda, ty->c[i], &f) != AP_OK) return -1;
    r = fmax(r, f.friction_ratio);
  }
  *out = r - ty->mu;
  return 0;
}

static const char *torque_set(double T, char *buf) {
  snprintf(buf, 64, "effects.steer.torque=%.17g", T);
  return buf;
}

/* t* on the frictionless run with steer torque T. */
static double crossing(double T, double mu) {
  char b[64];
  const char *sets[] = {torque_set(T, b)};
  runner r;
  double t = NAN;
  AP_CHECK_EQ_INT(runner_start(&r, "bicycle_turn.yaml", sets, 1, RTOL), AP_OK);
  if (r.sim) {
    tyres ty;
    find_tyres(&r, &ty);
    ty.mu = mu;
    ap_event_def def = ap_event_def_default();
    def.name = "ratio", def.fn = max_ratio_minus_mu, def.user = &ty;
    def.direction = AP_EVENT_RISING, def.action = AP_EVENT_STOP, def.stage = AP_EVENT_REACTIONS;
    AP_CHECK_EQ_INT(ap_sim_add_event(r.sim, &def), AP_OK);
    if (ap_sim_advance(r.sim, 12.0) == AP_STOPPED) t = ap_sim_time(r.sim);
  }
  runner_stop(&r);
  return t;
}

/* The run with friction mu on both tyres. */
static int start_mu(runner *r, double T, double mu) {
  char b[64], fr[2][96];
  snprintf(fr[0], sizeof fr[0], "constraints.rear_contact.friction={mu: %.17g}", mu);
  snprintf(fr[1], sizeof fr[1], "constraints.front_contact.friction={mu: %.17g}", mu);
  const char *sets[] = {torque_set(T, b), fr[0], fr[1]};
  return runner_start(r, "bicycle_turn.yaml", sets, mu >= 0 ? 3 : 1, RTOL);
}

static void test_holds(void) {
  runner a, b;
  AP_CHECK_EQ_INT(start_mu(&a, 0.15, 0.8), AP_OK);
  AP_CHECK_EQ_INT(start_mu(&b, 0.15, -1.0), AP_OK);
  if (a.sim && b.sim) {
    AP_CHECK_EQ_INT(ap_sim_advance(a.sim, 10.0), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(b.sim, 10.0), AP_OK);
    int n = ap_model_n(ap_scene_model(a.sc)), k = ap_model_k(ap_scene_model(a.sc));
    double dq = 0.0;
    for (int i = 0; i < n; i++) dq = fmax(dq, fabs(ap_sim_q(a.sim)[i] - ap_sim_q(b.sim)[i]));
    for (int i = 0; i < k; i++) dq = fmax(dq, fabs(ap_sim_v(a.sim)[i] - ap_sim_v(b.sim)[i]));
    tyres ty;
    find_tyres(&a, &ty);
    int rolling = ap_sim_contact_mode(a.sim, ty.c[0]) == AP_CONTACT_ROLLING &&
                  ap_sim_contact_mode(a.sim, ty.c[1]) == AP_CONTACT_ROLLING;
    printf("  steer torque 0.15 N m, mu 0.8: after 10 s %d events, both rolling %d, largest "
           "difference from the frictionless run %.2g\n", ap_sim_event_count(a.sim), rolling,
           dq);
    AP_CHECK_EQ_INT(ap_sim_event_count(a.sim), 0);
    AP_CHECK(rolling && dq <= 1e-10);
  }
  runner_stop(&a), runner_stop(&b);
}

static void test_slips(double T, double mu) {
  double ts = crossing(T, mu);
  runner r;
  AP_CHECK_EQ_INT(start_mu(&r, T, mu), AP_OK);
  if (r.sim && isfinite(ts)) {
    tyres ty;
    find_tyres(&r, &ty);
    AP_CHECK_EQ_INT(ap_sim_advance(r.sim, ts + 1e-8), AP_OK);
    ap_event_record rec;
    memset(&rec, 0, sizeof rec);
    int n = ap_sim_event_count(r.sim);
    if (n > 0) AP_CHECK_EQ_INT(ap_sim_event_get(r.sim, 0, &rec), AP_OK);
    int sliding = ap_sim_contact_mode(r.sim, ty.c[0]) == AP_CONTACT_SLIDING ||
                  ap_sim_contact_mode(r.sim, ty.c[1]) == AP_CONTACT_SLIDING;
    printf("  steer torque %g N m, mu %g: frictionless ratio reaches mu at t* = %.15g; with "
           "friction first event %s at %.15g (|t - t*| / t* = %.2g), a tyre sliding after: %d\n",
           T, mu, ts, n ? rec.name : "none", rec.t, fabs(rec.t - ts) / ts, sliding);
    AP_CHECK(n >= 1 && strstr(rec.name, ".slip") != NULL && sliding);
    AP_CHECK_LE(fabs(rec.t - ts), 1e-9 * ts);
  }
  AP_CHECK(isfinite(ts));
  runner_stop(&r);
}

int main(void) {
  printf("the bicycle with tyre friction:\n");
  test_holds();
  test_slips(0.3, 0.8);
  test_slips(0.15, 0.1);
  return ap_check_finish("test_bicycle_friction");
}
