/* One run of a batch: load the scene with the run's overrides, make the initial state
 * consistent, simulate from t0 to t_end and fill the run's row of summaries.
 *
 * The run stops where `appell run` writes rows, t_i = t0 + i * interval (the last one t_end
 * exactly), so its trajectory is the CLI's to the last bit; a sample time more than 1e-9
 * intervals away from every output time adds a stop of its own. At every output time the
 * energy E(t) enters the drift max |E(t) - E(t0)|; when channels are asked for, the scene's
 * output row is evaluated there as well (angles are unwrapped from row to row, as in the
 * CLI's CSV), and at each sample time the channels are copied into the row.
 * The scene's events are added to the simulation: a stop event ends the run (AP_STOPPED) with
 * a last energy and sample at the event time, as appell run's last row.
 * Row layout (batch_int.h, ap_batch_col_name): t, steps, rhs_evals, err_fails, max_residual,
 * energy_drift, [q@end, v@end], [channel@time, times outer]; NaN where nothing was reached. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "appell/scene.h"
#include "appell/sim.h"
#include "batch/batch_int.h"

typedef struct one_run {
  const ap_batch *b;
  ap_scene *sc;
  ap_sim *sim;
  ap_scene_run run;
  double *buf;             /* q0 (n), v0 (k), the scene's output row */
  double *orow;
  int *chan;               /* (nchannels) each channel's column in the scene's row */
  double *row;             /* the result row (b->ncols) */
  int next;                /* next sample in b->order */
  int rows;                /* energies evaluated */
  double E0, drift;
  char *msg;
  size_t msg_len;
} one_run;

static int fail(one_run *r, int rc, const char *what, const char *detail) {
  if (r->msg && r->msg_len) snprintf(r->msg, r->msg_len, "%s%s", what, detail);
  return rc;
}

/* Sizes, buffers and the columns of the channels in this run's scene. */
static int prepare(one_run *r) {
  const ap_batch *b = r->b;
  const ap_model *m = ap_scene_model(r->sc);
  if (ap_model_n(m) != b->n || ap_model_k(m) != b->k)
    return fail(r, AP_ERR_ARG, "the overrides change the model's coordinates or speeds; the "
                "runs of a batch must share them", "");
  int nc = ap_scene_output_count(r->sc);
  r->buf = calloc((size_t)(b->n + b->k + nc) + 1, sizeof *r->buf);
  r->chan = calloc((size_t)b->def.nchannels + 1, sizeof *r->chan);
  if (!r->buf || !r->chan) return fail(r, AP_ERR_NOMEM, "out of memory", "");
  r->orow = r->buf + b->n + b->k;
  for (int c = 0; c < b->def.nchannels; c++) {
    r->chan[c] = -1;
    for (int i = 0; i < nc && r->chan[c] < 0; i++)
      if (strcmp(ap_scene_output_name(r->sc, i), b->channels[c]) == 0) r->chan[c] = i;
    if (r->chan[c] < 0)
      return fail(r, AP_ERR_ARG, "the overrides remove the output column ", b->channels[c]);
  }
  return AP_OK;
}

static int start(one_run *r) {
  char report[2048], why[1024];
  double *q0 = r->buf, *v0 = r->buf + r->b->n;
  int rc = ap_scene_initial_state(r->sc, q0, v0, report, sizeof report, r->msg, r->msg_len);
  if (rc != AP_OK) return rc;
  ap_scene_get_run(r->sc, &r->run);
  rc = ap_sim_create(ap_scene_model(r->sc), &r->run.sim, r->run.t0, q0, v0, &r->sim, why,
                     sizeof why);
  if (rc != AP_OK) return fail(r, rc, "cannot start the simulation: ", why);
  rc = ap_scene_add_events(r->sc, r->sim, why, sizeof why);
  if (rc != AP_OK) return fail(r, rc, "cannot add the scene's events: ", why);
  return AP_OK;
}

/* Energy (at output times), the output row and the samples due at time t. */
static int record(one_run *r, double t, int grid, double tol) {
  const ap_batch *b = r->b;
  int due = r->next < b->def.ntimes && fabs(b->times[b->order[r->next]] - t) <= tol;
  if (grid) {
    double E = 0.0;
    int rc = ap_scene_energy(r->sc, t, ap_sim_q(r->sim), ap_sim_v(r->sim), &E);
    if (rc != AP_OK) return fail(r, rc, "energy evaluation failed", "");
    if (r->rows++ == 0) r->E0 = E;
    r->drift = fmax(r->drift, fabs(E - r->E0));
  }
  if (b->def.nchannels == 0)   /* nothing to sample; the times still pass (the loop waits for
                                  them: without this it spun for ever on a time it had reached) */
    for (; r->next < b->def.ntimes && fabs(b->times[b->order[r->next]] - t) <= tol; r->next++) {}
  if (b->def.nchannels == 0 || (!grid && !due)) return AP_OK;
  int rc = ap_scene_output_row(r->sc, r->sim, r->orow);
  if (rc != AP_OK) return fail(r, rc, "output row failed: ", ap_sim_message(r->sim));
  int base = AP_BAT_FIXED_COLS + (b->def.final_state ? b->n + b->k : 0);
  for (; r->next < b->def.ntimes && fabs(b->times[b->order[r->next]] - t) <= tol; r->next++)
    for (int c = 0; c < b->def.nchannels; c++)
      r->row[base + b->order[r->next] * b->def.nchannels + c] = r->orow[r->chan[c]];
  return AP_OK;
}

/* The stop event that ended the run, as its message. */
static int stopped(one_run *r) {
  ap_event_record ev;
  int n = ap_sim_event_count(r->sim);
  if (n > 0 && ap_sim_event_get(r->sim, n - 1, &ev) == AP_OK && r->msg && r->msg_len)
    snprintf(r->msg, r->msg_len, "stopped by event '%s' at t = %.10g", ev.name, ev.t);
  return AP_STOPPED;
}

static int advance(one_run *r, double t) {
  int rc = ap_sim_advance(r->sim, t);
  if (rc == AP_OK) return AP_OK;
  if (rc == AP_STOPPED) return stopped(r);
  char what[1200];   /* the scene expression at fault first, when there is one */
  int n = ap_scene_locate_failure(r->sc, r->sim, t, what, sizeof what - 100) != AP_OK && what[0]
              ? (int)strlen(what) : 0;
  snprintf(what + n, sizeof what - (size_t)n, "%sthe simulation failed at t = %.10g: %s: ",
           n ? "; " : "", ap_sim_time(r->sim), ap_strerror(rc));
  return fail(r, rc, what, ap_sim_message(r->sim));
}

/* The output times of appell run, with the off-grid sample times in between. */
static int loop(one_run *r) {
  const ap_batch *b = r->b;
  double t0 = r->run.t0, dt = r->run.interval, tol = 1e-9 * dt;
  long nrows = (long)ceil((r->run.t_end - t0) / dt - 1e-9);
  if (nrows < 1) nrows = 1;   /* an interval past t_end: still the stop at t_end (t_end > t0) */
  while (r->next < b->def.ntimes && b->times[b->order[r->next]] < t0 - tol) r->next++;
  int rc = record(r, t0, 1, tol);
  for (long i = 1; rc == AP_OK && i <= nrows; i++) {
    double t = i == nrows ? r->run.t_end : t0 + (double)i * dt;
    while (rc == AP_OK && r->next < b->def.ntimes && b->times[b->order[r->next]] < t - tol) {
      double ts = b->times[b->order[r->next]];
      rc = advance(r, ts);
      if (rc == AP_OK) rc = record(r, ts, 0, tol);
    }
    if (rc == AP_OK) rc = advance(r, t);
    if (rc == AP_OK) rc = record(r, t, 1, tol);
  }
  if (rc == AP_STOPPED) {   /* the last row of appell run is at the event: its energy too */
    int rec = record(r, ap_sim_time(r->sim), 1, tol);
    if (rec != AP_OK) rc = rec;
  }
  return rc;
}

/* Time reached, counters, drift and where the run ended. */
static void summarize(one_run *r) {
  const ap_batch *b = r->b;
  ap_sim_stats st;
  ap_sim_get_stats(r->sim, &st);
  double *row = r->row;
  row[0] = ap_sim_time(r->sim);
  row[1] = (double)st.steps, row[2] = (double)st.rhs_evals, row[3] = (double)st.err_fails;
  row[4] = st.max_residual;
  row[5] = r->rows ? r->drift : NAN;
  if (!b->def.final_state) return;
  memcpy(row + AP_BAT_FIXED_COLS, ap_sim_q(r->sim), sizeof(double) * (size_t)b->n);
  memcpy(row + AP_BAT_FIXED_COLS + b->n, ap_sim_v(r->sim), sizeof(double) * (size_t)b->k);
}

/* The run's events as "NAME@T;NAME@T" into ev (the last AP_BAT_MAX_EVENTS; cut at a whole
 * event when ev is too short). */
static void event_text(const ap_sim *sim, char *ev, size_t len) {
  int n = ap_sim_event_count(sim);
  size_t used = 0;
  ev[0] = '\0';
  for (int i = n > AP_BAT_MAX_EVENTS ? n - AP_BAT_MAX_EVENTS : 0; i < n; i++) {
    ap_event_record r;
    if (ap_sim_event_get(sim, i, &r) != AP_OK) continue;
    int w = snprintf(ev + used, len - used, "%s%s@%.17g", used ? ";" : "", r.name, r.t);
    if (w < 0 || (size_t)w >= len - used) {
      ev[used] = '\0';
      return;
    }
    used += (size_t)w;
  }
}

/* ap_sim_poll_fn: stop once the batch is cancelled. */
static int poll_stop(double t, void *user) {
  (void)t;
  return atomic_load_explicit((const atomic_int *)user, memory_order_relaxed) != 0;
}

int ap_bat_run_one(const ap_batch *b, const char *const *vsets, int nv, double *row, char *msg,
                   size_t msg_len, char *ev, size_t ev_len, const atomic_int *stop) {
  one_run r;
  memset(&r, 0, sizeof r);
  r.b = b, r.row = row, r.msg = msg, r.msg_len = msg_len;
  if (msg && msg_len) msg[0] = '\0';
  for (int j = 0; j < b->ncols; j++) row[j] = NAN;
  int rc = ap_bat_load(b, vsets, nv, &r.sc, msg, msg_len);
  if (rc == AP_OK) rc = prepare(&r);
  if (rc == AP_OK) rc = start(&r);
  if (rc == AP_OK && stop) ap_sim_set_poll(r.sim, poll_stop, (void *)stop);
  if (rc == AP_OK) rc = loop(&r);
  if (r.sim) summarize(&r);
  if (r.sim && ev && ev_len) event_text(r.sim, ev, ev_len);
  if (rc == AP_OK && r.sim && ap_sim_warning(r.sim)[0] && msg && msg_len)
    snprintf(msg, msg_len, "warning: %s", ap_sim_warning(r.sim));
  ap_sim_free(r.sim);
  ap_scene_free(r.sc);
  free(r.buf);
  free(r.chan);
  return rc;
}
