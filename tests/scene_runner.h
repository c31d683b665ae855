/* A simulation of an example scene for tests (test_loads, test_vehicle_slip): the scene
 * examples/scenes/FILE under AP_SRCDIR with --set overrides, its initial state, and an ap_sim
 * with the scene's settings (rtol > 0: dop853 at rtol, atol = rtol / 100 instead). And the
 * Whipple bicycle scene with the indices of its coordinates (test_bicycle, test_bicycle_ride). */
#ifndef AP_TEST_SCENE_RUNNER_H
#define AP_TEST_SCENE_RUNNER_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

typedef struct runner {
  ap_scene *sc;
  ap_sim *sim;
  double *x0;
} runner;

static inline int runner_start(runner *r, const char *file, const char *const *sets, int nsets,
                        double rtol) {
  char path[1200], msg[1024] = "";
  memset(r, 0, sizeof *r);
  snprintf(path, sizeof path, "%s/examples/scenes/%s", AP_SRCDIR, file);
  int rc = ap_scene_load(path, sets, nsets, &r->sc, msg, sizeof msg);
  if (rc != AP_OK) return printf("  %s: %s\n", file, msg), rc;
  const ap_model *m = ap_scene_model(r->sc);
  int n = ap_model_n(m);
  ap_scene_run run;
  ap_scene_get_run(r->sc, &run);
  if (rtol > 0) run.sim.rtol = rtol, run.sim.atol = rtol / 100, run.sim.method = "dop853";
  r->x0 = calloc((size_t)(n + ap_model_k(m)), sizeof *r->x0);
  rc = ap_scene_initial_state(r->sc, r->x0, r->x0 + n, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK)
    rc = ap_sim_create(m, &run.sim, run.t0, r->x0, r->x0 + n, &r->sim, msg, sizeof msg);
  if (rc != AP_OK) printf("  %s: %s\n", file, msg);
  return rc;
}

/* The simulation's event i into *rec (zeroed, name "none", when there is none); returns the
 * number of events recorded. */
static inline int runner_event(const ap_sim *s, int i, ap_event_record *rec) {
  int n = ap_sim_event_count(s);
  memset(rec, 0, sizeof *rec);
  rec->name = "none";
  if (i < n && ap_sim_event_get(s, i, rec) != AP_OK) rec->name = "none";
  return n;
}

static inline void runner_stop(runner *r) {
  ap_sim_free(r->sim);
  ap_scene_free(r->sc);
  free(r->x0);
}

/* ---- the Whipple bicycle (examples/scenes/bicycle.yaml; test_bicycle, test_bicycle_ride) ---- */

/* The scene's model and the indices of its coordinates, speeds and wheels. */
typedef struct bike {
  ap_scene *sc;
  const ap_model *m;
  int n, k;
  int cx, cq, cR, cH, cF;      /* coordinates: rear_frame.x (y, z follow), .qw, the angles */
  int sv, sw, sR, sH, sF;      /* speeds: rear_frame.vx, .wx, the rates */
  int rear, front;             /* wheel bodies */
} bike;

static inline int bike_load(bike *bk, const char *const *sets, int nsets) {
  char file[1200], msg[1024] = "";
  snprintf(file, sizeof file, "%s/examples/scenes/bicycle.yaml", AP_SRCDIR);
  memset(bk, 0, sizeof *bk);
  if (ap_scene_load(file, sets, nsets, &bk->sc, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "loading %s: %s\n", file, msg);
    return 0;
  }
  const ap_model *m = bk->m = ap_scene_model(bk->sc);
  bk->n = ap_model_n(m), bk->k = ap_model_k(m);
  bk->cx = ap_model_find_coord(m, "rear_frame.x"), bk->cq = ap_model_find_coord(m, "rear_frame.qw");
  bk->cR = ap_model_find_coord(m, "rear_wheel.angle");
  bk->cH = ap_model_find_coord(m, "front_frame.angle");
  bk->cF = ap_model_find_coord(m, "front_wheel.angle");
  bk->sv = ap_model_find_speed(m, "rear_frame.vx"), bk->sw = ap_model_find_speed(m, "rear_frame.wx");
  bk->sR = ap_model_find_speed(m, "rear_wheel.angle_dot");
  bk->sH = ap_model_find_speed(m, "front_frame.angle_dot");
  bk->sF = ap_model_find_speed(m, "front_wheel.angle_dot");
  bk->rear = ap_model_find_body(m, "rear_wheel"), bk->front = ap_model_find_body(m, "front_wheel");
  int ok = bk->n == 10 && bk->k == 9 && bk->cx >= 0 && bk->cq >= 0 && bk->cR >= 0 &&
           bk->cH >= 0 && bk->cF >= 0 && bk->sv >= 0 && bk->sw >= 0 && bk->sR >= 0 &&
           bk->sH >= 0 && bk->sF >= 0 && bk->rear >= 0 && bk->front >= 0 &&
           ap_model_find_coord(m, "rear_frame.z") == bk->cx + 2 &&
           ap_model_find_speed(m, "rear_frame.wz") == bk->sw + 2 &&
           ap_model_find_speed(m, "rear_frame.vz") == bk->sv + 2;
  AP_CHECK(ok);
  return ok;
}

/* Heights of both wheels' lowest points (the contact rows' phi) and the energies. */
static inline int scene_eval(const bike *bk, ap_data *d, const double *q, const double *v,
                      double height[2], double *T, double *V) {
  d->t = 0;
  memcpy(d->q, q, sizeof(double) * (size_t)bk->n);
  memcpy(d->v, v, sizeof(double) * (size_t)bk->k);
  ap_body_state st;
  int rc = ap_body_eval(bk->m, d);
  for (int w = 0; rc == AP_OK && w < 2; w++) {
    rc = ap_body_get_state(bk->m, d, w ? bk->front : bk->rear, &st);
    height[w] = st.contact[2];
  }
  if (rc == AP_OK && T) rc = ap_body_energy(bk->m, d, T, V);
  return rc;
}

#endif
