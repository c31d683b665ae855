/* appell run's accuracy options (docs/accuracy.md): --accuracy (the method and tolerance
 * chosen by ap_accuracy_pick before the run), --error-estimate (the run's rows kept, then a
 * reference run through the same times by ap_error_against, the differences written to
 * OUT.error.csv), and the error control where it matters (coordinates nothing and
 * no output depends on left out of the step-size control; --error-control all turns it off).
 *
 * Which coordinates an output asks for: a column named after the coordinate, or else the
 * scene's output row is evaluated at the initial
 * state and at the initial state with one free coordinate moved by 1e-4 of its size (a
 * throw-away simulation each); a channel that moves by more than 1e-10 of its size keeps the
 * coordinate under control. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "run_accuracy.h"
#include "runrecord.h"

/* ---- outputs of the simulations the library makes (ap_output_fn, ap_sim_setup_fn) ------- */

typedef struct pick_ctx {
  ap_scene *sc;
  ap_scene_out *out;       /* the current simulation's output state (angles, E(t0)) */
  const int *unc;          /* coordinates to leave uncontrolled, or NULL */
} pick_ctx;

/* A terminating signal stops the pilot, the checks and the reference between steps. */
static int poll_signal(double t, void *user) {
  (void)t, (void)user;
  return cli_interrupted();
}

static int pick_setup(ap_sim *s, void *user) {
  pick_ctx *c = user;
  ap_sim_set_poll(s, poll_signal, NULL);
  ap_scene_out_free(c->out);
  c->out = NULL;
  char msg[512];
  int rc = ap_scene_add_events(c->sc, s, msg, sizeof msg);
  if (rc == AP_OK && c->unc) rc = ap_sim_set_uncontrolled(s, c->unc);
  if (rc == AP_OK) rc = ap_scene_out_create(c->sc, &c->out);
  /* The first row at t0, as the run's: it sets E(t0) and the angles' unwrapping. */
  double *row = rc == AP_OK ? calloc((size_t)ap_scene_output_count(c->sc) + 1, sizeof *row)
                            : NULL;
  if (rc == AP_OK) rc = row ? ap_scene_out_row(c->out, s, row) : AP_ERR_NOMEM;
  free(row);
  return rc;
}

static int pick_out(ap_sim *s, double *row, void *user) {
  return ap_scene_out_row(((pick_ctx *)user)->out, s, row);
}

/* The output times of the run: t0 + i interval, the last t_end (as tools/run.c's loop). */
static double *output_times(const ap_scene_run *run, int *nt) {
  long n = (long)ceil((run->t_end - run->t0) / run->interval - 1e-9);
  if (n < 1) n = 1;
  double *t = malloc(sizeof(double) * (size_t)n);
  for (long i = 1; t && i <= n; i++)
    t[i - 1] = i == n ? run->t_end : run->t0 + (double)i * run->interval;
  *nt = (int)n;
  return t;
}

int cli_acc_pick(cli_acc *a, ap_scene *sc, ap_scene_run *run, const double *q0,
                 const double *v0, int quiet) {
  int nt = 0;
  double *times = output_times(run, &nt);
  if (!times) return fprintf(stderr, "appell run: out of memory\n"), AP_ERR_NOMEM;
  pick_ctx c = {sc, NULL, a->unc};
  char msg[1024];
  int rc = ap_accuracy_pick(ap_scene_model(sc), &run->sim, run->t0, q0, v0, times, nt,
                            ap_scene_output_count(sc), pick_out, pick_setup, &c, a->accuracy,
                            &a->pick, msg, sizeof msg);
  ap_scene_out_free(c.out);
  free(times);
  if (rc != AP_OK) {
    fprintf(stderr, "appell run: --accuracy %g: %s: %s\n", a->accuracy, ap_strerror(rc), msg);
    return rc;
  }
  a->picked = 1;
  run->sim = a->pick.def;
  if (!quiet)
    fprintf(stderr, "appell run: --accuracy %g: picked %s at rtol = atol = %.3g (estimated "
            "error %.3g, %ld evaluations; the choice cost %ld evaluations: pilot %ld, checks "
            "%ld)\n", a->accuracy, a->pick.def.method, a->pick.def.rtol,
            a->pick.estimated_error, a->pick.evals, a->pick.pilot_evals + a->pick.verify_evals,
            a->pick.pilot_evals, a->pick.verify_evals);
  return AP_OK;
}

/* ---- error control where it matters ------------------------------------------------------ */

/* 1 when the output row at (t0, q0 with q_i moved, v0) differs from base (nc). */
static int output_moves(ap_scene *sc, const ap_scene_run *run, const double *q0,
                        const double *v0, int i, const double *base, double *row) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), nc = ap_scene_output_count(sc), moved = 1;
  double *q = malloc(sizeof(double) * (size_t)n);
  ap_sim *s = NULL;
  ap_scene_out *o = NULL;
  if (!q) return 1;
  memcpy(q, q0, sizeof(double) * (size_t)n);
  q[i] += 1e-4 * (1.0 + fabs(q[i]));
  if (ap_sim_create(m, &run->sim, run->t0, q, v0, &s, NULL, 0) == AP_OK &&
      ap_scene_out_create(sc, &o) == AP_OK && ap_scene_out_row(o, s, row) == AP_OK) {
    moved = 0;
    for (int c = 1; c < nc; c++)
      if (!(fabs(row[c] - base[c]) <= 1e-10 * (1.0 + fabs(base[c])))) moved = 1;
  }
  ap_scene_out_free(o);
  ap_sim_free(s);
  free(q);
  return moved;
}

/* 1 when a column of the output is the coordinate itself (a quaternion's w moved at w = 1 is
 * normalized back: the row would not move). */
static int named_output(const ap_scene *sc, const char *name) {
  for (int c = 1; c < ap_scene_output_count(sc); c++)
    if (strcmp(ap_scene_output_name(sc, c), name) == 0) return 1;
  return 0;
}

int cli_acc_control(cli_acc *a, ap_scene *sc, const ap_scene_run *run, ap_sim *sim,
                    const double *q0, const double *v0) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), nc = ap_scene_output_count(sc);
  if (a->control_all || run->sim.mode == AP_MODE_DAE) return AP_OK;
  a->unc = calloc((size_t)n + 1, sizeof *a->unc);
  double *rows = calloc(2 * (size_t)nc + 1, sizeof *rows);
  ap_scene_out *o = NULL;
  int rc = a->unc && rows ? ap_sim_free_coordinates(sim, a->unc) : AP_ERR_NOMEM;
  if (rc == AP_OK) rc = ap_scene_out_create(sc, &o);
  if (rc == AP_OK) rc = ap_scene_out_row(o, sim, rows);
  for (int i = 0; rc == AP_OK && i < n; i++)
    if (a->unc[i] && (named_output(sc, ap_model_coord_name(m, i)) ||
                      output_moves(sc, run, q0, v0, i, rows, rows + nc)))
      a->unc[i] = 0;
  for (int i = 0; rc == AP_OK && i < n; i++) a->nunc += a->unc[i];
  if (rc == AP_OK && a->nunc) rc = ap_sim_set_uncontrolled(sim, a->unc);
  ap_scene_out_free(o);
  free(rows);
  if (rc != AP_OK) a->nunc = 0;
  return rc;
}

/* ---- the global error estimate -------------------------------------------------------- */

/* Rows kept for the estimate: at most this many numbers (400 MB). */
#define CLI_ACC_MAX_CELLS 50000000L

int cli_acc_keep_row(cli_acc *a, const double *row, int nc) {
  if (!a->estimate || a->too_many) return AP_OK;
  if ((a->rows + 1) * (long)nc > CLI_ACC_MAX_CELLS) return a->too_many = 1, AP_OK;
  if (a->rows == a->cap) {
    long cap = a->cap ? 2 * a->cap : 1024;
    double *p = realloc(a->kept, sizeof(double) * (size_t)cap * (size_t)nc);
    if (!p) return a->too_many = 1, AP_ERR_NOMEM;
    a->kept = p, a->cap = cap;
  }
  memcpy(a->kept + (size_t)a->rows * (size_t)nc, row, sizeof(double) * (size_t)nc);
  a->nc = nc, a->rows++;
  return AP_OK;
}

/* OUT.error.csv: t and |row - ref| per column, through a .part file renamed into place. */
static void write_errors(cli_acc *a, const ap_scene *sc, const double *ref, const char *out) {
  char part[AP_OUT_PATH_MAX + 24];
  snprintf(a->path, sizeof a->path, "%s.error.csv", out);
  snprintf(part, sizeof part, "%s.part", a->path);
  FILE *f = fopen(part, "w");
  for (int c = 0; f && c < a->nc; c++) fprintf(f, c ? ",%s" : "%s", ap_scene_output_name(sc, c));
  if (f) fprintf(f, "\n%.15g", a->kept[0]);
  for (int c = 1; f && c < a->nc; c++) fputs(",0", f);
  for (long i = 1; f && i < a->rows; i++) {
    const double *r = a->kept + (size_t)i * (size_t)a->nc, *x = ref + (size_t)(i - 1) * a->nc;
    fprintf(f, "\n%.15g", r[0]);
    for (int c = 1; c < a->nc; c++) fprintf(f, ",%.6g", fabs(r[c] - x[c]));
  }
  if (f) fputc('\n', f);
  if (!f || fclose(f) != 0 || rename(part, a->path) != 0) {
    unlink(part);
    snprintf(a->failure, sizeof a->failure, "cannot write %.900s", a->path);
    a->path[0] = '\0';
  }
}

/* The estimate of the rows kept: the reference (ap_error_against) through their times. */
static void estimate(cli_acc *a, ap_scene *sc, const ap_scene_run *run, const double *q0,
                     const double *v0, const char *out) {
  if (a->too_many || a->rows < 2) {
    snprintf(a->failure, sizeof a->failure, "%s", a->too_many ? "too many rows to keep for the "
             "estimate" : "no row after the first");
    return;
  }
  long nt = a->rows - 1;
  double *times = malloc(sizeof(double) * (size_t)nt * (size_t)(a->nc + 1));
  if (!times) return (void)snprintf(a->failure, sizeof a->failure, "out of memory");
  double *ref = times + nt;
  for (long i = 0; i < nt; i++) times[i] = a->kept[(size_t)(i + 1) * (size_t)a->nc];
  pick_ctx c = {sc, NULL, a->unc};
  char msg[1024];
  int rc = ap_error_against(ap_scene_model(sc), &run->sim, run->t0, q0, v0, times, (int)nt,
                            a->nc, pick_out, pick_setup, &c, a->kept + a->nc, ref, NULL, NULL,
                            &a->rep, msg, sizeof msg);
  ap_scene_out_free(c.out);
  if (rc != AP_OK) snprintf(a->failure, sizeof a->failure, "%s: %.900s", ap_strerror(rc), msg);
  else a->done = 1;
  if (rc == AP_OK && out) write_errors(a, sc, ref, out);
  free(times);
}

void cli_acc_finish(cli_acc *a, ap_scene *sc, const ap_scene_run *run, const double *q0,
                    const double *v0, int keep, const char *out_path) {
  if (out_path && keep) {   /* an older estimate must not describe these rows */
    char old[AP_OUT_PATH_MAX + 16];
    if ((size_t)snprintf(old, sizeof old, "%s.error.csv", out_path) < sizeof old) unlink(old);
  }
  if (a->estimate && keep) estimate(a, sc, run, q0, v0, out_path);
}

void cli_acc_summary(const cli_acc *a, const ap_model *m) {
  if (a->done)
    fprintf(stderr, "  estimated global error %.3g on the outputs (reference: %s at rtol %.3g, "
            "%ld steps, %ld evaluations)%s%s\n", a->rep.error, a->rep.ref.method,
            a->rep.ref.rtol, a->rep.ref_stats.steps, a->rep.ref_stats.rhs_evals,
            a->path[0] ? " -> " : "", a->path);
  if (a->failure[0]) fprintf(stderr, "appell run: --error-estimate: %s\n", a->failure);
  for (int i = 0, k = 0; a->unc && i < ap_model_n(m); i++) {
    if (!a->unc[i]) continue;
    fprintf(stderr, "%s%s", k ? ", " : "  not error-controlled (nothing and no output depends "
            "on them; --error-control all): ", ap_model_coord_name(m, i));
    if (++k == a->nunc) fputc('\n', stderr);
  }
}

void cli_acc_free(cli_acc *a) {
  free(a->kept);
  free(a->unc);
}

/* ---- the run record's "accuracy" member ------------------------------------------------- */

static void jkey(FILE *f, const char *name, int first) {
  fputs(first ? "{" : ", ", f);
  cli_json_string(f, name);
  fputs(": ", f);
}

static void record_estimate(FILE *f, const cli_acc *a) {
  jkey(f, "error", 1), cli_json_number(f, a->rep.error);
  jkey(f, "how", 0), cli_json_string(f, "a second run at a tighter tolerance on the same "
                                         "output times (docs/accuracy.md)");
  jkey(f, "reliable", 0), fputs(a->rep.reliable ? "true" : "false", f);
  jkey(f, "reference", 0);
  jkey(f, "method", 1), cli_json_string(f, a->rep.ref.method);
  jkey(f, "rtol", 0), cli_json_number(f, a->rep.ref.rtol);
  jkey(f, "atol", 0), cli_json_number(f, a->rep.ref.atol);
  jkey(f, "steps", 0), fprintf(f, "%ld", a->rep.ref_stats.steps);
  jkey(f, "evaluations", 0), fprintf(f, "%ld}", a->rep.ref_stats.rhs_evals);
  jkey(f, "file", 0);
  if (a->path[0]) cli_json_string(f, a->path);
  else fputs("null", f);
  fputs("}", f);
}

static void record_pick(FILE *f, const cli_acc *a) {
  const ap_pick_report *p = &a->pick;
  jkey(f, "accuracy", 1), cli_json_number(f, p->accuracy);
  jkey(f, "method", 0), cli_json_string(f, p->def.method);
  jkey(f, "rtol", 0), cli_json_number(f, p->def.rtol);
  jkey(f, "atol", 0), cli_json_number(f, p->def.atol);
  jkey(f, "estimated_error", 0), cli_json_number(f, p->estimated_error);
  jkey(f, "evaluations", 0), fprintf(f, "%ld", p->evals);
  jkey(f, "pilot_evaluations", 0), fprintf(f, "%ld", p->pilot_evals);
  jkey(f, "check_evaluations", 0), fprintf(f, "%ld", p->verify_evals);
  jkey(f, "candidates", 0), fputc('[', f);
  for (int i = 0; i < p->ncand; i++) {
    fputs(i ? ", " : "", f);
    jkey(f, "method", 1), cli_json_string(f, p->cand[i].method);
    jkey(f, "pilot_rtol", 0), cli_json_number(f, p->cand[i].rtol);
    jkey(f, "pilot_error", 0), cli_json_number(f, p->cand[i].error);
    jkey(f, "rtol", 0), cli_json_number(f, p->cand[i].rtol_pick);
    jkey(f, "predicted_evaluations", 0), cli_json_number(f, p->cand[i].evals);
    fputc('}', f);
  }
  fputs("]}", f);
}

void cli_acc_record(FILE *f, const cli_acc *a, const ap_model *m) {
  jkey(f, "error_estimate", 1);
  if (a->done) record_estimate(f, a);
  else if (a->estimate) cli_json_string(f, a->failure[0] ? a->failure : "not made");
  else fputs("null", f);
  jkey(f, "pick", 0);
  if (a->picked) record_pick(f, a);
  else fputs("null", f);
  jkey(f, "uncontrolled", 0), fputc('[', f);
  for (int i = 0, k = 0; a->unc && i < ap_model_n(m); i++)
    if (a->unc[i]) fputs(k++ ? ", " : "", f), cli_json_string(f, ap_model_coord_name(m, i));
  fputs("]}", f);
}
