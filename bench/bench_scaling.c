/* bench_scaling: cost per step as the system grows (issue 6 "Scaling").
 *
 * Two families of body models, N = 1, 2, 4, ... (doubling):
 *   trailers  a car (planar joint, knife edge on its rear axle) pulling N trailers, each hitched
 *             to the previous body by a revolute joint about the vertical and carrying a knife
 *             edge on its axle: a tree with k = N + 3 speeds and b = N + 1 rows.
 *   disks     N independent thin disks in one model, each on its own plane-contact joint with
 *             a rolling constraint, under one gravity effect: k = 5 N, b = 2 N.
 *
 * Per N:
 *   step      a minimal-mode dopri5 run at rtol 1e-8 (atol 1e-10) from a consistent initial
 *             state (ap_body_complete_speeds): after an untimed warm-up of `warm` steps that
 *             also gives the mean step h, the run is advanced in `chunks` chunks of 4 h each
 *             (so a chunk is about 4 steps, plus the stop at its end); per chunk the thread CPU
 *             time divided by the steps taken; reported is the median over the chunks, and
 *             the evaluations per step over all timed chunks.
 *   stages    ap_fwd_position, ap_fwd_velocity and ap_fwd_acceleration on a saved state (the
 *             state after warm-up; partitioned basis chosen by ap_partition, speeds from e' as
 *             minimal mode's right-hand side runs them). Each is timed as a difference of
 *             repeated prefixes of the pipeline: P, P+V, P+V+A (so every timed call sees the
 *             inputs it would see inside ap_forward); median over `blocks` blocks.
 * Growth stops when one step costs more than --max-ms (default 50 ms) or N exceeds --max-n
 * (default 512). The exponent p of time ~ N^p is the least-squares slope on log-log axes over
 * the Ns >= --fit-from (default 16).
 *
 * Usage: bench_scaling [--csv-dir DIR] [--plot] [--max-n N] [--max-ms X] [--fit-from N]
 * Writes DIR/scaling_trailers.csv, DIR/scaling_disks.csv (and with --plot, via gnuplot,
 * DIR/scaling_step.{png,svg} and DIR/scaling_stages.{png,svg}). Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <malloc.h>
#include <valgrind/callgrind.h>

#include "appell/appell.h"
#include "treemodels.h"

static volatile double sink;

static double now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double median(double *x, int n) {
  qsort(x, (size_t)n, sizeof *x, cmp_double);
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

static void die(const char *what, const char *msg) {
  fprintf(stderr, "bench_scaling: %s: %s\n", what, msg);
  exit(1);
}

static void check(int rc, const char *what) {
  if (rc != AP_OK) die(what, ap_strerror(rc));
}

/* Bytes held by malloc now (glibc: arena in use plus mmapped blocks). */
static double heap_bytes(void) {
  struct mallinfo2 mi = mallinfo2();
  return (double)mi.uordblks + (double)mi.hblkhd;
}

static void *xcalloc(size_t n, size_t size) {
  void *p = calloc(n ? n : 1, size);
  if (!p) die("memory", "out of memory");
  return p;
}

/* ---- measurements --------------------------------------------------------------------------- */

typedef struct result {
  int N, n, k, b;
  double step_ns, evals_per_step, eval_ns;     /* eval_ns: step_ns / evals_per_step */
  double pos_ns, vel_ns, acc_ns, fwd_ns;
  double bytes;                                /* model + simulation (with its data) */
  double model_bytes;                          /* the model alone */
  long steps_timed;
} result;

static ap_path path = AP_PATH_AUTO;

static int warm = 40, chunks = 15, blocks = 7;

static void time_steps(const ap_model *m, const double *q0, const double *v0, result *r,
                       double *q_saved, double *v_saved) {
  ap_sim_def def = ap_sim_def_default();
  def.mode = AP_MODE_MINIMAL, def.method = "dopri5", def.rtol = 1e-8, def.atol = 1e-10;
  ap_sim *s = NULL;
  char msg[512];
  double b0 = heap_bytes();
  if (ap_sim_create(m, &def, 0.0, q0, v0, &s, msg, sizeof msg) != AP_OK) die("sim", msg);
  r->bytes += heap_bytes() - b0;
  ap_sim_stats st;
  /* warm-up: advance until `warm` steps were taken, in growing intervals */
  double t = 0, dt = 1e-3;
  do {
    t += dt, dt *= 1.5;
    if (ap_sim_advance(s, t) != AP_OK) die("warm-up", ap_sim_message(s));
    ap_sim_get_stats(s, &st);
  } while (st.steps < warm);
  double h = t / (double)st.steps;
  memcpy(q_saved, ap_sim_q(s), sizeof(double) * (size_t)r->n);
  memcpy(v_saved, ap_sim_v(s), sizeof(double) * (size_t)r->k);
  double *per = xcalloc((size_t)chunks, sizeof *per);
  long steps0 = st.steps, evals0 = st.rhs_evals;
  for (int c = 0; c < chunks; c++) {
    long s0 = st.steps;
    double c0 = now_ns();
    if (ap_sim_advance(s, t += 4 * h) != AP_OK) die("run", ap_sim_message(s));
    double c1 = now_ns();
    ap_sim_get_stats(s, &st);
    per[c] = (c1 - c0) / (double)(st.steps - s0 > 0 ? st.steps - s0 : 1);
  }
  r->step_ns = median(per, chunks);
  r->steps_timed = st.steps - steps0;
  r->evals_per_step = (double)(st.rhs_evals - evals0) / (double)r->steps_timed;
  r->eval_ns = r->step_ns / r->evals_per_step;
  free(per);
  ap_sim_free(s);
}

/* stages = 1: P; 2: P + V; 3: P + V + A; 4: ap_forward. */
static void run_prefix(const ap_model *m, ap_data *d, int stages) {
  int rc = AP_OK;
  if (stages == 4) rc = ap_forward(m, d);
  else {
    rc = ap_fwd_position(m, d);
    if (rc == AP_OK && stages >= 2) rc = ap_fwd_velocity(m, d);
    if (rc == AP_OK && stages >= 3) rc = ap_fwd_acceleration(m, d);
  }
  if (rc != AP_OK) die("stage", d->msg);
  sink += d->vdot[0];
}

static void time_stages(const ap_model *m, const double *q, const double *v, result *r) {
  ap_data *d = NULL;
  check(ap_data_create(m, &d), "data");
  d->t = 0;
  memcpy(d->q, q, sizeof(double) * (size_t)r->n);
  memcpy(d->v, v, sizeof(double) * (size_t)r->k);
  d->basis = AP_BASIS_PARTITIONED;
  if (ap_partition(m, d) != AP_OK) die("partition", d->msg);
  for (int j = 0; j < d->l; j++) d->e[j] = d->v[d->perm[d->rank + j]];
  d->speeds_from_e = 1;
  /* reps: about 2 ms of ap_forward per block, at least 3 */
  double c0 = now_ns();
  run_prefix(m, d, 4);
  double one = now_ns() - c0;
  int reps = (int)(2e6 / (one > 1 ? one : 1));
  if (reps < 3) reps = 3;
  if (reps > 20000) reps = 20000;
  for (int i = 0; i < reps; i++) run_prefix(m, d, 4);   /* warm-up */
  double *x[4];
  for (int p = 0; p < 4; p++) x[p] = xcalloc((size_t)blocks, sizeof(double));
  for (int bl = 0; bl < blocks; bl++)
    for (int p = 0; p < 4; p++) {
      double t0 = now_ns();
      for (int i = 0; i < reps; i++) run_prefix(m, d, p + 1);
      x[p][bl] = (now_ns() - t0) / reps;
    }
  double med[4];
  for (int p = 0; p < 4; p++) med[p] = median(x[p], blocks), free(x[p]);
  r->pos_ns = med[0], r->vel_ns = med[1] - med[0], r->acc_ns = med[2] - med[1];
  r->fwd_ns = med[3];
  ap_data_free(d);
}

/* Least-squares slope of log(y) against log(N) over the results with N >= from. */
static double fit_exponent(const result *r, int count, int from, double (*get)(const result *),
                           int *used) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int c = 0;
  for (int i = 0; i < count; i++) {
    if (r[i].N < from) continue;
    double x = log((double)r[i].N), y = log(get(&r[i]));
    sx += x, sy += y, sxx += x * x, sxy += x * y, c++;
  }
  *used = c;
  if (c < 2) return NAN;
  return (c * sxy - sx * sy) / (c * sxx - sx * sx);
}

static double get_step(const result *r) { return r->step_ns; }
static double get_pos(const result *r) { return r->pos_ns; }
static double get_vel(const result *r) { return r->vel_ns > 1 ? r->vel_ns : 1; }
static double get_acc(const result *r) { return r->acc_ns > 1 ? r->acc_ns : 1; }

static double get_bytes(const result *r) { return r->bytes; }

static const char *path_name(const ap_model *m) {
  return ap_model_path(m) == AP_PATH_TREE ? "tree" : "dense";
}

/* N = min_n, 2 min_n, ... and max_n itself last. */
static int next_n(int N, int max_n) { return N < max_n && 2 * N > max_n ? max_n : 2 * N; }

static int run_family(const char *family, int min_n, int max_n, double max_ms, int fit_from,
                      const char *dir, result *res) {
  int count = 0;
  printf("\n%s (minimal mode, dopri5, rtol 1e-8; step: median over %d chunks of ~4 steps; "
         "stages: median over %d blocks)\n", family, chunks, blocks);
  printf("%6s %6s %6s %6s %5s %11s %7s %10s %11s %11s %11s %11s %5s %9s %9s\n", "N", "n", "k",
         "b", "path", "step_us", "ev/step", "eval_us", "position_us", "velocity_us", "accel_us",
         "forward_us", "dom", "bytes/N", "model/N");
  for (int N = min_n; N <= max_n; N = next_n(N, max_n)) {
    int tr = strcmp(family, "trailers") == 0;
    double b0 = heap_bytes();
    ap_model *m = tr ? tm_trailers(N, path) : tm_disks(N, path);
    result *r = &res[count];
    memset(r, 0, sizeof *r);
    r->N = N, r->n = ap_model_n(m), r->k = ap_model_k(m), r->b = ap_model_b(m);
    double *q = xcalloc((size_t)r->n, sizeof *q), *v = xcalloc((size_t)r->k, sizeof *v);
    double *qs = xcalloc((size_t)r->n, sizeof *qs), *vs = xcalloc((size_t)r->k, sizeof *vs);
    r->bytes = r->model_bytes = heap_bytes() - b0;   /* time_steps adds the simulation's */
    if (tr) tm_trailers_state(m, N, q, v);
    else tm_disks_state(m, N, q, v);
    time_steps(m, q, v, r, qs, vs);
    time_stages(m, qs, vs, r);
    const char *dom = r->pos_ns >= r->vel_ns && r->pos_ns >= r->acc_ns ? "pos"
                      : r->vel_ns >= r->acc_ns                            ? "vel"
                                                                          : "acc";
    printf("%6d %6d %6d %6d %5s %11.2f %7.2f %10.3f %11.3f %11.3f %11.3f %11.3f %5s %9.0f "
           "%9.0f\n", N, r->n, r->k, r->b, path_name(m), r->step_ns * 1e-3, r->evals_per_step,
           r->eval_ns * 1e-3, r->pos_ns * 1e-3, r->vel_ns * 1e-3, r->acc_ns * 1e-3,
           r->fwd_ns * 1e-3, dom, r->bytes / N, r->model_bytes / N);
    fflush(stdout);
    free(q), free(v), free(qs), free(vs);
    ap_model_free(m);
    count++;
    if (r->step_ns > max_ms * 1e6) {
      printf("stopped: one step at N = %d costs %.1f ms > %.0f ms\n", N, r->step_ns * 1e-6,
             max_ms);
      break;
    }
  }
  int used = 0;
  double p = fit_exponent(res, count, fit_from, get_step, &used);
  printf("exponent (time per step ~ N^p, least squares over %d Ns >= %d): p = %.2f\n", used,
         fit_from, p);
  double pp = fit_exponent(res, count, fit_from, get_pos, &used);
  double pv = fit_exponent(res, count, fit_from, get_vel, &used);
  double pa = fit_exponent(res, count, fit_from, get_acc, &used);
  printf("stage exponents: position %.2f, velocity %.2f, acceleration %.2f\n", pp, pv, pa);
  double pm = fit_exponent(res, count, fit_from, get_bytes, &used);
  printf("memory exponent (model + simulation bytes ~ N^p): p = %.2f\n", pm);
  if (dir) {
    char path[1024];
    snprintf(path, sizeof path, "%s/scaling_%s.csv", dir, family);
    FILE *f = fopen(path, "w");
    if (!f) die(path, "cannot write");
    fprintf(f, "N,n,k,b,step_ns,evals_per_step,eval_ns,position_ns,velocity_ns,"
               "acceleration_ns,forward_ns,steps_timed,bytes\n");
    for (int i = 0; i < count; i++)
      fprintf(f, "%d,%d,%d,%d,%.1f,%.3f,%.1f,%.1f,%.1f,%.1f,%.1f,%ld,%.0f\n", res[i].N,
              res[i].n, res[i].k, res[i].b, res[i].step_ns, res[i].evals_per_step,
              res[i].eval_ns, res[i].pos_ns, res[i].vel_ns, res[i].acc_ns, res[i].fwd_ns,
              res[i].steps_timed, res[i].bytes);
    fprintf(f, "# exponent_step,%.3f,fit_from,%d\n# exponent_position,%.3f\n"
               "# exponent_velocity,%.3f\n# exponent_acceleration,%.3f\n"
               "# exponent_bytes,%.3f\n", p, fit_from, pp, pv, pa, pm);
    fclose(f);
  }
  return count;
}

/* The fitted exponent of the step time in DIR/scaling_FAMILY.csv (NAN when absent). */
static double csv_exponent(const char *dir, const char *family) {
  char path[1024], line[256];
  double p = NAN;
  snprintf(path, sizeof path, "%s/scaling_%s.csv", dir, family);
  FILE *f = fopen(path, "r");
  while (f && fgets(line, sizeof line, f))
    if (sscanf(line, "# exponent_step,%lf", &p) == 1) break;
  if (f) fclose(f);
  return p;
}

static void plot(const char *dir, const char *term, const char *ext) {
  double pt = csv_exponent(dir, "trailers"), pd = csv_exponent(dir, "disks");
  FILE *g = popen("gnuplot", "w");
  if (!g) die("gnuplot", "cannot start");
  fprintf(g, "set terminal %s size 900,600\nset datafile separator ','\n"
             "set logscale xy\nset grid\nset key top left\nset xlabel 'N'\n", term);
  fprintf(g, "set output '%s/scaling_step.%s'\nset ylabel 'CPU time per step (us)'\n"
             "set title 'Cost per step, minimal mode, dopri5, rtol 1e-8'\n"
             "plot '%s/scaling_trailers.csv' every ::1 using 1:($5/1e3) with linespoints "
             "title 'car + N trailers (k = N+3, b = N+1): fitted N^%.2f', "
             "'%s/scaling_disks.csv' every ::1 using 1:($5/1e3) with linespoints "
             "title 'N rolling disks (k = 5N, b = 2N): fitted N^%.2f'\n",
          dir, ext, dir, pt, dir, pd);
  fprintf(g, "set output '%s/scaling_stages.%s'\nset ylabel 'CPU time per call (us)'\n"
             "set title 'Pipeline stages on a saved state'\n"
             "plot for [c=8:10] '%s/scaling_trailers.csv' every ::1 using 1:(column(c)/1e3) "
             "with linespoints title 'trailers '.word('position velocity acceleration', c-7), "
             "for [c=8:10] '%s/scaling_disks.csv' every ::1 using 1:(column(c)/1e3) "
             "with linespoints dashtype 2 title 'disks '.word('position velocity "
             "acceleration', c-7)\n",
          dir, ext, dir, dir);
  if (pclose(g) != 0) die("gnuplot", "failed");
}

/* One family at one N for callgrind (--collect-atstart=no): the warm-up uncounted, then
 * collection on for about `steps` steps; prints the steps and evaluations counted. */
static int callgrind_run(const char *family, int N, int steps) {
  int tr = strcmp(family, "trailers") == 0;
  ap_model *m = tr ? tm_trailers(N, path) : tm_disks(N, path);
  int n = ap_model_n(m), k = ap_model_k(m);
  double *q = xcalloc((size_t)n, sizeof *q), *v = xcalloc((size_t)k, sizeof *v);
  if (tr) tm_trailers_state(m, N, q, v);
  else tm_disks_state(m, N, q, v);
  ap_sim_def def = ap_sim_def_default();
  def.mode = AP_MODE_MINIMAL, def.method = "dopri5", def.rtol = 1e-8, def.atol = 1e-10;
  ap_sim *s = NULL;
  char msg[512];
  if (ap_sim_create(m, &def, 0.0, q, v, &s, msg, sizeof msg) != AP_OK) die("sim", msg);
  ap_sim_stats st;
  double t = 0, dt = 1e-3;
  do {
    t += dt, dt *= 1.5;
    if (ap_sim_advance(s, t) != AP_OK) die("warm-up", ap_sim_message(s));
    ap_sim_get_stats(s, &st);
  } while (st.steps < 10);
  double h = t / (double)st.steps;
  long s0 = st.steps, e0 = st.rhs_evals;
  CALLGRIND_TOGGLE_COLLECT;
  while (st.steps < s0 + steps) {   /* output times every step or so, as time_steps */
    if (ap_sim_advance(s, t += h) != AP_OK) die("run", ap_sim_message(s));
    ap_sim_get_stats(s, &st);
  }
  CALLGRIND_TOGGLE_COLLECT;
  printf("callgrind %s N %d k %d path %s steps %ld evals %ld\n", family, N, k, path_name(m),
         st.steps - s0, st.rhs_evals - e0);
  ap_sim_free(s);
  ap_model_free(m);
  free(q), free(v);
  return 0;
}

int main(int argc, char **argv) {
  int min_n = 1, max_n = 512, fit_from = 16, do_plot = 0, cg_n = 0, cg_steps = 20;
  double max_ms = 50;
  const char *dir = NULL, *cg_family = NULL, *only = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv-dir") && i + 1 < argc) dir = argv[++i];
    else if (!strcmp(argv[i], "--plot")) do_plot = 1;
    else if (!strcmp(argv[i], "--plot-only")) do_plot = 2;   /* from DIR's csv files */
    else if (!strcmp(argv[i], "--min-n") && i + 1 < argc) min_n = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--max-n") && i + 1 < argc) max_n = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--max-ms") && i + 1 < argc) max_ms = atof(argv[++i]);
    else if (!strcmp(argv[i], "--fit-from") && i + 1 < argc) fit_from = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--family") && i + 1 < argc) only = argv[++i];
    else if (!strcmp(argv[i], "--path") && i + 1 < argc) {
      const char *p = argv[++i];
      path = !strcmp(p, "tree") ? AP_PATH_TREE : !strcmp(p, "dense") ? AP_PATH_DENSE
                                                                       : AP_PATH_AUTO;
      if (strcmp(p, "tree") && strcmp(p, "dense") && strcmp(p, "auto")) die("--path", p);
    } else if (!strcmp(argv[i], "--callgrind") && i + 3 < argc) {
      cg_family = argv[++i], cg_n = atoi(argv[++i]), cg_steps = atoi(argv[++i]);
    } else {
      fprintf(stderr, "usage: bench_scaling [--csv-dir DIR] [--plot] [--path auto|dense|tree] "
                      "[--family trailers|disks] [--min-n N] [--max-n N] [--max-ms X] "
                      "[--fit-from N] [--plot-only]\n       bench_scaling [--path P] --callgrind FAMILY N "
                      "STEPS   (under valgrind --tool=callgrind --collect-atstart=no)\n");
      return 2;
    }
  }
  if (cg_family) return callgrind_run(cg_family, cg_n, cg_steps);
  if (do_plot && !dir) die("--plot", "needs --csv-dir");
  if (do_plot == 2) return plot(dir, "pngcairo", "png"), plot(dir, "svg", "svg"), 0;
  if (min_n < 1 || max_n < min_n) die("--min-n/--max-n", "need 1 <= min-n <= max-n");
  result res[40];
  printf("bench_scaling: thread CPU time; us = microseconds; bytes: malloc'd by the model and "
         "the simulation\n");
  if (!only || !strcmp(only, "trailers"))
    run_family("trailers", min_n, max_n, max_ms, fit_from, dir, res);
  if (!only || !strcmp(only, "disks"))
    run_family("disks", min_n, max_n, max_ms, fit_from, dir, res);
  if (do_plot) plot(dir, "pngcairo", "png"), plot(dir, "svg", "svg");
  return sink == 12345.678 ? 1 : 0;
}
