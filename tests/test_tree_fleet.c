/* Fleets on the tree path (docs/large.md): vehicles with wheel contacts on revolute joints of
 * a chassis and trailers with knife edges, each vehicle one tree. Against the dense path
 * through ap_sim, minimal and projected mode at rtol 1e-6 and 1e-9 (tree_compare.h: the end
 * states within 20 rtol): 2 and 5 differential-drive robots, some pulling trailers; free disks
 * rolling as wheel contacts (a free joint: the contact rows' phi drifts and is projected after
 * every step, so the tree path's projection runs); a robot beside a free sphere rolling with a
 * spring or damper on it (free_rolling_scene); the suspended car, whose rows are redundant
 * only where its wheel contacts close (suspended_car); refused: a rolling body on a free joint
 * to another body. Also: the automatic choice takes a fleet of
 * 16 speeds or more; ap_body_project_q on both paths gives the same q; the energy agrees at
 * the tree path picks the dense path's partition; the example scene fleet_16.yaml on both
 * paths; refused on a forced tree path: a wheel contact with friction, wheel loads asked for
 * (path auto takes the dense path then). */
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
static void free_disks_state(const ap_model *m, int N, double *q, double *v) {
  ap_data *d = NULL;
  int k = ap_model_k(m), *given = calloc((size_t)k, sizeof(int));
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  const double ex[3] = {1, 0, 0};
  for (int i = 0; i < N; i++) {
    double *qi = q + 7 * i, *vi = v + 6 * i, R[9], tilt = (20.0 + 20.0 * i / N) * 3.14159265358979323846 / 180;
    qi[0] = 1.5 * i, qi[1] = 0.0, qi[2] = 0.3 * cos(tilt) + 1e-7;   /* a little off: closed below */
    ap_quat_from_axis_angle(ex, tilt, qi + 3);
    ap_quat_to_matrix(qi + 3, R);
    for (int r = 0; r < 3; r++) vi[3 + r] = (-8.0 + i) * R[6 + r] + (r == 2 ? 1.5 : 0.0);
    given[6 * i + 3] = given[6 * i + 4] = given[6 * i + 5] = 1;
  }
  double change = 0.0;
  AP_CHECK_EQ_INT(ap_body_project_q(m, d, q, &change), AP_OK);
  AP_CHECK(change > 0.0);
  d->t = 0;
  AP_CHECK_EQ_INT(ap_body_complete_speeds(m, d, q, given, v), AP_OK);
  ap_data_free(d);
  free(given);
}

static void rolling_free(int N, double t1) {
  ap_model *md = tm_free_disks(N, AP_PATH_DENSE), *mt = tm_free_disks(N, AP_PATH_TREE);
  AP_CHECK_EQ_INT(ap_model_path(mt), AP_PATH_TREE);
  int n = ap_model_n(md), k = ap_model_k(md);
  double *x = calloc((size_t)(2 * n + k), sizeof(double)), *q2 = x + n + k;
  free_disks_state(md, N, x, x + n);
  compare_runs("free disks", md, mt, x, x + n, t1);
  /* one projection of q off the contacts, both paths: the same q */
  ap_data *dd = NULL, *dt = NULL;
  AP_CHECK_EQ_INT(ap_data_create(md, &dd), AP_OK);
  AP_CHECK_EQ_INT(ap_data_create(mt, &dt), AP_OK);
  for (int i = 0; i < N; i++) x[7 * i + 2] += 1e-5 * (i + 1), x[7 * i + 4] += 1e-5;
  memcpy(q2, x, sizeof(double) * (size_t)n);
  double cd = 0.0, ct = 0.0, phi = 1.0;
  AP_CHECK_EQ_INT(ap_body_project_q(md, dd, x, &cd), AP_OK);
  AP_CHECK_EQ_INT(ap_body_project_q(mt, dt, q2, &ct), AP_OK);
  AP_CHECK(cd > 1e-6);
  AP_CHECK_NEAR(ct, cd, 1e-9 * cd);
  AP_CHECK_LE(rel_diff(n, x, q2), 1e-13);
  memcpy(dt->q, q2, sizeof(double) * (size_t)n);
  AP_CHECK_EQ_INT(ap_body_loop_residual(mt, dt, &phi), AP_OK);
  AP_CHECK_LE(phi, 1e-12 * 0.3);
  printf("projection: |dq| dense-tree %.2e, change %.3e, phi after %.2e\n",
         rel_diff(n, x, q2), ct, phi);
  ap_data_free(dd), ap_data_free(dt);
  free(x);
  ap_model_free(md), ap_model_free(mt);
}

/* q off the contacts: the free body's height (".z") up 1e-5, the wheel angles moved. */
static void lift(const ap_model *m, double *q) {
  for (int i = 0, a = 0; i < ap_model_n(m); i++) {
    const char *nm = ap_model_coord_name(m, i), *dot = strrchr(nm, '.');
    if (dot && !strcmp(dot, ".z")) q[i] += 1e-5;
    if (dot && !strcmp(dot, ".angle")) q[i] += 1.2345 * ++a;
  }
}

/* A test scene (tests/scenes/NAME.yaml: a planar robot beside a free sphere rolling with a
 * spring or joint damping on it, difftest seeds 1001385, 1000051) on both paths from the
 * dense path's initial state to its t_end (compare_runs); then one closure of q lifted off the
 * contacts (lift) on both paths: the same q. Before the fix the tree path took the rank of
 * each tree's contact rows relative to that tree alone, so the chassis' rows (identically
 * zero, gradients of round-off) moved the wheel angles by -phi / 1e-17: tens of radians. */
static void free_rolling_scene(const char *root, const char *name) {
  char file[1024], msg[512] = "";
  snprintf(file, sizeof file, "%s/tests/scenes/%s.yaml", root, name);
  ap_scene *s[2] = {NULL, NULL};
  const char *set[2] = {"simulation.path=dense", "simulation.path=tree"};
  for (int p = 0; p < 2; p++)
    AP_CHECK_EQ_INT(ap_scene_load(file, set + p, 1, &s[p], msg, sizeof msg), AP_OK);
  const ap_model *md = s[0] ? ap_scene_model(s[0]) : NULL;
  const ap_model *mt = s[1] ? ap_scene_model(s[1]) : NULL;
  if (md && mt) {
    AP_CHECK_EQ_INT(ap_model_path(mt), AP_PATH_TREE);
    int n = ap_model_n(md), k = ap_model_k(md);
    double *x = calloc((size_t)(3 * n + k), sizeof(double)), *qd = x + n + k, *qt = qd + n;
    ap_scene_run run;
    ap_scene_get_run(s[0], &run);
    AP_CHECK_EQ_INT(ap_scene_initial_state(s[0], x, x + n, NULL, 0, msg, sizeof msg), AP_OK);
    compare_runs(name, md, mt, x, x + n, run.t_end);
    ap_data *dd = NULL, *dt = NULL;
    AP_CHECK_EQ_INT(ap_data_create(md, &dd), AP_OK);
    AP_CHECK_EQ_INT(ap_data_create(mt, &dt), AP_OK);
    memcpy(qd, x, sizeof(double) * (size_t)n);
    lift(md, qd);
    memcpy(qt, qd, sizeof(double) * (size_t)n);
    double cd = 0.0, ct = 0.0;
    AP_CHECK_EQ_INT(ap_body_project_q(md, dd, qd, &cd), AP_OK);
    AP_CHECK_EQ_INT(ap_body_project_q(mt, dt, qt, &ct), AP_OK);
    printf("%s: one closure, |dq| dense-tree %.2e (change %.3e)\n", name,
           rel_diff(n, qd, qt), cd);
    AP_CHECK(cd > 1e-6);
    AP_CHECK_LE(rel_diff(n, qd, qt), 1e-12);
    ap_data_free(dd), ap_data_free(dt);
    free(x);
  }
  ap_scene_free(s[0]), ap_scene_free(s[1]);
}

/* The suspended car (car_suspension.yaml: a free chassis on four sprung struts; 3 of its 14
 * rows are redundant, 2 only where the wheel contacts close). Standing, 2 s at rtol 1e-10 on
 * both paths (scene_both). Then in minimal and projected mode with the free coordinates'
 * probe first (ap_sim_free_coordinates evaluates the model off the manifold by 1e-3, where
 * those rows look independent and inconsistent: the tree path stopped there in minimal mode
 * before it told them apart), to t = 0.5: the tree path's run ends where the dense path's does
 * (20 rtol). Plain mode refuses such rows on both paths. */
static int car_run(const char *file, int tree, ap_mode mode, double *x, int *n, int *k) {
  char msg[512] = "";
  const char *set[2] = {tree ? "simulation.path=tree" : "simulation.path=dense",
                        "output.channels=[coordinates]"};
  ap_scene *s = NULL;
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, set, 2, &s, msg, sizeof msg), AP_OK);
  if (!s) return AP_ERR_ARG;
  const ap_model *m = ap_scene_model(s);
  *n = ap_model_n(m), *k = ap_model_k(m);
  ap_scene_run run;
  ap_scene_get_run(s, &run);
  run.sim.mode = mode;
  int rc = ap_scene_initial_state(s, x, x + *n, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_create(m, &run.sim, run.t0, x, x + *n, &sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_free_coordinates(sim, (int *)(x + *n + *k));
  if (rc == AP_OK) rc = ap_sim_advance(sim, 0.5);
  if (rc == AP_OK) memcpy(x, ap_sim_q(sim), sizeof(double) * (size_t)*n);
  if (rc == AP_OK) memcpy(x + *n, ap_sim_v(sim), sizeof(double) * (size_t)*k);
  if (rc != AP_OK) printf("car_suspension %s, mode %d: %s\n", set[0], (int)mode,
                          sim ? ap_sim_message(sim) : msg);
  AP_CHECK(mode != AP_MODE_PLAIN || strstr(msg, "2 constraint rows are redundant only where"));
  ap_sim_free(sim);
  ap_scene_free(s);
  return rc;
}

static void suspended_car(const char *root) {
  scene_both(root, "car_suspension", "output.channels=[coordinates]");
  char file[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/car_suspension.yaml", root);
  double *x = calloc(200, sizeof(double)), *y = x + 100;
  int n = 0, k = 0;
  const ap_mode modes[2] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED};
  for (int i = 0; i < 2; i++) {
    AP_CHECK_EQ_INT(car_run(file, 0, modes[i], x, &n, &k), AP_OK);
    AP_CHECK_EQ_INT(car_run(file, 1, modes[i], y, &n, &k), AP_OK);
    double eq = rel_diff(n, x, y), ev = rel_diff(k, x + n, y + n);
    printf("car_suspension %-9s probed: |dq| %.2e  |dv| %.2e at t = 0.5\n",
           i ? "projected" : "minimal", eq, ev);
    AP_CHECK_LE(eq, 20 * 1e-10);
    AP_CHECK_LE(ev, 20 * 1e-10);
  }
  for (int p = 0; p < 2; p++)   /* refused alike */
    AP_CHECK_EQ_INT(car_run(file, p, AP_MODE_PLAIN, x, &n, &k), AP_ERR_UNSUPPORTED);
  free(x);
}

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
  rolling_free(3, 1.0);
  free_rolling_scene(argv[1], "tree_free_rolling");
  free_rolling_scene(argv[1], "tree_free_damped");
  suspended_car(argv[1]);
  /* refused: a rolling body on a free joint to another body (bdf's runs on the tree path) */
  snprintf(file, sizeof file, "%s/tests/scenes/tree_free_hung.yaml", argv[1]);
  s = NULL;
  AP_CHECK(ap_scene_load(file, cf + 1, 1, &s, msg, sizeof msg) != AP_OK);
  AP_CHECK(strstr(msg, "free joint to another body") != NULL);
  printf("forced tree path, hung free rolling body: %s\n", msg);
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
