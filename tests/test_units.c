/* Tolerances follow the model's units (issue 24): a model scaled from metres to millimetres
 * (lengths x 1000, inertias x 1e6 with the masses unchanged, gravity x 1000, atol x 1000) moves
 * as the original: lengths and linear speeds / 1000 and every angle, quaternion and angular
 * speed equal the original's within the two runs' error bounds. A tolerance compared in
 * absolute terms against a quantity with units (rank_rtol against the gradient of a contact
 * row, a consistency residual against max(1, ...)) would treat the two differently.
 *
 * Models (examples/scenes): the rolling disk (plane contact, rolling rows, gravity) and the
 * sleigh on a wheel (a knife edge on a wheel on a revolute below a planar chassis: the wheel's
 * contact row vanishes identically, and rows of Phi_q below rank_rtol times the model's length
 * scale are left out). Minimal and projected mode, 3 s, outputs every 0.5 s.
 * Bound, per compared value: the sum of the two runs' global errors, each 10 (rtol X + atol_m),
 * X the largest magnitude of that quantity along the metre run, atol_m the metre run's atol
 * (the millimetre run's error in metres). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "clitest.h"

#define MAXSET 16
#define NOUT 7   /* t = 0, 0.5, ..., 3 */

typedef struct ucase {
  const char *file;
  const char *lengths[8];   /* coordinate and speed names in length units */
  const char *mm[MAXSET];   /* the overrides to millimetres */
} ucase;

static const ucase CASES[] = {
    {"rolling_disk.yaml",
     {"disk.x", "disk.y", "disk.vx", "disk.vy", NULL},
     {"bodies.disk.shape.radius=500", "effects.gravity.g.2=-9810", NULL}},
    {"sleigh_wheel.yaml",
     {"sleigh.x", "sleigh.y", "sleigh.x_dot", "sleigh.y_dot", NULL},
     {"bodies.sleigh.com.0=1000/0.9", "bodies.sleigh.inertia.0=0.5e6",
      "bodies.sleigh.inertia.1=0.5e6", "bodies.sleigh.inertia.2=(2 - 1/0.9 - 0.1*0.1^2/4)*1e6",
      "bodies.wheel.shape.radius=100", "joints.sleigh.parent_frame.pos.2=100",
      "initial.sleigh.vx=-100", NULL}},
};

static const double RTOL = 1e-9, ATOL_M = 1e-12;

/* Run the scene (with its overrides) in mode to 3 s; the state at each output into x. */
static int run(const ucase *c, int mm, const char *mode, double *x, int *nx, char *names[64]) {
  char path[1200], msg[1024] = "", modeset[64], rt[64], at[64];
  ct_source(path, sizeof path, "examples/scenes", c->file);
  const char *sets[MAXSET + 8];
  int ns = 0;
  snprintf(modeset, sizeof modeset, "simulation.mode=%s", mode);
  snprintf(rt, sizeof rt, "simulation.rtol=%g", RTOL);
  snprintf(at, sizeof at, "simulation.atol=%g", mm ? 1e3 * ATOL_M : ATOL_M);
  sets[ns++] = modeset, sets[ns++] = rt, sets[ns++] = at, sets[ns++] = "simulation.t_end=3";
  for (int i = 0; mm && c->mm[i]; i++) sets[ns++] = c->mm[i];
  ap_scene *s = NULL;
  int rc = ap_scene_load(path, sets, ns, &s, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) {
    fprintf(stderr, "%s: %s\n", c->file, msg);
    return rc;
  }
  const ap_model *m = ap_scene_model(s);
  int n = ap_model_n(m), k = ap_model_k(m);
  *nx = n + k;
  for (int i = 0; i < n + k && i < 64; i++)
    names[i] = (char *)(i < n ? ap_model_coord_name(m, i) : ap_model_speed_name(m, i - n));
  ap_scene_run sr;
  ap_scene_get_run(s, &sr);
  double *q0 = calloc((size_t)(n + k), sizeof(double)), *v0 = q0 + n;
  rc = ap_scene_initial_state(s, q0, v0, NULL, 0, msg, sizeof msg);
  ap_sim *sim = NULL;
  if (rc == AP_OK) rc = ap_sim_create(m, &sr.sim, 0.0, q0, v0, &sim, msg, sizeof msg);
  for (int o = 0; rc == AP_OK && o < NOUT; o++) {
    if (o > 0) rc = ap_sim_advance(sim, 0.5 * o);
    memcpy(x + (size_t)o * (n + k), ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(x + (size_t)o * (n + k) + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
  }
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) fprintf(stderr, "%s: %s %s\n", c->file, msg, sim ? ap_sim_message(sim) : "");
  ap_sim_free(sim);
  free(q0);
  /* names point into the model: keep the scene until the comparison is done (leaked into
   * the caller's list below, freed there) */
  names[63] = (char *)s;
  return rc;
}

static int is_length(const ucase *c, const char *name) {
  for (int i = 0; c->lengths[i]; i++)
    if (!strcmp(c->lengths[i], name)) return 1;
  return 0;
}

static void compare(const ucase *c, const char *mode) {
  double *xm = calloc(2 * 64 * NOUT, sizeof(double)), *xmm = xm + 64 * NOUT;
  char *nm[64] = {0}, *nmm[64] = {0};
  int nx = 0, nx2 = 0;
  int rc = run(c, 0, mode, xm, &nx, nm);
  if (rc == AP_OK) rc = run(c, 1, mode, xmm, &nx2, nmm);
  if (rc == AP_OK && nx == nx2 && nx < 63) {
    double worst = 0.0;   /* largest difference / bound */
    for (int i = 0; i < nx; i++) {
      double f = is_length(c, nm[i]) ? 1e-3 : 1.0, X = 0.0, d = 0.0;
      for (int o = 0; o < NOUT; o++) {
        X = fmax(X, fabs(xm[o * nx + i]));
        d = fmax(d, fabs(xm[o * nx + i] - f * xmm[o * nx + i]));
      }
      double bound = 2 * 10 * (RTOL * X + ATOL_M);
      AP_CHECK_LE(d, bound);
      worst = fmax(worst, d / bound);
    }
    printf("%-18s %-9s metres vs millimetres / 1000: largest difference %.2f of its bound\n",
           c->file, mode, worst);
  }
  if (nm[63]) ap_scene_free((ap_scene *)nm[63]);
  if (nmm[63]) ap_scene_free((ap_scene *)nmm[63]);
  free(xm);
}

int main(void) {
  ct_find_source(ct_src, sizeof ct_src);
  for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
    compare(&CASES[i], "minimal");
    compare(&CASES[i], "projected");
  }
  return ap_check_finish("units");
}
