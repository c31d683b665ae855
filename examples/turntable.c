/* Ball on a rotating turntable (docs/references.md §3): an affine, rheonomic constraint.
 *
 * A uniform ball rolls without slipping on a table turning at Omega(t) = Omega0 + dOmega t.
 * The free term a0 = (Omega y, -Omega x) of the rolling rows carries the table's motion. With
 * constant Omega the centre moves on a circle at kappa = k Omega / (1 + k); with Omega(t) it
 * follows z' = i kt Omega(t) z + c (kt = k/(1+k)) with the same complex constant c.
 * Both runs are compared with the closed form; the second one also with the invariant c.
 *
 * Exits non-zero if a position is off by more than ERR_BOUND = 1e3 * rtol (relative to
 * max(1, |q|)). */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#include "refsys.h"

#define RTOL 1e-11
#define ERR_BOUND (1e3 * RTOL)

/* Simulate one table for 20 s and print every 2 s; returns the worst position error or -1. */
static double run(rs_turntable *p, ap_mode mode) {
  double q0[5], v0[5], c0[2];
  rs_turntable_initial(p, 0.3, -0.1, 1.0, -2.0, 3.0, q0, v0);   /* x, y, wx, wy, wz */
  rs_turntable_invariant(p, 0.0, q0, v0, c0);

  ap_system_def def;
  rs_turntable_system(p, &def);
  ap_model *m = NULL;
  char msg[512];
  int st = ap_model_from_system(&def, &m, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "turntable: model: %s: %s\n", ap_strerror(st), msg);
    return -1.0;
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode;
  sd.method = "dopri5";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  ap_sim *s = NULL;
  st = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "turntable: simulation: %s: %s\n", ap_strerror(st), msg);
    ap_model_free(m);
    return -1.0;
  }

  printf("%5s %8s %13s %13s %13s %13s %10s %10s %10s\n", "t", "Omega", "x", "y", "x exact",
         "y exact", "pos err", "c drift", "|Av+a0|");
  double worst = 0.0;
  for (int i = 0; i <= 10; i++) {
    double t = 2.0 * i, qe[5], ve[5], c[2];
    if (i > 0 && (st = ap_sim_advance(s, t)) != AP_OK) {
      fprintf(stderr, "turntable: advance to t = %g: %s: %s\n", t, ap_strerror(st),
              ap_sim_message(s));
      worst = -1.0;
      break;
    }
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    rs_turntable_exact(p, q0, v0, t, qe, ve);
    rs_turntable_invariant(p, t, q, v, c);
    double err = 0.0;
    for (int j = 0; j < 5; j++) err = fmax(err, fabs(q[j] - qe[j]) / fmax(1.0, fabs(qe[j])));
    worst = fmax(worst, err);
    printf("%5.1f %8.3f %13.9f %13.9f %13.9f %13.9f %10.2e %10.2e %10.2e\n", t,
           rs_turntable_omega(p, t), q[0], q[1], qe[0], qe[1], err,
           hypot(c[0] - c0[0], c[1] - c0[1]), ap_constraint_residual(ap_sim_data(s), v));
  }
  ap_sim_free(s);
  ap_model_free(m);
  return worst;
}

int main(void) {
  rs_turntable steady = {.m = 1.0, .R = 0.1, .kI = 0.4, .Omega0 = 2.0, .dOmega = 0.0};
  rs_turntable spinup = {.m = 1.0, .R = 0.1, .kI = 0.4, .Omega0 = 0.5, .dOmega = 0.1};
  double kap = steady.kI / (1.0 + steady.kI) * steady.Omega0;

  printf("Solid ball on a turntable at Omega = %.1f rad/s (minimal mode, dopri5, rtol %.0e)\n",
         steady.Omega0, RTOL);
  printf("circle rate kappa = 2 Omega / 7 = %.9f rad/s\n\n", kap);
  double e1 = run(&steady, AP_MODE_MINIMAL);

  printf("\nThe same ball, table spinning up: Omega(t) = %.1f + %.1f t (projected mode)\n\n",
         spinup.Omega0, spinup.dOmega);
  double e2 = run(&spinup, AP_MODE_PROJECTED);

  if (e1 < 0.0 || e2 < 0.0) return 1;
  double worst = fmax(e1, e2);
  printf("\nworst position error %.2e (bound %.0e): %s\n", worst, ERR_BOUND,
         worst <= ERR_BOUND ? "ok" : "TOO LARGE");
  return worst <= ERR_BOUND ? 0 : 1;
}
