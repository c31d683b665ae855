/* The global error of a run on its output channels, estimated a posteriori
 * (include/appell/accuracy.h, docs/accuracy.md).
 *
 * Method: a second integration of the same model from the same state through the same output
 * times, at rtol / 100 with dop853 (ap_error_reference_def). Its global error is about 100
 * times smaller than the run's for a method whose error is proportional to its tolerance
 * (docs/steppers.md "Accuracy": within a factor 10 of rtol for the explicit pairs of order 5
 * and more), so |x_run - x_ref| estimates the run's error within about 1 %, plus the
 * reference's own departure from proportionality. The cost is the reference run: for dop853
 * about 100^(1/8) = 1.8 times the run's evaluations at the same method, more for lower-order
 * runs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/accuracy.h"
#include "appell/status.h"

void ap_error_reference_def(const ap_sim_def *def, ap_sim_def *ref) {
  *ref = *def;
  ap_method_info info;
  int known = ap_method_find(def->method, &info) == AP_OK;
  int stiff = def->mode != AP_MODE_DAE && def->method &&
              (strcmp(def->method, "bdf") == 0 || strcmp(def->method, "adams") == 0);
  ref->mode = def->mode == AP_MODE_PROJECTED ? AP_MODE_PROJECTED : AP_MODE_MINIMAL;
  ref->method = stiff ? "bdf" : "dop853";
  if (known && !info.adaptive && def->mode != AP_MODE_DAE) {
    ref->rtol = 1e-12, ref->atol = 1e-14;
    return;
  }
  ref->rtol = fmax(def->rtol / 100.0, 1e-14);
  ref->atol = fmax(def->atol / 100.0, 1e-16);
  if (stiff) ref->rtol = fmax(ref->rtol, 1e-8), ref->atol = fmax(ref->atol, 1e-10);
}

void ap_error_fold(int nc, const double *row, const double *ref, double *err, double *scale) {
  for (int c = 0; c < nc; c++) {
    double e = fabs(row[c] - ref[c]);
    if (err && (e > err[c] || isnan(e))) err[c] = e;
    if (scale && fabs(ref[c]) > scale[c]) scale[c] = fabs(ref[c]);
  }
}

double ap_error_norm(int nc, const double *err, const double *scale) {
  double e = 0.0;
  for (int c = 0; c < nc; c++) {
    double x = err[c] / fmax(1.0, scale ? scale[c] : 0.0);
    if (x > e || isnan(x)) e = x;
  }
  return e;
}

static int say(char *msg, size_t len, int rc, const char *what, double t, const char *why) {
  if (msg && len) snprintf(msg, len, "the %s failed at t = %.10g: %s", what, t, why);
  return rc;
}

/* Run def through times, the outputs into rows (nt x nc); stats into *st. */
static int run_rows(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                    const double *v0, const double *times, int nt, int nc, ap_output_fn out,
                    ap_sim_setup_fn setup, void *user, double *rows, ap_sim_stats *st,
                    const char *what, char *msg, size_t len) {
  ap_sim *s = NULL;
  char buf[512];
  int rc = ap_sim_create(m, def, t0, q0, v0, &s, buf, sizeof buf);
  if (rc != AP_OK) return say(msg, len, rc, what, t0, buf);
  if (setup && (rc = setup(s, user)) != AP_OK) {
    snprintf(buf, sizeof buf, "%s", ap_sim_message(s));
    ap_sim_free(s);
    return say(msg, len, rc, what, t0, buf[0] ? buf : "its setup failed");
  }
  for (int i = 0; i < nt && rc == AP_OK; i++) {
    rc = ap_sim_advance(s, times[i]);
    if (rc == AP_STOPPED) rc = AP_OK;   /* a stop event: the later rows repeat its state */
    if (rc == AP_OK) rc = out(s, rows + (size_t)i * (size_t)nc, user);
    if (rc != AP_OK) say(msg, len, rc, what, ap_sim_time(s), ap_sim_message(s));
  }
  ap_sim_get_stats(s, st);
  ap_sim_free(s);
  return rc;
}

/* An estimate below 30 x the reference's rtol does not tell the run's error from the
 * reference's own: the run was far more accurate than its tolerance (its steps were set by
 * the output times, so the reference took the same steps: dop853 at rtol 1e-4 on the
 * spinning-up turntable estimated 9.4e-12 for a true 6.6e-8), or the reference was not much
 * better. Then one more reference at max(1e-14, min(rtol_ref, estimate) / 100); 1 when it is
 * due (rep->ref updated). */
static int second_pass(ap_error_report *rep, const ap_sim_def *def) {
  double r = rep->ref.rtol;
  if (!(rep->error < 30 * r) || r <= 1e-14 || strcmp(rep->ref.method, "dop853") != 0) return 0;
  rep->ref.rtol = fmax(1e-14, fmin(r, rep->error) / 100);
  rep->ref.atol = fmax(1e-16, def->atol * rep->ref.rtol / def->rtol);
  return 1;
}

int ap_error_against(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                     const double *v0, const double *times, int nt, int nc, ap_output_fn out,
                     ap_sim_setup_fn setup, void *user, const double *rows, double *ref_rows,
                     double *err, double *scale, ap_error_report *rep, char *msg,
                     size_t msg_len) {
  if (!m || !def || !q0 || !v0 || !times || !out || !rows || !rep || nt < 1 || nc < 0) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_error_against: NULL argument or nt < 1");
    return AP_ERR_ARG;
  }
  memset(rep, 0, sizeof *rep);
  ap_error_reference_def(def, &rep->ref);
  size_t cells = (size_t)nt * (size_t)nc;
  double *b = calloc(2 * (size_t)nc + cells + 1, sizeof *b);
  if (!b) return AP_ERR_NOMEM;
  double *e = b + cells, *sc = e + nc;
  int rc = AP_OK;
  for (int pass = 0; rc == AP_OK && pass < 2; pass++) {
    ap_sim_stats st;
    rc = run_rows(m, &rep->ref, t0, q0, v0, times, nt, nc, out, setup, user, b, &st,
                  "reference run", msg, msg_len);
    rep->ref_stats.steps += st.steps, rep->ref_stats.rhs_evals += st.rhs_evals;
    rep->ref_last = st;
    memset(e, 0, sizeof(double) * 2 * (size_t)nc);
    for (int i = 0; rc == AP_OK && i < nt; i++)
      ap_error_fold(nc, rows + (size_t)i * nc, b + (size_t)i * nc, e, sc);
    rep->error = ap_error_norm(nc, e, sc);
    if (!second_pass(rep, def)) break;
  }
  rep->reliable = rep->ref.rtol <= 0.1 * def->rtol || rep->ref.rtol == 1e-12;
  if (rc == AP_OK && ref_rows) memcpy(ref_rows, b, sizeof(double) * cells);
  if (rc == AP_OK && err) memcpy(err, e, sizeof(double) * (size_t)nc);
  if (rc == AP_OK && scale) memcpy(scale, sc, sizeof(double) * (size_t)nc);
  free(b);
  return rc;
}

int ap_global_error(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                    const double *v0, const double *times, int nt, int nc, ap_output_fn out,
                    ap_sim_setup_fn setup, void *user, double *rows, double *err,
                    double *scale, ap_error_report *rep, char *msg, size_t msg_len) {
  if (!m || !def || !q0 || !v0 || !times || !out || !rep || nt < 1 || nc < 0) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_global_error: NULL argument or nt < 1");
    return AP_ERR_ARG;
  }
  memset(rep, 0, sizeof *rep);
  size_t cells = (size_t)nt * (size_t)nc;
  double *a = calloc(cells + 1, sizeof *a);
  if (!a) return AP_ERR_NOMEM;
  ap_sim_stats run;
  int rc = run_rows(m, def, t0, q0, v0, times, nt, nc, out, setup, user, a, &run, "run", msg,
                    msg_len);
  if (rc == AP_OK)
    rc = ap_error_against(m, def, t0, q0, v0, times, nt, nc, out, setup, user, a, NULL, err,
                          scale, rep, msg, msg_len);
  rep->run = run;
  if (rc == AP_OK && rows) memcpy(rows, a, sizeof(double) * cells);
  free(a);
  return rc;
}
