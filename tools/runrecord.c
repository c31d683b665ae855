/* appell run's run record: OUT.run.json beside --out OUT, saying how the run ended and with
 * what (docs/cli.md "The run record"). JSON written by hand: strings are escaped per RFC 8259
 * (quote, backslash, control characters as \uXXXX) and kept valid UTF-8 (a byte that does not
 * start or continue a well-formed sequence becomes U+FFFD, so a scene path in another encoding
 * still gives a readable record); numbers have 17 significant digits (they read back to the
 * same double) and NaN or infinities, which JSON cannot hold, are null. The events come from
 * cli_run_events, the one place where the library's events are to be connected. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commit.h"
#include "run_accuracy.h"
#include "runrecord.h"
#include "sweep.h"

int cli_run_events(const ap_sim *sim, cli_event *out, int max) {
  static const char *const actions[] = {"stop", "log", "switch"};
  int n = ap_sim_event_count(sim), kept = 0;
  for (int i = n > max ? n - max : 0; i < n; i++) {   /* the last max: the stop is last */
    ap_event_record ev;
    if (ap_sim_event_get(sim, i, &ev) != AP_OK) continue;
    out[kept++] = (cli_event){ev.name, ev.t, actions[(unsigned)ev.action % 3],
                              ev.direction > 0 ? "rising" : "falling", ev.q, ev.v};
  }
  return kept;
}

const char *cli_outcome(int status) {
  return status == AP_OK ? CLI_STATUS_OK : status == AP_STOPPED ? CLI_STATUS_EVENT
                                                                : CLI_STATUS_FAILED;
}

void sweep_outcome_cells(FILE *f, int status, const char *events) {
  fprintf(f, ",%s,", cli_outcome(status));
  sweep_csv_quote(f, events ? events : "");
}

/* Length of the well-formed UTF-8 sequence at s (1 to 4), or 0 when there is none. */
static int utf8_len(const unsigned char *s) {
  int n = s[0] < 0x80 ? 1 : s[0] >= 0xC2 && s[0] <= 0xDF ? 2 : s[0] >= 0xE0 && s[0] <= 0xEF ? 3
        : s[0] >= 0xF0 && s[0] <= 0xF4 ? 4 : 0;
  for (int i = 1; i < n; i++)
    if ((s[i] & 0xC0) != 0x80) return 0;
  if (n == 3 && ((s[0] == 0xE0 && s[1] < 0xA0) || (s[0] == 0xED && s[1] >= 0xA0))) return 0;
  if (n == 4 && ((s[0] == 0xF0 && s[1] < 0x90) || (s[0] == 0xF4 && s[1] >= 0x90))) return 0;
  return n;
}

void cli_json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p;) {
    int n = utf8_len(p);
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p == '\n') fputs("\\n", f);
    else if (*p == '\t') fputs("\\t", f);
    else if (*p == '\r') fputs("\\r", f);
    else if (*p < 0x20 || *p == 0x7F) fprintf(f, "\\u%04x", *p);
    else if (n == 0) fputs("\\ufffd", f);
    else fwrite(p, 1, (size_t)n, f);
    p += n ? n : 1;
  }
  fputc('"', f);
}

/* The shortest of %.15g, %.16g, %.17g that reads back to x (1e-12, not 9.9999999999999998e-13). */
void cli_json_number(FILE *f, double x) {
  if (!isfinite(x)) {
    fputs("null", f);
    return;
  }
  char buf[40];
  for (int p = 15; p <= 17; p++) {
    snprintf(buf, sizeof buf, "%.*g", p, x);
    if (strtod(buf, NULL) == x) break;
  }
  fputs(buf, f);
}

static void key(FILE *f, const char *name, int indent) {
  fprintf(f, ",\n%*s", indent, "");
  cli_json_string(f, name);
  fputs(": ", f);
}

/* {"name": value, ...} of len values named by name(m, i). */
static void named(FILE *f, const ap_model *m, const char *(*name)(const ap_model *, int),
                  const double *x, int len) {
  fputc('{', f);
  for (int i = 0; x && i < len; i++) {
    fputs(i ? ", " : "", f);
    cli_json_string(f, name(m, i));
    fputs(": ", f);
    cli_json_number(f, x[i]);
  }
  fputc('}', f);
}

static void events(FILE *f, const cli_record *r) {
  cli_event ev[64];
  int n = r->sim ? cli_run_events(r->sim, ev, 64) : 0;
  fputc('[', f);
  for (int i = 0; i < n; i++) {
    fputs(i ? ",\n    {" : "\n    {", f);
    fputs("\"name\": ", f), cli_json_string(f, ev[i].name);
    fputs(", \"t\": ", f), cli_json_number(f, ev[i].t);
    fputs(", \"action\": ", f), cli_json_string(f, ev[i].action);
    fputs(", \"direction\": ", f), cli_json_string(f, ev[i].direction);
    fputs(", \"state\": {\"q\": ", f);
    named(f, r->model, ap_model_coord_name, ev[i].q, ap_model_n(r->model));
    fputs(", \"v\": ", f);
    named(f, r->model, ap_model_speed_name, ev[i].v, ap_model_k(r->model));
    fputs("}}", f);
  }
  fputs(n ? "\n  ]" : "]", f);
}

static void settings(FILE *f, const cli_record *r) {
  static const char *const modes[] = {"minimal", "projected", "dae", "plain"};
  const ap_sim_def *d = &r->run->sim;
  fputc('{', f);
  fputs("\n    \"mode\": ", f), cli_json_string(f, modes[d->mode % 4]);
  key(f, "method", 4), cli_json_string(f, d->mode == AP_MODE_DAE ? "ida" : d->method);
  key(f, "path", 4), cli_json_string(f, ap_model_path(r->model) == AP_PATH_TREE ? "tree"
                                                                                 : "dense");
  key(f, "rtol", 4), cli_json_number(f, d->rtol);
  key(f, "atol", 4), cli_json_number(f, d->atol);
  key(f, "h_fixed", 4), cli_json_number(f, d->h_fixed);
  key(f, "h_init", 4), cli_json_number(f, d->h_init);
  key(f, "h_max", 4), cli_json_number(f, d->h_max);
  key(f, "max_steps", 4), fprintf(f, "%ld", d->max_steps);
  key(f, "t0", 4), cli_json_number(f, r->run->t0);
  key(f, "t_end", 4), cli_json_number(f, r->run->t_end);
  key(f, "interval", 4), cli_json_number(f, r->run->interval);
  fputs("\n  }", f);
}

void cli_record_write(FILE *f, const cli_record *r) {
  ap_sim_stats st;
  ap_sim_get_stats(r->sim, &st);
  fputs("{\n  \"format\": \"appell run record 1\"", f);
  key(f, "appell", 2), cli_json_string(f, AP_VERSION_STRING);
  key(f, "commit", 2), cli_json_string(f, CLI_COMMIT);
  key(f, "scene", 2), cli_json_string(f, r->scene);
  key(f, "name", 2), cli_json_string(f, r->scene_name);
  key(f, "out", 2), cli_json_string(f, r->out);
  key(f, "overrides", 2), fputc('[', f);
  for (int i = 0; i < r->nsets; i++) fputs(i ? ", " : "", f), cli_json_string(f, r->sets[i]);
  fputc(']', f);
  key(f, "settings", 2), settings(f, r);
  key(f, "status", 2), cli_json_string(f, r->status);
  key(f, "exit_code", 2), fprintf(f, "%d", r->exit_code);
  key(f, "error", 2);
  if (r->error) cli_json_string(f, r->error);
  else fputs("null", f);
  key(f, "message", 2), cli_json_string(f, r->message);
  key(f, "t", 2), cli_json_number(f, r->t);
  key(f, "rows", 2), fprintf(f, "%ld", r->rows);
  key(f, "events", 2), events(f, r);
  key(f, "steps", 2), fprintf(f, "%ld", st.steps);
  key(f, "rejected_steps", 2), fprintf(f, "%ld", st.err_fails);
  key(f, "evaluations", 2), fprintf(f, "%ld", st.rhs_evals);
  key(f, "partition_switches", 2), fprintf(f, "%ld", st.partition_switches);
  key(f, "projections", 2), fprintf(f, "%ld", st.projections);
  key(f, "max_residual", 2), cli_json_number(f, st.max_residual);
  key(f, "energy_drift", 2), cli_json_number(f, r->energy_drift);
  key(f, "energy_drift_relative", 2),
      cli_json_number(f, r->energy_drift / fmax(fabs(r->energy0), 1e-300));
  key(f, "energy_conserved", 2), fputs(r->conserves_energy ? "true" : "false", f);
  key(f, "wall_time", 2), cli_json_number(f, r->wall);
  if (r->acc) key(f, "accuracy", 2), cli_acc_record(f, r->acc, r->model);
  fputs("\n}\n", f);
}
