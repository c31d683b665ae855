/* test_scene_act: joint effects in scene files (docs/scenes.md "effects": joint_torque,
 * joint_force, motor; expressions of the state).
 *
 * Bad scenes (tests/scenes/act_*.yaml): each is refused with AP_ERR_ARG and one message with
 * file:line:column, the key path and a phrase. Good scenes: each runs from its own initial state
 * and settings and is compared with a closed form at every output row:
 *   act_flywheel.yaml   rate motor, saturated then exponential (as test_actuators)
 *   act_torque_t.yaml   joint torque 0.1 cos(t) on a flywheel from rest: w = 0.1 sin(t) / I
 *   act_spring.yaml     torque "-3*hinge.angle": a = a0 cos(W t) + (w0 / W) sin(W t),
 *                       W = sqrt(k / I)
 *   act_slider.yaml     vertical slider, force "-40*slider.position - 0.8*slider.pos_dot":
 *                       damped oscillation about -m g / k
 *   act_follow.yaml     angle motor with set-point "leader.angle" (leader at 3 rad/s): the
 *                       follower lags by kd w / kp (no feed-forward of a state set-point)
 * and the partial derivatives of a state expression from the evaluator's jets (exact); then
 * examples/scenes/diff_drive_motors.yaml (the robot's wheel rates held by motors) against the
 * closed-form steady circle and the motors' steady-state error (test_robot below).
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
     "act_motor_two_setpoints.yaml:12:55: effects.motor.angle:",
     "a motor holds one set-point, and rate is given too"},
    {"act_motor_no_kd.yaml", "act_motor_no_kd.yaml:12:10: effects.motor:",
     "a rate motor needs kd > 0"},
    {"act_motor_kp_rate.yaml", "act_motor_kp_rate.yaml:12:52: effects.motor.kp:",
     "belongs to a motor that holds an angle"},
    {"act_motor_angle_ball.yaml", "act_motor_angle_ball.yaml:12:54: effects.motor.angle:",
     "a motor can hold its rate only"},
    {"act_motor_max.yaml", "act_motor_max.yaml:12:62: effects.motor.max:", "must be positive"},
    {"act_unknown_joint.yaml", "act_unknown_joint.yaml:12:31: effects.motor.joint:",
     "no joint named 'wheeel' (did you mean 'wheel'?)"},
    {"act_motor_driven.yaml", "act_motor_driven.yaml:8:31: effects.servo.joint:",
     "the angle of joint 'arm' is driven"},
    {"act_state_unknown.yaml", "act_state_unknown.yaml:6:54: effects.spring.torque:",
     "unknown name 'hinge.angel' in expression '-3*hinge.angel' (column 4 of the value; did "
     "you mean 'hinge.angle'?)"},
    {"act_state_driven.yaml", "act_state_driven.yaml:8:46: effects.follow.angle:",
     "'arm.angle' is driven: a function of t, not part of the state"},
    {"act_state_not_finite.yaml", "act_state_not_finite.yaml:6:54: effects.spring.torque:",
     "is not finite at t = 0: log(-0.6) = nan (column 4 of the expression)"},
};

/* Load a scene and, if that works, make its initial state (where values of the state are
 * checked). */
static int load_and_init(const char *file, char *msg, size_t len) {
  ap_scene *sc = NULL;
  int rc = ap_scene_load(file, NULL, 0, &sc, msg, len);
  if (rc == AP_OK) {
    const ap_model *m = ap_scene_model(sc);
    double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
    rc = ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, msg, len);
    free(x);
  }
  ap_scene_free(sc);
  return rc;
}

static void test_bad_scenes(void) {
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char file[1200], msg[1024] = "";
    snprintf(file, sizeof file, "%s/tests/scenes/%s", srcdir, bad[i].file);
    int rc = load_and_init(file, msg, sizeof msg);
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

/* Run a scene over its output times and compare coordinate `col` and speed `col` (its rate)
 * with a closed form; largest errors, and the scene's rtol. */
static void run_scene(const char *name, int col, closed_fn f, double *ea, double *ew,
                      double *rtol) {
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
  double x[4] = {0, 0, 0, 0};
  int n = ap_model_n(m);
  ap_sim *sim = NULL;
  AP_CHECK(n == ap_model_k(m) && n <= 2);
  if (ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg) != AP_OK ||
      ap_sim_create(m, &run.sim, run.t0, x, x + n, &sim, msg, sizeof msg) != AP_OK) {
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
    *ea = fmax(*ea, fabs(ap_sim_q(sim)[col] - a));
    *ew = fmax(*ew, fabs(ap_sim_v(sim)[col] - w));
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

/* I e'' + c e' + k e = 0 (underdamped) from e(0) = e0, e'(0) = de0: e and e'. */
static void oscillator(double t, double I, double k, double c, double e0, double de0, double *e,
                       double *de) {
  double W0 = sqrt(k / I), z = c / (2.0 * sqrt(k * I)), s = z * W0, Wd = W0 * sqrt(1 - z * z);
  double A = e0, B = (de0 + s * e0) / Wd, ex = exp(-s * t), C = cos(Wd * t), S = sin(Wd * t);
  *e = ex * (A * C + B * S);
  *de = ex * ((-s * A + Wd * B) * C + (-s * B - Wd * A) * S);
}

/* act_spring.yaml: I = 0.05, torque -3 angle, from (0.4, 2). */
static void spring_closed(double t, double *a, double *w) {
  oscillator(t, 0.05, 3.0, 0.0, 0.4, 2.0, a, w);
}

/* act_slider.yaml: m = 1, force -40 x - 0.8 x' - 9.81, from (0.3, 0). */
static void slider_closed(double t, double *a, double *w) {
  double xe = -9.81 / 40.0;
  oscillator(t, 1.0, 40.0, 0.8, 0.3 - xe, 0.0, a, w);
  *a += xe;
}

/* act_follow.yaml: follower I = 0.05, kp 2, kd 0.06, set-point 3 t from rest: e = a - (3 t -
 * kd 3 / kp) obeys the oscillator from e(0) = 0.09, e'(0) = -3. */
static void follow_closed(double t, double *a, double *w) {
  double lag = 0.06 * 3.0 / 2.0;
  oscillator(t, 0.05, 2.0, 0.06, lag, -3.0, a, w);
  *a += 3.0 * t - lag, *w += 3.0;
}

/* The partials of act_slider's force from the scene's jets: exactly -40, -0.8, 0; then of a
 * nonlinear force of t and the state set with --set, against its derivatives by hand. */
static void test_partials(void) {
  char file[1200], msg[1024] = "";
  snprintf(file, sizeof file, "%s/tests/scenes/act_slider.yaml", srcdir);
  ap_scene *sc = NULL;
  const char *set[] = {"effects.suspension.force=-40*sin(slider.position)*t - "
                       "0.8*slider.pos_dot^2"};
  if (ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    AP_CHECK(0);
    return;
  }
  const ap_model *m = ap_scene_model(sc);
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  d->t = 0.3, d->q[0] = 0.2, d->v[0] = -1.5;
  double tau = 0, dq = 0, dv = 0, dt = 1;
  int col = -1;
  AP_CHECK(ap_body_actuator_partials(m, d, 1, &col, &tau, &dq, &dv, &dt) == AP_OK);
  printf("act_slider.yaml partials from the jets: tau %.17g, dtau/dx %.17g, dtau/dx' %.17g, "
         "dtau/dt %g\n", tau, dq, dv, dt);
  AP_CHECK_EQ_INT(col, 0);
  AP_CHECK_NEAR(tau, -40 * 0.2 - 0.8 * -1.5, 1e-15);
  AP_CHECK_EQ_INT(dq == -40.0 && dv == -0.8 && dt == 0.0, 1);
  ap_data_free(d);
  ap_scene_free(sc);
  sc = NULL;
  if (ap_scene_load(file, set, 1, &sc, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    AP_CHECK(0);
    return;
  }
  m = ap_scene_model(sc);
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  double t = 0.3, x = 0.2, v = -1.5;
  d->t = t, d->q[0] = x, d->v[0] = v;
  AP_CHECK(ap_body_actuator_partials(m, d, 1, &col, &tau, &dq, &dv, &dt) == AP_OK);
  double e_tau = -40 * sin(x) * t - 0.8 * v * v, e_dq = -40 * cos(x) * t, e_dv = -1.6 * v;
  double e_dt = -40 * sin(x), err = fmax(fmax(fabs(tau - e_tau), fabs(dq - e_dq)),
                                         fmax(fabs(dv - e_dv), fabs(dt - e_dt)));
  printf("%s: partials from the jets vs by hand: max difference %.1e\n", set[0], err);
  AP_CHECK_LE(err, 4 * 2.2e-16 * 40);
  ap_data_free(d);
  ap_scene_free(sc);
}

static void test_good_scenes(void) {
  double ea, ew, rtol = 0;
  run_scene("act_flywheel.yaml", 0, flywheel_closed, &ea, &ew, &rtol);
  printf("act_flywheel.yaml (rate motor, saturated then exponential): max |w - closed| %.2e "
         "rad/s, |a - closed| %.2e rad\n", ew, ea);
  AP_CHECK_LE(ew, 100 * rtol * 15.0);
  AP_CHECK_LE(ea, 100 * rtol * 15.0 * 3.0);
  run_scene("act_torque_t.yaml", 0, torque_closed, &ea, &ew, &rtol);
  printf("act_torque_t.yaml (joint torque 0.1 cos t): max |w - closed| %.2e rad/s, |a - "
         "closed| %.2e rad\n", ew, ea);
  AP_CHECK_LE(ew, 100 * rtol * 2.0);
  AP_CHECK_LE(ea, 100 * rtol * 4.0 * 6.0);
  double W = sqrt(3.0 / 0.05), scale = 0.4 * W + 2.0;   /* 4 s = 4.9 periods */
  run_scene("act_spring.yaml", 0, spring_closed, &ea, &ew, &rtol);
  printf("act_spring.yaml (torque -3*hinge.angle): W = sqrt(k/I) = %.4f rad/s: max |a - "
         "closed| %.2e rad, |a' - closed| %.2e rad/s\n", W, ea, ew);
  AP_CHECK_LE(ea, 100 * rtol * scale * 4.0);
  AP_CHECK_LE(ew, 100 * rtol * scale * W * 4.0);
  W = sqrt(40.0), scale = (0.3 + 9.81 / 40) * W;
  run_scene("act_slider.yaml", 0, slider_closed, &ea, &ew, &rtol);
  printf("act_slider.yaml (force -40*slider.position - 0.8*slider.pos_dot): max |x - closed| "
         "%.2e m, |x' - closed| %.2e m/s\n", ea, ew);
  AP_CHECK_LE(ea, 100 * rtol * scale * 5.0);
  AP_CHECK_LE(ew, 100 * rtol * scale * W * 5.0);
  W = sqrt(2.0 / 0.05), scale = 3.0 + 0.09 * W;
  run_scene("act_follow.yaml", 1, follow_closed, &ea, &ew, &rtol);
  printf("act_follow.yaml (angle motor, set-point leader.angle): lag kd w / kp = 0.09 rad: "
         "max |a - closed| %.2e rad, |a' - closed| %.2e rad/s\n", ea, ew);
  AP_CHECK_LE(ea, 100 * rtol * scale * 5.0);
  AP_CHECK_LE(ew, 100 * rtol * scale * W * 5.0);
}

/* ---- the differential-drive robot with motors ----------------------------------------------
 *
 * examples/scenes/diff_drive_motors.yaml: chassis (first moment m a = 10 kg x 0.1 m ahead of
 * the axle) on a planar joint, wheels of radius r = 0.1 m, track b = 0.5 m, rate motors with
 * gain kd at w_l* = 8, w_r* = 12 rad/s. Held exactly, the axle midpoint would run on the circle
 * R = (b/2)(w_r + w_l)/(w_r - w_l) at speed v = r (w_r + w_l)/2, turning at w = v / R.
 * Steady motion on a circle needs ground forces along the heading F_l + F_r = -(m a) w^2 (the
 * centre of mass's tangential acceleration) and F_r - F_l = 2 (m a) v w / b (no moment about
 * the centre of mass: the lateral force M v w acts a_sys = m a / M behind it); each wheel at
 * constant spin needs the motor torque tau_i = r F_i. A motor gives that torque only with the
 * rate error tau_i / kd, so the steady rates solve w_i = w_i* - tau_i(v(w), w(w)) / kd (a fixed
 * point, found by iteration). The test checks the simulated steady rates, speed and radius
 * against that fixed point (100 rtol), and the radius and speed against the ideal closed form
 * within the motors' steady-state error computed from the torques at the ideal motion. */
typedef struct robot { double r, b, ma, kd, wl, wr; } robot;

static void robot_torques(const robot *p, double wl, double wr, double *tl, double *tr) {
  double v = p->r * (wl + wr) / 2, w = p->r * (wr - wl) / p->b;
  double Fs = -p->ma * w * w, Fd = 2 * p->ma * v * w / p->b;
  *tl = p->r * (Fs - Fd) / 2, *tr = p->r * (Fs + Fd) / 2;
}

/* One run of diff_drive_motors.yaml to T in the given mode; the steady state checked. */
static void robot_run(ap_scene *sc, ap_mode mode, double T) {
  robot p = {0.1, 0.5, 10.0 * 0.1, 50.0, 8.0, 12.0};
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double x[16] = {0};
  char msg[1024] = "";
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.mode = mode;
  ap_sim *sim = NULL;
  int iv = ap_model_find_speed(m, "chassis.x_dot");   /* then chassis.y_dot */
  int ih = ap_model_find_speed(m, "chassis.heading_dot");
  int il = ap_model_find_speed(m, "wheel_l.angle_dot");
  int ir = ap_model_find_speed(m, "wheel_r.angle_dot");
  AP_CHECK(n + k <= 16 && iv >= 0 && il >= 0 && ir >= 0 && ih >= 0);
  if (ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg) != AP_OK ||
      ap_sim_create(m, &run.sim, run.t0, x, x + n, &sim, msg, sizeof msg) != AP_OK ||
      ap_sim_advance(sim, T) != AP_OK) {
    fprintf(stderr, "diff_drive_motors: %s %s\n", msg, sim ? ap_sim_message(sim) : "");
    AP_CHECK(0);
    ap_sim_free(sim);
    return;
  }
  const double *v = ap_sim_v(sim);
  double wl = v[il], wr = v[ir], speed = hypot(v[iv], v[iv + 1]), turn = v[ih];
  /* the steady state with the motors' error: fixed point of w = w* - tau(w) / kd */
  double fl = p.wl, fr = p.wr, tl, tr;
  for (int it = 0; it < 60; it++) {
    robot_torques(&p, fl, fr, &tl, &tr);
    fl = p.wl - tl / p.kd, fr = p.wr - tr / p.kd;
  }
  double fv = p.r * (fl + fr) / 2, fw = p.r * (fr - fl) / p.b;
  /* the ideal motion, and the motors' steady-state error at it (first order in 1 / kd) */
  double R0 = p.b / 2 * (p.wr + p.wl) / (p.wr - p.wl), v0 = p.r * (p.wr + p.wl) / 2;
  robot_torques(&p, p.wl, p.wr, &tl, &tr);
  double dl = -tl / p.kd, dr = -tr / p.kd;   /* rate errors w - w* */
  double dR = p.b / 2 * (2 * p.wr * dl - 2 * p.wl * dr) / ((p.wr - p.wl) * (p.wr - p.wl));
  double dv = p.r * (dl + dr) / 2, Rs = speed / turn;
  printf("diff_drive_motors, %s, t = %g s: rates %.10f, %.10f rad/s (off the fixed point by "
         "%.1e, %.1e); R %.8f m, speed %.8f m/s (off by %.1e)\n",
         mode == AP_MODE_MINIMAL ? "minimal" : "projected", T, wl, wr, fabs(wl - fl),
         fabs(wr - fr), Rs, speed, fabs(speed - fv));
  printf("  steady torques at the ideal circle tau_l = %.4f, tau_r = %.4f N m: rate errors "
         "%.2e, %.2e rad/s; R - R0 = %.3e m (first order %.3e), speed - v0 = %.3e m/s (%.3e)\n",
         tl, tr, dl, dr, Rs - R0, dR, speed - v0, dv);
  double tol = 100 * run.sim.rtol;
  AP_CHECK_NEAR(wl, fl, tol * p.wr);
  AP_CHECK_NEAR(wr, fr, tol * p.wr);
  AP_CHECK_NEAR(speed, fv, tol * v0);
  AP_CHECK_NEAR(turn, fw, tol * fw);
  /* against the ideal closed form: within the motors' steady-state error (first order; the
   * second-order part is below 1 % of it at kd = 50) */
  AP_CHECK_LE(fabs(Rs - R0), 1.01 * fabs(dR));
  AP_CHECK_LE(fabs(speed - v0), 1.01 * fabs(dv) + tol * v0);
  AP_CHECK(fabs(Rs - R0) > 0.5 * fabs(dR));   /* and the error is the motors' */
  ap_sim_free(sim);
}

static void test_robot(void) {
  char file[1200], msg[1024] = "";
  snprintf(file, sizeof file, "%s/examples/scenes/diff_drive_motors.yaml", srcdir);
  ap_scene *sc = NULL;
  if (ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    AP_CHECK(0);
    return;
  }
  robot_run(sc, AP_MODE_MINIMAL, 3.0);
  robot_run(sc, AP_MODE_PROJECTED, 3.0);
  ap_scene_free(sc);
}

int main(int argc, char **argv) {
  if (argc > 1) srcdir = argv[1];
  test_bad_scenes();
  test_good_scenes();
  test_partials();
  test_robot();
  return ap_check_finish("test_scene_act");
}
