/* bench_vehicles: what the vehicles of examples/scenes cost (docs/vehicles.md "Cost").
 *
 * For each scene, next to the rolling disk (rolling_disk.yaml, one body on a plane-contact
 * joint) measured in the same run:
 *   eval    one ap_forward as the minimal-mode integrator calls it (partitioned basis, speeds
 *           from e'), from the scene's initial state: median and spread over `blocks` blocks
 *           of `reps` evaluations (thread CPU time), and evaluations per second;
 *   run     the scene simulated at rtol 1e-8 (atol 1e-10, dopri5) in minimal and projected
 *           mode to t_end: steps, right-hand-side evaluations, CPU time, and the error against
 *           the closed form where there is one (the robots' circle, the car's circle: the
 *           largest |x - x_exact|, |y - y_exact|, |heading - heading_exact| at 0.05 s outputs).
 * Instructions per evaluation do not depend on load:
 *   valgrind --tool=callgrind --toggle-collect=eval_block build/bench/bench_vehicles \
 *       --only diff_drive --reps 1000 --blocks 3 --no-run
 * counts every evaluation of the warm-up and timed blocks: divide the total by
 * reps x (blocks + 1) (bench_vehicles prints the divisor).
 * Usage: bench_vehicles [--only NAME] [--reps N] [--blocks N] [--no-run]
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

typedef struct vcase {
  const char *name, *file;
  double t_end;
  double R, Omega;       /* the closed-form circle of the chassis; R = 0: none */
} vcase;

static const vcase cases[] = {
    {"rolling_disk", "rolling_disk.yaml", 15.0, 0, 0},
    {"diff_drive", "diff_drive.yaml", 60.0, 1.25, 0.8},
    {"diff_drive_caster", "diff_drive_caster.yaml", 60.0, 1.25, 0.8},
    {"diff_drive_loops", "diff_drive_loops.yaml", 60.0, 1.25, 0.8},
    {"car_ackermann", "car_ackermann.yaml", 20.0, 0, 0},
};

/* ---- one evaluation ------------------------------------------------------------------------ */

/* ---- a run at rtol 1e-8 ---------------------------------------------------------------------- */

static void bench_run(const vcase *c, ap_scene *sc, const double *x, ap_mode mode) {
  const ap_model *m = ap_scene_model(sc);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.mode = mode, run.sim.method = "dopri5", run.sim.rtol = 1e-8, run.sim.atol = 1e-10;
  char msg[1024];
  ap_sim *sim = NULL;
  int n = ap_model_n(m), ix = ap_model_find_coord(m, "chassis.x");
  int iy = ap_model_find_coord(m, "chassis.y"), ih = ap_model_find_coord(m, "chassis.heading");
  double R = c->R, W = c->Omega, err = 0.0;
  if (strcmp(c->name, "car_ackermann") == 0) R = 1.2 / tan(0.3), W = 2.0 / R;
  double t0 = bench_thread_ns();
  if (ap_sim_create(m, &run.sim, run.t0, x, x + n, &sim, msg, sizeof msg) != AP_OK)
    bench_die(c->name, msg);
  int nout = (int)lround(c->t_end / 0.05);
  for (int i = 1; i <= nout; i++) {
    double t = 0.05 * i;
    if (ap_sim_advance(sim, t) != AP_OK) bench_die(c->name, ap_sim_message(sim));
    if (R == 0 || ix < 0) continue;
    const double *q = ap_sim_q(sim);
    double th = W * t;
    err = fmax(err, fmax(fmax(fabs(q[ix] - R * sin(th)), fabs(q[iy] - R * (1 - cos(th)))),
                         fabs(q[ih] - th)));
  }
  double cpu = (bench_thread_ns() - t0) * 1e-9;
  ap_sim_stats st;
  ap_sim_get_stats(sim, &st);
  printf("%-18s run   %-9s t_end %4.0f s  steps %6ld  evals %7ld  cpu %6.3f s", c->name,
         mode == AP_MODE_MINIMAL ? "minimal" : "projected", c->t_end, st.steps, st.rhs_evals,
         cpu);
  if (R > 0) printf("  error %.2e", err);
  printf("\n");
  ap_sim_free(sim);
}

int main(int argc, char **argv) {
  const char *only = NULL;
  int reps = 20000, blocks = 9, runs = 1;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = atoi(argv[++i]);
    else if (strcmp(argv[i], "--blocks") == 0 && i + 1 < argc) blocks = atoi(argv[++i]);
    else if (strcmp(argv[i], "--no-run") == 0) runs = 0;
    else bench_die("usage", "bench_vehicles [--only NAME] [--reps N] [--blocks N] [--no-run]");
  }
  if (reps < 1 || blocks < 1) bench_die("usage", "--reps and --blocks must be positive");
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const vcase *c = &cases[i];
    if (only && strcmp(only, c->name) != 0) continue;
    char file[1200], msg[1024];
    ap_scene *sc = NULL;
    snprintf(file, sizeof file, "%s/examples/scenes/%s", AP_SRCDIR, c->file);
    if (ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg) != AP_OK) bench_die(c->name, msg);
    const ap_model *m = ap_scene_model(sc);
    double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
    if (ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg) != AP_OK)
      bench_die(c->name, msg);
    bench_forward(c->name, 18, ap_scene_model(sc), x, reps, blocks);
    if (runs) bench_run(c, sc, x, AP_MODE_MINIMAL), bench_run(c, sc, x, AP_MODE_PROJECTED);
    free(x);
    ap_scene_free(sc);
  }
  return 0;
}
