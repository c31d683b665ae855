/* The linearization's sweep machinery, its scene section and its error paths (lib/analyze,
 * lib/scene/linearize.c); the closed-form proofs are in tests/test_linearize.c.
 *
 *  - Sweeps: a synthetic spectrum with branches that cross (tracking must keep them apart:
 *    sorting would swap them), zero crossings of a real eigenvalue and of a pair, and a meeting,
 *    at known parameters, found to 1e-12; bad parameter grids refused.
 *  - Scene section: read back (overrides, speed keys with sequences, lists, sweep); bad
 *    sections named with file:line:column and the reason.
 *  - Errors: a point that is not steady (the state and its rate named), a subsystem that is not
 *    closed (the coupling state named), a repeated state, a turntable whose rate changes with
 *    time (refused as time-dependent), NULL arguments. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "appell/scene.h"
#include "check.h"

static char srcdir[1024];

static void find_srcdir(void) {
  const char *env = getenv("APPELL_SOURCE_DIR");
  if (env) {
    snprintf(srcdir, sizeof srcdir, "%s", env);
    return;
  }
  snprintf(srcdir, sizeof srcdir, "%s", __FILE__);
  char *slash = strrchr(srcdir, '/');
  if (slash) *slash = '\0', slash = strrchr(srcdir, '/');
  if (slash) *slash = '\0';
  else snprintf(srcdir, sizeof srcdir, ".");
}

/* ---- sweeps on a synthetic spectrum --------------------------------------------------------
 * Real eigenvalues p - 1 and 0.5 - p (they cross each other at 0.75: sorting would swap them;
 * zero crossings at 1, rising, and 0.5, falling), a pair (p - 0.4) +- 2i (crossing at 0.4,
 * rising) and c +- sqrt(d) with c = -3, d = p - 0.6 (complex below 0.6, real above: a pair
 * splitting at 0.6). Returned in scrambled order so tracking cannot rely on it. */
static int synth(double p, int n, double *re, double *im, void *user) {
  (void)user;
  double r[6] = {p - 1, 0.5 - p, p - 0.4, p - 0.4, -3, -3}, i[6] = {0, 0, 2, -2, 0, 0};
  double d = p - 0.6;
  if (d >= 0) r[4] += sqrt(d), r[5] -= sqrt(d);
  else i[4] = sqrt(-d), i[5] = -sqrt(-d);
  static const int order[6] = {3, 5, 0, 2, 4, 1};
  int shift = (int)floor(p * 37) % 6;
  for (int k = 0; k < n; k++) re[k] = r[order[(k + shift) % 6]], im[k] = i[order[(k + shift) % 6]];
  return AP_OK;
}

static void test_sweep(void) {
  double p[41];
  for (int i = 0; i < 41; i++) p[i] = 0.013 + 1.2 * i / 40;
  ap_lin_sweep sw;
  char msg[256];
  AP_CHECK_EQ_INT(ap_lin_sweep_run(synth, NULL, 6, p, 41, 1e-13, 1e-9, &sw, msg, sizeof msg),
                  AP_OK);
  /* tracking: each row stays on one branch (p - 1 stays increasing, 0.5 - p decreasing) */
  int up = -1, down = -1;
  for (int r = 0; r < 6; r++) {
    if (fabs(sw.re[r] - (p[0] - 1)) < 1e-14 && sw.im[r] == 0) up = r;
    if (fabs(sw.re[r] - (0.5 - p[0])) < 1e-14 && sw.im[r] == 0) down = r;
  }
  AP_CHECK(up >= 0 && down >= 0);
  for (int c = 0; c < 41 && up >= 0 && down >= 0; c++) {
    AP_CHECK_NEAR(sw.re[up + 6 * c], p[c] - 1, 1e-14);
    AP_CHECK_NEAR(sw.re[down + 6 * c], 0.5 - p[c], 1e-14);
  }
  static const struct { ap_lin_event kind; double p; int rising; } want[] = {
      {AP_LIN_CROSSING, 1.0, 1}, {AP_LIN_CROSSING, 0.5, 0}, {AP_LIN_CROSSING, 0.4, 1},
      {AP_LIN_MEETING, 0.6, 0}};
  AP_CHECK_EQ_INT(sw.npoints, 4);
  for (int w = 0; w < 4; w++) {
    int found = 0;
    for (int i = 0; i < sw.npoints; i++)
      if (sw.points[i].kind == want[w].kind && fabs(sw.points[i].p - want[w].p) < 1e-12 &&
          sw.points[i].rising == want[w].rising)
        found = 1;
    if (!found) fprintf(stderr, "  event at %g not found\n", want[w].p);
    AP_CHECK(found);
  }
  ap_lin_sweep_free(&sw);
  AP_CHECK_EQ_INT(ap_lin_sweep_run(synth, NULL, 6, p, 0, 1e-13, 1e-9, &sw, msg, sizeof msg),
                  AP_ERR_ARG);
  double bad[3] = {0, 1, 0.5};
  AP_CHECK_EQ_INT(ap_lin_sweep_run(synth, NULL, 6, bad, 3, 1e-13, 1e-9, &sw, msg, sizeof msg),
                  AP_ERR_ARG);
}

/* ---- errors -------------------------------------------------------------------------------- */

/* The example rolling disk with overrides; its model, state and scene (free the scene). */
static const ap_model *disk_scene(ap_scene **sc, const char *const *sets, int nsets, double *q,
                                  double *u) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/rolling_disk.yaml", srcdir);
  AP_CHECK_EQ_INT(ap_scene_load(file, sets, nsets, sc, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_scene_initial_state(*sc, q, u, NULL, 0, msg, sizeof msg), AP_OK);
  return ap_scene_model(*sc);
}

static void test_errors(void) {
  ap_scene *sc = NULL;
  double q[6], u[5];
  const ap_model *m = disk_scene(&sc, NULL, 0, q, u);   /* leaning 30 degrees: not steady */
  ap_lin *L = NULL;
  ap_lin_def def = ap_lin_def_default();
  AP_CHECK_EQ_INT(ap_lin_create(NULL, &def, 0.0, q, u, &L), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, NULL, u, &L), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, u, NULL), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, u, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L, NAN), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_linearize(L), AP_ERR_INCONSISTENT);
  AP_CHECK(strstr(ap_lin_message(L), "not an operating point") != NULL);
  AP_CHECK(ap_lin_A(L) == NULL);
  AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 0), AP_ERR_ARG);
  ap_lin_free(L);
  ap_scene_free(sc);
  /* upright: keeping tilt but not wx (its rate) is not a closed subsystem */
  static const char *const up[] = {"initial.disk.tilt=90*deg", "initial.disk.heading_rate=0"};
  m = disk_scene(&sc, up, 2, q, u);
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, u, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_linearize(L), AP_OK);
  int sel[2] = {ap_lin_find_state(L, "disk.tilt"), ap_lin_find_state(L, "disk.wz")};
  AP_CHECK_EQ_INT(ap_lin_eigen(L, sel, 2, 0), AP_ERR_ARG);
  AP_CHECK(strstr(ap_lin_message(L), "disk.wx") != NULL);
  int dup[2] = {sel[0], sel[0]};
  AP_CHECK_EQ_INT(ap_lin_eigen(L, dup, 2, 0), AP_ERR_ARG);
  ap_lin_free(L);
  ap_scene_free(sc);
  /* a turntable whose rate changes with time has no steady motion */
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/turntable_ball.yaml", srcdir);
  static const char *const sets[] = {"ground.omega=2+0.1*t"};
  sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, sets, 1, &sc, msg, sizeof msg), AP_OK);
  double qb[6], vb[5];
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, qb, vb, NULL, 0, msg, sizeof msg), AP_OK);
  def.about = AP_LIN_EQUILIBRIUM;
  AP_CHECK_EQ_INT(ap_lin_create(ap_scene_model(sc), &def, 0.0, qb, vb, &L), AP_OK);
  int rc = ap_lin_operating_point(L, NAN);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  AP_CHECK_EQ_INT(rc, AP_ERR_UNSUPPORTED);
  AP_CHECK(strstr(ap_lin_message(L), "depends on time") != NULL);
  ap_lin_free(L);
  ap_scene_free(sc);
}

/* ---- the scene section ---------------------------------------------------------------------- */

static const char scene_text[] =
    "bodies:\n"
    "  disk: {mass: 1, shape: {kind: disk, radius: 0.5}, inertia: uniform}\n"
    "joints:\n"
    "  disk: {kind: plane_contact}\n"
    "constraints:\n"
    "  roll: {kind: rolling, body: disk}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  disk: {tilt: 90*deg, spin_rate: -6}\n"
    "linearize:\n"
    "  about: equilibrium\n"
    "  initial: {disk: {tilt: 80*deg, omega: [0, 1, 2]}}\n"
    "  speed: {disk: {spin_rate: -2, omega: [0, 0, 0.5]}}\n"
    "  free: [disk.tilt]\n"
    "  states: [disk.tilt, disk.wx]\n"
    "  drop_cyclic: false\n"
    "  sweep: {from: 0, to: 2, count: 5}\n";

static void test_scene_section(void) {
  ap_scene *sc = NULL;
  char msg[1024];
  AP_CHECK_EQ_INT(ap_scene_load_string(scene_text, strlen(scene_text), "s.yaml", NULL, 0, &sc,
                                       msg, sizeof msg), AP_OK);
  ap_scene_lin l;
  AP_CHECK_EQ_INT(ap_scene_get_linearize(sc, &l, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(l.present, 1);
  AP_CHECK_EQ_INT(l.about, AP_LIN_EQUILIBRIUM);
  AP_CHECK_EQ_INT(l.nsets, 4);
  if (l.nsets == 4) {
    AP_CHECK(strcmp(l.sets[0], "initial.disk.tilt=80*deg") == 0);
    AP_CHECK(strcmp(l.sets[3], "initial.disk.omega.2=2") == 0);
  }
  AP_CHECK_EQ_INT(l.nspeed, 4);
  if (l.nspeed == 4) {
    AP_CHECK(strcmp(l.speed_keys[0], "initial.disk.spin_rate") == 0);
    AP_CHECK_NEAR(l.speed_coef[0], -2.0, 0.0);
    AP_CHECK(strcmp(l.speed_keys[3], "initial.disk.omega.2") == 0);
    AP_CHECK_NEAR(l.speed_coef[3], 0.5, 0.0);
  }
  AP_CHECK(l.free && strcmp(l.free[0], "disk.tilt") == 0 && !l.free[1]);
  AP_CHECK(l.states && strcmp(l.states[1], "disk.wx") == 0 && !l.states[2]);
  AP_CHECK(l.inputs == NULL && l.independent == NULL);
  AP_CHECK_EQ_INT(l.drop_cyclic, 0);
  AP_CHECK_EQ_INT(l.sweep_count, 5);
  AP_CHECK_NEAR(l.sweep_to, 2.0, 0.0);
  ap_scene_lin_free(&l);
  ap_scene_free(sc);
  /* bad sections: each names the line and the key path */
  static const char *const bad[][2] = {
      {"linearize: {abut: steady}", "did you mean 'about'"},
      {"linearize: {about: sideways}", "unknown about 'sideways'"},
      {"linearize: {initial: {wheel: {tilt: 1}}}", "no joint named 'wheel'"},
      {"linearize: {speed: {disk: {spin_rate: fast}}}", "fast"},
      {"linearize: {free: disk.tilt}", "sequence"},
      {"linearize: {sweep: {from: 1, to: 0, count: 5}}", "greater than"},
      {"linearize: {sweep: {from: 0, to: 1, count: 1}}", "count"}};
  for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
    char text[2048];
    size_t cut = strstr(scene_text, "linearize:") - scene_text;
    snprintf(text, sizeof text, "%.*s%s\n", (int)cut, scene_text, bad[i][0]);
    int rc = ap_scene_load_string(text, strlen(text), "bad.yaml", NULL, 0, &sc, msg, sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
    if (!strstr(msg, bad[i][1]) || !strstr(msg, "bad.yaml:11:"))
      fprintf(stderr, "  bad section %zu: %s\n", i, msg);
    AP_CHECK(strstr(msg, bad[i][1]) != NULL);
    AP_CHECK(strstr(msg, "bad.yaml:11:") != NULL);
  }
}


int main(void) {
  find_srcdir();
  test_sweep();
  test_scene_section();
  test_errors();
  return ap_check_finish("lin_misc");
}
