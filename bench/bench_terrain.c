/* bench_terrain: the cost of one ap_forward (as the minimal-mode integrator calls it) of a ball
 * rolling on each kind of ground: the incline (ball_incline.yaml), the ground sphere from inside
 * (ball_bowl.yaml), the same bowl as a height field z = 1 - sqrt(1 - x^2 - y^2) (Newton on the
 * closest point, h and its derivatives from the expression's jets: the price of a general
 * surface over the closed form), and the bumps of ball_bumps.yaml; each at its scene's initial
 * state, evaluated again and again (the Newton solve warm-started from the last point).
 * Instructions do not depend on the load of the machine:
 *   valgrind --tool=callgrind --toggle-collect=eval_block build/bench/bench_terrain \
 *       --only bowl_field --reps 1000 --blocks 3
 * and divide by the printed divisor reps x (blocks + 1).
 * Usage: bench_terrain [--only NAME] [--reps N] [--blocks N]. Run with OPENBLAS_NUM_THREADS=1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "benchutil.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

typedef struct tcase {
  const char *name, *file, *set;
} tcase;

static const tcase cases[] = {
    {"incline", "ball_incline.yaml", NULL},
    {"bowl_sphere", "ball_bowl.yaml", NULL},
    {"bowl_field", "ball_bowl.yaml", "ground={kind: height_field, z: \"1 - sqrt(1 - x^2 - y^2)\"}"},
    {"bumps_field", "ball_bumps.yaml", NULL}};

int main(int argc, char **argv) {
  const char *only = NULL;
  int reps = 20000, blocks = 7;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--only") == 0) only = argv[i + 1];
    else if (strcmp(argv[i], "--reps") == 0) reps = atoi(argv[i + 1]);
    else if (strcmp(argv[i], "--blocks") == 0) blocks = atoi(argv[i + 1]);
    else bench_die("bench_terrain", "usage: [--only NAME] [--reps N] [--blocks N]");
  }
  if (reps < 1 || blocks < 1) bench_die("bench_terrain", "--reps and --blocks must be >= 1");
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    const tcase *t = &cases[c];
    if (only && strcmp(only, t->name) != 0) continue;
    char file[1024], msg[1024];
    ap_scene *sc = NULL;
    snprintf(file, sizeof file, "%s/examples/scenes/%s", AP_SRCDIR, t->file);
    if (ap_scene_load(file, &t->set, t->set ? 1 : 0, &sc, msg, sizeof msg) != AP_OK)
      bench_die(t->name, msg);
    const ap_model *m = ap_scene_model(sc);
    double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
    if (!x) bench_die(t->name, "out of memory");
    if (ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, msg, sizeof msg) != AP_OK)
      bench_die(t->name, msg);
    bench_forward(t->name, 12, m, x, reps, blocks);
    free(x);
    ap_scene_free(sc);
  }
  return 0;
}
