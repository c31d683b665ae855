/* Contact modes (docs/scenes.md "Friction, slip and lift-off"): rolling, sliding and airborne
 * contacts switched by events, against closed forms. A uniform ball (radius r = 0.1 m, mass
 * m = 2 kg, I = 2/5 m r^2) on a free joint, gravity g = 9.81 m/s^2 along -z, in minimal and projected modes (dop853).
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
 * Without a change of mode a contact with modes runs bit for bit as the same contact without
 * them (a rolling ball with mu = 10). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#define G 9.81
static const double R = 0.1, MASS = 2.0;

/* The ball on a free joint; ground sphere of radius Rg about the origin when Rg > 0. */
static ap_model *ball(double mu, int unilateral, double Rg) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  if (ap_builder_create("ball", &b) != AP_OK) return NULL;
  ap_body_def bd = ap_body_def_default();
  bd.name = "ball", bd.shape.kind = AP_SHAPE_SPHERE, bd.shape.radius = R;
  int rc = ap_body_def_uniform(&bd, MASS);
  if (rc == AP_OK) rc = ap_builder_add_body(b, &bd, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_FREE, j.child = 0;
  if (rc == AP_OK) rc = ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0, c.mu = mu, c.unilateral = unilateral;
  c.ground.sphere_radius = Rg;
  if (rc == AP_OK) rc = ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[0] = 0, e.gravity[1] = 0, e.gravity[2] = -G;
  if (rc == AP_OK) rc = ap_builder_add_effect(b, &e, NULL);
  if (rc == AP_OK) rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) printf("  build: %s\n", ap_builder_message(b));
  ap_builder_free(b);
  return m;
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
  AP_CHECK_EQ_INT(ap_sim_advance(s, 2 * ts), AP_OK);
  ap_event_record r;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 0, &r), AP_OK);
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
  ex[0] = (5 * v[0] + 2 * R * v[4]) / 7, ex[1] = (5 * v[1] - 2 * R * v[3]) / 7, ex[2] = 0.0;
  ex[3] = -ex[1] / R, ex[4] = ex[0] / R, ex[5] = v[5];
  ap_sim *s = start(m, mode, q, v);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
  AP_CHECK_EQ_INT(ap_sim_advance(s, tc + 0.2), AP_OK);
  ap_event_record r;
  AP_CHECK_EQ_INT(ap_sim_event_count(s), 1);
  AP_CHECK_EQ_INT(ap_sim_event_get(s, 0, &r), AP_OK);
  AP_CHECK(strcmp(r.name, "roll.touchdown") == 0);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_ROLLING);
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
  }
  test_bitwise();
  return ap_check_finish("test_contact_modes");
}
