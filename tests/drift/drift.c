/* Constraint-drift regression runs (issue 7; docs/drift.md).
 *
 * Long runs (>= 1e5 accepted steps; 1e6 in the "long" runs of the slow suite) of every example
 * system in every mode, each reduced to a few drift figures:
 *
 *   residual   max |A v + a0| over all accepted steps (ap_sim_stats.max_residual)
 *   loop       max |phi(q)| of the position-level closure over the outputs (m): the body
 *              model's loop closures (ap_body_loop_residual), or Hoffmann's primitive
 *              connection y = 2 a1 sin(theta) + a2 sin(phi), z = ... (math level)
 *   quat       max ||q| - 1| of the quaternions over the outputs
 *   energy     max |E - E0| / |E0| over the outputs (conservative systems)
 *   L_z, spin  the heavy top's momentum about the vertical and spin (relative, as energy)
 *   c, w_z     the turntable ball's conserved complex number z' - i k Omega z (absolute, m/s)
 *              and its spin about the vertical (absolute, rad/s)
 *   jacobi     the rotating line's Jacobi integral (relative)
 *   speed      the spinning ball's speeds, all constant: max |v - v0| (absolute, m/s and rad/s)
 *   track      its centre's distance from the straight line x0 + v0 t (absolute, m)
 *
 * A figure regresses when max(value, floor) > 2 max(baseline, floor), or when it is NaN. The
 * floors (floor_of: per quantity, 4 eps per step for the invariants, 100 rtol in DAE mode) sit
 * above the round-off spread of the figures, measured by running every case again from
 * initial states perturbed by 1e-15 relative (--perturb N): values under the floor are noise,
 * not drift. The baselines themselves are the largest figure over such perturbed runs
 * (scripts/refresh-drift), since chaotic motions (rattleback, rolling disk) turn the last bits
 * of the start into a different sample of the same drift.
 *
 * usage: drift [--group G]... [--mode M] [--check BASELINES.csv] [--write OUT.csv] [--perturb N]
 *              [--list]
 * Without --group every run is made. --check fails (exit 1) on a regression, a NaN, a run with
 * fewer steps than it promises, or a figure without a baseline; --write writes the figures
 * (system,mode,quantity,value) for scripts/refresh-drift. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "drift.h"

/* ---- quantities and their floors --------------------------------------------------------- */

typedef struct quantity {
  const char *name;
  double floor;
} quantity;

static const quantity quantities[] = {
    {"residual", 1e-14}, {"loop", 1e-14},  {"quat", 1e-14}, {"energy", 1e-13},
    {"L_z", 1e-13},      {"spin", 1e-13},  {"c", 1e-13},    {"w_z", 1e-13},
    {"jacobi", 1e-13},   {"speed", 1e-13}, {"track", 1e-13},
};
#define NQUANT ((int)(sizeof quantities / sizeof quantities[0]))

/* Two more floors, both measured:
 * - energy and the other invariants accumulate round-off at every step, and in a nearly
 *   steady state the same rounding repeats: the projected sleigh in its final straight-line
 *   motion gains 3 eps per step (6.9e-10 after 1e6 steps from one perturbed start, 2.8e-11
 *   from the next: whether the rounding is biased is itself decided by the last bits). Their
 *   floor is 4 eps per step taken.
 * - the DAE mode's figures sit at the level of IDA's Newton tolerance, where which iteration
 *   stops where depends on the last bits: under 1e-15 perturbations of the initial state they
 *   spread by up to 26x below 1e-6 (rtol 1e-8). Its floor is 100 rtol. */
static double floor_of(const char *name, ap_mode mode, double rtol, long steps) {
  double fl = 0.0;
  for (int i = 0; i < NQUANT; i++)
    if (strcmp(quantities[i].name, name) == 0) fl = quantities[i].floor;
  /* the spinning ball's speeds and track: its accelerations vanish, so the steps carry v
   * exactly and round-off enters only through a projection (the case is there for that) */
  if (strcmp(name, "residual") && strcmp(name, "loop") && strcmp(name, "quat") &&
      strcmp(name, "speed") && strcmp(name, "track"))
    fl = fmax(fl, 4.0 * DBL_EPSILON * (double)steps);
  return mode == AP_MODE_DAE ? fmax(fl, 100.0 * rtol) : fl;
}

static const char *const mode_names[4] = {"minimal", "projected", "dae", "plain"};

/* ---- one run ------------------------------------------------------------------------------ */

/* Outputs: 2000, so that output times fall on the step grids of the runs with h_max (1e-3,
 * 1e-4). Before issue 10 the DAE sleigh from a state perturbed by -1e-15 ended a step
 * 1.6e-11 s short of t = 5.5 there, and IDA's index-2 Newton iteration failed on the sliver
 * (h = 3e-19); the suite used 1999 outputs to avoid it. DAE mode now never leaves a sliver
 * before an output (dae.c, tests/test_dae_tight.c). */
#define NOUT 2000
#define MAXFIG 8

typedef struct figures {
  int n;
  const char *name[MAXFIG];
  double value[MAXFIG];
  long steps;
  double seconds;
  char msg[512];
} figures;

static void add_fig(figures *f, const char *name, double value) {
  f->name[f->n] = name, f->value[f->n] = value, f->n++;
}

static double quat_error(const sysrun *r, const double *q) {
  double e = 0.0;
  for (int i = 0; i < r->nquat; i++) {
    const double *p = q + r->quat[i];
    e = fmax(e, fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]) - 1.0));
  }
  return e;
}

/* Drift of invariant i from inv0 to inv. The turntable's c compares the complex number. */
static double inv_drift(const drift_sys *s, int i, const double *inv0, const double *inv) {
  if (strcmp(s->inv[i], "c") == 0) return hypot(inv[i] - inv0[i], inv[MAXINV] - inv0[MAXINV]);
  double dev = fabs(inv[i] - inv0[i]);
  return s->inv_scale[i] > 0 ? dev / fmax(fabs(inv0[i]), s->inv_scale[i]) : dev;
}

/* fmax that keeps a NaN (fmax drops it). */
static double maxnan(double a, double b) { return isnan(a) || isnan(b) ? NAN : fmax(a, b); }

static int run_one(const drift_sys *s, ap_mode mode, int perturb, figures *f) {
  sysrun r;
  memset(&r, 0, sizeof r);
  memset(f, 0, sizeof *f);
  r.sys = s;
  int rc = s->setup(&r);
  if (rc == AP_OK) rc = ap_data_create(r.m, &r.d);
  if (rc != AP_OK) {
    snprintf(f->msg, sizeof f->msg, "setup failed (%d)", rc);
    ap_model_free(r.m);
    return rc;
  }
  int k = ap_model_k(r.m);
  for (int i = 0; perturb && i < k; i++)   /* 1e-15 relative: the round-off spread */
    r.v0[i] *= 1.0 + 1e-15 * perturb * (i % 2 ? 1 : -1);
  double inv0[MAXINV + 1], inv[MAXINV + 1], loop = 0.0, dinv[MAXINV] = {0}, dloop = 0.0;
  double dquat = quat_error(&r, r.q0);
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.method = s->method, sd.rtol = s->rtol, sd.atol = 1e-2 * s->rtol;
  sd.h_max = s->h_max, sd.max_steps = 10 * s->min_steps;
  ap_sim *sim = NULL;
  clock_t c0 = clock();
  rc = ap_sim_create(r.m, &sd, 0.0, r.q0, r.v0, &sim, f->msg, sizeof f->msg);
  if (rc == AP_OK) rc = s->measure(&r, 0.0, r.q0, r.v0, inv0, &loop);
  dloop = loop;
  double t_end = mode == AP_MODE_DAE ? s->dae_t_end : s->t_end;
  for (int i = 1; rc == AP_OK && i <= NOUT; i++) {
    double t = t_end * i / NOUT;
    rc = ap_sim_advance(sim, t);
    if (rc != AP_OK) {
      snprintf(f->msg, sizeof f->msg, "t = %g: %s", ap_sim_time(sim), ap_sim_message(sim));
      break;
    }
    const double *q = ap_sim_q(sim), *v = ap_sim_v(sim);
    rc = s->measure(&r, t, q, v, inv, &loop);
    for (int c = 0; c < s->ninv; c++) dinv[c] = maxnan(dinv[c], inv_drift(s, c, inv0, inv));
    dloop = s->has_loop ? maxnan(dloop, loop) : 0.0;
    dquat = maxnan(dquat, quat_error(&r, q));
  }
  f->seconds = (double)(clock() - c0) / CLOCKS_PER_SEC;
  if (sim) {
    ap_sim_stats st;
    ap_sim_get_stats(sim, &st);
    f->steps = st.steps;
    if (ap_model_b(r.m) > 0) add_fig(f, "residual", st.max_residual);
  }
  if (s->has_loop) add_fig(f, "loop", dloop);
  if (r.nquat) add_fig(f, "quat", dquat);
  for (int c = 0; c < s->ninv; c++) add_fig(f, s->inv[c], dinv[c]);
  ap_sim_free(sim);
  ap_data_free(r.d);
  ap_model_free(r.m);
  return rc;
}

/* ---- baselines ---------------------------------------------------------------------------- */

typedef struct baseline {
  char system[64], mode[16], quantity[16];
  double value;
  int used;
} baseline;

static baseline *base = NULL;
static int nbase = 0;

static int read_baselines(const char *path) {
  FILE *fp = fopen(path, "r");
  if (!fp) return fprintf(stderr, "drift: cannot open %s\n", path), -1;
  char line[256];
  while (fgets(line, sizeof line, fp)) {
    if (line[0] == '#' || line[0] == '\n' || strncmp(line, "system,", 7) == 0) continue;
    baseline b;
    memset(&b, 0, sizeof b);
    char *p = line, *fld[4];
    for (int i = 0; i < 4; i++) {
      fld[i] = p;
      p = p ? strchr(p, ',') : NULL;
      if (p) *p++ = '\0';
    }
    if (!fld[3]) continue;
    snprintf(b.system, sizeof b.system, "%s", fld[0]);
    snprintf(b.mode, sizeof b.mode, "%s", fld[1]);
    snprintf(b.quantity, sizeof b.quantity, "%s", fld[2]);
    b.value = strtod(fld[3], NULL);
    baseline *nb = realloc(base, sizeof *base * (size_t)(nbase + 1));
    if (!nb) break;
    base = nb, base[nbase++] = b;
  }
  fclose(fp);
  return 0;
}

static baseline *find_baseline(const char *sys, const char *mode, const char *q) {
  for (int i = 0; i < nbase; i++)
    if (!strcmp(base[i].system, sys) && !strcmp(base[i].mode, mode) &&
        !strcmp(base[i].quantity, q))
      return &base[i];
  return NULL;
}

/* ---- main --------------------------------------------------------------------------------- */

static int in_groups(const char *g, char **groups, int ng) {
  if (ng == 0) return 1;
  for (int i = 0; i < ng; i++)
    if (strcmp(groups[i], g) == 0) return 1;
  return 0;
}

static int mode_index(const char *name) {
  for (int i = 0; i < 4; i++)
    if (strcmp(mode_names[i], name) == 0) return i;
  return -1;
}

int main(int argc, char **argv) {
  char *groups[32];
  int ng = 0, perturb = 0, list = 0, only = -1;
  const char *check = NULL, *write = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--group") && i + 1 < argc && ng < 32) groups[ng++] = argv[++i];
    else if (!strcmp(argv[i], "--check") && i + 1 < argc) check = argv[++i];
    else if (!strcmp(argv[i], "--write") && i + 1 < argc) write = argv[++i];
    else if (!strcmp(argv[i], "--mode") && i + 1 < argc) {
      if ((only = mode_index(argv[++i])) < 0)
        return fprintf(stderr, "drift: unknown mode '%s'\n", argv[i]), 2;
    } else if (!strcmp(argv[i], "--perturb") && i + 1 < argc) perturb = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--list")) list = 1;
    else return fprintf(stderr, "usage: drift [--group G]... [--mode M] [--check FILE] "
                        "[--write FILE] [--perturb N] [--list]\n"), 2;
  }
  if (check && read_baselines(check) != 0) return 1;
  FILE *out = NULL;
  if (write && !(out = fopen(write, "w"))) return fprintf(stderr, "cannot write %s\n", write), 1;
  for (int si = 0; si < drift_nsys; si++) {
    const drift_sys *s = &drift_systems[si];
    if (!in_groups(s->group, groups, ng)) continue;
    for (int mode = 0; mode < 4; mode++) {
      if (!(s->modes & (1u << mode)) || (only >= 0 && mode != only)) continue;
      if (list) {
        printf("%s %s %s\n", s->group, s->name, mode_names[mode]);
        continue;
      }
      figures f;
      int rc = run_one(s, (ap_mode)mode, perturb, &f);
      printf("%-18s %-9s %8ld steps %6.2f s%s%s\n", s->name, mode_names[mode], f.steps,
             f.seconds, rc == AP_OK ? "" : "  FAILED: ", rc == AP_OK ? "" : f.msg);
      AP_CHECK_EQ_INT(rc, AP_OK);
      AP_CHECK(f.steps >= s->min_steps);
      for (int i = 0; i < f.n; i++) {
        double fl = floor_of(f.name[i], (ap_mode)mode, s->rtol, f.steps);
        if (out) fprintf(out, "%s,%s,%s,%.3e\n", s->name, mode_names[mode], f.name[i], f.value[i]);
        if (!check) {
          printf("    %-9s %.3e\n", f.name[i], f.value[i]);
          continue;
        }
        baseline *b = find_baseline(s->name, mode_names[mode], f.name[i]);
        double limit = b ? 2.0 * fmax(b->value, fl) : NAN;
        printf("    %-9s %.3e  baseline %.3e  floor %.1e  %s\n", f.name[i], f.value[i],
               b ? b->value : NAN, fl,
               !b ? "NO BASELINE (run scripts/refresh-drift)"
               : !(fmax(f.value[i], fl) <= limit) || isnan(f.value[i]) ? "REGRESSED" : "ok");
        if (b) b->used = 1;
        AP_CHECK(b != NULL);
        AP_CHECK(!isnan(f.value[i]));
        if (b) AP_CHECK_LE(fmax(f.value[i], fl), limit);
      }
    }
  }
  if (out) fclose(out);
  free(base);
  return list ? 0 : ap_check_finish("drift");
}
