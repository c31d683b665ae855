/* bench_dae: the DAE mode (IDA, GGL rows) against the Appell modes (minimal, projected) at
 * equal achieved accuracy, measured in the same run, on body models:
 *   rolling_disk      disk on a plane-contact joint, rolling, gravity (n 6, k 5, b 2, one
 *                     quaternion: one GGL row in DAE mode); leaning 10 degrees, spinning and
 *                     turning, 6 s; the centre (x, y) is compared
 *   hoffmann_sliding  two rods on revolutes, the lower rod's end on a vertical line (n 2,
 *                     k 2, b 1, one loop: a velocity row and a GGL row), 6 s; both angles
 * Reference: minimal mode, fehlberg8, rtol = 1e-13, atol = 1e-15, checked against the DAE
 * mode at rtol = atol = 1e-11 (the difference is printed). Each run integrates from 0 to T
 * stopping at NOUT equally spaced outputs; err = the largest difference from the reference
 * over the outputs (max-norm); cpu = CPU time of create + integrate + free, median of 3 to 15
 * repeats after an untimed warm-up. Curves: minimal {dopri5, verner6, fehlberg8}, projected
 * {verner6, fehlberg8}, DAE; rtol = atol = 1e-3 ... 1e-11. The time at an error level E is
 * interpolated in (log err, log cpu) between the first two consecutive points of a curve that
 * bracket E (bench_wp's rule); the ratio is DAE over the cheapest Appell curve at E.
 *
 * Usage: bench_dae [--csv FILE]. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "refsys.h"

#define NOUT 10
#define NTOL 9           /* rtol = 1e-3 ... 1e-11 */
#define NCURVE 6
#define MAXQ 8

typedef struct problem {
  const char *name;
  ap_model *m;
  double q0[MAXQ], v0[MAXQ], T;
  int npos;              /* q[0 .. npos-1] compared */
  double ref[NOUT][MAXQ];
} problem;

typedef struct curve { const char *label; ap_mode mode; const char *method; } curve;

static const curve curves[NCURVE] = {
    {"minimal dopri5", AP_MODE_MINIMAL, "dopri5"},
    {"minimal verner6", AP_MODE_MINIMAL, "verner6"},
    {"minimal fehlberg8", AP_MODE_MINIMAL, "fehlberg8"},
    {"projected verner6", AP_MODE_PROJECTED, "verner6"},
    {"projected fehlberg8", AP_MODE_PROJECTED, "fehlberg8"},
    {"dae ida", AP_MODE_DAE, "dopri5"},
};

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static ap_model *compile(ap_builder *b) {
  ap_model *m = NULL;
  if (ap_builder_compile(b, &m) != AP_OK) {
    fprintf(stderr, "bench_dae: %s\n", ap_builder_message(b));
    exit(1);
  }
  ap_builder_free(b);
  return m;
}

/* ---- problems ---------------------------------------------------------------------------- */

static void setup_disk(problem *p) {
  const double mass = 1.0, r = 0.5, th = 10.0 * RS_PI / 180.0;
  ap_builder *b = NULL;
  ap_builder_create("rolling disk", &b);
  ap_body_def d = ap_body_def_default();
  d.name = "disk", d.shape.kind = AP_SHAPE_DISK, d.shape.radius = r;
  ap_body_def_uniform(&d, mass);
  ap_builder_add_body(b, &d, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  ap_builder_add_effect(b, &e, NULL);
  p->m = compile(b);
  /* axis a = R e_z tilted th from horizontal-left, b_up in the disk plane; w = 1 rad/s about
   * b_up (turning) and -6 rad/s about a (spinning); the centre velocity from rolling */
  double a[3] = {0, cos(th), -sin(th)}, bu[3] = {0, sin(th), cos(th)}, R[9];
  for (int i = 0; i < 3; i++) R[i] = (i == 0), R[3 + i] = -bu[i], R[6 + i] = a[i];
  p->q0[0] = 0.0, p->q0[1] = 0.0;
  ap_quat_from_matrix(R, p->q0 + 2);
  for (int i = 0; i < 3; i++) p->v0[2 + i] = 1.0 * bu[i] - 6.0 * a[i];
  ap_data *dd = NULL;
  int given[5] = {0, 0, 1, 1, 1};
  ap_data_create(p->m, &dd);
  if (ap_body_complete_speeds(p->m, dd, p->q0, given, p->v0) != AP_OK) exit(1);
  ap_data_free(dd);
  p->name = "rolling_disk", p->T = 6.0, p->npos = 2;
}

static int rod(ap_builder *b, const char *name, double mass, double comz, double I) {
  ap_body_def d = ap_body_def_default();
  int id = -1;
  d.name = name, d.mass = mass, d.com[2] = comz;
  d.inertia[0] = d.inertia[4] = I, d.inertia[8] = 1e-3 * I;
  ap_builder_add_body(b, &d, &id);
  return id;
}

static void setup_hoffmann(problem *p) {
  rs_hoffmann h = {1.0, 0.8, 0.5, 0.4, 0, 0, 9.81, 2.0};
  h.I1 = h.m1 * h.a1 * h.a1 / 3, h.I2 = h.m2 * h.a2 * h.a2 / 3;
  ap_builder *b = NULL;
  ap_builder_create("Hoffmann sliding", &b);
  int up = rod(b, "upper", h.m1, -h.a1, h.I1), lo = rod(b, "lower", h.m2, 0.0, h.I2);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_REVOLUTE, j.child = up, j.axis[0] = 1.0, j.axis[2] = 0.0;
  ap_builder_add_joint(b, &j, NULL);
  j.name = "hinge", j.parent = up, j.child = lo;
  j.parent_frame.pos[2] = -2 * h.a1, j.child_frame.pos[2] = h.a2;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "slider", c.kind = AP_CON_POINT_ON_PLANE, c.body = lo, c.body2 = AP_GROUND;
  c.point[2] = -h.a2, c.point2[1] = 0.3;
  ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[2] = -h.grav;
  ap_builder_add_effect(b, &e, NULL);
  e = ap_effect_def_default();
  e.name = "F", e.kind = AP_EFFECT_APPLIED, e.body = lo, e.force[1] = h.F;
  ap_builder_add_effect(b, &e, NULL);
  p->m = compile(b);
  ap_data *dd = NULL;
  int given[2] = {1, 0};
  double change = 0.0;
  p->q0[0] = 0.5, p->q0[1] = -0.5, p->v0[0] = 1.0, p->v0[1] = 0.0;
  ap_data_create(p->m, &dd);
  if (ap_body_project_q(p->m, dd, p->q0, &change) != AP_OK ||
      ap_body_complete_speeds(p->m, dd, p->q0, given, p->v0) != AP_OK)
    exit(1);
  ap_data_free(dd);
  p->name = "hoffmann_sliding", p->T = 6.0, p->npos = 2;
}

/* ---- runs -------------------------------------------------------------------------------- */

/* One run; err (max over outputs of |q - ref|, first npos), steps, evaluations. Returns 0 on
 * success. With out != NULL the positions are stored instead of compared. */
static int run(const problem *p, ap_mode mode, const char *method, double tol,
               double out[NOUT][MAXQ], double *err, long *steps, long *evals) {
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.method = method, sd.rtol = tol, sd.atol = tol, sd.max_steps = 200000;
  ap_sim *s = NULL;
  if (ap_sim_create(p->m, &sd, 0.0, p->q0, p->v0, &s, NULL, 0) != AP_OK) return 1;
  double e = 0.0;
  int rc = AP_OK;
  for (int i = 0; i < NOUT && rc == AP_OK; i++) {
    rc = ap_sim_advance(s, p->T * (i + 1) / NOUT);
    const double *q = ap_sim_q(s);
    for (int c = 0; c < p->npos && rc == AP_OK; c++) {
      if (out) out[i][c] = q[c];
      else e = fmax(e, fabs(q[c] - p->ref[i][c]));
    }
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  ap_sim_free(s);
  if (err) *err = e;
  if (steps) *steps = st.steps;
  if (evals) *evals = st.rhs_evals;
  return rc != AP_OK;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Median CPU time of repeated runs (warm-up first); < 0 when the run fails. */
static double timed(const problem *p, const curve *c, double tol, double *err, long *steps,
                    long *evals) {
  if (run(p, c->mode, c->method, tol, NULL, err, steps, evals)) return -1.0;
  double ts[15], total = 0.0;
  int n = 0;
  while (n < 15 && (n < 3 || total < 0.2)) {
    double t0 = cpu_now();
    run(p, c->mode, c->method, tol, NULL, NULL, NULL, NULL);
    ts[n] = cpu_now() - t0;
    total += ts[n++];
  }
  qsort(ts, (size_t)n, sizeof *ts, cmp_double);
  return ts[n / 2];
}

/* Time (or evaluations) of a curve at error level E, interpolated in logs; < 0 when it does
 * not bracket E. */
static double value_at(const double *err, const double *val, double E) {
  for (int i = 0; i + 1 < NTOL; i++) {
    if (!(val[i] > 0) || !(val[i + 1] > 0)) continue;
    double e0 = err[i], e1 = err[i + 1];
    if (!(e0 >= E && e1 <= E) || !(e0 > e1)) continue;
    double f = (log(E) - log(e0)) / (log(e1) - log(e0));
    return exp(log(val[i]) + f * (log(val[i + 1]) - log(val[i])));
  }
  return -1.0;
}

static void bench(problem *p, FILE *csv) {
  double dae_ref[NOUT][MAXQ], diff = 0.0;
  if (run(p, AP_MODE_MINIMAL, "fehlberg8", 1e-13, p->ref, NULL, NULL, NULL) ||
      run(p, AP_MODE_DAE, "dopri5", 1e-11, dae_ref, NULL, NULL, NULL)) {
    fprintf(stderr, "bench_dae: %s: the reference runs failed\n", p->name);
    exit(1);
  }
  for (int i = 0; i < NOUT; i++)
    for (int c = 0; c < p->npos; c++) diff = fmax(diff, fabs(dae_ref[i][c] - p->ref[i][c]));
  printf("%s, T = %g s: reference minimal fehlberg8 at rtol 1e-13; DAE at 1e-11 differs by "
         "%.2g\n", p->name, p->T, diff);
  double err[NCURVE][NTOL], cpu[NCURVE][NTOL], ev[NCURVE][NTOL];
  for (int ci = 0; ci < NCURVE; ci++)
    for (int ti = 0; ti < NTOL; ti++) {
      double tol = pow(10.0, -3.0 - ti);
      long steps = 0, evals = 0;
      cpu[ci][ti] = timed(p, &curves[ci], tol, &err[ci][ti], &steps, &evals);
      if (cpu[ci][ti] < 0) err[ci][ti] = NAN;
      ev[ci][ti] = cpu[ci][ti] < 0 ? -1.0 : (double)evals;
      if (cpu[ci][ti] < 0)
        printf("  %-20s rtol %.0e  failed (steps %ld)\n", curves[ci].label, tol, steps);
      else
        printf("  %-20s rtol %.0e  err %.3e  cpu %9.3f ms  steps %6ld  evals %7ld\n",
               curves[ci].label, tol, err[ci][ti], 1e3 * cpu[ci][ti], steps, evals);
      if (csv)
        fprintf(csv, "%s,%s,%.0e,%.6e,%.6e,%ld,%ld\n", p->name, curves[ci].label, tol,
                err[ci][ti], cpu[ci][ti], steps, evals);
    }
  printf("  %-6s  %-22s %10s  %10s  %12s  %s\n", "error", "cheapest Appell curve",
         "time (ms)", "DAE (ms)", "DAE / Appell", "evaluations Appell, DAE");
  for (double E = 1e-4; E >= 0.99e-10; E *= 1e-2) {
    int best = -1;
    double tb = -1.0, td = value_at(err[NCURVE - 1], cpu[NCURVE - 1], E);
    for (int ci = 0; ci + 1 < NCURVE; ci++) {
      double t = value_at(err[ci], cpu[ci], E);
      if (t > 0 && (tb < 0 || t < tb)) tb = t, best = ci;
    }
    if (best < 0 || td < 0) {
      printf("  %.0e  not reached by %s (tightest rtol 1e-11)\n", E,
             best < 0 ? "the Appell curves" : "the DAE curve");
      continue;
    }
    printf("  %.0e  %-22s %10.3f  %10.3f  %12.2f  %.0f, %.0f\n", E, curves[best].label,
           1e3 * tb, 1e3 * td, td / tb, value_at(err[best], ev[best], E),
           value_at(err[NCURVE - 1], ev[NCURVE - 1], E));
  }
}

int main(int argc, char **argv) {
  FILE *csv = NULL;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      csv = fopen(argv[++i], "w");
      if (!csv) return fprintf(stderr, "bench_dae: cannot write %s\n", argv[i]), 1;
      fprintf(csv, "problem,curve,rtol,err,cpu_s,steps,evals\n");
    } else {
      fprintf(stderr, "usage: bench_dae [--csv FILE]\n");
      return 2;
    }
  }
  problem P[2];
  memset(P, 0, sizeof P);
  setup_disk(&P[0]);
  setup_hoffmann(&P[1]);
  for (int i = 0; i < 2; i++) {
    bench(&P[i], csv);
    ap_model_free(P[i].m);
  }
  if (csv) fclose(csv);
  return 0;
}
