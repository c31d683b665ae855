/* The Kepler problem of the stepper tests (kepler.h): eccentricity ECC, mu = a = 1, started at
 * pericentre, y = (x, y, vx, vy); the exact state from Kepler's equation; drivers that run a
 * stepper through it and measure the error. */
#include "kepler.h"

#include <math.h>
#include <stdio.h>

#include "appell/status.h"

int kepler_rhs(double t, const double *y, double *ydot, void *user) {
  kepler *k = user;
  (void)t;
  k->calls++;
  if (k->fail_at && k->calls == k->fail_at) return k->fail_code;
  double r2 = y[0] * y[0] + y[1] * y[1], r3 = r2 * sqrt(r2);
  ydot[0] = y[2], ydot[1] = y[3], ydot[2] = -y[0] / r3, ydot[3] = -y[1] / r3;
  if ((k->nan_from && k->calls >= k->nan_from) || k->calls == k->nan_at) ydot[2] = NAN;
  return 0;
}

/* Exact state at time t (Kepler's equation E - e sin E = t by Newton). */
void kepler_exact(double t, double *y) {
  double E = t;
  for (int i = 0; i < 50; i++) {
    double dE = (E - ECC * sin(E) - t) / (1.0 - ECC * cos(E));
    E -= dE;
    if (fabs(dE) < 1e-16) break;
  }
  double s = sqrt(1.0 - ECC * ECC), den = 1.0 - ECC * cos(E);
  y[0] = cos(E) - ECC, y[1] = s * sin(E), y[2] = -sin(E) / den, y[3] = s * cos(E) / den;
}

double err_at(double t, const double *y) {
  double ye[4], e = 0.0;
  kepler_exact(t, ye);
  for (int i = 0; i < 4; i++) e = fmax(e, fabs(y[i] - ye[i]));
  return e;
}

ap_step_opts kepler_opts(double rtol, double h_fixed) {
  ap_step_opts o = {rtol, rtol * 1e-2, h_fixed, 0.0, 0.0, 10000000L, NULL, NULL};
  return o;
}

/* Integrate from 0 through the tstops; returns the status, y the final state. */
int kepler_run(const ap_step_method *m, ap_step_opts o, kepler *k, int ntstop,
               const double *tstops, double *y, ap_step_stats *st) {
  ap_stepper *s = NULL;
  char msg[512];
  double t = 0.0;
  kepler_exact(0.0, y);
  int rc = ap_step_create(m, 4, kepler_rhs, k, 0.0, y, &o, &s, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "%s: create: %s\n", m->name, msg);
    return rc;
  }
  for (int i = 0; rc == AP_OK && i < ntstop; i++)
    while (rc == AP_OK && t < tstops[i]) rc = ap_step_one(s, tstops[i], &t, y);
  if (st) ap_step_get_stats(s, st);
  ap_step_free(s);
  return rc;
}

/* Error at T after nsteps fixed steps T / nsteps. */
double fixed_error(const ap_step_method *m, double T, int nsteps) {
  kepler k = {0};
  double y[4];
  int rc = kepler_run(m, kepler_opts(0.0, T / nsteps), &k, 1, &T, y, NULL);
  return rc == AP_OK ? err_at(T, y) : NAN;
}

double adaptive_error(const ap_step_method *m, double rtol, ap_step_stats *st) {
  kepler k = {0};
  double y[4], T = PERIOD;
  int rc = kepler_run(m, kepler_opts(rtol, 0.0), &k, 1, &T, y, st);
  return rc == AP_OK ? err_at(T, y) : NAN;
}

/* Least-squares slope of log(e) against log(x). */
double slope(int n, const double *x, const double *e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int i = 0; i < n; i++) {
    double lx = log(x[i]), ly = log(e[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}
