/* Contact-mode switches that must not depend on the mode or the method (docs/scenes.md
 * "Friction, slip and lift-off"; lib/integrate/contact_settle.c), against closed forms, in
 * minimal, projected and DAE mode at the differential tester's rtol 1e-8 and at 1e-10. A
 * uniform ball (r = 0.1 m, m = 2 kg) on a free joint, gravity g = 9.81 m/s^2 along -z.
 *
 * Bounces down to rest. Dropped from the gap h = 0.05 m with restitution e = 0.5 (no spin, no
 * slip: the tangential part sticks trivially), it touches down at t1 = V / g, V = sqrt(2 g h),
 * and leaves touchdown i at e^i V, so t_{i+1} = t_i + 2 e^i V / g (free flight is a parabola:
 * every explicit method integrates it exactly, the events are located to round-off). A bounce
 * slower than 1e-6 (1 + max |v_i|) m/s ends in rolling: touchdown i (closing speed e^(i-1) V)
 * bounces while e^i V > 1e-6 (1 + e^(i-1) V), so the run has exactly that many touchdowns
 * plus the last one, each at its closed-form time, and no other switch: a touchdown at a
 * bounce's own state (its gap is round-off there) would add one, a touchdown missed after a
 * step that spans a whole low bounce would leave the ball falling through the floor. IDA
 * (DAE mode) holds q to its tolerance only, so a bounce's time is off by about atol / e^i V:
 * there the touchdowns at 1 mm/s and faster are checked, the rest only for their names and
 * number, and the ball must end on the ground.
 *
 * Ball off a dome. From rest at th0 = 0.01 rad from the top of a fixed sphere (R = 1 m) it
 * rolls (perfectly rough, unilateral) and leaves it where cos(th) = 10/17 cos(th0)
 * (test_contact_modes.c derives it); at lift-off F_n = 0 and the gap is 0 with its rate and
 * acceleration, so round-off decides its sign just after: the run must fly on without a
 * touchdown (the ball flies away from the dome) and follow the parabola from the event's
 * state. Bound: 1e3 rtol for the angle (the event's time is located on the run's state) and
 * the flight.
 *
 * Indeterminate friction. Two wheels on one rigid axle (tests/scenes/difftest/
 * axle_stick_together.yaml): their sideways rows are one row (the axle's sideways motion), so
 * each wheel's tangential rows are combinations of the others and its friction force is not
 * unique; the run's warning must name both contacts. The single ball (3 independent rows)
 * must not be named. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "check.h"

#define G 9.81
static const double R = 0.1, MASS = 2.0;

static ap_model *ball(double mu, double Rg, double e) {
  static double grav[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.mu = mu, c.unilateral = 1;
  c.ground.sphere_radius = Rg, c.restitution = e;
  return bs_free_ball(AP_SHAPE_SPHERE, R, MASS, &c, grav);
}

static const char *mode_name(ap_mode mode) {
  return mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_PROJECTED ? "projected" : "dae";
}

/* The tester's settings: dop853 (bdf, i.e. IDA, in DAE mode), atol = rtol / 100. */
static ap_sim *start(const ap_model *m, ap_mode mode, double rtol, const double *q,
                     const double *v) {
  return bs_start(m, mode, mode == AP_MODE_DAE ? "bdf" : "dop853", rtol, rtol * 1e-2, q, v);
}

static void test_bounces(ap_mode mode, double rtol) {
  double h = 0.05, e = 0.5, V = sqrt(2 * G * h);
  ap_model *m = ball(0.8, 0.0, e);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {0.2, -0.1, R + h, 1, 0, 0, 0}, v[6] = {0, 0, 0, 0, 0, 0};
  ap_sim *s = start(m, mode, rtol, q, v);
  if (!s) return ap_model_free(m);
  int rc = ap_sim_advance(s, 0.5);
  if (rc != AP_OK) printf("  advance: %s\n", ap_sim_message(s));
  AP_CHECK_EQ_INT(rc, AP_OK);
  int n = 1;   /* touchdowns: the bounces, then the last one */
  while (pow(e, n) * V > 1e-6 * (1 + pow(e, n - 1) * V)) n++;
  int got = ap_sim_event_count(s), names = 1, fast = 0;
  double worst = 0.0, tref = V / G;
  for (int i = 0; i < got; i++) {
    ap_event_record r;
    AP_CHECK_EQ_INT(ap_sim_event_get(s, i, &r), AP_OK);
    names &= strcmp(r.name, "roll.touchdown") == 0;
    if (mode != AP_MODE_DAE || pow(e, i) * V >= 1e-3) worst = fmax(worst, fabs(r.t - tref));
    fast += pow(e, i) * V >= 1e-3;
    tref += 2 * pow(e, i + 1) * V / G;
  }
  printf("  bounces to rest (%s, rtol %g): %d touchdowns (closed form %d), all touchdowns: %s, "
         "times off by %.1e s at most%s; mode at 0.5 s: %d\n", mode_name(mode), rtol, got, n,
         names ? "yes" : "no", worst, mode == AP_MODE_DAE ? " (those at >= 1 mm/s)" : "",
         ap_sim_contact_mode(s, 0));
  AP_CHECK(names);
  AP_CHECK_LE(worst, 1e3 * rtol);
  if (mode == AP_MODE_DAE) {   /* IDA: q to its tolerance, not exact on a parabola */
    AP_CHECK(got >= fast && got <= n);
    AP_CHECK(ap_sim_contact_mode(s, 0) != AP_CONTACT_AIRBORNE);
  } else {
    AP_CHECK_EQ_INT(got, n);
    AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
  }
  ap_sim_free(s);
  ap_model_free(m);
}

static void test_dome_flight(ap_mode mode, double rtol) {
  double Rg = 1.0, L = Rg + R, th0 = 0.01, thref = acos(10.0 / 17.0 * cos(th0));
  ap_model *m = ball(-1.0, Rg, 0.0);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {L * sin(th0), 0, L * cos(th0), 1, 0, 0, 0}, v[6] = {0, 0, 0, 0, 0, 0};
  ap_sim *s = start(m, mode, rtol, q, v);
  if (!s) return ap_model_free(m);
  int rc = AP_OK;
  for (int k = 1; k <= 400 && rc == AP_OK && ap_sim_event_count(s) == 0; k++)
    rc = ap_sim_advance(s, 0.01 * k);
  ap_event_record r;
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (ap_sim_event_count(s) != 1 || ap_sim_event_get(s, 0, &r) != AP_OK) {
    AP_CHECK(0);
    ap_sim_free(s);
    return ap_model_free(m);
  }
  double dt = 0.3, p[3], th = atan2(r.q[0], r.q[2]);
  AP_CHECK(strcmp(r.name, "roll.lift_off") == 0);
  AP_CHECK_EQ_INT(ap_sim_advance(s, r.t + dt), AP_OK);
  for (int i = 0; i < 3; i++) p[i] = r.q[i] + r.v[i] * dt;
  p[2] -= 0.5 * G * dt * dt;
  const double *x = ap_sim_q(s);
  double perr = fmax(fabs(x[0] - p[0]), fmax(fabs(x[1] - p[1]), fabs(x[2] - p[2])));
  printf("  dome lift-off (%s, rtol %g): angle off by %.1e rad, %d event(s) in the %.2g s "
         "after, %.1e m off the parabola\n", mode_name(mode), rtol, fabs(th - thref),
         ap_sim_event_count(s) - 1, dt, perr);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  AP_CHECK_NEAR(th, thref, 1e3 * rtol);
  AP_CHECK_LE(perr, 1e3 * rtol);
  ap_sim_free(s);
  ap_model_free(m);
}

/* The warning of the scene at path (its initial state, its own settings), or "" . */
static void scene_warning(const char *path, char *out, size_t len) {
  ap_scene *sc = NULL;
  ap_sim *s = NULL;
  char msg[600] = "";
  out[0] = 0;
  int rc = ap_scene_load(path, NULL, 0, &sc, msg, sizeof msg);
  const ap_model *m = rc == AP_OK ? ap_scene_model(sc) : NULL;
  double *q = m ? calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof(double)) : NULL;
  if (q) rc = ap_scene_initial_state(sc, q, q + ap_model_n(m), NULL, 0, msg, sizeof msg);
  ap_scene_run run;
  if (q && rc == AP_OK) {
    ap_scene_get_run(sc, &run);
    rc = ap_sim_create(m, &run.sim, run.t0, q, q + ap_model_n(m), &s, msg, sizeof msg);
  }
  if (rc != AP_OK || !s) printf("  %s: %s\n", path, msg);
  AP_CHECK(s != NULL);
  if (s) snprintf(out, len, "%s", ap_sim_warning(s));
  ap_sim_free(s);
  free(q);
  ap_scene_free(sc);
}

static void test_indeterminate(const char *root) {
  char path[1024], w[1200];
  snprintf(path, sizeof path, "%s/tests/scenes/difftest/axle_stick_together.yaml", root);
  scene_warning(path, w, sizeof w);
  int c0 = strstr(w, "contact 'c0': its friction rows are combinations") != NULL;
  int c1 = strstr(w, "contact 'c1': its friction rows are combinations") != NULL;
  printf("  axle of two wheels: indeterminate friction named for c0: %s, c1: %s\n",
         c0 ? "yes" : "no", c1 ? "yes" : "no");
  AP_CHECK(c0 && c1);
  ap_model *m = ball(0.8, 0.0, 0.0);
  double q[7] = {0, 0, R, 1, 0, 0, 0}, v[6] = {1, 0, 0, 0, 1 / R, 0};
  ap_sim *s = m ? start(m, AP_MODE_MINIMAL, 1e-8, q, v) : NULL;
  AP_CHECK(s && !strstr(ap_sim_warning(s), "statically indeterminate"));
  ap_sim_free(s);
  ap_model_free(m);
}

int main(int argc, char **argv) {
  printf("contact switches alike in every mode:\n");
  if (argc > 1) test_indeterminate(argv[1]);
  else AP_CHECK(0);   /* the source root is the first argument */
  const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  const double rtols[2] = {1e-8, 1e-10};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 2; j++) {
      test_bounces(modes[i], rtols[j]);
      test_dome_flight(modes[i], rtols[j]);
    }
  return ap_check_finish("test_contact_settle");
}
