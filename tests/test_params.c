/* Scene parameters (lib/scene/params.c, docs/scenes.md "Parameters").
 *
 *  - The bicycle (examples/scenes/bicycle.yaml, written with Meijaard's Table 1 names): the
 *    trail set once (--set parameters.c=0.1) must give the same model as the three overrides
 *    that a trail change needed before (steer joint position, front wheel position, front
 *    frame centre of mass, each written out as an expression of the new trail): the same
 *    initial state and the same motion over 1 s, to the last bit (both paths fold the same
 *    expressions in the same order). A different trail must move all three: the run differs.
 *  - The values a scene reports (ap_scene_parameter): Table 1's, and the override.
 *  - Bad parameters, each refused with FILE:LINE:COLUMN and its key path: a cycle (named with
 *    its chain), an unknown name (with "did you mean"), a name taken by a function or constant,
 *    a value that is not a constant expression, --set of a parameter the scene does not have. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

static char srcdir[1024];

/* The old scene's three tied overrides for a trail of 0.1, written out (tests/test_params.c
 * keeps them: they are the reference the parameter must reproduce). */
static const char *const tied[] = {
    "joints.front_frame.parent_frame.pos.0=1.02 + 0.1 - 0.3*tan(pi/10)",
    "joints.front_wheel.parent_frame.pos.0=0.3*tan(pi/10) - 0.1",
    "bodies.front_frame.com.0=0.9 - (1.02 + 0.1 - 0.3*tan(pi/10))"};

/* Load the bicycle with sets, run it 1 s, and leave q(1) and v(1) in x (n + k entries). */
static int run_bicycle(const char *const *sets, int nsets, double *x, int *nx) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/bicycle.yaml", srcdir);
  ap_scene *sc = NULL;
  int rc = ap_scene_load(file, sets, nsets, &sc, msg, sizeof msg);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), rc;
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double q[64], v[64];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  rc = ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_create(m, &run.sim, run.t0, q, v, &sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_advance(sim, 1.0);
  if (rc == AP_OK) {
    memcpy(x, ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(x + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
    *nx = n + k;
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
  return rc;
}

static void test_trail(void) {
  double a[128], b[128], c[128];
  int na = 0, nb = 0, nc = 0;
  const char *once[] = {"parameters.c=0.1"};
  AP_CHECK_EQ_INT(run_bicycle(once, 1, a, &na), AP_OK);
  AP_CHECK_EQ_INT(run_bicycle(tied, 3, b, &nb), AP_OK);
  AP_CHECK_EQ_INT(run_bicycle(NULL, 0, c, &nc), AP_OK);
  AP_CHECK_EQ_INT(na, nb);
  double same = 0.0, moved = 0.0;
  for (int i = 0; i < na && i < nb && i < nc; i++) {
    same = fmax(same, fabs(a[i] - b[i]));
    moved = fmax(moved, fabs(a[i] - c[i]));
  }
  printf("bicycle, trail 0.1 after 1 s: parameter vs three tied overrides differ by %.3g; "
         "vs trail 0.08 by %.3g\n", same, moved);
  AP_CHECK(same == 0.0);
  AP_CHECK(moved > 1e-3);
}

static void test_values(void) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/bicycle.yaml", srcdir);
  const char *sets[] = {"parameters.c=0.1"};
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, sets, 1, &sc, msg, sizeof msg), AP_OK);
  if (!sc) return;
  AP_CHECK_EQ_INT(ap_scene_parameter_count(sc), 26);
  static const struct { const char *name; double value; } table1[] = {
      {"w", 1.02}, {"c", 0.1}, {"lambda", 3.14159265358979323846 / 10}, {"g", 9.81}, {"r_R", 0.3}, {"m_B", 85},
      {"I_Bxz", 2.4}, {"z_H", -0.7}, {"I_Hxz", -0.00756}, {"r_F", 0.35}, {"I_Fyy", 0.28}};
  int found = 0;
  for (int i = 0; i < ap_scene_parameter_count(sc); i++) {
    const char *name = NULL;
    double value = 0.0;
    AP_CHECK_EQ_INT(ap_scene_parameter(sc, i, &name, &value), AP_OK);
    for (size_t j = 0; j < sizeof table1 / sizeof table1[0]; j++)
      if (name && strcmp(name, table1[j].name) == 0) {
        AP_CHECK(value == table1[j].value);
        found++;
      }
  }
  AP_CHECK_EQ_INT(found, (int)(sizeof table1 / sizeof table1[0]));
  ap_scene_free(sc);
}

/* ---- bad parameters ---------------------------------------------------------------------- */

static const char body[] =
    "bodies: {disk: {mass: m, shape: {kind: disk, radius: r}, inertia: uniform}}\n"
    "joints: {disk: {kind: plane_contact}}\n"
    "initial: {disk: {tilt: 80*deg, spin_rate: spin}}\n";

typedef struct bad_param {
  const char *params;   /* the parameters: section */
  const char *set;      /* one override, or NULL */
  const char *where, *what;
} bad_param;

static const bad_param bad[] = {
    {"parameters:\n  m: 2*r\n  r: half + 0.1\n  half: m/4\n  spin: 3\n", NULL,
     "p.yaml:2:6: parameters.m:", "cycle: m -> r -> half -> m"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3*rr\n", NULL, "p.yaml:4:9: parameters.spin:",
     "unknown name 'rr'"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3*rr\n", NULL, "p.yaml:4:9", "did you mean 'r'?"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3\n  exp: 2\n", NULL, "p.yaml:5:3: parameters.exp:",
     "a function of expressions"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3\n  pi: 2\n", NULL, "p.yaml:5:3: parameters.pi:",
     "a constant of expressions"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3*t\n", NULL, "p.yaml:4:9: parameters.spin:",
     "the time t is not allowed"},
    {"parameters:\n  m: 1\n  r: [0.5]\n  spin: 3\n", NULL, "p.yaml:3:6: parameters.r:",
     "expected a scalar"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3\n", "parameters.rr=2", "p.yaml: --set parameters.rr=2",
     "no parameter 'rr' (did you mean 'r'?)"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3\n", "parameters.m=-1", "p.yaml:5:23: bodies.disk.mass",
     "must be positive"},
    {"parameters:\n  m: 1\n  r: 0.5\n  spin: 3\n", "parameters.r=1/0", "parameters.r (set by --set",
     "not a finite number"},
};

static void test_bad(void) {
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char text[2048], msg[1024] = "";
    snprintf(text, sizeof text, "%s%s", bad[i].params, body);
    ap_scene *sc = NULL;
    const char *sets[] = {bad[i].set};
    int rc = ap_scene_load_string(text, strlen(text), "p.yaml", sets, bad[i].set ? 1 : 0, &sc,
                                  msg, sizeof msg);
    int ok = rc == AP_ERR_ARG && strstr(msg, bad[i].where) && strstr(msg, bad[i].what);
    if (!ok) fprintf(stderr, "  case %zu: rc %d, message: %s\n", i, rc, msg);
    else printf("  %s\n", msg);
    AP_CHECK(ok);
    ap_scene_free(sc);
  }
  /* The good version of the same scene loads, and every parameter reaches its use. */
  char text[2048], msg[1024];
  snprintf(text, sizeof text, "parameters: {m: 2*r, r: half + 0.1, half: 0.2, spin: -6}\n%s",
           body);
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load_string(text, strlen(text), "p.yaml", NULL, 0, &sc, msg,
                                       sizeof msg), AP_OK);
  const char *name = NULL;
  double m = 0.0;
  AP_CHECK_EQ_INT(ap_scene_parameter(sc, 0, &name, &m), AP_OK);
  AP_CHECK(name && strcmp(name, "m") == 0 && fabs(m - 0.6) < 1e-15);
  ap_scene_free(sc);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  test_trail();
  test_values();
  test_bad();
  return ap_check_finish("test_params");
}
