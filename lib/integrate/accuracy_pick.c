/* Accuracy on demand: the method and tolerance that reach a requested global error on the
 * outputs at the fewest evaluations (include/appell/accuracy.h, docs/accuracy.md).
 *
 * Model: an error-controlled explicit pair keeps its global error nearly proportional to its
 * tolerance, err(rtol) = C rtol (docs/steppers.md "Accuracy": C stays within a factor 10 from
 * rtol 1e-6 to 1e-12 for dopri5 and dop853), and its evaluations grow like rtol^(-1/p) for a
 * method of order p. The pilot measures C per candidate at one loose tolerance
 * rtol_a = min(1e-3, 1e4 x accuracy), its error estimated against the reference at rtol_a / 100
 * (global_error.c), and the evaluations of both runs give the cost curve (its slope in
 * log-log, but no flatter than 1/p: at loose tolerances the stops at the output times
 * flatten it). The choice is the candidate whose rtol = accuracy / (SAFETY C) costs least.
 * SAFETY = 3 covers C growing as the tolerance tightens (dop853: 1.1 at 1e-6, 5.8 at 1e-12);
 * for an 8th-order method it costs 3^(1/8) = 15 % more evaluations. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "appell/accuracy.h"
#include "appell/status.h"

#define SAFETY 3.0
#define RTOL_MIN 1e-13
#define VERIFY_MARGIN 1.5
#define VERIFY_TRIES 6

static const struct {
  const char *name;
  int order;
  double loosest;          /* accuracies below this skip the candidate (its cost is hopeless) */
} cands[] = {{"dop853", 8, 0.0}, {"dopri5", 5, 1e-6}, {"bs3", 3, 1e-4}};

/* Evaluations at rtol from the two pilot points (rtol_a, ea) and (rtol_b < rtol_a, eb). */
static double cost_at(double rtol, double rtol_a, double ea, double rtol_b, double eb,
                      int order) {
  double slope = log(fmax(eb, 1.0) / fmax(ea, 1.0)) / log(rtol_a / rtol_b);
  if (!(slope >= 1.0 / order)) slope = 1.0 / order;
  double r_ref = rtol <= rtol_b ? rtol_b : rtol_a, e_ref = r_ref < rtol_a ? eb : ea;
  return e_ref * pow(r_ref / rtol, slope);
}

static int pilot(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                 const double *v0, const double *times, int nt, int nc, ap_output_fn out,
                 ap_sim_setup_fn setup, void *user, int c, double accuracy, ap_pick_report *p,
                 char *msg, size_t msg_len) {
  ap_sim_def d = *def;
  d.method = cands[c].name;
  d.rtol = d.atol = fmin(1e-3, 1e4 * accuracy);
  ap_error_report rep;
  int rc = ap_global_error(m, &d, t0, q0, v0, times, nt, nc, out, setup, user, NULL, NULL,
                           NULL, &rep, msg, msg_len);
  p->pilot_evals += rep.run.rhs_evals + rep.ref_stats.rhs_evals;
  if (rc != AP_OK) return rc;
  int i = p->ncand++;
  double C = fmax(rep.error, 1e-300) / d.rtol;
  double r = fmin(accuracy / (SAFETY * C), 1e-2);
  p->cand[i].method = cands[c].name, p->cand[i].rtol = d.rtol, p->cand[i].error = rep.error;
  p->cand[i].rtol_pick = r;
  p->cand[i].evals = r < RTOL_MIN ? INFINITY
                     : cost_at(r, d.rtol, (double)rep.run.rhs_evals, rep.ref.rtol,
                               (double)rep.ref_last.rhs_evals, cands[c].order);
  return AP_OK;
}

/* The choice checked by its own error estimate (global_error.c, within a factor 1.2 of the
 * true error on the reference problems): while the estimate exceeds accuracy / VERIFY_MARGIN,
 * rtol shrinks by accuracy / (SAFETY x estimate) (at least 5x), at most VERIFY_TRIES times.
 * The pilot's error model misses where the error per unit rtol grows as rtol tightens (the
 * knife edge's partition switches: 1.8 at 1e-3, 8 from 1e-4 on). */
static int verify(const ap_model *m, double t0, const double *q0, const double *v0,
                  const double *times, int nt, int nc, ap_output_fn out, ap_sim_setup_fn setup,
                  void *user, ap_pick_report *p, char *msg, size_t msg_len) {
  for (int i = 0; i < VERIFY_TRIES; i++) {
    ap_error_report rep;
    int rc = ap_global_error(m, &p->def, t0, q0, v0, times, nt, nc, out, setup, user, NULL,
                             NULL, NULL, &rep, msg, msg_len);
    p->verify_evals += rep.run.rhs_evals + rep.ref_stats.rhs_evals;
    if (rc != AP_OK) return rc;
    p->estimated_error = rep.error, p->evals = rep.run.rhs_evals, p->tries = i + 1;
    if (rep.error <= p->accuracy / VERIFY_MARGIN) return AP_OK;
    double r = p->def.rtol * fmin(0.2, p->accuracy / (SAFETY * rep.error));
    if (r < RTOL_MIN) break;
    p->def.rtol = p->def.atol = r;
  }
  if (msg && msg_len) snprintf(msg, msg_len, "ap_accuracy_pick: %s at rtol %.3g still has an "
                               "estimated error of %.3g, above the requested %.3g",
                               p->def.method, p->def.rtol, p->estimated_error, p->accuracy);
  return AP_ERR_SOLVER;
}

int ap_accuracy_pick(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                     const double *v0, const double *times, int nt, int nc, ap_output_fn out,
                     ap_sim_setup_fn setup, void *user, double accuracy, ap_pick_report *pick,
                     char *msg, size_t msg_len) {
  if (!m || !def || !q0 || !v0 || !times || !out || !pick || nt < 1 || nc < 1 ||
      !(accuracy >= 1e-12 && accuracy < 1.0)) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_accuracy_pick: NULL argument, no output "
                                 "channel, or accuracy %g outside [1e-12, 1)", accuracy);
    return AP_ERR_ARG;
  }
  memset(pick, 0, sizeof *pick);
  pick->accuracy = accuracy;
  ap_sim_def base = *def;
  if (base.mode == AP_MODE_DAE || base.mode == AP_MODE_PLAIN) base.mode = AP_MODE_MINIMAL;
  int rc = AP_OK, best = -1;
  for (int c = 0; c < (int)(sizeof cands / sizeof cands[0]); c++) {
    if (accuracy < cands[c].loosest) continue;
    int r = pilot(m, &base, t0, q0, v0, times, nt, nc, out, setup, user, c, accuracy, pick, msg,
                  msg_len);
    if (r != AP_OK) rc = r;
  }
  for (int i = 0; i < pick->ncand; i++)
    if (best < 0 || pick->cand[i].evals < pick->cand[best].evals) best = i;
  if (best < 0) return rc != AP_OK ? rc : AP_ERR_SOLVER;
  if (!isfinite(pick->cand[best].evals)) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_accuracy_pick: no method reaches %g: the "
                                 "tolerance it needs is below %g", accuracy, RTOL_MIN);
    return AP_ERR_SOLVER;
  }
  pick->def = base;
  pick->def.method = pick->cand[best].method;
  pick->def.rtol = pick->def.atol = pick->cand[best].rtol_pick;
  pick->predicted_error = accuracy / SAFETY;
  pick->predicted_evals = pick->cand[best].evals;
  rc = verify(m, t0, q0, v0, times, nt, nc, out, setup, user, pick, msg, msg_len);
  if (rc == AP_OK && msg && msg_len) msg[0] = '\0';
  return rc;
}
