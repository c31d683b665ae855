/* Contact modes in DAE mode (docs/design.md "Contact modes in DAE mode"): IDA made again at
 * each switch, the sliding contact's Coulomb force coupled to the normal row's multiplier, the
 * lift-off event on IDA's own multipliers. The ball of tests/test_contact_modes.c (uniform
 * sphere r = 0.1 m, m = 2 kg, free joint, g = 9.81 m/s^2), against the same closed forms
 * (derived there) and against the minimal-mode run (dop853) at the same tolerances:
 *
 *   bowling ball   launched at v0 = 3 m/s without spin, mu = 0.2: slides, rolls from
 *                  t* = 2 v0 / (7 mu g), at 5/7 v0, having lost m v0^2 / 7;
 *   ball off a dome  rolling from rest 0.01 rad from the top of a sphere of radius 1 m
 *                  (unilateral, perfectly rough): lifts off at cos th = 10/17 cos th0, then
 *                  flies: 0.15 s later on the parabola from the event's state.
 *
 * Tolerances. The runs use rtol = 1e-10, atol = 1e-12. IDA runs at rtol / 10
 * (AP_DAE_TOL_FACTOR) so that its global error on smooth motions stays near the requested rtol
 * (docs/design.md "The DAE cross-check"), and each switch restarts BDF at order 1. The checks
 * are at TOLF = 10 rtol for the event times, angles, speeds and positions, all of order 1 (the
 * dome's angle error is its time error times th' of about 3 rad/s; the energy's is m v0 times
 * the speed's): one decade above rtol, the margin the other DAE cross-checks use, and far below
 * what a lost coupling would give (without the friction term the ball never rolls). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "check.h"

#define G 9.81
#define RTOL 1e-10
#define ATOL 1e-12
#define TOLF (10 * RTOL)
static const double R = 0.1, MASS = 2.0;

static ap_model *ball(double mu, int unilateral, double Rg) {
  ap_constraint_def c = ap_constraint_def_default();
  double g[3] = {0, 0, -G};
  c.name = "roll", c.mu = mu, c.unilateral = unilateral, c.ground.sphere_radius = Rg;
  return bs_free_ball(AP_SHAPE_SPHERE, R, MASS, &c, g);
}

static ap_sim *start(const ap_model *m, ap_mode mode, const double *q, const double *v) {
  return bs_start(m, mode, mode == AP_MODE_DAE ? NULL : "dop853", RTOL, ATOL, q, v);
}

static const char *mode_name(ap_mode mode) { return mode == AP_MODE_DAE ? "DAE" : "minimal"; }

/* The last event record of s, named name (1 when found). */
static int last_event(const ap_sim *s, const char *name, ap_event_record *r) {
  int n = ap_sim_event_count(s);
  return n > 0 && ap_sim_event_get(s, n - 1, r) == AP_OK && strcmp(r->name, name) == 0;
}

/* Bowling ball: stick time, final speed, energy lost; into out (t*, vx, wy, loss). */
static void bowling(ap_mode mode, double *out) {
  double mu = 0.2, v0 = 3.0, ts = 2 * v0 / (7 * mu * G);
  ap_model *m = ball(mu, -1, 0.0);
  double q[7] = {0, 0, R, 1, 0, 0, 0}, v[6] = {v0, 0, 0, 0, 0, 0};
  ap_sim *s = m ? start(m, mode, q, v) : NULL;
  AP_CHECK(s != NULL);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  ap_event_record r0;                                    /* sliding from t0: its slip event */
  AP_CHECK(last_event(s, "roll.slip", &r0) && r0.t == 0.0 && ap_sim_event_count(s) == 1);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2 * ts), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
  ap_event_record r;
  int found = last_event(s, "roll.stick", &r);
  AP_CHECK(found);
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  const double *vq = ap_sim_v(s);
  double loss = 0.5 * MASS * v0 * v0 - (d ? bs_energy(m, d, ap_sim_q(s), vq) - MASS * G * R : 0);
  out[0] = found ? r.t : NAN, out[1] = vq[0], out[2] = vq[4], out[3] = loss;
  printf("  bowling ball (%s): rolls at t = %.15g (closed form %.15g, error %.1e), speed %.15g "
         "(error %.1e), energy lost %.15g J (error %.1e), %d events\n", mode_name(mode),
         out[0], ts, fabs(out[0] - ts), vq[0], fabs(vq[0] - 5 * v0 / 7), loss,
         fabs(loss - MASS * v0 * v0 / 7), ap_sim_event_count(s));
  AP_CHECK_NEAR(out[0], ts, TOLF);
  AP_CHECK_NEAR(vq[0], 5 * v0 / 7, TOLF);
  AP_CHECK_NEAR(vq[4], 5 * v0 / 7 / R, TOLF / R);
  AP_CHECK_NEAR(loss, MASS * v0 * v0 / 7, TOLF);
  ap_data_free(d);
  ap_sim_free(s);
  ap_model_free(m);
}

/* Ball off a dome: lift-off angle and time, and the flight; into out (th, t, x, z). */
static void dome(ap_mode mode, double *out) {
  double Rg = 1.0, L = Rg + R, th0 = 0.01, thref = acos(10.0 / 17.0 * cos(th0));
  ap_model *m = ball(-1.0, 1, Rg);
  double q[7] = {L * sin(th0), 0, L * cos(th0), 1, 0, 0, 0}, v[6] = {0};
  ap_sim *s = m ? start(m, mode, q, v) : NULL;
  AP_CHECK(s != NULL);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2.2), AP_OK);   /* past the lift-off (2.083 s) */
  ap_event_record r;
  int found = last_event(s, "roll.lift_off", &r);
  AP_CHECK(found);
  if (!found) {
    ap_sim_free(s);
    return ap_model_free(m);
  }
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  double th = atan2(r.q[0], r.q[2]), dt = 0.15, p[3];
  AP_CHECK_EQ_INT(ap_sim_advance(s, r.t + dt), AP_OK);
  for (int i = 0; i < 3; i++) p[i] = r.q[i] + r.v[i] * dt;
  p[2] -= 0.5 * G * dt * dt;
  const double *x = ap_sim_q(s);
  double perr = fmax(fabs(x[0] - p[0]), fmax(fabs(x[1] - p[1]), fabs(x[2] - p[2])));
  out[0] = th, out[1] = r.t, out[2] = x[0], out[3] = x[2];
  printf("  ball off a dome (%s): lift-off at t = %.15g, angle %.15g rad, closed form %.15g "
         "(error %.1e); flight %.2g s later off the parabola by %.1e m\n", mode_name(mode), r.t,
         th, thref, fabs(th - thref), dt, perr);
  AP_CHECK_NEAR(th, thref, TOLF);
  AP_CHECK_LE(perr, TOLF);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  ap_sim_free(s);
  ap_model_free(m);
}

/* Slip onset off the dome (test_dome_slip of tests/test_contact_modes.c): with mu = 0.5 the
 * rolling ball's friction ratio 2 sin th / (17 cos th - 10 cos th0) reaches mu before F_n
 * vanishes; the slip event (on IDA's multipliers in DAE mode) against the root of
 * 2 sin th = mu (17 cos th - 10 cos th0) (Newton's iteration); into out (angle). */
static void dome_slip(ap_mode mode, double *out) {
  double Rg = 1.0, L = Rg + R, th0 = 0.01, mu = 0.5, th = 0.7;
  for (int i = 0; i < 50; i++)
    th -= (2 * sin(th) - mu * (17 * cos(th) - 10 * cos(th0))) / (2 * cos(th) + 17 * mu * sin(th));
  ap_model *m = ball(mu, -1, Rg);
  double q[7] = {L * sin(th0), 0, L * cos(th0), 1, 0, 0, 0}, v[6] = {0};
  ap_sim *s = m ? start(m, mode, q, v) : NULL;
  AP_CHECK(s != NULL);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 1.99), AP_OK);   /* just past the slip (1.98 s) */
  ap_event_record r;
  int found = ap_sim_event_count(s) == 1 && last_event(s, "roll.slip", &r);
  AP_CHECK(found);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  out[0] = found ? atan2(r.q[0], r.q[2]) : NAN;
  printf("  ball off a dome with mu %g (%s): slips at %.15g rad, closed form %.15g (error %.1e)\n",
         mu, mode_name(mode), out[0], th, fabs(out[0] - th));
  AP_CHECK_NEAR(out[0], th, TOLF);
  ap_sim_free(s);
  ap_model_free(m);
}

/* A thin uniform disk (r = 0.3 m, 1.5 kg) sliding and spinning with its axis 50 deg from the
 * vertical, mu = 0.3 (test_sliding_disk of tests/test_contact_modes.c): its friction has a
 * moment that changes the normal force (1 + u != 1), so the Coulomb force must use the
 * coupled F_n, here IDA's own multiplier. F_n / (m g) at 0.02, 0.04, 0.06, 0.08 s and the state
 * after 0.08 s into out (4 + 6; F_n from IDA's multipliers in DAE mode, from the coupled solve
 * in minimal mode), and |F_t| / F_n = mu of the reported contact force. */
static void sliding_disk(ap_mode mode, double *out) {
  double r = 0.3, mu = 0.3, tilt = 50 * 3.14159265358979323846 / 180, g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "slide", c.mu = mu;
  ap_model *m = bs_free_ball(AP_SHAPE_DISK, r, 1.5, &c, g);
  double q[7] = {0, 0, r * sin(tilt), cos(tilt / 2), sin(tilt / 2), 0, 0};
  double v[6] = {1.0, 0.5, 0.0, 0.0, 0.0, 6.0}, worst = 0.0;
  ap_sim *s = m ? start(m, mode, q, v) : NULL;
  AP_CHECK(s != NULL);
  if (!s) return ap_model_free(m);
  int n = 0;
  for (int i = 1; i <= 4 && ap_sim_advance(s, 0.02 * i) == AP_OK; i++) {
    const double *lambda = NULL;
    ap_contact_force f;
    if (ap_sim_contact_mode(s, 0) != AP_CONTACT_SLIDING || ap_sim_reactions(s, &lambda) != AP_OK ||
        ap_body_contact_force(m, ap_sim_data(s), lambda, 0, &f) != AP_OK)
      break;
    worst = fmax(worst, fabs(f.friction_ratio - mu));
    out[n++] = f.normal / (1.5 * G);
  }
  memcpy(out + 4, ap_sim_q(s), 3 * sizeof *out), memcpy(out + 7, ap_sim_v(s), 3 * sizeof *out);
  printf("  sliding disk (%s, axis 50 deg from vertical, mu %g): |F_t| / F_n - mu worst %.1e "
         "over %d times\n", mode_name(mode), mu, worst, n);
  AP_CHECK_EQ_INT(n, 4);
  AP_CHECK_LE(worst, TOLF);
  ap_sim_free(s);
  ap_model_free(m);
}

/* The DAE run against the minimal-mode run: each of n numbers within tol. */
static void against_minimal(const char *what, const double *dae, const double *min, int n,
                            double tol) {
  double worst = 0.0;
  for (int i = 0; i < n; i++) {
    double e = fabs(dae[i] - min[i]);
    if (!(e <= worst)) worst = e;   /* a NaN stays */
  }
  printf("  %s: DAE against minimal mode, largest difference %.1e (bound %.0e)\n", what, worst,
         tol);
  AP_CHECK_LE(worst, tol);
}

int main(void) {
  printf("contact modes in DAE mode (rtol %.0e, atol %.0e):\n", RTOL, ATOL);
  double b[2][4], d[2][4], k[2][10], sl[2][1];
  for (int i = 0; i < 2; i++) {
    ap_mode mode = i ? AP_MODE_DAE : AP_MODE_MINIMAL;
    bowling(mode, b[i]);
    dome(mode, d[i]);
    sliding_disk(mode, k[i]);
    dome_slip(mode, sl[i]);
  }
  against_minimal("bowling ball (t*, vx, w_y r, loss)", b[1], b[0], 2, TOLF);
  against_minimal("ball off a dome (angle, time, x, z after 0.15 s)", d[1], d[0], 4, TOLF);
  against_minimal("ball off a dome with mu 0.5 (slip angle)", sl[1], sl[0], 1, TOLF);
  against_minimal("sliding disk (F_n / m g at 4 times, centre and velocity after 0.08 s)", k[1],
                  k[0], 10, TOLF);
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_contact_dae");
}
