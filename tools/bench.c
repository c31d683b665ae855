/* appell bench: a work-precision sweep of one scene against its own tight reference
 * (docs/cli.md, docs/performance.md; issue 6 "Work-precision").
 *
 * Flow: options -> ap_scene_load -> consistent initial state -> reference run (minimal mode,
 * fehlberg8, rtol 1e-12, atol 1e-14, checked against verner6 at the same tolerances) -> for
 * each mode and adaptive stepper, rtol = atol = tol_max, tol_max/10, ... down to tol_min: a
 * run from t0 to t_end stopping at the comparison times (--outputs N equally spaced, default
 * 10 as in bench/bench_wp.c, so that the stops do not dictate the steps); achieved error =
 * largest |q - q_ref| over those times and all coordinates; CPU time of create + run + free (runs under
 * 20 ms are repeated 5 times, the median kept) -> table on stdout, optional CSV, optional
 * gnuplot work-precision diagram. A curve stops going tighter once a run costs more than 2 s
 * of CPU; a mode/method pair the library refuses is listed once. Fixed-step methods (rk4) are not swept. DAE mode has one
 * stepper (IDA), so it gives one curve. Public API only. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <appell/appell.h>

#include "cli.h"

#define MAX_SETS 256
#define MAX_CURVES 64
#define MAX_TOLS 32
#define MAX_TIMES 100

static const char help[] =
    "usage: appell bench SCENE [options]\n"
    "\n"
    "Work-precision sweep of SCENE: runs it against its own tight reference (minimal mode,\n"
    "fehlberg8 at rtol 1e-12, atol 1e-14, checked against verner6) over the scene's t0 .. t_end\n"
    "for each mode and adaptive stepper at rtol = atol = tol-max, tol-max/10, ... tol-min, and\n"
    "prints mode, method, rtol, achieved error (largest coordinate difference from the\n"
    "reference at N equally spaced comparison times in (t0, t_end]), CPU time (create + run\n"
    "+ free), steps and evaluations.\n"
    "\n"
    "options:\n"
    "  --plot FIG.png|FIG.svg  draw error vs CPU time, one curve per mode and method (gnuplot)\n"
    "  --csv FILE.csv          also write the table as CSV\n"
    "  --outputs N             comparison times N (default 10, at most 100)\n"
    "  --tol-min X             tightest tolerance (default 1e-10)\n"
    "  --tol-max X             loosest tolerance (default 1e-3)\n"
    "  --methods a,b,..        steppers (default: every adaptive one; dae mode always uses ida)\n"
    "  --modes m,..            minimal, projected, dae (default: all three)\n"
    "  --set PATH=VALUE        override a scalar of the scene (repeatable)\n"
    "  -h, --help              this help\n"
    "\n"
    "A run that fails is listed with its message and the sweep goes on; a curve stops going\n"
    "tighter after a run that costs more than 2 s. Exit codes: 0 success,\n"
    "2 bad input, 3 the reference run failed, 1 internal error (gnuplot missing or failing).\n";

typedef struct row {
  int mode;
  const char *method;
  double rtol, err, cpu, resid;
  long steps, evals;
  int ok, created;
  char msg[200];
} row;

typedef struct bench_ctx {
  ap_scene *sc;
  const ap_model *m;
  int n, k, nt;
  double t0, times[MAX_TIMES];
  double *q0, *v0, *qref;        /* qref: nt x n */
  ap_scene_run run;
} bench_ctx;

static const char *const mode_names[] = {"minimal", "projected", "dae"};

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* One run; q at the comparison times into qout (nt x n) when given, else the error against
 * the reference into r->err. Returns the library status. */
static int one_run(bench_ctx *c, row *r, double *qout) {
  ap_sim_def def = c->run.sim;
  def.mode = (ap_mode)r->mode, def.method = r->method, def.rtol = r->rtol, def.atol = r->rtol;
  if (qout) def.atol = 1e-14;
  ap_sim *s = NULL;
  char msg[512];
  double start = cpu_now();
  int rc = ap_sim_create(c->m, &def, c->t0, c->q0, c->v0, &s, msg, sizeof msg);
  r->created = rc == AP_OK;
  if (rc != AP_OK) {
    snprintf(r->msg, sizeof r->msg, "%.150s", msg);
    return rc;
  }
  double err = 0;
  for (int i = 0; i < c->nt && rc == AP_OK; i++) {
    rc = ap_sim_advance(s, c->times[i]);
    if (rc != AP_OK) {
      snprintf(r->msg, sizeof r->msg, "t = %.6g: %.120s", ap_sim_time(s), ap_sim_message(s));
      break;
    }
    const double *q = ap_sim_q(s);
    if (qout) memcpy(qout + (size_t)i * (size_t)c->n, q, sizeof(double) * (size_t)c->n);
    else
      for (int j = 0; j < c->n; j++) {
        double d = fabs(q[j] - c->qref[(size_t)i * (size_t)c->n + (size_t)j]);
        if (!(d <= err)) err = d;   /* NaN wins */
      }
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  ap_sim_free(s);
  r->cpu = cpu_now() - start;
  r->err = err, r->steps = st.steps, r->evals = st.rhs_evals, r->resid = st.max_residual;
  return rc;
}

static int parse_list(const char *text, char *buf, size_t len, const char **items, int max) {
  snprintf(buf, len, "%s", text);
  int count = 0;
  for (char *tok = strtok(buf, ","); tok && count < max; tok = strtok(NULL, ","))
    if (*tok) items[count++] = tok;
  return count;
}

/* 1 when the curve of row i (same mode and method) has a point to plot. */
static int has_points(const row *rows, int nrows, int i) {
  for (int j = 0; j < nrows; j++)
    if (rows[j].mode == rows[i].mode && !strcmp(rows[j].method, rows[i].method) && rows[j].ok &&
        rows[j].err > 0)
      return 1;
  return 0;
}

static int plot(const char *fig, const row *rows, int nrows, const char *scene) {
  size_t len = strlen(fig);
  int svg = len > 4 && strcmp(fig + len - 4, ".svg") == 0;
  fflush(NULL);
  FILE *g = popen("gnuplot 2>&1", "w");
  if (!g) {
    fprintf(stderr, "appell bench: cannot run gnuplot (%s)\n", CLI_STRERROR(errno));
    return EXIT_INTERNAL;
  }
  fprintf(g, "set terminal %s size 900,600 noenhanced\nset output '%s'\n",
          svg ? "svg" : "pngcairo", fig);
  fprintf(g, "set logscale xy\nset grid\nset key outside right\nset format x '%%.0e'\n"
             "set xlabel 'achieved error (max |q - q_ref|)'\nset ylabel 'CPU time (s)'\n"
             "set title 'work-precision: %s'\nplot ", scene);
  int curves = 0;
  for (int i = 0; i < nrows; i++) {
    if (!has_points(rows, nrows, i) ||
        (i > 0 && rows[i].mode == rows[i - 1].mode && !strcmp(rows[i].method, rows[i - 1].method)))
      continue;
    fprintf(g, "%s'-' using 1:2 with linespoints title '%s %s'", curves ? ", " : "",
            mode_names[rows[i].mode], rows[i].method);
    curves++;
  }
  fputc('\n', g);
  for (int i = 0; i < nrows; i++) {
    if (!has_points(rows, nrows, i)) continue;
    if (rows[i].ok && rows[i].err > 0) fprintf(g, "%.6e %.6e\n", rows[i].err, rows[i].cpu);
    int last = i + 1 == nrows || rows[i + 1].mode != rows[i].mode ||
               strcmp(rows[i + 1].method, rows[i].method);
    if (last) fputs("e\n", g);
  }
  int st = pclose(g);
  if (st != 0) {
    fprintf(stderr, "appell bench: gnuplot failed or is missing (install gnuplot-nox)\n");
    return EXIT_INTERNAL;
  }
  return EXIT_OK;
}

int cmd_bench(int argc, char **argv) {
  static const char *const known[] = {"--plot", "--csv", "--outputs", "--tol-min", "--tol-max", "--methods",
                                      "--modes", "--set", "--help", NULL};
  const char *scene = NULL, *fig = NULL, *csv = NULL, *methods_arg = NULL, *modes_arg = NULL;
  const char *sets[MAX_SETS];
  int nsets = 0;
  double tol_min = 1e-10, tol_max = 1e-3, outputs = 10;
  for (int i = 1; i < argc; i++) {
    const char *val = NULL;
    int r;
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return fputs(help, stdout), EXIT_OK;
    if ((r = cli_opt(argc, argv, &i, "--plot", &val))) fig = val;
    else if ((r = cli_opt(argc, argv, &i, "--csv", &val))) csv = val;
    else if ((r = cli_opt(argc, argv, &i, "--methods", &val))) methods_arg = val;
    else if ((r = cli_opt(argc, argv, &i, "--modes", &val))) modes_arg = val;
    else if ((r = cli_opt(argc, argv, &i, "--set", &val))) {
      if (r > 0 && nsets < MAX_SETS) sets[nsets++] = val;
    } else if ((r = cli_opt(argc, argv, &i, "--outputs", &val))) {
      if (r > 0 && cli_number("bench", "--outputs", val, &outputs)) return EXIT_INPUT;
    } else if ((r = cli_opt(argc, argv, &i, "--tol-min", &val))) {
      if (r > 0 && cli_number("bench", "--tol-min", val, &tol_min)) return EXIT_INPUT;
    } else if ((r = cli_opt(argc, argv, &i, "--tol-max", &val))) {
      if (r > 0 && cli_number("bench", "--tol-max", val, &tol_max)) return EXIT_INPUT;
    } else if (argv[i][0] == '-' && argv[i][1] != '\0') return cli_unknown("bench", argv[i], known);
    else if (!scene) scene = argv[i];
    else return fprintf(stderr, "appell bench: more than one scene ('%s')\n", argv[i]), EXIT_INPUT;
    if (r < 0) return cli_need("bench", argv[i], NULL), EXIT_INPUT;
  }
  if (!scene) return fprintf(stderr, "appell bench: no scene file (see appell bench --help)\n"),
               EXIT_INPUT;
  if (!(outputs >= 1 && outputs <= MAX_TIMES))
    return fprintf(stderr, "appell bench: --outputs must be 1 .. %d\n", MAX_TIMES), EXIT_INPUT;
  if (!(tol_min > 0) || !(tol_max >= tol_min) || tol_max >= 1)
    return fprintf(stderr, "appell bench: need 0 < --tol-min <= --tol-max < 1\n"), EXIT_INPUT;

  /* modes and methods */
  char mbuf[512], sbuf[512];
  const char *mlist[MAX_CURVES], *slist[8];
  int nm = 0, ns = 0;
  if (methods_arg) {
    nm = parse_list(methods_arg, mbuf, sizeof mbuf, mlist, MAX_CURVES);
    for (int i = 0; i < nm; i++) {
      ap_method_info info;
      if (ap_method_find(mlist[i], &info) != AP_OK)
        return fprintf(stderr, "appell bench: --methods: unknown method '%s'\n", mlist[i]),
               EXIT_INPUT;
      if (!info.adaptive)
        return fprintf(stderr, "appell bench: --methods: '%s' has a fixed step; only adaptive "
                               "methods are swept over tolerances\n", mlist[i]), EXIT_INPUT;
    }
  } else {
    static ap_method_info all[MAX_CURVES];
    for (int i = 0; i < ap_method_count() && nm < MAX_CURVES; i++)
      if (ap_method_get(i, &all[nm]) == AP_OK && all[nm].adaptive) mlist[nm] = all[nm].name, nm++;
  }
  int modes[3], nmodes = 0;
  ns = parse_list(modes_arg ? modes_arg : "minimal,projected,dae", sbuf, sizeof sbuf, slist, 8);
  for (int i = 0; i < ns; i++) {
    int found = -1;
    for (int j = 0; j < 3; j++)
      if (!strcmp(slist[i], mode_names[j])) found = j;
    if (found < 0)
      return fprintf(stderr, "appell bench: --modes: unknown mode '%s' (minimal, projected, "
                             "dae)\n", slist[i]), EXIT_INPUT;
    if (nmodes < 3) modes[nmodes++] = found;
  }

  /* scene, initial state, comparison times */
  bench_ctx c;
  memset(&c, 0, sizeof c);
  char msg[1024], report[2048];
  int rc = ap_scene_load(scene, sets, nsets, &c.sc, msg, sizeof msg);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), cli_exit_code(rc);
  c.m = ap_scene_model(c.sc);
  c.n = ap_model_n(c.m), c.k = ap_model_k(c.m);
  ap_scene_get_run(c.sc, &c.run);
  c.t0 = c.run.t0;
  double span = c.run.t_end - c.run.t0;
  int nt = (int)outputs;
  c.nt = nt;
  for (int i = 0; i < nt; i++) c.times[i] = i + 1 == nt ? c.run.t_end : c.t0 + span * (i + 1) / nt;
  c.q0 = calloc((size_t)c.n, sizeof(double));
  c.v0 = calloc((size_t)c.k + 1, sizeof(double));
  c.qref = calloc((size_t)nt * (size_t)c.n, sizeof(double));
  double *qchk = calloc((size_t)nt * (size_t)c.n, sizeof(double));
  row *rows = calloc((size_t)nmodes * (size_t)(nm + 1) * MAX_TOLS, sizeof(row));
  int code = EXIT_OK, nrows = 0;
  if (!c.q0 || !c.v0 || !c.qref || !qchk || !rows) {
    fprintf(stderr, "appell bench: out of memory\n");
    code = EXIT_INTERNAL;
    goto done;
  }
  rc = ap_scene_initial_state(c.sc, c.q0, c.v0, report, sizeof report, msg, sizeof msg);
  if (rc != AP_OK) {
    fprintf(stderr, "%s\n", msg);
    code = cli_exit_code(rc);
    goto done;
  }

  /* reference, and its check */
  row ref = {0}, chk = {0};
  ref.mode = AP_MODE_MINIMAL, ref.method = "fehlberg8", ref.rtol = 1e-12;
  chk = ref, chk.method = "verner6";
  rc = one_run(&c, &ref, c.qref);
  if (rc != AP_OK) {
    fprintf(stderr, "appell bench: the reference run (minimal, fehlberg8, rtol 1e-12) failed: "
                    "%s\n", ref.msg);
    code = EXIT_NUMERIC;
    goto done;
  }
  double refdiff = 0;
  if (one_run(&c, &chk, qchk) == AP_OK)
    for (size_t i = 0; i < (size_t)nt * (size_t)c.n; i++)
      if (!(fabs(qchk[i] - c.qref[i]) <= refdiff)) refdiff = fabs(qchk[i] - c.qref[i]);
  printf("appell bench: %s: t = %g .. %g, n %d, k %d, b %d; errors at %d times\n",
         ap_scene_name(c.sc), c.t0, c.run.t_end, c.n, c.k, ap_model_b(c.m), nt);
  printf("reference: minimal fehlberg8, rtol 1e-12, atol 1e-14: %ld steps, %.3g s CPU; "
         "verner6 at the same tolerances differs by %.2e", ref.steps, ref.cpu, refdiff);
  printf(chk.msg[0] ? " (verner6 failed: %s)\n" : "%s\n", chk.msg);
  printf("\n%-9s %-9s %7s %10s %10s %8s %9s  %s\n", "mode", "method", "rtol", "error", "cpu_ms",
         "steps", "evals", "note");

  const double max_cpu = 2.0;
  int ntol = 0;
  double tols[MAX_TOLS];
  for (double t = tol_max; t >= tol_min * (1 - 1e-9) && ntol < MAX_TOLS; t /= 10) tols[ntol++] = t;
  for (int a = 0; a < nmodes; a++) {
    int mcount = modes[a] == AP_MODE_DAE ? 1 : nm;
    for (int b = 0; b < mcount; b++) {
      const char *method = modes[a] == AP_MODE_DAE ? "ida" : mlist[b];
      for (int t = 0; t < ntol; t++) {
        row *r = &rows[nrows++];
        r->mode = modes[a], r->method = method, r->rtol = tols[t];
        int st = one_run(&c, r, NULL);
        r->ok = st == AP_OK;
        if (r->ok && r->cpu < 0.02) {   /* short: median of 5 */
          double cpu[5] = {r->cpu};
          for (int rep = 1; rep < 5; rep++) one_run(&c, r, NULL), cpu[rep] = r->cpu;
          qsort(cpu, 5, sizeof *cpu, cmp_double);
          r->cpu = cpu[2];
        }
        if (!r->ok && !r->created) {   /* refused (e.g. adams in projected mode): once */
          printf("%-9s %-9s %7s %10s %10s %8s %9s  refused: %s\n", mode_names[r->mode],
                 r->method, "all", "-", "-", "-", "-", r->msg);
          break;
        }
        if (r->ok)
          printf("%-9s %-9s %7.0e %10.3e %10.3f %8ld %9ld\n", mode_names[r->mode], r->method,
                 r->rtol, r->err, 1e3 * r->cpu, r->steps, r->evals);
        else
          printf("%-9s %-9s %7.0e %10s %10s %8s %9s  failed: %s\n", mode_names[r->mode],
                 r->method, r->rtol, "-", "-", "-", "-", r->msg);
        fflush(stdout);
        if (r->cpu > max_cpu) break;   /* tighter would cost more still */
      }
    }
  }
  if (csv) {
    FILE *f = fopen(csv, "w");
    if (!f) {
      fprintf(stderr, "appell bench: cannot write %s: %s\n", csv, CLI_STRERROR(errno));
      code = EXIT_INTERNAL;
      goto done;
    }
    fprintf(f, "mode,method,rtol,error,cpu_s,steps,evals,max_residual,ok\n");
    for (int i = 0; i < nrows; i++)
      fprintf(f, "%s,%s,%.0e,%.6e,%.6e,%ld,%ld,%.3e,%d\n", mode_names[rows[i].mode],
              rows[i].method, rows[i].rtol, rows[i].err, rows[i].cpu, rows[i].steps,
              rows[i].evals, rows[i].resid, rows[i].ok);
    if (fclose(f) != 0) code = EXIT_INTERNAL;
  }
  if (fig && code == EXIT_OK) code = plot(fig, rows, nrows, ap_scene_name(c.sc));

done:
  free(c.q0), free(c.v0), free(c.qref), free(qchk), free(rows);
  ap_scene_free(c.sc);
  return code;
}
