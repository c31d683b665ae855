/* Reference systems with known answers (docs/references.md) as math-level systems (refsys.h):
 * what the systems share. rs_gauss_legendre and rs_panels make the composite 16-point
 * Gauss-Legendre rule of the closed forms that need a quadrature (sleigh x, y; turntable with
 * Omega(t)), panels short against the fastest rate of the integrand (error ~1e-15);
 * rs_residual is the velocity-constraint residual |A v + a0| of any of them.
 *
 * The systems: refsys_blade.c (knife edge, Chaplygin sleigh), refsys_moving.c (ball on a
 * turntable, particle on a rotating line), refsys_hoffmann.c (Hoffmann's pendulum). */
#include "refsys.h"

#include <math.h>
#include <string.h>

#include "refsys_quad.h"

/* Composite Gauss-Legendre panels: a panel spans at most RS_PANEL_TURN radians of the fastest
 * rotation in the integrand and at most RS_PANEL_MAX seconds. */
#define RS_PANEL_TURN 0.5
#define RS_PANEL_MAX 0.5

void rs_gauss_legendre(int n, double *x, double *w) {
  /* Newton on P_n from the Tricomi-type initial guess; weights 2 / ((1 - z^2) P_n'(z)^2). */
  for (int i = 0; i < (n + 1) / 2; i++) {
    double z = cos(RS_PI * (i + 0.75) / (n + 0.5)), pp = 1.0;
    for (int it = 0; it < 100; it++) {
      double p1 = 1.0, p2 = 0.0;
      for (int j = 1; j <= n; j++) {
        double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
      }
      pp = n * (z * p1 - p2) / (z * z - 1.0);
      double dz = p1 / pp;
      z -= dz;
      if (fabs(dz) < 1e-16 && it > 2) break;
    }
    x[i] = -z;
    x[n - 1 - i] = z;
    w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * pp * pp);
  }
}

int rs_panels(double t, double rate) {
  double hp = RS_PANEL_MAX;
  if (rate * hp > RS_PANEL_TURN) hp = RS_PANEL_TURN / rate;
  int np = (int)ceil(fabs(t) / hp);
  return np < 1 ? 1 : np;
}

double rs_residual(const ap_system_def *def, double t, const double *q, const double *v,
                   double *scale) {
  double A[256], a0[16], worst = 0.0, sc = 0.0;
  int b = def->b, k = def->k;
  if (scale) *scale = 0.0;
  if (b == 0) return 0.0;
  if (b > 16 || k > 16 || b * k > 256) return -1.0;
  memset(A, 0, sizeof A);
  memset(a0, 0, sizeof a0);
  if (def->constraint(t, q, A, a0, def->user) != 0) return -1.0;
  for (int s = 0; s < b; s++) {
    double r = a0[s], mag = fabs(a0[s]);
    for (int c = 0; c < k; c++) {
      r += A[s + b * c] * v[c];
      mag += fabs(A[s + b * c] * v[c]);
    }
    if (fabs(r) > worst) worst = fabs(r);
    if (mag > sc) sc = mag;
  }
  if (scale) *scale = sc;
  return worst;
}

