/* bench_fleet: cost per step of N differential-drive robots on one floor (docs/large.md
 * "Fleets"), the model of tests/treemodels.h (tm_fleet: chassis on a planar joint, two wheels
 * on revolute joints with rolling wheel contacts, damped axles; every fourth robot pulls a
 * trailer with a knife edge), from the consistent state tm_fleet_state.
 *
 * Per N (16, 32, ... doubling to --max-n, default 1024): a minimal-mode dopri5 run at rtol 1e-8
 * (atol 1e-10); after an untimed warm-up of 20 steps that gives the mean step h, `chunks` (15)
 * chunks of 4 h each are advanced, and per chunk the thread CPU time is divided by the steps
 * it took; reported: the median over the chunks, steps, evaluations per step, and partition
 * switches per step (each robot's lateral row picks x' or y' of its chassis and switches as the
 * robot turns through 45 degrees: a restart of the stepper). The exponent p of time per step
 * ~ N^p is the least-squares slope on log-log axes over every N. Growth stops when a step costs
 * more than --max-ms (default 200 ms).
 *
 *   bench_fleet [--path auto|dense|tree] [--min-n N] [--max-n N] [--max-ms X]
 *   bench_fleet [--path P] --callgrind N STEPS   (under valgrind --tool=callgrind
 *                                                 --collect-atstart=no; bench/fleet_callgrind.sh)
 * Run niced, with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <valgrind/callgrind.h>

#include "appell/appell.h"
#include "benchutil.h"
#include "treemodels.h"

#define EVERY 4   /* every fourth robot pulls a trailer */

static ap_path path = AP_PATH_AUTO;

typedef struct fleet_run {
  ap_model *m;
  ap_sim *s;
  double t, h;
} fleet_run;

/* The model, its state and a simulation warmed up by `warm` steps (h: the mean step). */
static void start(int N, int warm, fleet_run *r) {
  r->m = tm_fleet(N, EVERY, path);
  int n = ap_model_n(r->m), k = ap_model_k(r->m);
  double *x = calloc((size_t)(n + k), sizeof(double));
  if (!x) bench_die("memory", "out of memory");
  tm_fleet_state(r->m, N, EVERY, x, x + n);
  ap_sim_def def = ap_sim_def_default();
  def.mode = AP_MODE_MINIMAL, def.method = "dopri5", def.rtol = 1e-8, def.atol = 1e-10;
  char msg[512];
  if (ap_sim_create(r->m, &def, 0.0, x, x + n, &r->s, msg, sizeof msg) != AP_OK)
    bench_die("sim", msg);
  free(x);
  ap_sim_stats st;
  double dt = 1e-3;
  r->t = 0;
  do {
    r->t += dt, dt *= 1.5;
    if (ap_sim_advance(r->s, r->t) != AP_OK) bench_die("warm-up", ap_sim_message(r->s));
    ap_sim_get_stats(r->s, &st);
  } while (st.steps < warm);
  r->h = r->t / (double)st.steps;
}

static void stop(fleet_run *r) {
  ap_sim_free(r->s);
  ap_model_free(r->m);
}

static const char *path_name(const ap_model *m) {
  return ap_model_path(m) == AP_PATH_TREE ? "tree" : "dense";
}

static int callgrind_run(int N, int steps) {
  fleet_run r;
  start(N, 10, &r);
  ap_sim_stats st;
  ap_sim_get_stats(r.s, &st);
  long s0 = st.steps, e0 = st.rhs_evals, p0 = st.partition_switches;
  CALLGRIND_TOGGLE_COLLECT;
  while (st.steps < s0 + steps) {   /* an output time about every step */
    if (ap_sim_advance(r.s, r.t += r.h) != AP_OK) bench_die("run", ap_sim_message(r.s));
    ap_sim_get_stats(r.s, &st);
  }
  CALLGRIND_TOGGLE_COLLECT;
  printf("callgrind fleet N %d k %d path %s steps %ld evals %ld partitions %ld\n", N,
         ap_model_k(r.m), path_name(r.m), st.steps - s0, st.rhs_evals - e0,
         st.partition_switches - p0);
  stop(&r);
  return 0;
}

/* Median thread CPU ns per step over `chunks` chunks of 4 h; steps, evaluations and
 * partition switches per step over all of them. */
static double time_steps(int N, int chunks, double *ev, double *sw, long *steps, int *k,
                         const char **pn) {
  fleet_run r;
  start(N, 20, &r);
  double *per = calloc((size_t)chunks, sizeof *per);
  if (!per) bench_die("memory", "out of memory");
  ap_sim_stats st;
  ap_sim_get_stats(r.s, &st);
  long s0 = st.steps, e0 = st.rhs_evals, p0 = st.partition_switches;
  for (int c = 0; c < chunks; c++) {
    long c0 = st.steps;
    double t0 = bench_thread_ns();
    if (ap_sim_advance(r.s, r.t += 4 * r.h) != AP_OK) bench_die("run", ap_sim_message(r.s));
    double t1 = bench_thread_ns();
    ap_sim_get_stats(r.s, &st);
    per[c] = (t1 - t0) / (double)(st.steps - c0 > 0 ? st.steps - c0 : 1);
  }
  qsort(per, (size_t)chunks, sizeof *per, bench_cmp_double);
  double med = chunks % 2 ? per[chunks / 2] : 0.5 * (per[chunks / 2 - 1] + per[chunks / 2]);
  *steps = st.steps - s0;
  *ev = (double)(st.rhs_evals - e0) / (double)*steps;
  *sw = (double)(st.partition_switches - p0) / (double)*steps;
  *k = ap_model_k(r.m), *pn = path_name(r.m);
  free(per);
  stop(&r);
  return med;
}

int main(int argc, char **argv) {
  int min_n = 16, max_n = 1024, cg_n = 0, cg_steps = 0, chunks = 15;
  double max_ms = 200;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--min-n") && i + 1 < argc) min_n = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--max-n") && i + 1 < argc) max_n = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--max-ms") && i + 1 < argc) max_ms = atof(argv[++i]);
    else if (!strcmp(argv[i], "--callgrind") && i + 2 < argc)
      cg_n = atoi(argv[++i]), cg_steps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--path") && i + 1 < argc) {
      const char *p = argv[++i];
      if (strcmp(p, "tree") && strcmp(p, "dense") && strcmp(p, "auto")) bench_die("--path", p);
      path = !strcmp(p, "tree") ? AP_PATH_TREE : !strcmp(p, "dense") ? AP_PATH_DENSE
                                                                       : AP_PATH_AUTO;
    } else {
      fprintf(stderr, "usage: bench_fleet [--path auto|dense|tree] [--min-n N] [--max-n N] "
                      "[--max-ms X]\n       bench_fleet [--path P] --callgrind N STEPS\n");
      return 2;
    }
  }
  if (cg_n > 0) return callgrind_run(cg_n, cg_steps);
  if (min_n < 1 || max_n < min_n) bench_die("--min-n/--max-n", "need 1 <= min-n <= max-n");
  printf("bench_fleet: N robots (every %dth with a trailer), minimal mode, dopri5, rtol 1e-8; "
         "thread CPU time per step, median over %d chunks of ~4 steps\n", EVERY, chunks);
  printf("%6s %6s %5s %11s %11s %8s %9s %9s\n", "N", "k", "path", "step_us", "us/robot",
         "steps", "ev/step", "sw/step");
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int c = 0;
  for (int N = min_n; N <= max_n; N *= 2) {
    double ev, sw;
    long steps;
    int k;
    const char *pn;
    double ns = time_steps(N, chunks, &ev, &sw, &steps, &k, &pn);
    printf("%6d %6d %5s %11.1f %11.3f %8ld %9.2f %9.3f\n", N, k, pn, ns * 1e-3, ns * 1e-3 / N,
           steps, ev, sw);
    fflush(stdout);
    double x = log((double)N), y = log(ns);
    sx += x, sy += y, sxx += x * x, sxy += x * y, c++;
    if (ns > max_ms * 1e6) break;
  }
  if (c >= 2)
    printf("exponent (time per step ~ N^p, least squares over %d Ns): p = %.3f\n", c,
           (c * sxy - sx * sy) / (c * sxx - sx * sx));
  return 0;
}
