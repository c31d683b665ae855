/* bench_bicycle: what the Whipple bicycle (examples/scenes/bicycle.yaml) costs, next to the
 * rolling disk (rolling_disk.yaml) measured in the same run (docs/vehicles.md "The Whipple
 * bicycle", "Cost").
 *   load    ap_scene_load (read, parse, compile the model) and then ap_scene_initial_state
 *           (the consistent initial state): median and spread of `loads` loads, thread CPU
 *           time; the target is a scene loaded in under 10 ms;
 *   eval    one ap_forward as the minimal-mode integrator calls it (partitioned basis, speeds
 *           from e'), at the scene's initial state: median and spread over `blocks` blocks of
 *           `reps` evaluations (thread CPU time), evaluations per second; the target is under
 *           8 us (PyDy's generated bicycle right-hand side: 8.34 us);
 *   run     10 s at rtol 1e-8 (--rtol; atol 1e-2 rtol; dopri5, and IDA in DAE mode) in every
 *           mode: steps, evaluations, CPU time, the largest contact row |phi| (the wheels'
 *           lowest points off the ground, not timed) and the error against a run at rtol 1e-13
 *           (minimal mode): the largest difference of the lean, the steer (rad) and the rear
 *           wheel centre's x, y (m) at 0.01 s outputs.
 * Instructions do not depend on the load of the machine:
 *   valgrind --tool=callgrind --toggle-collect=eval_block build/bench/bench_bicycle \
 *       --only bicycle --reps 1000 --blocks 3 --loads 1 --no-run
 * collects every evaluation of the warm-up and timed blocks: divide by reps x (blocks + 1)
 * (printed as the divisor); --toggle-collect=load_one counts the loads with their initial
 * states (a warm-up, `loads` timed ones and the one evaluated: divide by loads + 2).
 * Hoffmann's two rods with their loop closure (hoffmann.yaml) are measured the same way (load
 * and eval; no runs): the third scene whose evaluation cost the generic-scalar conversion of
 * lib/core and lib/model was checked against.
 * Usage: bench_bicycle [--only bicycle|rolling_disk|hoffmann] [--reps N] [--blocks N]
 *                      [--loads N] [--rtol X] [--no-run]
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "benchutil.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

static void scene_path(const char *name, char *file, size_t len) {
  snprintf(file, len, "%s/examples/scenes/%s.yaml", AP_SRCDIR, name);
}

/* ---- loading ------------------------------------------------------------------------------- */

/* One load with its initial state (callgrind: --toggle-collect=load_one). */
__attribute__((noinline)) ap_scene *load_one(const char *file, double *x, size_t xlen,
                                             double *t_load) {
  char msg[1024];
  ap_scene *sc = NULL;
  double t0 = bench_thread_ns();
  if (ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg) != AP_OK) bench_die(file, msg);
  *t_load = bench_thread_ns() - t0;
  const ap_model *m = ap_scene_model(sc);
  if ((size_t)(ap_model_n(m) + ap_model_k(m)) > xlen) bench_die(file, "state too large");
  if (ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg) != AP_OK)
    bench_die(file, msg);
  return sc;
}

static void bench_load(const char *name, int loads) {
  char file[1200];
  scene_path(name, file, sizeof file);
  double *tl = malloc(sizeof(double) * (size_t)loads), *ti = malloc(sizeof(double) * (size_t)loads);
  double x[64], t_load;
  ap_scene_free(load_one(file, x, 64, &t_load));   /* warm-up: the file in the page cache */
  for (int i = 0; i < loads; i++) {
    double t0 = bench_thread_ns();
    ap_scene *sc = load_one(file, x, 64, &t_load);
    ti[i] = bench_thread_ns() - t0, tl[i] = t_load;
    ap_scene_free(sc);
  }
  qsort(tl, (size_t)loads, sizeof *tl, bench_cmp_double);
  qsort(ti, (size_t)loads, sizeof *ti, bench_cmp_double);
  printf("%-13s load  %8.3f ms (%.3f..%.3f); with the initial state %.3f ms (%.3f..%.3f)  "
         "callgrind divisor %d\n", name, tl[loads / 2] * 1e-6, tl[0] * 1e-6,
         tl[loads - 1] * 1e-6, ti[loads / 2] * 1e-6, ti[0] * 1e-6, ti[loads - 1] * 1e-6,
         loads + 2);
  free(tl), free(ti);
}

/* ---- one evaluation ------------------------------------------------------------------------ */

/* ---- runs at rtol 1e-8 against rtol 1e-13 ---------------------------------------------------- */

#define NOUT 1000              /* 10 s, outputs every 0.01 s */

typedef struct track {
  double v[NOUT + 1][4];       /* lean, steer, x, y */
} track;

static void bench_run(ap_scene *sc, const double *x, ap_mode mode, double rtol, track *tr,
                      const track *ref) {
  const ap_model *m = ap_scene_model(sc);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.mode = mode, run.sim.method = "dopri5", run.sim.rtol = rtol;
  run.sim.atol = 1e-2 * rtol;
  int n = ap_model_n(m), iq = ap_model_find_coord(m, "rear_frame.qw");
  int ix = ap_model_find_coord(m, "rear_frame.x"), is = ap_model_find_coord(m, "front_frame.angle");
  if (iq < 0 || ix < 0 || is < 0) bench_die("bicycle", "coordinates not found");
  int wheel[2] = {ap_model_find_body(m, "rear_wheel"), ap_model_find_body(m, "front_wheel")};
  char msg[1024];
  ap_sim *sim = NULL;
  ap_data *d = NULL;
  double t0 = bench_thread_ns(), ang = 0, pos = 0, phi = 0, cpu = 0;
  if (ap_data_create(m, &d) != AP_OK) bench_die("run", "ap_data_create");
  if (ap_sim_create(m, &run.sim, 0, x, x + n, &sim, msg, sizeof msg) != AP_OK)
    bench_die("run", msg);
  for (int i = 0; i <= NOUT; i++) {
    if (i > 0 && ap_sim_advance(sim, 0.01 * i) != AP_OK) {
      printf("%-13s run   mode %d rtol %.0e failed: %s\n", "bicycle", (int)mode, rtol,
             ap_sim_message(sim));
      ap_sim_free(sim), ap_data_free(d);
      return;
    }
    const double *q = ap_sim_q(sim), *p = q + iq;
    double t1 = bench_thread_ns();           /* the contact rows, outside the timed part */
    ap_body_state st;
    memcpy(d->q, q, sizeof(double) * (size_t)n);
    memcpy(d->v, ap_sim_v(sim), sizeof(double) * (size_t)ap_model_k(m));
    d->t = 0.01 * i;
    for (int w = 0; w < 2; w++)
      if (ap_body_eval(m, d) == AP_OK && ap_body_get_state(m, d, wheel[w], &st) == AP_OK)
        phi = fmax(phi, fabs(st.contact[2]));
    cpu -= bench_thread_ns() - t1;
    double nn = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
    double *o = tr->v[i];
    o[0] = acos(1 - 2 * (p[1] * p[1] + p[2] * p[2]) / nn) - acos(-1.0) / 2;   /* tilt - pi/2 */
    o[1] = q[is], o[2] = q[ix], o[3] = q[ix + 1];
    if (ref)
      ang = fmax(ang, fmax(fabs(o[0] - ref->v[i][0]), fabs(o[1] - ref->v[i][1]))),
      pos = fmax(pos, fmax(fabs(o[2] - ref->v[i][2]), fabs(o[3] - ref->v[i][3])));
  }
  cpu = (cpu + bench_thread_ns() - t0) * 1e-9;
  ap_sim_stats st;
  ap_sim_get_stats(sim, &st);
  ap_data_free(d);
  const char *mn = mode == AP_MODE_MINIMAL ? "minimal" : mode == AP_MODE_PROJECTED ? "projected"
                                                                                    : "dae";
  printf("%-13s run   %-9s rtol %.0e  steps %6ld  evals %7ld  cpu %6.3f s", "bicycle", mn,
         rtol, st.steps, st.rhs_evals, cpu);
  printf("  contact rows %.1e m", phi);
  if (ref) printf("  error: lean, steer %.1e rad; x, y %.1e m", ang, pos);
  printf("\n");
  ap_sim_free(sim);
}

int main(int argc, char **argv) {
  const char *only = NULL;
  int reps = 20000, blocks = 9, loads = 51, runs = 1;
  double rtol = 1e-8;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = atoi(argv[++i]);
    else if (strcmp(argv[i], "--blocks") == 0 && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (strcmp(argv[i], "--loads") == 0 && i + 1 < argc) loads = atoi(argv[++i]);
    else if (strcmp(argv[i], "--rtol") == 0 && i + 1 < argc) rtol = atof(argv[++i]);
    else if (strcmp(argv[i], "--no-run") == 0) runs = 0;
    else bench_die("usage", "bench_bicycle [--only bicycle|rolling_disk|hoffmann] [--reps N] "
             "[--blocks N] "
             "[--loads N] [--rtol X] [--no-run]");
  }
  if (reps < 1 || blocks < 1 || loads < 1 || !(rtol > 0))
    bench_die("usage", "--reps, --blocks, --loads and --rtol must be > 0");
  const char *names[3] = {"rolling_disk", "bicycle", "hoffmann"};
  for (int c = 0; c < 3; c++) {
    if (only && strcmp(only, names[c]) != 0) continue;
    char file[1200];
    double x[64], t_load;
    scene_path(names[c], file, sizeof file);
    bench_load(names[c], loads);
    ap_scene *sc = load_one(file, x, 64, &t_load);
    bench_forward(names[c], 13, ap_scene_model(sc), x, reps, blocks);
    if (runs && c == 1) {
      static track ref, tr;
      bench_run(sc, x, AP_MODE_MINIMAL, 1e-13, &ref, NULL);
      for (int mode = 0; mode < 3; mode++) bench_run(sc, x, (ap_mode)mode, rtol, &tr, &ref);
    }
    ap_scene_free(sc);
  }
  return 0;
}
