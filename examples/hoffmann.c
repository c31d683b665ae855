/* Hoffmann's two-rod pendulum and Kron's method (docs/references.md §6).
 *
 * Two uniform rods hinged together, the upper one hung from a fixed point, a horizontal force F
 * at the lower rod's midpoint. Kron: the metric of the connected system is C^T M C of the
 * primitive (unconnected) system, with C the Jacobian of the connection. This program checks
 * that identity against the printed g and Q, then integrates (a) the reduced two-coordinate
 * system and (b) the primitive four-coordinate system with the connection imposed as two
 * velocity rows, side by side, and finally starts a run at the equilibrium under F.
 *
 * Exits non-zero if the two forms differ by more than ERR_BOUND = 1e3 * rtol, the energy
 * (with the force's potential) drifts by more than 1e-9 relative, or the equilibrium moves. */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#include "refsys.h"

#define RTOL 1e-11
#define ERR_BOUND (1e3 * RTOL)
#define ENERGY_BOUND 1e-9

static ap_sim *start(const ap_system_def *def, const double *q0, const double *v0,
                     ap_model **m) {
  char msg[512];
  ap_sim *s = NULL;
  int st = ap_model_from_system(def, m, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "hoffmann: model '%s': %s: %s\n", def->name, ap_strerror(st), msg);
    return NULL;
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_MINIMAL;
  sd.method = "fehlberg8";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  st = ap_sim_create(*m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "hoffmann: simulation '%s': %s: %s\n", def->name, ap_strerror(st), msg);
    ap_model_free(*m);
    *m = NULL;
  }
  return s;
}

/* Run reduced and primitive side by side from (q2, v2) for 20 s; returns 0 if within bounds,
 * and the largest |(theta, phi) - qref| in *dev (for the equilibrium run). */
static int compare(rs_hoffmann *p, const double q2[2], const double v2[2], const double qref[2],
                   double *dev) {
  double q4[4], v4[4];
  rs_hoffmann_lift(p, q2, v2, q4, v4);
  ap_system_def dr, dp;
  rs_hoffmann_reduced_system(p, &dr);
  rs_hoffmann_primitive_system(p, &dp);
  ap_model *mr = NULL, *mp = NULL;
  ap_sim *sr = start(&dr, q2, v2, &mr);
  ap_sim *sp = sr ? start(&dp, q4, v4, &mp) : NULL;
  if (!sr || !sp) {
    ap_sim_free(sr);
    ap_model_free(mr);
    return 1;
  }
  printf("%5s %14s %14s %14s %14s %10s %10s %10s\n", "t", "theta red", "theta prim",
         "phi red", "phi prim", "diff", "dE/E", "|Av+a0|");
  double E0 = rs_hoffmann_energy(p, q2, v2), diff = 0.0, de = 0.0;
  int st = AP_OK;
  *dev = 0.0;
  for (int i = 0; i <= 10; i++) {
    double t = 2.0 * i;
    if (i > 0 && ((st = ap_sim_advance(sr, t)) != AP_OK || (st = ap_sim_advance(sp, t)) != AP_OK)) {
      fprintf(stderr, "hoffmann: advance to t = %g: %s: %s | %s\n", t, ap_strerror(st),
              ap_sim_message(sr), ap_sim_message(sp));
      break;
    }
    const double *a = ap_sim_q(sr), *b = ap_sim_q(sp);
    double d = fmax(fabs(a[0] - b[0]), fabs(a[1] - b[1]));
    double e = fabs(rs_hoffmann_energy(p, b, ap_sim_v(sp)) - E0) / fmax(1.0, fabs(E0));
    diff = fmax(diff, d);
    de = fmax(de, e);
    *dev = fmax(*dev, fmax(fabs(a[0] - qref[0]), fabs(a[1] - qref[1])));
    *dev = fmax(*dev, fmax(fabs(b[0] - qref[0]), fabs(b[1] - qref[1])));
    printf("%5.1f %14.10f %14.10f %14.10f %14.10f %10.2e %10.2e %10.2e\n", t, a[0], b[0], a[1],
           b[1], d, e, ap_constraint_residual(ap_sim_data(sp), ap_sim_v(sp)));
  }
  ap_sim_free(sr);
  ap_sim_free(sp);
  ap_model_free(mr);
  ap_model_free(mp);
  if (st != AP_OK) return 1;
  printf("reduced vs primitive: %.2e (bound %.0e), energy drift %.2e (bound %.0e)\n", diff,
         ERR_BOUND, de, ENERGY_BOUND);
  return diff <= ERR_BOUND && de <= ENERGY_BOUND ? 0 : 1;
}

int main(void) {
  rs_hoffmann p = {.m1 = 1.0, .m2 = 0.8, .a1 = 0.5, .a2 = 0.4, .grav = 9.81, .F = 2.0};
  p.I1 = p.m1 * p.a1 * p.a1 / 3.0;   /* uniform rods of length 2a: I = m (2a)^2 / 12 */
  p.I2 = p.m2 * p.a2 * p.a2 / 3.0;
  int bad = 0;

  /* Kron's identity at a few configurations. */
  double worst = 0.0;
  for (int j = 0; j < 8; j++) {
    double q2[2] = {-2.0 + 0.6 * j, 1.5 - 0.45 * j}, g1[4], g2[4], Q1[2], Q2[2];
    rs_hoffmann_printed(&p, q2, g1, Q1);
    rs_hoffmann_connected(&p, q2, g2, Q2);
    for (int e = 0; e < 4; e++) worst = fmax(worst, fabs(g1[e] - g2[e]));
    for (int e = 0; e < 2; e++) worst = fmax(worst, fabs(Q1[e] - Q2[e]));
  }
  printf("Hoffmann's pendulum, F = %.1f N. Kron: |C^T M C - g|, |C^T F - Q| <= %.2e\n\n", p.F,
         worst);
  bad |= worst > 1e-14;

  double q2[2] = {0.5, -0.3}, v2[2] = {0.0, 1.0}, dev, none[2] = {0.0, 0.0};
  printf("swinging from theta = %.2f, phi = %.2f, phi' = %.2f (minimal mode, fehlberg8, rtol "
         "%.0e)\n", q2[0], q2[1], v2[1], RTOL);
  bad |= compare(&p, q2, v2, none, &dev);

  double qs[2], zero[2] = {0.0, 0.0}, g[4], Q[2];
  rs_hoffmann_equilibrium(&p, qs);
  rs_hoffmann_printed(&p, qs, g, Q);
  printf("\nequilibrium tan theta* = 2F/((m1 + 2 m2) g), tan phi* = F/(m2 g): (%.12f, %.12f), "
         "Q there = (%.1e, %.1e)\n", qs[0], qs[1], Q[0], Q[1]);
  bad |= compare(&p, qs, zero, qs, &dev);
  printf("largest departure from the equilibrium: %.2e (bound 1e-10)\n", dev);
  bad |= dev > 1e-10;

  printf("\n%s\n", bad ? "FAILED" : "ok");
  return bad ? 1 : 0;
}
