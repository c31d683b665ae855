/* Steppers (lib/integrate/stepper*.c), orders: every method is checked on the order it claims,
 * on the Kepler problem of kepler.h (e = 0.5; after one period T = 2 pi the state returns to
 * y0). The behaviour (accuracy, counts, restarts, failures, arguments) is tested in
 * test_steppers_behave.c.
 *
 * 1. Order conditions: for every Runge-Kutta method, the Butcher table the stepper really
 *    hands to ARKODE (ap_step_butcher) satisfies c_i = sum_j A_ij and the rooted-tree
 *    conditions b . Phi(t) = 1 / gamma(t) for all trees of order <= p, and fails order p + 1.
 * 2. Observed order: fixed steps h = (T/2) / N from pericentre to apocentre, least-squares
 *    slope of log(err) against log(h) over a factor 4 in h, within 0.3 of the claimed order
 *    (ERK methods; step ranges where the error is asymptotic and far above round-off). CVODE
 *    has no fixed step: a tolerance sweep must make the error fall monotonically.
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
#include "kepler.h"

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
  ap_step_opts o = kepler_opts(0.0, h);
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

int main(void) {
  check_tables();
  check_dop853_tables();
  check_fixed_orders();
  report_dop853_slopes();
  check_dense_order();
  check_cvode_sweep();
  report_raw_erkstep();
  return ap_check_finish("steppers");
}
