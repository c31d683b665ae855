/* Body layer: the builder's validation and messages, names, and the exact kinematics against
 * central finite differences along the motion.
 *
 * Finite differences: at a random state (t, q, v) the path q(s) = q + s N(q) v, t(s) = t + s
 * has tangent (q', 1) at s = 0, so along it (v held fixed)
 *   d/ds x_p   = v_p          (point velocity from the Jacobian: J_p v + rheonomic part)
 *   d/ds R R^T = [w]x         (angular velocity)
 *   d/ds w(s)  = aw           (angular bias acceleration Jw' v + rw')
 *   d/ds v_p(s)= av           (point bias acceleration)
 *   d/ds (A v + a0) = -gamma
 *   d/ds V     = -Q . v       (conservative effects, scleronomic models)
 * The derivative is a Richardson-extrapolated central difference, (4 D(h/2) - D(h)) / 3 with
 * D(h) = (f(h) - f(-h)) / 2h: truncation O(h^4 f^(5)) ~ 1e-12 for h = 1e-3 on these O(1)
 * problems and round-off ~ eps |f| / h ~ 1e-13, so the asserted relative tolerance 1e-7
 * (relative to max(1, |analytic|)) leaves five orders of margin while any missing term
 * (a factor 2 in a Coriolis term, the contact point moving over the surface) is O(1) wrong.
 * Near a singular shape (disk 0.1 degree from flat) h is scaled with the distance to the
 * singularity. A deliberately broken rolling gamma (without the surface-motion term) must
 * fail the same check by orders of magnitude: the test shows it catches that mistake. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "model/model.h"

#define FD_TOL 1e-7
#define RS_PI_ 3.14159265358979323846
#define MAXB 8
#define MAXK 40
#define MAXR 24

/* ---- random numbers (xorshift64*, fixed seed) -------------------------------------------- */

static unsigned long long rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void) {
  rng_state ^= rng_state >> 12, rng_state ^= rng_state << 25, rng_state ^= rng_state >> 27;
  return (double)((rng_state * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}
static double srand1(void) { return 2.0 * urand() - 1.0; }
static void rand_vec(double *x, int n, double s) {
  for (int i = 0; i < n; i++) x[i] = s * srand1();
}
static void rand_quat(double *q) {
  double n = 0.0;
  for (int i = 0; i < 4; i++) q[i] = srand1(), n += q[i] * q[i];
  n = sqrt(n);
  for (int i = 0; i < 4; i++) q[i] /= n;
}
static void rand_frame(ap_frame *f) {
  rand_vec(f->pos, 3, 0.3);
  rand_quat(f->quat);
}
/* A random physical inertia: R diag(l) R^T, l in [1, 1.5] * scale (triangle inequality). */
static void rand_inertia(double *I, double scale) {
  double q[4], R[9], l[3];
  rand_quat(q);
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++) l[i] = scale * (1.0 + 0.5 * urand());
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double s = 0.0;
      for (int c = 0; c < 3; c++) s += R[i + 3 * c] * l[c] * R[j + 3 * c];
      I[i + 3 * j] = s;
    }
}

/* ---- time functions used by drives, turntables, prescribed speeds ---------------------------- */

static int f_sine(double t, double f[3], void *user) {
  double a = user ? *(double *)user : 1.0, w = 1.3;
  f[0] = 0.5 * a * sin(w * t) + 0.2 * t;
  f[1] = 0.5 * a * w * cos(w * t) + 0.2;
  f[2] = -0.5 * a * w * w * sin(w * t);
  return 0;
}
static int f_omega(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.7 + 0.3 * sin(0.9 * t);
  f[1] = 0.27 * cos(0.9 * t);
  return 0;
}
static int f_vel(double t, double f[3], void *user) {
  (void)user;
  f[0] = 0.4 * cos(1.1 * t);
  f[1] = -0.44 * sin(1.1 * t);
  return 0;
}
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

/* ---- measurements along the path ------------------------------------------------------------ */

typedef struct meas {
  double x[MAXB][3], R[MAXB][9], w[MAXB][3], vp[MAXB][3], aw[MAXB][3], av[MAXB][3];
  double c[MAXR], gamma[MAXR], QV, V;
} meas;

static const double probe[3] = {0.13, -0.21, 0.17};

static int measure(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
                   meas *out) {
  int nb = ap_model_body_count(m), k = m->k;
  d->t = t;
  memcpy(d->q, q, sizeof(double) * (size_t)m->n);
  memcpy(d->v, v, sizeof(double) * (size_t)k);
  d->basis = AP_BASIS_NONE, d->speeds_from_e = 0;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(m, d);
  if (rc != AP_OK) return rc;
  for (int b = 0; b < nb; b++) {
    ap_body_state st;
    double Jw[3 * MAXK], Jv[3 * MAXK], rw[3], rv[3];
    ap_body_get_state(m, d, b, &st);
    ap_body_point_jacobian(m, d, b, probe, Jw, Jv, rw, rv, out->aw[b], out->av[b]);
    memcpy(out->R[b], st.R, sizeof st.R);
    for (int i = 0; i < 3; i++) {
      out->x[b][i] = st.pos[i];
      for (int j = 0; j < 3; j++) out->x[b][i] += st.R[i + 3 * j] * probe[j];
      out->w[b][i] = rw[i], out->vp[b][i] = rv[i];
      for (int c = 0; c < k; c++)
        out->w[b][i] += Jw[i + 3 * c] * v[c], out->vp[b][i] += Jv[i + 3 * c] * v[c];
    }
  }
  for (int s = 0; s < m->b; s++) {
    out->c[s] = d->a0[s], out->gamma[s] = d->gamma[s];
    for (int c = 0; c < k; c++) out->c[s] += d->A[s + (size_t)c * m->b] * v[c];
  }
  out->QV = 0.0;
  for (int c = 0; c < k; c++) out->QV += d->Q[c] * v[c];
  double T = 0.0;
  return ap_body_energy(m, d, &T, &out->V);
}

/* All fields of a meas as one flat array, so differences apply to everything at once. */
#define MEAS_N (sizeof(meas) / sizeof(double))

static double err_rel(const double *an, const double *fd, int n) {
  double e = 0.0, s = 1.0;
  for (int i = 0; i < n; i++) s = fmax(s, fabs(an[i]));
  for (int i = 0; i < n; i++) e = fmax(e, fabs(an[i] - fd[i]));
  return e / s;
}

typedef struct fd_result {
  double vel, omega, alpha, acc, gamma, power;   /* relative errors */
} fd_result;

/* Richardson-extrapolated derivative of every field along the path. */
static int fd_along(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
                    const double *qd, double h, meas *der) {
  static meas f[4];
  const double sgn[4] = {1, -1, 0.5, -0.5};
  double qs[MAXK];
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < m->n; j++) qs[j] = q[j] + sgn[i] * h * qd[j];
    int rc = measure(m, d, t + sgn[i] * h, qs, v, &f[i]);
    if (rc != AP_OK) return rc;
  }
  double *D = (double *)der, *f0 = (double *)&f[0], *f1 = (double *)&f[1],
         *f2 = (double *)&f[2], *f3 = (double *)&f[3];
  for (size_t i = 0; i < MEAS_N; i++) {
    double Dh = (f0[i] - f1[i]) / (2 * h), Dh2 = (f2[i] - f3[i]) / h;
    D[i] = (4 * Dh2 - Dh) / 3;
  }
  return AP_OK;
}

/* Compare the analytic quantities at (t, q, v) with finite differences along the motion. */
static int fd_check(const ap_model *m, ap_data *d, double t, const double *q, const double *v,
                    double h, fd_result *res) {
  static meas a, der;
  double qd[MAXK];
  int nb = ap_model_body_count(m), rc = measure(m, d, t, q, v, &a);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < m->n; i++) {
    qd[i] = 0.0;
    for (int c = 0; c < m->k; c++) qd[i] += d->N[i + (size_t)c * m->n] * v[c];
  }
  rc = fd_along(m, d, t, q, v, qd, h, &der);
  if (rc != AP_OK) return rc;
  memset(res, 0, sizeof *res);
  for (int b = 0; b < nb; b++) {
    double w[3], *Rd = der.R[b], *R = a.R[b], W[9];
    for (int i = 0; i < 3; i++)   /* W = R' R^T */
      for (int j = 0; j < 3; j++)
        W[i + 3 * j] = Rd[i] * R[j] + Rd[i + 3] * R[j + 3] + Rd[i + 6] * R[j + 6];
    w[0] = 0.5 * (W[2 + 3 * 1] - W[1 + 3 * 2]);
    w[1] = 0.5 * (W[0 + 3 * 2] - W[2 + 3 * 0]);
    w[2] = 0.5 * (W[1 + 3 * 0] - W[0 + 3 * 1]);
    res->vel = fmax(res->vel, err_rel(a.vp[b], der.x[b], 3));
    res->omega = fmax(res->omega, err_rel(a.w[b], w, 3));
    res->alpha = fmax(res->alpha, err_rel(a.aw[b], der.w[b], 3));
    res->acc = fmax(res->acc, err_rel(a.av[b], der.vp[b], 3));
  }
  double mg[MAXR], pw = -a.QV;
  for (int s = 0; s < m->b; s++) mg[s] = -a.gamma[s];
  res->gamma = m->b ? err_rel(mg, der.c, m->b) : 0.0;
  res->power = err_rel(&pw, &der.V, 1);
  return AP_OK;
}

/* Random state: coordinates (quaternions unit), speeds, time. */
static void rand_state(const ap_model *m, double *q, double *v, double *t) {
  rand_vec(q, m->n, 1.0);
  for (int i = 0; i < m->n; i++) {
    const char *nm = ap_model_coord_name(m, i);
    const char *dot = strrchr(nm, '.');
    if (dot && strcmp(dot, ".qw") == 0) rand_quat(q + i), i += 3;
  }
  rand_vec(v, m->k, 1.0);
  *t = 2.0 * urand();
}

/* Run fd_check at several random states and assert every error; returns the worst. */
static fd_result fd_many(const char *label, const ap_model *m, int samples, int check_power,
                         double min_flat) {
  ap_data *d = NULL;
  fd_result worst = {0, 0, 0, 0, 0, 0};
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  for (int s = 0; s < samples; s++) {
    double q[MAXK], v[MAXK], t;
    fd_result r;
    int rc;
    do {   /* keep disks and tori away from lying flat in the generic samples */
      rand_state(m, q, v, &t);
      rc = measure(m, d, t, q, v, &(meas){0});
      if (rc == AP_OK && min_flat > 0) {
        ap_body_state st;
        ap_body_get_state(m, d, 0, &st);
        if (hypot(st.R[8], 0.0) > sqrt(1 - min_flat * min_flat)) rc = 1;
      }
    } while (rc != AP_OK);
    rc = fd_check(m, d, t, q, v, 1e-3, &r);
    AP_CHECK(rc == AP_OK);
    worst.vel = fmax(worst.vel, r.vel), worst.omega = fmax(worst.omega, r.omega);
    worst.alpha = fmax(worst.alpha, r.alpha), worst.acc = fmax(worst.acc, r.acc);
    worst.gamma = fmax(worst.gamma, r.gamma), worst.power = fmax(worst.power, r.power);
  }
  printf("  %-22s vel %.1e  omega %.1e  alpha %.1e  acc %.1e  gamma %.1e  power %.1e\n", label,
         worst.vel, worst.omega, worst.alpha, worst.acc, worst.gamma,
         check_power ? worst.power : 0.0);
  AP_CHECK_LE(worst.vel, FD_TOL);
  AP_CHECK_LE(worst.omega, FD_TOL);
  AP_CHECK_LE(worst.alpha, FD_TOL);
  AP_CHECK_LE(worst.acc, FD_TOL);
  AP_CHECK_LE(worst.gamma, FD_TOL);
  if (check_power) AP_CHECK_LE(worst.power, FD_TOL);
  ap_data_free(d);
  return worst;
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
        AP_CHECK(fd_check(m, d, 0.3, q, v, 1e-3 * sin(off), &r) == AP_OK);
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
  disk_defs(&bd, &jd, &cd), jd.kind = AP_JOINT_BALL;
  expect_fail(disk_builder(&bd, &jd, &cd), "rolling needs body 'disk' on a plane-contact");
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
