/* Runs of one model on the dense and the tree path through ap_sim, compared (test_tree_path,
 * test_tree_fleet). The two are the same ODE in different coordinates (the tree path picks its
 * dependent speeds body by body), so the trajectories agree to the integrators' global error:
 * max |q_dense - q_tree| and |v_dense - v_tree| at the end, relative to max(1, |x|), within
 * 20 rtol, in minimal and projected mode at rtol 1e-6 and 1e-9. Include after check.h. */
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

static void compare_runs(const char *label, ap_model *md, ap_model *mt, const double *q0,
                         const double *v0, double t1) {
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

#endif
