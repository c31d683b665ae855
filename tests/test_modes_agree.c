/* Issue 24's regression: unconstrained chains of quaternion joints (n > k, no constraint rows)
 * in every mode (minimal, projected, plain, DAE) and on both evaluation paths (dense, tree; the
 * DAE mode is dense only). Minimal mode wrote the identity N (n x k) for i < n and ran past N
 * into A, a0 and B of the same block, so the double top started with upper.wz = 54.90.
 *
 * Scenes (tests/scenes/modes_*.yaml): the double top (two ball joints), a chain of three
 * ball joints with revolutes between them, a free body with two ball joints. Per run:
 *   - the speeds the simulation starts from (ap_sim_v after ap_sim_create) equal the scene's
 *     values to round-off: for the double top the closed form upper.w = 150 (0, -sin 30deg,
 *     cos 30deg) (spin_rate 150 about the body axis tilted 30deg about x), elsewhere the
 *     omega/rate/v the scene writes; 1e-13 max|v|;
 *   - energy (nothing adds or removes it) is conserved: |E(t_end) - E(0)| <= 10 rtol (T0 + |V0|)
 *     (the runs' energy error is a sum of local errors each held to rtol of the state);
 *   - every run agrees with the minimal dense run at t_end: per coordinate and speed, within
 *     the sum of the two runs' global errors, each bounded by C (rtol X + atol), C = 10 for the
 *     explicit Appell modes and C = 100 for IDA's variable-order BDF (whose global error is a
 *     larger multiple of rtol). X is the scale of the quantity: for the speeds max|v|; for the
 *     coordinates max(max|q|, t_end max|v|), the angle a joint may have turned through, since
 *     a quaternion's error is half its phase error and the phase error is relative to the
 *     angle travelled (the double top turns through 65 rad). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "clitest.h"

typedef struct speed_ref {
  const char *name;
  double value;
} speed_ref;

typedef struct mscene {
  const char *file;
  speed_ref v[16];   /* closed-form initial speeds; the rest are 0 */
} mscene;

#define DEG (M_PI / 180.0)

static const mscene SCENES[] = {
    {"modes_double_top.yaml",
     {{"upper.wx", 0.0}, {"upper.wy", -150.0 * 0.5}, {"upper.wz", 150.0 * 0.8660254037844386},
      {NULL, 0}}},
    {"modes_chain.yaml",
     {{"a.wx", 1.5}, {"a.wy", -2}, {"a.wz", 30}, {"b.angle_dot", 2}, {"c.wx", -3}, {"c.wy", 1},
      {"c.wz", 25}, {"d.angle_dot", -1.5}, {"e.wx", 4}, {"e.wy", 0.5}, {"e.wz", -20},
      {NULL, 0}}},
    {"modes_free_balls.yaml",
     {{"base.vx", 0.3}, {"base.vy", -0.2}, {"base.vz", 2}, {"base.wx", 1}, {"base.wy", 2},
      {"base.wz", 3}, {"arm.wx", 0}, {"arm.wy", 5}, {"arm.wz", 20}, {"tip.wx", 10},
      {"tip.wy", 0}, {"tip.wz", -5}, {NULL, 0}}},
};

static const char *const MODES[4] = {"minimal", "projected", "plain", "dae"};
static const char *const PATHS[2] = {"dense", "tree"};

typedef struct result {
  int ok;
  double *q, *v;    /* at t_end */
  double rtol, atol;
} result;

/* The scene's closed-form initial speeds in model order. */
static void expected_speeds(const mscene *sc, const ap_model *m, double *v) {
  int k = ap_model_k(m);
  for (int i = 0; i < k; i++) v[i] = 0.0;
  for (const speed_ref *r = sc->v; r->name; r++) {
    int i = ap_model_find_speed(m, r->name);
    AP_CHECK(i >= 0);
    if (i >= 0) v[i] = r->value;
  }
}

static double vmax(int k, const double *v) {
  double mx = 0.0;
  for (int i = 0; i < k; i++) mx = fmax(mx, fabs(v[i]));
  return mx;
}

/* One run of scene sc in mode mi on path pi; *res gets the state at t_end. */
static void run_one(const mscene *sc, int mi, int pi, result *res) {
  char path[1200], set_mode[64], set_path[64], msg[1024] = "";
  ct_source(path, sizeof path, "tests/scenes", sc->file);
  snprintf(set_mode, sizeof set_mode, "simulation.mode=%s", MODES[mi]);
  snprintf(set_path, sizeof set_path, "simulation.path=%s", PATHS[pi]);
  const char *sets[2] = {set_mode, set_path};
  ap_scene *s = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(path, sets, 2, &s, msg, sizeof msg), AP_OK);
  if (!s) {
    fprintf(stderr, "%s: %s\n", sc->file, msg);
    return;
  }
  const ap_model *m = ap_scene_model(s);
  int n = ap_model_n(m), k = ap_model_k(m);
  AP_CHECK_EQ_INT(ap_model_b(m), 0);
  AP_CHECK(n > k);   /* the case of the bug: more coordinates than speeds */
  AP_CHECK_EQ_INT(ap_model_path(m), pi == 0 ? AP_PATH_DENSE : AP_PATH_TREE);
  ap_scene_run run;
  ap_scene_get_run(s, &run);
  double *x = calloc((size_t)(n + 3 * k), sizeof(double));
  double *q0 = x, *v0 = q0 + n, *vref = v0 + k, *v1 = vref + k;
  expected_speeds(sc, m, vref);
  AP_CHECK_EQ_INT(ap_scene_initial_state(s, q0, v0, NULL, 0, msg, sizeof msg), AP_OK);
  double tol = 1e-13 * vmax(k, vref);
  ap_sim *sim = NULL;
  int rc = ap_sim_create(m, &run.sim, run.t0, q0, v0, &sim, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc == AP_OK) {
    memcpy(v1, ap_sim_v(sim), sizeof(double) * (size_t)k);
    for (int i = 0; i < k; i++) {
      AP_CHECK_NEAR(v0[i], vref[i], tol);
      AP_CHECK_NEAR(v1[i], vref[i], tol);
    }
    double E0 = 0, E1 = 0, T0 = 0;
    AP_CHECK_EQ_INT(ap_scene_energy(s, run.t0, q0, v0, &E0), AP_OK);
    rc = ap_sim_advance(sim, run.t_end);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) fprintf(stderr, "%s %s: %s\n", sc->file, MODES[mi], ap_sim_message(sim));
    AP_CHECK_EQ_INT(ap_scene_energy(s, run.t_end, ap_sim_q(sim), ap_sim_v(sim), &E1), AP_OK);
    /* kinetic energy at t0: E0 minus the potential of the zero-speed state */
    double *zero = calloc((size_t)k, sizeof(double)), V0 = 0;
    AP_CHECK_EQ_INT(ap_scene_energy(s, run.t0, q0, zero, &V0), AP_OK);
    T0 = E0 - V0;
    free(zero);
    double bound = 10.0 * run.sim.rtol * (T0 + fabs(V0));
    printf("%-22s %-9s %-5s wz0 %.12g  |dE| %.2e (bound %.2e)\n", sc->file, MODES[mi],
           PATHS[pi], v1[k > 2 ? 2 : 0], fabs(E1 - E0), bound);
    AP_CHECK_LE(fabs(E1 - E0), bound);
    res->ok = rc == AP_OK;
    res->q = malloc(sizeof(double) * (size_t)(n + k));
    res->v = res->q + n;
    memcpy(res->q, ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(res->v, ap_sim_v(sim), sizeof(double) * (size_t)k);
    res->rtol = run.sim.rtol, res->atol = run.sim.atol;
  }
  ap_sim_free(sim);
  free(x);
  ap_scene_free(s);
}

/* Global-error bound of a run in mode mi for a quantity of largest magnitude xmax. */
static double run_bound(int mi, const result *r, double xmax) {
  return (mi == 3 ? 100.0 : 10.0) * (r->rtol * xmax + r->atol);
}

static void compare(const mscene *sc, int n, int k, double t_end, result res[4][2]) {
  const result *ref = &res[0][0];
  if (!ref->ok) return;
  double vm = vmax(k, ref->v), qmax = fmax(vmax(n, ref->q), t_end * vm);
  for (int mi = 0; mi < 4; mi++)
    for (int pi = 0; pi < 2; pi++) {
      const result *r = &res[mi][pi];
      if ((mi == 0 && pi == 0) || (mi == 3 && pi == 1) || !r->ok) continue;
      double dq = 0, dv = 0;
      for (int i = 0; i < n; i++) dq = fmax(dq, fabs(r->q[i] - ref->q[i]));
      for (int i = 0; i < k; i++) dv = fmax(dv, fabs(r->v[i] - ref->v[i]));
      double bq = run_bound(0, ref, qmax) + run_bound(mi, r, qmax);
      double bv = run_bound(0, ref, vm) + run_bound(mi, r, vm);
      printf("%-22s %-9s %-5s vs minimal dense: |dq| %.2e (bound %.2e)  |dv| %.2e (bound "
             "%.2e)\n", sc->file, MODES[mi], PATHS[pi], dq, bq, dv, bv);
      AP_CHECK_LE(dq, bq);
      AP_CHECK_LE(dv, bv);
    }
}

static void scene_all_modes(const mscene *sc) {
  result res[4][2];
  memset(res, 0, sizeof res);
  int n = 0, k = 0;
  double t_end = 0;
  for (int mi = 0; mi < 4; mi++)
    for (int pi = 0; pi < 2; pi++) {
      if (mi == 3 && pi == 1) continue;   /* the DAE mode forms g and A: dense only */
      run_one(sc, mi, pi, &res[mi][pi]);
    }
  /* sizes from the scene (every run has the same model) */
  char path[1200], msg[512];
  ct_source(path, sizeof path, "tests/scenes", sc->file);
  ap_scene *s = NULL;
  if (ap_scene_load(path, NULL, 0, &s, msg, sizeof msg) == AP_OK) {
    n = ap_model_n(ap_scene_model(s)), k = ap_model_k(ap_scene_model(s));
    ap_scene_run run;
    ap_scene_get_run(s, &run);
    t_end = run.t_end - run.t0;
    ap_scene_free(s);
  }
  compare(sc, n, k, t_end, res);
  for (int mi = 0; mi < 4; mi++)
    for (int pi = 0; pi < 2; pi++) free(res[mi][pi].q);
}

int main(void) {
  ct_find_source(ct_src, sizeof ct_src);
  for (size_t i = 0; i < sizeof SCENES / sizeof SCENES[0]; i++) scene_all_modes(&SCENES[i]);
  return ap_check_finish("modes_agree");
}
