/* Knife edge (skate) on an inclined plane (docs/references.md §1).
 *
 * A skate on a slope of angle alpha cannot move across its blade: A = [sin phi, -cos phi, 0].
 * Turning at a constant rate w it does not slide down on average but drifts sideways at
 * G/(2w), G = g sin(alpha). The turning blade makes the minimal mode re-partition its speeds
 * (x or y dependent) about four times a turn; the run still follows the closed form, and the
 * reaction across the blade matches lambda = -m w u - m G sin(phi).
 *
 * Exits non-zero if a position is off by more than ERR_BOUND = 1e3 * rtol (relative to
 * max(1, |q|)) or the multiplier by more than that relative to m (|w u| + G). */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#include "refsys.h"

#define RTOL 1e-11
#define ERR_BOUND (1e3 * RTOL)

int main(void) {
  rs_knife p = {.m = 1.0, .J = 0.2, .grav = 9.81, .alpha = 0.3};
  double q0[3], v0[3], w0 = 3.0, G = p.grav * sin(p.alpha);
  rs_knife_initial(0.0, 0.0, 0.4, 1.0, w0, q0, v0);   /* x, y, phi, u, w */

  ap_system_def def;
  rs_knife_system(&p, &def);
  ap_model *m = NULL;
  char msg[512];
  int st = ap_model_from_system(&def, &m, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "knife_edge: model: %s: %s\n", ap_strerror(st), msg);
    return 1;
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_MINIMAL;
  sd.method = "verner6";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  ap_sim *s = NULL;
  st = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "knife_edge: simulation: %s: %s\n", ap_strerror(st), msg);
    ap_model_free(m);
    return 1;
  }

  printf("Knife edge on a %.2f rad slope, w = %.1f rad/s (minimal mode, verner6, rtol %.0e)\n",
         p.alpha, w0, RTOL);
  printf("sideways drift G/(2w) = %.6f m/s\n\n", G / (2.0 * w0));
  printf("%5s %13s %13s %11s %12s %12s %10s %10s %10s\n", "t", "x", "y", "phi", "lambda",
         "exact", "pos err", "lam err", "|Av+a0|");
  double worst = 0.0, worst_lam = 0.0;
  int failed = 0;
  for (int i = 0; i <= 20 && !failed; i++) {
    double t = 1.0 * i, qe[3], ve[3], le;
    const double *lam = NULL;
    if (i > 0 && (st = ap_sim_advance(s, t)) != AP_OK) {
      fprintf(stderr, "knife_edge: advance to t = %g: %s: %s\n", t, ap_strerror(st),
              ap_sim_message(s));
      failed = 1;
      break;
    }
    if ((st = ap_sim_reactions(s, &lam)) != AP_OK) {
      fprintf(stderr, "knife_edge: reactions: %s: %s\n", ap_strerror(st), ap_sim_message(s));
      failed = 1;
      break;
    }
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    rs_knife_exact(&p, q0, v0, t, qe, ve, &le);
    double err = 0.0;
    for (int j = 0; j < 3; j++) err = fmax(err, fabs(q[j] - qe[j]) / fmax(1.0, fabs(qe[j])));
    double lam_err = fabs(lam[0] - le) / (p.m * (fabs(w0 * hypot(ve[0], ve[1])) + G));
    worst = fmax(worst, err);
    worst_lam = fmax(worst_lam, lam_err);
    printf("%5.1f %13.9f %13.9f %11.6f %12.8f %12.8f %10.2e %10.2e %10.2e\n", t, q[0], q[1], q[2],
           lam[0], le, err, lam_err, ap_constraint_residual(ap_sim_data(s), v));
  }

  ap_sim_stats stats;
  ap_sim_get_stats(s, &stats);
  ap_sim_free(s);
  ap_model_free(m);
  if (failed) return 1;
  printf("\n%ld steps, %ld partition switches over %.1f turns, max |A v + a0| = %.2e\n",
         stats.steps, stats.partition_switches, w0 * 20.0 / (2.0 * RS_PI), stats.max_residual);
  int ok = worst <= ERR_BOUND && worst_lam <= ERR_BOUND;
  printf("worst position error %.2e, multiplier error %.2e (bound %.0e): %s\n", worst, worst_lam,
         ERR_BOUND, ok ? "ok" : "TOO LARGE");
  return ok ? 0 : 1;
}
