/* Pieces every benchmark program of bench/ shares: clocks, a comparison for qsort, a fatal
 * error, and the timed block of ap_forward evaluations that bench_bicycle and bench_vehicles
 * report (and that callgrind counts with --toggle-collect=eval_block).
 *
 * Clocks return nanoseconds as doubles. bench_thread_ns is the CPU time of the calling thread
 * (the machine is shared: wall time would count the time other processes hold the cores;
 * cache contention still shows), bench_process_ns that of the whole process, bench_mono_ns
 * wall time. */
#ifndef APPELL_BENCHUTIL_H
#define APPELL_BENCHUTIL_H

#include "appell/appell.h"

/* Written with the timed work's result so the compiler cannot drop the work. */
extern volatile double bench_sink;

double bench_thread_ns(void);
double bench_process_ns(void);
double bench_mono_ns(void);

/* qsort comparison of doubles, ascending. */
int bench_cmp_double(const void *a, const void *b);

/* Prints "PROGRAM: what: msg" on stderr and exits with status 1 (benchmarks only). */
_Noreturn void bench_die(const char *what, const char *msg);

/* The timed block: reps evaluations of ap_forward on d (callgrind collects inside it). */
double eval_block(const ap_model *m, ap_data *d, int reps);

/* One ap_forward as the minimal-mode integrator calls it (partitioned basis, speeds from e')
 * at the state x = (q, v): a warm-up block and `blocks` timed blocks of `reps` evaluations
 * (thread CPU time). Prints one line, the name padded to `width`: median ns per evaluation,
 * the spread, evaluations per second, n, k, b, l and the callgrind divisor
 * reps (blocks + 1). */
void bench_forward(const char *name, int width, const ap_model *m, const double *x, int reps,
                   int blocks);

#endif
