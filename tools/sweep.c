/* appell sweep: many runs of one scene over grids and random samples, on a pool of threads,
 * one CSV row per run (docs/sweeps.md).
 *
 * Flow: options -> a plan (include/appell/batch.h: --grid, --random, --samples, --seed) and a
 * batch (the scene with --set and the shorthands, the channels and times) -> one check of the
 * overrides with typical values -> this shard's runs on --jobs threads -> the CSV, written
 * atomically (tools/output.c, as appell run writes). Columns: run, runs (the plan's size, so that --merge can tell
 * a complete set of shards), plan (the sweep's identity, ap_batch_plan_id, so that --merge
 * joins only shards of one sweep), each parameter's path, status, outcome and events (as in a
 * run record: tools/runrecord.c), the batch's columns, message.
 * Numbers are written with 17 significant digits, which read back to the same double.
 * The runs go a batch at a time; each batch's rows are appended to the checkpoint
 * FILE.csv.partial (flushed and synced; tools/sweep_resume.c), so memory does not depend on
 * the number of runs and --resume continues an interrupted sweep. Invariant: a file at --out
 * holds every run of its shard; an interrupted or failed sweep leaves none (only the
 * checkpoint). --merge lives in tools/sweep_merge.c. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <appell/appell.h>

#include "cli.h"
#include "runrecord.h"
#include "sweep.h"

#define MAX_ARGS 256

static const char help[] =
    "usage: appell sweep SCENE --out FILE.csv [options]\n"
    "       appell sweep --merge --out FILE.csv SHARD.csv...\n"
    "\n"
    "Run SCENE once per point of a grid or random sample of its values and write one CSV row\n"
    "per run: run, runs, plan (the sweep's identity), the parameters, status, outcome, events,\n"
    "t, steps, rhs_evals, err_fails, max_residual, energy_drift, the coordinates and speeds at\n"
    "the end (NAME@end), the channels asked for at the times asked for (CHANNEL@T), message\n"
    "(docs/sweeps.md).\n"
    "\n"
    "parameters (a product: the first grid varies slowest, random samples fastest):\n"
    "  --grid PATH=A:B:N      N values from A to B, both included (A, B may be 70*deg, pi/2)\n"
    "  --grid PATH=V1,V2,...  the values listed (numbers, expressions or words)\n"
    "  --random 'PATH=normal(MU,SIGMA)' | 'PATH=uniform(A,B)'\n"
    "                         a random value per sample (needs --samples)\n"
    "  --samples N            random samples per grid point\n"
    "  --seed S               seed of the random values (default 1); the same seed gives the\n"
    "                         same values, whatever --jobs and --shard\n"
    "each row:\n"
    "  --channel NAME         an output column of the scene (as in appell run's CSV header),\n"
    "                         sampled at the --at times (repeatable)\n"
    "  --at T1,T2,...         sample times in seconds (default: t_end)\n"
    "  --no-final             leave out the coordinates and speeds at the end\n"
    "every run:\n"
    "  --set PATH=VALUE       override a scalar of the scene (repeatable), and the shorthands\n"
    "  --mode M  --method NAME  --rtol X  --atol X  --t-end T  --interval DT  (as appell run)\n"
    "running:\n"
    "  --jobs N               threads (default 1; 0 = one per processor)\n"
    "  --shard I/N            only the I-th of N equal slices of the runs (1 <= I <= N)\n"
    "  --out FILE.csv         where the table goes (required); it appears only when complete\n"
    "  --quiet                no progress bar and no summary\n"
    "  --resume               continue an interrupted sweep from its checkpoint FILE.csv.partial\n"
    "  --merge                join shard files (same header, every run exactly once)\n"
    "\n"
    "A failed run is a row with its status (the library's code, 0 = success) and message.\n"
    "Exit codes: 0 the table was written, 2 bad input, 3 every run failed numerically,\n"
    "1 internal error or failed write, 128 + N stopped by signal N (no table then).\n";

typedef struct sweep_opts {
  const char *scene, *out;
  const char *grids[MAX_ARGS], *randoms[MAX_ARGS], *sets[MAX_ARGS + 8], *channels[MAX_ARGS];
  int ngrids, nrandoms, nsets, nchannels;
  char extra[6][128];
  double times[MAX_ARGS];
  int ntimes, quiet, final, jobs, merge, resume;
  long samples, shard_i, shard_n;
  unsigned long long seed;
  const char *inputs[MAX_ARGS];
  int ninputs;
} sweep_opts;

static int need(const char *opt) {
  return cli_need("sweep", opt, NULL);
}

static int push(const char **list, int *n, const char *v, const char *opt) {
  if (*n >= MAX_ARGS) return fprintf(stderr, "appell sweep: too many %s\n", opt), -1;
  list[(*n)++] = v;
  return 0;
}

/* --at T1,T2,...: constant expressions, none empty. */
static int parse_times(sweep_opts *o, const char *v) {
  char buf[4096], msg[512];
  if (strlen(v) >= sizeof buf) return fprintf(stderr, "appell sweep: --at: too long\n"), -1;
  snprintf(buf, sizeof buf, "%s", v);
  int item = 0;
  for (char *tok = buf, *end; tok; tok = end ? end + 1 : NULL) {
    end = strchr(tok, ',');
    if (end) *end = '\0';
    item++;
    if (tok[strspn(tok, " \t")] == '\0')
      return fprintf(stderr, "appell sweep: --at '%s': time %d is empty (expected T1,T2,... in "
                     "seconds)\n", v, item), -1;
    if (o->ntimes >= MAX_ARGS) return fprintf(stderr, "appell sweep: too many --at times\n"), -1;
    if (ap_scene_constant(tok, &o->times[o->ntimes++], msg, sizeof msg) != AP_OK)
      return fprintf(stderr, "appell sweep: --at '%s': %s\n", tok, msg), -1;
  }
  return 0;
}

static int parse_shard(sweep_opts *o, const char *v) {
  char *end = NULL;
  o->shard_i = strtol(v, &end, 10);
  if (end && *end == '/') o->shard_n = strtol(end + 1, &end, 10);
  if (!end || *end || o->shard_n < 1 || o->shard_n > 1000000 || o->shard_i < 1 ||
      o->shard_i > o->shard_n)
    return fprintf(stderr, "appell sweep: --shard: expected I/N with 1 <= I <= N, got '%s'\n",
                   v), -1;
  return 0;
}

static int parse_count(const char *opt, const char *v, long lo, long *out) {
  double x;
  if (cli_number("sweep", opt, v, &x) != 0) return -1;
  if (x != floor(x) || x < (double)lo || x > 1e15)
    return fprintf(stderr, "appell sweep: %s: expected a whole number >= %ld, got '%s'\n", opt,
                   lo, v), -1;
  *out = (long)x;
  return 0;
}

/* --samples N: 1 to 10^9, as a grid's N (the library's limit, said here before any work). */
static int parse_samples(sweep_opts *o, const char *v) {
  if (parse_count("--samples", v, 1, &o->samples) != 0) return -1;
  if (o->samples > 1000000000L)
    return fprintf(stderr, "appell sweep: --samples %s: at most 10^9 random samples per grid "
                   "point\n", v), -1;
  return 0;
}

/* Options that take a value; returns 1 when argv[*i] was one, -1 on error, 0 otherwise. */
static int value_opt(int argc, char **argv, int *i, sweep_opts *o, int *extra) {
  static const char *const mapped[][2] = {
      {"--mode", "simulation.mode"}, {"--method", "simulation.method"},
      {"--rtol", "simulation.rtol"}, {"--atol", "simulation.atol"},
      {"--t-end", "simulation.t_end"}, {"--interval", "output.interval"}};
  const char *v = NULL;
  int r;
  long x = 0;
  if ((r = cli_opt(argc, argv, i, "--out", &v)) || (r = cli_opt(argc, argv, i, "-o", &v)))
    return r < 0 ? need("--out") : (o->out = v, 1);
  if ((r = cli_opt(argc, argv, i, "--grid", &v)))
    return r < 0 ? need("--grid") : push(o->grids, &o->ngrids, v, "--grid") ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--random", &v)))
    return r < 0 ? need("--random") : push(o->randoms, &o->nrandoms, v, "--random") ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--set", &v)))
    return r < 0 ? need("--set") : push(o->sets, &o->nsets, v, "--set") ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--channel", &v)))
    return r < 0 ? need("--channel") : push(o->channels, &o->nchannels, v, "--channel") ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--at", &v))) return r < 0 ? need("--at") : parse_times(o, v) ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--shard", &v))) return r < 0 ? need("--shard") : parse_shard(o, v) ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--samples", &v)))
    return r < 0 ? need("--samples") : parse_samples(o, v) ? -1 : 1;
  if ((r = cli_opt(argc, argv, i, "--seed", &v)))
    return r < 0 ? need("--seed") : parse_count("--seed", v, 0, &x) ? -1 : (o->seed = (unsigned long long)x, 1);
  if ((r = cli_opt(argc, argv, i, "--jobs", &v)) || (r = cli_opt(argc, argv, i, "-j", &v)))
    return r < 0 ? need("--jobs") : parse_count("--jobs", v, 0, &x) ? -1 : (o->jobs = (int)(x > 256 ? 256 : x), 1);
  for (int m = 0; m < 6; m++) {
    if (!(r = cli_opt(argc, argv, i, mapped[m][0], &v))) continue;
    if (r < 0) return need(mapped[m][0]);
    double num;
    if (m >= 2 && cli_number("sweep", mapped[m][0], v, &num) != 0) return -1;
    snprintf(o->extra[m], sizeof o->extra[0], "%s=%s", mapped[m][1], v);   /* the last wins */
    *extra |= 1 << m;
    return 1;
  }
  return 0;
}

static int parse_args(int argc, char **argv, sweep_opts *o) {
  static const char *const known[] = {
      "--out", "--grid", "--random", "--samples", "--seed", "--channel", "--at", "--no-final",
      "--set", "--mode", "--method", "--rtol", "--atol", "--t-end", "--interval", "--jobs",
      "--shard", "--quiet", "--merge", "--resume", "--help", NULL};
  int extra = 0;
  for (int i = 1; i < argc; i++) {
    int r;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) return 1;
    if (strcmp(argv[i], "--quiet") == 0) o->quiet = 1;
    else if (strcmp(argv[i], "--no-final") == 0) o->final = 0;
    else if (strcmp(argv[i], "--merge") == 0) o->merge = 1;
    else if (strcmp(argv[i], "--resume") == 0) o->resume = 1;
    else if ((r = value_opt(argc, argv, &i, o, &extra)) != 0) {
      if (r < 0) return -1;
    } else if (argv[i][0] == '-' && argv[i][1]) {
      cli_unknown("sweep", argv[i], known);
      return -1;
    } else if (push(o->inputs, &o->ninputs, argv[i], "input files")) {
      return -1;
    }
  }
  for (int m = 0; m < 6; m++)   /* the shorthands win over --set, as in appell run */
    if (extra & (1 << m)) o->sets[o->nsets++] = o->extra[m];
  if (!o->out) return fprintf(stderr, "appell sweep: --out FILE.csv is required\n"), -1;
  if (o->merge) return o->ninputs ? 0 : (fprintf(stderr, "appell sweep: --merge needs shard files\n"), -1);
  if (o->ninputs != 1)
    return fprintf(stderr, "appell sweep: %s\n", o->ninputs ? "one scene at a time"
                   : "no scene file (see appell sweep --help)"), -1;
  o->scene = o->inputs[0];
  if (o->ntimes && !o->nchannels)
    return fprintf(stderr, "appell sweep: --at gives the times to sample the --channel columns "
                   "at; name at least one --channel\n"), -1;
  if (o->nrandoms && !o->samples)
    return fprintf(stderr, "appell sweep: --random needs --samples N\n"), -1;
  if (o->samples && !o->nrandoms)
    return fprintf(stderr, "appell sweep: --samples needs a --random parameter\n"), -1;
  return 0;
}

/* ---- running ---------------------------------------------------------------------------- */

typedef struct sweep_state {
  const sweep_opts *o;
  ap_plan *plan;
  ap_batch *batch;
  long first, count, total;
  double *values;
  int *status;
  char **messages;
  char **events;           /* each run's "NAME@T;..." or NULL */
  int bar;
  double t_start;
  char id[17];             /* the sweep's identity (ap_batch_plan_id), in every row */
  long base;               /* the shard row of values[0] (runs go a batch at a time) */
  long resumed;            /* rows kept from the checkpoint (--resume) */
  FILE *ck;                /* the checkpoint: OUT.partial, or a temporary file */
  char ck_path[PATH_MAX + 16];
  long failed, ran;        /* failed runs and runs made by this process */
  int first_status;        /* the first failure's status and message */
  char first_msg[512];
  long first_bad;
} sweep_state;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int on_progress(long done, long total, void *user) {
  sweep_state *s = user;
  done += s->base, total = s->count;   /* this batch's count, within the shard */
  if (s->bar) {
    double frac = total ? (double)done / (double)total : 1.0, el = now() - s->t_start;
    int w = 30, fill = (int)(frac * w + 0.5);
    fprintf(stderr, "\r[%.*s%*s] %3d%%  %ld/%ld runs", fill, "##############################",
            w - fill, "", (int)(100 * frac + 0.5), done, total);
    if (done > 0 && done < total) fprintf(stderr, ", %.0f s left ", el / (double)done * (double)(total - done));
    if (done == total) fputs("\r\033[K", stderr);
  }
  return cli_interrupted() != 0;
}

static int build_plan(sweep_state *s) {
  const sweep_opts *o = s->o;
  char msg[1024];
  if (ap_plan_create(&s->plan) != AP_OK) return fprintf(stderr, "appell sweep: out of memory\n"), EXIT_INTERNAL;
  for (int i = 0; i < o->ngrids; i++)
    if (ap_plan_add_grid(s->plan, o->grids[i], msg, sizeof msg) != AP_OK)
      return fprintf(stderr, "appell sweep: --grid %s\n", msg), EXIT_INPUT;
  for (int i = 0; i < o->nrandoms; i++)
    if (ap_plan_add_random(s->plan, o->randoms[i], msg, sizeof msg) != AP_OK)
      return fprintf(stderr, "appell sweep: --random %s\n", msg), EXIT_INPUT;
  if (o->samples && ap_plan_set_samples(s->plan, o->samples, o->seed) != AP_OK)
    return fprintf(stderr, "appell sweep: --samples: more than 2^53 runs\n"), EXIT_INPUT;
  s->total = ap_plan_count(s->plan);
  long n = o->shard_n;   /* slice i of n: [N (i-1)/n, N i/n) without overflow */
  s->first = s->total / n * (o->shard_i - 1) + s->total % n * (o->shard_i - 1) / n;
  s->count = s->total / n * o->shard_i + s->total % n * o->shard_i / n - s->first;
  return EXIT_OK;
}

static int build_batch(sweep_state *s) {
  const sweep_opts *o = s->o;
  char msg[1024];
  ap_batch_def def = ap_batch_def_default();
  def.threads = o->jobs;
  def.channels = o->channels, def.nchannels = o->nchannels;
  def.final_state = o->final;
  def.progress = on_progress, def.user = s;
  def.times = o->times, def.ntimes = o->ntimes;   /* none: t_end */
  int rc = ap_batch_load(o->scene, o->sets, o->nsets, &def, &s->batch, msg, sizeof msg);
  if (rc != AP_OK)   /* "channel 'X': ..." is about an option: name it */
    return fprintf(stderr, "%s%s\n", strncmp(msg, "channel '", 9) ? "" : "appell sweep: --",
                   msg), cli_exit_code(rc);
  rc = ap_batch_check_plan(s->batch, s->plan, msg, sizeof msg);
  if (rc != AP_OK)
    return fprintf(stderr, "appell sweep: the scene with every parameter at a typical value "
                   "(first grid value, mean): %s\n", msg), cli_exit_code(rc);
  rc = ap_batch_plan_id(s->batch, s->plan, s->id, sizeof s->id);
  return rc == AP_OK ? EXIT_OK : EXIT_INTERNAL;
}

/* The range [t0, t_end] of every run of this shard: the scene's with --set, narrowed by the
 * values a plan gives simulation.t0 or simulation.t_end. */
static int run_range(const sweep_state *s, double *t0, double *t_end) {
  const sweep_opts *o = s->o;
  char msg[1024], buf[1024];
  ap_scene *sc = NULL;
  int rc = ap_scene_load(o->scene, o->sets, o->nsets, &sc, msg, sizeof msg);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), cli_exit_code(rc);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_scene_free(sc);
  *t0 = run.t0, *t_end = run.t_end;
  for (int r = 0; r < ap_plan_nparams(s->plan); r++) {
    int is_t0 = strcmp(ap_plan_path(s->plan, r), "simulation.t0") == 0;
    if (!is_t0 && strcmp(ap_plan_path(s->plan, r), "simulation.t_end") != 0) continue;
    for (long i = s->first; i < s->first + s->count; i++) {
      double x = NAN;
      if (ap_plan_value(s->plan, i, r, &x, buf, sizeof buf) != AP_OK || isnan(x)) continue;
      if (is_t0) *t0 = fmax(*t0, x);
      else *t_end = fmin(*t_end, x);
    }
  }
  return EXIT_OK;
}

/* Every --at time inside every run's [t0, t_end] (a time outside would give rows of NaN). */
static int check_times(const sweep_state *s) {
  const sweep_opts *o = s->o;
  if (o->ntimes == 0) return EXIT_OK;
  double t0 = 0.0, t_end = 0.0;
  int code = run_range(s, &t0, &t_end);
  if (code != EXIT_OK) return code;
  double tol = 1e-12 * fmax(fabs(t0), fabs(t_end));
  for (int i = 0; i < o->ntimes; i++)
    if (!(o->times[i] >= t0 - tol && o->times[i] <= t_end + tol))
      return fprintf(stderr, "appell sweep: --at %.10g is outside the runs' time range t0 = %.10g "
                     ".. t_end = %.10g (simulation.t0, simulation.t_end%s)\n", o->times[i], t0,
                     t_end, t0 < t_end ? "" : "; the plan leaves no time common to every run"),
             EXIT_INPUT;
  return EXIT_OK;
}

/* ---- the table ---------------------------------------------------------------------------- */

static void write_header(const sweep_state *s, FILE *f) {
  fputs("run,runs,plan", f);
  for (int r = 0; r < ap_plan_nparams(s->plan); r++) fprintf(f, ",%s", ap_plan_path(s->plan, r));
  fputs(",status,outcome,events", f);
  for (int j = 0; j < ap_batch_ncols(s->batch); j++) fprintf(f, ",%s", ap_batch_col_name(s->batch, j));
  fputs(",message\n", f);
}

/* Row i of the current batch (run first + base + i). */
static void write_row(const sweep_state *s, FILE *f, long i) {
  char buf[1024];
  long run = s->first + s->base + i;
  fprintf(f, "%ld,%ld,%s", run, s->total, s->id);
  for (int r = 0; r < ap_plan_nparams(s->plan); r++) {
    double x = 0.0;
    ap_plan_value(s->plan, run, r, &x, buf, sizeof buf);
    fprintf(f, ",%s", strchr(buf, '=') + 1);
  }
  fprintf(f, ",%d", s->status[i]);
  sweep_outcome_cells(f, s->status[i], s->events[i]);
  int nc = ap_batch_ncols(s->batch);
  for (int j = 0; j < nc; j++) fprintf(f, ",%.17g", s->values[(size_t)i * (size_t)nc + (size_t)j]);
  fputc(',', f);
  sweep_csv_quote(f, s->messages[i] ? s->messages[i] : "");
  fputc('\n', f);
}

static int summary(const sweep_state *s, double wall) {
  if (!s->o->quiet) {
    fprintf(stderr, "appell sweep: %ld runs", s->count);
    if (s->o->shard_n > 1)
      fprintf(stderr, " (shard %ld/%ld: runs %ld..%ld of %ld)", s->o->shard_i, s->o->shard_n,
              s->first, s->first + s->count - 1, s->total);
    if (s->resumed) fprintf(stderr, ", %ld of them from the checkpoint,", s->resumed);
    fprintf(stderr, " in %.3f s (%.1f runs/s), %ld failed -> %s\n", wall,
            wall > 0 ? (double)s->ran / wall : 0.0, s->failed, s->o->out);
    if (s->first_bad >= 0)
      fprintf(stderr, "  first failure: run %ld: %s\n", s->first_bad,
              s->first_msg[0] ? s->first_msg : ap_strerror(s->first_status));
  }
  if (s->ran > 0 && s->failed == s->ran && !s->resumed) return cli_exit_code(s->first_status);
  return EXIT_OK;
}

/* The header line as text (to compare with a checkpoint's). */
static char *header_text(const sweep_state *s) {
  char *text = NULL;
  size_t len = 0;
  FILE *m = open_memstream(&text, &len);
  if (!m) return NULL;
  write_header(s, m);
  return fclose(m) == 0 ? text : (free(text), NULL);
}

/* The checkpoint: OUT.partial next to a regular --out (resumed with --resume), else a
 * temporary file (standard output, a device, a FIFO: no resume). */
static int open_checkpoint(sweep_state *s, const cli_out *out) {
  char *header = header_text(s);
  if (!header) return fprintf(stderr, "appell sweep: out of memory\n"), EXIT_INTERNAL;
  int code = EXIT_OK;
  if (out->kind != CLI_OUT_FILE) {
    if (s->o->resume)
      code = (fprintf(stderr, "appell sweep: --resume needs --out naming a regular file\n"),
              EXIT_INPUT);
    else if (!(s->ck = tmpfile()))
      code = (fprintf(stderr, "appell sweep: cannot make a temporary file\n"), EXIT_INTERNAL);
    else fputs(header, s->ck);
    return free(header), code;
  }
  snprintf(s->ck_path, sizeof s->ck_path, "%s.partial", out->file.path);
  if (s->o->resume) {
    s->resumed = sweep_checkpoint_rows(s->ck_path, header, s->id, s->first, s->total, s->count);
    if (s->resumed < 0) code = EXIT_INPUT;
    else s->ck = fopen(s->ck_path, "a");
  } else if (access(s->ck_path, F_OK) == 0) {
    fprintf(stderr, "appell sweep: %s exists: the checkpoint of an interrupted sweep; --resume "
            "continues it (or remove it)\n", s->ck_path);
    code = EXIT_INPUT;
  } else if ((s->ck = fopen(s->ck_path, "w"))) {
    fputs(header, s->ck);
    fflush(s->ck);   /* on disk before any run: a resume finds the sweep's header */
  }
  if (code == EXIT_OK && !s->ck)
    code = (fprintf(stderr, "appell sweep: %s: %s\n", s->ck_path, CLI_STRERROR(errno)), EXIT_INTERNAL);
  free(header);
  return code;
}

/* Rows of the batch just run: appended to the checkpoint (flushed and synced), counted. */
static int keep_batch(sweep_state *s, long n) {
  for (long i = 0; i < n; i++) {
    write_row(s, s->ck, i);
    if (s->status[i] != AP_OK && s->status[i] != AP_STOPPED && s->failed++ == 0) {
      s->first_bad = s->first + s->base + i, s->first_status = s->status[i];
      snprintf(s->first_msg, sizeof s->first_msg, "%s", s->messages[i] ? s->messages[i] : "");
    }
  }
  s->ran += n;
  ap_batch_messages_free(n, s->messages);
  ap_batch_messages_free(n, s->events);
  if (fflush(s->ck) != 0 || ferror(s->ck) || fsync(fileno(s->ck)) != 0)
    return fprintf(stderr, "appell sweep: cannot write the checkpoint %s: %s\n",
                   s->ck_path[0] ? s->ck_path : "(temporary)", CLI_STRERROR(errno)), EXIT_INTERNAL;
  return EXIT_OK;
}

/* The checkpoint's text into the table at --out (tools/output.c's rules), then removed. */
static int publish(sweep_state *s, cli_out *out) {
  int code = cli_out_open(out);
  if (code != EXIT_OK) return code;
  char buf[1 << 16];
  size_t got;
  rewind(s->ck);
  FILE *in = s->ck_path[0] ? fopen(s->ck_path, "rb") : s->ck;
  while (in && (got = fread(buf, 1, sizeof buf, in)) > 0) fwrite(buf, 1, got, out->f);
  if (!in || ferror(in)) code = EXIT_INTERNAL;
  if (in && in != s->ck) fclose(in);
  code = cli_out_close(out, code);
  if (code == EXIT_OK && s->ck_path[0]) remove(s->ck_path);
  return code;
}

/* The shard's runs a batch at a time (memory does not depend on the number of runs), each
 * batch's rows checkpointed; then the table. */
static int run_sweep(sweep_state *s, cli_out *out) {
  long nc = ap_batch_ncols(s->batch), batch = 64L * (s->o->jobs > 0 ? s->o->jobs : 8);
  s->values = malloc(sizeof *s->values * (size_t)(batch * nc + 1));
  s->status = malloc(sizeof *s->status * (size_t)batch);
  s->messages = calloc((size_t)batch, sizeof *s->messages);
  s->events = calloc((size_t)batch, sizeof *s->events);
  s->first_bad = -1;
  if (!s->values || !s->status || !s->messages || !s->events)
    return fprintf(stderr, "appell sweep: out of memory\n"), EXIT_INTERNAL;
  int code = open_checkpoint(s, out);
  s->bar = !s->o->quiet && isatty(STDERR_FILENO);
  s->t_start = now();
  for (s->base = s->resumed; code == EXIT_OK && s->base < s->count; s->base += batch) {
    long n = s->count - s->base < batch ? s->count - s->base : batch;
    int rc = ap_batch_run_plan_events(s->batch, s->plan, s->first + s->base, n, s->values,
                                      s->status, s->messages, s->events);
    int sig = cli_interrupted();
    if (rc == AP_BATCH_CANCELLED || sig) {
      ap_batch_messages_free(n, s->messages);
      ap_batch_messages_free(n, s->events);
      fprintf(stderr, "%sappell sweep: interrupted by %s; no table written%s%s%s\n",
              s->bar ? "\r\033[K" : "", cli_signal_name(sig),
              s->ck_path[0] ? "; the finished runs are in " : "", s->ck_path,
              s->ck_path[0] ? " (--resume continues)" : "");
      code = EXIT_SIGNAL(sig ? sig : SIGINT);
    } else if (rc != AP_OK) {   /* when nothing ran (row 0 not run), its message says why */
      int up_front = n > 0 && s->status[0] == AP_BATCH_NOT_RUN && s->messages[0];
      fprintf(stderr, "appell sweep: %s\n", up_front ? s->messages[0] : ap_strerror(rc));
      code = cli_exit_code(rc);
      ap_batch_messages_free(n, s->messages);
      ap_batch_messages_free(n, s->events);
    } else {
      code = keep_batch(s, n);
    }
  }
  double wall = now() - s->t_start;
  if (code == EXIT_OK) code = publish(s, out);
  return code == EXIT_OK ? summary(s, wall) : code;
}

int cmd_sweep(int argc, char **argv) {
  sweep_opts o;
  memset(&o, 0, sizeof o);
  o.final = 1, o.jobs = 1, o.seed = 1, o.shard_i = 1, o.shard_n = 1;
  int rc = parse_args(argc, argv, &o);
  if (rc != 0) return rc > 0 ? (fputs(help, stdout), EXIT_OK) : EXIT_INPUT;
  cli_out_command("sweep");
  cli_out out;
  int code = cli_out_check(&out, o.out, o.merge ? NULL : o.inputs[0]);
  if (code != EXIT_OK) return code;
  cli_signals_install();
  if (o.merge) return sweep_merge(&out, o.inputs, o.ninputs, o.quiet);
  sweep_state s;
  memset(&s, 0, sizeof s);
  s.o = &o;
  code = build_plan(&s);
  if (code == EXIT_OK) code = build_batch(&s);
  if (code == EXIT_OK) code = check_times(&s);
  if (code == EXIT_OK) code = run_sweep(&s, &out);
  if (s.ck) fclose(s.ck);
  free(s.messages);
  free(s.events);
  free(s.values);
  free(s.status);
  ap_batch_free(s.batch);
  ap_plan_free(s.plan);
  return code;
}
