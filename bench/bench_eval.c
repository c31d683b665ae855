/* bench_eval: the cost of one Appell evaluation (ap_forward as the integrator calls it) for the
 * reference systems, side by side with the hand-reduced closed-form right-hand side a person
 * would derive for the same problem, measured in the same run.
 *
 * Method: warm up, then time blocks of `reps` evaluations from a saved state with
 * CLOCK_MONOTONIC; report the median over `blocks` blocks and the spread (min, max) in
 * nanoseconds per evaluation, and the ratio of medians. Writes CSV to stdout-or-file.
 * Usage: bench_eval [--csv FILE] [--reps N] [--blocks N] [--only SYSTEM]
 * For instruction counts per evaluation (stable on a loaded machine):
 *   valgrind --tool=callgrind --toggle-collect=fwd_body bench_eval --only sleigh
 *   valgrind --tool=callgrind --toggle-collect=hand_body bench_eval --only sleigh
 * and divide the totals by 2 (bases) x reps x (blocks + 1).
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "benchutil.h"
#include "refsys.h"

typedef struct timing {
  double median, lo, hi;       /* ns per evaluation */
} timing;

/* ---- hand-reduced right-hand sides ------------------------------------------------------- */

/* Knife edge: y = (x, y, phi, u, w): x' = u cos phi, y' = u sin phi, u' = G cos phi, w' = 0. */
static void knife_hand(const rs_knife *p, const double *y, double *yd) {
  double G = p->grav * sin(p->alpha), c = cos(y[2]), s = sin(y[2]);
  yd[0] = y[3] * c, yd[1] = y[3] * s, yd[2] = y[4], yd[3] = G * c, yd[4] = 0.0;
}

/* Chaplygin sleigh: y = (x, y, theta, u, w): u' = a w^2, J w' = -m a u w. */
static void sleigh_hand(const rs_sleigh *p, const double *y, double *yd) {
  double J = p->I + p->m * p->a * p->a;
  yd[0] = y[3] * cos(y[2]), yd[1] = y[3] * sin(y[2]), yd[2] = y[4];
  yd[3] = p->a * y[4] * y[4], yd[4] = -p->m * p->a * y[3] * y[4] / J;
}

/* Ball on a turntable: y = (x, y, x', y'): x'' = -kt (Omega y)', y'' = kt (Omega x)'. */
static void turntable_hand(const rs_turntable *p, double t, const double *y, double *yd) {
  double kt = p->kI / (1 + p->kI), W = p->Omega0 + p->dOmega * t, Wd = p->dOmega;
  yd[0] = y[2], yd[1] = y[3];
  yd[2] = -kt * (Wd * y[1] + W * y[3]);
  yd[3] = kt * (Wd * y[0] + W * y[2]);
}

/* Hoffmann's pendulum, reduced by hand: 2 x 2 solve by Cramer's rule. y = (th, ph, th', ph'). */
static void hoffmann_hand(const rs_hoffmann *p, const double *y, double *yd) {
  double c = cos(y[0] - y[1]), s = sin(y[0] - y[1]);
  double g11 = p->I1 + p->m1 * p->a1 * p->a1 + 4 * p->m2 * p->a1 * p->a1;
  double g12 = 2 * p->m2 * p->a1 * p->a2 * c, g22 = p->I2 + p->m2 * p->a2 * p->a2;
  double k = 2 * p->m2 * p->a1 * p->a2 * s;
  double Q1 = -(p->m1 + 2 * p->m2) * p->grav * p->a1 * sin(y[0]) + 2 * p->a1 * p->F * cos(y[0]);
  double Q2 = p->a2 * p->F * cos(y[1]) - p->a2 * p->m2 * p->grav * sin(y[1]);
  double r1 = Q1 - k * y[3] * y[3], r2 = Q2 + k * y[2] * y[2];
  double det = g11 * g22 - g12 * g12;
  yd[0] = y[2], yd[1] = y[3];
  yd[2] = (g22 * r1 - g12 * r2) / det, yd[3] = (g11 * r2 - g12 * r1) / det;
}

/* ---- timing ------------------------------------------------------------------------------ */

typedef struct bench_case {
  const char *name;
  ap_system_def def;
  const double *q, *v;         /* the state */
  ap_mode mode;
  int hand_n;                  /* size of the hand-reduced state */
  const double *hand_y;
  void (*hand)(const void *p, double t, const double *y, double *yd);
  const void *p;
} bench_case;

static void h_knife(const void *p, double t, const double *y, double *yd) {
  (void)t;
  knife_hand(p, y, yd);
}
static void h_sleigh(const void *p, double t, const double *y, double *yd) {
  (void)t;
  sleigh_hand(p, y, yd);
}
static void h_turn(const void *p, double t, const double *y, double *yd) {
  turntable_hand(p, t, y, yd);
}
static void h_hoff(const void *p, double t, const double *y, double *yd) {
  (void)t;
  hoffmann_hand(p, y, yd);
}

static timing time_blocks(int blocks, int reps, void (*body)(void *), void *arg) {
  double *ns = malloc(sizeof(double) * (size_t)blocks);
  for (int i = 0; i < reps; i++) body(arg);                      /* warm-up */
  for (int b = 0; b < blocks; b++) {
    double t0 = bench_mono_ns();
    for (int i = 0; i < reps; i++) body(arg);
    ns[b] = (bench_mono_ns() - t0) / reps;
  }
  qsort(ns, (size_t)blocks, sizeof *ns, bench_cmp_double);
  timing t = {ns[blocks / 2], ns[0], ns[blocks - 1]};
  free(ns);
  return t;
}

typedef struct fwd_arg {
  const ap_model *m;
  ap_data *d;
  double t;
} fwd_arg;

static void fwd_body(void *arg) {
  fwd_arg *a = arg;
  a->d->t = a->t;
  if (ap_forward(a->m, a->d) != AP_OK) abort();
  bench_sink += a->d->vdot[0];
}

typedef struct hand_arg {
  const bench_case *c;
  double yd[8];
} hand_arg;

static void hand_body(void *arg) {
  hand_arg *a = arg;
  a->c->hand(a->c->p, 0.3, a->c->hand_y, a->yd);
  bench_sink += a->yd[a->c->hand_n - 1];
}

int main(int argc, char **argv) {
  int reps = 20000, blocks = 31;
  const char *csv = NULL, *only = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blocks") && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
    else {
      fprintf(stderr, "usage: bench_eval [--csv FILE] [--reps N] [--blocks N] [--only SYSTEM]\n");
      return 2;
    }
  }
  if (reps < 1 || blocks < 1) return 2;

  rs_knife kp = {2.0, 0.3, 9.81, 0.4};
  rs_sleigh sp = {1.0, 1.0, 1.0};
  rs_turntable tp = {1.0, 0.5, 0.4, 2.0, 0.1};
  rs_hoffmann hp = {1.0, 1.5, 0.5, 0.4, 0.1, 0.08, 9.81, 2.0};
  double kq[3], kv[3], sq[3], sv[3], tq[5], tv[5], hq[2] = {0.3, -0.2}, hv[2] = {0.5, 1.1};
  double h4q[4], h4v[4];
  rs_knife_initial(0.1, 0.2, 0.7, 1.0, 2.0, kq, kv);
  rs_sleigh_initial(0, 0, 1.0, 0.1, 0.2, sq, sv);
  rs_turntable_initial(&tp, 0.3, -0.2, 0.5, 1.0, 2.0, tq, tv);
  rs_hoffmann_lift(&hp, hq, hv, h4q, h4v);
  double ky[5] = {kq[0], kq[1], kq[2], 1.0, 2.0};
  double sy[5] = {sq[0], sq[1], sq[2], 0.1, 0.2};
  double ty[4] = {tq[0], tq[1], tv[0], tv[1]};
  double hy[4] = {hq[0], hq[1], hv[0], hv[1]};

  bench_case cases[6];
  memset(cases, 0, sizeof cases);
  cases[0] = (bench_case){"knife_edge", {0}, kq, kv, AP_MODE_MINIMAL, 5, ky, h_knife, &kp};
  rs_knife_system(&kp, &cases[0].def);
  cases[1] = (bench_case){"sleigh", {0}, sq, sv, AP_MODE_MINIMAL, 5, sy, h_sleigh, &sp};
  rs_sleigh_system(&sp, 1, &cases[1].def);
  cases[2] = (bench_case){"sleigh_christoffel", {0}, sq, sv, AP_MODE_MINIMAL, 5, sy, h_sleigh, &sp};
  rs_sleigh_system(&sp, 0, &cases[2].def);
  cases[3] = (bench_case){"turntable", {0}, tq, tv, AP_MODE_MINIMAL, 4, ty, h_turn, &tp};
  rs_turntable_system(&tp, &cases[3].def);
  cases[4] = (bench_case){"hoffmann_reduced", {0}, hq, hv, AP_MODE_MINIMAL, 4, hy, h_hoff, &hp};
  rs_hoffmann_reduced_system(&hp, &cases[4].def);
  cases[5] = (bench_case){"hoffmann_primitive", {0}, h4q, h4v, AP_MODE_MINIMAL, 4, hy, h_hoff, &hp};
  rs_hoffmann_primitive_system(&hp, &cases[5].def);

  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (csv && !out) {
    fprintf(stderr, "bench_eval: cannot write %s\n", csv);
    return 1;
  }
  if (out) fprintf(out, "system,basis,k,b,appell_ns,appell_lo,appell_hi,hand_ns,hand_lo,hand_hi,ratio\n");
  printf("%-20s %-12s %2s %2s %12s %20s %10s %20s %7s\n", "system", "basis", "k", "b",
         "appell ns", "(min..max)", "hand ns", "(min..max)", "ratio");
  for (int c = 0; c < 6; c++) {
    if (only && strcmp(only, cases[c].name)) continue;
    for (int basis = 0; basis < 2; basis++) {
      ap_model *m = NULL;
      char msg[256];
      if (ap_model_from_system(&cases[c].def, &m, msg, sizeof msg) != AP_OK) {
        fprintf(stderr, "bench_eval: %s\n", msg);
        return 1;
      }
      ap_data *d = NULL;
      if (ap_data_create(m, &d) != AP_OK) return 1;
      d->basis = (ap_basis)basis;
      d->t = 0.3;
      memcpy(d->q, cases[c].q, sizeof(double) * (size_t)d->n);
      memcpy(d->v, cases[c].v, sizeof(double) * (size_t)d->k);
      if (basis == AP_BASIS_PARTITIONED) {
        if (ap_partition(m, d) != AP_OK) return 1;
        for (int j = 0; j < d->l; j++) d->e[j] = d->v[d->perm[d->rank + j]];
        d->speeds_from_e = 1;   /* as minimal mode's right-hand side runs */
      }
      fwd_arg fa = {m, d, 0.3};
      hand_arg ha = {&cases[c], {0}};
      timing ta = time_blocks(blocks, reps, fwd_body, &fa);
      timing th = time_blocks(blocks, reps, hand_body, &ha);
      const char *bname = basis ? "orthonormal" : "partitioned";
      printf("%-20s %-12s %2d %2d %12.1f (%7.1f..%8.1f) %10.1f (%7.1f..%8.1f) %7.1f\n",
             cases[c].name, bname, d->k, d->b, ta.median, ta.lo, ta.hi, th.median, th.lo,
             th.hi, ta.median / th.median);
      if (out)
        fprintf(out, "%s,%s,%d,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.3f\n", cases[c].name, bname,
                d->k, d->b, ta.median, ta.lo, ta.hi, th.median, th.lo, th.hi,
                ta.median / th.median);
      ap_data_free(d);
      ap_model_free(m);
    }
  }
  if (out) fclose(out);
  return 0;
}
