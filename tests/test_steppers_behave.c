/* Steppers (lib/integrate/stepper*.c), behaviour, on the Kepler problem of kepler.h (e = 0.5;
 * after one period T = 2 pi the state returns to y0); the orders are tested in
 * test_steppers.c.
 *
 * 3. Adaptive accuracy (error < 1e-8 after one period at rtol 1e-10; verner6, adams and bdf
 *    need rtol 1e-11, see docs/steppers.md), evaluations per step, reset-and-continue, dense
 *    output, failing right-hand sides (> 0 once, < 0, NaN), max_steps, argument checks. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "check.h"
#include "kepler.h"

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
    ap_step_opts o = kepler_opts(0.0, PERIOD / n);
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
    ap_step_opts o = kepler_opts(1e-10, fixed ? PERIOD / 256 : 0.0);
    double ya[4], yb[4], t = 0.0, tb = 0.0, ts[2] = {PERIOD / 2, PERIOD};
    kepler k = {0};
    ap_stepper *s = NULL;
    AP_CHECK_EQ_INT(kepler_run(m, o, &k, 2, ts, ya, NULL), AP_OK);
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
    AP_CHECK_EQ_INT(kepler_run(m, kepler_opts(1e-9, 0.0), &k, 2, ts, ya, &sa), AP_OK);
    ap_stepper *s = NULL, *r = NULL;
    kepler_exact(0.0, yb), kepler_exact(0.0, yc);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, yb, &(ap_step_opts){1e-9, 1e-11,
                    0, 0, 0, 10000000L, NULL, NULL}, &s, NULL, 0), AP_OK);
    AP_CHECK_EQ_INT(ap_step_create(m, 4, kepler_rhs, &k, 0.0, yc, &(ap_step_opts){1e-9, 1e-11,
                    0, 0, 0, 10000000L, NULL, NULL}, &r, NULL, 0), AP_OK);
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
    ap_step_opts o = kepler_opts(1e-10, m->adaptive ? 0.0 : PERIOD / 1000);
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
    ap_step_opts o = kepler_opts(1e-9, m->adaptive ? 0.0 : PERIOD / 2000);
    double y[4], T = PERIOD / 4;
    ap_step_stats st;
    kepler k = {.fail_at = 40, .fail_code = 1};
    AP_CHECK_EQ_INT(kepler_run(m, o, &k, 1, &T, y, &st), AP_OK);
    AP_CHECK_EQ_INT(st.rhs_fails, 1);
    AP_CHECK_LE(err_at(T, y), 1e-6);

    kepler kn = {.fail_at = 40, .fail_code = -7};
    AP_CHECK_EQ_INT(kepler_run(m, o, &kn, 1, &T, y, NULL), AP_ERR_CALLBACK);
    kepler kq = {.nan_from = 40};
    int rc = kepler_run(m, o, &kq, 1, &T, y, NULL);
    AP_CHECK(rc < 0);
    AP_CHECK_EQ_INT(rc, AP_ERR_NAN);
    kepler k1 = {.nan_at = 40};                  /* NaN once behaves like f > 0 once */
    AP_CHECK_EQ_INT(kepler_run(m, o, &k1, 1, &T, y, &st), AP_OK);
    AP_CHECK_EQ_INT(st.rhs_fails, 1);
    AP_CHECK_LE(err_at(T, y), 1e-6);
  }
}

/* The state after a failed step is the last accepted one, and the message says what failed. */
static void check_failed_state(const char *name, const char *flag) {
  const ap_step_method *m = ap_step_method_find(name);
  ap_step_opts o = kepler_opts(1e-9, 0.0);
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
  ap_step_opts o = kepler_opts(1e-6, 0.0), of = kepler_opts(1e-6, 0.01);
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
  ap_step_opts o5 = kepler_opts(0.0, 0.01);
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
  check_adaptive();
  check_fixed_counts();
  check_reset();
  check_restart();
  check_dky();
  check_failures();
  check_failed_state("dopri5", "ARK_RHSFUNC_FAIL");
  check_failed_state("dop853", "returned -2");
  check_args();
  return ap_check_finish("steppers_behave");
}
