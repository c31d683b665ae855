/* bench_linearize: the cost of linearizing one operating point and of a 101-value speed sweep
 * (issue 12 "Speed": the Whipple bicycle's whole 101-speed sweep under 100 ms).
 *
 * Cases:
 *   disk_point   rolling disk (m 1, r 0.5), upright at 3 m/s: operating point (Newton: only a
 *                check here), A (8 x 8) and B, eigenvalues of the non-cyclic block
 *   disk_sweep   the same at 101 speeds from 0 to 5 m/s (continuation), tracked, and the
 *                critical speed located by root finding (about 10 more linearizations)
 *   bike_point   the Whipple bicycle (examples/scenes/bicycle.yaml and its linearize:
 *                section), upright at 5 m/s: operating point, A (10 x 10), B (2 inputs),
 *                eigenvalues of the roll/steer block (4 x 4)
 *   bike_sweep   the same at 101 speeds from 0 to 10 m/s, tracked, with the three
 *                characteristic speeds (v_d, weave, capsize) located by root finding
 *   bike_point_ridders, bike_sweep_ridders   the same with Ridders' differences (the
 *                fallback) instead of the default complex step, in the same run
 *   hoff_point   Hoffmann's pendulum as a body model with a loop closure (example scene):
 *                equilibrium by Newton from the scene's state, A (4 x 4), B, eigenvalues
 *   hoff_reduced the hand-derived Hoffmann system (tests/refsys.h), same work
 * Each is warmed up, then timed in `blocks` blocks of `reps` runs with the thread's CPU time
 * (the machine is shared; the load average is printed); A by the default method (the complex
 * step) unless the name says Ridders; reported: median and spread (min..max) per run, and the
 * number of evaluations of the reduced equations (Appell solves, real and complex-step) per
 * run, from the data's counters.
 * The scene is loaded once, outside the timing (a run starts from the loaded model and the
 * guess). --only NAME runs one case (for valgrind --tool=callgrind --toggle-collect=run_once).
 * Usage: bench_linearize [--csv FILE] [--reps N] [--blocks N] [--only NAME]. Run with
 * OPENBLAS_NUM_THREADS=1 and APPELL_SOURCE_DIR (default ..). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "appell/appell.h"
#include "benchutil.h"
#include "refsys.h"

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
  double q[16], v[16], dir[16];
  int sweep;
  double s_point, s_to;    /* speed of the point; the sweep runs from 0 to s_to */
  int sel[4], ns;          /* the subsystem (ns = 0: the non-cyclic states) */
} bcase;

static const char *only = NULL;

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
long run_once(bcase *c, double *critical);   /* not static: a callgrind entry point */
long run_once(bcase *c, double *critical) {
  ap_lin *L = NULL;
  long evals = 0;
  check(ap_lin_create(c->m, &c->def, 0.0, c->q, c->v, &L), "create", L);
  if (!c->sweep) {
    check(ap_lin_operating_point(L, c->def.speed_dir ? c->s_point : NAN), "operating point", L);
    check(ap_lin_linearize(L), "linearize", L);
    check(ap_lin_eigen(L, c->ns ? c->sel : NULL, c->ns, 1), "eigen", L);
  } else {
    double s[101];
    ap_lin_sweep sw;
    for (int i = 0; i < 101; i++) s[i] = c->s_to * i / 100;
    check(ap_lin_sweep_speed(L, s, 101, c->ns ? c->sel : NULL, c->ns, 1,
                             1e-14 * fmax(1.0, c->s_to), &sw), "sweep", L);
    for (int i = 0; i < 3; i++) critical[i] = i < sw.npoints ? sw.points[i].p : NAN;
    ap_lin_sweep_free(&sw);
  }
  evals = L->d->cnt.acceleration + (L->ws_cs.d ? L->ws_cs.d->cnt.acceleration : 0);
  ap_lin_free(L);
  return evals;
}

static void measure(bcase *c, int reps, int blocks, FILE *csv) {
  if (only && strcmp(only, c->name) != 0) return;
  double crit[3] = {NAN, NAN, NAN}, *ns = malloc(sizeof *ns * (size_t)blocks);
  long evals = 0;
  if (!ns) exit(1);
  for (int i = 0; i < (only ? 1 : 3); i++) evals = run_once(c, crit);   /* warm up */
  for (int b = 0; b < blocks; b++) {
    double t0 = bench_thread_ns();
    for (int i = 0; i < reps; i++) run_once(c, crit);
    ns[b] = (bench_thread_ns() - t0) / reps;
  }
  qsort(ns, (size_t)blocks, sizeof *ns, bench_cmp_double);
  printf("%-18s %12.3f %12.3f %12.3f %10ld", c->name, ns[blocks / 2] * 1e-6, ns[0] * 1e-6,
         ns[blocks - 1] * 1e-6, evals);
  if (c->sweep && c->ns == 0)
    printf("   critical speed %.15g (sqrt(g r/3) = %.15g)", crit[0], sqrt(9.81 * 0.5 / 3));
  else if (c->sweep)
    printf("   v_d %.15g, weave %.15g, capsize %.15g", crit[0], crit[1], crit[2]);
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
  double load[3] = {NAN, NAN, NAN};
  f = fopen("/proc/loadavg", "r");
  if (f && fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3) load[0] = NAN;
  if (f) fclose(f);
  printf("machine: %s, %d logical CPUs; thread CPU time; load average %.2f %.2f %.2f\n", model,
         cpus, load[0], load[1], load[2]);
}

/* The bicycle from its scene and linearize: section (the guess and the speed direction). */
static void bike(const char *src, int reps, int blocks, FILE *csv) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/bicycle.yaml", src);
  ap_scene_lin_guess g;
  check(ap_scene_lin_guess_load(file, NULL, 0, NULL, 0, &g, msg, sizeof msg), msg, NULL);
  if (g.n > 16 || g.k > 16 || !g.dir) check(AP_ERR_INTERNAL, "bicycle sizes", NULL);
  bcase c = {"bike_point", (ap_model *)ap_scene_model(g.scene), ap_scene_lin_def(&g), {0}, {0},
             {0}, 0, 5.0, 10.0, {0}, 4};
  memcpy(c.q, g.q, sizeof *g.q * (size_t)g.n);
  memcpy(c.v, g.v0, sizeof *g.v * (size_t)g.k);
  memcpy(c.dir, g.dir, sizeof *g.dir * (size_t)g.k);
  c.def.speed_dir = c.dir;
  ap_lin *L = NULL;   /* the states of the roll/steer block (the partition is deterministic) */
  check(ap_lin_create(c.m, &c.def, g.t0, c.q, c.v, &L), "create", L);
  check(ap_lin_operating_point(L, 0.0), "operating point", L);
  for (int i = 0; i < 4; i++) {
    c.sel[i] = ap_lin_find_state(L, g.sec.states[i]);
    if (c.sel[i] < 0) check(AP_ERR_INTERNAL, "the bicycle's states", L);
  }
  ap_lin_free(L);
  measure(&c, reps, blocks, csv);
  c.name = "bike_sweep", c.sweep = 1;
  measure(&c, reps > 4 ? reps / 4 : 1, blocks, csv);
  c.def.method = AP_LIN_RIDDERS;
  c.name = "bike_point_ridders", c.sweep = 0;
  measure(&c, reps, blocks, csv);
  c.name = "bike_sweep_ridders", c.sweep = 1;
  measure(&c, reps > 4 ? reps / 4 : 1, blocks, csv);
  ap_scene_lin_guess_free(&g);
}

int main(int argc, char **argv) {
  int reps = 20, blocks = 11;
  const char *csvname = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csvname = argv[++i];
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blocks") && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
    else return fprintf(stderr, "usage: bench_linearize [--csv FILE] [--reps N] [--blocks N] "
                        "[--only NAME]\n"), 2;
  }
  if (reps < 1 || blocks < 1) return 2;
  machine();
  FILE *csv = csvname ? fopen(csvname, "w") : NULL;
  if (csv) fprintf(csv, "case,median_ms,min_ms,max_ms,appell_solves\n");
  printf("%-18s %12s %12s %12s %10s\n", "case", "median (ms)", "min (ms)", "max (ms)", "solves");
  /* the disk: upright, rolling along +x (axis along -y), speed parameter in m/s */
  bcase c = {"disk_point", disk(), ap_lin_def_default(), {0, 0, sqrt(0.5), sqrt(0.5), 0, 0},
             {0}, {1, 0, 0, 2, 0}, 0, 3.0, 5.0, {0}, 0};
  c.def.speed_dir = c.dir;
  measure(&c, reps, blocks, csv);
  c.name = "disk_sweep", c.sweep = 1;
  measure(&c, reps > 4 ? reps / 4 : 1, blocks, csv);
  ap_model_free(c.m);
  char file[1200], msg[1024];
  const char *src = getenv("APPELL_SOURCE_DIR");
  bike(src ? src : "..", reps, blocks, csv);
  /* Hoffmann: the example scene (loop closure) and the hand-derived system */
  snprintf(file, sizeof file, "%s/examples/scenes/hoffmann.yaml", src ? src : "..");
  ap_scene *sc = NULL;
  check(ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg), msg, NULL);
  bcase h = {"hoff_point", (ap_model *)ap_scene_model(sc), ap_lin_def_default(), {0}, {0}, {0},
             0, 0.0, 0.0, {0}, 0};
  static const char *const ind[] = {"upper.angle", "lower.heading", "upper.angle_dot",
                                    "lower.heading_dot", NULL};
  h.def.about = AP_LIN_EQUILIBRIUM, h.def.independent = ind;
  check(ap_scene_initial_state(sc, h.q, h.v, NULL, 0, msg, sizeof msg), msg, NULL);
  measure(&h, reps, blocks, csv);
  double I = 0.0833333333333333;
  rs_hoffmann p = {1.0, 1.0, 0.5, 0.5, I, I, 9.81, 2.0};
  ap_system_def sd;
  rs_hoffmann_reduced_system(&p, &sd);
  bcase r = {"hoff_reduced", NULL, ap_lin_def_default(), {0.3, -0.2}, {0, 0}, {0}, 0, 0.0, 0.0,
             {0}, 0};
  check(ap_model_from_system(&sd, &r.m, NULL, 0), "reduced model", NULL);
  r.def.about = AP_LIN_EQUILIBRIUM;
  measure(&r, reps, blocks, csv);
  ap_model_free(r.m);
  ap_scene_free(sc);
  if (csv) fclose(csv);
  return 0;
}
