/* appell run: simulate a scene and write its output channels as CSV (docs/cli.md).
 *
 * Flow: options -> the output target checked (tools/output.c) -> signal handlers -> overrides
 * (--set first, then --mode/--method/--rtol/--atol/--t-end, so the command line wins over the
 * file) -> ap_scene_load -> initial state (corrections reported) -> ap_sim_create -> rows at
 * t0 + i * interval up to t_end -> summary on stderr. A terminating signal is seen between
 * internal steps (the simulation polls cli_interrupted) and a failed write after the row.
 * Invariant: with --out naming a regular file, rows go to a temporary file beside the target,
 * renamed over it after the last row, with the run record (OUT.run.json, tools/runrecord.c)
 * renamed beside it: a run that reached t_end, failed (exit 3) or was stopped by a signal
 * (128 + N) keeps every row up to where it stopped and says why; a failed write or a second
 * signal removes the temporary files, so a file at the target path is always complete. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <appell/appell.h>

#include "cli.h"
#include "run_accuracy.h"
#include "runrecord.h"

#define MAX_SETS 256

static const char help[] =
    "usage: appell run SCENE [options]\n"
    "\n"
    "Simulate SCENE (a YAML scene file, docs/scenes.md) and write one CSV row per output\n"
    "interval: a header, then t and the channels the scene asks for (docs/cli.md).\n"
    "\n"
    "options:\n"
    "  --out FILE.csv     write the CSV to FILE.csv (default or -: standard output); a\n"
    "                     regular file appears when the run ends, with every row up to\n"
    "                     where it ended (also after a failure or a signal) and the run\n"
    "                     record FILE.csv.run.json saying how (docs/cli.md); a FIFO or a\n"
    "                     device is written in place; a directory or the scene is refused\n"
    "  --set PATH=VALUE   override a scalar of the scene by its dotted key path, e.g.\n"
    "                     --set bodies.disk.mass=2 --set initial.disk.tilt=80*deg (repeatable)\n"
    "  --mode M           minimal, projected, dae or plain (simulation.mode)\n"
    "  --method NAME      stepper (simulation.method); see the list below\n"
    "  --path P           auto, dense or tree: how the model evaluates (simulation.path)\n"
    "  --rtol X           relative tolerance (simulation.rtol)\n"
    "  --atol X           absolute tolerance (simulation.atol)\n"
    "  --t-end T          end time in seconds (simulation.t_end)\n"
    "  --interval DT      output interval in seconds (output.interval)\n"
    "  --error-estimate   estimate the global error of every output channel by a second\n"
    "                     run at rtol / 100 (docs/accuracy.md); the estimate goes to the\n"
    "                     summary, the run record and FILE.csv.error.csv\n"
    "  --accuracy E       pick the method and tolerance that reach the global error E on\n"
    "                     the outputs at the least cost, from a short pilot run\n"
    "  --error-control C  outputs (default): coordinates that nothing and no output\n"
    "                     depends on are left out of the step-size control; all: none\n"
    "  --compile C        never, auto or always: run the model's kinematics as C compiled\n"
    "                     for it (simulation.compile; docs/compiled.md)\n"
    "  --quiet            no summary and no progress bar\n"
    "  -h, --help         this help\n"
    "\n"
    "Command-line values win over the file. A summary (steps, evaluations, wall time, largest\n"
    "constraint residual, energy drift) goes to standard error, with a progress bar when\n"
    "standard error is a terminal. Exit codes: 0 success, 2 bad input, 3 numerical failure,\n"
    "1 internal error or a failed write, 128 + N stopped by signal N (130: Ctrl-C).\n";

typedef struct run_opts {
  const char *scene, *out;
  const char *sets[MAX_SETS + 8];
  int nsets, quiet;
  int estimate, control_all;   /* --error-estimate, --error-control all */
  double accuracy;             /* --accuracy, 0 when not given */
  char extra[7][96];      /* overrides built from --mode, --method, ... */
} run_opts;

static void print_methods(void) {
  ap_method_info info;
  printf("\nmethods:\n");
  for (int i = 0; i < ap_method_count(); i++)
    if (ap_method_get(i, &info) == AP_OK)
      printf("  %-12s order %d, %s  %s\n", info.name, info.order,
             info.adaptive ? "adaptive" : "fixed step", info.summary);
}

/* Options that become overrides: option name and the scene path. */
static const char *const mapped[][2] = {{"--mode", "simulation.mode"},
                                        {"--method", "simulation.method"},
                                        {"--rtol", "simulation.rtol"},
                                        {"--atol", "simulation.atol"},
                                        {"--t-end", "simulation.t_end"},
                                        {"--interval", "output.interval"},
                                        {"--path", "simulation.path"},
                                        {"--compile", "simulation.compile"}};

static int mapped_opt(int argc, char **argv, int *i, run_opts *o, int *extra) {
  for (int m = 0; m < (int)(sizeof mapped / sizeof mapped[0]); m++) {
    const char *v = NULL;
    int r = cli_opt(argc, argv, i, mapped[m][0], &v);
    if (r == 0) continue;
    if (r < 0) return cli_need("run", mapped[m][0], NULL);
    double x;
    if (m >= 2 && m < 6 && cli_number("run", mapped[m][0], v, &x) != 0) return -1;
    snprintf(o->extra[*extra], sizeof o->extra[0], "%s=%s", mapped[m][1], v);
    ++*extra;
    return 1;
  }
  return 0;
}

static int parse_args(int argc, char **argv, run_opts *o) {
  static const char *const known[] = {"--out", "--set", "--mode", "--method", "--rtol", "--atol",
                                      "--t-end", "--interval", "--path", "--quiet", "--help",
                                      "--error-estimate", "--accuracy", "--error-control",
                                      "--compile", NULL};
  int extra = 0;
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) return 1;
    if (strcmp(argv[i], "--quiet") == 0) {
      o->quiet = 1;
    } else if (strcmp(argv[i], "--error-estimate") == 0) {
      o->estimate = 1;
    } else if ((r = cli_opt(argc, argv, &i, "--accuracy", &v)) != 0) {
      if (r < 0) return cli_need("run", "--accuracy", "a global error, e.g. 1e-6");
      if (cli_number("run", "--accuracy", v, &o->accuracy) != 0) return -1;
      if (!(o->accuracy >= 1e-12 && o->accuracy < 1))
        return fprintf(stderr, "appell run: --accuracy %s: give a global error in [1e-12, 1)\n",
                       v), -1;
    } else if ((r = cli_opt(argc, argv, &i, "--error-control", &v)) != 0) {
      if (r < 0 || (strcmp(v, "all") != 0 && strcmp(v, "outputs") != 0))
        return fprintf(stderr, "appell run: --error-control needs 'outputs' or 'all'\n"), -1;
      o->control_all = strcmp(v, "all") == 0;
    } else if ((r = cli_opt(argc, argv, &i, "--out", &v)) != 0 ||
               (r = cli_opt(argc, argv, &i, "-o", &v)) != 0) {
      if (r < 0) return cli_need("run", "--out", "a file name");
      o->out = v;
    } else if ((r = cli_opt(argc, argv, &i, "--set", &v)) != 0) {
      if (r < 0) return cli_need("run", "--set", "PATH=VALUE");
      if (o->nsets >= MAX_SETS)
        return fprintf(stderr, "appell run: at most %d --set\n", MAX_SETS), -1;
      o->sets[o->nsets++] = v;
    } else if ((r = mapped_opt(argc, argv, &i, o, &extra)) != 0) {
      if (r < 0) return -1;
    } else if (argv[i][0] == '-' && argv[i][1]) {
      cli_unknown("run", argv[i], known);
      return -1;
    } else if (!o->scene) {
      o->scene = argv[i];
    } else {
      return fprintf(stderr, "appell run: one scene at a time (got '%s' and '%s')\n", o->scene,
                     argv[i]), -1;
    }
  }
  for (int e = 0; e < extra; e++) o->sets[o->nsets++] = o->extra[e];
  if (!o->scene) return fprintf(stderr, "appell run: no scene file (see appell run --help)\n"), -1;
  return 0;
}

/* ---- the run ---------------------------------------------------------------------------- */

typedef struct run_state {
  ap_scene *sc;
  ap_sim *sim;
  ap_scene_run run;
  double *buf, *row, E0, drift, wall;   /* buf: q0, v0, row */
  double t_last;           /* time of the last row written */
  char *lift;              /* per column: 1 = a contact normal force (.contact.Fz) not yet
                              negative, 2 = warned about, 0 = another column */
  long rows;
  int progress;
  const char *status;      /* how the run ended (CLI_STATUS_*); NULL after a failed write */
  int quiet_events;        /* --quiet: no line for a stop event */
  const char *error;       /* ap_strerror of the failure, or NULL */
  char message[4096];      /* what stopped it, as printed on stderr */
  cli_acc acc;             /* --accuracy, --error-estimate, --error-control (run_accuracy.c) */
  const char *err_path;    /* --out when it names a regular file (for OUT.error.csv), or NULL */
} run_state;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void progress(const run_state *rs, double t, int done) {
  double frac = (t - rs->run.t0) / (rs->run.t_end - rs->run.t0);
  int w = 30, fill = (int)(frac * w + 0.5);
  fprintf(stderr, "\r[%.*s%*s] %3d%%  t = %-10.4g", fill, "##############################",
          w - fill, "", (int)(100 * frac + 0.5), t);
  if (done) fputs("\r\033[K", stderr);
}

/* A negative contact normal force: the ground would have to pull, the body would lift off
 * (the contact holds regardless: a plane-contact joint or a wheel's contact row). Once per
 * contact. */
static void warn_lift_off(run_state *rs, int nc) {
  for (int i = 0; rs->lift && i < nc; i++) {
    if (rs->lift[i] != 1 || !(rs->row[i] < 0)) continue;
    rs->lift[i] = 2;
    fprintf(stderr, "%sappell run: warning: %s = %.6g N < 0 at t = %.10g: the ground would have "
            "to pull; a real body would lift off here (the model keeps the contact closed)\n", rs->progress ? "\r\033[K" : "", ap_scene_output_name(rs->sc, i),
            rs->row[i], ap_sim_time(rs->sim));
  }
}

static int write_row(run_state *rs, FILE *f) {
  int rc = ap_scene_output_row(rs->sc, rs->sim, rs->row), nc = ap_scene_output_count(rs->sc);
  if (rc != AP_OK) return rc;
  rs->t_last = ap_sim_time(rs->sim);
  for (int i = 0; i < nc; i++) fprintf(f, i ? ",%.15g" : "%.15g", rs->row[i]);
  fputc('\n', f);
  cli_acc_keep_row(&rs->acc, rs->row, nc);
  warn_lift_off(rs, nc);
  double E = 0.0;
  rc = ap_scene_energy(rs->sc, ap_sim_time(rs->sim), ap_sim_q(rs->sim), ap_sim_v(rs->sim), &E);
  if (rc != AP_OK) return rc;
  if (rs->rows++ == 0) rs->E0 = E;
  rs->drift = fmax(rs->drift, fabs(E - rs->E0));
  return AP_OK;
}

/* A run that failed mid-run: name the scene expression that is not finite where it failed
 * (at the failing evaluation's time and state, or at the output time), whatever the method,
 * on stderr and after the message of the run record. */
static void locate(run_state *rs, double tout) {
  char msg[1024];
  if (ap_scene_locate_failure(rs->sc, rs->sim, tout, msg, sizeof msg) != AP_OK && msg[0]) {
    fprintf(stderr, "%s\n", msg);
    size_t used = strlen(rs->message);
    snprintf(rs->message + used, sizeof rs->message - used, "\n%s", msg);
  }
}

/* The run stopped at a failure (status rc): the message on stderr and in the record. */
static int failed(run_state *rs, int rc, double tout, const char *what) {
  snprintf(rs->message, sizeof rs->message, "appell run: %s at t = %.10g: %s: %s", what,
           ap_sim_time(rs->sim), ap_strerror(rc), ap_sim_message(rs->sim));
  fprintf(stderr, "%s%s\n", rs->progress ? "\r\033[K" : "", rs->message);
  locate(rs, tout);
  rs->status = CLI_STATUS_FAILED, rs->error = ap_strerror(rc);
  return cli_exit_code(rc) == EXIT_INPUT ? EXIT_NUMERIC : cli_exit_code(rc);
}

/* The simulation's poll (ap_sim_set_poll): stop at a terminating signal. */
static int poll_signal(double t, void *user) {
  (void)t, (void)user;
  return cli_interrupted();
}

/* After a failed write: the message comes from cli_out_close; the rows are not kept. */
static int write_failed(run_state *rs, const cli_out *out) {
  rs->status = NULL;
  return out->err == EPIPE ? EXIT_SIGNAL(SIGPIPE) : EXIT_INTERNAL;
}

/* An advance that returned AP_STOPPED before its output time because a stop event fired (its
 * row, at the event time, is written): the run ends there with exit 0, the record saying
 * "event". The events come from cli_run_events (tools/runrecord.c). */
static int stopped_by_event(run_state *rs) {
  cli_event ev[64];
  int n = cli_run_events(rs->sim, ev, 64);
  const cli_event *last = n > 0 ? &ev[n > 64 ? 63 : n - 1] : NULL;
  if (!last || strcmp(last->action, "stop") != 0) return 0;
  snprintf(rs->message, sizeof rs->message, "appell run: stopped by event '%s' at t = %.10g",
           last->name, last->t);
  if (!rs->quiet_events) fprintf(stderr, "%s%s\n", rs->progress ? "\r\033[K" : "", rs->message);
  rs->status = CLI_STATUS_EVENT;
  return 1;
}

static int loop(run_state *rs, cli_out *out) {
  long nrows = (long)ceil((rs->run.t_end - rs->run.t0) / rs->run.interval - 1e-9);
  if (nrows < 1) nrows = 1;   /* an interval past t_end: still the row at t_end (t_end > t0) */
  double last_draw = 0.0;
  int rc = write_row(rs, out->f);
  if (cli_out_failed(out)) return write_failed(rs, out);
  for (long i = 1; rc == AP_OK && i <= nrows && !cli_interrupted(); i++) {
    double t = i == nrows ? rs->run.t_end : rs->run.t0 + (double)i * rs->run.interval;
    rc = ap_sim_advance(rs->sim, t);
    if (rc == AP_ERR_INTERRUPTED && cli_interrupted()) break;
    if (rc == AP_STOPPED) {                      /* a stop event: the last row is there */
      rc = write_row(rs, out->f);
      if (cli_out_failed(out)) return write_failed(rs, out);
      if (rc == AP_OK && stopped_by_event(rs)) return EXIT_OK;
      break;
    }
    if (rc != AP_OK) {
      /* The rows end at the last output time reached: after a failure inside an advance the
       * simulation's time is where the integrator gave up (the record's t) but its q and v
       * may still be those of the last output time, so no row is made there. */
      return failed(rs, rc, t, "the simulation failed");
    }
    rc = write_row(rs, out->f);
    if (cli_out_failed(out)) return write_failed(rs, out);
    if (rs->progress && (now() - last_draw > 0.1 || i == nrows)) {
      progress(rs, t, 0);
      last_draw = now();
    }
  }
  if (rs->progress) progress(rs, rs->run.t_end, 1);
  int sig = cli_interrupted();
  if (sig) {
    snprintf(rs->message, sizeof rs->message, "appell run: interrupted by %s at t = %.10g",
             cli_signal_name(sig), ap_sim_time(rs->sim));
    fprintf(stderr, "%s\n", rs->message);
    rs->status = CLI_STATUS_INTERRUPTED;
    /* A row where it stopped: an interrupted advance leaves q and v at that step. */
    if (ap_sim_time(rs->sim) > rs->t_last) write_row(rs, out->f);
    return cli_out_failed(out) ? write_failed(rs, out) : EXIT_SIGNAL(sig);
  }
  if (rc != AP_OK) return failed(rs, rc, ap_sim_time(rs->sim), "output failed");
  snprintf(rs->message, sizeof rs->message, "%s", ap_sim_warning(rs->sim));
  rs->status = CLI_STATUS_OK;
  return EXIT_OK;
}

static void summary(const run_state *rs, const run_opts *o) {
  ap_sim_stats st;
  ap_sim_get_stats(rs->sim, &st);
  const ap_sim_def *d = &rs->run.sim;
  static const char *const modes[] = {"minimal", "projected", "dae", "plain"};
  /* The time reached: t_end, or where a stop event ended the run. */
  double t_last = fmin(ap_sim_time(rs->sim), rs->run.t_end);
  fprintf(stderr, "appell: %s: t = %g .. %.10g, %ld rows%s%s\n", ap_scene_name(rs->sc),
          rs->run.t0, t_last, rs->rows, o->out ? " -> " : "", o->out ? o->out : "");
  fprintf(stderr, "  mode %s, method %s, rtol %.3g, atol %.3g\n", modes[d->mode % 4],
          d->mode == AP_MODE_DAE ? "ida" : d->method, d->rtol, d->atol);
  fprintf(stderr, "  steps %ld (rejected %ld), evaluations %ld, partition switches %ld, "
          "projections %ld, wall time %.3f s\n", st.steps, st.err_fails, st.rhs_evals,
          st.partition_switches, st.projections, rs->wall);
  fprintf(stderr, "  max constraint residual %.3g, energy drift %.3g (relative %.3g; %s)\n",
          st.max_residual, rs->drift, rs->drift / fmax(fabs(rs->E0), 1e-300),
          ap_scene_conserves_energy(rs->sc) ? "energy is conserved in this scene"
                                            : "energy is not conserved in this scene");
  if (ap_sim_warning(rs->sim)[0]) fprintf(stderr, "  warning: %s\n", ap_sim_warning(rs->sim));
}

static int start(run_state *rs, const run_opts *o) {
  char msg[1024], report[2048];
  const ap_model *m = ap_scene_model(rs->sc);
  int n = ap_model_n(m), k = ap_model_k(m), nc = ap_scene_output_count(rs->sc);
  double *q0 = calloc((size_t)(n + k + nc) + 1, sizeof *q0), *v0 = q0 ? q0 + n : NULL;
  if (!q0) return fprintf(stderr, "appell run: out of memory\n"), EXIT_INTERNAL;
  rs->buf = q0, rs->row = v0 + k;
  rs->lift = calloc((size_t)nc + 1, 1);
  if (!rs->lift) return fprintf(stderr, "appell run: out of memory\n"), EXIT_INTERNAL;
  for (int i = 0; i < nc; i++) {
    const char *name = ap_scene_output_name(rs->sc, i);
    size_t len = strlen(name), sl = strlen(".contact.Fz");
    rs->lift[i] = len > sl && strcmp(name + len - sl, ".contact.Fz") == 0;
    const char *mode = i + 2 < nc ? ap_scene_output_name(rs->sc, i + 2) : "";
    if (rs->lift[i] && strstr(mode, ".contact.mode")) rs->lift[i] = 0;   /* it does lift off */
  }
  int rc = ap_scene_initial_state(rs->sc, q0, v0, report, sizeof report, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    return cli_exit_code(rc);
  }
  if (report[0] && !o->quiet) fprintf(stderr, "appell: initial state: %s", report);
  ap_scene_get_run(rs->sc, &rs->run);
  rs->acc.estimate = o->estimate, rs->acc.accuracy = o->accuracy;
  rs->acc.control_all = o->control_all;
  cli_warn_tolerance("run", rs->run.sim.mode == AP_MODE_DAE, rs->run.sim.method,
                     rs->run.sim.rtol);
  rc = ap_sim_create(m, &rs->run.sim, rs->run.t0, q0, v0, &rs->sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_scene_add_events(rs->sc, rs->sim, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "%s: cannot start the simulation: %s: %s\n", o->scene, ap_strerror(rc), msg);
    return cli_exit_code(rc);
  }
  rc = cli_acc_control(&rs->acc, rs->sc, &rs->run, rs->sim, q0, v0);
  if (rc == AP_OK && o->accuracy > 0) {   /* the pick, then the simulation with its choice */
    if ((rc = cli_acc_pick(&rs->acc, rs->sc, &rs->run, q0, v0, o->quiet)) != AP_OK)
      return cli_exit_code(rc) == EXIT_INPUT ? EXIT_NUMERIC : cli_exit_code(rc);
    ap_sim_free(rs->sim);
    rc = ap_sim_create(m, &rs->run.sim, rs->run.t0, q0, v0, &rs->sim, msg, sizeof msg);
    if (rc == AP_OK) rc = ap_scene_add_events(rs->sc, rs->sim, msg, sizeof msg);
    if (rc == AP_OK && rs->acc.nunc) rc = ap_sim_set_uncontrolled(rs->sim, rs->acc.unc);
  }
  if (rc != AP_OK) {
    fprintf(stderr, "%s: cannot start the simulation: %s: %s\n", o->scene, ap_strerror(rc),
            ap_sim_message(rs->sim));
    return cli_exit_code(rc);
  }
  return EXIT_OK;
}

static void write_header(const ap_scene *sc, FILE *f) {
  for (int i = 0; i < ap_scene_output_count(sc); i++)
    fprintf(f, i ? ",%s" : "%s", ap_scene_output_name(sc, i));
  fputc('\n', f);
}

/* ---- the run record (tools/runrecord.c) --------------------------------------------------- */

/* With --out naming a file: OUT.run.json beside it, checked by the same rules before the run
 * (a directory or the scene there is refused). No record for standard output, a FIFO or a
 * device. */
static int check_record(cli_out *rec, const cli_out *out, const run_opts *o, char *path,
                        size_t len) {
  rec->kind = CLI_OUT_STDOUT, rec->f = NULL;
  if (out->kind != CLI_OUT_FILE) return EXIT_OK;
  if ((size_t)snprintf(path, len, "%s.run.json", o->out) >= len)
    return fprintf(stderr, "appell run: --out %s: the path is too long\n", o->out), EXIT_INPUT;
  return cli_out_check(rec, path, o->scene);
}

static void fill_record(FILE *f, const run_state *rs, const run_opts *o, int code) {
  cli_record r = {o->scene, ap_scene_name(rs->sc), o->out, o->sets, o->nsets, &rs->run,
                  ap_scene_model(rs->sc), rs->status, code, rs->error, rs->message,
                  ap_sim_time(rs->sim), rs->rows > 0 ? rs->rows : 0, rs->sim, rs->drift,
                  rs->E0, rs->wall, ap_scene_conserves_energy(rs->sc), &rs->acc};
  cli_record_write(f, &r);
}

/* Finish the CSV and the record: a run that reached t_end, failed or was interrupted keeps its
 * rows (rs->status says how it ended) and gets its record, renamed into place right after the
 * CSV; a failed write keeps nothing. Returns the exit code. */
static int finish(run_state *rs, const run_opts *o, cli_out *out, cli_out *rec, int code) {
  int keep = rs->status != NULL;
  int recorded = keep && rec->kind == CLI_OUT_FILE && cli_out_open(rec) == EXIT_OK;
  if (recorded) fill_record(rec->f, rs, o, code);
  int csv = cli_out_finish(out, code, keep);
  if (!recorded && rec->kind == CLI_OUT_FILE && keep && csv == code) {
    unlink(rec->file.path);   /* an older record must not describe these rows */
    return csv == EXIT_OK ? EXIT_INTERNAL : csv;
  }
  if (!recorded) return csv;
  int rc = cli_out_finish(rec, csv == code ? EXIT_OK : EXIT_INTERNAL, csv == code);
  if (csv == code && rc != EXIT_OK) unlink(rec->file.path);   /* as above */
  return csv != code || rc == EXIT_OK || code != EXIT_OK ? csv : rc;
}

int cmd_run(int argc, char **argv) {
  run_opts o = {0};
  int rc = parse_args(argc, argv, &o);
  if (rc != 0) return rc > 0 ? (fputs(help, stdout), print_methods(), EXIT_OK) : EXIT_INPUT;
  cli_out out, rec;
  char rec_path[AP_OUT_PATH_MAX + 16];
  int code = cli_out_check(&out, o.out, o.scene);
  if (code == EXIT_OK) code = check_record(&rec, &out, &o, rec_path, sizeof rec_path);
  if (code != EXIT_OK) return code;
  cli_signals_install();
  char msg[1024];
  run_state rs = {0};
  rs.err_path = out.kind == CLI_OUT_FILE ? o.out : NULL;
  int st = ap_scene_load(o.scene, o.sets, o.nsets, &rs.sc, msg, sizeof msg);
  if (st != AP_OK) return fprintf(stderr, "%s\n", msg), cli_exit_code(st);
  if (ap_scene_compile_notice(rs.sc)[0]) fprintf(stderr, "%s\n", ap_scene_compile_notice(rs.sc));
  code = start(&rs, &o);
  if (code == EXIT_OK && cli_interrupted())
    code = fprintf(stderr, "appell run: interrupted by %s\n", cli_signal_name(cli_interrupted())),
    EXIT_SIGNAL(cli_interrupted());
  if (code == EXIT_OK) code = cli_out_open(&out);
  if (code == EXIT_OK) {
    ap_sim_set_poll(rs.sim, poll_signal, NULL);
    rs.progress = !o.quiet && isatty(STDERR_FILENO);
    rs.quiet_events = o.quiet;
    double t_start = now();
    write_header(rs.sc, out.f);
    code = loop(&rs, &out);
    rs.wall = now() - t_start;
    cli_acc_finish(&rs.acc, rs.sc, &rs.run, rs.buf, rs.buf + ap_model_n(ap_scene_model(rs.sc)),
                   rs.status && strcmp(rs.status, CLI_STATUS_INTERRUPTED) != 0 &&
                   strcmp(rs.status, CLI_STATUS_FAILED) != 0, rs.err_path);
    code = finish(&rs, &o, &out, &rec, code);
    if (code == EXIT_OK && !o.quiet) summary(&rs, &o);
    if (code == EXIT_OK && !o.quiet) cli_acc_summary(&rs.acc, ap_scene_model(rs.sc));
    if (!o.quiet) cli_print_events(rs.sim);
  }
  free(rs.buf);
  free(rs.lift);
  cli_acc_free(&rs.acc);
  ap_sim_free(rs.sim);
  ap_scene_free(rs.sc);
  return code;
}
