/* dae_accuracy: global error per requested tolerance, the DAE mode (IDA) against the Appell
 * modes' steppers, on the body models of tests/test_dae_tight.c (docs/architecture.md, "The
 * DAE mode", and docs/steppers.md). Not a timing: the number printed for each method and rtol
 * is max |x - xref| / (rtol |x|max + atol) over q and v at 20 outputs (atol = rtol / 100),
 * with the reference from minimal mode, verner6, rtol 1e-13, atol 1e-15, and the steps taken.
 *
 * Rows: minimal dopri5, minimal verner6, minimal bdf (CVODE, the same BDF family as IDA on the
 * ODE of the Appell solve), and DAE. IDA runs at rtol / AP_DAE_TOL_FACTOR (not below 1e-12),
 * so the DAE requested at 10 rtol (atol rtol / 10) is IDA itself at rtol, atol rtol / 100: its
 * ratio relative to rtol is printed as "IDA at rtol" (the ratio of BDF's global error to the
 * local tolerance IDA controls).
 *
 * Usage: dae_accuracy. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bodysys.h"

#define NOUT 20
#define MAXN 8
#define NTOL 7

typedef struct problem {
  const char *name;
  ap_model *m;
  double q0[MAXN], v0[MAXN], t_end;
  double Q[NOUT * MAXN], V[NOUT * MAXN], qm, vm;
} problem;

/* err / tol of one run (or -1 when it failed), its steps. */
static double run(problem *p, ap_mode mode, const char *method, double rtol, double atol,
                  double norm_rtol, long *steps) {
  int n = ap_model_n(p->m), k = ap_model_k(p->m), rc = AP_OK;
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.method = method, sd.rtol = rtol, sd.atol = atol;
  ap_sim *s = NULL;
  char msg[512] = "";
  double eq = 0.0, ev = 0.0;
  rc = ap_sim_create(p->m, &sd, 0.0, p->q0, p->v0, &s, msg, sizeof msg);
  for (int i = 1; rc == AP_OK && i <= NOUT; i++) {
    rc = ap_sim_advance(s, p->t_end * i / NOUT);
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    for (int c = 0; c < n && norm_rtol > 0; c++)
      eq = fmax(eq, fabs(q[c] - p->Q[(size_t)(i - 1) * n + c]));
    for (int c = 0; c < k && norm_rtol > 0; c++)
      ev = fmax(ev, fabs(v[c] - p->V[(size_t)(i - 1) * k + c]));
    if (norm_rtol <= 0) {   /* the reference */
      memcpy(p->Q + (size_t)(i - 1) * n, q, sizeof(double) * (size_t)n);
      memcpy(p->V + (size_t)(i - 1) * k, v, sizeof(double) * (size_t)k);
    }
  }
  ap_sim_stats st;
  *steps = 0;
  if (s) ap_sim_get_stats(s, &st), *steps = st.steps;
  if (rc != AP_OK) fprintf(stderr, "%s %s rtol %g: %s\n", p->name, method, rtol,
                           s ? ap_sim_message(s) : msg);
  ap_sim_free(s);
  if (rc != AP_OK) return -1.0;
  double na = norm_rtol / 100;
  return fmax(eq / (norm_rtol * p->qm + na), ev / (norm_rtol * p->vm + na));
}

static void table(problem *p) {
  int n = ap_model_n(p->m), k = ap_model_k(p->m);
  long steps = 0;
  run(p, AP_MODE_MINIMAL, "verner6", 1e-13, 1e-15, 0.0, &steps);
  p->qm = p->vm = 0.0;
  for (int i = 0; i < NOUT * n; i++) p->qm = fmax(p->qm, fabs(p->Q[i]));
  for (int i = 0; i < NOUT * k; i++) p->vm = fmax(p->vm, fabs(p->V[i]));
  printf("\n%s, %.1f s (reference: %ld steps)\n%-18s", p->name, p->t_end, steps, "rtol");
  for (int j = 0; j < NTOL; j++) printf(" %14.0e", pow(10.0, -6 - j));
  printf("\n");
  const char *label[5] = {"minimal dopri5", "minimal verner6", "minimal bdf", "DAE",
                          "IDA at rtol"};
  for (int r = 0; r < 5; r++) {
    printf("%-18s", label[r]);
    for (int j = 0; j < NTOL; j++) {
      double rtol = pow(10.0, -6 - j), x;
      if (r < 3)
        x = run(p, AP_MODE_MINIMAL, r == 0 ? "dopri5" : r == 1 ? "verner6" : "bdf", rtol,
                rtol / 100, rtol, &steps);
      else   /* DAE requested at rtol, or at 10 rtol (IDA itself at rtol) */
        x = run(p, AP_MODE_DAE, "dopri5", r == 3 ? rtol : 10 * rtol, r == 3 ? rtol / 100 :
                rtol / 10, rtol, &steps);
      if (x < 0) printf(" %14s", "failed");
      else printf(" %7.2f %6ld", x, steps);
    }
    printf("\n");
  }
}

int main(void) {
  static const double t_end[BS_DAE_CASES] = {10.0, 2.0, 10.0, 10.0, 10.0, 5.0};
  problem p[BS_DAE_CASES];
  memset(p, 0, sizeof p);
  bs_case c[BS_DAE_CASES];
  bs_dae_cases(c);
  for (int i = 0; i < BS_DAE_CASES; i++) {
    p[i].name = c[i].name, p[i].m = c[i].m, p[i].t_end = t_end[i];
    memcpy(p[i].q0, c[i].q0, sizeof p[i].q0), memcpy(p[i].v0, c[i].v0, sizeof p[i].v0);
  }
  printf("max |x - xref| / (rtol |x|max + atol) over q and v, and steps, per requested rtol\n");
  for (int i = 0; i < BS_DAE_CASES; i++) {
    if (p[i].m) table(&p[i]);
    ap_model_free(p[i].m);
  }
  return bs_failures() ? 1 : 0;
}
