/* test_scene_act: joint effects in scene files (docs/scenes.md "effects": joint_torque,
 * joint_force, motor; expressions of the state).
 *
 * Bad scenes (tests/scenes/act_*.yaml): each is refused with AP_ERR_ARG and one message with
 * file:line:column, the key path and a phrase. Good scenes: each runs from its own initial state
 * and settings and is compared with a closed form at every output row:
 *   act_flywheel.yaml   rate motor, saturated then exponential (as test_actuators)
 *   act_torque_t.yaml   joint torque 0.1 cos(t) on a flywheel from rest: w = 0.1 sin(t) / I
 * Tolerances: 100 x the scene's rtol times the scale of the solution, as in test_actuators.
 * The source directory comes as argv[1] (meson passes it). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

static const char *srcdir = ".";

typedef struct bad_case {
  const char *file, *where, *what;   /* "file:L:C: path" and a phrase of the message */
} bad_case;

static const bad_case bad[] = {
    {"act_torque_prismatic.yaml", "act_torque_prismatic.yaml:12:37: effects.spin.joint:",
     "the prismatic joint 'slider' has none (kind: joint_force"},
    {"act_force_revolute.yaml", "act_force_revolute.yaml:12:36: effects.push.joint:",
     "the revolute joint 'wheel' has none (kind: joint_torque"},
    {"act_speed_ambiguous.yaml", "act_speed_ambiguous.yaml:12:9: effects.push:",
     "choose one with speed: (vx, vy)"},
    {"act_speed_wrong_sort.yaml", "act_speed_wrong_sort.yaml:12:50: effects.turn.speed:",
     "speed 'vx' of joint 'sled' is linear"},
    {"act_motor_two_setpoints.yaml",
     "act_motor_two_setpoints.yaml:12:55: effects.motor.angle:", "rate and angle are both"},
    {"act_motor_no_kd.yaml", "act_motor_no_kd.yaml:12:10: effects.motor:",
     "a rate motor needs kd > 0"},
    {"act_motor_kp_rate.yaml", "act_motor_kp_rate.yaml:12:52: effects.motor.kp:",
     "kp belongs to a motor that holds an angle"},
    {"act_motor_angle_ball.yaml", "act_motor_angle_ball.yaml:12:54: effects.motor.angle:",
     "a motor can hold its rate only"},
    {"act_motor_max.yaml", "act_motor_max.yaml:12:62: effects.motor.max:", "must be positive"},
    {"act_unknown_joint.yaml", "act_unknown_joint.yaml:12:31: effects.motor.joint:",
     "no joint named 'wheeel' (did you mean 'wheel'?)"},
    {"act_motor_driven.yaml", "act_motor_driven.yaml:8:31: effects.servo.joint:",
     "the angle of joint 'arm' is driven"},
};

static void test_bad_scenes(void) {
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char file[1200], msg[1024] = "";
    snprintf(file, sizeof file, "%s/tests/scenes/%s", srcdir, bad[i].file);
    ap_scene *sc = NULL;
    int rc = ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg);
    ap_scene_free(sc);
    AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
    int where = strstr(msg, bad[i].where) != NULL, what = strstr(msg, bad[i].what) != NULL;
    AP_CHECK(where && what);
    if (!where || !what)
      fprintf(stderr, "  %s: expected '%s' ... '%s'\n  got: %s\n", bad[i].file, bad[i].where,
                bad[i].what, msg);
    AP_CHECK(strchr(msg, '\n') == NULL);
  }
  printf("bad scenes: %zu refused with file:line:column\n", sizeof bad / sizeof bad[0]);
}

/* ---- good scenes against closed forms ------------------------------------------------------ */

typedef void (*closed_fn)(double t, double *a, double *w);

/* Run a one-joint scene (q = angle, v = rate) over its output times; largest errors. */
static void run_scene(const char *name, closed_fn f, double *ea, double *ew, double *rtol) {
  char file[1200], msg[1024] = "";
  snprintf(file, sizeof file, "%s/tests/scenes/%s", srcdir, name);
  ap_scene *sc = NULL;
  *ea = *ew = HUGE_VAL;
  int rc = ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    return;
  }
  const ap_model *m = ap_scene_model(sc);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  *rtol = run.sim.rtol;
  double x[2] = {0, 0};
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_model_n(m), 1);
  if (ap_scene_initial_state(sc, x, x + 1, NULL, 0, msg, sizeof msg) != AP_OK ||
      ap_sim_create(m, &run.sim, run.t0, x, x + 1, &sim, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "%s: %s\n", name, msg);
    AP_CHECK(0);
  }
  *ea = *ew = 0.0;
  int steps = (int)floor((run.t_end - run.t0) / run.interval + 0.5);
  for (int i = 1; sim && i <= steps; i++) {
    double t = run.t0 + i * run.interval, a, w;
    if (ap_sim_advance(sim, t) != AP_OK) {
      fprintf(stderr, "%s: %s\n", name, ap_sim_message(sim));
      AP_CHECK(0);
      break;
    }
    f(t, &a, &w);
    *ea = fmax(*ea, fabs(ap_sim_q(sim)[0] - a));
    *ew = fmax(*ew, fabs(ap_sim_v(sim)[0] - w));
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
}

/* act_flywheel.yaml: I = 0.05, kd = 0.2, max 0.5 N m, rate 12, from -3 rad/s. */
static void flywheel_closed(double t, double *a, double *w) {
  double I = 0.05, kd = 0.2, M = 0.5, ws = 12.0, w0 = -3.0, tau = I / kd;
  double t1 = (ws - M / kd - w0) * I / M, a1 = w0 * t1 + 0.5 * M / I * t1 * t1;
  if (t <= t1) {
    *w = w0 + M / I * t, *a = w0 * t + 0.5 * M / I * t * t;
    return;
  }
  double e = exp(-(t - t1) / tau), w1 = ws - M / kd;
  *w = ws + (w1 - ws) * e;
  *a = a1 + ws * (t - t1) + (w1 - ws) * tau * (1.0 - e);
}

/* act_torque_t.yaml: I = 0.05, torque 0.1 cos(t), from rest. */
static void torque_closed(double t, double *a, double *w) {
  *w = 0.1 * sin(t) / 0.05;
  *a = 0.1 * (1.0 - cos(t)) / 0.05;
}

static void test_good_scenes(void) {
  double ea, ew, rtol = 0;
  run_scene("act_flywheel.yaml", flywheel_closed, &ea, &ew, &rtol);
  printf("act_flywheel.yaml (rate motor, saturated then exponential): max |w - closed| %.2e "
         "rad/s, |a - closed| %.2e rad\n", ew, ea);
  AP_CHECK_LE(ew, 100 * rtol * 15.0);
  AP_CHECK_LE(ea, 100 * rtol * 15.0 * 3.0);
  run_scene("act_torque_t.yaml", torque_closed, &ea, &ew, &rtol);
  printf("act_torque_t.yaml (joint torque 0.1 cos t): max |w - closed| %.2e rad/s, |a - "
         "closed| %.2e rad\n", ew, ea);
  AP_CHECK_LE(ew, 100 * rtol * 2.0);
  AP_CHECK_LE(ea, 100 * rtol * 4.0 * 6.0);
}

int main(int argc, char **argv) {
  if (argc > 1) srcdir = argv[1];
  test_bad_scenes();
  test_good_scenes();
  return ap_check_finish("test_scene_act");
}
