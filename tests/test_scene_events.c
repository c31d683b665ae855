/* Scene events (docs/scenes.md "Events") against closed forms, and appell run's handling.
 *
 * 1. tests/scenes/pendulum_events.yaml: a pendulum released from rest at theta0 = 0.5 rad
 *    logs the vertical at K(k) / omega and stops at -0.25 rad at (K(k) + F(phi, k)) / omega,
 *    k = sin(theta0 / 2), sin(phi) = sin(0.125) / k, omega^2 = m g l / (m l^2 + I): the
 *    elliptic integrals by 64-point Gauss-Legendre quadrature of their smooth integrand
 *    (exact to round-off). Event times within 1e-10 relative at rtol 1e-12, in minimal,
 *    projected and DAE modes.
 * 2. appell run on it: exit 0, the last CSV row at the stop event's time, the events on
 *    stderr; appell check's located errors for a bad events: entry.
 * 3. tests/scenes/kinks.yaml: kinks of functions of t hit to round-off (closed form, 1e-10).
 * 4. tests/scenes/motor_saturation.yaml: a rate motor saturating and desaturating at the
 *    closed-form times of its saturated PD law (1e-10 relative).
 * 5. examples/scenes/bicycle_falling.yaml: collide: stop in minimal, projected and DAE modes,
 *    the event times agreeing to 10 rtol.
 * 7. A run failing mid-way: ap_sim_time, ap_sim_q, ap_sim_v and ap_sim_data describe the
 *    last accepted state (against the pendulum's closed form), the failure still located.
 * 6. Built-in events against closed forms, in minimal, projected and DAE modes, 1e-10
 *    relative at rtol 1e-12: tests/scenes/pendulum_floor.yaml, a pendulum's ball touching the
 *    floor (collide) at the elliptic time of its angle; tests/scenes/disk_events.yaml, a
 *    rolling disk pushed along x reaching x = 2.5 at sqrt(3.5) - 1 s and lifting off
 *    (lift_off: F_n = m g - c t) at 1.2 s. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"
#include "refsys.h"

/* F(phi, k) = int_0^phi dpsi / sqrt(1 - k^2 sin^2 psi). */
static double ell_f(double phi, double k) {
  double x[64], w[64], s = 0.0;
  rs_gauss_legendre(64, x, w);
  for (int i = 0; i < 64; i++) {
    double psi = 0.5 * phi * (x[i] + 1.0), sn = sin(psi);
    s += 0.5 * phi * w[i] / sqrt(1.0 - k * k * sn * sn);
  }
  return s;
}

/* A simulation of the scene at path (with sets), from its initial state, in mode (-1: the
 * scene's), with the scene's events when events; *sc receives the scene (free it after the
 * simulation). NULL, with the failure counted, when a step fails. */
static ap_sim *scene_sim(const char *path, const char *const *sets, int nsets, int mode,
                         int events, ap_scene **sc) {
  char msg[1024];
  ap_sim *s = NULL;
  *sc = NULL;
  int rc = ap_scene_load(path, sets, nsets, sc, msg, sizeof msg);
  const ap_model *m = *sc ? ap_scene_model(*sc) : NULL;
  double *x = m ? calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof *x) : NULL;
  if (rc == AP_OK && x)
    rc = ap_scene_initial_state(*sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg);
  ap_scene_run run;
  ap_scene_get_run(*sc, &run);
  if (mode >= 0) run.sim.mode = (ap_mode)mode;
  if (rc == AP_OK && x)
    rc = ap_sim_create(m, &run.sim, run.t0, x, x + ap_model_n(m), &s, msg, sizeof msg);
  if (rc == AP_OK && s && events) rc = ap_scene_add_events(*sc, s, msg, sizeof msg);
  free(x);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", path, msg);
  AP_CHECK(rc == AP_OK && s);
  return s;
}

static void test_pendulum(const char *path, ap_mode mode) {
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, NULL, 0, mode, 1, &sc);
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 5.0), AP_STOPPED);
  double k = sin(0.25), omega = sqrt(9.81 * 1.0 / (1.0 + 0.001));
  double K = ell_f(RS_PI / 2, k), F = ell_f(asin(sin(0.125) / k), k);
  double t_down = K / omega, t_back = (K + F) / omega;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
  ap_event_record a, b;
  AP_CHECK(ap_sim_event_get(s, 0, &a) == AP_OK && ap_sim_event_get(s, 1, &b) == AP_OK);
  AP_CHECK(strcmp(a.name, "down") == 0 && strcmp(b.name, "back") == 0);
  AP_CHECK(a.action == AP_EVENT_LOG && b.action == AP_EVENT_STOP && b.direction == -1);
  printf("pendulum %-9s vertical at %.15f (exact %.15f, %.1e), -0.25 rad at %.15f "
         "(exact %.15f, %.1e)\n", mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_DAE
         ? "dae" : "projected", a.t, t_down, fabs(a.t / t_down - 1), b.t, t_back,
         fabs(b.t / t_back - 1));
  AP_CHECK_LE(fabs(a.t / t_down - 1), 1e-10);
  AP_CHECK_LE(fabs(b.t / t_back - 1), 1e-10);
  AP_CHECK_NEAR(ap_sim_time(s), b.t, 0.0);
  AP_CHECK_NEAR(ap_sim_q(s)[0], -0.25, 1e-10);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* tests/scenes/kinks.yaml: x'' = |t - 1| from rest; the wheel's step response after t = 3. */
static void kinks_exact(double t, double *x, double *q) {
  double u = t - 1.0, tau = t - 3.0, wd = sqrt(15.0);
  *x = t <= 1.0 ? t * t / 2 - t * t * t / 6 : 1.0 / 3 + 0.5 * u + u * u * u / 6;
  *q = t <= 3.0 ? 0.0 : 1.0 - exp(-tau) * (cos(wd * tau) + sin(wd * tau) / wd);
}

/* The kinks hit to round-off (the run matches the smooth pieces to 1e-10 at rtol 1e-12), with
 * the implicit events; without them (events not added) the steps straddle the kinks. */
static void test_kinks(const char *path, ap_mode mode, int with_events) {
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, NULL, 0, mode, with_events, &sc);
  double err = 0.0, x, q;
  if (!s) return ap_scene_free(sc);
  for (int i = 1; i <= 16; i++) {   /* output times off the kinks */
    int rc = ap_sim_advance(s, 0.3 * i);
    if (!with_events && rc != AP_OK) {   /* dop853 cannot step across the set-point's jump */
      printf("kinks without events: %s at t = %.17g\n", ap_strerror(rc), ap_sim_time(s));
      break;
    }
    AP_CHECK_EQ_INT(rc, AP_OK);
    kinks_exact(0.3 * i, &x, &q);
    err = fmax(err, fmax(fabs(ap_sim_q(s)[0] - x), fabs(ap_sim_q(s)[1] - q)));
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  printf("kinks %-9s %s events: max error %.2e, %ld steps, %ld rejected, %d events\n",
         mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_DAE ? "dae" : "projected",
         with_events ? "with   " : "without", err, st.steps, st.err_fails,
         ap_sim_event_count(s));
  if (with_events) {
    ap_event_record a, b;
    AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
    AP_CHECK(ap_sim_event_get(s, 0, &a) == AP_OK && ap_sim_event_get(s, 1, &b) == AP_OK);
    AP_CHECK_NEAR(a.t, 1.0, 4e-16);
    AP_CHECK_NEAR(b.t, 3.0, 1e-15);
    AP_CHECK_LE(err, 1e-10);
  }
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* examples/scenes/bicycle_falling.yaml: stopped by the rear hub guard touching the ground, at
 * the same time in every mode to the run's tolerance (10 rtol: IDA runs at rtol / 10 but its
 * global error is larger, docs/architecture.md), with the hub 0.15 m above the ground. */
static void test_bicycle(const char *path) {
  const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  double times[3] = {NAN, NAN, NAN}, rtol = 0.0;
  for (int i = 0; i < 3; i++) {
    ap_scene *sc = NULL;
    ap_sim *s = scene_sim(path, NULL, 0, modes[i], 1, &sc);
    ap_scene_run run;
    ap_scene_get_run(sc, &run);
    rtol = run.sim.rtol;
    if (s) AP_CHECK_EQ_INT(ap_sim_advance(s, run.t_end), AP_STOPPED);
    ap_event_record r;
    AP_CHECK(ap_sim_event_get(s, 0, &r) == AP_OK && strcmp(r.name, "rear_frame.collide") == 0);
    times[i] = ap_sim_time(s);
    if (s) AP_CHECK_NEAR(ap_sim_q(s)[2], 0.15, 1e-9);   /* rear_frame.z: the hub */
    ap_sim_free(s);
    ap_scene_free(sc);
  }
  printf("falling bicycle stopped at t = %.12f (minimal), %.12f (projected), %.12f (dae)\n",
         times[0], times[1], times[2]);
  AP_CHECK_NEAR(times[1], times[0], 10 * rtol * times[0]);
  AP_CHECK_NEAR(times[2], times[0], 10 * rtol * times[0]);
}

/* tests/scenes/motor_saturation.yaml: the saturation switching at its closed-form times. */
static void test_saturation(const char *path, ap_mode mode) {
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, NULL, 0, mode, 1, &sc);
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 10.0), AP_OK);
  double t1 = 2.0, v4 = 10.0 - 2.0 * exp(-4.0), t3 = 4.0 + (v4 + 8.0) / 4.0;
  const char *names[4] = {"saturation of motor (+max)", "kink 1 of effects.motor.rate",
                          "saturation of motor (-max)", "saturation of motor (-max)"};
  const double times[4] = {t1, 4.0, 4.0, t3};
  const int dirs[4] = {-1, 1, -1, 1};
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 4);
  double worst = 0.0;
  for (int i = 0; i < 4 && i < ap_sim_event_count(s); i++) {
    ap_event_record r;
    AP_CHECK(ap_sim_event_get(s, i, &r) == AP_OK);
    AP_CHECK(strcmp(r.name, names[i]) == 0);
    AP_CHECK_EQ_INT(r.direction, dirs[i]);
    worst = fmax(worst, fabs(r.t / times[i] - 1));
  }
  double v10 = -10.0 + 2.0 * exp(-2.0 * (10.0 - t3));   /* unsaturated again after t3 */
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  printf("saturated PD motor %-9s: switch times off by %.1e (relative), v(10) off by %.1e, "
         "%ld steps, %ld rejected\n", mode == AP_MODE_MINIMAL ? "minimal" : "dae", worst,
         fabs(ap_sim_v(s)[0] - v10), st.steps, st.err_fails);
  AP_CHECK_LE(worst, 1e-10);
  AP_CHECK_NEAR(ap_sim_v(s)[0], v10, 1e-9);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* Built-ins: joint_range on the pendulum (leaves [-0.3, 0.6] at -0.3 rad, the elliptic time),
 * and lift_off and collide on the rolling disk (F_n = m g and the rim on the ground: they
 * evaluate at every step and never cross). */
static void test_builtins(const char *pend, const char *disk) {
  const char *range[] = {"events={range: {kind: joint_range, joint: hinge, min: -0.3, max: 0.6}}"};
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(pend, range, 1, -1, 1, &sc);
  if (s) AP_CHECK_EQ_INT(ap_sim_advance(s, 5.0), AP_STOPPED);
  double k = sin(0.25), omega = sqrt(9.81 / 1.001);
  double t_exit = (ell_f(RS_PI / 2, k) + ell_f(asin(sin(0.15) / k), k)) / omega;
  printf("joint_range: left at t = %.15f (exact %.15f)\n", ap_sim_time(s), t_exit);
  AP_CHECK_NEAR(ap_sim_time(s), t_exit, 1e-10 * t_exit);
  if (s) AP_CHECK_NEAR(ap_sim_q(s)[0], -0.3, 1e-10);
  ap_sim_free(s);
  ap_scene_free(sc);
  const char *lift[] = {"events={lift: {kind: lift_off, constraint: roll, action: log}, "
                        "low: {kind: collide, body: disk, action: log}}"};
  s = scene_sim(disk, lift, 1, -1, 1, &sc);
  if (s) AP_CHECK_EQ_INT(ap_sim_advance(s, 1.0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 0);
  ap_sim_free(s);
  ap_scene_free(sc);
}

static const char *mode_name(ap_mode mode) {
  return mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_DAE ? "dae" : "projected";
}

/* tests/scenes/pendulum_floor.yaml: collide: stop of the ball on the floor when the angle
 * falls through 0.25 rad, at (K(k) - F(phi, k)) / omega. */
static void test_floor(const char *path, ap_mode mode) {
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, NULL, 0, mode, 1, &sc);
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 5.0), AP_STOPPED);
  double k = sin(0.25), omega = sqrt(9.81 / 1.001);
  double t_hit = (ell_f(RS_PI / 2, k) - ell_f(asin(sin(0.125) / k), k)) / omega;
  ap_event_record r;
  AP_CHECK(ap_sim_event_get(s, 0, &r) == AP_OK && strcmp(r.name, "bob.collide") == 0);
  printf("collide %-9s ball on the floor at %.15f (exact %.15f, %.1e)\n", mode_name(mode),
         r.t, t_hit, fabs(r.t / t_hit - 1));
  AP_CHECK_LE(fabs(r.t / t_hit - 1), 1e-10);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 0.25, 1e-10);
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* tests/scenes/disk_events.yaml: a rolling disk pushed along x reaches x = 2.5 at
 * sqrt(3.5) - 1 (logged) and lifts off (F_n = m g - c t) at t = 1.2 (stop). */
static void test_disk(const char *path, ap_mode mode) {
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, NULL, 0, mode, 1, &sc);
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2.0), AP_STOPPED);
  ap_event_record far, lift;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
  AP_CHECK(ap_sim_event_get(s, 0, &far) == AP_OK && ap_sim_event_get(s, 1, &lift) == AP_OK);
  AP_CHECK(strcmp(far.name, "far") == 0 && strcmp(lift.name, "lift") == 0);
  double t_far = sqrt(3.5) - 1.0, t_lift = 1.2;
  printf("disk %-9s x = 2.5 at %.15f (exact %.15f, %.1e), lift-off at %.15f (exact 1.2, "
         "%.1e)\n", mode_name(mode), far.t, t_far, fabs(far.t / t_far - 1), lift.t,
         fabs(lift.t / t_lift - 1));
  AP_CHECK_LE(fabs(far.t / t_far - 1), 1e-10);
  AP_CHECK_LE(fabs(lift.t / t_lift - 1), 1e-10);
  AP_CHECK_NEAR(ap_sim_time(s), lift.t, 0.0);
  AP_CHECK_NEAR(ap_sim_q(s)[0], 2.0 * 1.2 + 1.2 * 1.2, 1e-10);   /* x = v0 t + t^2 */
  ap_sim_free(s);
  ap_scene_free(sc);
}

/* A run that fails mid-way (a torque sqrt(angle) of the pendulum, not finite once the angle
 * is negative, first after K(k) / omega): ap_sim_time, ap_sim_q and ap_sim_v describe the
 * same last accepted state (the angle there is the closed form's at that time to the run's
 * tolerance, v consistent with the data), and the failure is still located at the failing
 * evaluation (ap_sim_failed_state: a negative angle), in every mode. */
static void test_failure_state(const char *path, ap_mode mode) {
  const char *set[] = {"effects={gravity: {kind: gravity}, push: {kind: joint_torque, joint: "
                       "hinge, torque: \"1e-12*sqrt(hinge.angle)\"}}", "events={}"};
  ap_scene *sc = NULL;
  ap_sim *s = scene_sim(path, set, 2, mode, 1, &sc);
  if (!s) return ap_scene_free(sc);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 0.4), AP_OK);
  int rc = ap_sim_advance(s, 1.0);
  AP_CHECK(rc != AP_OK && rc != AP_STOPPED);
  double k = sin(0.25), omega = sqrt(9.81 / 1.001), t = ap_sim_time(s);
  double t_down = ell_f(RS_PI / 2, k) / omega;
  const ap_data *d = ap_sim_data(s);
  /* theta(t) = 2 asin(k sn(K - omega t)): from the angle at t, the time back to the vertical */
  double q = ap_sim_q(s)[0], v = ap_sim_v(s)[0];
  double t_of_q = (ell_f(RS_PI / 2, k) - ell_f(asin(sin(q / 2) / k), k)) / omega;
  printf("failure %-9s at t = %.15f (last output 0.4), q = %.3e (time of that angle %.15f), "
         "v = %.6f\n", mode_name(mode), t, q, t_of_q, v);
  AP_CHECK(t > 0.4 && t <= t_down + 1e-9);
  AP_CHECK_NEAR(t_of_q, t, 1e-8);
  AP_CHECK_NEAR(d->t, t, 0.0);
  AP_CHECK_NEAR(d->q[0], q, 0.0);
  AP_CHECK_NEAR(d->v[0], v, 0.0);
  /* the speed: energy 0.5 J v^2 = m g l (cos q - cos 0.5) */
  AP_CHECK_NEAR(v, -sqrt(2 * 9.81 * (cos(q) - cos(0.5)) / 1.001), 1e-8);
  double tf = NAN;
  const double *qf = NULL;
  AP_CHECK_EQ_INT(ap_sim_failed_state(s, &tf, &qf, NULL), AP_OK);
  if (qf) AP_CHECK(qf[0] < 0 && tf >= t);
  char msg[1024];
  AP_CHECK_EQ_INT(ap_scene_locate_failure(sc, s, NAN, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "sqrt(hinge.angle)") != NULL);
  ap_sim_free(s);
  ap_scene_free(sc);
}

static double last_time(const char *csv) {
  FILE *f = fopen(csv, "r");
  char line[4096];
  double t = NAN;
  while (f && fgets(line, sizeof line, f))
    if (line[0] != 't') t = strtod(line, NULL);
  if (f) fclose(f);
  return t;
}

static void test_cli(const char *path) {
  char csv[1200];
  snprintf(csv, sizeof csv, "%s/p.csv", ct_tmp);
  const char *argv[] = {ct_bin, "run", path, "--out", csv, NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_log_has("event 'down' at t = ") && ct_log_has("event 'back' at t = "));
  AP_CHECK(ct_log_has("(falling, stop)"));
  double k = sin(0.25), omega = sqrt(9.81 / 1.001);
  double t_back = (ell_f(RS_PI / 2, k) + ell_f(asin(sin(0.125) / k), k)) / omega;
  AP_CHECK_NEAR(last_time(csv), t_back, 1e-9 * t_back);   /* printed to 15 digits */
  remove(csv);
  const char *sets[][2] = {
      {"events.back.when=hinge.angel", "did you mean 'hinge.angle'?"},
      {"events.back.direction=up", "unknown direction 'up'"},
      {"events.back.action=halt", "events.back.action: unknown action 'halt'"},
      {"events.back.when=3", "is a constant"}};
  for (int i = 0; i < 4; i++) {
    const char *chk[] = {ct_bin, "check", path, "--set", sets[i][0], NULL};
    AP_CHECK_EQ_INT(ct_run(chk), 2);
    AP_CHECK(ct_log_has(sets[i][1]));
  }
}

int main(void) {
  if (ct_init("scene_events") != 0) return 1;
  char path[1200];
  ct_source(path, sizeof path, "tests/scenes", "pendulum_events.yaml");
  test_pendulum(path, AP_MODE_MINIMAL);
  test_pendulum(path, AP_MODE_PROJECTED);
  test_pendulum(path, AP_MODE_DAE);
  test_cli(path);
  test_failure_state(path, AP_MODE_MINIMAL);
  test_failure_state(path, AP_MODE_PROJECTED);
  test_failure_state(path, AP_MODE_DAE);
  char disk[1200];
  ct_source(disk, sizeof disk, "examples/scenes", "rolling_disk.yaml");
  test_builtins(path, disk);
  ct_source(path, sizeof path, "tests/scenes", "kinks.yaml");
  test_kinks(path, AP_MODE_MINIMAL, 0);
  test_kinks(path, AP_MODE_MINIMAL, 1);
  test_kinks(path, AP_MODE_PROJECTED, 1);
  test_kinks(path, AP_MODE_DAE, 0);
  test_kinks(path, AP_MODE_DAE, 1);
  ct_source(path, sizeof path, "tests/scenes", "motor_saturation.yaml");
  test_saturation(path, AP_MODE_MINIMAL);
  test_saturation(path, AP_MODE_DAE);
  ct_source(path, sizeof path, "examples/scenes", "bicycle_falling.yaml");
  test_bicycle(path);
  const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  for (int i = 0; i < 3; i++) {
    ct_source(path, sizeof path, "tests/scenes", "pendulum_floor.yaml");
    test_floor(path, modes[i]);
    ct_source(path, sizeof path, "tests/scenes", "disk_events.yaml");
    test_disk(path, modes[i]);
  }
  ct_finish();
  return ap_check_finish("scene_events");
}
