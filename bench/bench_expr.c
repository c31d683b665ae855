/* bench_expr: the cost of evaluating a scene expression of t with its first and second time
 * derivatives (sc_expr_eval: what a joint drive, a turntable rate, a ground velocity or an
 * applied force costs at every evaluation of the model).
 *
 * Each expression is compiled once; then eval_loop() calls sc_expr_eval at `evals` times
 * t = 0.001 i and sums the results (so nothing is optimized away). Reported per expression:
 * the median thread CPU time per evaluation over the repeats, with min..max. Instruction
 * counts do not depend on the load of the machine; count them with callgrind, collecting only
 * inside eval_loop, one expression at a time:
 *
 *   valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect=eval_loop \
 *       build/bench/bench_expr --expr '0.5*sin(2*t)' --evals 10000 --repeats 1
 *
 * and divide the "Collected" total by evals. Usage: bench_expr [--expr TEXT] [--evals N]
 * [--repeats N] [--csv FILE]. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "scene/scene_int.h"

/* Typical expressions of scenes: a drive, a spin-up, a polynomial, a composite. */
static const char *const defaults[] = {"0.5*sin(2*t)", "2*tanh(t)", "0.1*t^2 - 0.3*t + 1",
                                       "0.2*exp(-t/4)*cos(3*t + pi/3)", NULL};

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The measured loop (callgrind: --toggle-collect=eval_loop). */
__attribute__((noinline)) double eval_loop(const sc_expr *e, long evals) {
  double sum = 0.0, f[3];
  for (long i = 0; i < evals; i++) {
    if (sc_expr_eval(e, 0.001 * (double)i, f) != 0) return NAN;
    sum += f[0] + f[1] + f[2];
  }
  return sum;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static int bench_one(const char *text, long evals, int repeats, FILE *csv) {
  sc_ctx c = {"bench", "", AP_OK};
  sc_node at = {.kind = SC_SCALAR, .text = (char *)text, .line = 1, .col = 1, .path = "expr"};
  sc_expr e;
  if (sc_expr_compile(&c, &at, text, 1, &e) != AP_OK)
    return fprintf(stderr, "bench_expr: %s\n", c.msg), 1;
  double *ns = malloc(sizeof(double) * (size_t)repeats), check = 0.0;
  if (!ns) return sc_expr_free(&e), 1;
  for (int r = 0; r < repeats; r++) {
    double t0 = cpu_now();
    check += eval_loop(&e, evals);
    ns[r] = 1e9 * (cpu_now() - t0) / (double)evals;
  }
  qsort(ns, (size_t)repeats, sizeof *ns, cmp);
  printf("%-34s %8.1f ns/eval (min %.1f, max %.1f)   checksum %.6g\n", text, ns[repeats / 2],
         ns[0], ns[repeats - 1], check);
  if (csv) fprintf(csv, "\"%s\",%.2f,%.2f,%.2f\n", text, ns[repeats / 2], ns[0], ns[repeats - 1]);
  free(ns);
  sc_expr_free(&e);
  return isfinite(check) ? 0 : 1;
}

int main(int argc, char **argv) {
  const char *only = NULL, *csv_path = NULL;
  long evals = 200000;
  int repeats = 7;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--expr") == 0) only = argv[i + 1];
    else if (strcmp(argv[i], "--evals") == 0) evals = atol(argv[i + 1]);
    else if (strcmp(argv[i], "--repeats") == 0) repeats = atoi(argv[i + 1]);
    else if (strcmp(argv[i], "--csv") == 0) csv_path = argv[i + 1];
    else return fprintf(stderr, "bench_expr: unknown option %s\n", argv[i]), 2;
  }
  if (evals < 1 || repeats < 1) return fprintf(stderr, "bench_expr: bad --evals/--repeats\n"), 2;
  FILE *csv = csv_path ? fopen(csv_path, "w") : NULL;
  if (csv_path && !csv) return fprintf(stderr, "bench_expr: cannot write %s\n", csv_path), 1;
  if (csv) fprintf(csv, "expression,median_ns,min_ns,max_ns\n");
  printf("sc_expr_eval (value, f', f''), %ld evaluations, median of %d repeats\n", evals, repeats);
  int bad = 0;
  if (only) bad |= bench_one(only, evals, repeats, csv);
  for (int i = 0; !only && defaults[i]; i++) bad |= bench_one(defaults[i], evals, repeats, csv);
  if (csv) fclose(csv);
  return bad;
}
