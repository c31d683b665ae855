/* bench_linearize: the cost of linearizing one operating point and of a 101-value speed sweep
 * (issue 12 "Speed"; the bicycle's target, the whole 101-speed sweep under 100 ms, awaits the
 * bicycle model).
 *
 * Cases:
 *   disk_point   rolling disk (m 1, r 0.5), upright at 3 m/s: operating point (Newton: only a
 *                check here), A (8 x 8, Ridders) and B, eigenvalues of the non-cyclic block
 *   disk_sweep   the same at 101 speeds from 0 to 5 m/s (continuation), tracked, and the
 *                critical speed located by root finding (about 10 more linearizations)
 *   hoff_point   Hoffmann's pendulum as a body model with a loop closure (example scene):
 *                equilibrium by Newton from the scene's state, A (4 x 4), B, eigenvalues
 *   hoff_reduced the hand-derived Hoffmann system (tests/refsys.h), same work
 * Each is warmed up, then timed in `blocks` blocks of `reps` runs with the thread's CPU time
 * (the machine is shared); reported: median and spread (min..max) per run, and the number of
 * evaluations of the reduced equations (Appell solves) per run, from the data's counters.
 * Usage: bench_linearize [--csv FILE] [--reps N] [--blocks N]. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "analyze/analyze_int.h"
#include "appell/appell.h"
#include "refsys.h"

static double now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void check(int rc, const char *what, const ap_lin *L) {
  if (rc == AP_OK) return;
  fprintf(stderr, "bench_linearize: %s: %s: %s\n", what, ap_strerror(rc),
          L ? ap_lin_message(L) : "");
  exit(1);
}

/* ---- cases ----------------------------------------------------------------------------- */

typedef struct bcase {
  const char *name;
  ap_model *m;
  ap_lin_def def;
  double q[8], v[8], dir[8];
  int sweep;
} bcase;

static ap_model *disk(void) {
  ap_builder *b = NULL;
  ap_builder_create("disk", &b);
  ap_body_def d = ap_body_def_default();
  d.name = "disk", d.shape.kind = AP_SHAPE_DISK, d.shape.radius = 0.5, d.mass = 1.0;
  d.inertia[0] = d.inertia[4] = 0.0625, d.inertia[8] = 0.125;
  ap_builder_add_body(b, &d, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.body = 0;
  ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  ap_builder_add_effect(b, &e, NULL);
  ap_model *m = NULL;
  check(ap_builder_compile(b, &m), "disk model", NULL);
  ap_builder_free(b);
  return m;
}

/* One run: a fresh linearizer, the point or the sweep; returns the Appell solves it took. */
static long run_once(bcase *c, double *critical) {
  ap_lin *L = NULL;
  long evals = 0;
  check(ap_lin_create(c->m, &c->def, 0.0, c->q, c->v, &L), "create", L);
  if (!c->sweep) {
    check(ap_lin_operating_point(L, c->def.speed_dir ? 3.0 : NAN), "operating point", L);
    check(ap_lin_linearize(L), "linearize", L);
    check(ap_lin_eigen(L, NULL, 0, 1), "eigen", L);
  } else {
    double s[101];
    ap_lin_sweep sw;
    for (int i = 0; i < 101; i++) s[i] = 5.0 * i / 100;
    check(ap_lin_sweep_speed(L, s, 101, NULL, 0, 1, 1e-14, &sw), "sweep", L);
    *critical = sw.npoints ? sw.points[0].p : NAN;
    ap_lin_sweep_free(&sw);
  }
  evals = L->d->cnt.acceleration;
  ap_lin_free(L);
  return evals;
}

static void measure(bcase *c, int reps, int blocks, FILE *csv) {
  double crit = NAN, *ns = malloc(sizeof *ns * (size_t)blocks);
  long evals = 0;
  if (!ns) exit(1);
  for (int i = 0; i < 3; i++) evals = run_once(c, &crit);   /* warm up */
  for (int b = 0; b < blocks; b++) {
    double t0 = now_ns();
    for (int i = 0; i < reps; i++) run_once(c, &crit);
    ns[b] = (now_ns() - t0) / reps;
  }
  qsort(ns, (size_t)blocks, sizeof *ns, cmp_double);
  printf("%-13s %12.3f %12.3f %12.3f %10ld", c->name, ns[blocks / 2] * 1e-6, ns[0] * 1e-6,
         ns[blocks - 1] * 1e-6, evals);
  if (c->sweep) printf("   critical speed %.15g (sqrt(g r/3) = %.15g)", crit, sqrt(9.81 * 0.5 / 3));
  printf("\n");
  if (csv)
    fprintf(csv, "%s,%.6f,%.6f,%.6f,%ld\n", c->name, ns[blocks / 2] * 1e-6, ns[0] * 1e-6,
            ns[blocks - 1] * 1e-6, evals);
  free(ns);
}

static void machine(void) {
  FILE *f = fopen("/proc/cpuinfo", "r");
  char line[512];
  int cpus = 0;
  const char *model = "unknown";
  static char buf[256];
  while (f && fgets(line, sizeof line, f)) {
    if (strncmp(line, "model name", 10) == 0) {
      cpus++;
      char *p = strchr(line, ':');
      if (p && cpus == 1) snprintf(buf, sizeof buf, "%s", p + 2), model = buf;
    }
  }
  if (f) fclose(f);
  buf[strcspn(buf, "\n")] = '\0';
  printf("machine: %s, %d logical CPUs; thread CPU time\n", model, cpus);
}

int main(int argc, char **argv) {
  int reps = 20, blocks = 11;
  const char *csvname = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csvname = argv[++i];
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blocks") && i + 1 < argc) blocks = atoi(argv[++i]);
    else return fprintf(stderr, "usage: bench_linearize [--csv FILE] [--reps N] [--blocks N]\n"), 2;
  }
  if (reps < 1 || blocks < 1) return 2;
  machine();
  FILE *csv = csvname ? fopen(csvname, "w") : NULL;
  if (csv) fprintf(csv, "case,median_ms,min_ms,max_ms,appell_solves\n");
  printf("%-13s %12s %12s %12s %10s\n", "case", "median (ms)", "min (ms)", "max (ms)", "solves");
  /* the disk: upright, rolling along +x (axis along -y), speed parameter in m/s */
  bcase c = {"disk_point", disk(), ap_lin_def_default(), {0, 0, sqrt(0.5), sqrt(0.5), 0, 0},
             {0}, {1, 0, 0, 2, 0}, 0};
  c.def.speed_dir = c.dir;
  measure(&c, reps, blocks, csv);
  c.name = "disk_sweep", c.sweep = 1;
  measure(&c, reps > 4 ? reps / 4 : 1, blocks, csv);
  ap_model_free(c.m);
  /* Hoffmann: the example scene (loop closure) and the hand-derived system */
  char file[1200], msg[1024];
  const char *src = getenv("APPELL_SOURCE_DIR");
  snprintf(file, sizeof file, "%s/examples/scenes/hoffmann.yaml", src ? src : "..");
  ap_scene *sc = NULL;
  check(ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg), msg, NULL);
  bcase h = {"hoff_point", (ap_model *)ap_scene_model(sc), ap_lin_def_default(), {0}, {0}, {0},
             0};
  static const char *const ind[] = {"upper.angle", "lower.heading", "upper.angle_dot",
                                    "lower.heading_dot", NULL};
  h.def.about = AP_LIN_EQUILIBRIUM, h.def.independent = ind;
  check(ap_scene_initial_state(sc, h.q, h.v, NULL, 0, msg, sizeof msg), msg, NULL);
  measure(&h, reps, blocks, csv);
  double I = 0.0833333333333333;
  rs_hoffmann p = {1.0, 1.0, 0.5, 0.5, I, I, 9.81, 2.0};
  ap_system_def sd;
  rs_hoffmann_reduced_system(&p, &sd);
  bcase r = {"hoff_reduced", NULL, ap_lin_def_default(), {0.3, -0.2}, {0, 0}, {0}, 0};
  check(ap_model_from_system(&sd, &r.m, NULL, 0), "reduced model", NULL);
  r.def.about = AP_LIN_EQUILIBRIUM;
  measure(&r, reps, blocks, csv);
  ap_model_free(r.m);
  ap_scene_free(sc);
  if (csv) fclose(csv);
  return 0;
}
