/* Sliding impacts (docs/scenes.md "Impacts"): a touchdown whose sticking impulse leaves the
 * friction cone slides through the impact. The ball of tests/test_contact_modes.c (uniform
 * sphere r = 0.1 m, m = 2 kg, I = 2/5 m r^2, free joint, g = 9.81 m/s^2) dropped from h = 0.05 m
 * with velocity (vx, vy, 0) and spin w onto the plane, in minimal, projected and DAE mode.
 *
 * Closed form. At touchdown vz- = -V, the contact point's slip is s = (vx - r wy, vy + r wx)
 * (w x (-r e_z) = (-r wy, r wx, 0)), s^ = s / |s|. The normal impulse with restitution e is
 * P_n = m (1 + e) V (a sphere's friction has no moment that moves its contact point along the
 * normal). The sticking impulse keeps the angular momentum about the contact point: it changes
 * the slip by -s, with tangential impulse -2/7 m s; it lies outside the cone when
 * 2/7 |s| > mu (1 + e) V. Then the impulse slides: P_t = -mu P_n s^ at the contact point
 * (-r e_z), which changes the centre's speed by P_t / m and the spin by (-r e_z) x P_t / I:
 *     v_t+ = v_t - mu (1 + e) V s^,    w+ = w + 5 mu (1 + e) V / (2 r) (-s^_y, s^_x, 0),
 *     vz+ = e V,    slip+ = s - 7/2 mu (1 + e) V s^.
 * Energy: the impulses' work is P . (u- + u+) / 2 at the contact point, so the kinetic energy
 * lost is m (1 - e^2) V^2 / 2 + mu P_n (|s-| + |s+|) / 2 (normal and friction parts), checked
 * against T(v-) - T(v+) computed from the model.
 *
 * The jump is applied to the run's own pre-impact state (the touchdown record's v), so it is
 * checked to 1e-12 in every mode (round-off of the projections); the state after it is read
 * at T = t_touchdown + 2e-4 s (before the slip of 1 % of |s-| left after the impact ends) and
 * carried back along the motion after the impact (sliding: v_t' = -mu g s^,
 * w' = 5 mu g / (2 r) (-s^_y, s^_x, 0); flying: vz' = -g), which the methods integrate exactly
 * (velocities linear in t). The touchdown time and vz- against sqrt(2 h / g)
 * and V = sqrt(2 g h): 1e-12 with dop853 at rtol 1e-12, 10 rtol in DAE mode at rtol 1e-10
 * (tests/test_contact_dae.c). With mu 1 % above 2/7 |s| / ((1 + e) V) the impact sticks
 * (rolling afterwards: no sliding impact), 1 % below it slides. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "check.h"

#define G 9.81
static const double R = 0.1, MASS = 2.0, H = 0.05;

static ap_model *ball(double mu, double e) {
  ap_constraint_def c = ap_constraint_def_default();
  double g[3] = {0, 0, -G};
  c.name = "roll", c.mu = mu, c.restitution = e;
  return bs_free_ball(AP_SHAPE_SPHERE, R, MASS, &c, g);
}

static const char *mode_name(ap_mode mode) {
  return mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_PROJECTED ? "projected" : "DAE";
}

/* The closed-form sliding impact of v- (vx vy vz wx wy wz) into vp; P_n and |s-|, |s+|. */
static void sliding_impact(const double *vm, double mu, double e, double *vp, double *pn,
                           double *s0, double *s1) {
  double V = -vm[2], sx = vm[0] - R * vm[4], sy = vm[1] + R * vm[3], ns = hypot(sx, sy);
  double ux = sx / ns, uy = sy / ns, dv = mu * (1 + e) * V, dw = 5 * dv / (2 * R);
  vp[0] = vm[0] - dv * ux, vp[1] = vm[1] - dv * uy, vp[2] = e * V;
  vp[3] = vm[3] - dw * uy, vp[4] = vm[4] + dw * ux, vp[5] = vm[5];
  *pn = MASS * (1 + e) * V, *s0 = ns, *s1 = ns - 3.5 * dv;
}

/* v at T carried back to the impact at t (dt = T - t) for the mode after it. */
static void carry_back(const double *vT, int mode, double mu, const double *vm, double dt,
                       double *v) {
  memcpy(v, vT, 6 * sizeof *v);
  if (mode == AP_CONTACT_AIRBORNE) {
    v[2] += G * dt;
    return;
  }
  double sx = vm[0] - R * vm[4], sy = vm[1] + R * vm[3], ns = hypot(sx, sy);
  double ux = sx / ns, uy = sy / ns, a = mu * G * dt, b = 5 * a / (2 * R);
  v[0] += a * ux, v[1] += a * uy, v[3] += b * uy, v[4] -= b * ux;
}

static void drop(ap_mode mode, double e, double mu_factor) {
  double q[7] = {0.2, -0.1, R + H, 1, 0, 0, 0}, v[6] = {1.3, -0.6, 0.0, 4.0, 7.0, 11.0};
  double tc = sqrt(2 * H / G), V = sqrt(2 * G * H), ns = hypot(v[0] - R * v[4], v[1] + R * v[3]);
  double mu = mu_factor * 2.0 / 7.0 * ns / ((1 + e) * V), rt = mode == AP_MODE_DAE ? 1e-10 : 1e-12;
  double tol = mode == AP_MODE_DAE ? 10 * rt : 1e-12;
  ap_model *m = ball(mu, e);
  ap_sim *s = m ? bs_start(m, mode, mode == AP_MODE_DAE ? NULL : "dop853", rt, rt * 1e-2, q, v)
                : NULL;
  AP_CHECK(s != NULL);
  if (!s) return ap_model_free(m);
  AP_CHECK_EQ_INT(ap_sim_advance(s, tc + 2e-4), AP_OK);
  ap_event_record r;
  int n = ap_sim_event_count(s), mode1 = ap_sim_contact_mode(s, 0);
  AP_CHECK(n >= 1 && ap_sim_event_get(s, n - 1, &r) == AP_OK && !strcmp(r.name, "roll.touchdown"));
  if (n < 1 || ap_sim_event_get(s, n - 1, &r) != AP_OK) {
    ap_sim_free(s);
    return ap_model_free(m);
  }
  double vp[6], pn, s0, s1, got[6], err = 0.0;
  sliding_impact(r.v, mu, e, vp, &pn, &s0, &s1);
  carry_back(ap_sim_v(s), mode1, mu, r.v, ap_sim_time(s) - r.t, got);
  for (int i = 0; i < 6; i++) err = fmax(err, fabs(got[i] - vp[i]));
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  double lost = d ? bs_energy(m, d, r.q, r.v) - bs_energy(m, d, r.q, got) : NAN;   /* same V */
  ap_data_free(d);
  double book = 0.5 * MASS * (1 - e * e) * r.v[2] * r.v[2] + 0.5 * mu * pn * (s0 + s1);
  printf("  %s, e = %g, mu %s the sticking limit: touchdown at %.15g (error %.1e), vz- error "
         "%.1e, then %s; ", mode_name(mode), e, mu_factor > 1 ? "1 % above" : "1 % below", r.t,
         fabs(r.t - tc), fabs(r.v[2] + V), mode1 == AP_CONTACT_SLIDING ? "sliding"
         : mode1 == AP_CONTACT_AIRBORNE ? "airborne" : "rolling");
  AP_CHECK_NEAR(r.t, tc, tol);
  AP_CHECK_NEAR(r.v[2], -V, tol);
  if (mu_factor > 1) {   /* sticks: rolling or bouncing, never the sliding jump */
    printf("no sliding impact (v+ differs from it by %.2g)\n", err);
    AP_CHECK_EQ_INT(mode1, e > 0 ? AP_CONTACT_AIRBORNE : AP_CONTACT_ROLLING);
    AP_CHECK(err > 1e-3);
  } else {
    printf("v+ error %.1e, energy lost %.15g J, impulses' work %.15g J (difference %.1e)\n", err,
           lost, book, fabs(lost - book));
    AP_CHECK_EQ_INT(mode1, e > 0 ? AP_CONTACT_AIRBORNE : AP_CONTACT_SLIDING);
    AP_CHECK_LE(err, 1e-12);
    AP_CHECK_NEAR(lost, book, 1e-12);
  }
  ap_sim_free(s);
  ap_model_free(m);
}

/* The rod of test_painleve (tests/test_contact_modes.c: a thin ellipsoid, semi-axes 0.01, 0.01,
 * 0.5 m, 1 kg, k^2 = (a^2 + c^2) / 5, at 45 deg, its tip at r = (r_x, 0, r_z) from the centre,
 * mu = 2) dropped 1 mm onto the plane at vz = -0.5 m/s while moving at 10 m/s along +x or -x,
 * without spin. Planar impulse P = (P_x, P_z) at the tip: the tip's velocity changes by W P,
 * W = I / m + q q^T / (m k^2), q = (r_z, -r_x), and w_y by (r_z P_x - r_x P_z) / (m k^2). The
 * sticking impulse P = -W^-1 u- (u- the tip's velocity).
 * +x: it lies in the cone (|P_x| / P_z = 1.35 < mu: Painleve's configuration, where sliding
 *     would have 1 + u = -0.43 < 0, is resolved by sticking), and the normal force after it
 *     would pull (F_n < 0), so the rod flies off at once: v+ = v- + P / m and w_y+ from the
 *     closed form, then free flight (v' = -g e_z, w constant) to T = 0.01 s, to 1e-12 of the
 *     largest speed (round-off).
 * -x: the sticking impulse would pull (P_z < 0): outside the cone, the impact slides. */
static void rod_impact(void) {
  bs_rod p;
  ap_model *m = bs_leaning_rod("tip", 2.0, &p);
  double mu = 2.0, I = p.k2, rx = p.rx, rz = p.rz;   /* unit mass: I = k^2 */
  double W[4] = {1 + rz * rz / I, -rz * rx / I, -rz * rx / I, 1 + rx * rx / I};  /* xx xz zx zz */
  double det = W[0] * W[3] - W[1] * W[2];
  AP_CHECK(m != NULL);
  if (!m) return;
  for (int dir = 1; dir >= -1; dir -= 2) {
    double q[7] = {0, 0, p.h + 1e-3, cos(-p.th / 2), 0, sin(-p.th / 2), 0};
    double v[6] = {dir * 10.0, 0, -0.5, 0, 0, 0};
    ap_sim *s = bs_start(m, AP_MODE_MINIMAL, "dop853", 1e-12, 1e-14, q, v);
    AP_CHECK(s != NULL);
    if (!s) continue;
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.01), AP_OK);
    ap_event_record r, r2;
    /* +x: the touchdown, then the lift-off the forces make at once (recorded at its time) */
    int ok = ap_sim_event_count(s) == (dir > 0 ? 2 : 1) && ap_sim_event_get(s, 0, &r) == AP_OK;
    printf("  rod impact (%+d): %d events\n", dir, ap_sim_event_count(s));
    AP_CHECK(ok);
    if (ok && dir > 0) {
      AP_CHECK_EQ_INT(ap_sim_event_get(s, 1, &r2), AP_OK);
      AP_CHECK(strcmp(r2.name, "tip.lift_off") == 0 && r2.t == r.t);
    }
    if (!ok) {
      ap_sim_free(s);
      continue;
    }
    double px = -(W[3] * r.v[0] - W[1] * r.v[2]) / det;
    double pz = -(-W[2] * r.v[0] + W[0] * r.v[2]) / det;
    double ex[6] = {r.v[0] + px, 0, r.v[2] + pz - G * (0.01 - r.t), 0, (rz * px - rx * pz) / I, 0};
    double err = 0.0, big = 0.0;   /* round-off relative to the largest speed (w_y ~ 30) */
    for (int i = 0; i < 6; i++) err = fmax(err, fabs(ap_sim_v(s)[i] - ex[i]));
    for (int i = 0; i < 6; i++) big = fmax(big, fabs(ex[i]));
    printf("  rod at 45 deg, mu 2, moving %s: sticking impulse (%.4g, %.4g) N s: %s\n",
           dir > 0 ? "+x" : "-x", px, pz, dir > 0 ? "in the cone" : "pulls: slides");
    if (dir > 0) {
      printf("    sticks, flies at once; v, w_y 0.01 s later off the closed form by %.1e "
             "(largest speed %.3g)\n", err, big);
      AP_CHECK(pz > 0 && fabs(px) < mu * pz);
      AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_AIRBORNE);
      AP_CHECK_LE(err, 1e-12 * big);
    } else {
      AP_CHECK(pz < 0);
      AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
    }
    ap_sim_free(s);
  }
  ap_model_free(m);
}

int main(void) {
  printf("sliding impacts (ball dropped from %g m with slip and spin):\n", H);
  ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 2; j++) {
      drop(modes[i], j ? 0.5 : 0.0, 0.99);
      drop(modes[i], j ? 0.5 : 0.0, 1.01);
    }
  rod_impact();
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_contact_impact");
}
