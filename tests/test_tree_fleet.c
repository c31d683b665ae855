/* Fleets on the tree path (docs/large.md): vehicles with wheel contacts on revolute joints of
 * a chassis and trailers with knife edges, each vehicle one tree. Against the dense path
 * through ap_sim, minimal and projected mode at rtol 1e-6 and 1e-9 (tree_compare.h: the end
 * states within 20 rtol): 2 and 5 differential-drive robots, some pulling trailers. Also: the
 * automatic choice takes a fleet of 16 speeds or more; the tree path picks the dense path's
 * partition; the example scene fleet_16.yaml on both paths; refused on a forced tree path: a
 * wheel contact with friction, wheel loads asked for (path auto takes the dense path then), a
 * wheel contact of a body on a free joint. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "tree_compare.h"
#include "treemodels.h"

static void fleet(int N, int every, double t1) {
  ap_model *md = tm_fleet(N, every, AP_PATH_DENSE), *mt = tm_fleet(N, every, AP_PATH_TREE);
  AP_CHECK_EQ_INT(ap_model_path(md), AP_PATH_DENSE);
  AP_CHECK_EQ_INT(ap_model_path(mt), AP_PATH_TREE);
  int n = ap_model_n(md), k = ap_model_k(md);
  double *x = calloc((size_t)(n + k), sizeof(double));
  tm_fleet_state(md, N, every, x, x + n);
  char label[32];
  snprintf(label, sizeof label, "fleet %d", N);
  compare_runs(label, md, mt, x, x + n, t1);
  /* the tree path picks the dense path's partition (pivoted QR on each robot's block) */
  ap_data *dd = NULL, *dt = NULL;
  AP_CHECK_EQ_INT(ap_data_create(md, &dd), AP_OK);
  AP_CHECK_EQ_INT(ap_data_create(mt, &dt), AP_OK);
  for (ap_data *d = dd; d; d = d == dd ? dt : NULL) {
    memcpy(d->q, x, sizeof(double) * (size_t)n);
    memcpy(d->v, x + n, sizeof(double) * (size_t)k);
    d->t = 0.0;
    AP_CHECK_EQ_INT(ap_partition(d == dd ? md : mt, d), AP_OK);
  }
  AP_CHECK_EQ_INT(dt->rank, dd->rank);
  int same = 1;
  for (int c = dd->rank; c < k; c++) same &= dt->perm[c] == dd->perm[c];
  AP_CHECK(same);
  ap_data_free(dd), ap_data_free(dt);
  free(x);
  ap_model_free(md), ap_model_free(mt);
}

/* Disks tilted 20-40 degrees, spinning and turning; q closed on the contacts, v completed. */
int main(int argc, char **argv) {
  if (argc < 2) return fprintf(stderr, "usage: test_tree_fleet SOURCE_ROOT\n"), 2;
  /* the example fleet (16 robots on motors, parts/robot.yaml) and a single robot */
  scene_both(argv[1], "fleet_16", "simulation.t_end=0.5");
  scene_both(argv[1], "diff_drive_motors", "simulation.t_end=2");
  fleet(2, 2, 2.0);
  /* refused, with the reason: a wheel contact with friction (contact modes) */
  char file[1024], msg[512] = "";
  const char *set[2] = {"simulation.path=tree", "output.channels=[coordinates]"};
  ap_scene *s = NULL;
  snprintf(file, sizeof file, "%s/examples/scenes/diff_drive_brake.yaml", argv[1]);
  AP_CHECK(ap_scene_load(file, set, 2, &s, msg, sizeof msg) != AP_OK);
  AP_CHECK(strstr(msg, "friction") != NULL && strstr(msg, "tree path") != NULL);
  printf("forced tree path with friction: %s\n", msg);
  ap_scene_free(s);
  /* wheel loads (contact_forces of wheel contacts): auto takes the dense path, tree refuses */
  snprintf(file, sizeof file, "%s/examples/scenes/fleet_16.yaml", argv[1]);
  const char *cf[2] = {"output.channels=[coordinates, contact_forces]", "simulation.path=tree"};
  s = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, cf, 1, &s, msg, sizeof msg), AP_OK);
  AP_CHECK(s && ap_model_path(ap_scene_model(s)) == AP_PATH_DENSE);
  ap_scene_free(s);
  s = NULL;
  AP_CHECK(ap_scene_load(file, cf, 2, &s, msg, sizeof msg) != AP_OK);
  AP_CHECK(strstr(msg, "dense path only") != NULL);
  printf("forced tree path with wheel loads: %s\n", msg);
  ap_scene_free(s);
  fleet(5, 3, 2.0);
  /* refused: a wheel contact of a body on a free joint (wrong runs with a spring on it) */
  snprintf(file, sizeof file, "%s/tests/scenes/tree_free_rolling.yaml", argv[1]);
  s = NULL;
  AP_CHECK(ap_scene_load(file, cf + 1, 1, &s, msg, sizeof msg) != AP_OK);
  AP_CHECK(strstr(msg, "free joint") != NULL);
  printf("forced tree path, free rolling body: %s\n", msg);
  ap_scene_free(s);
  s = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, NULL, 0, &s, msg, sizeof msg), AP_OK);
  ap_scene_free(s);
  /* the automatic choice: a fleet of 16 speeds or more takes the tree path */
  ap_model *m = tm_fleet(4, 0, AP_PATH_AUTO);
  AP_CHECK(ap_model_k(m) >= AP_TREE_AUTO_K);
  AP_CHECK_EQ_INT(ap_model_path(m), AP_PATH_TREE);
  ap_model_free(m);
  return ap_check_finish("test_tree_fleet");
}
