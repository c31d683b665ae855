/* Complex-step Jacobians of the linearization (lib/analyze/jacobian.c) against Ridders' on every
 * example scene, and the fallback to Ridders.
 *
 * Every scene of examples/scenes (the directory is listed: a new scene is covered without
 * editing this file) is prepared as `appell linearize` prepares it (the linearize: section's
 * guess, speed parameter, free, independent and input lists) and its operating point found;
 * a scene without one must be in `refused` below, with the reason printed. At the point, A =
 * dF/dx is computed twice: by complex step (AP_LIN_COMPLEX_STEP, estimate E_cs) and by
 * Ridders' extrapolated differences (AP_LIN_RIDDERS, estimate E_R). The proof: every
 * entry
 *     |A_cs - A_R| <= 2 (E_R + E_cs) + 16 eps max |A|,
 * the tolerance tests/test_linearize.c gives an entry against its closed form. (Ridders'
 * estimate is a heuristic that the complex step shows to be optimistic by up to about 3 on
 * entries that are zero by symmetry and made of round-off alone, such as the rolling disk's
 * d wy' / d spin; hence the factor 2 and the floor; the figures without them are printed.)
 * The loops of hoffmann.yaml and diff_drive_loops.yaml and the wheel contacts put Newton on
 * complex numbers inside F (the implicit function's derivative). Printed per scene: the
 * largest |A_cs - A_R| / (E_R + E_cs) and the largest E_cs and E_R relative to max |A|.
 * The state-function scenes of tests/scenes (a joint torque -3 angle, a slider force, an angle
 * motor following another joint) are linearized about their equilibria the same way. Under
 * AP_LIN_AUTO every scene uses the complex step. Fallbacks: a model with a user effect or a
 * user constraint is linearized by Ridders under AP_LIN_AUTO with ap_lin_fallback naming the
 * element, and refused (AP_ERR_UNSUPPORTED, named) with AP_LIN_COMPLEX_STEP; so is a state
 * function that gives no partial derivatives (found at evaluation); a math-level system falls
 * back too. The command: `appell linearize` reports the method, `--derivatives ridders` and
 * `complex-step` choose it, anything else is refused (exit 2). The source directory comes as
 * argv[1]. */
#include <complex.h>
#undef I
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "analyze/analyze_int.h"
#include "check.h"
#include "clitest.h"
#include "refsys.h"

static const char *srcdir = ".";

/* ---- the guess of appell linearize ----------------------------------------------------------- */

typedef struct guess {
  ap_scene_lin sec;
  ap_scene *sc;
  double q[64], v[64], v0[64], dir[64], speed;
} guess;

/* Load path with the section's initial sets and the speed keys at coef * s (NaN: none). */
static int load(const char *path, const ap_scene_lin *sec, double s, ap_scene **out, double *q,
                double *v) {
  const char *sets[256];
  char buf[64][160];
  int n = 0;
  for (int i = 0; i < sec->nsets && n < 128; i++) sets[n++] = sec->sets[i];
  for (int i = 0; isfinite(s) && i < sec->nspeed && i < 64; i++) {
    snprintf(buf[i], sizeof buf[i], "%.100s=%.17g", sec->speed_keys[i], sec->speed_coef[i] * s);
    sets[n++] = buf[i];
  }
  char msg[1024];
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, sets, n, &sc, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", path, msg);
  if (rc != AP_OK || !out) ap_scene_free(sc);
  else *out = sc;
  return rc;
}

static int guess_load(const char *path, guess *g) {
  char msg[1024];
  ap_scene *sc0 = NULL;
  memset(g, 0, sizeof *g);
  int rc = ap_scene_load(path, NULL, 0, &sc0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_scene_get_linearize(sc0, &g->sec, msg, sizeof msg);
  ap_scene_free(sc0);
  if (rc != AP_OK) return fprintf(stderr, "%s: %s\n", path, msg), rc;
  rc = load(path, &g->sec, NAN, &g->sc, g->q, g->v);
  g->speed = NAN;
  if (rc != AP_OK || g->sec.nspeed == 0) return rc;
  double qt[64], num = 0.0, den = 0.0;
  int k = ap_model_k(ap_scene_model(g->sc));
  rc = load(path, &g->sec, 0.0, NULL, qt, g->v0);
  if (rc == AP_OK) rc = load(path, &g->sec, 1.0, NULL, qt, g->dir);
  for (int i = 0; rc == AP_OK && i < k; i++) {
    g->dir[i] -= g->v0[i];
    num += (g->v[i] - g->v0[i]) * g->dir[i], den += g->dir[i] * g->dir[i];
  }
  g->speed = den > 0 ? num / den : 0.0;
  return rc;
}

static void guess_free(guess *g) {
  ap_scene_free(g->sc);
  ap_scene_lin_free(&g->sec);
}

/* ---- complex step against Ridders ------------------------------------------------------------ */

static double max_abs(const double *x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

static double worst_all = 0.0;

/* Linearize L (at its operating point) by both methods and compare. */
static void compare(ap_lin *L, const char *label) {
  int nx = ap_lin_nx(L), nn = nx * nx;
  if (nx == 0) return;
  double *Acs = calloc((size_t)nn * 2 + 1, sizeof *Acs), *Ecs = Acs + nn;
  L->def.method = AP_LIN_COMPLEX_STEP;
  int rc = ap_lin_linearize(L);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", label, ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_COMPLEX_STEP);
  if (rc == AP_OK) memcpy(Acs, ap_lin_A(L), sizeof *Acs * (size_t)nn * 1);
  if (rc == AP_OK) memcpy(Ecs, ap_lin_A_error(L), sizeof *Ecs * (size_t)nn);
  L->def.method = AP_LIN_RIDDERS;
  int rr = ap_lin_linearize(L);
  AP_CHECK_EQ_INT(rr, AP_OK);
  AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_RIDDERS);
  if (rc == AP_OK && rr == AP_OK) {
    const double *A = ap_lin_A(L), *E = ap_lin_A_error(L);
    double worst = 0.0, diff = 0.0, est = 0.0, amax = max_abs(Acs, nn);
    int at = 0;
    for (int i = 0; i < nn; i++) {
      double d = fabs(Acs[i] - A[i]), r = d / (E[i] + Ecs[i]);
      double tol = 2.0 * (E[i] + Ecs[i]) + 16 * DBL_EPSILON * amax;
      if (!(d <= tol))
        fprintf(stderr, "  %s A[%s, %s]: complex step %.17g (E %.3g), Ridders %.17g (E %.3g)\n",
                label, ap_lin_state_name(L, i % nx), ap_lin_state_name(L, i / nx), Acs[i],
                Ecs[i], A[i], E[i]);
      AP_CHECK(d <= tol);
      if (d > 0 && r > worst) worst = r, diff = d, est = E[i] + Ecs[i], at = i;
    }
    printf("%-24s nx %2d  max |cs - R| / (E_R + E_cs) %.3g (%.2g / %.2g at A[%s, %s])  "
           "max E_cs / max|A| %.2g  max E_R / max|A| %.2g\n", label, nx, worst, diff, est,
           ap_lin_state_name(L, at % nx), ap_lin_state_name(L, at / nx),
           max_abs(Ecs, nn) / amax, max_abs(E, nn) / amax);
    worst_all = fmax(worst_all, worst);
  }
  L->def.method = AP_LIN_AUTO;
  free(Acs);
}

/* The example scenes that have no operating point (appell linearize refuses them too). */
static const char *const refused[] = {
    "ball_incline.yaml",        /* a ball accelerating down an incline: no steady state */
    "ball_bowl.yaml",           /* released off the bottom of the bowl: not at rest there */
    "diff_drive_motors.yaml",   /* motors driving the wheels: no steady state in the scene's
                                   state, no section */
    "bicycle_falling.yaml",     /* released with a roll rate to fall: no steady state in its
                                   state, no section */
    "bowling_ball.yaml",        /* contact modes: sliding, then rolling: no steady state */
    "fleet_16.yaml",            /* 16 robots on the tree path (path: auto, k = 80); motors from
                                   rest: no steady state either */
    "ball_drop_spin.yaml",      /* falling onto the floor */
    "ball_dome_liftoff.yaml",   /* rolling off the top of a dome */
    "diff_drive_skid.yaml",     /* skidding with locked wheels: its contacts slide */
    "diff_drive_brake.yaml",    /* braking: decelerating, no steady state */
    "ball_bumps.yaml",          /* rolling over bumps: no steady state */
    "bicycle_turn.yaml",        /* bicycle.yaml's section (upright, straight) with a steer
                                   torque: not steady there */
    "car_breakaway.yaml",       /* speeding up in a turn under a drive torque: no steady state */
    NULL};

static int in(const char *const *list, const char *name) {
  for (; *list; list++)
    if (strcmp(*list, name) == 0) return 1;
  return 0;
}

/* One scene: dir/file, about overrides the section's unless < 0. */
static void scene(const char *dir, const char *file, int about) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s/%s", srcdir, dir, file);
  guess g;
  int rc = guess_load(path, &g);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return guess_free(&g);
  const ap_model *m = ap_scene_model(g.sc);
  ap_scene_run run;
  ap_scene_get_run(g.sc, &run);
  ap_lin_def def = ap_lin_def_default();
  def.about = about >= 0 ? (ap_lin_about)about : g.sec.about;
  def.free = (const char *const *)g.sec.free;
  def.independent = (const char *const *)g.sec.independent;
  def.inputs = (const char *const *)g.sec.inputs;
  def.speed_dir = g.sec.nspeed ? g.dir : NULL;
  ap_lin *L = NULL;
  rc = ap_lin_create(m, &def, run.t0, g.q, g.sec.nspeed ? g.v0 : g.v, &L);
  if (rc == AP_OK) rc = ap_lin_operating_point(L, g.speed);
  if (rc == AP_OK) rc = ap_lin_linearize(L);   /* steady only in cyclic rows? */
  if (rc != AP_OK) {
    int ok = in(refused, file);
    printf("%-24s %s: %s\n", file, ok ? "refused as expected" : "REFUSED", ap_lin_message(L));
    AP_CHECK(ok);
    ap_lin_free(L);
    return guess_free(&g);
  }
  AP_CHECK(!in(refused, file));
  if (rc == AP_OK) {
    char why[512];
    AP_CHECK_EQ_INT(ap_core_has_cs(m, why, sizeof why), 1);
    compare(L, file);
    AP_CHECK_EQ_INT(ap_lin_linearize(L), AP_OK);   /* the default: complex step */
    AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_COMPLEX_STEP);
    AP_CHECK(strcmp(ap_lin_fallback(L), "") == 0);
  }
  ap_lin_free(L);
  guess_free(&g);
}

/* ---- models the complex-step build cannot evaluate ------------------------------------------ */

static int user_damping(double t, const double *q, const double *v, double *Q, void *user) {
  (void)t, (void)q, (void)user;
  Q[0] -= 0.1 * v[0];
  return 0;
}

static int user_rows_fn(double t, const double *q, double *A, double *a0, void *user) {
  (void)t, (void)q, (void)a0, (void)user;
  A[0] = 1.0;   /* the pendulum's rate is 0: a trivial row */
  return 0;
}

static int user_gamma_fn(double t, const double *q, const double *v, double *g, void *user) {
  (void)t, (void)q, (void)v, (void)user;
  g[0] = 0.0;
  return 0;
}

/* tau = -3 angle, with (partials) or without (no_partials) df. */
static int spring_fn(const ap_state_args *a, double *f, double *df, void *user) {
  *f = -3.0 * a->x[0];
  if (df && !user) df[0] = 0.0, df[1] = -3.0;
  return 0;
}

/* A pendulum (rod on a revolute joint about x, gravity) with one extra element. */
static ap_model *pendulum(int extra) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  if (ap_builder_create("pendulum", &b) != AP_OK) return NULL;
  ap_body_def bd = ap_body_def_default();
  bd.name = "rod", bd.mass = 1.0, bd.com[2] = -0.5;
  bd.inertia[0] = bd.inertia[4] = bd.inertia[8] = 0.1;
  int body = -1, joint = -1;
  ap_builder_add_body(b, &bd, &body);
  ap_joint_def jd = ap_joint_def_default();
  jd.name = "hinge", jd.kind = AP_JOINT_REVOLUTE, jd.child = body;
  jd.axis[0] = 1, jd.axis[1] = 0, jd.axis[2] = 0;
  ap_builder_add_joint(b, &jd, &joint);
  ap_effect_def g = ap_effect_def_default();
  g.name = "gravity";
  ap_builder_add_effect(b, &g, NULL);
  ap_effect_def e = ap_effect_def_default();
  ap_constraint_def c = ap_constraint_def_default();
  switch (extra) {
    case 1:
      e.name = "drag", e.kind = AP_EFFECT_USER, e.generalized = user_damping;
      ap_builder_add_effect(b, &e, NULL);
      break;
    case 2:
      c.name = "lock", c.kind = AP_CON_USER, c.rows = 1, c.user_constraint = user_rows_fn;
      c.user_gamma = user_gamma_fn;
      ap_builder_add_constraint(b, &c, NULL);
      break;
    case 3:
    case 4:
      e.name = "spring", e.kind = AP_EFFECT_JOINT_FORCE, e.joint = joint, e.state_fn = spring_fn;
      e.ninputs = 1, e.inputs[0].joint = joint, e.inputs[0].speed = 0, e.inputs[0].index = 0;
      e.user = extra == 4 ? (void *)&e : NULL;   /* non-NULL: no partials */
      ap_builder_add_effect(b, &e, NULL);
      break;
  }
  if (ap_builder_compile(b, &m) != AP_OK) fprintf(stderr, "%s\n", ap_builder_message(b));
  ap_builder_free(b);
  return m;
}

/* Linearize m about its equilibrium from the zero state under method; returns the status, with
 * the method used and the fallback note. */
static int lin(const ap_model *m, ap_lin_method method, ap_lin **out) {
  double q[8] = {0}, v[8] = {0};
  ap_lin_def def = ap_lin_def_default();
  def.about = AP_LIN_EQUILIBRIUM, def.method = method;
  int rc = ap_lin_create(m, &def, 0.0, q, v, out);
  if (rc == AP_OK) rc = ap_lin_operating_point(*out, NAN);
  if (rc == AP_OK) rc = ap_lin_linearize(*out);
  return rc;
}

/* Under AP_LIN_AUTO: Ridders, with the fallback naming `name`; with AP_LIN_COMPLEX_STEP:
 * AP_ERR_UNSUPPORTED naming it. */
static void check_fallback(const ap_model *m, const char *name) {
  ap_lin *L = NULL;
  int rc = lin(m, AP_LIN_AUTO, &L);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_RIDDERS);
  AP_CHECK(strstr(ap_lin_fallback(L), name) != NULL);
  printf("  AP_LIN_AUTO: Ridders' (%s)\n", ap_lin_fallback(L));
  ap_lin_free(L);
  L = NULL;
  AP_CHECK_EQ_INT(lin(m, AP_LIN_COMPLEX_STEP, &L), AP_ERR_UNSUPPORTED);
  AP_CHECK(strstr(ap_lin_message(L), name) != NULL);
  printf("  AP_LIN_COMPLEX_STEP: %s\n", ap_lin_message(L));
  ap_lin_free(L);
}

static void fallbacks(void) {
  static const char *const names[] = {"drag", "lock"};
  for (int extra = 1; extra <= 2; extra++) {
    ap_model *m = pendulum(extra);
    AP_CHECK(m != NULL);
    if (!m) continue;
    char why[256] = "";
    AP_CHECK_EQ_INT(ap_core_has_cs(m, why, sizeof why), 0);
    AP_CHECK(strstr(why, names[extra - 1]) != NULL);
    printf("fallback: %s\n", why);
    ap_data_cs *dc = NULL;
    AP_CHECK_EQ_INT(ap_data_create_cs(m, &dc), AP_OK);
    dc->q[0] = 0.3, dc->v[0] = 0.2 + AP_CS_STEP * _Complex_I;
    int rc = ap_fwd_position_cs(m, dc);
    if (rc == AP_OK) rc = ap_fwd_velocity_cs(m, dc);
    AP_CHECK_EQ_INT(rc, AP_ERR_UNSUPPORTED);
    AP_CHECK(strstr(dc->msg, names[extra - 1]) != NULL);
    printf("  refused: %s\n", dc->msg);
    ap_data_free_cs(dc);
    check_fallback(m, names[extra - 1]);
    ap_model_free(m);
  }
  /* a state function with partials: d tau / d angle = -3 exactly; without: refused */
  for (int extra = 3; extra <= 4; extra++) {
    ap_model *m = pendulum(extra);
    AP_CHECK(m != NULL);
    if (!m) continue;
    char why[256] = "";
    AP_CHECK_EQ_INT(ap_core_has_cs(m, why, sizeof why), 1);
    ap_data_cs *dc = NULL;
    AP_CHECK_EQ_INT(ap_data_create_cs(m, &dc), AP_OK);
    dc->basis = AP_BASIS_NONE;
    dc->q[0] = 0.3 + AP_CS_STEP * _Complex_I, dc->v[0] = 0.2;
    int rc = ap_fwd_position_cs(m, dc);
    if (rc == AP_OK) rc = ap_fwd_velocity_cs(m, dc);
    if (extra == 3) {
      AP_CHECK_EQ_INT(rc, AP_OK);
      /* Q = -m g l sin(angle) - 3 angle about x with the com at -0.5 z: dQ = -9.81 0.5 cos - 3 */
      AP_CHECK_NEAR(cimag(dc->Q[0]) / AP_CS_STEP, -9.81 * 0.5 * cos(0.3) - 3.0, 1e-14);
      /* linearized by complex step about angle 0: rate' = -(m g l + 3) / (I + m l^2) angle */
      ap_lin *L = NULL;
      AP_CHECK_EQ_INT(lin(m, AP_LIN_AUTO, &L), AP_OK);
      AP_CHECK_EQ_INT(ap_lin_method_used(L), AP_LIN_COMPLEX_STEP);
      int ia = ap_lin_find_state(L, "rod.angle"), iv = ap_lin_find_state(L, "rod.angle_dot");
      AP_CHECK(ia >= 0 && iv >= 0);
      if (ia >= 0 && iv >= 0) {
        double a = ap_lin_A(L)[iv + ap_lin_nx(L) * ia], ref = -(9.81 * 0.5 + 3.0) / 0.35;
        AP_CHECK_NEAR(a, ref, 2 * ap_lin_A_error(L)[iv + ap_lin_nx(L) * ia] +
                                  16 * DBL_EPSILON * fabs(ref));
      }
      ap_lin_free(L);
    } else {
      AP_CHECK_EQ_INT(rc, AP_ERR_UNSUPPORTED);
      AP_CHECK(strstr(dc->msg, "spring") && strstr(dc->msg, "partial"));
      printf("  refused: %s\n", dc->msg);
      check_fallback(m, "spring");
    }
    ap_data_free_cs(dc);
    ap_model_free(m);
  }
  /* a math-level system: no complex-step data */
  rs_sleigh sp = {1.0, 1.0, 1.0};
  ap_system_def def;
  rs_sleigh_system(&sp, 1, &def);
  ap_model *m = NULL;
  char msg[256];
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_OK);
  ap_data_cs *dc = NULL;
  AP_CHECK_EQ_INT(ap_core_has_cs(m, msg, sizeof msg), 0);
  AP_CHECK(strstr(msg, "math-level") != NULL);
  printf("fallback: %s\n", msg);
  AP_CHECK_EQ_INT(ap_data_create_cs(m, &dc), AP_ERR_UNSUPPORTED);
  AP_CHECK(dc == NULL);
  check_fallback(m, "math-level");
  ap_model_free(m);
}

/* ---- appell linearize --derivatives ----------------------------------------------------------- */

static void command(void) {
  int ok = ct_init("test_lin_cs") == 0;
  AP_CHECK(ok);
  if (!ok) return;
  char scene_file[1200];
  ct_source(scene_file, sizeof scene_file, "examples/scenes", "rolling_disk.yaml");
  const char *dflt[] = {ct_bin, "linearize", scene_file, "--speed", "3", NULL};
  AP_CHECK_EQ_INT(ct_run(dflt), 0);
  AP_CHECK(ct_log_has("derivatives  complex step (exact to round-off)"));
  const char *rid[] = {ct_bin, "linearize", scene_file, "--speed", "3", "--derivatives",
                       "ridders", NULL};
  AP_CHECK_EQ_INT(ct_run(rid), 0);
  AP_CHECK(ct_log_has("derivatives  Ridders' extrapolated differences"));
  const char *cs[] = {ct_bin, "linearize", scene_file, "--speed", "3", "--derivatives",
                      "complex-step", NULL};
  AP_CHECK_EQ_INT(ct_run(cs), 0);
  AP_CHECK(ct_log_has("derivatives  complex step"));
  const char *bad[] = {ct_bin, "linearize", scene_file, "--derivatives", "dual", NULL};
  AP_CHECK_EQ_INT(ct_run(bad), 2);
  AP_CHECK(ct_log_has("--derivatives complex-step or ridders, not 'dual'"));
  ct_finish();
}

static int by_name(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv) {
  if (argc > 1) srcdir = argv[1];
  char dir[1024], *names[256];
  int count = 0;
  snprintf(dir, sizeof dir, "%s/examples/scenes", srcdir);
  DIR *dp = opendir(dir);
  AP_CHECK(dp != NULL);
  for (struct dirent *e; dp && (e = readdir(dp)) && count < 256;) {
    size_t len = strlen(e->d_name);
    if (len > 5 && strcmp(e->d_name + len - 5, ".yaml") == 0) names[count++] = strdup(e->d_name);
  }
  if (dp) closedir(dp);
  qsort(names, (size_t)count, sizeof *names, by_name);
  AP_CHECK(count >= 15);
  for (int i = 0; i < count; i++) scene("examples/scenes", names[i], -1), free(names[i]);
  static const char *const act[] = {"act_spring.yaml", "act_slider.yaml", "act_follow.yaml",
                                    "act_body.yaml"};
  for (size_t i = 0; i < sizeof act / sizeof *act; i++)
    scene("tests/scenes", act[i], AP_LIN_EQUILIBRIUM);
  printf("largest |A_cs - A_R| / (E_R + E_cs) over every scene: %.3g\n", worst_all);
  fallbacks();
  command();
  return ap_check_finish("lin_cs");
}
