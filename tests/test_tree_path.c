/* The tree path chosen at compile time and used by the drivers (docs/large.md): the trailer
 * chain and N rolling disks run through ap_sim on the dense path and on the tree path, in
 * minimal and projected mode, at two tolerances. The two are the same ODE in different
 * coordinates (the tree path picks its dependent speeds body by body), so the trajectories
 * agree to the integrators' global error: max |q_dense - q_tree| and |v_dense - v_tree| at the
 * end, relative to max(1, |x|), within 20 rtol. Also: the automatic choice (tree at
 * AP_TREE_AUTO_K speeds and more, never for a loop closure), the refusals (a forced tree path
 * on a loop; the DAE mode and linearization on a tree model), the data's missing dense arrays,
 * the body queries (energy, contact forces) equal on both paths at one state, and a second
 * projection of projected speeds that does not move them. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "tree_compare.h"
#include "treemodels.h"

/* Energy and contact forces of the disks at their initial state: both paths, one ap_forward
 * with reactions each. */
static void compare_queries(ap_model *md, ap_model *mt, const double *q0, const double *v0) {
  ap_data *dd = NULL, *dt = NULL;
  AP_CHECK_EQ_INT(ap_data_create(md, &dd), AP_OK);
  AP_CHECK_EQ_INT(ap_data_create(mt, &dt), AP_OK);
  AP_CHECK(dt->g == NULL && dt->A == NULL && dt->B == NULL && dt->G == NULL && dt->N == NULL);
  ap_data *ds[2] = {dd, dt};
  ap_model *ms[2] = {md, mt};
  double T[2], V[2];
  for (int i = 0; i < 2; i++) {
    ap_data *d = ds[i];
    memcpy(d->q, q0, sizeof(double) * (size_t)d->n);
    memcpy(d->v, v0, sizeof(double) * (size_t)d->k);
    d->t = 0.0, d->want_reactions = 1;
    AP_CHECK_EQ_INT(ap_partition(ms[i], d), AP_OK);
    AP_CHECK_EQ_INT(ap_forward(ms[i], d), AP_OK);
  }
  AP_CHECK_LE(rel_diff(dd->k, dd->vdot, dt->vdot), 1e-12);
  for (int c = 0; c < 3; c++) {   /* the first three rolling constraints */
    ap_contact_force fd, ft;
    AP_CHECK_EQ_INT(ap_body_contact_force(md, dd, NULL, c, &fd), AP_OK);
    AP_CHECK_EQ_INT(ap_body_contact_force(mt, dt, NULL, c, &ft), AP_OK);
    for (int r = 0; r < 3; r++) AP_CHECK_NEAR(ft.force[r], fd.force[r], 1e-10 * fabs(fd.normal));
  }
  for (int i = 0; i < 2; i++) AP_CHECK_EQ_INT(ap_body_energy(ms[i], ds[i], &T[i], &V[i]), AP_OK);
  AP_CHECK_NEAR(T[1], T[0], 1e-12 * T[0]);
  AP_CHECK_NEAR(V[1], V[0], 1e-12 * fabs(V[0]) + 1e-12);
  AP_CHECK_NEAR(ap_kinetic_energy(dt, dt->v), T[0], 1e-12 * T[0]);
  /* projecting projected speeds leaves them as they are (the projection works from the
   * residual, as the dense path's; 27 of 60 states moved when it did not) */
  int moved = 0;
  for (int rep = 0; rep < 8; rep++) {
    double *v1 = calloc((size_t)(2 * dt->k), sizeof(double)), *v2 = v1 + dt->k, c1 = 0, c2 = 0;
    for (int i = 0; i < dt->k; i++) v1[i] = v0[i] * (1.0 + 0.01 * rep) + 1e-3 * (i % 7) * rep;
    AP_CHECK_EQ_INT(ap_project_speeds(mt, dt, v1, &c1), AP_OK);
    memcpy(v2, v1, sizeof(double) * (size_t)dt->k);
    AP_CHECK_EQ_INT(ap_project_speeds(mt, dt, v2, &c2), AP_OK);
    for (int i = 0; i < dt->k; i++) moved += v2[i] != v1[i];
    AP_CHECK(rep == 0 || c1 > 0);
    free(v1);
  }
  AP_CHECK_EQ_INT(moved, 0);
  ap_body_state sd, st;
  AP_CHECK_EQ_INT(ap_body_get_state(md, dd, 2, &sd), AP_OK);
  AP_CHECK_EQ_INT(ap_body_get_state(mt, dt, 2, &st), AP_OK);
  for (int r = 0; r < 3; r++) AP_CHECK_NEAR(st.vel[r], sd.vel[r], 1e-12);
  ap_data_free(dd), ap_data_free(dt);
}

/* Two bodies joined by a loop closure: never the tree path. */
static void refusals(void) {
  ap_builder *b = NULL;
  AP_CHECK_EQ_INT(ap_builder_create("loop", &b), AP_OK);
  int id[2];
  for (int i = 0; i < 2; i++) {
    ap_body_def d = ap_body_def_default();
    d.name = i ? "b" : "a", d.mass = 1.0;
    d.inertia[0] = d.inertia[4] = d.inertia[8] = 0.1;
    ap_builder_add_body(b, &d, &id[i]);
    ap_joint_def j = ap_joint_def_default();
    j.name = d.name, j.kind = AP_JOINT_PLANAR, j.child = id[i];
    ap_builder_add_joint(b, &j, NULL);
  }
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "pin", c.kind = AP_CON_COINCIDENT, c.body = id[0], c.body2 = id[1];
  AP_CHECK_EQ_INT(ap_builder_add_constraint(b, &c, NULL), AP_OK);
  AP_CHECK_EQ_INT(ap_builder_set_path(b, (ap_path)7), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_builder_set_path(b, AP_PATH_TREE), AP_OK);
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_builder_compile(b, &m), AP_ERR_UNSUPPORTED);
  AP_CHECK(m == NULL && strstr(ap_builder_message(b), "'pin'") != NULL);
  printf("forced tree on a loop: %s\n", ap_builder_message(b));
  AP_CHECK_EQ_INT(ap_builder_set_path(b, AP_PATH_AUTO), AP_OK);
  AP_CHECK_EQ_INT(ap_builder_compile(b, &m), AP_OK);
  AP_CHECK_EQ_INT(ap_model_path(m), AP_PATH_DENSE);
  ap_model_free(m);
  ap_builder_free(b);
  /* DAE mode on a tree model: refused with a message, no crash */
  ap_model *mt = tm_trailers(3, AP_PATH_TREE);
  int n = ap_model_n(mt), k = ap_model_k(mt);
  double *x = calloc((size_t)(n + k), sizeof(double));
  tm_trailers_state(mt, 3, x, x + n);
  ap_sim_def def = ap_sim_def_default();
  def.mode = AP_MODE_DAE;
  ap_sim *s = NULL;
  char msg[512] = "";
  AP_CHECK_EQ_INT(ap_sim_create(mt, &def, 0.0, x, x + n, &s, msg, sizeof msg),
                  AP_ERR_UNSUPPORTED);
  AP_CHECK(strstr(msg, "tree path") != NULL);
  printf("DAE on the tree path: %s\n", msg);
  ap_sim_free(s);
  free(x);
  ap_model_free(mt);
}

static void family(const char *label, int N, int disks, double t1) {
  ap_model *md = disks ? tm_disks(N, AP_PATH_DENSE) : tm_trailers(N, AP_PATH_DENSE);
  ap_model *mt = disks ? tm_disks(N, AP_PATH_TREE) : tm_trailers(N, AP_PATH_TREE);
  AP_CHECK_EQ_INT(ap_model_path(md), AP_PATH_DENSE);
  AP_CHECK_EQ_INT(ap_model_path(mt), AP_PATH_TREE);
  int n = ap_model_n(md), k = ap_model_k(md);
  double *x = calloc((size_t)(n + k), sizeof(double));
  if (disks) tm_disks_state(md, N, x, x + n);
  else tm_trailers_state(md, N, x, x + n);
  compare_runs(label, md, mt, x, x + n, t1);
  if (disks) compare_queries(md, mt, x, x + n);
  free(x);
  ap_model_free(md), ap_model_free(mt);
}

int main(int argc, char **argv) {
  if (argc < 2) return fprintf(stderr, "usage: test_tree_path SOURCE_ROOT\n"), 2;
  /* example scenes the tree path takes (vehicles with wheel contacts: test_tree_fleet.c; the
   * others have loops; the rattleback's spin reversal amplifies any difference of step
   * sequence: docs/large.md) */
  const char *scenes[] = {"chaplygin_sleigh", "rolling_disk", "skate_incline",
                          "turntable_ball", "heavy_top"};
  for (int i = 0; i < 5; i++) scene_both(argv[1], scenes[i], NULL);
  family("trailers", 10, 0, 3.0);
  family("disks", 6, 1, 1.5);
  /* the automatic choice: by size, for models the tree path takes */
  ap_model *small = tm_trailers(12, AP_PATH_AUTO), *big = tm_trailers(13, AP_PATH_AUTO);
  AP_CHECK(ap_model_k(small) < AP_TREE_AUTO_K && ap_model_k(big) >= AP_TREE_AUTO_K);
  AP_CHECK_EQ_INT(ap_model_path(small), AP_PATH_DENSE);
  AP_CHECK_EQ_INT(ap_model_path(big), AP_PATH_TREE);
  ap_model_free(small), ap_model_free(big);
  refusals();
  return ap_check_finish("test_tree_path");
}
