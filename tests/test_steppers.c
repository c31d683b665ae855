/* Steppers (lib/integrate/stepper*.c): every method is checked on what it claims.
 *
 * Problem: the Kepler two-body problem, eccentricity 0.5, y = (x, y, vx, vy), mu = a = 1,
 * started at pericentre; the exact solution at any t comes from Kepler's equation, and after
 * one period T = 2 pi the state returns to y0.
 *
 * 1. Order conditions: for every Runge-Kutta method, the Butcher table the stepper really
 *    hands to ARKODE (ap_step_butcher) satisfies c_i = sum_j A_ij and the rooted-tree
 *    conditions b . Phi(t) = 1 / gamma(t) for all trees of order <= p, and fails order p + 1.
 * 2. Observed order: fixed steps h = (T/2) / N from pericentre to apocentre, least-squares
 *    slope of log(err) against log(h) over a factor 4 in h, within 0.3 of the claimed order
 *    (ERK methods; step ranges where the error is asymptotic and far above round-off). CVODE
 *    has no fixed step: a tolerance sweep must make the error fall monotonically.
 * 3. Adaptive accuracy (error < 1e-8 after one period at rtol 1e-10; verner6, adams and bdf
 *    need rtol 1e-11, see docs/steppers.md), evaluations per step, reset-and-continue, dense
 *    output, failing right-hand sides (> 0 once, < 0, NaN), max_steps, argument checks.
 * The orders of raw SUNDIALS ERKStep with its own Heun-Euler, Verner 8-5-6 and Fehlberg
 * 13-7-8 tables are printed for docs/steppers.md (the FSAL bug worked around in
 * stepper_arkode.c); they are not asserted. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>

#include "appell/status.h"
#include "check.h"
#include "integrate/stepper.h"

#define ECC 0.5
#define PERIOD (2.0 * 3.14159265358979323846)
#define MAXS 16

/* ---- the problem ------------------------------------------------------------------------ */

typedef struct kepler {
  long calls;
  long fail_at;      /* this call (1-based) returns fail_code; 0 = never */
  int fail_code;
  long nan_from;     /* from this call on, ydot = NaN; 0 = never */
  long nan_at;       /* this call only gives ydot = NaN; 0 = never */
} kepler;

static int kepler_rhs(double t, const double *y, double *ydot, void *user) {
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
static void kepler_exact(double t, double *y) {
  double E = t;
  for (int i = 0; i < 50; i++) {
    double dE = (E - ECC * sin(E) - t) / (1.0 - ECC * cos(E));
    E -= dE;
    if (fabs(dE) < 1e-16) break;
  }
  double s = sqrt(1.0 - ECC * ECC), den = 1.0 - ECC * cos(E);
  y[0] = cos(E) - ECC, y[1] = s * sin(E), y[2] = -sin(E) / den, y[3] = s * cos(E) / den;
}

static double err_at(double t, const double *y) {
  double ye[4], e = 0.0;
  kepler_exact(t, ye);
  for (int i = 0; i < 4; i++) e = fmax(e, fabs(y[i] - ye[i]));
  return e;
}

static ap_step_opts opts(double rtol, double h_fixed) {
  ap_step_opts o = {rtol, rtol * 1e-2, h_fixed, 0.0, 0.0, 10000000L, NULL};
  return o;
}

/* Integrate from 0 through the tstops; returns the status, y the final state. */
static int run(const ap_step_method *m, ap_step_opts o, kepler *k, int ntstop,
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
static double fixed_error(const ap_step_method *m, double T, int nsteps) {
  kepler k = {0};
  double y[4];
  int rc = run(m, opts(0.0, T / nsteps), &k, 1, &T, y, NULL);
  return rc == AP_OK ? err_at(T, y) : NAN;
}

static double adaptive_error(const ap_step_method *m, double rtol, ap_step_stats *st) {
  kepler k = {0};
  double y[4], T = PERIOD;
  int rc = run(m, opts(rtol, 0.0), &k, 1, &T, y, st);
  return rc == AP_OK ? err_at(T, y) : NAN;
}

/* Least-squares slope of log(e) against log(x). */
static double slope(int n, const double *x, const double *e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int i = 0; i < n; i++) {
    double lx = log(x[i]), ly = log(e[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/* ---- 1. order conditions on rooted trees -------------------------------------------------- */

#define MAXT 800   /* trees of order <= 9: 1+1+2+4+9+20+48+115+286 = 486 */

typedef struct trees {
  int nt, s;
  int order[MAXT];
  double gamma[MAXT];
  double phi[MAXT][MAXS];    /* elementary weights Phi_i(t) */
  double aphi[MAXT][MAXS];   /* (A Phi(t))_i, the factor a child contributes to its parent */
} trees;

/* Add every tree of order `order` whose root's children (indices >= first, non-decreasing)
 * have orders summing to `left`; kids/nk: children chosen so far. */
static void grow(trees *T, const double *A, int order, int first, int left, int *kids,
                 int nk) {
  if (left == 0) {
    if (T->nt >= MAXT) return;
    int t = T->nt++;
    T->order[t] = order, T->gamma[t] = order;
    for (int i = 0; i < T->s; i++) T->phi[t][i] = 1.0;
    for (int c = 0; c < nk; c++) {
      T->gamma[t] *= T->gamma[kids[c]];
      for (int i = 0; i < T->s; i++) T->phi[t][i] *= T->aphi[kids[c]][i];
    }
    for (int i = 0; i < T->s; i++) {
      T->aphi[t][i] = 0.0;
      for (int j = 0; j < T->s; j++) T->aphi[t][i] += A[i * T->s + j] * T->phi[t][j];
    }
    return;
  }
  int last = T->nt;   /* only trees that exist before this order */
  for (int c = first; c < last; c++) {
    if (T->order[c] > left) continue;
    kids[nk] = c;
    grow(T, A, order, c, left - T->order[c], kids, nk + 1);
  }
}

/* Largest p <= pmax such that b satisfies all conditions b . Phi(t) = theta^|t| / gamma(t)
 * up to order p (theta = 1: the method's weights; theta < 1: a dense output's weights at
 * theta); *res gets the largest residual over orders <= p and *next the largest at p + 1. */
static int rk_order_at(int s, const double *A, const double *b, int pmax, double theta,
                       double *res, double *next) {
  static trees T;
  int kids[16], p = 0;
  T.nt = 0, T.s = s;
  *res = 0.0, *next = 0.0;
  for (int order = 1; order <= pmax; order++) {
    int start = T.nt;
    grow(&T, A, order, 0, order - 1, kids, 0);
    double worst = 0.0;
    for (int t = start; t < T.nt; t++) {
      double sum = 0.0;
      for (int i = 0; i < s; i++) sum += b[i] * T.phi[t][i];
      worst = fmax(worst, fabs(sum - pow(theta, order) / T.gamma[t]));
    }
    if (worst > 1e-12) {
      *next = worst;
      return p;
    }
    p = order, *res = fmax(*res, worst);
  }
  return p;
}

static int rk_order(int s, const double *A, const double *b, int pmax, double *res,
                    double *next) {
  return rk_order_at(s, A, b, pmax, 1.0, res, next);
}

/* Order of the embedded solution d: one below the method's, but 5 for DOP853 (its error
 * estimate combines embeddings of orders 5 and 3). */
static int embedded_order(const ap_step_method *m) {
  return strcmp(m->name, "dop853") == 0 ? 5 : m->order - 1;
}

static void check_tables(void) {
  printf("order conditions (table handed to ARKODE; dop853: to our own stepper):\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    double A[MAXS * MAXS], b[MAXS], c[MAXS], d[MAXS], res, next, dres, dnext, rowsum = 0.0;
    int s, q;
    if (ap_step_butcher(m, MAXS, &s, &q, A, b, c, d) != AP_OK) continue;
    for (int r = 0; r < s; r++) {
      double sum = 0.0;
      for (int j = 0; j < s; j++) sum += A[r * s + j];
      rowsum = fmax(rowsum, fabs(sum - c[r]));
    }
    int p = rk_order(s, A, b, m->order + 1, &res, &next);
    int pd = m->adaptive ? rk_order(s, A, d, m->order, &dres, &dnext) : 0;
    printf("  %-9s stages %2d  b: order %d (residual %.1e; order %d fails by %.1e)  "
           "d: order %d  max|c - A 1| %.1e\n", m->name, s, p, res, p + 1, next, pd, rowsum);
    AP_CHECK_EQ_INT(p, m->order);
    AP_CHECK_EQ_INT(q, m->order);
    AP_CHECK_LE(rowsum, 1e-14);
    AP_CHECK(next > 1e-8);   /* order p + 1 fails clearly: the claimed order is sharp */
    if (m->adaptive) AP_CHECK_EQ_INT(pd, embedded_order(m));   /* the embedding */
  }
}

/* DOP853 (stepper_rk.c) beyond ap_step_butcher: the dense-output stages 14 ... 16 and their
 * row sums, the order-3 embedding, and the continuous extension: its weights w(theta) satisfy
 * every condition of order <= 7 at theta (w(theta) . Phi(t) = theta^|t| / gamma(t)) and fail
 * order 8 inside the step. */
static void check_dop853_tables(void) {
  double A[MAXS * MAXS], c[MAXS], b3[MAXS], w[MAXS], res, next, rowsum = 0.0;
  int s;
  AP_CHECK_EQ_INT(ap_step_rk_tables(MAXS, &s, A, c, b3, 1.0, w), AP_OK);
  AP_CHECK_EQ_INT(s, 16);
  for (int r = 0; r < s; r++) {
    double sum = 0.0;
    for (int j = 0; j < s; j++) sum += A[r * s + j];
    rowsum = fmax(rowsum, fabs(sum - c[r]));
  }
  int p3 = rk_order(s, A, b3, 5, &res, &next);
  printf("  dop853    16 stages with dense output: max|c - A 1| %.1e; order-3 embedding: order "
         "%d (order 4 fails by %.1e)\n", rowsum, p3, next);
  AP_CHECK_LE(rowsum, 1e-14);
  AP_CHECK_EQ_INT(p3, 3);
  int p1 = rk_order(s, A, w, 9, &res, &next);     /* theta = 1: the step itself */
  AP_CHECK_EQ_INT(p1, 8);
  static const double thetas[] = {0.1, 0.3, 0.5, 0.7, 0.9};
  for (int i = 0; i < 5; i++) {
    AP_CHECK_EQ_INT(ap_step_rk_tables(MAXS, &s, A, c, b3, thetas[i], w), AP_OK);
    int p = rk_order_at(s, A, w, 8, thetas[i], &res, &next);
    printf("            dense output at theta %.1f: order %d (residual %.1e; order %d fails "
           "by %.1e)\n", thetas[i], p, res, p + 1, next);
    AP_CHECK_EQ_INT(p, 7);
    AP_CHECK(next > 1e-9);
  }
}

/* ---- 2. observed order -------------------------------------------------------------------- */

/* First N per method and the fitted range N, N sqrt2, ..., 4 N: errors asymptotic and far
 * above round-off (found by scanning N from 16 to 4096; docs/steppers.md). */
static int fixed_range(const char *name) {
  static const struct { const char *name; int n0; } r[] = {
      {"heun2", 1000}, {"bs3", 192},     {"rk4", 270},
      {"dopri5", 135}, {"verner6", 135}, {"fehlberg8", 24}, {"dop853", 18}};
  for (size_t i = 0; i < sizeof r / sizeof r[0]; i++)
    if (strcmp(r[i].name, name) == 0) return r[i].n0;
  return 0;
}

/* Fitted order of a stepping function over the range of `name`. */
static double fit_order(const char *name, double (*err)(const void *, double, int),
                        const void *arg) {
  int n0 = fixed_range(name);
  double h[5], e[5], T = PERIOD / 2;
  for (int j = 0; j < 5; j++) {
    int n = (int)(n0 * pow(2.0, 0.5 * j) + 0.5);
    h[j] = T / n;
    e[j] = err(arg, T, n);
    printf("  %.2e", e[j]);
  }
  return slope(5, h, e);
}

static double method_error(const void *m, double T, int n) { return fixed_error(m, T, n); }

static void check_fixed_orders(void) {
  printf("observed order at fixed steps, Kepler e = 0.5 over [0, T/2] (errors for N = N0 "
         "... 4 N0):\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    if (!fixed_range(m->name)) continue;
    printf("  %-9s N0 %4d:", m->name, fixed_range(m->name));
    double p = fit_order(m->name, method_error, m);
    printf("  -> fitted order %.2f (claimed %d)\n", p, m->order);
    AP_CHECK_NEAR(p, m->order, 0.3);
  }
}

/* dop853's local slopes over the half period, N = 12 ... 204 (for docs/steppers.md: the
 * fitted order depends on the range; printed, not asserted). */
static void report_dop853_slopes(void) {
  const ap_step_method *m = ap_step_method_find("dop853");
  double T = PERIOD / 2, prev = 0.0;
  printf("dop853 at fixed steps over [0, T/2], local slopes between N and N + 8:\n ");
  for (int n = 12; n <= 204; n += 8) {
    double e = fixed_error(m, T, n);
    if (n > 12) printf(" %d:%.1f", n - 8, log(prev / e) / log((double)n / (n - 8)));
    if ((n - 12) % 96 == 88) printf("\n ");
    prev = e;
  }
  printf("\n");
}

/* Dense output: one fixed step h from the exact state at t0 = 1 (past pericentre), then
 * ap_step_dky at t0 + h/2 against the exact solution; the local error of an interpolant of
 * order r is O(h^(r+1)). Fitted over h = 0.4 / sqrt2^j, j = 1 ... 5 (DOP853's errors 4e-9 ...
 * 7e-14, far above round-off; its local slopes still rise towards 8 over this range). Printed for every ERK method (docs/steppers.md), asserted for
 * dop853, whose continuous extension has order 7. */
static double dense_error(const ap_step_method *m, double h, double *step_err) {
  ap_step_opts o = opts(0.0, h);
  ap_stepper *s = NULL;
  double t0 = 1.0, y[4], ym[4], t = t0;
  kepler k = {0};
  kepler_exact(t0, y);
  if (ap_step_create(m, 4, kepler_rhs, &k, t0, y, &o, &s, NULL, 0) != AP_OK) return NAN;
  int rc = ap_step_one(s, t0 + h, &t, y);
  if (rc == AP_OK) rc = ap_step_dky(s, t0 + 0.5 * h, ym);
  ap_step_free(s);
  *step_err = err_at(t, y);
  return rc == AP_OK ? err_at(t0 + 0.5 * h, ym) : NAN;
}

static void check_dense_order(void) {
  printf("dense output, local error at the middle of one step h from the exact state "
         "(Kepler, t0 = 1; h = 0.28 ... 0.071):\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    if (m->backend == &ap_step_cvode) continue;
    double h[5], e[5], es[5];
    printf("  %-9s", m->name);
    for (int j = 0; j < 5; j++) {
      h[j] = 0.4 / pow(2.0, 0.5 * (j + 1));
      e[j] = dense_error(m, h[j], &es[j]);
      printf("  %.2e", e[j]);
    }
    double p = slope(5, h, e) - 1.0;
    printf("  -> dense output order %.2f (the step's local error: order %.2f)\n", p,
           slope(5, h, es) - 1.0);
    if (strcmp(m->name, "dop853") == 0) AP_CHECK_NEAR(p, 7.0, 0.3);
  }
}

static void check_cvode_sweep(void) {
  printf("CVODE tolerance sweep (Kepler, one period, atol = rtol / 100):\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    if (m->backend != &ap_step_cvode) continue;
    double tol[5], e[5];
    printf("  %-9s", m->name);
    for (int j = 0; j < 5; j++) {
      tol[j] = pow(10.0, -4.0 - 2.0 * j);
      e[j] = adaptive_error(m, tol[j], NULL);
      printf("  rtol %.0e err %.2e", tol[j], e[j]);
      if (j > 0) AP_CHECK(e[j] < e[j - 1]);
    }
    double p = slope(5, tol, e);
    printf("  -> d log(err) / d log(rtol) = %.2f\n", p);
    AP_CHECK(p > 0.5 && p < 1.5);
  }
}

/* The unrepaired SUNDIALS table through ERKStep at fixed steps: the bug, for the record. */
static int raw_rhs(realtype t, N_Vector y, N_Vector ydot, void *user) {
  return kepler_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), user);
}

static double raw_evals_per_step;   /* of the last raw_erkstep_error run */

static double raw_erkstep_error(const void *table, double T, int nsteps) {
  SUNContext ctx;
  kepler k = {0};
  realtype t = 0.0;
  if (SUNContext_Create(NULL, &ctx) != 0) return NAN;
  N_Vector y = N_VNew_Serial(4, ctx);
  kepler_exact(0.0, N_VGetArrayPointer(y));
  void *mem = ERKStepCreate(raw_rhs, 0.0, y, ctx);
  ERKStepSetUserData(mem, &k);
  ERKStepSetTableNum(mem, *(const ARKODE_ERKTableID *)table);
  ERKStepSetFixedStep(mem, T / nsteps);
  ERKStepSetStopTime(mem, T);
  ERKStepSetMaxNumSteps(mem, 10 * nsteps);
  int flag = ERKStepEvolve(mem, T, y, &t, ARK_NORMAL);
  double e = flag >= 0 ? err_at(T, N_VGetArrayPointer(y)) : NAN;
  raw_evals_per_step = (double)k.calls / nsteps;
  ERKStepFree(&mem);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return e;
}

static void report_raw_erkstep(void) {
  static const ARKODE_ERKTableID ids[] = {ARKODE_HEUN_EULER_2_1_2, ARKODE_VERNER_8_5_6,
                                          ARKODE_FEHLBERG_13_7_8};
  static const char *names[] = {"heun2", "verner6", "fehlberg8"};
  printf("the same, SUNDIALS %s ERKStep with its own tables, no FSAL repair (not asserted):\n",
         SUNDIALS_VERSION);
  for (int i = 0; i < 3; i++) {
    ARKodeButcherTable B = ARKodeButcherTable_LoadERK(ids[i]);
    printf("  %-9s N0 %4d:", names[i], fixed_range(names[i]));
    double p = fit_order(names[i], raw_erkstep_error, &ids[i]);
    printf("  -> fitted order %.2f, %.2f evaluations per step with %d stages\n", p,
           raw_evals_per_step, B ? B->stages : 0);
    if (B) {   /* how well the reused last stage Y_s approximates y_{n+1}: its order */
      int ns = B->stages;
      double A[MAXS * MAXS], w[MAXS], res, next;
      for (int r = 0; r < ns; r++)
        for (int j = 0; j < ns; j++) A[r * ns + j] = B->A[r][j];
      for (int j = 0; j < ns; j++) w[j] = B->A[ns - 1][j];
      printf("            last row of A (c = %g) as weights: order %d; b_1 = %g\n",
             B->c[ns - 1], rk_order(ns, A, w, 8, &res, &next), B->b[0]);
    }
    ARKodeButcherTable_Free(B);
  }
}

/* ---- 3. behaviour ------------------------------------------------------------------------- */

/* rtol at which each method's error after one period is below 1e-8 (measured; the global
 * error of verner6 runs about 100 x rtol on this problem, CVODE's about 1000 x rtol). */
static double rtol_for_1e8(const ap_step_method *m) {
  const char *slow[] = {"verner6", "adams", "bdf"};
  for (int i = 0; i < 3; i++)
    if (strcmp(m->name, slow[i]) == 0) return 1e-11;
  return 1e-10;
}

static void check_adaptive(void) {
  printf("adaptive, atol = rtol / 100, one period:\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    if (!m->adaptive) continue;
    ap_step_stats st;
    double e10 = adaptive_error(m, 1e-10, &st), rtol = rtol_for_1e8(m);
    printf("  %-9s rtol 1e-10: err %.2e  steps %7ld  rhs evals %8ld  error-test fails %3ld",
           m->name, e10, st.steps, st.rhs_evals, st.err_fails);
    double e = rtol == 1e-10 ? e10 : adaptive_error(m, rtol, NULL);
    if (rtol != 1e-10) printf("   rtol %.0e: err %.2e", rtol, e);
    printf("\n");
    AP_CHECK_LE(e, 1e-8);
    AP_CHECK_LE(e10, 1e-6);
    AP_CHECK(st.steps > 0 && st.rhs_evals >= st.steps);
  }
}

/* Fixed steps: exactly one step per call and, before the step that reaches tstop, exactly
 * (stages - 1) evaluations per step plus one (the repaired tables are all FSAL). Reaching
 * tstop costs up to 4 more: ARKODE evaluates its Hermite interpolant there. */
static void check_fixed_counts(void) {
  printf("evaluations per fixed step:\n");
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    double A[MAXS * MAXS], b[MAXS], c[MAXS], d[MAXS], y[4], t = 0.0;
    int s, q, n = 64;
    if (ap_step_butcher(m, MAXS, &s, &q, A, b, c, d) != AP_OK) continue;
    ap_step_opts o = opts(0.0, PERIOD / n);
    ap_stepper *st = NULL;
    ap_step_stats before, after;
    kepler k = {0};
    kepler_exact(0.0, y);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, y, &o, &st, NULL, 0), AP_OK);
    if (!st) continue;
    for (int j = 0; j < n - 1; j++) ap_step_one(st, PERIOD, &t, y);
    ap_step_get_stats(st, &before);
    AP_CHECK_EQ_INT(ap_step_one(st, PERIOD, &t, y), AP_OK);
    AP_CHECK(t == PERIOD);
    ap_step_get_stats(st, &after);
    long last = after.rhs_evals - before.rhs_evals;
    printf("  %-9s %d per step (%d stages), the step reaching tstop %ld\n", m->name, s - 1, s,
           last);
    AP_CHECK_EQ_INT(before.steps, n - 1);
    AP_CHECK_EQ_INT(after.steps, n);
    AP_CHECK_EQ_INT(before.rhs_evals, (long)(n - 1) * (s - 1) + 1);
    AP_CHECK(last >= s - 1 && last <= s + 3);
    AP_CHECK_EQ_INT(after.err_fails, 0);
    AP_CHECK_NEAR(after.h_last, PERIOD / n, 1e-12);
    AP_CHECK_EQ_INT(after.rhs_evals, k.calls);
    if (strcmp(m->name, "dopri5") == 0) AP_CHECK_EQ_INT(s - 1, 6);
    ap_step_free(st);
  }
}

/* Stop at T/2 and go on to T, once plainly and once with ap_step_reset at T/2. */
static void check_reset(void) {
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    int fixed = m->backend == &ap_step_arkode || m->backend == &ap_step_rk;
    ap_step_opts o = opts(1e-10, fixed ? PERIOD / 256 : 0.0);
    double ya[4], yb[4], t = 0.0, tb = 0.0, ts[2] = {PERIOD / 2, PERIOD};
    kepler k = {0};
    ap_stepper *s = NULL;
    AP_CHECK_EQ_INT(run(m, o, &k, 2, ts, ya, NULL), AP_OK);
    kepler_exact(0.0, yb);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, yb, &o, &s, NULL, 0), AP_OK);
    if (!s) continue;
    while (t < ts[0]) AP_CHECK_EQ_INT(ap_step_one(s, ts[0], &t, yb), AP_OK);
    AP_CHECK(t == ts[0]);                         /* lands on tstop exactly */
    AP_CHECK_EQ_INT(ap_step_reset(s, t, yb), AP_OK);
    while (t < ts[1] && ap_step_one(s, ts[1], &t, yb) == AP_OK) tb = t;
    AP_CHECK(tb == ts[1]);
    double diff = 0.0;
    for (int j = 0; j < 4; j++) diff = fmax(diff, fabs(ya[j] - yb[j]));
    /* ERK at fixed steps: the restart recomputes f(y) exactly, the result is the same */
    AP_CHECK_LE(diff, fixed ? 1e-14 : 1e-6);
    if (!fixed) AP_CHECK_LE(err_at(PERIOD, yb), 1e-6);
    ap_step_free(s);
  }
}

/* ap_step_restart (a change of coordinates on the same trajectory): DOP853 handed the exact
 * f(t, y) continues exactly as if uninterrupted (same step sizes, same result bit for bit, no
 * extra evaluation); ap_step_reset costs one evaluation (f at the new start) and otherwise
 * gives the same steps. Other methods restart as with ap_step_reset. */
static void check_restart(void) {
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    if (!m->adaptive || m->order < 5) continue;   /* heun2, bs3: too many steps at 1e-9 */
    int own = m->backend == &ap_step_rk;
    double ts[2] = {PERIOD / 2, PERIOD}, ya[4], yb[4], yc[4], f[4], t = 0.0, tc = 0.0;
    ap_step_stats sa, sb, sc;
    kepler k = {0};
    AP_CHECK_EQ_INT(run(m, opts(1e-9, 0.0), &k, 2, ts, ya, &sa), AP_OK);
    ap_stepper *s = NULL, *r = NULL;
    kepler_exact(0.0, yb), kepler_exact(0.0, yc);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, yb, &(ap_step_opts){1e-9, 1e-11,
                    0, 0, 0, 10000000L, NULL}, &s, NULL, 0), AP_OK);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, yc, &(ap_step_opts){1e-9, 1e-11,
                    0, 0, 0, 10000000L, NULL}, &r, NULL, 0), AP_OK);
    if (!s || !r) continue;
    while (t < ts[0]) AP_CHECK_EQ_INT(ap_step_one(s, ts[0], &t, yb), AP_OK);
    while (tc < ts[0]) AP_CHECK_EQ_INT(ap_step_one(r, ts[0], &tc, yc), AP_OK);
    kepler_rhs(t, yb, f, &k);
    AP_CHECK_EQ_INT(ap_step_restart(s, t, yb, f), AP_OK);
    AP_CHECK_EQ_INT(ap_step_reset(r, tc, yc), AP_OK);
    while (t < ts[1]) AP_CHECK_EQ_INT(ap_step_one(s, ts[1], &t, yb), AP_OK);
    while (tc < ts[1]) AP_CHECK_EQ_INT(ap_step_one(r, ts[1], &tc, yc), AP_OK);
    ap_step_get_stats(s, &sb), ap_step_get_stats(r, &sc);
    double db = 0.0, dc = 0.0;
    for (int j = 0; j < 4; j++) db = fmax(db, fabs(yb[j] - ya[j])), dc = fmax(dc, fabs(yc[j] - ya[j]));
    printf("  %-9s restart at T/2: steps %ld, evaluations %ld (uninterrupted %ld, %ld; with "
           "reset %ld, %ld), |y - y_uninterrupted| %.1e (reset %.1e)\n", m->name, sb.steps,
           sb.rhs_evals, sa.steps, sa.rhs_evals, sc.steps, sc.rhs_evals, db, dc);
    AP_CHECK_LE(err_at(PERIOD, yb), 1e-6);
    if (own) {
      AP_CHECK(memcmp(ya, yb, sizeof ya) == 0);   /* bit for bit */
      AP_CHECK_EQ_INT(sb.steps, sa.steps);
      AP_CHECK_EQ_INT(sb.rhs_evals, sa.rhs_evals);
      AP_CHECK(memcmp(ya, yc, sizeof ya) == 0);   /* reset: the same f recomputed */
      AP_CHECK_EQ_INT(sc.rhs_evals, sa.rhs_evals + 1);
    }
    ap_step_free(s), ap_step_free(r);
  }
}

/* Dense output in the middle of the last step, and refusal outside it. */
static void check_dky(void) {
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    ap_step_opts o = opts(1e-10, m->adaptive ? 0.0 : PERIOD / 1000);
    kepler k = {0};
    ap_stepper *s = NULL;
    double y[4], ym[4], t = 0.0, t0 = 0.0;
    kepler_exact(0.0, y);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, y, &o, &s, NULL, 0), AP_OK);
    if (!s) continue;
    for (int j = 0; j < 20; j++) t0 = t, ap_step_one(s, PERIOD, &t, y);
    AP_CHECK_EQ_INT(ap_step_dky(s, 0.5 * (t0 + t), ym), AP_OK);
    AP_CHECK_LE(err_at(0.5 * (t0 + t), ym), 1e-7);
    AP_CHECK(ap_step_dky(s, t + 10.0, ym) < 0);
    ap_step_free(s);
  }
}

/* f > 0 once: retried and accurate; f < 0: AP_ERR_CALLBACK; NaN: a clean negative status. */
static void check_failures(void) {
  for (int i = 0; i < ap_step_method_count(); i++) {
    const ap_step_method *m = ap_step_method_get(i);
    ap_step_opts o = opts(1e-9, m->adaptive ? 0.0 : PERIOD / 2000);
    double y[4], T = PERIOD / 4;
    ap_step_stats st;
    kepler k = {.fail_at = 40, .fail_code = 1};
    AP_CHECK_EQ_INT(run(m, o, &k, 1, &T, y, &st), AP_OK);
    AP_CHECK_EQ_INT(st.rhs_fails, 1);
    AP_CHECK_LE(err_at(T, y), 1e-6);

    kepler kn = {.fail_at = 40, .fail_code = -7};
    AP_CHECK_EQ_INT(run(m, o, &kn, 1, &T, y, NULL), AP_ERR_CALLBACK);
    kepler kq = {.nan_from = 40};
    int rc = run(m, o, &kq, 1, &T, y, NULL);
    AP_CHECK(rc < 0);
    AP_CHECK_EQ_INT(rc, AP_ERR_NAN);
    kepler k1 = {.nan_at = 40};                  /* NaN once behaves like f > 0 once */
    AP_CHECK_EQ_INT(run(m, o, &k1, 1, &T, y, &st), AP_OK);
    AP_CHECK_EQ_INT(st.rhs_fails, 1);
    AP_CHECK_LE(err_at(T, y), 1e-6);
  }
}

/* The state after a failed step is the last accepted one, and the message says what failed. */
static void check_failed_state(const char *name, const char *flag) {
  const ap_step_method *m = ap_step_method_find(name);
  ap_step_opts o = opts(1e-9, 0.0);
  kepler k = {0};
  ap_stepper *s = NULL;
  double y[4], yl[4], t = 0.0, tl = 0.0;
  kepler_exact(0.0, y);
  AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, y, &o, &s, NULL, 0), AP_OK);
  for (int j = 0; j < 5; j++) ap_step_one(s, PERIOD, &t, y);
  tl = t, memcpy(yl, y, sizeof y);
  k.fail_at = k.calls + 3, k.fail_code = -2;
  AP_CHECK_EQ_INT(ap_step_one(s, PERIOD, &t, y), AP_ERR_CALLBACK);
  AP_CHECK(t == tl && memcmp(y, yl, sizeof y) == 0);
  AP_CHECK(strstr(ap_step_message(s), name) != NULL);
  AP_CHECK(strstr(ap_step_message(s), flag) != NULL);
  printf("message after f < 0: %s\n", ap_step_message(s));
  AP_CHECK_EQ_INT(ap_step_one(s, PERIOD, &t, y), AP_OK);   /* and it can go on */
  AP_CHECK(t > tl);
  AP_CHECK_EQ_INT(ap_step_one(s, t, &t, y), AP_ERR_ARG);    /* tstop not ahead */
  ap_step_free(s);
}

static void check_args(void) {
  kepler k = {0};
  double y[4];
  ap_stepper *s = NULL;
  char msg[256];
  ap_step_opts o = opts(1e-6, 0.0), of = opts(1e-6, 0.01);
  kepler_exact(0.0, y);
  AP_CHECK(ap_step_method_find("nope") == NULL);
  AP_CHECK(ap_step_method_find("verner6") != NULL);
  AP_CHECK_EQ_INT(ap_step_create(ap_step_method_find("rk4"), 4, kepler_rhs, &k, 0.0, y, &o, &s,
                                 msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(s == NULL);
  AP_CHECK_EQ_INT(ap_step_create(ap_step_method_find("adams"), 4, kepler_rhs, &k, 0.0, y, &of,
                                 &s, msg, sizeof msg), AP_ERR_UNSUPPORTED);
  y[1] = NAN;
  AP_CHECK_EQ_INT(ap_step_create(ap_step_method_find("dopri5"), 4, kepler_rhs, &k, 0.0, y, &o,
                                 &s, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(ap_step_butcher(ap_step_method_find("bdf"), MAXS, NULL, NULL, NULL, NULL, NULL,
                           NULL) == AP_ERR_UNSUPPORTED);
  /* max_steps: at most 5 steps while heading for one tstop */
  ap_step_opts o5 = opts(0.0, 0.01);
  double t = 0.0;
  int rc = AP_OK, taken = 0;
  o5.max_steps = 5;
  kepler_exact(0.0, y);
  AP_CHECK_EQ_INT(ap_step_create(ap_step_method_find("rk4"), 4, kepler_rhs, &k, 0.0, y, &o5, &s,
                                 msg, sizeof msg), AP_OK);
  while (s && rc == AP_OK && t < 1.0)
    if ((rc = ap_step_one(s, 1.0, &t, y)) == AP_OK) taken++;
  AP_CHECK_EQ_INT(rc, AP_ERR_SOLVER);
  AP_CHECK_EQ_INT(taken, 5);
  AP_CHECK(s && strstr(ap_step_message(s), "max_steps") != NULL);
  AP_CHECK_EQ_INT(s ? ap_step_one(s, 0.06, &t, y) : -1, AP_OK);   /* a new tstop: counts anew */
  ap_step_free(s);
}

int main(void) {
  check_tables();
  check_dop853_tables();
  check_fixed_orders();
  report_dop853_slopes();
  check_dense_order();
  check_cvode_sweep();
  report_raw_erkstep();
  check_adaptive();
  check_fixed_counts();
  check_reset();
  check_restart();
  check_dky();
  check_failures();
  check_failed_state("dopri5", "ARK_RHSFUNC_FAIL");
  check_failed_state("dop853", "returned -2");
  check_args();
  return ap_check_finish("steppers");
}
