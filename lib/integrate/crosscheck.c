/* The cross-check: one model, three modes (minimal, projected, DAE), the same tolerances;
 * the largest differences in coordinates, speeds and multipliers at common output times.
 * Minimal mode is the reference the other two are compared with. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "appell/sim.h"
#include "core/core.h"
#include "core/text.h"

static const char *mode_name[3] = {"minimal", "projected", "DAE"};

static double max_diff(const double *a, const double *b, int len) {
  double mx = 0.0;
  for (int i = 0; i < len; i++) mx = fmax(mx, fabs(a[i] - b[i]));
  return mx;
}

static double max_abs(const double *a, int len) {
  double mx = 0.0;
  for (int i = 0; i < len; i++) mx = fmax(mx, fabs(a[i]));
  return mx;
}

/* Compare the three simulations at their common current time. */
static int compare(ap_sim *sim[3], const ap_model *m, ap_crosscheck_report *r) {
  const double *lam[3] = {NULL, NULL, NULL};
  for (int i = 0; i < 3 && m->b > 0; i++) {
    int rc = ap_sim_reactions(sim[i], &lam[i]);
    if (rc != AP_OK) return rc;
  }
  const double *q0 = ap_sim_q(sim[0]), *v0 = ap_sim_v(sim[0]);
  r->dq_projected = fmax(r->dq_projected, max_diff(q0, ap_sim_q(sim[1]), m->n));
  r->dq_dae = fmax(r->dq_dae, max_diff(q0, ap_sim_q(sim[2]), m->n));
  r->dv_projected = fmax(r->dv_projected, max_diff(v0, ap_sim_v(sim[1]), m->k));
  r->dv_dae = fmax(r->dv_dae, max_diff(v0, ap_sim_v(sim[2]), m->k));
  r->max_q = fmax(r->max_q, max_abs(q0, m->n));
  r->max_v = fmax(r->max_v, max_abs(v0, m->k));
  if (m->b > 0) {
    r->dlambda_projected = fmax(r->dlambda_projected, max_diff(lam[0], lam[1], m->b));
    r->dlambda_dae = fmax(r->dlambda_dae, max_diff(lam[0], lam[2], m->b));
    r->max_lambda = fmax(r->max_lambda, max_abs(lam[0], m->b));
  }
  return AP_OK;
}

int ap_crosscheck(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                  const double *v0, double t_end, int n_out, ap_crosscheck_report *rep,
                  char *msg, size_t msg_len) {
  if (!m || !def || !q0 || !v0 || !rep || n_out < 1 || !(t_end > t0) || !isfinite(t_end)) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_crosscheck: bad arguments");
    return AP_ERR_ARG;
  }
  memset(rep, 0, sizeof *rep);
  ap_sim *sim[3] = {NULL, NULL, NULL};
  int rc = AP_OK, failed = -1;
  for (int i = 0; i < 3 && rc == AP_OK; i++) {
    ap_sim_def d = *def;
    d.mode = (ap_mode)i;
    rc = ap_sim_create(m, &d, t0, q0, v0, &sim[i], msg, msg_len);
    if (rc != AP_OK) failed = i;
  }
  rep->t_fail = t_end;
  for (int j = 1; j <= n_out && rc == AP_OK; j++) {
    double t = t0 + (t_end - t0) * j / n_out;
    for (int i = 0; i < 3 && rc == AP_OK; i++) {
      rc = ap_sim_advance(sim[i], t);
      if (rc != AP_OK) failed = i, rep->t_fail = ap_sim_time(sim[i]);
    }
    if (rc == AP_OK) rc = compare(sim, m, rep);
  }
  if (rc != AP_OK && failed >= 0 && sim[failed] && msg && msg_len)
    snprintf(msg, msg_len, "%s mode: %s", mode_name[failed], ap_sim_message(sim[failed]));
  else if (rc != AP_OK && failed >= 0 && msg && msg_len) {
    char prefix[32];   /* the message of ap_sim_create, kept whole as far as msg_len allows */
    snprintf(prefix, sizeof prefix, "%s mode: ", mode_name[failed]);
    ap_core_prefix(msg, msg_len, prefix);
  }
  for (int i = 0; i < 3; i++) {
    if (sim[i]) {
      ap_sim_get_stats(sim[i], &rep->stats[i]);
      rep->residual[i] = rep->stats[i].max_residual;
    }
    ap_sim_free(sim[i]);
  }
  return rc;
}
