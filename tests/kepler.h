/* The problem shared by the stepper tests (test_steppers.c: order conditions and observed
 * orders; test_steppers_behave.c: accuracy, counts, restarts, failures, arguments): the Kepler
 * two-body problem, eccentricity 0.5, y = (x, y, vx, vy), mu = a = 1, started at pericentre;
 * the exact solution at any t comes from Kepler's equation, and after one period T = 2 pi the
 * state returns to y0. A right-hand side that fails on purpose (> 0, < 0, NaN) on chosen calls
 * walks the steppers' error paths. */
#ifndef AP_TESTS_KEPLER_H
#define AP_TESTS_KEPLER_H

#include "integrate/stepper.h"

#define ECC 0.5
#define PERIOD (2.0 * 3.14159265358979323846)
#define MAXS 16    /* the most stages of a Butcher table asked for */

typedef struct kepler {
  long calls;
  long fail_at;      /* this call (1-based) returns fail_code; 0 = never */
  int fail_code;
  long nan_from;     /* from this call on, ydot = NaN; 0 = never */
  long nan_at;       /* this call only gives ydot = NaN; 0 = never */
} kepler;

/* The right-hand side (user: a kepler, which counts the calls and fails as it says). */
int kepler_rhs(double t, const double *y, double *ydot, void *user);

/* Exact state at time t (Kepler's equation E - e sin E = t by Newton). */
void kepler_exact(double t, double *y);

/* max |y - y_exact(t)|. */
double err_at(double t, const double *y);

/* Options: rtol, atol = rtol / 100, a fixed step h_fixed (0: adaptive), 1e7 steps at most. */
ap_step_opts kepler_opts(double rtol, double h_fixed);

/* Integrate from 0 through the tstops; returns the status, y the final state. */
int kepler_run(const ap_step_method *m, ap_step_opts o, kepler *k, int ntstop,
               const double *tstops, double *y, ap_step_stats *st);

/* Error at T after nsteps fixed steps T / nsteps. */
double fixed_error(const ap_step_method *m, double T, int nsteps);

/* Error after one period, adaptive at rtol; st (may be NULL) gets the stepper's counts. */
double adaptive_error(const ap_step_method *m, double rtol, ap_step_stats *st);

/* Least-squares slope of log(e) against log(x). */
double slope(int n, const double *x, const double *e);

#endif
