/* test_scene: the scene layer in process (lib/scene, include/appell/scene.h).
 *
 * Bad scenes (the fixtures in tests/scenes): each gives AP_ERR_ARG and one message with
 * file:line:column and the key path. Good scenes (examples/scenes): each loads, gets a
 * consistent initial state and runs a little. Then: --set overrides, the Euler conventions
 * against quaternions and finite differences, expressions and their derivatives, the initial
 * state's completion and projection, and the output columns.
 *
 * Files are found from this source file's directory (meson runs tests in the build root and
 * __FILE__ is relative to it) or from $APPELL_SOURCE_DIR. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"
#include "scene/scene_int.h"

static char srcdir[1024];

static void path_of(char *out, size_t len, const char *dir, const char *name) {
  snprintf(out, len, "%s/%s/%s", srcdir, dir, name);
}

/* ---- bad scenes ------------------------------------------------------------------------- */

typedef struct bad_case {
  const char *file, *where, *what;   /* "file:L:C: path" and a phrase of the message */
} bad_case;

static const bad_case bad[] = {
    {"malformed.yaml", "malformed.yaml:3:1:", "malformed YAML"},
    {"unknown_key.yaml", "unknown_key.yaml:3:5: bodies.disk.mas:", "did you mean 'mass'?"},
    {"wrong_type.yaml", "wrong_type.yaml:3:11: bodies.disk.mass:", "expected a scalar"},
    {"negative_mass.yaml", "negative_mass.yaml:3:11: bodies.disk.mass:", "must be positive"},
    {"inertia_not_pd.yaml", "inertia_not_pd.yaml:4:14: bodies.disk.inertia:",
     "not positive definite"},
    {"missing_body.yaml", "missing_body.yaml:8:31: constraints.roll.body:",
     "no body named 'dsik' (did you mean 'disk'?)"},
    {"bad_expression.yaml", "bad_expression.yaml:12:35: initial.disk.spin_rate:",
     "cannot parse"},
    {"unknown_name.yaml", "unknown_name.yaml:11:34: ground.omega:", "unknown name 'w'"},
    {"disk_flat.yaml", "disk_flat.yaml:12:3: initial:", "lies flat"},
    {"joint_no_child.yaml", "joint_no_child.yaml:7:10: joints.wheel:", "needs a child body"},
    {"body_no_joint.yaml", "body_no_joint.yaml:2:10: bodies.spare:", "has no joint"},
    {"duplicate_key.yaml", "duplicate_key.yaml:7:3: joints.disk:", "duplicate key"},
    {"unknown_section.yaml", "unknown_section.yaml:1:1: bodys:", "did you mean 'bodies'?"},
    {"bad_kind.yaml", "bad_kind.yaml:6:16: joints.disk.kind:", "did you mean 'plane_contact'?"},
    {"negative_radius.yaml", "negative_radius.yaml:4:33: bodies.disk.shape.radius:",
     "must be positive"},
    {"bodies_scalar.yaml", "bodies_scalar.yaml:1:9: bodies:", "expected a mapping"},
    {"two_documents.yaml", "two_documents.yaml:14:1:", "one YAML document"},
    {"recursive_alias.yaml", "recursive_alias.yaml:1:8: a[0]:", "recursive alias"},
    {"t_end_before_t0.yaml", "t_end_before_t0.yaml:11:28: simulation.t_end:", "must be after"},
    {"inconsistent_constraints.yaml",
     "inconsistent_constraints.yaml:8:15: constraints.turn_again:", "contradict each other"},
    {"driven_initial.yaml", "driven_initial.yaml:6:16: initial.arm.angle:", "is driven"},
    {"uniform_point.yaml", "uniform_point.yaml:2:47: bodies.p.inertia:", "needs a solid shape"},
    {"special_float.yaml", "special_float.yaml:4:11: bodies.disk.mass:",
     "expected a finite number, got '.nan' (YAML's not-a-number)"},
    /* Expressions and an initial state that a run would refuse at t0 (issue 10). */
    {"drive_inverse.yaml", "drive_inverse.yaml:11:20: joints.wheel.drive.angle:",
     "'1/t' is not finite at t = 0: 1 / 0 = inf (column 2 of the expression)"},
    {"drive_log.yaml", "drive_log.yaml:11:20: joints.wheel.drive.angle:",
     "is not finite at t = 0: log(-1) = nan (column 5 of the expression)"},
    {"force_not_finite.yaml", "force_not_finite.yaml:7:69: effects.push.torque[2]:",
     "'2*sqrt(t)' has no finite first time derivative at t = 0"},
    {"speed_at_t0.yaml", "speed_at_t0.yaml:7:66: constraints.turn.value:",
     "is not finite at t = 2: 1 / 0 = inf"},
    {"ground_not_finite.yaml", "ground_not_finite.yaml:11:34: ground.omega:",
     "log(0) = -inf (column 9 of the expression)"},
    {"initial_overflow.yaml", "initial_overflow.yaml:13:53: initial.disk.heading_rate:",
     "the equations of motion cannot be evaluated at the initial state"},
};

/* Load (and, if that works, initialize) a scene; return the status and the message. */
static int load_and_init(const char *file, const char *const *sets, int nsets, char *msg,
                         size_t len) {
  ap_scene *sc = NULL;
  int rc = ap_scene_load(file, sets, nsets, &sc, msg, len);
  if (rc == AP_OK) {
    const ap_model *m = ap_scene_model(sc);
    double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
    rc = ap_scene_initial_state(sc, x, x + ap_model_n(m), NULL, 0, msg, len);
    free(x);
  }
  ap_scene_free(sc);
  return rc;
}

/* Does the message name its key twice ("inertia: inertia: ...")? The path before ": " ends
 * with the key; the text after it must not start with the key again. */
static int repeats_key(const char *msg) {
  const char *sep = strstr(msg, ": ");
  if (!sep || !(sep = strstr(sep + 2, ": "))) return 0;
  const char *path = sep;
  while (path > msg && path[-1] != ' ' && path[-1] != '.') path--;
  size_t len = (size_t)(sep - path);
  return len > 0 && strncmp(sep + 2, path, len) == 0 && sep[2 + len] == ':';
}

static void test_bad_scenes(void) {
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char file[1200], msg[1024] = "";
    path_of(file, sizeof file, "tests/scenes", bad[i].file);
    int rc = load_and_init(file, NULL, 0, msg, sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
    int where = strstr(msg, bad[i].where) != NULL, what = strstr(msg, bad[i].what) != NULL;
    AP_CHECK(where && what);
    if (!where || !what)
      fprintf(stderr, "  %s: expected '%s' ... '%s'\n  got: %s\n", bad[i].file, bad[i].where,
              bad[i].what, msg);
    AP_CHECK(strchr(msg, '\n') == NULL);   /* one message, one line */
    AP_CHECK(!repeats_key(msg));
  }
}

/* ---- good scenes ------------------------------------------------------------------------ */

static const char *const examples[] = {"rolling_disk.yaml", "skate_incline.yaml",
                                       "chaplygin_sleigh.yaml", "turntable_ball.yaml",
                                       "hoffmann.yaml", "rattleback.yaml", "heavy_top.yaml"};

/* Run a loaded scene for a short time; return the largest |A v + a0| over the output rows. */
static double short_run(ap_scene *sc, double span, int *rows) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m), nc = ap_scene_output_count(sc);
  double *x = calloc((size_t)(n + k + nc), sizeof *x), *row = x + n + k, worst = -1.0;
  char msg[1024], rep[1024];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  *rows = 0;
  if (ap_scene_initial_state(sc, x, x + n, rep, sizeof rep, msg, sizeof msg) == AP_OK &&
      ap_sim_create(m, &run.sim, run.t0, x, x + n, &sim, msg, sizeof msg) == AP_OK) {
    worst = 0.0;
    for (int i = 0; i <= 10; i++) {
      if (i && ap_sim_advance(sim, run.t0 + span * i / 10) != AP_OK) return free(x), -1.0;
      if (ap_scene_output_row(sc, sim, row) != AP_OK) return free(x), -1.0;
      for (int c = 0; c < nc; c++) AP_CHECK(isfinite(row[c]));
      double r = 0.0;
      ap_scene_residual(sc, ap_sim_time(sim), ap_sim_q(sim), ap_sim_v(sim), &r);
      worst = fmax(worst, r);
      ++*rows;
    }
  } else {
    fprintf(stderr, "  short_run: %s\n", msg);
  }
  ap_sim_free(sim);
  free(x);
  return worst;
}

static void test_examples(void) {
  for (size_t i = 0; i < sizeof examples / sizeof examples[0]; i++) {
    char file[1200], msg[1024] = "";
    path_of(file, sizeof file, "examples/scenes", examples[i]);
    ap_scene *sc = NULL;
    int rc = ap_scene_load(file, NULL, 0, &sc, msg, sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) {
      fprintf(stderr, "  %s: %s\n", examples[i], msg);
      continue;
    }
    AP_CHECK_EQ_INT(strcmp(ap_scene_output_name(sc, 0), "t"), 0);
    int rows = 0;
    double worst = short_run(sc, 0.1, &rows);
    AP_CHECK_EQ_INT(rows, 11);
    AP_CHECK_LE(worst, 1e-9);
    ap_scene_free(sc);
  }
}

/* ---- --set ------------------------------------------------------------------------------ */

static double disk_energy(const char *const *sets, int nsets) {
  char file[1200], msg[1024];
  path_of(file, sizeof file, "examples/scenes", "rolling_disk.yaml");
  ap_scene *sc = NULL;
  if (ap_scene_load(file, sets, nsets, &sc, msg, sizeof msg) != AP_OK) return NAN;
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m);
  double x[16] = {0}, E = NAN;
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  if (ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg) == AP_OK)
    ap_scene_energy(sc, run.t0, x, x + n, &E);
  ap_scene_free(sc);
  return E;
}

static void test_overrides(void) {
  const char *one[] = {"bodies.disk.mass=1"}, *two[] = {"bodies.disk.mass=2"},
             *last[] = {"bodies.disk.mass=5", "bodies.disk.mass=2"};
  double E1 = disk_energy(one, 1), E2 = disk_energy(two, 1), E3 = disk_energy(last, 2);
  AP_CHECK_NEAR(E2, 2.0 * E1, 1e-12 * E1);   /* same motion, twice the mass */
  AP_CHECK_NEAR(E3, E2, 1e-12 * E1);         /* the last override wins */
  char file[1200], msg[1024];
  path_of(file, sizeof file, "examples/scenes", "rolling_disk.yaml");
  const char *typo[] = {"bodies.disk.mas=2"}, *deep[] = {"bodies.disk.shape.radius.x=1"},
             *bad[] = {"bodies.disk.mass"}, *seq[] = {"output.channels.9=energy"},
             *expr[] = {"initial.disk.tilt=85*deg"};
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, typo, 1, &sc, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "--set bodies.disk.mas=2") && strstr(msg, "did you mean 'mass'?"));
  AP_CHECK_EQ_INT(ap_scene_load(file, deep, 1, &sc, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "is a scalar") != NULL);
  AP_CHECK_EQ_INT(ap_scene_load(file, bad, 1, &sc, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "PATH=VALUE") != NULL);
  AP_CHECK_EQ_INT(ap_scene_load(file, seq, 1, &sc, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "no entry '9'") != NULL);
  AP_CHECK_EQ_INT(ap_scene_load(file, expr, 1, &sc, msg, sizeof msg), AP_OK);
  ap_scene_free(sc);
}

/* ---- Euler angles ----------------------------------------------------------------------- */

static void test_euler(void) {
  double e[3] = {0.7, 1.1, -2.3}, q[4], back[3], R[9];
  sc_euler_to_quat(0, e, q);
  sc_quat_to_zxz(q, back);
  for (int i = 0; i < 3; i++) AP_CHECK_NEAR(back[i], e[i], 1e-12);
  /* Z-X-Z: the body z axis is (sin a sin b, -cos a sin b, cos b); tilt is its angle from z. */
  ap_quat_to_matrix(q, R);
  AP_CHECK_NEAR(R[6], sin(0.7) * sin(1.1), 1e-14);
  AP_CHECK_NEAR(R[7], -cos(0.7) * sin(1.1), 1e-14);
  AP_CHECK_NEAR(R[8], cos(1.1), 1e-14);
  /* omega from the rates against a finite difference of R: [w]x = R' R^T. */
  for (int zyx = 0; zyx < 2; zyx++) {
    double r[3] = {0.4, -0.9, 1.7}, w[3], h = 1e-6, ep[3], em[3], qp[4], qm[4], Rp[9], Rm[9];
    sc_euler_rates_to_omega(zyx, e, r, w);
    sc_euler_to_quat(zyx, e, q);
    ap_quat_to_matrix(q, R);
    for (int i = 0; i < 3; i++) ep[i] = e[i] + h * r[i], em[i] = e[i] - h * r[i];
    sc_euler_to_quat(zyx, ep, qp), sc_euler_to_quat(zyx, em, qm);
    ap_quat_to_matrix(qp, Rp), ap_quat_to_matrix(qm, Rm);
    double W[9] = {0};   /* W = R' R^T, column-major */
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        for (int c = 0; c < 3; c++)
          W[i + 3 * j] += (Rp[i + 3 * c] - Rm[i + 3 * c]) / (2 * h) * R[j + 3 * c];
    AP_CHECK_NEAR(W[5], w[0], 1e-8);    /* W(2,1) = wx */
    AP_CHECK_NEAR(W[6], w[1], 1e-8);    /* W(0,2) = wy */
    AP_CHECK_NEAR(W[1], w[2], 1e-8);    /* W(1,0) = wz */
  }
}

/* ---- expressions ------------------------------------------------------------------------ */

static void test_expressions(void) {
  sc_ctx c = {"expr", "", AP_OK};
  sc_node at = {.kind = SC_SCALAR, .text = "2*sin(3*t) + t^2", .line = 1, .col = 1,
                .path = "x"};
  sc_expr e;
  AP_CHECK_EQ_INT(sc_expr_compile(&c, &at, at.text, 1, &e), AP_OK);
  double f[3], t = 0.7;
  AP_CHECK_EQ_INT(sc_expr_eval(&e, t, f), 0);
  AP_CHECK_NEAR(f[0], 2 * sin(3 * t) + t * t, 1e-14);
  AP_CHECK_NEAR(f[1], 6 * cos(3 * t) + 2 * t, 1e-13);
  AP_CHECK_NEAR(f[2], -18 * sin(3 * t) + 2, 1e-12);
  sc_expr_free(&e);
  at.text = "90*deg";
  AP_CHECK_EQ_INT(sc_expr_compile(&c, &at, at.text, 0, &e), AP_OK);
  AP_CHECK_NEAR(e.value, 1.5707963267948966, 1e-15);
  AP_CHECK_EQ_INT(e.timed, 0);
  sc_expr_free(&e);
  const char *bad[] = {"t", "sin(", "t'", "2 t", "\xff", "x+1", ""};
  for (int i = 0; i < 7; i++) {
    sc_ctx c2 = {"expr", "", AP_OK};
    at.text = (char *)bad[i];
    AP_CHECK_EQ_INT(sc_expr_compile(&c2, &at, bad[i], 0, &e), AP_ERR_ARG);
    AP_CHECK(strstr(c2.msg, "expr:1:1: x:") != NULL);
  }
}

/* A turntable spinning up as 2 tanh(t): rheonomic, the expression's derivative drives gamma. */
static void test_turntable_expression(void) {
  char file[1200], msg[1024];
  path_of(file, sizeof file, "examples/scenes", "turntable_ball.yaml");
  const char *sets[] = {"ground.omega=2*tanh(t)"};
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, sets, 1, &sc, msg, sizeof msg), AP_OK);
  if (!sc) return;
  AP_CHECK_EQ_INT(ap_scene_conserves_energy(sc), 0);
  int rows = 0;
  AP_CHECK_LE(short_run(sc, 1.0, &rows), 1e-9);
  AP_CHECK_EQ_INT(rows, 11);
  ap_scene_free(sc);
}

/* ---- initial state ---------------------------------------------------------------------- */

static const char disk_text[] =
    "bodies:\n  disk: {mass: 2, shape: {kind: disk, radius: 0.3}}\n"
    "joints:\n  disk: {kind: plane_contact}\n"
    "constraints:\n  roll: {kind: rolling, body: disk}\n"
    "initial:\n  disk: {tilt: 90*deg, heading: 30*deg, spin_rate: -5, vx: 3, vy: 0}\n";

static void test_initial_projection(void) {
  char msg[1024], rep[2048];
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(disk_text, sizeof disk_text - 1, "disk", NULL, 0, &sc, msg,
                                sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return;
  double x[11] = {0}, resid = 1.0;
  rc = ap_scene_initial_state(sc, x, x + 6, rep, sizeof rep, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK(strstr(rep, "projected") != NULL && strstr(rep, "disk.vx") != NULL);
  ap_scene_residual(sc, 0.0, x, x + 6, &resid);
  AP_CHECK_LE(resid, 1e-12);
  AP_CHECK(sqrt(x[6] * x[6] + x[7] * x[7]) > 0.1);   /* still rolling */
  ap_scene_free(sc);
  /* Only the spin given: the centre's velocity is completed, nothing projected. */
  static const char spin_only[] =
      "bodies:\n  disk: {mass: 2, shape: {kind: disk, radius: 0.3}}\n"
      "joints:\n  disk: {kind: plane_contact}\n"
      "constraints:\n  roll: {kind: rolling, body: disk}\n"
      "initial:\n  disk: {tilt: 90*deg, spin_rate: -5}\n";
  rc = ap_scene_load_string(spin_only, sizeof spin_only - 1, "disk", NULL, 0, &sc, msg,
                            sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return;
  rc = ap_scene_initial_state(sc, x, x + 6, rep, sizeof rep, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(rep[0], '\0');
  AP_CHECK_NEAR(x[6], 5 * 0.3, 1e-12);   /* v = r |spin| along the heading (x) */
  AP_CHECK_NEAR(x[7], 0.0, 1e-12);
  ap_scene_free(sc);
}

/* The output columns: names in order, counts match the channels. */
static void test_columns(void) {
  static const char text[] =
      "bodies:\n  b: {mass: 1, shape: {kind: sphere, radius: 0.1}}\n"
      "joints:\n  b: {kind: plane_contact}\n"
      "constraints:\n  r: {kind: rolling, body: b}\n"
      "effects:\n  g: {kind: gravity}\n"
      "initial:\n  b: {vx: 1}\n"
      "output:\n  channels: [angles, contacts, energy, residual, reactions]\n";
  char msg[1024];
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load_string(text, sizeof text - 1, "cols", NULL, 0, &sc, msg,
                                       sizeof msg), AP_OK);
  if (!sc) return;
  static const char *const want[] = {"t", "b.heading", "b.tilt", "b.spin", "b.contact.x",
                                     "b.contact.y", "kinetic", "potential", "energy",
                                     "energy_error", "residual", "lambda.r.x", "lambda.r.y"};
  AP_CHECK_EQ_INT(ap_scene_output_count(sc), 13);
  for (int i = 0; i < 13 && i < ap_scene_output_count(sc); i++)
    AP_CHECK_EQ_INT(strcmp(ap_scene_output_name(sc, i), want[i]), 0);
  AP_CHECK_EQ_INT(ap_scene_count(sc, AP_SCENE_CHANNELS), 5);
  AP_CHECK_EQ_INT(strcmp(ap_scene_element_name(sc, AP_SCENE_EFFECTS, 0), "g"), 0);
  AP_CHECK_EQ_INT(strcmp(ap_scene_element_kind(sc, AP_SCENE_JOINTS, 0), "plane_contact"), 0);
  AP_CHECK_EQ_INT(ap_scene_conserves_energy(sc), 1);
  int rows = 0;
  AP_CHECK_LE(short_run(sc, 0.2, &rows), 1e-12);
  ap_scene_free(sc);
}


/* Springs, joint damping, drives and time-dependent applied forces: a pendulum hung from a cart
 * on a rail. Undriven and damped, its energy can only decrease; driven, the cart's coordinate
 * leaves q; a torque f(t) goes through the wrench callback. */
static const char pendulum[] =
    "bodies:\n"
    "  cart: {mass: 1, inertia: [0.1, 0.1, 0.1]}\n"
    "  bob: {mass: 0.5, com: [0, 0, -1], inertia: [0.01, 0.01, 0.01]}\n"
    "joints:\n"
    "  cart: {kind: prismatic, axis: y}\n"
    "  bob: {kind: revolute, parent: cart, axis: x}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "  spring: {kind: spring, body: bob, point: [0, 0, -1], point2: [0, 0.5, -1], stiffness: 3,"
    " damping: 0.2, rest_length: 0.1}\n"
    "  friction: {kind: joint_damping, joint: bob, damping: 0.05}\n"
    "initial:\n  bob: {angle: 0.4, rate: 1}\n  cart: {rate: 0.3}\n"
    "output:\n  interval: 0.05\n  channels: [coordinates, energy]\n";

static void test_effects(void) {
  char msg[1024];
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(pendulum, sizeof pendulum - 1, "pendulum", NULL, 0, &sc, msg,
                                sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)fprintf(stderr, "  %s\n", msg);
  AP_CHECK_EQ_INT(ap_scene_conserves_energy(sc), 0);
  const ap_model *m = ap_scene_model(sc);
  AP_CHECK_EQ_INT(ap_model_n(m), 2);
  double x[4], E, Eprev = INFINITY;
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, x, x + 2, NULL, 0, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, 0.0, x, x + 2, &sim, msg, sizeof msg), AP_OK);
  for (int i = 0; sim && i <= 40; i++) {
    if (i) AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.05 * i), AP_OK);
    ap_scene_energy(sc, ap_sim_time(sim), ap_sim_q(sim), ap_sim_v(sim), &E);
    AP_CHECK_LE(E, Eprev + 1e-9);   /* dampers only take energy out */
    Eprev = E;
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
  /* Drive the cart and push the bob with a torque f(t): the cart leaves q. */
  static const char driven[] =
      "bodies:\n"
      "  cart: {mass: 1, inertia: [0.1, 0.1, 0.1]}\n"
      "  bob: {mass: 0.5, com: [0, 0, -1], inertia: [0.01, 0.01, 0.01]}\n"
      "joints:\n"
      "  cart: {kind: prismatic, axis: y, drive: {position: \"0.2*sin(2*t)\"}}\n"
      "  bob: {kind: revolute, parent: cart, axis: x}\n"
      "effects:\n"
      "  gravity: {kind: gravity}\n"
      "  push: {kind: applied, body: bob, point: [0, 0, -1], torque: [\"0.1*cos(t)\", 0, 0]}\n"
      "initial:\n  bob: {angle: 0.4}\n";
  rc = ap_scene_load_string(driven, sizeof driven - 1, "driven", NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)fprintf(stderr, "  %s\n", msg);
  AP_CHECK_EQ_INT(ap_model_n(ap_scene_model(sc)), 1);
  AP_CHECK_EQ_INT(strcmp(ap_model_coord_name(ap_scene_model(sc), 0), "bob.angle"), 0);
  int rows = 0;
  AP_CHECK(short_run(sc, 1.0, &rows) >= 0.0);
  AP_CHECK_EQ_INT(rows, 11);
  ap_scene_free(sc);
}

/* A ball on a plane translating with V(t) = 0.5 sin t: its centre accelerates at 2/7 of the
 * plane's acceleration, so vx(t) = sin(t) / 7 exactly (from rest). */
static void test_moving_plane(void) {
  static const char text[] =
      "ground: {kind: translating, velocity: [\"0.5*sin(t)\", 0]}\n"
      "bodies:\n  ball: {mass: 1, shape: {kind: sphere, radius: 0.1}}\n"
      "joints:\n  ball: {kind: plane_contact}\n"
      "constraints:\n  roll: {kind: rolling, body: ball}\n"
      "effects:\n  gravity: {kind: gravity}\n"
      "simulation: {rtol: 1e-11, atol: 1e-13}\n";
  char msg[1024];
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, sizeof text - 1, "plane", NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)fprintf(stderr, "  %s\n", msg);
  const ap_model *m = ap_scene_model(sc);
  double x[11];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, x, x + 6, NULL, 0, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_create(m, &run.sim, 0.0, x, x + 6, &sim, msg, sizeof msg), AP_OK);
  int vx = ap_model_find_speed(m, "ball.vx");
  for (int i = 1; sim && vx >= 0 && i <= 6; i++) {
    AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.5 * i), AP_OK);
    AP_CHECK_NEAR(ap_sim_v(sim)[vx], sin(0.5 * i) / 7.0, 1e-9);
  }
  AP_CHECK(vx >= 0);
  ap_sim_free(sim);
  ap_scene_free(sc);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  test_bad_scenes();
  test_examples();
  test_overrides();
  test_euler();
  test_expressions();
  test_turntable_expression();
  test_initial_projection();
  test_columns();
  test_effects();
  test_moving_plane();
  return ap_check_finish("test_scene");
}
