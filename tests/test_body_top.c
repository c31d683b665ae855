/* A heavy symmetric top on a ball joint and a rattleback (an ellipsoid rolling on the plane,
 * centre of mass below the centre, inertia with a product term), from bodies.
 *
 * Top: mass m, centre of mass at distance l on the symmetry axis a = R e_z, inertia
 * diag(A0, A0, C) about the centre of mass, pivot fixed at the origin. Exact invariants: the
 * energy T + m g l a_z, the angular momentum about the vertical L_z = e_z . (I_O w) (I_O the
 * inertia about the pivot; gravity has no moment about e_z) and the spin w . a (Euler's third
 * equation: C w3' = 0 for a symmetric body whose torque is normal to a).
 * Rattleback: rolling without slip, energy conserved. It prefers one direction of spin: spun
 * the "wrong" way (here w_z < 0, set by the sign of the product term) it starts rocking and
 * reverses within about a second; spun the other way it holds more than twice as long (the
 * conservative model has no dissipation, so the motion stays quasi-periodic and reversals
 * recur in both directions; with no product term there is none at all).
 * Tolerances: 1e-9 relative, the target for the energy. The top at rtol 1e-11 drifts by
 * ~1e-11; the rattleback's fast rocking drifts ~1e-10 per decade of rtol (measured 7e-10 at
 * 1e-11, 5e-11 at 1e-12: truncation, not modelling), so it runs at rtol 1e-12. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "bodysys.h"

#define RTOL 1e-11
#define INV_TOL 1e-9

static ap_sim *start_tol(const ap_model *m, ap_mode mode, const char *method, const double *q0,
                         const double *v0, double rtol) {
  return bs_start(m, mode, method, rtol, 1e-2 * rtol, q0, v0);
}

static ap_sim *start(const ap_model *m, ap_mode mode, const char *method, const double *q0,
                     const double *v0) {
  return start_tol(m, mode, method, q0, v0, RTOL);
}

/* ---- heavy symmetric top --------------------------------------------------------------------- */

/* Energy, L_z about the pivot and the spin w . a from the state (q = quaternion, v = w). */
static void top_invariants(const bs_top *p, const double *q, const double *w, double inv[3]) {
  double R[9], a[3], c[3], Iw[3], L[3];
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++) a[i] = R[6 + i], c[i] = p->l * a[i];
  /* I_com w in world axes: R diag(A0, A0, C) R^T w = A0 w + (C - A0) (a . w) a */
  double aw = a[0] * w[0] + a[1] * w[1] + a[2] * w[2];
  for (int i = 0; i < 3; i++) Iw[i] = p->A0 * w[i] + (p->C - p->A0) * aw * a[i];
  double vc[3] = {w[1] * c[2] - w[2] * c[1], w[2] * c[0] - w[0] * c[2], w[0] * c[1] - w[1] * c[0]};
  double T = 0.5 * (w[0] * Iw[0] + w[1] * Iw[1] + w[2] * Iw[2]) +
             0.5 * p->m * (vc[0] * vc[0] + vc[1] * vc[1] + vc[2] * vc[2]);
  /* L_O = I_com w + m c x (w x c) */
  for (int i = 0; i < 3; i++) L[i] = Iw[i];
  L[2] += p->m * (c[0] * vc[1] - c[1] * vc[0]);
  inv[0] = T + p->m * p->grav * c[2];
  inv[1] = L[2];
  inv[2] = aw;
}

static void test_top(void) {
  bs_top p = bs_top_default();
  ap_model *m = bs_top_model(&p);
  double q0[4], v0[3], inv0[3];
  if (!m) return;
  bs_top_initial(q0, v0);
  top_invariants(&p, q0, v0, inv0);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double T = 0.0, V = 0.0;
  memcpy(d->q, q0, sizeof q0), memcpy(d->v, v0, sizeof v0);
  AP_CHECK(ap_body_energy(m, d, &T, &V) == AP_OK);
  AP_CHECK_NEAR(T + V, inv0[0], 1e-13 * fabs(inv0[0]));   /* the engine's energy = the formula */
  const ap_mode modes[2] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED};
  const char *methods[2] = {"verner6", "fehlberg8"};
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = start(m, modes[mi], methods[mi], q0, v0);
    double drift[3] = {0, 0, 0}, inv[3];
    for (int i = 1; s && i <= 20; i++) {
      AP_CHECK_EQ_INT(ap_sim_advance(s, 0.5 * i), AP_OK);
      top_invariants(&p, ap_sim_q(s), ap_sim_v(s), inv);
      for (int c = 0; c < 3; c++)
        drift[c] = fmax(drift[c], fabs(inv[c] - inv0[c]) / fmax(fabs(inv0[c]), 1e-3));
    }
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    printf("heavy top %-9s %-9s 10 s: energy %.1e, L_z %.1e, spin %.1e (relative drift); "
           "steps %ld, restarts %ld\n", mi ? "projected" : "minimal", methods[mi], drift[0],
           drift[1], drift[2], st.steps, st.restarts);
    for (int c = 0; c < 3; c++) AP_CHECK_LE(drift[c], INV_TOL);
    ap_sim_free(s);
  }
  ap_data_free(d);
  ap_model_free(m);
}

/* ---- rattleback ------------------------------------------------------------------------------ */

static void test_rattleback(void) {
  ap_model *m = bs_rattleback_model(0.1);
  ap_data *d = NULL;
  double t_first[2] = {0, 0};
  if (!m) return;
  ap_data_create(m, &d);
  for (int dir = -1; dir <= 1; dir += 2) {
    double q0[6], v0[5], E0, T, V;
    AP_CHECK_EQ_INT(bs_rattleback_state(m, d, 0.02, 5.0 * dir, q0, v0), AP_OK);
    memcpy(d->q, q0, sizeof q0), memcpy(d->v, v0, sizeof v0);
    AP_CHECK(ap_body_energy(m, d, &T, &V) == AP_OK);
    E0 = T + V;
    ap_sim *s = start_tol(m, AP_MODE_MINIMAL, "fehlberg8", q0, v0, 1e-12);
    double dE = 0.0, wz_min = 1e300, wz_max = -1e300, t_rev = -1.0;
    for (int i = 1; s && i <= 100; i++) {
      int rc = ap_sim_advance(s, 0.1 * i);
      if (rc != AP_OK) fprintf(stderr, "%s\n", ap_sim_message(s));
      AP_CHECK_EQ_INT(rc, AP_OK);
      if (rc != AP_OK) break;
      memcpy(d->q, ap_sim_q(s), sizeof q0), memcpy(d->v, ap_sim_v(s), sizeof v0);
      AP_CHECK(ap_body_energy(m, d, &T, &V) == AP_OK);
      dE = fmax(dE, fabs(T + V - E0) / fabs(E0));
      wz_min = fmin(wz_min, ap_sim_v(s)[4]), wz_max = fmax(wz_max, ap_sim_v(s)[4]);
      if (t_rev < 0 && ap_sim_v(s)[4] * v0[4] < 0) t_rev = 0.1 * i;
    }
    t_first[dir > 0] = t_rev < 0 ? 1e300 : t_rev;
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    printf("rattleback spun %+.0f rad/s, 10 s: energy drift %.1e, w_z between %+.3f and "
           "%+.3f, first reversal at t = %.1f s, steps %ld, residual %.1e\n", v0[4], dE, wz_min,
           wz_max, t_rev, st.steps, st.max_residual);
    AP_CHECK_LE(dE, INV_TOL);
    ap_sim_free(s);
  }
  AP_CHECK_LE(t_first[0], 1.5);                 /* the wrong way reverses quickly */
  AP_CHECK(t_first[1] > 2.0 * t_first[0]);      /* the preferred way holds longer */
  ap_data_free(d);
  ap_model_free(m);
}

int main(void) {
  test_top();
  test_rattleback();
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_body_top");
}
