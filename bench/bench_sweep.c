/* bench_sweep: runs per second of a sweep of the rolling disk on the batch API's thread pool,
 * with 1 and 2 threads (or --threads LIST), and what one run costs outside the integration.
 *
 * The sweep: examples/scenes/rolling_disk.yaml, 5 s each at rtol 1e-8, over a grid of initial
 * tilt (60..89 deg) x spin rate (-8..-4 rad/s), --runs of them (default 10^4, a 100 x 100
 * grid). Each thread count runs the same sweep after a warm-up of 20 runs; reported: wall time
 * (CLOCK_MONOTONIC), the process's CPU time (CLOCK_PROCESS_CPUTIME_ID, all threads), runs per
 * second of wall time, CPU milliseconds per run, and the speed-up of wall throughput over the
 * first thread count, measured in the same invocation; the load average before and after
 * (the machine may be shared: wall-clock ratios are credible only when the load is below the
 * processor count minus the threads used). The tables of the thread counts must be equal bit
 * for bit. --setup also times the runs with t_end = 1e-6 s (load, initial state, simulation
 * creation: the per-run cost that is not integration).
 *
 *   OPENBLAS_NUM_THREADS=1 build/bench/bench_sweep [--runs N] [--threads 1,2] [--setup]
 *                                                  [--scene PATH]                          */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <appell/appell.h>

typedef struct timing {
  double wall, cpu;
} timing;

static double clock_s(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void loadavg(double la[3]) {
  FILE *f = fopen("/proc/loadavg", "r");
  la[0] = la[1] = la[2] = NAN;
  if (f) {
    if (fscanf(f, "%lf %lf %lf", &la[0], &la[1], &la[2]) != 3) la[0] = NAN;
    fclose(f);
  }
}

/* A grid of about `runs` points (rows x cols). */
static ap_plan *make_plan(long runs) {
  long a = (long)floor(sqrt((double)runs)), b = (runs + a - 1) / a;
  char g1[128], g2[128], msg[256];
  snprintf(g1, sizeof g1, "initial.disk.tilt=60*deg:89*deg:%ld", a);
  snprintf(g2, sizeof g2, "initial.disk.spin_rate=-8:-4:%ld", b);
  ap_plan *p = NULL;
  if (ap_plan_create(&p) != AP_OK || ap_plan_add_grid(p, g1, msg, sizeof msg) != AP_OK ||
      ap_plan_add_grid(p, g2, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "bench_sweep: plan: %s\n", msg);
    ap_plan_free(p);
    return NULL;
  }
  return p;
}

/* One timed batch of count runs; values receive the table. */
static int timed(const char *scene, const char *const *sets, int nsets, int threads,
                 const ap_plan *p, long count, double *values, int *status, timing *t,
                 int *ncols) {
  ap_batch_def def = ap_batch_def_default();
  def.threads = threads;
  ap_batch *b = NULL;
  char msg[1024];
  int rc = ap_batch_load(scene, sets, nsets, &def, &b, msg, sizeof msg);
  if (rc != AP_OK) return fprintf(stderr, "bench_sweep: %s\n", msg), rc;
  *ncols = ap_batch_ncols(b);
  if (*ncols > 64) return ap_batch_free(b), fprintf(stderr, "bench_sweep: too many columns\n"), 1;
  rc = ap_batch_run_plan(b, p, 0, count < 20 ? count : 20, values, status, NULL);   /* warm-up */
  double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
  if (rc == AP_OK) rc = ap_batch_run_plan(b, p, 0, count, values, status, NULL);
  t->wall = clock_s(CLOCK_MONOTONIC) - w0;
  t->cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
  ap_batch_free(b);
  return rc;
}

int main(int argc, char **argv) {
  long runs = 10000;
  const char *scene = "examples/scenes/rolling_disk.yaml", *list = "1,2";
  int setup = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--runs") && i + 1 < argc) runs = atol(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) list = argv[++i];
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else if (!strcmp(argv[i], "--setup")) setup = 1;
    else return fprintf(stderr, "usage: bench_sweep [--runs N] [--threads 1,2] [--setup] "
                        "[--scene PATH]\n"), 2;
  }
  ap_plan *p = make_plan(runs > 0 ? runs : 1);
  if (!p) return 1;
  long count = ap_plan_count(p);
  const char *sets[] = {"simulation.t_end=5", "simulation.rtol=1e-8", "simulation.t_end=1e-6"};
  double *values = malloc(sizeof(double) * (size_t)count * 64), *first = NULL;
  int *status = malloc(sizeof(int) * (size_t)count), ncols = 0, rc = 0;
  double la0[3], la1[3];
  loadavg(la0);
  printf("threads,runs,wall_s,cpu_s,runs_per_s,cpu_ms_per_run,speedup_wall\n");
  double base = 0.0;
  for (const char *s = list; *s && rc == 0; s += strcspn(s, ",") + (s[strcspn(s, ",")] == ',')) {
    int threads = atoi(s);
    timing t;
    rc = timed(scene, sets, 2, threads, p, count, values, status, &t, &ncols);
    if (rc != AP_OK) break;
    long failed = 0;
    for (long i = 0; i < count; i++) failed += status[i] != AP_OK;
    if (!first) {
      first = malloc(sizeof(double) * (size_t)count * (size_t)ncols);
      memcpy(first, values, sizeof(double) * (size_t)count * (size_t)ncols);
      base = (double)count / t.wall;
    } else if (memcmp(first, values, sizeof(double) * (size_t)count * (size_t)ncols) != 0) {
      fprintf(stderr, "bench_sweep: the table with %d threads differs from the first\n", threads);
      rc = 1;
    }
    printf("%d,%ld,%.3f,%.3f,%.1f,%.3f,%.3f\n", threads, count, t.wall, t.cpu,
           (double)count / t.wall, 1e3 * t.cpu / (double)count, (double)count / t.wall / base);
    if (failed) fprintf(stderr, "bench_sweep: %ld runs failed\n", failed), rc = 1;
  }
  if (setup && rc == 0) {
    timing t;
    rc = timed(scene, sets + 1, 2, 1, p, count, values, status, &t, &ncols);   /* t_end = 1e-6 s */
    printf("# setup only (load, initial state, create; t_end = 1e-6 s), 1 thread: %.3f ms CPU per "
           "run, %.3f s wall\n", 1e3 * t.cpu / (double)count, t.wall);
  }
  loadavg(la1);
  printf("# load average before %.2f %.2f %.2f, after %.2f %.2f %.2f\n", la0[0], la0[1], la0[2],
         la1[0], la1[1], la1[2]);
  free(first);
  free(values);
  free(status);
  ap_plan_free(p);
  return rc ? 1 : 0;
}
