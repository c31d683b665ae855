/* A simulation of an example scene for tests (test_loads, test_vehicle_slip): the scene
 * examples/scenes/FILE under AP_SRCDIR with --set overrides, its initial state, and an ap_sim
 * with the scene's settings (rtol > 0: dop853 at rtol, atol = rtol / 100 instead). */
#ifndef AP_TEST_SCENE_RUNNER_H
#define AP_TEST_SCENE_RUNNER_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

typedef struct runner {
  ap_scene *sc;
  ap_sim *sim;
  double *x0;
} runner;

static int runner_start(runner *r, const char *file, const char *const *sets, int nsets,
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

static void runner_stop(runner *r) {
  ap_sim_free(r->sim);
  ap_scene_free(r->sc);
  free(r->x0);
}

#endif
