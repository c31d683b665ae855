/* bench_control: what a controller in the loop costs a run (docs/control.md, "Cost";
 * docs/performance.md). The same run is made without a controller (plain) and with one called
 * every `period` (10 ms by default) whose value changes at every call, so that the stepper is
 * stopped and restarted at every instant (ctrl): the controller returns +-1e-9 N m in turn,
 * too small to move the trajectory, so both runs take the same path and the ratio is the cost
 * of the mechanism (the stops, the restarts, the evaluation for the call), not of a different
 * motion or of the user's code.
 *
 * Scenes: the Whipple bicycle (examples/scenes/bicycle.yaml, self-stable at 4.6 m/s, its
 * rtol 1e-10; input: the steer torque) and the torque-driven diff-drive robot
 * (diff_drive_control.yaml, rtol 1e-8, coasting at 0.5 m/s; inputs: the wheel torques), each
 * advanced to t_end through outputs every 0.01 s, as appell run does, in minimal mode with
 * dopri5.
 *
 * Reported per scene: steps, right-hand-side evaluations and restarts of each run (exact), the
 * ratio of evaluations, and the CPU-time ratio ctrl/plain as the median over `rounds` ABAB
 * rounds (thread CPU time; A and B alternate so that the machine's load falls on both).
 * Instructions: valgrind --tool=callgrind --toggle-collect=run_plain --toggle-collect=run_ctrl
 * build/bench/bench_control --rounds 1 --only bicycle; callgrind_annotate --inclusive=yes
 * shows both (run_plain is called rounds + 1 times: a warm-up, then one per round).
 * Usage: bench_control [--rounds N] [--period S] [--t-end S] [--only bicycle|diff_drive].
 * Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "benchutil.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

typedef struct bscene {
  const char *name, *file, *inputs;
  ap_scene *sc;
  double q0[32], v0[32];
} bscene;

typedef struct brun {
  ap_sim_stats st;
  double ns;
} brun;

static int flip(double t, const double *q, const double *v, double *u, void *user) {
  (void)t, (void)q, (void)v;
  long *calls = user;
  (*calls)++;
  u[0] = (*calls % 2 ? 1e-9 : -1e-9);
  return 0;
}

static ap_sim *start(const bscene *b) {
  ap_scene_run run;
  ap_scene_get_run(b->sc, &run);
  ap_sim *s = NULL;
  char msg[512];
  if (ap_sim_create(ap_scene_model(b->sc), &run.sim, 0.0, b->q0, b->v0, &s, msg, sizeof msg))
    bench_die(b->name, msg);
  return s;
}

static void advance_all(ap_sim *s, const char *name, double t_end) {
  long n = lround(t_end / 0.01);
  for (long i = 1; i <= n; i++)
    if (ap_sim_advance(s, i == n ? t_end : 0.01 * (double)i) != AP_OK)
      bench_die(name, ap_sim_message(s));
}

/* Separate functions, so that callgrind can collect each (--toggle-collect). */
__attribute__((noinline)) void run_plain(const bscene *b, double t_end, brun *r) {
  ap_sim *s = start(b);
  double t0 = bench_thread_ns();
  advance_all(s, b->name, t_end);
  r->ns = bench_thread_ns() - t0;
  ap_sim_get_stats(s, &r->st);
  ap_sim_free(s);
}

__attribute__((noinline)) void run_ctrl(const bscene *b, double t_end, double period, brun *r) {
  ap_sim *s = start(b);
  char msg[512];
  long calls = 0;
  if (ap_scene_add_inputs(b->sc, s, msg, sizeof msg) != AP_OK) bench_die(b->name, msg);
  if (ap_sim_set_controller(s, flip, period, &calls) != AP_OK)
    bench_die(b->name, ap_sim_message(s));
  double t0 = bench_thread_ns();
  advance_all(s, b->name, t_end);
  r->ns = bench_thread_ns() - t0;
  ap_sim_get_stats(s, &r->st);
  ap_sim_free(s);
}

static void load(bscene *b) {
  char path[4096], msg[1024];
  const char *sets[] = {b->inputs};
  snprintf(path, sizeof path, "%s/examples/scenes/%s", AP_SRCDIR, b->file);
  if (ap_scene_load(path, sets, 1, &b->sc, msg, sizeof msg) != AP_OK) bench_die(b->name, msg);
  if (ap_scene_initial_state(b->sc, b->q0, b->v0, NULL, 0, msg, sizeof msg) != AP_OK)
    bench_die(b->name, msg);
}

static void bench(bscene *b, int rounds, double period, double t_end) {
  double *ratio = calloc((size_t)rounds, sizeof *ratio);
  brun p = {0}, c = {0};
  if (!ratio) bench_die(b->name, "out of memory");
  run_plain(b, t_end, &p);   /* warm-up */
  for (int i = 0; i < rounds; i++) {
    run_plain(b, t_end, &p);
    run_ctrl(b, t_end, period, &c);
    ratio[i] = c.ns / p.ns;
  }
  qsort(ratio, (size_t)rounds, sizeof *ratio, bench_cmp_double);
  printf("%-14s plain: %6ld steps %7ld evals %4ld restarts %8.2f ms | ctrl %.3g s: %6ld steps "
         "%7ld evals %5ld restarts %8.2f ms | evals x%.3f, CPU x%.3f (median of %d; %.3f-%.3f)\n",
         b->name, p.st.steps, p.st.rhs_evals, p.st.restarts, 1e-6 * p.ns, period, c.st.steps,
         c.st.rhs_evals, c.st.restarts, 1e-6 * c.ns, (double)c.st.rhs_evals / (double)p.st.rhs_evals,
         ratio[rounds / 2], rounds, ratio[0], ratio[rounds - 1]);
  free(ratio);
}

int main(int argc, char **argv) {
  int rounds = 9;
  double period = 0.01, t_end = 10.0;
  const char *only = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--rounds") && i + 1 < argc) rounds = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--period") && i + 1 < argc) period = atof(argv[++i]);
    else if (!strcmp(argv[i], "--t-end") && i + 1 < argc) t_end = atof(argv[++i]);
    else if (!strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
    else bench_die("usage", "bench_control [--rounds N] [--period S] [--t-end S] [--only NAME]");
  }
  if (rounds < 1 || !(period > 0) || !(t_end > 0)) bench_die("usage", "bad argument");
  bscene scenes[] = {
      {"bicycle", "bicycle.yaml", "inputs=[front_frame.angle_dot]", NULL, {0}, {0}},
      {"diff_drive", "diff_drive_control.yaml", "initial.chassis.vx=0.5", NULL, {0}, {0}},
  };
  for (int i = 0; i < 2; i++) {
    if (only && strcmp(only, scenes[i].name)) continue;
    load(&scenes[i]);
    bench(&scenes[i], rounds, period, t_end);
    ap_scene_free(scenes[i].sc);
  }
  return 0;
}
