/* The linearization's sweep machinery, its scene section and its error paths (lib/analyze,
 * lib/scene/linearize.c); the closed-form proofs are in tests/test_linearize.c.
 *
 *  - Sweeps: a synthetic spectrum with branches that cross (tracking must keep them apart:
 *    sorting would swap them), zero crossings of a real eigenvalue and of a pair, and a meeting,
 *    at known parameters, found to 1e-12; bad parameter grids refused.
 *  - Scene section: read back (overrides, speed keys with sequences, lists, sweep); bad
 *    sections named with file:line:column and the reason, the overrides of initial: included;
 *    names in free: / independent: that are not state variables refused at the entry's
 *    location with the closest name; a guess with NaN or Inf refused.
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
#include "clitest.h"

static char srcdir[1024];

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
      {"linearize: {sweep: {from: 0, to: 1, count: 1}}", "count"},
      /* overrides of initial: checked where the section writes them (they were reported at
       * the scene's initial: as "set by --set") */
      {"linearize: {initial: {disk: {tilt: 90*dg}}}", "linearize.initial.disk.tilt: unknown "
                                                      "name 'dg'"},
      {"linearize: {initial: {disk: {heading_rat: 0}}}", "did you mean 'heading_rate'"},
      {"linearize: {speed: {disk: {spin_rat: -2}}}", "did you mean 'spin_rate'"},
      {"linearize: {initial: {dsk: {tilt: 1}}}", "no joint named 'dsk' (did you mean 'disk'"}};
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

/* ap_scene_lin_guess_load: the rolling disk's section sets spin_rate = -2 s (v = s m/s at
 * r = 0.5), so the speeds are v0 + s dir with v0 = 0 (upright, no other rate), dir = the
 * speeds at s = 1 (forward speed 1 m/s along x: vx = 1, spin 2 rad/s about the axis), and
 * the scene's own spin_rate -6 gives s = 3; an override -4 gives 2, from text as from the
 * file. Hoffmann's section has no speed: no direction, speed NaN. A missing file fails with
 * its name and leaves nothing to free but the (empty) struct. */
static void test_guess(void) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/rolling_disk.yaml", srcdir);
  ap_scene_lin_guess g;
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load(file, NULL, 0, NULL, 0, &g, msg, sizeof msg), AP_OK);
  AP_CHECK(g.dir != NULL && g.v0 != NULL && g.n == 6 && g.k == 5);
  AP_CHECK_NEAR(g.speed, 3.0, 1e-14);
  double nv0 = 0.0, ndir = 0.0, nres = 0.0;
  for (int i = 0; g.dir && i < g.k; i++) {
    nv0 = fmax(nv0, fabs(g.v0[i])), ndir += g.dir[i] * g.dir[i];
    nres = fmax(nres, fabs(g.v[i] - g.v0[i] - g.speed * g.dir[i]));
  }
  AP_CHECK_NEAR(nv0, 0.0, 1e-15);
  AP_CHECK_NEAR(ndir, 5.0, 1e-14);   /* vx = 1 and |w| = 2 */
  AP_CHECK_NEAR(nres, 0.0, 1e-14);
  AP_CHECK(g.sec.present && g.sec.nspeed == 1);
  ap_lin *L = NULL;   /* the linearizer starts at v0 + s dir */
  AP_CHECK_EQ_INT(ap_scene_lin_create(&g, NULL, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L, g.speed), AP_OK);
  for (int i = 0; L && i < g.k; i++) AP_CHECK_NEAR(ap_lin_v(L)[i], g.v[i], 1e-13);
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
  FILE *f = fopen(file, "rb");
  static char text[8192];
  size_t len = f ? fread(text, 1, sizeof text, f) : 0;
  if (f) fclose(f);
  const char *set[] = {"initial.disk.spin_rate=-4"};
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load("disk.yaml", text, len, set, 1, &g, msg, sizeof msg),
                  AP_OK);
  AP_CHECK_NEAR(g.speed, 2.0, 1e-14);
  ap_scene_lin_guess_free(&g);
  snprintf(file, sizeof file, "%s/examples/scenes/hoffmann.yaml", srcdir);
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load(file, NULL, 0, NULL, 0, &g, msg, sizeof msg), AP_OK);
  AP_CHECK(g.dir == NULL && g.v0 == NULL && isnan(g.speed) && g.sec.about == AP_LIN_EQUILIBRIUM);
  ap_scene_lin_guess_free(&g);
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load("/nonexistent/bike.yaml", NULL, 0, NULL, 0, &g, msg,
                                          sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "/nonexistent/bike.yaml") != NULL && g.scene == NULL && g.q == NULL);
  ap_scene_lin_guess_free(&g);
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load(NULL, NULL, 0, NULL, 0, &g, msg, sizeof msg),
                  AP_ERR_ARG);
}

/* Names in free: / independent: that are not state variables are refused with the closest
 * name, located in the scene (they were ignored); a guess with NaN or Inf, or an infinite speed
 * parameter, is refused with a message naming the entry (it failed later, or not at all). */
static void test_bad_names_and_values(void) {
  char text[2048], msg[1024];
  size_t cut = strstr(scene_text, "linearize:") - scene_text;
  snprintf(text, sizeof text, "%.*slinearize:\n  free:\n    - disk.tilt\n    - disk.tlt\n",
           (int)cut, scene_text);
  ap_scene_lin_guess g;
  AP_CHECK_EQ_INT(ap_scene_lin_guess_load("names.yaml", text, strlen(text), NULL, 0, &g, msg,
                                          sizeof msg), AP_OK);
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_scene_lin_create(&g, NULL, &L), AP_ERR_ARG);
  const char *m = ap_lin_message(L);
  printf("  free: [disk.tilt, disk.tlt]: %s\n", m);
  AP_CHECK(strstr(m, "names.yaml:14:7: linearize.free[1]: 'disk.tlt' is not a state variable") ==
           m);
  AP_CHECK(strstr(m, "did you mean 'disk.tilt'?") != NULL);
  ap_lin_free(L);
  /* the same list given by the caller (not the section's): the library's own message */
  static const char *const indep[] = {"disk.wx", "disk.spin_rate", NULL};
  ap_lin_def def = ap_scene_lin_def(&g);
  def.independent = indep, def.free = NULL;
  AP_CHECK_EQ_INT(ap_scene_lin_create(&g, &def, &L), AP_ERR_ARG);
  m = ap_lin_message(L);
  printf("  independent: [disk.wx, disk.spin_rate]: %s\n", m);
  AP_CHECK(strstr(m, "independent: 'disk.spin_rate' is not a state variable of model") == m);
  AP_CHECK(strstr(m, "disk.wz") != NULL);   /* no close name: the variables are listed */
  ap_lin_free(L);
  def.independent = NULL;
  /* NaN and Inf in the guess, an infinite speed parameter */
  double q[16], v[16];
  memcpy(q, g.q, sizeof *q * (size_t)g.n), memcpy(v, g.v, sizeof *v * (size_t)g.k);
  q[2] = NAN;
  AP_CHECK_EQ_INT(ap_lin_create(ap_scene_model(g.scene), &def, 0.0, q, v, &L), AP_ERR_ARG);
  printf("  q[2] NaN: %s\n", ap_lin_message(L));
  AP_CHECK(strstr(ap_lin_message(L), "coordinate 2 (disk.qw) of the guess is nan") != NULL);
  ap_lin_free(L);
  q[2] = g.q[2], v[4] = -INFINITY;
  AP_CHECK_EQ_INT(ap_lin_create(ap_scene_model(g.scene), &def, 0.0, q, v, &L), AP_ERR_ARG);
  AP_CHECK(strstr(ap_lin_message(L), "speed 4 (disk.wz) of the guess is -inf") != NULL);
  ap_lin_free(L);
  v[4] = g.v[4];
  double dir[16] = {0};
  dir[0] = INFINITY;
  def.speed_dir = dir;
  AP_CHECK_EQ_INT(ap_lin_create(ap_scene_model(g.scene), &def, 0.0, q, v, &L), AP_ERR_ARG);
  AP_CHECK(strstr(ap_lin_message(L), "speed_dir[0] (disk.vx) is inf") != NULL);
  ap_lin_free(L);
  dir[0] = 1.0;
  def.about = AP_LIN_STEADY;
  AP_CHECK_EQ_INT(ap_lin_create(ap_scene_model(g.scene), &def, 0.0, q, v, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L, INFINITY), AP_ERR_ARG);
  AP_CHECK(strstr(ap_lin_message(L), "the speed parameter is inf") != NULL);
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  test_bad_names_and_values();
  test_sweep();
  test_scene_section();
  test_guess();
  test_errors();
  return ap_check_finish("lin_misc");
}
