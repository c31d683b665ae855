/* Shared pieces of the benchmark programs (benchutil.h): clocks, qsort's comparison, the fatal
 * error, and the timed ap_forward block with its report line. */
#define _GNU_SOURCE   /* program_invocation_short_name */
#include "benchutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

volatile double bench_sink;

static double clock_ns(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

double bench_thread_ns(void) { return clock_ns(CLOCK_THREAD_CPUTIME_ID); }
double bench_process_ns(void) { return clock_ns(CLOCK_PROCESS_CPUTIME_ID); }
double bench_mono_ns(void) { return clock_ns(CLOCK_MONOTONIC); }

int bench_cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

_Noreturn void bench_die(const char *what, const char *msg) {
  fprintf(stderr, "%s: %s: %s\n", program_invocation_short_name, what, msg);
  exit(1);
}

__attribute__((noinline)) double eval_block(const ap_model *m, ap_data *d, int reps) {
  double s = 0.0;
  for (int r = 0; r < reps; r++) {
    if (ap_forward(m, d) != AP_OK) bench_die("ap_forward", d->msg);
    s += d->edd[0] + d->qdot[0];
  }
  return s;
}

void bench_forward(const char *name, int width, const ap_model *m, const double *x, int reps,
                   int blocks) {
  int n = ap_model_n(m);
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) bench_die(name, "ap_data_create");
  memcpy(d->q, x, sizeof(double) * (size_t)n);
  memcpy(d->v, x + n, sizeof(double) * (size_t)ap_model_k(m));
  d->basis = AP_BASIS_PARTITIONED;
  if (ap_partition(m, d) != AP_OK) bench_die(name, d->msg);
  for (int j = 0; j < d->l; j++) d->e[j] = d->v[d->perm[d->rank + j]];
  d->speeds_from_e = 1;
  double *t = malloc(sizeof(double) * (size_t)blocks);
  if (!t) bench_die(name, "out of memory");
  bench_sink = eval_block(m, d, reps);   /* warm-up */
  for (int b = 0; b < blocks; b++) {
    double t0 = bench_thread_ns();
    bench_sink = eval_block(m, d, reps);
    t[b] = (bench_thread_ns() - t0) / reps;
  }
  qsort(t, (size_t)blocks, sizeof *t, bench_cmp_double);
  double med = t[blocks / 2];
  printf("%-*s eval  %8.0f ns (%.0f..%.0f)  %9.0f evals/s  n %2d k %2d b %2d l %d  "
         "callgrind divisor %d\n", width, name, med, t[0], t[blocks - 1], 1e9 / med, n,
         ap_model_k(m), ap_model_b(m), d->l, reps * (blocks + 1));
  free(t);
  ap_data_free(d);
}
