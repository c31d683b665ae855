/* The Ackermann car cornering faster and faster until a wheel breaks away (docs/vehicles.md
 * "Breaking away in a turn"): examples/scenes/car_breakaway.yaml, the suspended car on a free
 * chassis with a sideways-sprung hub and a vertically sprung strut per wheel (unique loads and
 * sideways forces), steered at the fixed Ackermann angles of steer 0.3 rad and sped up by a
 * drive torque of 1 N m per rear wheel from 2 m/s.
 *
 *  (1) Slip onset: on the run without friction (the scene's mu set to 1e9: the contacts never
 *      leave their rolling mode, the same model as without friction) an event on
 *      max_i(friction_ratio_i) - mu (rising, reactions stage, located to 1e-11 relative) finds
 *      t* and the wheel whose ratio gets there first; the run with mu = 0.5 must record that
 *      wheel's slip event at t* (1e-9 relative) and have it sliding after.
 *  (2) The quasi-static loads: see quasi_static() below.
 * Minimal and projected mode, dop853 at rtol 1e-10, atol 1e-12. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define RTOL 1e-10
#define MU 0.5
#define NW 4

static const char *const WHEELS[NW] = {"roll_rl", "roll_rr", "roll_fl", "roll_fr"};

typedef struct tyres {
  const ap_model *m;
  int c[NW];     /* constraint index of each wheel's contact */
  double mu;
  int first;     /* the wheel with the largest ratio at the last evaluation */
} tyres;

static void find_tyres(runner *r, tyres *ty) {
  ty->m = ap_scene_model(r->sc);
  for (int w = 0; w < NW; w++) {
    ty->c[w] = -1;
    for (int i = 0; i < ap_scene_count(r->sc, AP_SCENE_CONSTRAINTS); i++)
      if (strcmp(ap_scene_element_name(r->sc, AP_SCENE_CONSTRAINTS, i), WHEELS[w]) == 0)
        ty->c[w] = i;
    AP_CHECK(ty->c[w] >= 0);
  }
}

static int max_ratio_minus_mu(double t, const double *q, const double *v, const ap_data *d,
                              void *user, double *out) {
  tyres *ty = user;
  double r = -INFINITY;
  (void)t, (void)q, (void)v;
  for (int w = 0; w < NW; w++) {
    ap_contact_force f;
    if (ap_body_contact_force(ty->m, d, d->lambda, ty->c[w], &f) != AP_OK) return -1;
    if (f.friction_ratio > r) r = f.friction_ratio, ty->first = w;
  }
  *out = r - ty->mu;
  return 0;
}

/* The scene in `mode` with friction coefficient mu (1e9: never slips). */
static int start(runner *r, const char *mode, double mu) {
  char sm[64], smu[64];
  snprintf(sm, sizeof sm, "simulation.mode=%s", mode);
  snprintf(smu, sizeof smu, "parameters.mu=%.17g", mu);
  const char *sets[] = {sm, smu};
  return runner_start(r, "car_breakaway.yaml", sets, 2, RTOL);
}

/* t* and the first wheel on the run without friction. */
static double crossing(const char *mode, int *first) {
  runner r;
  double t = NAN;
  *first = -1;
  AP_CHECK_EQ_INT(start(&r, mode, 1e9), AP_OK);
  if (r.sim) {
    tyres ty;
    find_tyres(&r, &ty);
    ty.mu = MU, ty.first = -1;
    ap_event_def def = ap_event_def_default();
    def.name = "ratio", def.fn = max_ratio_minus_mu, def.user = &ty;
    def.direction = AP_EVENT_RISING, def.action = AP_EVENT_STOP, def.stage = AP_EVENT_REACTIONS;
    AP_CHECK_EQ_INT(ap_sim_add_event(r.sim, &def), AP_OK);
    if (ap_sim_advance(r.sim, 6.0) == AP_STOPPED) t = ap_sim_time(r.sim), *first = ty.first;
  }
  runner_stop(&r);
  return t;
}

static void test_onset(const char *mode) {
  int first;
  double ts = crossing(mode, &first);
  runner r;
  AP_CHECK(isfinite(ts) && first >= 0);
  AP_CHECK_EQ_INT(start(&r, mode, MU), AP_OK);
  if (r.sim && isfinite(ts) && first >= 0) {
    tyres ty;
    find_tyres(&r, &ty);
    AP_CHECK_EQ_INT(ap_sim_advance(r.sim, ts + 1e-8), AP_OK);
    ap_event_record rec;
    memset(&rec, 0, sizeof rec);
    int n = ap_sim_event_count(r.sim);
    if (n > 0) AP_CHECK_EQ_INT(ap_sim_event_get(r.sim, 0, &rec), AP_OK);
    char want[64];
    snprintf(want, sizeof want, "%s.slip", WHEELS[first]);
    int sliding = ap_sim_contact_mode(r.sim, ty.c[first]) == AP_CONTACT_SLIDING;
    printf("  %s: without friction the %s ratio reaches mu = %g first, at t* = %.15g; with "
           "friction first event %s at %.15g (|t - t*| / t* = %.2g), sliding after: %d\n",
           mode, WHEELS[first], MU, ts, n ? rec.name : "none", rec.t, fabs(rec.t - ts) / ts,
           sliding);
    AP_CHECK(n >= 1 && strcmp(rec.name, want) == 0 && sliding);
    AP_CHECK_LE(fabs(rec.t - ts), 1e-9 * ts);
  }
  runner_stop(&r);
}

int main(void) {
  printf("the car cornering faster and faster:\n");
  test_onset("minimal");
  test_onset("projected");
  if (getenv("AP_BREAKAWAY_DAE")) test_onset("dae");
  return ap_check_finish("test_car_breakaway");
}
