/* bench_wp: work-precision sweep of Appell on the reference problems with exact answers
 * (docs/references.md: knife edge, Chaplygin sleigh, ball on a turntable at constant and at
 * time-varying Omega, particle on a rotating line in its 3-D form with rheonomic rows) and on
 * the rolling disk (a body-layer model: disk on a plane-contact joint, rolling, gravity), side
 * by side with "the limit": each problem's hand-reduced closed-form ODE integrated by exactly
 * the same SUNDIALS stepper (lib/integrate/stepper.h), measured in the same run.
 *
 * The disk has no closed form: its reference positions come from its hand-reduced ODE at
 * rtol = atol = 1e-14 (fehlberg8), and Appell's minimal and DAE modes at tight tolerances are
 * checked against them (the difference is printed: it bounds how far the reference can be
 * trusted).
 *
 * For every problem, every Appell mode (minimal, projected, DAE) and every stepper (bs3,
 * dopri5, verner6, fehlberg8, dop853, adams, bdf at rtol = atol = 1e-3 ... 1e-12; rk4 over fixed steps
 * T / (10 m), m = 2, 4, ..., 4096) one run integrates from t = 0 to T, stopping exactly at
 * NOUT = 10 equally spaced output times, and records
 *   err    the largest position error (m) over the outputs against the exact solution
 *          (max-norm of the contact point / centre / bead position),
 *   cpu    CPU time (CLOCK_PROCESS_CPUTIME_ID) of create + integrate + free, median over
 *          repeats (runs under 50 ms are repeated after an untimed warm-up),
 *   steps, rhs evaluations, error-test failures, and the largest |A v + a0| at step ends.
 * A curve stops going tighter once one run costs more than --budget seconds (default 0.4),
 * reaches 1e-13, or fails three times in a row; a run fails after 20000 steps between
 * outputs.
 *
 * Writes one CSV row per run (--csv) and the problem descriptions with the exact positions at
 * the output times (--describe), which the peers (bench/peers/) read so that every tool
 * integrates the same problem from the same state and is scored against the same numbers.
 * Ratios at equal achieved error are computed from the CSV by bench/plot/report.py.
 *
 * --compiled sweeps only the turntables' body-built ball switched once to compiled kinematics
 * (ap_model_compile_native, docs/compiled.md; tool "appell_body_c"); the compile's wall time is
 * printed apart and is in no run's time.
 *
 * Usage: bench_wp [--csv FILE] [--describe FILE] [--problems a,b] [--budget S] [--quick]
 *                 [--compiled]
 *        bench_wp --one PROBLEM TOOL MODE METHOD TOL_OR_H [--reps N]   (for callgrind)
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bodysys.h"
#include "wp.h"

/* ---- runs --------------------------------------------------------------------------------- */

typedef struct wp_run {
  const char *tool;         /* "appell" or "hand" */
  const char *mode;         /* "minimal", "projected", "dae"; "reduced" for hand */
  const char *method;       /* stepper name; "ida" in DAE mode */
  double tol;               /* rtol = atol (adaptive), 0 for fixed step */
  double h;                 /* fixed step (rk4), 0 for adaptive */
} wp_run;

typedef struct wp_result {
  int status;
  double err;               /* max position error over the outputs (m) */
  long steps, evals, fails;
  double resid;             /* largest |A v + a0| at step ends (Appell) */
  double cpu, lo, hi;       /* CPU seconds: median, min, max */
  int reps;
  char msg[200];
} wp_result;

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double pos_err(const wp_problem *pr, int i, const double *pos) {
  double e = 0.0;
  for (int c = 0; c < pr->npos; c++) e = fmax(e, fabs(pos[c] - pr->epos[i][c]));
  return isfinite(e) ? e : INFINITY;
}

/* One Appell run: create the simulation, advance through the outputs, free. */
static int run_appell(const wp_problem *pr, const ap_model *m, const wp_run *r, wp_result *res) {
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = !strncmp(r->mode, "minimal", 7) ? AP_MODE_MINIMAL
            : !strcmp(r->mode, "projected") ? AP_MODE_PROJECTED : AP_MODE_DAE;
  sd.method = r->method;
  if (r->h > 0) sd.h_fixed = r->h;
  else sd.rtol = sd.atol = r->tol;
  sd.max_steps = WP_MAX_STEPS;
  ap_sim *s = NULL;
  int body = !strncmp(r->tool, "appell_body", 11), fl[MAXS] = {0};
  if (body) m = strcmp(r->tool, "appell_body_c") ? pr->ball_model : pr->ball_compiled;
  int rc = ap_sim_create(m, &sd, 0.0, body ? pr->bq0 : pr->q0, pr->v0, &s, res->msg,
                         sizeof res->msg);
  if (rc != AP_OK) return rc;
  if (body && !strcmp(r->mode, "minimal_free")) {   /* appell run's default error control */
    rc = ap_sim_free_coordinates(s, fl);
    if (rc == AP_OK) rc = ap_sim_set_uncontrolled(s, fl);
  }
  double err = 0.0, pos[3];
  for (int i = 0; i < NOUT && rc == AP_OK; i++) {
    double t = pr->T * (i + 1) / NOUT;
    rc = ap_sim_advance(s, t);
    if (rc != AP_OK) {
      snprintf(res->msg, sizeof res->msg, "%s", ap_sim_message(s));
      break;
    }
    pr->pos_q(pr, t, ap_sim_q(s), pos);
    err = fmax(err, pos_err(pr, i, pos));
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  res->err = err, res->steps = st.steps, res->evals = st.rhs_evals, res->fails = st.err_fails;
  res->resid = st.max_residual;
  ap_sim_free(s);
  return rc;
}

/* One run of the hand-reduced ODE under the same stepper. */
static int run_hand(const wp_problem *pr, const wp_run *r, wp_result *res) {
  const ap_step_method *meth = ap_step_method_find(r->method);
  if (!meth) return AP_ERR_ARG;
  ap_step_opts o;
  memset(&o, 0, sizeof o);
  if (r->h > 0) o.h_fixed = r->h;
  else o.rtol = o.atol = r->tol;
  o.max_steps = WP_MAX_STEPS;
  ap_stepper *st = NULL;
  double y[MAXS], t = 0.0, err = 0.0, pos[3];
  int rc = ap_step_create(meth, pr->hn, pr->hand, (void *)pr, 0.0, pr->hy0, &o, &st, res->msg,
                          sizeof res->msg);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < NOUT && rc == AP_OK; i++) {
    double tout = pr->T * (i + 1) / NOUT;
    while (t < tout && rc == AP_OK) rc = ap_step_one(st, tout, &t, y);
    if (rc != AP_OK) {
      snprintf(res->msg, sizeof res->msg, "%s", ap_step_message(st));
      break;
    }
    pr->pos_hand(pr, tout, y, pos);
    err = fmax(err, pos_err(pr, i, pos));
  }
  ap_step_stats ss;
  ap_step_get_stats(st, &ss);
  res->err = err, res->steps = ss.steps, res->evals = ss.rhs_evals, res->fails = ss.err_fails;
  res->resid = 0.0;
  ap_step_free(st);
  return rc;
}

static int run_once(const wp_problem *pr, const ap_model *m, const wp_run *r, wp_result *res) {
  return !strcmp(r->tool, "hand") ? run_hand(pr, r, res) : run_appell(pr, m, r, res);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Time one configuration: a first timed run; runs under 50 ms are repeated (the first one
 * then counts as warm-up) until about 0.15 s is spent, at least 3 and at most 15 times.
 * Kept out of line: scripts/bench --callgrind collects inside it (--toggle-collect). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static void measure(const wp_problem *pr, const ap_model *m, const wp_run *r, int min_reps,
                    wp_result *res) {
  double ts[64];
  memset(res, 0, sizeof *res);
  double t0 = cpu_now();
  res->status = run_once(pr, m, r, res);
  ts[0] = cpu_now() - t0;
  int n = 1, first = 0;
  if (res->status == AP_OK && (ts[0] < 0.05 || min_reps > 1)) {
    int reps = ts[0] > 0 ? (int)(0.15 / ts[0]) : 15;
    reps = reps < 3 ? 3 : reps > 15 ? 15 : reps;
    if (min_reps > reps) reps = min_reps > 63 ? 63 : min_reps;
    if (ts[0] < 0.05) first = 1;          /* drop the warm-up */
    for (; n < 1 + reps; n++) {
      wp_result tmp;
      memset(&tmp, 0, sizeof tmp);
      t0 = cpu_now();
      run_once(pr, m, r, &tmp);
      ts[n] = cpu_now() - t0;
    }
  }
  qsort(ts + first, (size_t)(n - first), sizeof(double), cmp_double);
  res->reps = n - first;
  res->cpu = ts[first + (n - first) / 2];
  res->lo = ts[first];
  res->hi = ts[n - 1];
}

/* ---- the sweep ------------------------------------------------------------------------------ */

static const char *const adaptive_methods[] = {"bs3", "dopri5", "verner6", "fehlberg8",
                                               "dop853", "adams", "bdf"};
#define NADAPT 7
#define NTOL 10     /* 1e-3 ... 1e-12 */
#define NFIX 12     /* rk4: h = T / (NOUT m), m = 2 ... 4096 */

static void print_row(FILE *out, const wp_problem *pr, const wp_run *r, const wp_result *res) {
  if (!out) return;
  fprintf(out, "%s,%s,%s,%s,%.3g,%.6g,%d,%.6e,%.6e,%.6e,%.6e,%d,%ld,%ld,%ld,%.4f,%.3e\n",
          pr->name, r->tool, r->mode, r->method, r->tol, r->h, res->status, res->err, res->cpu,
          res->lo, res->hi, res->reps, res->steps, res->evals, res->fails,
          res->evals > 0 ? 1e6 * res->cpu / res->evals : 0.0, res->resid);
  fflush(out);
}

/* One curve: tightening tolerances (or halving steps) until a run costs more than budget,
 * the error reaches 1e-13, or runs fail at three settings in a row (loose settings may fail
 * where tight ones work: the disk tips over flat in an oversized trial step). */
static void sweep_curve(FILE *out, const wp_problem *pr, const ap_model *m, wp_run r,
                        double budget, int quick) {
  int npts = r.h > 0 || !strcmp(r.method, "rk4") ? NFIX : NTOL, fails = 0;
  for (int i = 0; i < npts; i += quick ? 3 : 1) {
    if (!strcmp(r.method, "rk4")) r.h = pr->T / (NOUT * (double)(2 << i)), r.tol = 0.0;
    else r.tol = pow(10.0, -3 - i);
    wp_result res;
    measure(pr, m, &r, 1, &res);
    print_row(out, pr, &r, &res);
    printf("  %-9s %-6s %-10s %-9s %8.1e %8.2e %9.3e s %4d %8ld %9ld %6.3f us/eval%s%s\n",
           pr->name, r.tool, r.mode, r.method, r.h > 0 ? r.h : r.tol, res.err, res.cpu,
           res.reps, res.steps, res.evals, res.evals ? 1e6 * res.cpu / res.evals : 0.0,
           res.status ? "  FAILED: " : "", res.status ? res.msg : "");
    fflush(stdout);
    if (res.status != AP_OK && res.steps == 0) break;   /* refused (e.g. unsupported mode) */
    fails = res.status != AP_OK ? fails + 1 : 0;
    if (fails >= 3 || res.cpu > budget || (res.status == AP_OK && res.err < 1e-13)) break;
  }
}

/* The disk's reference confirmed by Appell: minimal mode (fehlberg8, 1e-13) and DAE mode
 * (IDA, 1e-10) against it, and the energy drift of the minimal run (rolling does no work). */
static void disk_check(const wp_problem *pr, const ap_model *m) {
  static const char *const modes[] = {"minimal", "dae"};
  for (int i = 0; i < 2; i++) {
    wp_run r = {"appell", modes[i], i ? "ida" : "fehlberg8", i ? 1e-10 : 1e-13, 0};
    wp_result res;
    memset(&res, 0, sizeof res);
    int rc = run_appell(pr, m, &r, &res);
    printf("  reference check: Appell %s %s rtol %.0e: max |centre - reference| = %.2e m%s%s\n",
           r.mode, r.method, r.tol, res.err, rc ? ", FAILED: " : "", rc ? res.msg : "");
  }
  ap_sim_def sd = ap_sim_def_default();
  sd.method = "fehlberg8", sd.rtol = sd.atol = 1e-13;
  ap_sim *s = NULL;
  double T0, V0, T1, V1;
  if (ap_sim_create(m, &sd, 0.0, pr->q0, pr->v0, &s, NULL, 0) != AP_OK) return;
  ap_data *d = (ap_data *)ap_sim_data(s);
  int ok = ap_body_energy(m, d, &T0, &V0) == AP_OK && ap_sim_advance(s, pr->T) == AP_OK &&
           ap_body_energy(m, d, &T1, &V1) == AP_OK;
  if (ok)
    printf("  reference check: energy %.15g J at t = 0, drift %.2e J at t = %g\n", T0 + V0,
           T1 + V1 - T0 - V0, pr->T);
  ap_sim_free(s);
}

/* --compiled: the ball's two error controls over the explicit steppers, compiled kinematics. */
static void sweep_compiled(FILE *out, const wp_problem *pr, double budget, int quick) {
  static const char *const body_modes[] = {"minimal", "minimal_free"};
  printf("%s: %s, T = %g s, body ball with compiled kinematics\n", pr->name, pr->title, pr->T);
  for (int md = 0; md < 2; md++)
    for (int j = 0; j < NADAPT - 2; j++) {   /* adams and bdf are the last two */
      wp_run r = {"appell_body_c", body_modes[md], adaptive_methods[j], 0, 0};
      sweep_curve(out, pr, NULL, r, budget, quick);
    }
}

/* The turntables' second ball, compiled once before any timed run; 0 or 1 on failure. */
static int compile_balls(wp_problem *P) {
  for (int i = 0; i < NPROB; i++) {
    if (!P[i].ball_model || P[i].ball_compiled) continue;
    char notice[256] = "";
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    P[i].ball_compiled = bs_turntable_model(&P[i].p.turn);
    int rc = P[i].ball_compiled ? ap_model_compile_native(P[i].ball_compiled, AP_COMPILE_ALWAYS,
                                                          notice, sizeof notice) : 0;
    clock_gettime(CLOCK_MONOTONIC, &b);
    if (rc != 1) {
      fprintf(stderr, "bench_wp: %s: the body ball does not compile: %s\n", P[i].name,
              notice[0] ? notice : "model not built");
      return 1;
    }
    printf("%s: body ball built and compiled in %.1f ms wall (cc, or the cache)%s%s\n",
           P[i].name, 1e3 * (b.tv_sec - a.tv_sec) + 1e-6 * (b.tv_nsec - a.tv_nsec),
           notice[0] ? ": " : "", notice);
  }
  return 0;
}

static void sweep_problem(FILE *out, const wp_problem *pr, double budget, int quick) {
  ap_model *m = NULL;
  char msg[256];
  double t0 = cpu_now();
  if (pr->body_model) m = pr->body_model;
  else if (ap_model_from_system(&pr->def, &m, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "bench_wp: %s: %s\n", pr->name, msg);
    exit(1);
  }
  if (pr->body_model) printf("%s: %s, T = %g s\n", pr->name, pr->title, pr->T);
  else
    printf("%s: %s, T = %g s, model compiled in %.1f us\n", pr->name, pr->title, pr->T,
           1e6 * (cpu_now() - t0));
  if (pr->body_model) disk_check(pr, m);
  static const char *const modes[] = {"minimal", "projected"};
  for (int md = 0; md < 2; md++) {
    for (int j = 0; j <= NADAPT; j++) {
      wp_run r = {"appell", modes[md], j < NADAPT ? adaptive_methods[j] : "rk4", 0, 0};
      sweep_curve(out, pr, m, r, budget, quick);
    }
  }
  wp_run dae = {"appell", "dae", "ida", 0, 0};
  sweep_curve(out, pr, m, dae, budget, quick);
  /* The turntables' ball built from bodies: every coordinate error-controlled, and with the
   * orientation (which nothing depends on) left out, as appell run does (docs/accuracy.md). */
  static const char *const body_modes[] = {"minimal", "minimal_free"};
  for (int md = 0; pr->ball_model && md < 2; md++)
    for (int j = 0; j < NADAPT; j++) {
      if (!strcmp(adaptive_methods[j], "adams") || !strcmp(adaptive_methods[j], "bdf")) continue;
      wp_run r = {"appell_body", body_modes[md], adaptive_methods[j], 0, 0};
      sweep_curve(out, pr, m, r, budget, quick);
    }
  for (int j = 0; j <= NADAPT; j++) {
    wp_run r = {"hand", "reduced", j < NADAPT ? adaptive_methods[j] : "rk4", 0, 0};
    sweep_curve(out, pr, m, r, budget, quick);
  }
  if (!pr->body_model) ap_model_free(m);
}

/* ---- problem descriptions for the peers ------------------------------------------------------ */

static void describe(FILE *f, const wp_problem *P) {
  fprintf(f, "# bench_wp problem descriptions: name key values...; exact rows: t pos...\n");
  for (int i = 0; i < NPROB; i++) {
    const wp_problem *pr = &P[i];
    fprintf(f, "%s T %.17g\n%s nout %d\n%s npos %d\n", pr->name, pr->T, pr->name, NOUT,
            pr->name, pr->npos);
    switch (i) {
      case 0:
        fprintf(f, "%s param m %.17g J %.17g grav %.17g alpha %.17g\n", pr->name,
                pr->p.knife.m, pr->p.knife.J, pr->p.knife.grav, pr->p.knife.alpha);
        break;
      case 1:
        fprintf(f, "%s param m %.17g I %.17g a %.17g\n", pr->name, pr->p.sleigh.m,
                pr->p.sleigh.I, pr->p.sleigh.a);
        break;
      case 2:
      case 3:
        fprintf(f, "%s param m %.17g R %.17g kI %.17g Omega0 %.17g dOmega %.17g\n", pr->name,
                pr->p.turn.m, pr->p.turn.R, pr->p.turn.kI, pr->p.turn.Omega0, pr->p.turn.dOmega);
        break;
      case 4:
        fprintf(f, "%s param m %.17g grav %.17g alpha %.17g w %.17g\n", pr->name,
                pr->p.line.m, pr->p.line.grav, pr->p.line.alpha, pr->p.line.w);
        break;
      default:
        fprintf(f, "%s param m %.17g r %.17g grav %.17g\n", pr->name, pr->p.disk.m,
                pr->p.disk.r, pr->p.disk.grav);
        fprintf(f, "%s euler", pr->name);   /* x y psi theta w1 w2 w3, see disk_hand */
        for (int c = 0; c < 7; c++) fprintf(f, " %.17g", pr->euler[c]);
        fprintf(f, "\n");
        break;
    }
    fprintf(f, "%s q0", pr->name);
    for (int c = 0; c < pr->n; c++) fprintf(f, " %.17g", pr->q0[c]);
    fprintf(f, "\n%s v0", pr->name);
    for (int c = 0; c < pr->k; c++) fprintf(f, " %.17g", pr->v0[c]);
    fprintf(f, "\n");
    for (int j = 0; j < NOUT; j++) {
      fprintf(f, "%s exact %.17g", pr->name, pr->T * (j + 1) / NOUT);
      for (int c = 0; c < pr->npos; c++) fprintf(f, " %.17g", pr->epos[j][c]);
      fprintf(f, "\n");
    }
  }
}

/* ---- main ------------------------------------------------------------------------------------ */

static int usage(void) {
  fprintf(stderr, "usage: bench_wp [--csv FILE] [--describe FILE] [--problems a,b,...] "
                  "[--budget S] [--quick] [--compiled]\n"
                  "       bench_wp --one PROBLEM appell|appell_body|appell_body_c|hand MODE "
                  "METHOD TOL_OR_H [--reps N]\n");
  return 2;
}

static int in_list(const char *list, const char *name) {
  if (!list) return 1;
  size_t n = strlen(name);
  for (const char *p = strstr(list, name); p; p = strstr(p + 1, name))
    if ((p == list || p[-1] == ',') && (p[n] == ',' || p[n] == '\0')) return 1;
  return 0;
}

/* --one: a single configuration repeated reps times (for callgrind and perf). */
static int run_one(const wp_problem *P, char **a, int reps) {
  for (int i = 0; i < NPROB; i++) {
    if (strcmp(P[i].name, a[0])) continue;
    wp_run r = {a[1], a[2], a[3], 0, 0};
    if (!strcmp(a[3], "rk4")) r.h = atof(a[4]);
    else r.tol = atof(a[4]);
    ap_model *m = P[i].body_model;
    if (!m && ap_model_from_system(&P[i].def, &m, NULL, 0) != AP_OK) return 1;
    wp_result res;
    measure(&P[i], m, &r, reps, &res);
    printf("%s %s %s %s: err %.3e, median %.4e s over %d, %ld steps, %ld evals, "
           "%.3f us/eval%s%s\n", a[0], a[1], a[2], a[3], res.err, res.cpu, res.reps, res.steps,
           res.evals, res.evals ? 1e6 * res.cpu / res.evals : 0.0,
           res.status ? ", FAILED: " : "", res.status ? res.msg : "");
    if (m != P[i].body_model) ap_model_free(m);
    return res.status != AP_OK;
  }
  fprintf(stderr, "bench_wp: no problem '%s'\n", a[0]);
  return 2;
}

int main(int argc, char **argv) {
  static wp_problem P[NPROB];
  const char *csv = NULL, *desc = NULL, *list = NULL;
  char **one = NULL;
  double budget = 0.4;
  int quick = 0, reps = 1, compiled = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--describe") && i + 1 < argc) desc = argv[++i];
    else if (!strcmp(argv[i], "--problems") && i + 1 < argc) list = argv[++i];
    else if (!strcmp(argv[i], "--budget") && i + 1 < argc) budget = atof(argv[++i]);
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--quick")) quick = 1;
    else if (!strcmp(argv[i], "--compiled")) compiled = 1;
    else if (!strcmp(argv[i], "--one") && i + 5 < argc) one = argv + i + 1, i += 5;
    else return usage();
  }
  if (!(budget > 0) || reps < 1) return usage();
  setup_problems(P);
  if ((compiled || (one && !strcmp(one[1], "appell_body_c"))) && compile_balls(P)) {
    free_problems(P);
    return 1;
  }
  if (one) {
    int rc = run_one(P, one, reps);
    free_problems(P);
    return rc;
  }
  if (desc) {
    FILE *f = fopen(desc, "w");
    if (!f) {
      fprintf(stderr, "bench_wp: cannot write %s\n", desc);
      return 1;
    }
    describe(f, P);
    fclose(f);
  }
  FILE *out = NULL;
  if (csv && !(out = fopen(csv, "w"))) {
    fprintf(stderr, "bench_wp: cannot write %s\n", csv);
    return 1;
  }
  if (out)
    fprintf(out, "problem,tool,mode,method,tol,h,status,err,cpu_s,cpu_lo,cpu_hi,reps,steps,"
                 "rhs_evals,err_fails,us_per_eval,residual\n");
  printf("  %-9s %-6s %-10s %-9s %8s %8s %11s %4s %8s %9s %s\n", "problem", "tool", "mode",
         "method", "tol/h", "err", "cpu", "reps", "steps", "evals", "cost");
  for (int i = 0; i < NPROB; i++) {
    if (!in_list(list, P[i].name)) continue;
    if (!compiled) sweep_problem(out, &P[i], budget, quick);
    else if (P[i].ball_compiled) sweep_compiled(out, &P[i], budget, quick);
  }
  if (out) fclose(out);
  free_problems(P);
  return 0;
}
