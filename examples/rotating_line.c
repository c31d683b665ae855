/* Particle on a rotating inclined line (docs/references.md §5): rheonomic, two ways.
 *
 * A bead slides on a line through the origin at angle alpha from the vertical, the line
 * turning about the vertical at w. (a) Reduced: one coordinate r with the rheonomic
 * centrifugal term h = -m s^2 r, s = w sin(alpha). (b) The bead as a free particle in 3-D held
 * on the line by two rheonomic velocity rows n_i(t) . p' + n_i'(t) . p = 0. Both follow
 * r(t) = A e^{st} + B e^{-st} + g cos(alpha) / s^2 and keep the Jacobi integral; energy is
 * not conserved (the line does work).
 *
 * Exits non-zero if r is off by more than ERR_BOUND = 1e3 * rtol relative to max(1, |r|), or
 * the Jacobi integral drifts by more than 1e-9 relative to the size of its terms. */
#include <math.h>
#include <stdio.h>

#include <appell/appell.h>

#include "refsys.h"

#define RTOL 1e-11
#define ERR_BOUND (1e3 * RTOL)
#define JACOBI_BOUND 1e-9

/* Model and simulation of one form; returns NULL on failure (message printed). */
static ap_sim *start(const ap_system_def *def, const double *q0, const double *v0,
                     ap_model **m) {
  char msg[512];
  ap_sim *s = NULL;
  int st = ap_model_from_system(def, m, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "rotating_line: model '%s': %s: %s\n", def->name, ap_strerror(st), msg);
    return NULL;
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_MINIMAL;
  sd.method = "verner6";
  sd.rtol = RTOL;
  sd.atol = 1e-13;
  st = ap_sim_create(*m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "rotating_line: simulation '%s': %s: %s\n", def->name, ap_strerror(st), msg);
    ap_model_free(*m);
    *m = NULL;
  }
  return s;
}

int main(void) {
  rs_line p = {.m = 1.0, .grav = 9.81, .alpha = 0.6, .w = 0.4};
  double r0 = 150.0, rd0 = 0.0, s_rate = p.w * sin(p.alpha);
  double q3[3], v3[3];
  rs_line_lift(&p, 0.0, r0, rd0, q3, v3);

  ap_system_def dr, d3;
  rs_line_reduced_system(&p, &dr);
  rs_line_3d_system(&p, &d3);
  ap_model *mr = NULL, *m3 = NULL;
  ap_sim *sr = start(&dr, &r0, &rd0, &mr);
  ap_sim *s3 = sr ? start(&d3, q3, v3, &m3) : NULL;
  if (!sr || !s3) {
    ap_sim_free(sr);
    ap_model_free(mr);
    return 1;
  }

  printf("Bead on a line at %.2f rad from the vertical turning at %.2f rad/s: s = %.6f 1/s\n",
         p.alpha, p.w, s_rate);
  printf("equilibrium r = g cos(alpha) / s^2 = %.6f m (unstable); r0 = %.1f m\n\n",
         p.grav * cos(p.alpha) / (s_rate * s_rate), r0);
  printf("%5s %16s %16s %16s %10s %10s %10s %10s\n", "t", "r exact", "r reduced", "r 3-D",
         "err red", "err 3-D", "Jacobi 3D", "|Av+a0|");
  double J0 = rs_line_jacobi(&p, r0, rd0), worst = 0.0, worst_j = 0.0;
  int st = AP_OK;
  for (int i = 0; i <= 10; i++) {
    double t = 2.0 * i, re, rde;
    if (i > 0 && ((st = ap_sim_advance(sr, t)) != AP_OK || (st = ap_sim_advance(s3, t)) != AP_OK)) {
      fprintf(stderr, "rotating_line: advance to t = %g: %s: %s | %s\n", t, ap_strerror(st),
              ap_sim_message(sr), ap_sim_message(s3));
      break;
    }
    rs_line_exact(&p, r0, rd0, t, &re, &rde);
    const double *q = ap_sim_q(s3), *v = ap_sim_v(s3);
    double c = cos(p.w * t), sn = sin(p.w * t), sa = sin(p.alpha), ca = cos(p.alpha);
    double r3 = q[0] * sa * c + q[1] * sa * sn + q[2] * ca;   /* r = p . d(t) */
    double rr = ap_sim_q(sr)[0], sc = fmax(1.0, fabs(re));
    double e_r = fabs(rr - re) / sc, e_3 = fabs(r3 - re) / sc;
    /* Jacobi drift relative to its largest term m (r'^2 + s^2 r^2) / 2. */
    double jsc = 0.5 * p.m * (rde * rde + s_rate * s_rate * re * re) + fabs(J0);
    double dj = fabs(rs_line_jacobi_3d(&p, q, v) - J0) / jsc;
    worst = fmax(worst, fmax(e_r, e_3));
    worst_j = fmax(worst_j, dj);
    printf("%5.1f %16.9f %16.9f %16.9f %10.2e %10.2e %10.2e %10.2e\n", t, re, rr, r3, e_r, e_3,
           dj, ap_constraint_residual(ap_sim_data(s3), v));
  }
  ap_sim_free(sr);
  ap_sim_free(s3);
  ap_model_free(mr);
  ap_model_free(m3);
  if (st != AP_OK) return 1;
  int ok = worst <= ERR_BOUND && worst_j <= JACOBI_BOUND;
  printf("\nworst r error %.2e (bound %.0e), Jacobi drift %.2e (bound %.0e): %s\n", worst,
         ERR_BOUND, worst_j, JACOBI_BOUND, ok ? "ok" : "TOO LARGE");
  return ok ? 0 : 1;
}
