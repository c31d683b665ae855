/* Contact modes (docs/scenes.md "Friction, slip and lift-off"): rolling, sliding and airborne
 * contacts switched by events, against closed forms. A uniform ball (radius r = 0.1 m, mass
 * m = 2 kg, I = 2/5 m r^2) on a free joint, gravity g = 9.81 m/s^2 along -z, in minimal and
 * projected modes (dop853).
 *
 * Bowling ball. Launched at v0 along x without spin on the plane z = 0 with mu: it slides, the
 * friction -mu m g e_x at the contact point (-r e_z) gives v' = -mu g and, about the centre,
 * the torque mu m g r e_y: w_y' = 5 mu g / (2 r). The slip vx - r w_y = v0 - 7/2 mu g t reaches 0
 * at t* = 2 v0 / (7 mu g), with speed v0 - mu g t* = 5/7 v0; then it rolls on at 5/7 v0 (a
 * rolling sphere on a plane keeps its velocity). Kinetic energy 1/2 m v0^2 before, 7/10 m
 * (5/7 v0)^2 = 5/14 m v0^2 after: m v0^2 / 7 lost. Checked to 1e-9 (t*, speed, loss).
 *
 * Spinning ball dropped. Released at gap h with (vx, vy, 0) and spin w, it falls freely and
 * touches down at t = sqrt(2 h / g) with vz- = -sqrt(2 g h). The sticking plastic impact keeps
 * the angular momentum about the contact point, (I w + m r e_z x v) along x and y, and ends in
 * rolling: vx+ = (5 vx + 2 r wy) / 7, vy+ = (5 vy - 2 r wx) / 7, vz+ = 0, w+ = (-vy+ / r, vx+ /
 * r, wz). Carnot: the energy lost T(v-) - T(v+) equals the kinetic energy of the jump
 * 1/2 (v+ - v-)^T g (v+ - v-). Checked to 1e-12.
 *
 * Ball off a dome. A ball rolling without slipping (unilateral, perfectly rough) from rest at
 * angle th0 from the top of a fixed sphere of radius R: its centre moves on the circle of radius
 * L = R + r, with speed V = L th', and T = 1/2 m V^2 + 1/2 I (V / r)^2 = 7/10 m V^2 =
 * m g L (cos th0 - cos th). Along the normal m V^2 / L = m g cos th - F_n, so F_n = m g cos th
 * - 10/7 m g (cos th0 - cos th) vanishes at cos th* = 10/17 cos th0 (10/17 from the top).
 * The lift-off event's angle is checked to 1e-9, then the free flight (a parabola from the
 * event's state) to 1e-9.
 *
 * Painleve's paradox (test_painleve), a disk in a steady turn with mu 1 % below and above what
 * the turn needs (test_disk_turn), a bouncing ball (restitution), a ball on a slope with mu 1 %
 * below and above what rolling needs (test_bounce, test_incline: closed forms in their
 * comments). Without a change of mode
 * a contact with modes runs bit for bit as the same contact without them (mu = 10). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "check.h"

#define G 9.81
static const double R = 0.1, MASS = 2.0;

static double GRAV[3] = {0, 0, -G};   /* gravity of the next ball() */
static double RESTITUTION = 0.0;      /* restitution of the next ball() */

/* The ball on a free joint; ground sphere of radius Rg about the origin when Rg > 0. */
static ap_model *ball(double mu, int unilateral, double Rg) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.mu = mu, c.unilateral = unilateral;
  c.ground.sphere_radius = Rg, c.restitution = RESTITUTION;
  return bs_free_ball(AP_SHAPE_SPHERE, R, MASS, &c, GRAV);
}

/* The velocity after the sticking impact of the ball (v: vx vy vz wx wy wz) on the floor with
 * the contact point leaving at vz_after: vx+ = (5 vx + 2 r wy) / 7, vy+ = (5 vy - 2 r wx) / 7,
 * w+ = (-vy+ / r, vx+ / r, wz) (angular momentum about the contact point kept). */
static void sticking_impact(const double *v, double vz_after, double *ex) {
  ex[0] = (5 * v[0] + 2 * R * v[4]) / 7, ex[1] = (5 * v[1] - 2 * R * v[3]) / 7;
  ex[2] = vz_after, ex[3] = -ex[1] / R, ex[4] = ex[0] / R, ex[5] = v[5];
}

static ap_sim *start(const ap_model *m, ap_mode mode, const double *q, const double *v) {
  ap_sim_def def = ap_sim_def_default();
  def.mode = mode, def.method = "dop853", def.rtol = 1e-12, def.atol = 1e-14;
  ap_sim *s = NULL;
  char msg[1024] = "";
  int rc = ap_sim_create(m, &def, 0.0, q, v, &s, msg, sizeof msg);
  if (rc != AP_OK) printf("  sim_create: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return s;
}

/* Advance s to t: exactly one event, named name, after which the contact is in mode; its
 * record in r. */
static void one_event(ap_sim *s, double t, const char *name, int mode, ap_event_record *r) {
  AP_CHECK_EQ_INT(ap_sim_advance(s, t), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 0, r), AP_OK);
  AP_CHECK(strcmp(r->name, name) == 0);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), mode);
}

static double energy(const ap_model *m, const double *q, const double *v) {
  ap_data *d = NULL;
  double T = NAN, V = 0;
  if (ap_data_create(m, &d) != AP_OK) return NAN;
  memcpy(d->q, q, 7 * sizeof *q), memcpy(d->v, v, 6 * sizeof *v);
  if (ap_body_energy(m, d, &T, &V) != AP_OK) T = NAN;
  ap_data_free(d);
  return T;
}

static const char *mode_name(ap_mode mode) {
  return mode == AP_MODE_MINIMAL ? "minimal" : "projected";
}

static void test_bowling(ap_mode mode) {
  double mu = 0.2, v0 = 3.0, ts = 2 * v0 / (7 * mu * G);
  ap_model *m = ball(mu, -1, 0.0);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {0, 0, R, 1, 0, 0, 0}, v[6] = {v0, 0, 0, 0, 0, 0};
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  ap_event_record r;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);   /* sliding from t0: roll.slip at 0 */
  AP_CHECK(ap_sim_event_get(s, 0, &r) == AP_OK && !strcmp(r.name, "roll.slip") && r.t == 0.0);
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2 * ts), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 1, &r), AP_OK);
  AP_CHECK(strcmp(r.name, "roll.stick") == 0);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
  const double *vq = ap_sim_v(s);
  double loss = 0.5 * MASS * v0 * v0 - energy(m, ap_sim_q(s), vq);
  double ref_loss = MASS * v0 * v0 / 7;
  printf("  bowling ball (%s): rolls at t = %.15g (closed form %.15g, error %.1e), speed %.15g "
         "(error %.1e), energy lost %.15g J (error %.1e)\n", mode_name(mode), r.t, ts,
         fabs(r.t - ts), vq[0], fabs(vq[0] - 5 * v0 / 7), loss, fabs(loss - ref_loss));
  AP_CHECK_NEAR(r.t, ts, 1e-9);
  AP_CHECK_NEAR(vq[0], 5 * v0 / 7, 1e-9);
  AP_CHECK_NEAR(vq[4], 5 * v0 / 7 / R, 1e-8);
  AP_CHECK_NEAR(loss, ref_loss, 1e-9);
  ap_sim_free(s);
  ap_model_free(m);
}

static void test_drop(ap_mode mode) {
  double h = 0.05, tc = sqrt(2 * h / G), vz = -sqrt(2 * G * h);
  ap_model *m = ball(10.0, -1, 0.0);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {0.2, -0.1, R + h, 1, 0, 0, 0}, v[6] = {1.3, -0.6, 0.0, 4.0, 7.0, 11.0};
  double ex[6];
  sticking_impact(v, 0.0, ex);
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  ap_event_record r;
  one_event(s, tc + 0.2, "roll.touchdown", AP_CONTACT_ROLLING, &r);
  const double *vp = ap_sim_v(s);
  double err = 0.0, dv[6], vm[6];
  for (int i = 0; i < 6; i++) err = fmax(err, fabs(vp[i] - ex[i]));
  memcpy(vm, v, sizeof vm);
  vm[2] = vz;
  for (int i = 0; i < 6; i++) dv[i] = vp[i] - r.v[i];
  double lost = energy(m, r.q, r.v) - energy(m, r.q, vp), jump = energy(m, r.q, dv);
  double I = 0.4 * MASS * R * R, ref = 0.5 * MASS * (vz * vz + (ex[0] - v[0]) * (ex[0] - v[0]) +
                                                     (ex[1] - v[1]) * (ex[1] - v[1])) +
                                        0.5 * I * ((ex[3] - v[3]) * (ex[3] - v[3]) +
                                                   (ex[4] - v[4]) * (ex[4] - v[4]));
  printf("  dropped spinning ball (%s): touchdown at t = %.15g (error %.1e), v+ error %.1e, "
         "v- error %.1e; energy lost %.15g J, Carnot %.15g J (difference %.1e), closed form "
         "%.1e off\n", mode_name(mode), r.t, fabs(r.t - tc), err, fabs(r.v[2] - vz), lost, jump,
         fabs(lost - jump), fabs(lost - ref));
  AP_CHECK_NEAR(r.t, tc, 1e-12);
  AP_CHECK_LE(err, 1e-12);
  AP_CHECK_NEAR(r.v[2], vz, 1e-12);
  AP_CHECK_NEAR(lost, jump, 1e-12);
  AP_CHECK_NEAR(lost, ref, 1e-12);
  ap_sim_free(s);
  ap_model_free(m);
}

static void test_dome(ap_mode mode) {
  double Rg = 1.0, L = Rg + R, th0 = 0.01, cref = 10.0 / 17.0 * cos(th0);
  ap_model *m = ball(-1.0, 1, Rg);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {L * sin(th0), 0, L * cos(th0), 1, 0, 0, 0}, v[6] = {0, 0, 0, 0, 0, 0};
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
  double tend = 0;
  int rc = AP_OK;
  for (int k = 1; k <= 400 && rc == AP_OK && ap_sim_event_count(s) == 0; k++)
    rc = ap_sim_advance(s, tend = 0.01 * k);
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  ap_event_record r;
  if (ap_sim_event_get(s, 0, &r) != AP_OK) {
    AP_CHECK(0);
    ap_sim_free(s);
    return ap_model_free(m);
  }
  AP_CHECK(strcmp(r.name, "roll.lift_off") == 0);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  double th = atan2(r.q[0], r.q[2]), thref = acos(cref);
  /* free flight from the event's state */
  double dt = 0.15, t1 = r.t + dt, p[3];
  AP_CHECK_EQ_INT(ap_sim_advance(s, t1), AP_OK);
  for (int i = 0; i < 3; i++) p[i] = r.q[i] + r.v[i] * dt;
  p[2] -= 0.5 * G * dt * dt;
  const double *x = ap_sim_q(s);
  double perr = fmax(fabs(x[0] - p[0]), fmax(fabs(x[1] - p[1]), fabs(x[2] - p[2])));
  printf("  ball off a dome (%s, th0 = %g): lift-off at t = %.12g, angle %.15g rad, closed form "
         "%.15g (error %.1e); flight %.2g s later off the parabola by %.1e m\n",
         mode_name(mode), th0, r.t, th, thref, fabs(th - thref), dt, perr);
  AP_CHECK_NEAR(th, thref, 1e-9);
  AP_CHECK_LE(perr, 1e-9);
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  (void)tend;
  ap_sim_free(s);
  ap_model_free(m);
}

/* Slip onset off a dome: the ball of test_dome with mu = 0.5. Rolling, its centre accelerates
 * along the circle at 5/7 g sin th, so the friction is F_t = m g sin th - m 5/7 g sin th =
 * 2/7 m g sin th, and F_n = m g (17 cos th - 10 cos th0) / 7 (test_dome): the ratio
 * 2 sin th / (17 cos th - 10 cos th0) reaches mu before F_n vanishes. The slip event's angle
 * against the root of 2 sin th = mu (17 cos th - 10 cos th0) (bisection), to 1e-9. */
static void test_dome_slip(ap_mode mode) {
  double Rg = 1.0, L = Rg + R, th0 = 0.01, mu = 0.5, lo = th0, hi = acos(10.0 / 17 * cos(th0));
  for (int i = 0; i < 200; i++) {
    double mid = 0.5 * (lo + hi);
    if (2 * sin(mid) - mu * (17 * cos(mid) - 10 * cos(th0)) < 0) lo = mid;
    else hi = mid;
  }
  ap_model *m = ball(mu, -1, Rg);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {L * sin(th0), 0, L * cos(th0), 1, 0, 0, 0}, v[6] = {0, 0, 0, 0, 0, 0};
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  int rc = AP_OK;
  for (int k = 1; k <= 400 && rc == AP_OK && ap_sim_event_count(s) == 0; k++)
    rc = ap_sim_advance(s, 0.01 * k);
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_event_record r;
  if (ap_sim_event_get(s, 0, &r) == AP_OK) {
    double th = atan2(r.q[0], r.q[2]);
    printf("  ball off a dome with mu %g (%s): slips at %.15g rad, closed form %.15g (error "
           "%.1e), then %s\n", mu, mode_name(mode), th, lo, fabs(th - lo),
           ap_sim_contact_mode(s, 0) == AP_CONTACT_SLIDING ? "slides" : "does not slide");
    AP_CHECK(strcmp(r.name, "roll.slip") == 0);
    AP_CHECK_NEAR(th, lo, 1e-9);
    AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  } else {
    AP_CHECK(0);
  }
  ap_sim_free(s);
  ap_model_free(m);
}

/* Restitution e = 0.5: the dropped spinning ball of test_drop leaves the floor at
 * vz+ = e sqrt(2 g h) with the same tangential velocities as the sticking plastic impact (for a
 * sphere the normal and tangential parts of the projection decouple: g is diagonal), and
 * touches down again 2 vz+ / g later, where it bounces at e^2 sqrt(2 g h). */
static void test_bounce(ap_mode mode) {
  double h = 0.05, e = 0.5, tc = sqrt(2 * h / G), vz = sqrt(2 * G * h);
  RESTITUTION = e;
  ap_model *m = ball(10.0, -1, 0.0);
  RESTITUTION = 0.0;
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {0.2, -0.1, R + h, 1, 0, 0, 0}, v[6] = {1.3, -0.6, 0.0, 4.0, 7.0, 11.0};
  double ex[6];
  sticking_impact(v, e * vz, ex);
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  double t2 = tc + 2 * e * vz / G;
  AP_CHECK_EQ_INT(ap_sim_advance(s, 0.5 * (tc + t2)), AP_OK);   /* mid-flight after a bounce */
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  const double *vp = ap_sim_v(s);
  double err = 0.0;
  for (int i = 0; i < 6; i++)
    err = fmax(err, fabs(vp[i] - ex[i] + (i == 2 ? G * (0.5 * (t2 - tc)) : 0.0)));
  AP_CHECK_EQ_INT(ap_sim_advance(s, t2 + 1e-3), AP_OK);
  ap_event_record r1, r2;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 2);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 0, &r1), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 1, &r2), AP_OK);
  double vz2 = ap_sim_v(s)[2] + G * 1e-3;
  printf("  bouncing ball (%s, e = %g): touchdowns at %.15g, %.15g s (errors %.1e, %.1e), "
         "velocity after the first %.1e off, second bounce at %.15g m/s (error %.1e)\n",
         mode_name(mode), e, r1.t, r2.t, fabs(r1.t - tc), fabs(r2.t - t2), err, vz2,
         fabs(vz2 - e * e * vz));
  AP_CHECK_NEAR(r1.t, tc, 1e-12);
  AP_CHECK_NEAR(r2.t, t2, 1e-12);
  AP_CHECK_LE(err, 1e-12);
  AP_CHECK_NEAR(vz2, e * e * vz, 1e-12);
  ap_sim_free(s);
  ap_model_free(m);
}

/* A ball released at rest on the plane under gravity tilted by a = 20 deg (down-slope along
 * +x): rolling needs |F_t| / F_n = 2/7 tan(a). With mu 1 % below that it slides from the start:
 * x'' = g (sin a - mu cos a), w_y' = 5 mu g cos a / (2 r), the slip g (sin a - 7/2 mu cos a) t
 * grows and never returns to 0; 1 % above, it rolls: x'' = 5/7 g sin a. After 0.5 s, to 1e-9. */
static void test_incline(ap_mode mode) {
  double a = 20 * 3.14159265358979323846 / 180, need = 2.0 / 7.0 * tan(a), T = 0.5;
  GRAV[0] = G * sin(a), GRAV[2] = -G * cos(a);
  for (int above = 0; above < 2; above++) {
    double mu = need * (above ? 1.01 : 0.99);
    ap_model *m = ball(mu, -1, 0.0);
    AP_CHECK(m != NULL);
    if (!m) continue;
    double q[7] = {0, 0, R, 1, 0, 0, 0}, v[6] = {0, 0, 0, 0, 0, 0};
    ap_sim *s = start(m, mode, q, v);
    if (!s) {
      ap_model_free(m);
      continue;
    }
    int mode0 = ap_sim_contact_mode(s, 0);
    AP_CHECK_EQ_INT(ap_sim_advance(s, T), AP_OK);
    double acc = above ? 5.0 / 7.0 * G * sin(a) : G * (sin(a) - mu * cos(a));
    double wacc = above ? acc / R : 5 * mu * G * cos(a) / (2 * R);
    double ex = 0.5 * acc * T * T, x = ap_sim_q(s)[0], wy = ap_sim_v(s)[4];
    printf("  ball on a 20 deg slope (%s), mu %s what rolling needs: %s, x(%.1f) = %.15g "
           "(error %.1e), w_y error %.1e, %d events\n", mode_name(mode),
           above ? "1 % above" : "1 % below", mode0 ? "slides from the start" : "rolls", T, x,
           fabs(x - ex), fabs(wy - wacc * T), ap_sim_event_count(s));
    AP_CHECK_EQ_INT(mode0, above ? AP_CONTACT_ROLLING : AP_CONTACT_SLIDING);
    AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), mode0);
    AP_CHECK_EQ_INT(ap_sim_event_count(s), above ? 0 : 1);   /* below: roll.slip at t0 */
    AP_CHECK_NEAR(x, ex, 1e-9);
    AP_CHECK_NEAR(wy, wacc * T, 1e-9);
    ap_sim_free(s);
    ap_model_free(m);
  }
  GRAV[0] = 0, GRAV[2] = -G;
}

/* The normal force of a sliding body that is not a sphere: a thin uniform disk (r = 0.3 m,
 * 1.5 kg) on a free joint, its axis 50 deg from the vertical, sliding and spinning with
 * mu = 0.3. Its friction has a moment that changes the contact's normal acceleration, so F_n
 * comes from the coupled solve (1 + u != 1). The Coulomb force the model applies is
 * mu F_n(coupled); the normal force the reactions give back, A^T lambda = g v' + h - Q, is
 * Newton's law for the vertical, m (a_z + g). Their ratio |F_t| / F_n must be mu: a normal
 * force taken without the coupling (lambda0) would not match. Checked to 1e-12 at 4 times. */
static void test_sliding_disk(ap_mode mode) {
  double r = 0.3, mass = 1.5, mu = 0.3, tilt = 50 * 3.14159265358979323846 / 180, g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "slide", c.mu = mu;
  ap_model *m = bs_free_ball(AP_SHAPE_DISK, r, mass, &c, g);
  AP_CHECK(m != NULL);
  if (!m) return;
  double q[7] = {0, 0, r * sin(tilt), cos(tilt / 2), sin(tilt / 2), 0, 0};
  double v[6] = {1.0, 0.5, 0.0, 0.0, 0.0, 6.0}, worst = 0.0, fn = 0.0;
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  int n = 0;
  for (int i = 1; i <= 4 && ap_sim_advance(s, 0.02 * i) == AP_OK; i++) {
    if (ap_sim_contact_mode(s, 0) != AP_CONTACT_SLIDING) break;
    const double *lambda = NULL;
    ap_contact_force f;
    AP_CHECK_EQ_INT(ap_sim_reactions(s, &lambda), AP_OK);
    AP_CHECK_EQ_INT(ap_body_contact_force(m, ap_sim_data(s), lambda, 0, &f), AP_OK);
    double newton = mass * (ap_sim_data(s)->vdot[2] + G);
    worst = fmax(worst, fmax(fabs(f.friction_ratio - mu), fabs(f.normal - newton) / newton));
    fn = f.normal, n++;
  }
  printf("  sliding disk (%s, axis 50 deg from vertical, mu %g): F_n %.6g N (m g = %.6g), "
         "|F_t| / F_n - mu and F_n against m (a_z + g): worst %.1e over %d times\n",
         mode_name(mode), mu, fn, mass * G, worst, n);
  AP_CHECK_EQ_INT(n, 4);
  AP_CHECK_LE(worst, 1e-12);
  ap_sim_free(s);
  ap_model_free(m);
}

/* Painleve's paradox: a thin uniform ellipsoid (semi-axes 0.01, 0.01, 0.5 m, 1 kg: a rod,
 * k^2 = (a^2 + c^2) / 5 about a transverse axis) leaning at 45 deg, its lower end at offset r
 * = (r_x, 0, r_z) from the centre, sliding along s e_x with mu = 2. Planar Newton-Euler: the
 * friction -mu N s e_x and N e_z at r give the end the vertical acceleration
 * a0 + N/m [1 + r_x (r_x + mu s r_z) / k^2], so the normal force is the frictionless one over
 * 1 + u = [1 + r_x (r_x + mu s r_z) / k^2] / [1 + r_x^2 / k^2]. Sliding toward +x (s = +1)
 * that is -0.43 < 0: no consistent normal force, the simulation refuses to start with the
 * number in its message (printed to 6 digits, checked to 1e-5); toward -x it is 2.4 and it
 * starts, sliding. */
static void test_painleve(void) {
  bs_rod p;
  double mu = 2.0;
  ap_model *m = bs_leaning_rod("slide", mu, &p);
  AP_CHECK(m != NULL);
  if (!m) return;
  double th = p.th, h = p.h, rx = p.rx, rz = p.rz, k2 = p.k2;
  for (int dir = 1; dir >= -1; dir -= 2) {
    double ref = (1 + rx * (rx + mu * dir * rz) / k2) / (1 + rx * rx / k2);
    double q[7] = {0, 0, h, cos(-th / 2), 0, sin(-th / 2), 0}, v[6] = {dir * 1.0, 0, 0, 0, 0, 0};
    ap_sim_def def = ap_sim_def_default();
    ap_sim *s = NULL;
    char msg[1024] = "";
    int rc = ap_sim_create(m, &def, 0.0, q, v, &s, msg, sizeof msg);
    const char *at = strstr(msg, "1 + u = ");
    double got = at ? strtod(at + 8, NULL) : NAN;
    printf("  Painleve (rod at 45 deg, mu 2, sliding %s): 1 + u = %.6g (closed form %.6g): %s\n",
           dir > 0 ? "+x" : "-x", dir > 0 ? got : ref, ref,
           rc == AP_OK ? "runs" : "refused, Painleve's paradox");
    if (dir > 0) {
      AP_CHECK_EQ_INT(rc, AP_ERR_SINGULAR);
      AP_CHECK(strstr(msg, "Painleve") != NULL);
      AP_CHECK_NEAR(got, ref, 1e-5 * fabs(ref));   /* printed to 6 digits */
      AP_CHECK(ref < 0);
    } else {
      AP_CHECK_EQ_INT(rc, AP_OK);
      AP_CHECK(ref > 1);
      if (s) AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
    }
    ap_sim_free(s);
  }
  ap_model_free(m);
}

/* A rolling disk in a steady turn (thin uniform disk r = 0.3 m, 1.5 kg on a free joint, lean
 * 0.3 rad from upright, heading rate Omega = 3 rad/s, w_a and w_n from the steady relation of
 * bs_disk_steady_rates): the centre keeps its height and runs round a horizontal circle, its
 * velocity vc turning at Omega, so the ground's horizontal force is m Omega |vc| and the
 * friction the turn needs is Omega |vc| / g. With mu 1 % above it the disk rolls on (no event
 * over 1 s, the contact's friction ratio Omega |vc| / g to 1e-9); 1 % below it slides from the
 * start. */
static void test_disk_turn(ap_mode mode) {
  bs_disk p = bs_disk_default();
  double th = 0.3, Om = 3.0, g[3] = {0, 0, -G}, q[7], v[6];
  bs_disk_turn_free(&p, th, Om, 0.4, q, v);
  double need = Om * hypot(v[0], v[1]) / G;
  for (int above = 0; above < 2; above++) {
    ap_constraint_def c = ap_constraint_def_default();
    c.name = "roll", c.mu = need * (above ? 1.01 : 0.99);
    ap_model *m = bs_free_ball(AP_SHAPE_DISK, p.r, p.m, &c, g);
    AP_CHECK(m != NULL);
    if (!m) continue;
    ap_sim *s = start(m, mode, q, v);
    if (!s) {
      ap_model_free(m);
      continue;
    }
    int mode0 = ap_sim_contact_mode(s, 0);
    double ratio = NAN;
    if (above) {
      AP_CHECK_EQ_INT(ap_sim_advance(s, 1.0), AP_OK);
      const double *lambda = NULL;
      ap_contact_force f;
      AP_CHECK_EQ_INT(ap_sim_reactions(s, &lambda), AP_OK);
      AP_CHECK_EQ_INT(ap_body_contact_force(m, ap_sim_data(s), lambda, 0, &f), AP_OK);
      ratio = f.friction_ratio;
      AP_CHECK_NEAR(ratio, need, 1e-9);
      AP_CHECK_EQ_INT(ap_sim_event_count(s), 0);
      AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
    }
    printf("  disk in a steady turn (%s), mu %s the %.9g it needs: %s%s", mode_name(mode),
           above ? "1 % above" : "1 % below", need,
           mode0 ? "slides from the start" : "rolls", above ? "" : "\n");
    if (above)
      printf(", after 1 s still rolling, friction ratio %.12g (error %.1e), %d events\n", ratio,
             fabs(ratio - need), ap_sim_event_count(s));
    AP_CHECK_EQ_INT(mode0, above ? AP_CONTACT_ROLLING : AP_CONTACT_SLIDING);
    ap_sim_free(s);
    ap_model_free(m);
  }
}

/* Refusals, each with the constraint's name: a NaN or infinite mu, mu_kinetic above mu, a
 * restitution outside [0, 1] or without lift-off, friction on a plane-contact joint (which
 * cannot leave the ground). (DAE mode: tests/test_contact_dae.c.) */
static void test_refusals(void) {
  double g[3] = {0, 0, -G};
  struct { double mu, muk, e; int uni; } bad[] = {
      {0.5, -1, 0, -1}, {0.5, 0.8, 0, -1}, {0.5, -1, 1.5, -1}, {-1, -1, 0.5, 0},
      {NAN, -1, 0, -1}, {INFINITY, -1, 0, -1}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    ap_constraint_def c = ap_constraint_def_default();
    c.name = "roll", c.mu = bad[i].mu, c.mu_kinetic = bad[i].muk, c.restitution = bad[i].e;
    c.unilateral = bad[i].uni;
    char msg[512];
    int rc = bs_ball_refused(i == 0 ? AP_JOINT_PLANE_CONTACT : AP_JOINT_FREE, R, MASS, &c, msg,
                             sizeof msg);
    printf("  refused (%d): %s\n", rc, msg);
    AP_CHECK(rc != AP_OK && strstr(msg, "'roll'") != NULL);
  }
  (void)g;
}

/* A rolling ball with mu = 10 never slips: the same run as without modes, bit for bit. */
static void test_bitwise(void) {
  ap_model *m0 = ball(-1.0, -1, 0.0), *m1 = ball(10.0, 0, 0.0);
  AP_CHECK(m0 && m1);
  if (!m0 || !m1) return;
  double q[7] = {0, 0, R, 1, 0, 0, 0}, v[6] = {0.7, -0.4, 0, 0.4 / R, 0.7 / R, 3.0};
  ap_sim *s0 = start(m0, AP_MODE_MINIMAL, q, v), *s1 = start(m1, AP_MODE_MINIMAL, q, v);
  int same = s0 && s1;
  for (int k = 1; k <= 20 && same; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s0, 0.05 * k), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(s1, 0.05 * k), AP_OK);
    same = memcmp(ap_sim_q(s0), ap_sim_q(s1), 7 * sizeof(double)) == 0 &&
           memcmp(ap_sim_v(s0), ap_sim_v(s1), 6 * sizeof(double)) == 0;
  }
  printf("  rolling ball with mu = 10 and without modes: %s over 1 s\n",
         same ? "the same bit for bit" : "DIFFERENT");
  AP_CHECK(same);
  ap_sim_free(s0), ap_sim_free(s1);
  ap_model_free(m0), ap_model_free(m1);
}

int main(void) {
  printf("contact modes:\n");
  for (int i = 0; i < 2; i++) {
    ap_mode mode = i ? AP_MODE_PROJECTED : AP_MODE_MINIMAL;
    test_bowling(mode);
    test_drop(mode);
    test_dome(mode);
    test_dome_slip(mode);
    test_bounce(mode);
    test_incline(mode);
    test_sliding_disk(mode);
    test_disk_turn(mode);
  }
  test_painleve();
  test_refusals();
  test_bitwise();
  return ap_check_finish("test_contact_modes");
}
