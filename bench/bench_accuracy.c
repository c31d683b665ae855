/* bench_accuracy: what accuracy on demand costs (docs/accuracy.md).
 *
 * 1. The picker against the best hand-picked setting. On bench_wp's six problems (wp.h: five
 *    closed forms and the body-built rolling disk against its hand ODE at 1e-14) and each
 *    requested accuracy 1e-4, 1e-6, 1e-8, 1e-10 (in ap_error_norm's units: the position error
 *    relative to max(1 m, the largest |position|)): the best hand-picked setting is the one of
 *    {bs3, dopri5, verner6, fehlberg8, dop853} x rtol = atol = 10^(-j/4), j = 8 ... 52 (1e-2
 *    ... 1e-13), with the fewest evaluations whose true error (against the exact positions)
 *    reaches the accuracy; the picker's choice (ap_accuracy_pick) is run the same way. Printed:
 *    both settings, their evaluations and true errors, the ratio picked / best of the run
 *    alone, and of the run plus the choice (pilot and checks).
 * 2. Error control where it matters: the body-built ball on a turntable (tests/bodysys.c),
 *    steady table, 16 s, 10 outputs, dopri5 and dop853 at rtol = atol 1e-6, 1e-8, 1e-10:
 *    steps and centre error against the closed form, with every coordinate controlled and
 *    with the free ones (the orientation) left out, next to the hand model (refsys).
 * Evaluations and steps do not depend on the machine's load.
 * Usage: bench_accuracy [--csv FILE]. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "bodysys.h"
#include "wp.h"

static int out_pos(ap_sim *s, double *row, void *user) {
  const wp_problem *pr = user;
  pr->pos_q(pr, ap_sim_time(s), ap_sim_q(s), row);
  return AP_OK;
}

/* Evaluations of a run with def (through the NOUT output times) and its true error; -1 when
 * it failed. */
static long run_true(const ap_model *m, wp_problem *pr, const ap_sim_def *def, double *err) {
  ap_sim *s = NULL;
  if (ap_sim_create(m, def, 0.0, pr->q0, pr->v0, &s, NULL, 0) != AP_OK) return -1;
  double e[3] = {0}, sc[3] = {0}, pos[3];
  long evals = -1;
  for (int i = 0; i < NOUT; i++) {
    if (ap_sim_advance(s, pr->T * (i + 1) / NOUT) != AP_OK) goto done;
    pr->pos_q(pr, ap_sim_time(s), ap_sim_q(s), pos);
    ap_error_fold(pr->npos, pos, pr->epos[i], e, sc);
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  evals = st.rhs_evals;
  *err = ap_error_norm(pr->npos, e, sc);
done:
  ap_sim_free(s);
  return evals;
}

static const char *const methods[5] = {"bs3", "dopri5", "verner6", "fehlberg8", "dop853"};

/* The cheapest hand-picked setting reaching acc: *best evaluations, method, rtol, error. */
static long best_hand(const ap_model *m, wp_problem *pr, double acc, const char **meth,
                      double *rtol, double *err) {
  long best = -1;
  for (int k = 0; k < 5; k++)
    for (int j = 8; j <= 52; j++) {
      ap_sim_def def = ap_sim_def_default();
      def.method = methods[k], def.rtol = def.atol = pow(10.0, -j / 4.0);
      def.max_steps = WP_MAX_STEPS;
      double e = 0.0;
      long ev = run_true(m, pr, &def, &e);
      if (ev < 0 || !(e <= acc)) continue;
      if (best < 0 || ev < best) best = ev, *meth = methods[k], *rtol = def.rtol, *err = e;
      break;   /* tighter rtol of this method only costs more */
    }
  return best;
}

static void picker(FILE *csv) {
  static wp_problem P[NPROB];
  setup_problems(P);
  static const double accs[4] = {1e-4, 1e-6, 1e-8, 1e-10};
  double worst = 0.0, worst_all = 0.0;
  int missed = 0;
  printf("%-14s %-7s | %-22s %7s %9s | %-22s %7s %9s %7s | %6s %8s\n", "problem", "accuracy",
         "best hand-picked", "evals", "error", "picked", "evals", "error", "choice", "ratio",
         "w/choice");
  if (csv) fprintf(csv, "problem,accuracy,best_method,best_rtol,best_evals,best_error,"
                        "pick_method,pick_rtol,pick_evals,pick_error,choice_evals,ratio,"
                        "ratio_with_choice\n");
  for (int i = 0; i < NPROB; i++) {
    wp_problem *pr = &P[i];
    ap_model *own = NULL;
    const ap_model *m = pr->body_model;
    if (!m && ap_model_from_system(&pr->def, &own, NULL, 0) != AP_OK) continue;
    if (!m) m = own;
    double t[NOUT];
    for (int j = 0; j < NOUT; j++) t[j] = pr->T * (j + 1) / NOUT;
    for (int a = 0; a < 4; a++) {
      const char *bm = "-";
      double br = 0, be = 0, pe = 0;
      long best = best_hand(m, pr, accs[a], &bm, &br, &be);
      ap_sim_def def = ap_sim_def_default();
      def.max_steps = WP_MAX_STEPS;
      ap_pick_report pk;
      char msg[512];
      int rc = ap_accuracy_pick(m, &def, 0.0, pr->q0, pr->v0, t, NOUT, pr->npos, out_pos, NULL,
                                pr, accs[a], &pk, msg, sizeof msg);
      long pev = rc == AP_OK ? run_true(m, pr, &pk.def, &pe) : -1;
      long choice = pk.pilot_evals + pk.verify_evals;
      double ratio = best > 0 && pev > 0 ? (double)pev / best : NAN;
      double ratio_all = best > 0 && pev > 0 ? (double)(pev + choice) / best : NAN;
      if (rc != AP_OK || !(pe <= accs[a])) missed++;
      worst = fmax(worst, ratio), worst_all = fmax(worst_all, ratio_all);
      printf("%-14s %-7.0e | %-9s rtol %-8.2g %7ld %9.2e | %-9s rtol %-8.2g %7ld %9.2e %7ld | "
             "%6.2f %8.2f%s\n", pr->name, accs[a], bm, br, best, be,
             rc == AP_OK ? pk.def.method : "failed", rc == AP_OK ? pk.def.rtol : 0.0, pev, pe,
             choice, ratio, ratio_all, rc == AP_OK && pe <= accs[a] ? "" : "  MISSED");
      if (csv) fprintf(csv, "%s,%g,%s,%g,%ld,%g,%s,%g,%ld,%g,%ld,%g,%g\n", pr->name, accs[a],
                       bm, br, best, be, rc == AP_OK ? pk.def.method : "failed",
                       rc == AP_OK ? pk.def.rtol : 0.0, pev, pe, choice, ratio, ratio_all);
    }
    ap_model_free(own);
  }
  free_problems(P);
  printf("picker: worst ratio of evaluations picked / best hand-picked %.2f (with the choice's "
         "pilot and checks %.2f); accuracy missed in %d of %d cases\n\n", worst, worst_all,
         missed, NPROB * 4);
}

static void free_coordinates(void) {
  static rs_turntable tp = {1.0, 0.1, 0.4, 2.0, 0.0};
  ap_system_def hd;
  rs_turntable_system(&tp, &hd);
  ap_model *m = bs_turntable_model(&tp), *h = NULL;
  if (!m || ap_model_from_system(&hd, &h, NULL, 0) != AP_OK) return;
  double qh[5], vh[5];
  rs_turntable_initial(&tp, 0.3, -0.1, 1.0, -2.0, 3.0, qh, vh);
  double qb[6] = {qh[0], qh[1], 1, 0, 0, 0};
  printf("ball on a turntable (16 s, 10 outputs): steps and centre error (m)\n");
  printf("%-7s %-6s | %-18s | %-18s | %-18s\n", "method", "rtol", "hand model", "body, all "
         "controlled", "body, orientation free");
  static const char *const ms[2] = {"dopri5", "dop853"};
  for (int k = 0; k < 2; k++)
    for (double r = 1e-6; r > 1e-11; r *= 1e-2) {
      double eh, e0, e1;
      long nh = bs_turntable_run(h, &tp, qh, vh, qh, vh, ms[k], r, 0, NULL, &eh);
      long n0 = bs_turntable_run(m, &tp, qb, vh, qh, vh, ms[k], r, 0, NULL, &e0);
      long n1 = bs_turntable_run(m, &tp, qb, vh, qh, vh, ms[k], r, 1, NULL, &e1);
      printf("%-7s %-6.0e | %5ld  %10.2e  | %5ld  %10.2e  | %5ld  %10.2e\n", ms[k], r, nh, eh, n0,
             e0, n1, e1);
    }
  ap_model_free(m);
  ap_model_free(h);
}

int main(int argc, char **argv) {
  const char *csv = NULL;
  for (int i = 1; i < argc; i++)
    if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) csv = argv[++i];
    else return fprintf(stderr, "usage: bench_accuracy [--csv FILE]\n"), 2;
  FILE *f = csv ? fopen(csv, "w") : NULL;
  if (csv && !f) return fprintf(stderr, "bench_accuracy: cannot write %s\n", csv), 1;
  picker(f);
  if (f) fclose(f);
  free_coordinates();
  return 0;
}
