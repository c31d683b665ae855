/* bench_bodies: the cost of one evaluation of a body-built system against its hand-derived
 * math-level twin (tests/refsys.h), in the same run (issue 3 "Benchmark": the generic body
 * layer within 3x of the hand-derived system's evaluation for the same problem).
 *
 * Pairs (the body models of tests/bodysys.h, as tests/test_body_rebuild.c uses them; the same
 * state on both sides, up to the order and kind of the coordinates):
 *   knife_edge      planar joint on an inclined frame + knife edge + gravity   | refsys skate
 *   sleigh          planar joint, centre of mass ahead of the blade + knife edge| refsys sleigh
 *                                                                      (explicit bias h)
 *   turntable       sphere on a plane-contact joint + rolling on a turntable  | refsys ball
 *   turntable_var   the same with Omega(t) = Omega0 + dOmega t (rheonomic)    | refsys ball
 *   hoffmann        two rods on revolutes, gravity, applied force (b = 0)     | refsys reduced
 *                                                                      (Christoffel h)
 *   hoffmann_prim   revolute rod + planar rod + coincident hinge (b = 2)      | refsys primitive
 *
 * Two measurements per pair: "forward" is ap_forward exactly as the minimal-mode integrator
 * calls it (partitioned basis chosen by ap_partition, speeds from e'); "objects" is only the
 * position and velocity stages without a basis (g, N, A, a0, h, Q, gamma: what the body layer
 * replaces), which isolates the body layer's own cost from the shared solve.
 *
 * Method (STYLE.md "Tests and benchmarks"): both sides are warmed up, then timed in
 * interleaved blocks of `reps` evaluations from a saved state (thread CPU time); reported are
 * the median over `blocks` blocks and the spread (min..max) in ns per evaluation, the ratio
 * body / hand of the medians, and the median of the per-block ratios ("paired").
 * Usage: bench_bodies [--csv FILE] [--reps N] [--blocks N]. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "benchutil.h"
#include "bodysys.h"

static void check(int rc, const char *what) {
  if (rc != AP_OK) bench_die(what, ap_strerror(rc));
}

/* ---- timing ------------------------------------------------------------------------------ */

typedef struct side {
  const ap_model *m;
  ap_data *d;
  int objects;                 /* 1: position + velocity stages only, no basis */
} side;

static void prepare(side *s, const ap_model *m, int objects, double t, const double *q,
                    const double *v) {
  s->m = m, s->objects = objects;
  check(ap_data_create(m, &s->d), "data");
  ap_data *d = s->d;
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)d->n);
  memcpy(d->v, v, sizeof(double) * (size_t)d->k);
  if (objects) {
    d->basis = AP_BASIS_NONE;
    return;
  }
  d->basis = AP_BASIS_PARTITIONED;
  if (ap_partition(m, d) != AP_OK) bench_die("partition", d->msg);
  for (int j = 0; j < d->l; j++) d->e[j] = d->v[d->perm[d->rank + j]];
  d->speeds_from_e = 1;   /* as minimal mode's right-hand side runs */
}

static void eval(side *s) {
  ap_data *d = s->d;
  int rc = s->objects ? ap_fwd_position(s->m, d) : ap_forward(s->m, d);
  if (rc == AP_OK && s->objects) rc = ap_fwd_velocity(s->m, d);
  if (rc != AP_OK) bench_die(ap_model_name(s->m), d->msg);
  bench_sink += s->objects ? d->h[0] + d->Q[0] : d->vdot[0];
}

typedef struct timing {
  double median, lo, hi;       /* ns per evaluation */
} timing;

static timing summarize(double *ns, int blocks) {
  qsort(ns, (size_t)blocks, sizeof *ns, bench_cmp_double);
  timing t = {ns[blocks / 2], ns[0], ns[blocks - 1]};
  return t;
}

/* Interleaved blocks: body, hand, body, hand, ... after a warm-up of each. *paired is the
 * median over the blocks of body / hand within a block (robust to the load changing). */
static void time_pair(side *body, side *hand, int blocks, int reps, timing *tb, timing *th,
                      double *paired) {
  double *nb = malloc(sizeof(double) * (size_t)blocks);
  double *nh = malloc(sizeof(double) * (size_t)blocks);
  double *pr = malloc(sizeof(double) * (size_t)blocks);
  if (!nb || !nh || !pr) bench_die("timing", "out of memory");
  for (int i = 0; i < reps; i++) eval(body), eval(hand);
  for (int b = 0; b < blocks; b++) {
    double t0 = bench_thread_ns();
    for (int i = 0; i < reps; i++) eval(body);
    double t1 = bench_thread_ns();
    for (int i = 0; i < reps; i++) eval(hand);
    double t2 = bench_thread_ns();
    nb[b] = (t1 - t0) / reps, nh[b] = (t2 - t1) / reps, pr[b] = nb[b] / nh[b];
  }
  *tb = summarize(nb, blocks), *th = summarize(nh, blocks), *paired = summarize(pr, blocks).median;
  free(nb), free(nh), free(pr);
}

typedef struct bench_pair {
  const char *name;
  const ap_model *body, *hand;
  double t;
  double qb[8], vb[8], qh[8], vh[8];
} bench_pair;

int main(int argc, char **argv) {
  int reps = 20000, blocks = 31;
  const char *csv = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blocks") && i + 1 < argc) blocks = atoi(argv[++i]);
    else {
      fprintf(stderr, "usage: bench_bodies [--csv FILE] [--reps N] [--blocks N]\n");
      return 2;
    }
  }
  if (reps < 1 || blocks < 1) return 2;

  /* parameters and states as in bench/bench_eval.c and tests/test_body_rebuild.c */
  rs_knife kp = {2.0, 0.3, 9.81, 0.4};
  rs_sleigh sp = {1.0, 1.0, 1.0};
  rs_turntable tp = {1.0, 0.5, 0.4, 2.0, 0.0}, tv = {1.0, 0.5, 0.4, 0.5, 0.1};
  rs_hoffmann hp = bs_hoffmann_params();
  ap_system_def def[6];
  rs_knife_system(&kp, &def[0]);
  rs_sleigh_system(&sp, 1, &def[1]);
  rs_turntable_system(&tp, &def[2]);
  rs_turntable_system(&tv, &def[3]);
  rs_hoffmann_reduced_system(&hp, &def[4]);
  rs_hoffmann_primitive_system(&hp, &def[5]);
  ap_model *hand[6], *body[6] = {bs_skate_model(&kp), bs_sleigh_model(&sp),
                                 bs_turntable_model(&tp), bs_turntable_model(&tv),
                                 bs_hoffmann_tree(&hp, 0, 0.0), bs_hoffmann_primitive(&hp)};
  if (bs_failures() > 0) bench_die("body models", "cannot build (see above)");
  for (int i = 0; i < 6; i++) {
    char msg[256];
    if (ap_model_from_system(&def[i], &hand[i], msg, sizeof msg) != AP_OK) bench_die("refsys", msg);
  }

  bench_pair P[6];
  memset(P, 0, sizeof P);
  static const char *const names[6] = {"knife_edge", "sleigh", "turntable", "turntable_var",
                                       "hoffmann", "hoffmann_prim"};
  for (int i = 0; i < 6; i++) P[i].name = names[i], P[i].body = body[i], P[i].hand = hand[i];
  /* knife edge, sleigh: same q = (x, y, heading), v = q' */
  rs_knife_initial(0.1, 0.2, 0.7, 1.0, 2.0, P[0].qh, P[0].vh);
  rs_sleigh_initial(0, 0, 1.0, 0.1, 0.2, P[1].qh, P[1].vh);
  for (int i = 0; i < 2; i++)
    memcpy(P[i].qb, P[i].qh, sizeof P[i].qb), memcpy(P[i].vb, P[i].vh, sizeof P[i].vb);
  /* turntables: refsys (x, y, a1, a2, a3), body (x, y, quaternion); the same speeds */
  rs_turntable_initial(&tp, 0.3, -0.2, 0.5, 1.0, 2.0, P[2].qh, P[2].vh);
  rs_turntable_initial(&tv, 0.3, -0.2, 0.5, 1.0, 2.0, P[3].qh, P[3].vh);
  for (int i = 2; i < 4; i++) {
    const double qb[6] = {P[i].qh[0], P[i].qh[1], 1, 0, 0, 0};
    memcpy(P[i].qb, qb, sizeof qb), memcpy(P[i].vb, P[i].vh, sizeof P[i].vb);
    P[i].t = 0.3;
  }
  /* Hoffmann: reduced (theta, phi) against the tree's (theta, psi = phi - theta); primitive
   * refsys (theta, phi, y, z) against the body's (theta, y, z, phi) */
  double q2[2] = {0.3, -0.2}, v2[2] = {0.5, 1.1}, q4[4], v4[4];
  memcpy(P[4].qh, q2, sizeof q2), memcpy(P[4].vh, v2, sizeof v2);
  P[4].qb[0] = q2[0], P[4].qb[1] = q2[1] - q2[0], P[4].vb[0] = v2[0], P[4].vb[1] = v2[1] - v2[0];
  rs_hoffmann_lift(&hp, q2, v2, q4, v4);
  memcpy(P[5].qh, q4, sizeof q4), memcpy(P[5].vh, v4, sizeof v4);
  const int perm[4] = {0, 2, 3, 1};
  for (int i = 0; i < 4; i++) P[5].qb[i] = q4[perm[i]], P[5].vb[i] = v4[perm[i]];

  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (csv && !out) bench_die(csv, "cannot write");
  if (out)
    fprintf(out, "system,what,k_body,k_hand,b,body_ns,body_lo,body_hi,hand_ns,hand_lo,hand_hi,"
                 "ratio,paired\n");
  printf("ns per evaluation: median over %d blocks of %d (min..max); ratio = body / hand\n\n",
         blocks, reps);
  printf("%-14s %-8s %5s %2s %10s %19s %10s %19s %6s %6s\n", "system", "what", "k", "b",
         "body", "(min..max)", "hand", "(min..max)", "ratio", "paired");
  double worst = 0.0;
  for (int i = 0; i < 6; i++)
    for (int objects = 0; objects < 2; objects++) {
      side sb, sh;
      prepare(&sb, P[i].body, objects, P[i].t, P[i].qb, P[i].vb);
      prepare(&sh, P[i].hand, objects, P[i].t, P[i].qh, P[i].vh);
      timing tb, th;
      double paired = 0.0;
      time_pair(&sb, &sh, blocks, reps, &tb, &th, &paired);
      double ratio = tb.median / th.median;
      if (!objects) worst = fmax(worst, ratio);
      char ks[16];
      snprintf(ks, sizeof ks, "%d/%d", ap_model_k(P[i].body), ap_model_k(P[i].hand));
      printf("%-14s %-8s %5s %2d %10.1f (%7.1f..%8.1f) %10.1f (%7.1f..%8.1f) %6.2f %6.2f\n",
             P[i].name, objects ? "objects" : "forward", ks, ap_model_b(P[i].body), tb.median,
             tb.lo, tb.hi, th.median, th.lo, th.hi, ratio, paired);
      if (out)
        fprintf(out, "%s,%s,%d,%d,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.3f,%.3f\n", P[i].name,
                objects ? "objects" : "forward", ap_model_k(P[i].body), ap_model_k(P[i].hand),
                ap_model_b(P[i].body), tb.median, tb.lo, tb.hi, th.median, th.lo, th.hi, ratio,
                paired);
      ap_data_free(sb.d), ap_data_free(sh.d);
    }
  printf("\nlargest forward ratio %.2f (aim: within 3x)\n", worst);
  if (out) fclose(out);
  for (int i = 0; i < 6; i++) ap_model_free(body[i]), ap_model_free(hand[i]);
  return 0;
}
