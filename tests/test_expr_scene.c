/* Scene expressions in simulations (docs/scenes.md "Expressions", "Kinks").
 *
 * 1. tests/scenes/kinks_fn.yaml: the kinks of max, clamp, sign and floor in joint forces are
 *    events hit to round-off: the run matches the closed-form double integrals of the
 *    piecewise forces to 1e-10 at rtol 1e-12, with every kink recorded at its exact time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

/* A simulation of the scene at path from its initial state, with its events; *sc receives the
 * scene. NULL (counted as a failure) when something fails. */
static ap_sim *load_sim(const char *path, ap_scene **sc) {
  char msg[1024];
  ap_sim *s = NULL;
  int rc = ap_scene_load(path, NULL, 0, sc, msg, sizeof msg);
  const ap_model *m = rc == AP_OK ? ap_scene_model(*sc) : NULL;
  double *x = m ? calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof *x) : NULL;
  if (rc == AP_OK && !x) rc = AP_ERR_NOMEM;
  if (rc == AP_OK)
    rc = ap_scene_initial_state(*sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg);
  ap_scene_run run;
  if (rc == AP_OK) {
    ap_scene_get_run(*sc, &run);
    rc = ap_sim_create(m, &run.sim, run.t0, x, x + ap_model_n(m), &s, msg, sizeof msg);
  }
  if (rc == AP_OK) rc = ap_scene_add_events(*sc, s, msg, sizeof msg);
  free(x);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", path, msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) ap_sim_free(s), s = NULL;
  return s;
}

/* ---- 1. kinks of min, max, clamp, sign, floor ------------------------------------------------ */

static double r2(double u) { return u > 0 ? u * u / 2 : 0.0; }
static double r3(double u) { return u > 0 ? u * u * u / 6 : 0.0; }

/* x'' = max(0, t - 1) - 2 clamp(t - 2, 0, 0.5) + sign(t - 3), y'' = floor(t / 1.5), from rest. */
static void kinks_exact(double t, double *x, double *y) {
  *x = r3(t - 1) - 2 * (r3(t - 2) - r3(t - 2.5)) - t * t / 2 + 2 * r2(t - 3);
  *y = r2(t - 1.5) + r2(t - 3) + r2(t - 4.5);
}

static void test_kinks(const char *path) {
  ap_scene *sc = NULL;
  ap_sim *s = load_sim(path, &sc);
  double err = 0.0, x, y;
  for (int i = 1; s && i <= 16; i++) {   /* output times off the kinks */
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.3 * i), AP_OK);
    kinks_exact(0.3 * i, &x, &y);
    err = fmax(err, fmax(fabs(ap_sim_q(s)[0] - x), fabs(ap_sim_q(s)[1] - y)));
  }
  if (s) {
    static const double when[] = {1, 1.5, 2, 2.5, 3, 3, 4.5};
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    printf("kinks of max, clamp, sign, floor: max error %.2e, %ld steps, %ld rejected, "
           "%d events\n", err, st.steps, st.err_fails, ap_sim_event_count(s));
    AP_CHECK_LE(err, 1e-10);
    AP_CHECK_EQ_INT(ap_sim_event_count(s), 7);
    for (int i = 0; i < 7 && i < ap_sim_event_count(s); i++) {
      ap_event_record ev;
      AP_CHECK_EQ_INT(ap_sim_event_get(s, i, &ev), AP_OK);
      AP_CHECK_NEAR(ev.t, when[i], 1e-14);
    }
  }
  ap_sim_free(s);
  ap_scene_free(sc);
}

int main(void) {
  char src[1024], path[1200];
  ct_find_source(src, sizeof src);
  snprintf(path, sizeof path, "%s/tests/scenes/kinks_fn.yaml", src);
  test_kinks(path);
  return ap_check_finish("test_expr_scene");
}
