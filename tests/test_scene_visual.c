/* test_scene_visual: what appell view and appell export read from the library.
 *
 *   ap_model_body_name / ap_model_body_shape: the scene's bodies and shapes, bad ids refused;
 *   ap_scene_body_visual: visual-only shapes (box, capsule, sphere) parsed with defaults, bad
 *     ones refused with file:line:column, and the dynamics unchanged by them (same q after a
 *     run with and without);
 *   the poses output channel against closed forms: a disk on the plane-contact joint tilted by
 *     theta from the vertical has its centre at height r sin(theta) above the contact point,
 *     its x, y are the joint's, and its orientation is the joint's quaternion (identity frames).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

static const char disk_scene[] =
    "bodies:\n"
    "  disk: {mass: 1, shape: {kind: disk, radius: 0.5}, visual: {kind: box, size: [0.1, 0.2,"
    " 0.3], at: [0, 0, 0.25]}}\n"
    "  arm: {mass: 0.2, inertia: [0.01, 0.01, 0.01], visual: {kind: capsule, radius: 0.02,"
    " length: 0.4, axis: x}}\n"
    "joints:\n"
    "  disk: {kind: plane_contact}\n"
    "  arm: {kind: revolute, parent: disk, axis: z}\n"
    "constraints:\n  roll: {kind: rolling, body: disk}\n"
    "effects:\n  gravity: {kind: gravity}\n"
    "initial:\n  disk: {tilt: 70*deg, heading: 0.3, spin_rate: -5, heading_rate: 2}\n"
    "output:\n  interval: 0.1\n  channels: [coordinates, angles, poses]\n"
    "simulation: {rtol: 1e-10, atol: 1e-12, t_end: 1}\n";

static void test_queries(ap_scene *sc) {
  const ap_model *m = ap_scene_model(sc);
  AP_CHECK_EQ_INT(ap_model_body_count(m), 2);
  AP_CHECK(ap_model_body_name(m, 0) && strcmp(ap_model_body_name(m, 0), "disk") == 0);
  AP_CHECK(ap_model_body_name(m, 1) && strcmp(ap_model_body_name(m, 1), "arm") == 0);
  AP_CHECK(ap_model_body_name(m, 2) == NULL && ap_model_body_name(NULL, 0) == NULL);
  ap_shape s;
  AP_CHECK_EQ_INT(ap_model_body_shape(m, 0, &s), AP_OK);
  AP_CHECK_EQ_INT(s.kind, AP_SHAPE_DISK);
  AP_CHECK_NEAR(s.radius, 0.5, 0.0);
  AP_CHECK_EQ_INT(ap_model_body_shape(m, 1, &s), AP_OK);
  AP_CHECK_EQ_INT(s.kind, AP_SHAPE_NONE);
  AP_CHECK_EQ_INT(ap_model_body_shape(m, -1, &s), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_model_body_shape(m, 0, NULL), AP_ERR_ARG);
  ap_scene_visual v;
  AP_CHECK_EQ_INT(ap_scene_body_visual(sc, 0, &v), AP_OK);
  AP_CHECK_EQ_INT(v.kind, AP_VISUAL_BOX);
  AP_CHECK_NEAR(v.size[1], 0.2, 0.0);
  AP_CHECK_NEAR(v.at[2], 0.25, 0.0);
  AP_CHECK_EQ_INT(ap_scene_body_visual(sc, 1, &v), AP_OK);
  AP_CHECK_EQ_INT(v.kind, AP_VISUAL_CAPSULE);
  AP_CHECK_EQ_INT(v.axis, 0);
  AP_CHECK_NEAR(v.length, 0.4, 0.0);
  AP_CHECK_EQ_INT(ap_scene_body_visual(sc, 2, &v), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_scene_body_visual(NULL, 0, &v), AP_ERR_ARG);
}

static int col(ap_scene *sc, const char *name) {
  for (int i = 0; i < ap_scene_output_count(sc); i++)
    if (strcmp(ap_scene_output_name(sc, i), name) == 0) return i;
  AP_CHECK(!"output column missing");
  return 0;
}

/* Run 1 s; at each row check the poses columns against the closed forms. Returns the final q
 * (n entries) in qend. */
static void run_and_check(ap_scene *sc, double *qend) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double x[64], row[256], worst = 0.0;
  char msg[512];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, 0.0, x, x + n, &sim, msg, sizeof msg), AP_OK);
  AP_CHECK(ap_scene_output_count(sc) <= 256 && k <= 32);
  for (int i = 0; sim && i <= 10; i++) {
    if (i) AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.1 * i), AP_OK);
    AP_CHECK_EQ_INT(ap_scene_output_row(sc, sim, row), AP_OK);
    /* the rotation of the body axes is the joint's quaternion normalized (the integrator keeps
     * |q| = 1 only to its projection tolerance), sign chosen with w >= 0 */
    double qn = hypot(hypot(row[col(sc, "disk.qw")], row[col(sc, "disk.qx")]),
                      hypot(row[col(sc, "disk.qy")], row[col(sc, "disk.qz")]));
    double tilt = row[col(sc, "disk.tilt")];
    double sign = (row[col(sc, "disk.qw")] < 0 ? -1.0 : 1.0) / qn;
    double e[] = {row[col(sc, "disk.pos.x")] - row[col(sc, "disk.x")],
                  row[col(sc, "disk.pos.y")] - row[col(sc, "disk.y")],
                  row[col(sc, "disk.pos.z")] - 0.5 * sin(tilt),
                  row[col(sc, "disk.rot.w")] - sign * row[col(sc, "disk.qw")],
                  row[col(sc, "disk.rot.x")] - sign * row[col(sc, "disk.qx")],
                  row[col(sc, "disk.rot.y")] - sign * row[col(sc, "disk.qy")],
                  row[col(sc, "disk.rot.z")] - sign * row[col(sc, "disk.qz")],
                  /* the arm turns about the disk axis at the disk's centre */
                  row[col(sc, "arm.pos.z")] - row[col(sc, "disk.pos.z")]};
    for (int j = 0; j < 8; j++) worst = fmax(worst, fabs(e[j]));
  }
  AP_CHECK_LE(worst, 1e-14);
  printf("  poses channel vs closed forms: max difference %.2e\n", worst);
  if (sim) memcpy(qend, ap_sim_q(sim), sizeof *qend * (size_t)n);
  ap_sim_free(sim);
}

static void test_bad_visuals(void) {
  static const char *const bad[][2] = {
      {"visual: {kind: box, size: [1, 0, 1]}", "visual.size"},
      {"visual: {kind: cube}", "visual.kind"},
      {"visual: {kind: capsule, length: 1}", "radius must be positive"},
      {"visual: {size: [1, 1, 1]}", "needs a kind"},
      {"visual: {kind: box, size: [1, 1, 1], colour: red}", "visual.colour"}};
  for (int i = 0; i < 5; i++) {
    char text[512], msg[1024] = "";
    snprintf(text, sizeof text,
             "bodies:\n  ball: {mass: 1, shape: {kind: sphere, radius: 0.1}, %s}\n"
             "joints:\n  ball: {kind: plane_contact}\n", bad[i][0]);
    ap_scene *sc = NULL;
    AP_CHECK_EQ_INT(ap_scene_load_string(text, strlen(text), "v", NULL, 0, &sc, msg, sizeof msg),
                    AP_ERR_ARG);
    AP_CHECK(strstr(msg, "v:2:") && strstr(msg, bad[i][1]));
    if (!strstr(msg, bad[i][1])) fprintf(stderr, "  case %d: %s\n", i, msg);
    ap_scene_free(sc);
  }
}

int main(void) {
  char msg[1024];
  ap_scene *sc = NULL, *plain = NULL;
  int rc = ap_scene_load_string(disk_scene, sizeof disk_scene - 1, "disk", NULL, 0, &sc, msg,
                                sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), ap_check_finish("test_scene_visual");
  test_queries(sc);
  double q1[16] = {0}, q2[16] = {0};
  run_and_check(sc, q1);
  /* The same scene without its visuals moves exactly alike. */
  const char *sets[] = {"bodies.disk.visual.kind=none", "bodies.arm.visual.kind=none"};
  rc = ap_scene_load_string(disk_scene, sizeof disk_scene - 1, "disk", sets, 2, &plain, msg,
                            sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (plain) run_and_check(plain, q2);
  for (int i = 0; i < ap_model_n(ap_scene_model(sc)); i++) AP_CHECK_NEAR(q1[i], q2[i], 0.0);
  ap_scene_free(plain);
  ap_scene_free(sc);
  test_bad_visuals();
  return ap_check_finish("test_scene_visual");
}
