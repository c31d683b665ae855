/* Runs of one model on the dense and the tree path through ap_sim, compared (test_tree_path,
 * test_tree_fleet). The two are the same ODE in different coordinates (the tree path picks its
 * dependent speeds body by body), so the trajectories agree to the integrators' global error:
 * max |q_dense - q_tree| and |v_dense - v_tree| at the end, relative to max(1, |x|), within
 * 20 rtol, in minimal and projected mode at rtol 1e-6 and 1e-9; example scenes with their own
 * settings (scene_both). Include after check.h. */
#ifndef TESTS_TREE_COMPARE_H
#define TESTS_TREE_COMPARE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"

static double rel_diff(int n, const double *a, const double *b) {
  double mx = 0.0, sc = 1.0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(a[i] - b[i])), sc = fmax(sc, fabs(a[i]));
  return mx / sc;
}

/* Run m from (q0, v0) to t1; q, v at t1 into q1, v1; the run's status. */
static int run(const ap_model *m, ap_mode mode, double rtol, const double *q0, const double *v0,
               double t1, double *q1, double *v1) {
  ap_sim_def def = ap_sim_def_default();
  def.mode = mode, def.rtol = rtol, def.atol = 1e-2 * rtol;
  ap_sim *s = NULL;
  char msg[512] = "";
  int rc = ap_sim_create(m, &def, 0.0, q0, v0, &s, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_advance(s, t1);
  if (rc != AP_OK) fprintf(stderr, "run: %s %s\n", msg, s ? ap_sim_message(s) : "");
  if (rc == AP_OK) {
    memcpy(q1, ap_sim_q(s), sizeof(double) * (size_t)ap_model_n(m));
    memcpy(v1, ap_sim_v(s), sizeof(double) * (size_t)ap_model_k(m));
  }
  ap_sim_free(s);
  return rc;
}

static void compare_runs(const char *label, const ap_model *md, const ap_model *mt,
                         const double *q0, const double *v0, double t1) {
  int n = ap_model_n(md), k = ap_model_k(md);
  double *x = calloc((size_t)(2 * (n + k)), sizeof(double));
  double *qd = x, *vd = qd + n, *qt = vd + k, *vt = qt + n;
  const ap_mode modes[2] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED};
  const double rtols[2] = {1e-6, 1e-9};
  for (int mi = 0; mi < 2; mi++)
    for (int ri = 0; ri < 2; ri++) {
      AP_CHECK_EQ_INT(run(md, modes[mi], rtols[ri], q0, v0, t1, qd, vd), AP_OK);
      AP_CHECK_EQ_INT(run(mt, modes[mi], rtols[ri], q0, v0, t1, qt, vt), AP_OK);
      double eq = rel_diff(n, qd, qt), ev = rel_diff(k, vd, vt);
      printf("%-9s %-9s rtol %.0e: |dq| %.2e  |dv| %.2e (bound %.0e)\n", label,
             mi ? "projected" : "minimal", rtols[ri], eq, ev, 20 * rtols[ri]);
      AP_CHECK_LE(eq, 20 * rtols[ri]);
      AP_CHECK_LE(ev, 20 * rtols[ri]);
    }
  free(x);
}

/* An example scene run to its t_end with its own settings (simulation.path set; t_end, when
 * not NULL, an override such as "simulation.t_end=0.5"), both paths; the end states compared
 * relative to max(1, |x|) within 20 rtol. */
static void scene_both(const char *root, const char *name, const char *t_end) {
  char file[1024], msg[512] = "";
  snprintf(file, sizeof file, "%s/examples/scenes/%s.yaml", root, name);
  double *x[2] = {NULL, NULL}, rtol = 0;
  int n = 0, k = 0;
  for (int p = 0; p < 2; p++) {
    const char *set[2] = {p ? "simulation.path=tree" : "simulation.path=dense", t_end};
    ap_scene *s = NULL;
    ap_sim *sim = NULL;
    AP_CHECK_EQ_INT(ap_scene_load(file, set, t_end ? 2 : 1, &s, msg, sizeof msg), AP_OK);
    if (!s) return;
    const ap_model *m = ap_scene_model(s);
    AP_CHECK_EQ_INT(ap_model_path(m), p ? AP_PATH_TREE : AP_PATH_DENSE);
    n = ap_model_n(m), k = ap_model_k(m);
    x[p] = calloc((size_t)(n + k), sizeof(double));
    ap_scene_run run;
    ap_scene_get_run(s, &run);
    rtol = run.sim.rtol;
    AP_CHECK_EQ_INT(ap_scene_initial_state(s, x[p], x[p] + n, NULL, 0, msg, sizeof msg), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, run.t0, x[p], x[p] + n, &sim, msg, sizeof msg),
                    AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(sim, run.t_end), AP_OK);
    memcpy(x[p], ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(x[p] + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
    ap_sim_free(sim);
    ap_scene_free(s);
  }
  double eq = rel_diff(n, x[0], x[1]), ev = rel_diff(k, x[0] + n, x[1] + n);
  printf("%-16s rtol %.0e: |dq| %.2e  |dv| %.2e at t_end\n", name, rtol, eq, ev);
  AP_CHECK_LE(eq, 20 * rtol);
  AP_CHECK_LE(ev, 20 * rtol);
  free(x[0]), free(x[1]);
}

#endif
