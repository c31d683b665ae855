/* test_effects: the library does only the work a scene asks for (docs/design.md §1 "Effects:
 * simulate only what the scene calls for"; issue 5 "Effects"). Proven by the counters of the
 * data struct (ap_data.cnt) and of the effects (ap_body_effect_count), never by timing:
 *
 *   effects      only listed effects are evaluated: each listed one exactly once per velocity
 *                stage (zero strength or not), the callbacks of effects that were defined but
 *                not added are never called, and a model without effects skips the force stage
 *   constraints  no constraint rows: no QR, no constraint and no gamma evaluation (math-level
 *                systems whose constraint and gamma callbacks would fail if called, and body
 *                models), in minimal and projected mode
 *   time         a scleronomic body model evaluates no rheonomic terms (cnt.rheonomic == 0);
 *                the same model made formally rheonomic (turntable at Omega = 0, a joint driven
 *                at a constant angle) counts them and gives the same g, h, Q, A, a0, gamma
 *   outputs      a scene without energy, residual, reactions or contact_forces channels
 *                computes none of them (scene data: cnt.energy, cnt.position; sim data:
 *                cnt.reactions all 0); with them, one of each per output row; the pipeline
 *                stage counts and the trajectory are the same either way: the skipped stages
 *                cost nothing else. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "refsys.h"
#include "scene/scene_int.h"

#define T_END 1.0

/* ---- counting callbacks ------------------------------------------------------------------ */

typedef struct calls {
  long wrench, user, constraint, gamma;
} calls;

static int zero_wrench(double t, double force[3], double torque[3], void *user) {
  (void)t, (void)force, (void)torque;
  ((calls *)user)->wrench++;
  return 0;
}

static int zero_user_force(double t, const double *q, const double *v, double *Q, void *user) {
  (void)t, (void)q, (void)v, (void)Q;
  ((calls *)user)->user++;
  return 0;
}

/* ---- the rolling disk from bodies, with a chosen list of effects -------------------------- */

enum { EFF_GRAVITY = 1, EFF_SPRING = 2, EFF_DAMPING = 4, EFF_APPLIED = 8, EFF_USER = 16,
       EFF_ALL = 31 };

/* Disk on a plane-contact joint, rolling on the ground (fixed, or a turntable at Omega = 0),
 * and the effects in `effects`, every one but gravity at zero strength. The wrench and user
 * effect definitions are always made (with counting callbacks); only listed ones are added. */
static ap_model *disk_model(unsigned effects, int turntable, calls *cb) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("disk", &b) == AP_OK);
  ap_body_def disk = ap_body_def_default();
  disk.name = "disk", disk.shape.kind = AP_SHAPE_DISK, disk.shape.radius = 0.3;
  AP_CHECK(ap_body_def_uniform(&disk, 1.5) == AP_OK);
  AP_CHECK(ap_builder_add_body(b, &disk, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.kind = AP_CON_ROLLING, c.body = 0;
  if (turntable) c.ground.kind = AP_GROUND_TURNTABLE, c.ground.omega = 0.0;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);

  ap_effect_def e[5];
  for (int i = 0; i < 5; i++) e[i] = ap_effect_def_default();
  e[0].name = "gravity";
  e[1].name = "spring", e[1].kind = AP_EFFECT_SPRING, e[1].body = 0, e[1].point[0] = 0.3;
  e[1].body2 = AP_GROUND, e[1].point2[2] = 1.0;                /* stiffness, damping 0 */
  e[2].name = "damping", e[2].kind = AP_EFFECT_JOINT_DAMPING, e[2].joint = 0;   /* 0 */
  e[3].name = "push", e[3].kind = AP_EFFECT_APPLIED, e[3].body = 0, e[3].wrench = zero_wrench;
  e[3].user = cb;
  e[4].name = "user", e[4].kind = AP_EFFECT_USER, e[4].generalized = zero_user_force;
  e[4].user = cb;
  for (int i = 0; i < 5; i++)
    if (effects & (1u << i)) AP_CHECK(ap_builder_add_effect(b, &e[i], NULL) == AP_OK);
  ap_model *m = NULL;
  int rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) fprintf(stderr, "compile: %s\n", ap_builder_message(b));
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_builder_free(b);
  return m;
}

/* Leaning 0.25 rad, spinning 7 rad/s and turning 1.2 rad/s (examples/rolling_disk.c). */
static void disk_state(const ap_model *m, double q0[6], double v0[5]) {
  double ex[3] = {1, 0, 0}, a[3] = {0, cos(0.25), -sin(0.25)};
  int given[5] = {0, 0, 1, 1, 1};
  q0[0] = q0[1] = 0.0;
  ap_quat_from_axis_angle(ex, -(1.5707963267948966 + 0.25), q0 + 2);
  v0[0] = v0[1] = 0.0;
  v0[2] = 7.0 * a[0], v0[3] = 7.0 * a[1], v0[4] = 7.0 * a[2] + 1.2;
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  d->t = 0.0;
  AP_CHECK(ap_body_complete_speeds(m, d, q0, given, v0) == AP_OK);
  ap_data_free(d);
}

static ap_sim *run(const ap_model *m, ap_mode mode, const double *q0, const double *v0,
                   double t_end) {
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.method = "dopri5", sd.rtol = 1e-9, sd.atol = 1e-11;
  ap_sim *s = NULL;
  char msg[512] = "";
  int rc = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "ap_sim_create (%s): %s\n", ap_model_name(m), msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (!s) return NULL;
  for (int i = 1; i <= 10; i++) {
    rc = ap_sim_advance(s, 0.1 * i * t_end);
    if (rc != AP_OK) fprintf(stderr, "advance (%s): %s\n", ap_model_name(m), ap_sim_message(s));
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) break;
  }
  return s;
}

/* ---- 1. only listed effects are evaluated ------------------------------------------------- */

static void test_listed_effects(void) {
  calls cl = {0, 0, 0, 0}, cf = {0, 0, 0, 0};
  ap_model *lean = disk_model(EFF_GRAVITY, 0, &cl), *full = disk_model(EFF_ALL, 0, &cf);
  ap_model *none = disk_model(0, 0, &cl);
  double q0[6], v0[5];
  disk_state(lean, q0, v0);
  ap_sim *sl = run(lean, AP_MODE_MINIMAL, q0, v0, T_END);
  ap_sim *sf = run(full, AP_MODE_MINIMAL, q0, v0, T_END);
  ap_sim *sn = run(none, AP_MODE_MINIMAL, q0, v0, 0.1);
  if (!sl || !sf || !sn) return;
  const ap_data *dl = ap_sim_data(sl), *df = ap_sim_data(sf), *dn = ap_sim_data(sn);

  /* gravity only: its counter is the velocity stage count; no effect index 1 exists, the
   * wrench and user callbacks defined alongside were never called */
  printf("gravity only:  %ld velocity stages, gravity evaluated %ld times, effect 1: %ld, "
         "wrench calls %ld, user force calls %ld\n", dl->cnt.velocity,
         ap_body_effect_count(lean, dl, 0), ap_body_effect_count(lean, dl, 1), cl.wrench,
         cl.user);
  AP_CHECK(dl->cnt.velocity > 100);
  AP_CHECK_EQ_INT(ap_body_effect_count(lean, dl, 0), dl->cnt.velocity);
  AP_CHECK_EQ_INT(ap_body_effect_count(lean, dl, 1), -1);
  AP_CHECK_EQ_INT(dl->cnt.force, dl->cnt.velocity);
  AP_CHECK_EQ_INT(cl.wrench, 0);
  AP_CHECK_EQ_INT(cl.user, 0);

  /* all five listed (four at zero strength): each once per velocity stage, nothing else */
  long sum = 0;
  for (int i = 0; i < 5; i++) {
    long n = ap_body_effect_count(full, df, i);
    AP_CHECK_EQ_INT(n, df->cnt.velocity);
    sum += n;
  }
  printf("five effects:  %ld velocity stages, effect evaluations %ld (5 x %ld), wrench calls "
         "%ld, user force calls %ld\n", df->cnt.velocity, sum, df->cnt.velocity, cf.wrench,
         cf.user);
  AP_CHECK_EQ_INT(sum, 5 * df->cnt.velocity);
  AP_CHECK_EQ_INT(ap_body_effect_count(full, df, 5), -1);
  AP_CHECK_EQ_INT(cf.wrench, df->cnt.velocity);
  AP_CHECK_EQ_INT(cf.user, df->cnt.velocity);

  /* zero-strength effects change nothing but the work: same steps, same trajectory */
  ap_sim_stats stl, stf;
  ap_sim_get_stats(sl, &stl), ap_sim_get_stats(sf, &stf);
  double dq = 0.0;
  for (int i = 0; i < 6; i++) dq = fmax(dq, fabs(ap_sim_q(sl)[i] - ap_sim_q(sf)[i]));
  printf("  same run: steps %ld and %ld, evaluations %ld and %ld, max |q difference| %.1e\n",
         stl.steps, stf.steps, stl.rhs_evals, stf.rhs_evals, dq);
  AP_CHECK_EQ_INT(stl.steps, stf.steps);
  AP_CHECK_EQ_INT(dl->cnt.velocity, df->cnt.velocity);
  AP_CHECK_LE(dq, 1e-15);

  /* no effects at all: the force stage is skipped (Q stays 0) */
  printf("no effects:    %ld velocity stages, force evaluations %ld, effect 0: %ld\n",
         dn->cnt.velocity, dn->cnt.force, ap_body_effect_count(none, dn, 0));
  AP_CHECK(dn->cnt.velocity > 0);
  AP_CHECK_EQ_INT(dn->cnt.force, 0);
  AP_CHECK_EQ_INT(ap_body_effect_count(none, dn, 0), -1);

  ap_sim_free(sl), ap_sim_free(sf), ap_sim_free(sn);
  ap_model_free(lean), ap_model_free(full), ap_model_free(none);
}

/* ---- 2. no constraints: no QR, no constraint rows, no gamma ------------------------------- */

static calls trap_calls;
static int trap_constraint(double t, const double *q, double *A, double *a0, void *user) {
  (void)t, (void)q, (void)A, (void)a0, (void)user;
  trap_calls.constraint++;
  return -1;   /* would stop the run if it were ever called */
}
static int trap_gamma(double t, const double *q, const double *v, double *gamma, void *user) {
  (void)t, (void)q, (void)v, (void)gamma, (void)user;
  trap_calls.gamma++;
  return -1;
}

/* Hoffmann's pendulum from bodies (section 3), optionally hung from a fixed or driven rod. */
enum { TOP_NONE = 0, TOP_FIXED = 1, TOP_DRIVEN = 2 };
static ap_model *pendulum_model(int top, double angle);

static void check_unconstrained(const char *what, const ap_data *d) {
  printf("%-34s position %5ld velocity %5ld acceleration %5ld | qr %ld, constraint %ld, "
         "gamma %ld, reactions %ld\n", what, d->cnt.position, d->cnt.velocity,
         d->cnt.acceleration, d->cnt.qr, d->cnt.constraint, d->cnt.gamma, d->cnt.reactions);
  AP_CHECK(d->cnt.position > 10 && d->cnt.velocity > 10);
  AP_CHECK_EQ_INT(d->cnt.qr, 0);
  AP_CHECK_EQ_INT(d->cnt.constraint, 0);
  AP_CHECK_EQ_INT(d->cnt.gamma, 0);
  AP_CHECK_EQ_INT(d->cnt.reactions, 0);
}

static void test_no_constraints(void) {
  static const ap_mode modes[2] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED};
  static const char *const names[2][2] = {{"math-level Hoffmann, minimal:", "math-level "
                                           "Hoffmann, projected:"},
                                          {"body Hoffmann (tree), minimal:", "body Hoffmann "
                                           "(tree), projected:"}};
  rs_hoffmann p = {1.0, 0.8, 0.5, 0.4, 0, 0, 9.81, 2.0};
  p.I1 = p.m1 * p.a1 * p.a1 / 3, p.I2 = p.m2 * p.a2 * p.a2 / 3;
  ap_system_def def;
  rs_hoffmann_reduced_system(&p, &def);
  def.constraint = trap_constraint, def.gamma = trap_gamma;   /* b = 0: must never be called */
  ap_model *mm = NULL, *mb = pendulum_model(TOP_NONE, 0.0);
  char msg[256];
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &mm, msg, sizeof msg), AP_OK);
  double q0[2] = {0.4, -0.3}, v0[2] = {0.5, 1.2};
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = run(mm, modes[mi], q0, v0, T_END);
    if (s) check_unconstrained(names[0][mi], ap_sim_data(s));
    ap_sim_free(s);
    s = run(mb, modes[mi], q0, v0, T_END);
    if (s) check_unconstrained(names[1][mi], ap_sim_data(s));
    ap_sim_free(s);
  }
  AP_CHECK_EQ_INT(trap_calls.constraint, 0);
  AP_CHECK_EQ_INT(trap_calls.gamma, 0);

  /* the contrast: with constraint rows every position stage factors A */
  calls cb = {0, 0, 0, 0};
  ap_model *disk = disk_model(EFF_GRAVITY, 0, &cb);
  double dq0[6], dv0[5];
  disk_state(disk, dq0, dv0);
  ap_sim *s = run(disk, AP_MODE_MINIMAL, dq0, dv0, 0.2);
  if (s) {
    const ap_data *d = ap_sim_data(s);
    printf("%-34s position %5ld velocity %5ld acceleration %5ld | qr %ld, constraint %ld, "
           "gamma %ld\n", "rolling disk (b = 2), minimal:", d->cnt.position, d->cnt.velocity,
           d->cnt.acceleration, d->cnt.qr, d->cnt.constraint, d->cnt.gamma);
    AP_CHECK_EQ_INT(d->cnt.qr, d->cnt.position);
    AP_CHECK(d->cnt.constraint >= d->cnt.position);   /* ap_partition evaluates A too */
    AP_CHECK_EQ_INT(d->cnt.gamma, d->cnt.velocity);
  }
  ap_sim_free(s);
  ap_model_free(disk), ap_model_free(mm), ap_model_free(mb);
}

/* ---- 3. scleronomic models evaluate no time-dependent terms ------------------------------- */

static int const_angle(double t, double f[3], void *user) {
  (void)t;
  f[0] = *(const double *)user, f[1] = 0.0, f[2] = 0.0;
  return 0;
}

/* Two rods on revolutes about x (Hoffmann's pendulum as a tree, k = 2), gravity and a
 * horizontal force on the lower rod. With top != TOP_NONE they hang from a third rod held at
 * `angle` about x, either by a revolute driven at that constant angle (TOP_DRIVEN: rheonomic,
 * the drive's column of every Jacobian is evaluated) or by a fixed joint turned by it
 * (TOP_FIXED: the same transform, scleronomic): k = 2 either way. */
static double drive_angle;
static ap_model *pendulum_model(int top, double angle) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create(top == TOP_DRIVEN ? "driven" : "pendulum", &b) == AP_OK);
  const double mass[3] = {1.0, 0.8, 0.6}, half[3] = {0.5, 0.4, 0.3};
  int ids[3], nrods = top == TOP_NONE ? 2 : 3;
  for (int r = 0; r < nrods; r++) {
    ap_body_def d = ap_body_def_default();
    double I = mass[r] * half[r] * half[r] / 3;
    d.mass = mass[r], d.com[2] = -half[r];
    d.inertia[0] = d.inertia[4] = I, d.inertia[8] = 1e-3 * I;
    AP_CHECK(ap_builder_add_body(b, &d, &ids[r]) == AP_OK);
  }
  ap_joint_def j = ap_joint_def_default();
  if (top != TOP_NONE) {
    const double ex[3] = {1, 0, 0};
    j.child = ids[2];
    if (top == TOP_DRIVEN) {
      drive_angle = angle;
      j.kind = AP_JOINT_REVOLUTE, j.axis[0] = 1.0, j.axis[2] = 0.0;
      j.drive[0] = const_angle, j.drive_user[0] = &drive_angle;
    } else {
      j.kind = AP_JOINT_FIXED;
      ap_quat_from_axis_angle(ex, angle, j.parent_frame.quat);
    }
    AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  }
  j = ap_joint_def_default();
  j.kind = AP_JOINT_REVOLUTE, j.axis[0] = 1.0, j.axis[2] = 0.0, j.child = ids[0];
  if (top != TOP_NONE) j.parent = ids[2], j.parent_frame.pos[2] = -2 * half[2];
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  j = ap_joint_def_default();
  j.kind = AP_JOINT_REVOLUTE, j.axis[0] = 1.0, j.axis[2] = 0.0;
  j.parent = ids[0], j.child = ids[1], j.parent_frame.pos[2] = -2 * half[0];
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  e = ap_effect_def_default();
  e.name = "F", e.kind = AP_EFFECT_APPLIED, e.body = ids[1], e.force[1] = 2.0;
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  ap_model *m = NULL;
  int rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) fprintf(stderr, "compile: %s\n", ap_builder_message(b));
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_builder_free(b);
  return m;
}

static double rel(double a, double b) { return fabs(a - b) / fmax(1.0, fabs(b)); }

/* Position and velocity stages of two models with the same sizes at (t, q, v); the largest
 * relative difference of g, h, Q, A, a0, gamma. */
static double same_objects(const ap_model *m1, ap_data *d1, const ap_model *m2, ap_data *d2,
                           double t, const double *q, const double *v) {
  ap_data *d[2] = {d1, d2};
  const ap_model *m[2] = {m1, m2};
  for (int i = 0; i < 2; i++) {
    d[i]->t = t, d[i]->speeds_from_e = 0, d[i]->basis = AP_BASIS_NONE;
    memcpy(d[i]->q, q, sizeof(double) * (size_t)d[i]->n);
    memcpy(d[i]->v, v, sizeof(double) * (size_t)d[i]->k);
    AP_CHECK_EQ_INT(ap_fwd_position(m[i], d[i]), AP_OK);
    AP_CHECK_EQ_INT(ap_fwd_velocity(m[i], d[i]), AP_OK);
  }
  int k = d1->k, b = d1->b;
  double e = 0.0;
  for (int i = 0; i < k * k; i++) e = fmax(e, rel(d1->g[i], d2->g[i]));
  for (int i = 0; i < k; i++) e = fmax(e, fmax(rel(d1->h[i], d2->h[i]), rel(d1->Q[i], d2->Q[i])));
  for (int i = 0; i < b * k; i++) e = fmax(e, rel(d1->A[i], d2->A[i]));
  for (int s = 0; s < b; s++)
    e = fmax(e, fmax(rel(d1->a0[s], d2->a0[s]), rel(d1->gamma[s], d2->gamma[s])));
  return e;
}

static void test_scleronomic(void) {
  calls cb = {0, 0, 0, 0};
  ap_model *fixed = disk_model(EFF_GRAVITY, 0, &cb), *table = disk_model(EFF_GRAVITY, 1, &cb);
  ap_data *df = NULL, *dt = NULL;
  AP_CHECK(ap_data_create(fixed, &df) == AP_OK && ap_data_create(table, &dt) == AP_OK);
  double q[6], v[5], e = 0.0;
  disk_state(fixed, q, v);
  for (int i = 0; i < 5; i++) {
    v[i % 5] += 0.1 * (i + 1);   /* states off the constraint set: rows, a0, gamma in full */
    e = fmax(e, same_objects(fixed, df, table, dt, 0.3 * i, q, v));
  }
  printf("disk, fixed ground vs turntable at Omega = 0: %ld and %ld position stages, rheonomic "
         "%ld and %ld; g h Q A a0 gamma agree to %.1e\n", df->cnt.position, dt->cnt.position,
         df->cnt.rheonomic, dt->cnt.rheonomic, e);
  AP_CHECK_EQ_INT(df->cnt.rheonomic, 0);
  AP_CHECK_EQ_INT(dt->cnt.rheonomic, dt->cnt.position);
  AP_CHECK_LE(e, 1e-15);
  ap_data_free(df), ap_data_free(dt);

  /* a whole run of the scleronomic disk */
  disk_state(fixed, q, v);
  ap_sim *s = run(fixed, AP_MODE_MINIMAL, q, v, 0.2);
  if (s) {
    printf("  a run on the fixed ground: %ld position stages, rheonomic %ld\n",
           ap_sim_data(s)->cnt.position, ap_sim_data(s)->cnt.rheonomic);
    AP_CHECK(ap_sim_data(s)->cnt.position > 10);
    AP_CHECK_EQ_INT(ap_sim_data(s)->cnt.rheonomic, 0);
  }
  ap_sim_free(s);
  ap_model_free(fixed), ap_model_free(table);

  /* a joint driven at a constant angle (rheonomic column of every Jacobian evaluated) against
   * a fixed joint turned by that angle (the column skipped) */
  ap_model *md = pendulum_model(TOP_DRIVEN, 0.7), *mx = pendulum_model(TOP_FIXED, 0.7);
  ap_data *dd = NULL, *dx = NULL;
  AP_CHECK(ap_data_create(md, &dd) == AP_OK && ap_data_create(mx, &dx) == AP_OK);
  AP_CHECK_EQ_INT(ap_model_k(md), 2);
  AP_CHECK_EQ_INT(ap_model_k(mx), 2);
  e = 0.0;
  for (int i = 0; i < 5; i++) {
    double qq[2] = {0.3 * i - 0.5, 0.2 - 0.4 * i}, vv[2] = {1.0 - 0.3 * i, 0.5 + 0.2 * i};
    e = fmax(e, same_objects(md, dd, mx, dx, 0.1 * i, qq, vv));
  }
  printf("pendulum below a driven joint vs below a fixed joint: rheonomic %ld and %ld of %ld "
         "position stages; g h Q agree to %.1e\n", dd->cnt.rheonomic, dx->cnt.rheonomic,
         dx->cnt.position, e);
  AP_CHECK_EQ_INT(dd->cnt.rheonomic, dd->cnt.position);
  AP_CHECK_EQ_INT(dx->cnt.rheonomic, 0);
  AP_CHECK_LE(e, 1e-14);
  ap_data_free(dd), ap_data_free(dx);
  ap_model_free(md), ap_model_free(mx);
}

/* ---- 4. outputs: energy, residual and reactions only when a channel asks ------------------ */

static const char scene_text[] =
    "name: disk\n"
    "bodies:\n"
    "  disk: {mass: 1.5, shape: {kind: disk, radius: 0.3}, inertia: uniform}\n"
    "joints:\n"
    "  disk: {kind: plane_contact}\n"
    "constraints:\n"
    "  roll: {kind: rolling, body: disk}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  disk: {heading: 0, tilt: 75*deg, spin: 0, spin_rate: -7, heading_rate: 1.2}\n"
    "simulation: {mode: minimal, method: dopri5, rtol: 1e-9, atol: 1e-11, t_end: 1}\n"
    "output:\n"
    "  interval: 0.05\n";

typedef struct scene_run {
  long rows, position, velocity, acceleration, energy, resid_pos, reactions, steps;
  double q[8];
} scene_run;

static scene_run run_scene(const char *channels) {
  scene_run r;
  memset(&r, 0, sizeof r);
  char text[2048], msg[1024] = "";
  snprintf(text, sizeof text, "%s  channels: %s\n", scene_text, channels);
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, strlen(text), "effects.yaml", NULL, 0, &sc, msg,
                                sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "scene: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (!sc) return r;
  const ap_model *m = ap_scene_model(sc);
  ap_scene_run sr;
  ap_scene_get_run(sc, &sr);
  double q0[8], v0[8], row[64];
  AP_CHECK(ap_scene_output_count(sc) <= 64);
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q0, v0, NULL, 0, msg, sizeof msg), AP_OK);
  ap_sim *s = NULL;
  AP_CHECK_EQ_INT(ap_sim_create(m, &sr.sim, sr.t0, q0, v0, &s, msg, sizeof msg), AP_OK);
  if (!s) {
    ap_scene_free(sc);
    return r;
  }
  long nrows = lround((sr.t_end - sr.t0) / sr.interval);
  for (long i = 0; i <= nrows; i++) {
    if (i > 0) AP_CHECK_EQ_INT(ap_sim_advance(s, sr.t0 + (double)i * sr.interval), AP_OK);
    AP_CHECK_EQ_INT(ap_scene_output_row(sc, s, row), AP_OK);
    r.rows++;
  }
  const ap_data *ds = ap_sim_data(s), *dout = sc_scene_output_data(sc);
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  r.position = ds->cnt.position, r.velocity = ds->cnt.velocity;
  r.acceleration = ds->cnt.acceleration, r.reactions = ds->cnt.reactions, r.steps = st.steps;
  r.energy = dout->cnt.energy, r.resid_pos = dout->cnt.position;
  memcpy(r.q, ap_sim_q(s), sizeof(double) * (size_t)ap_model_n(m));
  printf("channels %-56s rows %2ld | sim: position %4ld velocity %4ld acceleration %4ld "
         "reactions %2ld | outputs: energy %2ld residual %2ld\n", channels, r.rows, r.position,
         r.velocity, r.acceleration, r.reactions, r.energy, r.resid_pos);
  ap_sim_free(s);
  ap_scene_free(sc);
  return r;
}

static void test_outputs(void) {
  scene_run lean = run_scene("[coordinates]");
  scene_run all = run_scene("[coordinates, speeds, angles, com, contacts, energy, residual, "
                            "reactions]");
  scene_run forces = run_scene("[coordinates, contact_forces]");   /* needs the multipliers */
  AP_CHECK_EQ_INT(forces.reactions, forces.rows);
  AP_CHECK_EQ_INT(forces.energy, 0);
  AP_CHECK_EQ_INT(forces.resid_pos, 0);
  AP_CHECK_EQ_INT(forces.position, lean.position);
  AP_CHECK(lean.rows > 10);
  AP_CHECK_EQ_INT(lean.energy, 0);
  AP_CHECK_EQ_INT(lean.resid_pos, 0);
  AP_CHECK_EQ_INT(lean.reactions, 0);
  AP_CHECK_EQ_INT(all.rows, lean.rows);
  AP_CHECK_EQ_INT(all.energy, all.rows);
  AP_CHECK_EQ_INT(all.resid_pos, all.rows);
  AP_CHECK_EQ_INT(all.reactions, all.rows);
  /* the optional outputs add only their own stages: the pipeline ran the same number of
   * position, velocity and acceleration stages, and the trajectory is the same */
  AP_CHECK_EQ_INT(all.steps, lean.steps);
  AP_CHECK_EQ_INT(all.position, lean.position);
  AP_CHECK_EQ_INT(all.velocity, lean.velocity);
  AP_CHECK_EQ_INT(all.acceleration, lean.acceleration);
  double dq = 0.0;
  for (int i = 0; i < 6; i++) dq = fmax(dq, fabs(all.q[i] - lean.q[i]));
  AP_CHECK(dq == 0.0);
  printf("  same pipeline work (steps %ld, %ld position stages) and the same final state "
         "(difference %.1e) with and without the optional outputs\n", lean.steps, lean.position,
         dq);
}

int main(void) {
  test_listed_effects();
  test_no_constraints();
  test_scleronomic();
  test_outputs();
  return ap_check_finish("test_effects");
}
