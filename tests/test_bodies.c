/* Body layer: the builder's validation and messages, names, and the exact kinematics against
 * central finite differences along the motion (fdcheck.h: the method and its tolerance).
 *
 * Near a singular shape (disk 0.1 degree from flat) h is scaled with the distance to the
 * singularity. A deliberately broken rolling gamma (without the surface-motion term) must
 * fail the same check by orders of magnitude: the test shows it catches that mistake. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fdcheck.h"

/* ---- callbacks of the chain model -------------------------------------------------------- */

static int wrench_fn(double t, double F[3], double T[3], void *user) {
  (void)user;
  F[0] = cos(t), F[1] = 0.5, F[2] = -sin(t);
  T[0] = 0.1, T[1] = 0.2 * t, T[2] = -0.3;
  return 0;
}
static int user_force(double t, const double *q, const double *v, double *Q, void *user) {
  (void)t, (void)user;
  Q[0] += -0.3 * q[0] - 0.1 * v[0];
  return 0;
}
/* User row: v0 + 2 v1 - 0.5 sin(t) q0 = 0 (k >= 2). */
static int user_A(double t, const double *q, double *A, double *a0, void *user) {
  (void)user;
  A[0] = 1.0, A[1] = 2.0;
  a0[0] = -0.5 * sin(t) * q[0];
  return 0;
}
static int user_gamma(double t, const double *q, const double *v, double *gamma, void *user) {
  (void)user;
  gamma[0] = 0.5 * cos(t) * q[0] + 0.5 * sin(t) * v[0];
  return 0;
}

/* ---- helpers to build models -------------------------------------------------------------- */

static int add_body(ap_builder *b, const char *name, double mass, ap_shape_kind shape) {
  ap_body_def def = ap_body_def_default();
  def.name = name;
  def.mass = mass;
  def.shape.kind = shape;
  rand_vec(def.com, 3, 0.2);
  rand_inertia(def.inertia, 0.1 * mass);
  int id = -1;
  AP_CHECK(ap_builder_add_body(b, &def, &id) == AP_OK);
  return id;
}

static int add_joint(ap_builder *b, ap_joint_kind kind, int parent, int child, int frames) {
  ap_joint_def j = ap_joint_def_default();
  j.kind = kind, j.parent = parent, j.child = child;
  if (frames) rand_frame(&j.parent_frame), rand_frame(&j.child_frame);
  rand_vec(j.axis, 3, 1.0);
  int id = -1;
  AP_CHECK(ap_builder_add_joint(b, &j, &id) == AP_OK);
  return id;
}

static ap_model *compile(ap_builder *b) {
  ap_model *m = NULL;
  int rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) fprintf(stderr, "compile failed: %s\n", ap_builder_message(b));
  AP_CHECK(rc == AP_OK);
  ap_builder_free(b);
  return m;
}

/* ---- models for the finite-difference checks ------------------------------------------------- */

/* Every tree joint kind in one chain with random frames, coms and inertias, loops of the three
 * kinds, a knife edge on a turntable, a prescribed speed and a user row. With drive != 0 the
 * revolute angle, the planar x and the free joint's z are driven (rheonomic columns). */
static ap_model *chain_model(int drive, int effects) {
  static double amp = 0.8;
  static const ap_joint_kind kinds[6] = {AP_JOINT_REVOLUTE, AP_JOINT_PRISMATIC, AP_JOINT_PLANAR,
                                         AP_JOINT_BALL, AP_JOINT_FREE, AP_JOINT_FIXED};
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create(drive ? "driven chain" : "chain", &b) == AP_OK);
  int base = add_body(b, "base", 2.0, AP_SHAPE_NONE);
  int slider = add_body(b, "slider", 1.0, AP_SHAPE_NONE);
  int plate = add_body(b, "plate", 1.5, AP_SHAPE_NONE);
  int knob = add_body(b, "knob", 0.5, AP_SHAPE_NONE);
  int drone = add_body(b, "drone", 0.7, AP_SHAPE_NONE);
  int weld = add_body(b, "weld", 0.3, AP_SHAPE_NONE);
  for (int i = 0; i < 6; i++) {   /* joint i carries body i; its parent is body i - 1 */
    ap_joint_def j = ap_joint_def_default();
    j.kind = kinds[i], j.parent = i == 0 ? AP_GROUND : i - 1, j.child = i;
    rand_frame(&j.parent_frame), rand_frame(&j.child_frame);
    rand_vec(j.axis, 3, 1.0);
    if (drive && (i == 0 || i == 2)) j.drive[0] = f_sine, j.drive_user[0] = &amp;
    if (drive && i == 4) j.drive[2] = f_sine;
    AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  }
  int jp = 1;
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "weld to plate", c.kind = AP_CON_COINCIDENT, c.body = weld, c.body2 = plate;
  c.axes = 5u;
  rand_vec(c.point, 3, 0.3), rand_vec(c.point2, 3, 0.3);
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c.name = "knob on line", c.kind = AP_CON_POINT_ON_LINE, c.body = knob, c.body2 = base;
  rand_vec(c.direction, 3, 1.0);
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c.name = "drone on plane", c.kind = AP_CON_POINT_ON_PLANE, c.body = drone, c.body2 = slider;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c.name = "weld on floor", c.body = weld, c.body2 = AP_GROUND;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c = ap_constraint_def_default();
  c.name = "skate", c.kind = AP_CON_KNIFE_EDGE, c.body = plate;
  c.ground.kind = AP_GROUND_TURNTABLE, c.ground.omega_fn = f_omega;
  c.ground.center[0] = 0.3, c.ground.center[1] = -0.2;
  rand_vec(c.point, 3, 0.3), rand_vec(c.direction, 3, 1.0);
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c.name = "skate2", c.body = drone, c.ground.kind = AP_GROUND_TRANSLATING;
  c.ground.velocity_fn[0] = f_vel, c.ground.velocity[1] = 0.3;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c = ap_constraint_def_default();
  c.name = "motor", c.kind = AP_CON_PRESCRIBED_SPEED, c.joint = jp, c.speed = 0;
  c.speed_fn = f_sine;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  c = ap_constraint_def_default();
  c.name = "user", c.kind = AP_CON_USER, c.rows = 1, c.user_constraint = user_A;
  c.user_gamma = user_gamma;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  if (effects) {
    ap_effect_def e = ap_effect_def_default();
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
    e.kind = AP_EFFECT_SPRING, e.body = slider, e.body2 = drone, e.stiffness = 30.0;
    e.damping = 0.5, e.rest_length = 0.2;
    rand_vec(e.point, 3, 0.3), rand_vec(e.point2, 3, 0.3);
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
    e = ap_effect_def_default();
    e.kind = AP_EFFECT_APPLIED, e.body = knob, e.wrench = wrench_fn;
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
    e = ap_effect_def_default();
    e.kind = AP_EFFECT_JOINT_DAMPING, e.joint = 3, e.damping = 0.2;
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
    e = ap_effect_def_default();
    e.kind = AP_EFFECT_USER, e.generalized = user_force;
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  }
  return compile(b);
}

/* One body of the given shape on the plane-contact joint, rolling; ground motion by `ground`
 * (0 fixed, 1 turntable with Omega(t), 2 translating with V(t)); gravity. */
static ap_model *contact_model(ap_shape_kind kind, int ground, int no_spin, int spring) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("contact", &b) == AP_OK);
  ap_body_def def = ap_body_def_default();
  def.name = "wheel";
  def.mass = 1.3;
  def.shape.kind = kind;
  def.shape.radius = 0.4, def.shape.tube = 0.07;
  def.shape.semi_axes[0] = 0.5, def.shape.semi_axes[1] = 0.3, def.shape.semi_axes[2] = 0.2;
  rand_vec(def.com, 3, 0.1);
  rand_inertia(def.inertia, 0.05);
  AP_CHECK(ap_builder_add_body(b, &def, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0, c.no_spin = no_spin;
  if (ground == 1) {
    c.ground.kind = AP_GROUND_TURNTABLE, c.ground.omega_fn = f_omega;
    c.ground.center[0] = -0.4, c.ground.center[1] = 0.25;
  } else if (ground == 2) {
    c.ground.kind = AP_GROUND_TRANSLATING, c.ground.velocity_fn[1] = f_vel;
    c.ground.velocity[0] = -0.2;
  }
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  if (spring) {
    e.kind = AP_EFFECT_SPRING, e.body = 0, e.body2 = AP_GROUND, e.stiffness = 12.0;
    e.rest_length = 0.5, e.point[0] = 0.1, e.point2[2] = 1.5;
    AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  }
  return compile(b);
}

/* Conservative chain (gravity and a spring, no drive, no constraint) for Q . v = -dV/dt. */
static ap_model *conservative_model(void) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("conservative", &b) == AP_OK);
  int a = add_body(b, "a", 1.0, AP_SHAPE_NONE), c = add_body(b, "c", 2.0, AP_SHAPE_NONE);
  int e2 = add_body(b, "e", 0.5, AP_SHAPE_NONE);
  add_joint(b, AP_JOINT_BALL, AP_GROUND, a, 1);
  add_joint(b, AP_JOINT_PLANAR, a, c, 1);
  add_joint(b, AP_JOINT_FREE, AP_GROUND, e2, 1);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[0] = 0.5;
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  e.kind = AP_EFFECT_SPRING, e.body = c, e.body2 = e2, e.stiffness = 20.0, e.rest_length = 0.4;
  rand_vec(e.point, 3, 0.3), rand_vec(e.point2, 3, 0.3);
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  e.body2 = AP_GROUND, e.rest_length = 0.0, e.stiffness = 5.0;
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  return compile(b);
}

static const char *const shape_names[] = {"none", "point", "sphere", "ellipsoid", "disk",
                                          "torus"};

static void test_fd(void) {
  printf("finite differences along the motion (relative errors, worst of the samples):\n");
  ap_model *m = chain_model(0, 1);
  fd_many("chain (all joints)", m, 12, 0, 0.0);
  ap_model_free(m);
  m = chain_model(1, 1);
  fd_many("driven chain", m, 12, 0, 0.0);
  ap_model_free(m);
  m = conservative_model();
  fd_many("conservative (Q.v)", m, 8, 1, 0.0);
  ap_model_free(m);
  for (int kind = AP_SHAPE_POINT; kind <= AP_SHAPE_TORUS; kind++)
    for (int ground = 0; ground < 3; ground++) {
      char label[64];
      snprintf(label, sizeof label, "%s, ground %d", shape_names[kind], ground);
      m = contact_model((ap_shape_kind)kind, ground, ground == 1, 0);
      fd_many(label, m, 8, 0, kind >= AP_SHAPE_DISK ? 0.2 : 0.0);
      ap_model_free(m);
    }
  for (int kind = AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++) {
    char label[64];
    snprintf(label, sizeof label, "%s (Q.v)", shape_names[kind]);
    m = contact_model((ap_shape_kind)kind, 0, 0, 1);
    fd_many(label, m, 6, 1, kind >= AP_SHAPE_DISK ? 0.2 : 0.0);
    ap_model_free(m);
  }
}

/* ---- near the singular shapes; the deliberately broken rolling gamma ----------------------- */

/* A state of the contact model with the shape's axis `off` radians from the vertical (flipped
 * upside down with flip), random spin and speeds. */
static void tilted_state(double off, int flip, double *q, double *v) {
  double ex[3] = {1, 0, 0}, ez[3] = {0, 0, 1}, q1[4], q2[4];
  ap_quat_from_axis_angle(ez, 2 * RS_PI_ * urand(), q1);      /* spin about the body axis */
  ap_quat_from_axis_angle(ex, flip ? RS_PI_ - off : off, q2);  /* tilt */
  q[0] = srand1(), q[1] = srand1();
  ap_quat_mul(q2, q1, q + 2);
  rand_vec(v, 5, 1.0);
}

static void test_near_flat(void) {
  printf("near lying flat (axis 0.1 degree from the vertical, and 0.1 degree beyond):\n");
  for (int kind = AP_SHAPE_DISK; kind <= AP_SHAPE_TORUS; kind++)
    for (int flip = 0; flip < 2; flip++) {
      ap_model *m = contact_model((ap_shape_kind)kind, 1, 0, 0);
      ap_data *d = NULL;
      AP_CHECK(ap_data_create(m, &d) == AP_OK);
      double off = 0.1 * RS_PI_ / 180, q[6], v[5], worst = 0.0;
      for (int s = 0; s < 4; s++) {
        fd_result r;
        tilted_state(off, flip, q, v);
        /* h ~ 1e-3 of the distance to the singularity: the contact point runs round the rim
         * at a rate ~ |w| / sin(off), so the derivatives of order p grow like sin(off)^-p. */
        AP_CHECK(fd_check(m, d, 0.3, q, v, 1e-3 * sin(off), &r, NULL, NULL) == AP_OK);
        worst = fmax(worst, fmax(fmax(r.vel, r.omega), fmax(fmax(r.alpha, r.acc), r.gamma)));
      }
      printf("  %-9s %s: worst relative error %.1e\n", shape_names[kind],
             flip ? "beyond flat" : "89.9 deg  ", worst);
      AP_CHECK_LE(worst, FD_TOL);
      /* Exactly flat: a clear recoverable error naming the body, never NaN. */
      double ex[3] = {1, 0, 0};
      ap_quat_from_axis_angle(ex, flip ? RS_PI_ : 0.0, q + 2);
      memcpy(d->q, q, sizeof q);
      d->t = 0.3, d->basis = AP_BASIS_NONE;
      int rc = ap_fwd_position(m, d);
      AP_CHECK_EQ_INT(rc, AP_RECOVERABLE);
      AP_CHECK(strstr(d->msg, "body 'wheel'") && strstr(d->msg, "flat"));
      if (kind == AP_SHAPE_DISK && !flip) printf("  flat disk: %s\n", d->msg);
      ap_data_free(d);
      ap_model_free(m);
    }
}

/* The rolling gamma without the contact point's motion over the surface fails the same check
 * that the real one passes: the test would catch the classic mistake. */
static void test_broken_gamma(void) {
  printf("rolling gamma without the surface-motion term (must fail the check):\n");
  for (int kind = AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++) {
    ap_model *m = contact_model((ap_shape_kind)kind, 0, 0, 0);
    ap_data *d = NULL;
    AP_CHECK(ap_data_create(m, &d) == AP_OK);
    double q[6], v[5], gb[3], good = 0.0, bad = 1e300, worst = 0.0;
    for (int s = 0; s < 4; s++) {
      static meas a, der;
      double qd[6];
      tilted_state(0.3 + urand(), 0, q, v);
      AP_CHECK(measure(m, d, 0.2, q, v, &a) == AP_OK);
      ap_con_rolling_gamma(ap_bm(m), ap_bm_scratch(d), 0, 0, gb);
      for (int i = 0; i < 6; i++) {
        qd[i] = 0.0;
        for (int c = 0; c < 5; c++) qd[i] += d->N[i + 6 * c] * v[c];
      }
      AP_CHECK(fd_along(m, d, 0.2, q, v, qd, 1e-3, &der) == AP_OK);
      double mg[2] = {-a.gamma[0], -a.gamma[1]}, mb[2] = {-gb[0], -gb[1]};
      good = fmax(good, err_rel(mg, der.c, 2));
      bad = fmin(bad, err_rel(mb, der.c, 2));
      worst = fmax(worst, err_rel(mb, der.c, 2));
    }
    printf("  %-9s with the term %.1e; without it %.1e to %.1e\n", shape_names[kind], good,
           bad, worst);
    AP_CHECK_LE(good, FD_TOL);
    AP_CHECK(bad > 100 * FD_TOL);   /* every sample flags the broken gamma */
    AP_CHECK(worst > 1e-2);
    ap_data_free(d);
    ap_model_free(m);
  }
}

/* ---- the builder's validation ------------------------------------------------------------- */

/* A disk on a plane-contact joint, rolling; the caller spoils one thing. */
static ap_builder *disk_builder(ap_body_def *bd, ap_joint_def *jd, ap_constraint_def *cd) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("disk", &b) == AP_OK);
  AP_CHECK(ap_builder_add_body(b, bd, NULL) == AP_OK);
  AP_CHECK(ap_builder_add_joint(b, jd, NULL) == AP_OK);
  if (cd) AP_CHECK(ap_builder_add_constraint(b, cd, NULL) == AP_OK);
  return b;
}

static void expect_fail(ap_builder *b, const char *what) {
  ap_model *m = (ap_model *)1;
  int rc = ap_builder_compile(b, &m);
  const char *msg = ap_builder_message(b);
  AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
  AP_CHECK(m == NULL);
  if (!strstr(msg, what)) fprintf(stderr, "message '%s' lacks '%s'\n", msg, what);
  AP_CHECK(strstr(msg, what) != NULL);
  printf("  %s\n", msg);
  ap_builder_free(b);
}

static void disk_defs(ap_body_def *bd, ap_joint_def *jd, ap_constraint_def *cd) {
  *bd = ap_body_def_default();
  bd->name = "disk";
  bd->shape.kind = AP_SHAPE_DISK, bd->shape.radius = 0.3;
  AP_CHECK(ap_body_def_uniform(bd, 2.0) == AP_OK);
  *jd = ap_joint_def_default();
  jd->kind = AP_JOINT_PLANE_CONTACT, jd->child = 0;
  *cd = ap_constraint_def_default();
  cd->name = "roll", cd->body = 0, cd->no_spin = 1;
}

static void test_validation(void) {
  ap_body_def bd;
  ap_joint_def jd;
  ap_constraint_def cd;
  printf("builder validation messages:\n");
  disk_defs(&bd, &jd, &cd), bd.mass = -1.0;
  expect_fail(disk_builder(&bd, &jd, &cd), "body 'disk': mass -1 kg is not positive");
  disk_defs(&bd, &jd, &cd), bd.inertia[8] = -0.1;
  expect_fail(disk_builder(&bd, &jd, &cd), "body 'disk': inertia not positive definite "
              "(eigenvalue -0.1");
  disk_defs(&bd, &jd, &cd), bd.inertia[3] = 0.01;
  expect_fail(disk_builder(&bd, &jd, &cd), "body 'disk': inertia tensor not symmetric");
  disk_defs(&bd, &jd, &cd), bd.inertia[0] = bd.inertia[4] = 0.01;
  expect_fail(disk_builder(&bd, &jd, &cd), "triangle inequality");
  disk_defs(&bd, &jd, &cd), bd.shape.radius = 0.0;
  expect_fail(disk_builder(&bd, &jd, &cd), "body 'disk': disk radius 0 m is not positive");
  disk_defs(&bd, &jd, &cd), bd.shape.kind = AP_SHAPE_NONE;
  expect_fail(disk_builder(&bd, &jd, &cd), "needs a shape");
  disk_defs(&bd, &jd, &cd), jd.child = 7;
  expect_fail(disk_builder(&bd, &jd, &cd), "child body 7 does not exist");
  disk_defs(&bd, &jd, &cd), jd.parent_frame.pos[2] = 0.1;
  expect_fail(disk_builder(&bd, &jd, &cd), "leave parent_frame and child_frame");
  disk_defs(&bd, &jd, &cd), jd.kind = AP_JOINT_BALL, jd.drive[0] = f_sine;
  expect_fail(disk_builder(&bd, &jd, &cd), "cannot be driven");
  disk_defs(&bd, &jd, &cd), jd.kind = AP_JOINT_BALL, bd.shape.kind = AP_SHAPE_NONE;
  expect_fail(disk_builder(&bd, &jd, &cd), "rolling needs body 'disk' to have a shape");
  disk_defs(&bd, &jd, &cd), bd.shape.kind = AP_SHAPE_SPHERE, cd.kind = AP_CON_KNIFE_EDGE;
  cd.wheel = 1;
  expect_fail(disk_builder(&bd, &jd, &cd), "a wheel knife edge needs body 'disk' to be a disk");
  disk_defs(&bd, &jd, &cd), cd.kind = AP_CON_KNIFE_EDGE, cd.direction[1] = 0.0;
  expect_fail(disk_builder(&bd, &jd, &cd), "direction (0, 0, 0) is zero");
  disk_defs(&bd, &jd, &cd), cd.kind = AP_CON_USER, cd.rows = 2;
  expect_fail(disk_builder(&bd, &jd, &cd), "user constraint needs rows >= 1 (got 2) and both");
  disk_defs(&bd, &jd, &cd), jd.kind = AP_JOINT_FIXED;
  expect_fail(disk_builder(&bd, &jd, NULL), "no degrees of freedom");
  disk_defs(&bd, &jd, &cd), jd.kind = AP_JOINT_REVOLUTE, jd.drive[0] = f_sine;
  cd.kind = AP_CON_PRESCRIBED_SPEED, cd.joint = 0;
  {
    ap_builder *b = disk_builder(&bd, &jd, &cd);
    jd.drive[0] = NULL;
    bd.name = "other";
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    jd.child = 1;
    AP_CHECK(ap_builder_add_joint(b, &jd, NULL) == AP_OK);
    expect_fail(b, "speed 0 of joint 'joint0' is driven");
  }
  /* tree errors */
  disk_defs(&bd, &jd, &cd);
  {
    ap_builder *b = disk_builder(&bd, &jd, &cd);
    bd.name = "lonely";
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    expect_fail(b, "body 'lonely' has no joint");
  }
  {
    disk_defs(&bd, &jd, &cd);
    ap_builder *b = disk_builder(&bd, &jd, &cd);
    AP_CHECK(ap_builder_add_joint(b, &jd, NULL) == AP_OK);
    expect_fail(b, "body 'disk' is the child of two joints");
  }
  {
    ap_builder *b = NULL;
    AP_CHECK(ap_builder_create("loop", &b) == AP_OK);
    bd.name = "a";
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    bd.name = "b";
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    jd = ap_joint_def_default();
    jd.kind = AP_JOINT_REVOLUTE, jd.parent = 1, jd.child = 0;
    AP_CHECK(ap_builder_add_joint(b, &jd, NULL) == AP_OK);
    jd.parent = 0, jd.child = 1;
    AP_CHECK(ap_builder_add_joint(b, &jd, NULL) == AP_OK);
    expect_fail(b, "form a cycle");
  }
  {
    ap_builder *b = disk_builder(&bd, &jd, NULL);
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    expect_fail(b, "bodies 0 and 1 are both named 'b'");
  }
}

/* ---- names, sizes, counters, many data on one model, projection ---------------------------- */

static void test_names_and_data(void) {
  ap_body_def bd;
  ap_joint_def jd;
  ap_constraint_def cd;
  disk_defs(&bd, &jd, &cd);
  ap_builder *b = disk_builder(&bd, &jd, &cd);
  ap_effect_def e = ap_effect_def_default();
  int eg = -1;
  AP_CHECK(ap_builder_add_effect(b, &e, &eg) == AP_OK);
  ap_model *m = compile(b);
  if (!m) return;
  AP_CHECK_EQ_INT(ap_model_n(m), 6);
  AP_CHECK_EQ_INT(ap_model_k(m), 5);
  AP_CHECK_EQ_INT(ap_model_b(m), 3);
  AP_CHECK(strcmp(ap_model_coord_name(m, 0), "disk.x") == 0);
  AP_CHECK(strcmp(ap_model_coord_name(m, 2), "disk.qw") == 0);
  AP_CHECK(strcmp(ap_model_speed_name(m, 4), "disk.wz") == 0);
  AP_CHECK(strcmp(ap_model_constraint_name(m, 2), "roll.spin") == 0);
  AP_CHECK_EQ_INT(ap_model_find_coord(m, "disk.qz"), 5);
  AP_CHECK_EQ_INT(ap_model_find_body(m, "disk"), 0);
  AP_CHECK(ap_model_is_body_model(m));

  /* two data on one model, interleaved, give what each gives alone */
  ap_data *d1 = NULL, *d2 = NULL;
  AP_CHECK(ap_data_create(m, &d1) == AP_OK && ap_data_create(m, &d2) == AP_OK);
  double q1[6], v1[5], q2[6], v2[5], h1[5];
  tilted_state(0.4, 0, q1, v1);
  tilted_state(1.0, 0, q2, v2);
  memcpy(d1->q, q1, sizeof q1), memcpy(d1->v, v1, sizeof v1);
  memcpy(d2->q, q2, sizeof q2), memcpy(d2->v, v2, sizeof v2);
  d1->basis = d2->basis = AP_BASIS_NONE;
  AP_CHECK(ap_fwd_position(m, d1) == AP_OK && ap_fwd_position(m, d2) == AP_OK);
  AP_CHECK(ap_fwd_velocity(m, d1) == AP_OK && ap_fwd_velocity(m, d2) == AP_OK);
  memcpy(h1, d1->h, sizeof h1);
  AP_CHECK(ap_fwd_position(m, d1) == AP_OK && ap_fwd_velocity(m, d1) == AP_OK);
  for (int i = 0; i < 5; i++) AP_CHECK(h1[i] == d1->h[i]);
  AP_CHECK_EQ_INT(ap_body_effect_count(m, d1, eg), 2);
  AP_CHECK_EQ_INT(ap_body_effect_count(m, d2, eg), 1);

  /* quaternion projection: a drifted norm comes back to 1, small drifts are left alone */
  double q[6], change = 0.0;
  memcpy(q, q1, sizeof q);
  for (int i = 2; i < 6; i++) q[i] *= 1.001;
  AP_CHECK(ap_body_project_q(m, d1, q, &change) == AP_OK);
  AP_CHECK_NEAR(sqrt(q[2] * q[2] + q[3] * q[3] + q[4] * q[4] + q[5] * q[5]), 1.0, 1e-15);
  AP_CHECK_NEAR(change, 1e-3, 1e-12);
  AP_CHECK(ap_body_project_q(m, d1, q, &change) == AP_OK);
  AP_CHECK(change == 0.0);

  /* completing speeds: keep the angular velocity, solve the rest */
  int given[5] = {0, 0, 1, 1, 0};   /* the no-spin row fixes wz */
  double v[5] = {0, 0, 0.3, -0.2, 0.5};
  int rcs = ap_body_complete_speeds(m, d1, q1, given, v);
  if (rcs != AP_OK) fprintf(stderr, "complete_speeds: %d %s\n", rcs, d1->msg);
  AP_CHECK(rcs == AP_OK);
  AP_CHECK_LE(ap_constraint_residual(d1, v), 1e-14);
  ap_data_free(d1);
  ap_data_free(d2);
  ap_model_free(m);
}

/* A four-bar: three rods on revolute joints about x, the last rod's end pinned (y, z) to a
 * ground point; from a perturbed state the projection closes the loop to round-off. */
static void test_loop_projection(void) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("four-bar", &b) == AP_OK);
  for (int i = 0; i < 3; i++) {
    ap_body_def bd = ap_body_def_default();
    double I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.01};
    bd.com[2] = -0.5;
    memcpy(bd.inertia, I, sizeof I);
    AP_CHECK(ap_builder_add_body(b, &bd, NULL) == AP_OK);
    ap_joint_def jd = ap_joint_def_default();
    jd.kind = AP_JOINT_REVOLUTE, jd.parent = i - 1, jd.child = i;
    jd.axis[0] = 1.0, jd.axis[2] = 0.0;
    if (i > 0) jd.parent_frame.pos[2] = -1.0;
    AP_CHECK(ap_builder_add_joint(b, &jd, NULL) == AP_OK);
  }
  ap_constraint_def cd = ap_constraint_def_default();
  cd.name = "pin", cd.kind = AP_CON_COINCIDENT, cd.body = 2, cd.axes = 6u;
  cd.point[2] = -1.0, cd.point2[1] = 1.2;
  AP_CHECK(ap_builder_add_constraint(b, &cd, NULL) == AP_OK);
  ap_model *m = compile(b);
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  double q[3] = {0.9, -1.2, -0.9}, change = 0.0;   /* a rough guess */
  AP_CHECK(ap_body_project_q(m, d, q, &change) == AP_OK);
  AP_CHECK(change > 0.01);
  /* the closed loop: end of rod 3 at (1.2, 0) */
  double y = sin(q[0]) + sin(q[0] + q[1]) + sin(q[0] + q[1] + q[2]);
  double z = -cos(q[0]) - cos(q[0] + q[1]) - cos(q[0] + q[1] + q[2]);
  AP_CHECK_NEAR(y, 1.2, 1e-12);
  AP_CHECK_NEAR(z, 0.0, 1e-12);
  ap_data_free(d);
  ap_model_free(m);
}

int main(void) {
  test_validation();
  test_names_and_data();
  test_loop_projection();
  test_fd();
  test_near_flat();
  test_broken_gamma();
  return ap_check_finish("test_bodies");
}
