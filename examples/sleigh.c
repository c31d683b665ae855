/* Chaplygin sleigh (docs/references.md §2): the main demo.
 *
 * A rigid body on a horizontal plane rests on a blade at P that cannot slide sideways; its centre
 * of mass sits a distance a ahead of P. The math-level system (tests/refsys_blade.c) hands Appell the
 * non-diagonal metric g(theta), its derivative dg/dtheta (h by Christoffel symbols) and the
 * blade row A = [-sin theta, cos theta, 0]. The run is compared with the closed form
 * u = V tanh(k t + c), w = w0 cosh c / cosh(k t + c), theta by the Gudermannian and x, y by
 * quadrature, and ends with the sample values printed in docs/references.md.
 *
 * Exits non-zero if a position is off by more than ERR_BOUND = 1e3 * rtol. */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#include "refsys.h"

#define RTOL 1e-11
#define ERR_BOUND (1e3 * RTOL)

int main(void) {
  rs_sleigh p = {.m = 1.0, .I = 1.0, .a = 1.0};
  double q0[3], v0[3];
  rs_sleigh_initial(0.0, 0.0, RS_PI, 0.1, 0.2, q0, v0);   /* x, y, theta, u, w */

  ap_system_def def;
  rs_sleigh_system(&p, 0, &def);
  ap_model *m = NULL;
  char msg[512];
  int st = ap_model_from_system(&def, &m, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "sleigh: model: %s: %s\n", ap_strerror(st), msg);
    return 1;
  }

  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_MINIMAL;
  sd.method = "dopri5";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  ap_sim *s = NULL;
  st = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "sleigh: simulation: %s: %s\n", ap_strerror(st), msg);
    ap_model_free(m);
    return 1;
  }

  printf("Chaplygin sleigh, m = I = a = 1, u0 = 0.1, w0 = 0.2, theta0 = pi (minimal mode, "
         "dopri5, rtol %.0e)\n\n", RTOL);
  printf("%5s %12s %12s %12s %13s %13s %10s %10s\n", "t", "u", "w", "theta", "x", "y",
         "error", "|Av+a0|");
  double worst = 0.0;
  for (int i = 0; i <= 10; i++) {
    double t = 1.5 * i, qe[3], ve[3];
    if (i > 0 && (st = ap_sim_advance(s, t)) != AP_OK) {
      fprintf(stderr, "sleigh: advance to t = %g: %s: %s\n", t, ap_strerror(st),
              ap_sim_message(s));
      ap_sim_free(s);
      ap_model_free(m);
      return 1;
    }
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    rs_sleigh_exact(&p, q0, v0, t, qe, ve);
    double err = 0.0;
    for (int j = 0; j < 3; j++) err = fmax(err, fabs(q[j] - qe[j]));
    worst = fmax(worst, err);
    double u = v[0] * cos(q[2]) + v[1] * sin(q[2]);
    double resid = ap_constraint_residual(ap_sim_data(s), v);
    printf("%5.1f %12.9f %12.9f %12.9f %13.9f %13.9f %10.2e %10.2e\n", t, u, v[2], q[2], q[0],
           q[1], err, resid);
  }

  /* The sample of docs/references.md at t = 15. */
  const double *q = ap_sim_q(s), *v = ap_sim_v(s);
  const double ref[5] = {0.29668571025517837, 0.03144510558402052, 4.672022704815886,
                         -1.5814737061340092, -3.0441567427652534};
  const double got[5] = {v[0] * cos(q[2]) + v[1] * sin(q[2]), v[2], q[2], q[0], q[1]};
  const char *name[5] = {"u", "w", "theta", "x", "y"};
  printf("\ndocs/references.md sample at t = 15:\n");
  for (int j = 0; j < 5; j++) {
    printf("  %-6s computed %22.17f  printed %22.17f  diff %9.2e\n", name[j], got[j], ref[j],
           got[j] - ref[j]);
    worst = fmax(worst, fabs(got[j] - ref[j]));
  }

  ap_sim_stats stats;
  ap_sim_get_stats(s, &stats);
  printf("\n%ld steps, %ld right-hand sides, max |A v + a0| = %.2e\n", stats.steps,
         stats.rhs_evals, stats.max_residual);
  printf("worst error %.2e (bound %.0e): %s\n", worst, ERR_BOUND,
         worst <= ERR_BOUND ? "ok" : "TOO LARGE");
  ap_sim_free(s);
  ap_model_free(m);
  return worst <= ERR_BOUND ? 0 : 1;
}
