/* Motor set-points as inputs (docs/control.md "Inputs") against closed forms.
 *
 * A flywheel of axial inertia I on a revolute joint, driven by a rate motor tau = kd (s - w)
 * whose set-point s is the input "spin.setpoint". With s held over [t_j, t_j + T) the rate
 * relaxes exponentially, a = kd / I, E = exp(-a T):
 *
 *     w_{j+1} = s_j + (w_j - s_j) E,    theta_{j+1} = theta_j + s_j T + (w_j - s_j)(1 - E) / a,
 *
 * which the simulation must reproduce at every instant under a controller s_j = S0 - c w_j
 * (rtol 1e-10 on states of size 1: 1e-8 allowed). While the motor's limit M holds it the
 * torque is M and w grows linearly, w = w0 + M t / I. The input starts at the motor's own
 * set-point. The linearizer's B column for the set-point is d(w')/ds = kd / I (an angle motor:
 * kp / I), 0 while saturated; on the diff-drive robot it is kd times the column of a torque
 * on the same wheel. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#define INERTIA 0.2
#define KDM 0.5
#define PERIOD 0.05
#define S0 3.0
#define CFB 0.5

static const char *fly_scene =
    "name: fly\n"
    "bodies: {fly: {mass: 1, inertia: [0.1, 0.1, 0.2]}}\n"
    "joints: {fly: {kind: revolute, axis: z}}\n"
    "effects: {spin: {kind: motor, joint: fly, %s}}\n"
    "initial: {fly: {rate: 1}}\n"
    "inputs: [spin.setpoint]\n";

static ap_scene *load(const char *motor) {
  char text[1024], msg[512];
  snprintf(text, sizeof text, fly_scene, motor);
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, strlen(text), "fly.yaml", NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  return sc;
}

static ap_sim *make_sim(ap_scene *sc) {
  char msg[512];
  double q[1], v[1];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.rtol = 1e-10, run.sim.atol = 1e-12;
  ap_sim *s = NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(ap_scene_model(sc), &run.sim, 0.0, q, v, &s, msg, sizeof msg),
                  AP_OK);
  int rc = s ? ap_scene_add_inputs(sc, s, msg, sizeof msg) : AP_ERR_ARG;
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  return s;
}

static int feedback(double t, const double *q, const double *v, double *u, void *user) {
  (void)t, (void)q;
  ++*(int *)user;
  u[0] = S0 - CFB * v[0];
  return 0;
}

/* The held set-point against the exact exponential recursion, 40 periods. */
static void test_held_setpoint(void) {
  ap_scene *sc = load("rate: 1, kd: 0.5");
  ap_sim *s = sc ? make_sim(sc) : NULL;
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_input_count(s), 1);
  AP_CHECK(strcmp(ap_sim_input_name(s, 0), "spin.setpoint") == 0);
  AP_CHECK_NEAR(ap_sim_inputs(s)[0], 1.0, 0.0);   /* the motor's own set-point */
  int calls = 0;
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, feedback, PERIOD, &calls), AP_OK);
  double a = KDM / INERTIA, E = exp(-a * PERIOD), th = 0.0, w = 1.0, err = 0.0;
  for (int j = 1; j <= 40; j++) {
    double sp = S0 - CFB * w;
    th += sp * PERIOD + (w - sp) * (1.0 - E) / a;
    w = sp + (w - sp) * E;
    int rc = ap_sim_advance(s, j * PERIOD);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) break;
    err = fmax(err, fmax(fabs(ap_sim_q(s)[0] - th), fabs(ap_sim_v(s)[0] - w)));
  }
  printf("rate motor, set-point held by a controller: largest error %.3g over 40 periods, "
         "%d calls; w -> %.9f (fixed point %.9f)\n", err, calls, w, S0 / (1.0 + CFB));
  AP_CHECK_LE(err, 1e-8);
  AP_CHECK_EQ_INT(calls, 41);   /* t = 0, T, ..., 40 T */
  AP_CHECK_NEAR(ap_sim_inputs(s)[0], S0 - CFB * ap_sim_v(s)[0], 1e-7);
  /* set by hand, no controller: w = s + (w0 - s) exp(-a t) */
  AP_CHECK_EQ_INT(ap_sim_set_controller(s, NULL, 0.0, NULL), AP_OK);
  double t0 = ap_sim_time(s), w0 = ap_sim_v(s)[0];
  AP_CHECK_EQ_INT(ap_sim_set_input(s, "spin.setpoint", -1.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(s, t0 + 1.0), AP_OK);
  AP_CHECK_NEAR(ap_sim_v(s)[0], -1.0 + (w0 + 1.0) * exp(-a), 1e-8);
  AP_CHECK_EQ_INT(ap_sim_set_input(s, "spin.setpont", 0.0), AP_ERR_ARG);
  AP_CHECK(strstr(ap_sim_message(s), "did you mean 'spin.setpoint'") != NULL);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* Saturated: tau = max, w = w0 + max t / I while kd (s - w) > max. */
static void test_saturated(void) {
  ap_scene *sc = load("rate: 0, kd: 0.5, max: 0.1");
  ap_sim *s = sc ? make_sim(sc) : NULL;
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_set_input(s, "spin.setpoint", 10.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2.0), AP_OK);   /* w = 2, kd (s - w) = 4 > 0.1 */
  AP_CHECK_NEAR(ap_sim_v(s)[0], 1.0 + 0.1 * 2.0 / INERTIA, 1e-8);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 2.0 + 0.05 * 4.0 / INERTIA, 1e-8);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* B's column for "name" in a linearization of m about (q, v) with inputs list; row = the
 * state named row. */
static double b_entry(const ap_model *m, const double *q, const double *v,
                      const char *const *inputs, int col, const char *row) {
  ap_lin_def def = ap_lin_def_default();
  def.inputs = inputs;
  def.free = (const char *const[]){"fly.angle_dot", NULL};
  ap_lin *L = NULL;
  int rc = ap_lin_create(m, &def, 0.0, q, v, &L);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", ap_lin_message(L)), ap_lin_free(L), NAN;
  AP_CHECK(strcmp(ap_lin_input_name(L, col), inputs[col]) == 0);
  double b = ap_lin_B(L)[ap_lin_find_state(L, row) + (size_t)col * ap_lin_nx(L)];
  ap_lin_free(L);
  return b;
}

static void test_linearizer(void) {
  const char *const sp[] = {"spin.setpoint", NULL};
  struct { const char *motor; double b; } cases[] = {
    {"rate: 1, kd: 0.5", KDM / INERTIA},                 /* steady at w = 1 */
    {"angle: 0, kp: 4, kd: 0.5", 4.0 / INERTIA},         /* at rest at the angle 0 */
  };
  for (int i = 0; i < 2; i++) {
    ap_scene *sc = load(cases[i].motor);
    if (!sc) continue;
    double q[1] = {0.0}, v[1] = {i == 1 ? 0.0 : 1.0};
    double b = b_entry(ap_scene_model(sc), q, v, sp, 0, "fly.angle_dot");
    double want = cases[i].b;
    printf("B for %-28s %.15g (closed form %.15g)\n", cases[i].motor, b, want);
    AP_CHECK_NEAR(b, want, 1e-13 * want);
    ap_scene_free(sc);
  }
}

/* The robot's wheel motor: B(set-point) = kd B(torque on the same wheel). */
static void test_robot_b(const char *dir) {
  char path[1024], msg[512];
  snprintf(path, sizeof path, "%s/examples/scenes/diff_drive_servo.yaml", dir);
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)fprintf(stderr, "%s\n", msg);
  const ap_model *m = ap_scene_model(sc);
  double q[16] = {0}, v[16] = {0};
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  const char *const in[] = {"wheel_l.angle_dot", "motor_l.setpoint", NULL};
  ap_lin_def def = ap_lin_def_default();
  def.inputs = in;
  ap_lin *L = NULL;
  rc = ap_lin_create(m, &def, 0.0, q, v, &L);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc == AP_OK) {
    int nx = ap_lin_nx(L);
    const double *B = ap_lin_B(L);
    double worst = 0.0, scale = 0.0;
    for (int r = 0; r < nx; r++)
      worst = fmax(worst, fabs(B[r + (size_t)nx] - 2.0 * B[r])), scale = fmax(scale, fabs(B[r]));
    printf("robot: |B(motor_l.setpoint) - kd B(wheel_l torque)| = %.3g (B up to %.3g)\n", worst,
           scale);
    AP_CHECK(scale > 0.1);
    AP_CHECK_LE(worst, 1e-14 * scale);
  } else {
    fprintf(stderr, "%s\n", ap_lin_message(L));
  }
  ap_lin_free(L);
  ap_scene_free(sc);
}

int main(int argc, char **argv) {
  test_held_setpoint();
  test_saturated();
  test_linearizer();
  if (argc > 1) test_robot_b(argv[1]);
  return ap_check_finish("control_motor");
}
