/* The drift suite's systems (drift.h; the runner and the figures are described in drift.c):
 * math-level systems (knife edge, sleigh, turntable, rotating line, Hoffmann's primitive
 * connection) and body models (rolling disk, heavy top, rattleback, Hoffmann's loop, spinning
 * ball), each with its setup, its invariants and the table of runs (group, modes, method, rtol,
 * length, promised steps). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "drift.h"


static int from_system(sysrun *r, ap_system_def *def) {
  char msg[256] = "";
  int rc = ap_model_from_system(def, &r->m, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", r->sys->name, msg);
  return rc;
}

static int compile(sysrun *r, ap_builder *b) {
  int rc = ap_builder_compile(b, &r->m);
  if (rc != AP_OK) fprintf(stderr, "%s: %s\n", r->sys->name, ap_builder_message(b));
  ap_builder_free(b);
  return rc;
}

/* ---- math level: knife edge, sleigh, turntable, rotating line, Hoffmann primitive ---------- */

static int skate_setup(sysrun *r) {
  rs_knife p = {1.0, 0.1, 9.81, 0.3};
  ap_system_def def;
  r->p.knife = p;
  rs_knife_system(&r->p.knife, &def);
  rs_knife_initial(0.0, 0.0, 0.1, 0.5, 2.0, r->q0, r->v0);
  return from_system(r, &def);
}

static int skate_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                         double *loop) {
  (void)t, (void)loop;
  inv[0] = rs_knife_energy(&r->p.knife, q, v);
  return AP_OK;
}

static int sleigh_setup(sysrun *r) {
  rs_sleigh p = {1.0, 1.0, 1.0};
  ap_system_def def;
  r->p.sleigh = p;
  rs_sleigh_system(&r->p.sleigh, 1, &def);
  rs_sleigh_initial(0.0, 0.0, RS_PI, 0.1, 0.2, r->q0, r->v0);   /* docs/references.md §2 sample */
  return from_system(r, &def);
}

static int sleigh_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                          double *loop) {
  (void)t, (void)loop;
  inv[0] = rs_sleigh_energy(&r->p.sleigh, q, v);
  return AP_OK;
}

static int table_setup(sysrun *r) {
  rs_turntable p = {1.2, 0.3, 0.4, 1.1, 0.0};
  ap_system_def def;
  r->p.table = p;
  rs_turntable_system(&r->p.table, &def);
  rs_turntable_initial(&r->p.table, 0.5, -0.2, 1.0, 2.0, 3.0, r->q0, r->v0);
  return from_system(r, &def);
}

static int table_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                         double *loop) {
  double c[2];
  (void)loop;
  rs_turntable_invariant(&r->p.table, t, q, v, c);
  inv[0] = c[0], inv[1] = v[4];
  inv[MAXINV] = c[1];   /* the imaginary part rides in the spare slot (inv_drift) */
  return AP_OK;
}

static int line_setup(sysrun *r) {
  rs_line p = {1.0, 9.81, 1.2, 0.25};
  ap_system_def def;
  r->p.line = p;
  rs_line_3d_system(&r->p.line, &def);
  rs_line_lift(&r->p.line, 0.0, 1.0, 0.3, r->q0, r->v0);
  return from_system(r, &def);
}

static int line_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                        double *loop) {
  (void)t, (void)loop;
  inv[0] = rs_line_jacobi_3d(&r->p.line, q, v);
  return AP_OK;
}

static rs_hoffmann hoffmann_params(void) {
  rs_hoffmann p = {1.0, 0.8, 0.5, 0.4, 0, 0, 9.81, 2.0};
  p.I1 = p.m1 * p.a1 * p.a1 / 3, p.I2 = p.m2 * p.a2 * p.a2 / 3;
  return p;
}

static int hoffprim_setup(sysrun *r) {
  ap_system_def def;
  double q2[2] = {0.4, -0.3}, v2[2] = {0.5, 1.2};
  r->p.hoff = hoffmann_params();
  rs_hoffmann_primitive_system(&r->p.hoff, &def);
  rs_hoffmann_lift(&r->p.hoff, q2, v2, r->q0, r->v0);
  return from_system(r, &def);
}

/* The primitive system's own energy (its velocity rows do no work), and the position-level
 * connection that only the velocity rows hold: it drifts with the integration error. */
static int hoffprim_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                            double *loop) {
  const rs_hoffmann *p = &r->p.hoff;
  double M0 = p->I1 + p->m1 * p->a1 * p->a1;
  (void)t;
  inv[0] = 0.5 * (M0 * v[0] * v[0] + p->I2 * v[1] * v[1] + p->m2 * (v[2] * v[2] + v[3] * v[3])) -
           p->m1 * p->grav * p->a1 * cos(q[0]) - p->F * q[2] + p->m2 * p->grav * q[3];
  double ey = q[2] - (2 * p->a1 * sin(q[0]) + p->a2 * sin(q[1]));
  double ez = q[3] + (2 * p->a1 * cos(q[0]) + p->a2 * cos(q[1]));
  *loop = fmax(fabs(ey), fabs(ez));
  return AP_OK;
}

/* ---- body models: rolling disk, heavy top, rattleback, Hoffmann's loop -------------------- */

static int body_energy(sysrun *r, double t, const double *q, const double *v, double *E) {
  double T = 0.0, V = 0.0;
  r->d->t = t;
  memcpy(r->d->q, q, sizeof(double) * (size_t)ap_model_n(r->m));
  memcpy(r->d->v, v, sizeof(double) * (size_t)ap_model_k(r->m));
  int rc = ap_body_energy(r->m, r->d, &T, &V);
  *E = T + V;
  return rc;
}

static int disk_setup(sysrun *r) {
  const double m = 1.5, rad = 0.3;
  ap_builder *b = NULL;
  ap_builder_create("rolling disk", &b);
  ap_body_def d = ap_body_def_default();
  d.name = "disk", d.shape.kind = AP_SHAPE_DISK, d.shape.radius = rad;
  ap_body_def_uniform(&d, m);
  ap_builder_add_body(b, &d, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  ap_builder_add_effect(b, &e, NULL);
  if (compile(r, b) != AP_OK) return AP_ERR_ARG;
  /* lean 0.25 rad, lean rate 0.4 rad/s, w_a 1.2 rad/s, w_n 7 rad/s (tests/test_body_disk.c) */
  const double psi = 0.3, th = 0.25, thd = 0.4, wa = 1.2, wn = 7.0;
  double e1[3] = {cos(psi), sin(psi), 0}, left[3] = {-sin(psi), cos(psi), 0}, a[3], bu[3];
  double R[9];
  for (int i = 0; i < 3; i++) {
    a[i] = cos(th) * left[i] - sin(th) * (i == 2);
    bu[i] = sin(th) * left[i] + cos(th) * (i == 2);
    R[i] = e1[i], R[3 + i] = -bu[i], R[6 + i] = a[i];
  }
  r->q0[0] = 0.1, r->q0[1] = -0.2;
  ap_quat_from_matrix(R, r->q0 + 2);
  for (int i = 0; i < 3; i++) r->v0[2 + i] = -thd * e1[i] + wa * bu[i] + wn * a[i];
  int given[5] = {0, 0, 1, 1, 1};
  ap_data *tmp = NULL;
  ap_data_create(r->m, &tmp);
  int rc = ap_body_complete_speeds(r->m, tmp, r->q0, given, r->v0);
  ap_data_free(tmp);
  r->quat[0] = 2, r->nquat = 1;
  return rc;
}

static int energy_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                          double *loop) {
  (void)loop;
  return body_energy(r, t, q, v, &inv[0]);
}

static int top_setup(sysrun *r) {
  const double m = 0.5, l = 0.1, A0 = 2e-3, C = 3e-3, grav = 9.81;
  double p[5] = {m, l, A0, C, grav};
  memcpy(r->top, p, sizeof p);
  ap_builder *b = NULL;
  ap_builder_create("heavy top", &b);
  ap_body_def d = ap_body_def_default();
  d.name = "top", d.mass = m, d.com[2] = l;
  d.inertia[0] = d.inertia[4] = A0, d.inertia[8] = C;
  ap_builder_add_body(b, &d, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_BALL, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[2] = -grav;
  ap_builder_add_effect(b, &e, NULL);
  if (compile(r, b) != AP_OK) return AP_ERR_ARG;
  double ex[3] = {1, 0, 0}, R[9];
  ap_quat_from_axis_angle(ex, 0.5, r->q0);
  ap_quat_to_matrix(r->q0, R);
  for (int i = 0; i < 3; i++) r->v0[i] = 50.0 * R[6 + i] + (i == 2) + 0.3 * (i == 0);
  r->quat[0] = 0, r->nquat = 1;
  return AP_OK;
}

/* Energy (the engine's), L_z about the pivot and the spin w . a (tests/test_body_top.c). */
static int top_measure(sysrun *r, double t, const double *q, const double *w, double *inv,
                       double *loop) {
  const double m = r->top[0], l = r->top[1], A0 = r->top[2], C = r->top[3];
  double R[9], a[3], c[3], Iw[3];
  (void)loop;
  ap_quat_to_matrix(q, R);
  for (int i = 0; i < 3; i++) a[i] = R[6 + i], c[i] = l * a[i];
  double aw = a[0] * w[0] + a[1] * w[1] + a[2] * w[2];
  for (int i = 0; i < 3; i++) Iw[i] = A0 * w[i] + (C - A0) * aw * a[i];
  double vc[3] = {w[1] * c[2] - w[2] * c[1], w[2] * c[0] - w[0] * c[2], w[0] * c[1] - w[1] * c[0]};
  inv[1] = Iw[2] + m * (c[0] * vc[1] - c[1] * vc[0]);
  inv[2] = aw;
  return body_energy(r, t, q, w, &inv[0]);
}

static int rattleback_setup(sysrun *r) {
  ap_builder *b = NULL;
  ap_builder_create("rattleback", &b);
  ap_body_def d = ap_body_def_default();
  d.name = "rattleback", d.shape.kind = AP_SHAPE_ELLIPSOID;
  d.shape.semi_axes[0] = 0.2, d.shape.semi_axes[1] = 0.03, d.shape.semi_axes[2] = 0.02;
  ap_body_def_uniform(&d, 1.0);
  double c = cos(0.1), s = sin(0.1), I1 = d.inertia[0], I2 = d.inertia[4];
  d.inertia[0] = c * c * I1 + s * s * I2, d.inertia[4] = s * s * I1 + c * c * I2;
  d.inertia[1] = d.inertia[3] = c * s * (I1 - I2);
  d.com[2] = -0.01;
  ap_builder_add_body(b, &d, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def con = ap_constraint_def_default();
  con.name = "roll", con.body = 0;
  ap_builder_add_constraint(b, &con, NULL);
  ap_effect_def e = ap_effect_def_default();
  ap_builder_add_effect(b, &e, NULL);
  if (compile(r, b) != AP_OK) return AP_ERR_ARG;
  double q0[6] = {0, 0, 1, 0, 0, 0}, v0[5] = {0, 0, 0.0, 0.02, -5.0};
  memcpy(r->q0, q0, sizeof q0), memcpy(r->v0, v0, sizeof v0);
  int given[5] = {0, 0, 1, 1, 1};
  ap_data *tmp = NULL;
  ap_data_create(r->m, &tmp);
  int rc = ap_body_complete_speeds(r->m, tmp, r->q0, given, r->v0);
  ap_data_free(tmp);
  r->quat[0] = 2, r->nquat = 1;
  return rc;
}

/* Hoffmann's second example (tests/test_body_rebuild.c): two rods on revolutes, the lower
 * rod's end sliding on the vertical line y = 0.3 (a point-on-plane loop closure), a constant
 * horizontal force F at the lower rod's centre. Energy includes F's potential -F y. */
static int hoffloop_setup(sysrun *r) {
  rs_hoffmann p = hoffmann_params();
  r->p.hoff = p;
  ap_builder *b = NULL;
  ap_builder_create("Hoffmann sliding", &b);
  int id[2];
  const char *names[2] = {"upper", "lower"};
  const double mass[2] = {p.m1, p.m2}, comz[2] = {-p.a1, 0.0}, I[2] = {p.I1, p.I2};
  for (int i = 0; i < 2; i++) {
    ap_body_def d = ap_body_def_default();
    d.name = names[i], d.mass = mass[i], d.com[2] = comz[i];
    d.inertia[0] = d.inertia[4] = I[i], d.inertia[8] = 1e-3 * I[i];
    ap_builder_add_body(b, &d, &id[i]);
  }
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_REVOLUTE, j.child = id[0], j.axis[0] = 1.0, j.axis[2] = 0.0;
  ap_builder_add_joint(b, &j, NULL);
  j.name = "hinge", j.parent = id[0], j.child = id[1];
  j.parent_frame.pos[2] = -2 * p.a1, j.child_frame.pos[2] = p.a2;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "slider", c.kind = AP_CON_POINT_ON_PLANE, c.body = id[1], c.body2 = AP_GROUND;
  c.point[2] = -p.a2, c.point2[1] = 0.3;
  ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[2] = -p.grav;
  ap_builder_add_effect(b, &e, NULL);
  e = ap_effect_def_default();
  e.name = "F", e.kind = AP_EFFECT_APPLIED, e.body = id[1], e.force[1] = p.F;
  ap_builder_add_effect(b, &e, NULL);
  if (compile(r, b) != AP_OK) return AP_ERR_ARG;
  ap_data *tmp = NULL;
  ap_data_create(r->m, &tmp);
  r->q0[0] = 0.5, r->q0[1] = -0.5, r->v0[0] = 1.0, r->v0[1] = 0.0;
  int given[2] = {1, 0};
  int rc = ap_body_project_q(r->m, tmp, r->q0, NULL);
  if (rc == AP_OK) rc = ap_body_complete_speeds(r->m, tmp, r->q0, given, r->v0);
  ap_data_free(tmp);
  return rc;
}

static int hoffloop_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                            double *loop) {
  const rs_hoffmann *p = &r->p.hoff;
  int rc = body_energy(r, t, q, v, &inv[0]);
  inv[0] -= p->F * (2 * p->a1 * sin(q[0]) + p->a2 * sin(q[0] + q[1]));
  if (rc == AP_OK) rc = ap_body_loop_residual(r->m, r->d, loop);
  return rc;
}

/* A uniform ball rolling straight while it spins at 1000 rad/s about the vertical (bodysys.h,
 * Chaplygin's ball with three equal moments): every speed is constant and the centre moves on
 * a straight line. Projected mode used to rebuild v from the basis after every step, which
 * moved a v already on the constraints by its round-off: measured, max |v - v0| 2.7e-12 in
 * projected mode against 1.1e-13 in minimal mode over 4 s (1.1e5 steps, rtol 1e-11). */
static int ball_setup(sysrun *r) {
  const double a = 0.1, I0 = 0.4 * a * a, I[3] = {I0, I0, I0}, p[4] = {1, 0, 0, 0};
  const double w[3] = {-5.0, 10.0, 1000.0};
  r->m = bs_chaplygin_ball_model(1.0, a, I);
  if (!r->m) return AP_ERR_ARG;
  r->quat[0] = 2, r->nquat = 1;
  return bs_chaplygin_ball_state(r->m, NULL, p, w, r->q0, r->v0);
}

static int ball_measure(sysrun *r, double t, const double *q, const double *v, double *inv,
                        double *loop) {
  (void)loop;
  double dv = 0.0;
  for (int i = 0; i < 5; i++) dv = fmax(dv, fabs(v[i] - r->v0[i]));
  inv[1] = dv;   /* drift against 0: inv0[1] = 0 */
  inv[2] = fmax(fabs(q[0] - r->q0[0] - r->v0[0] * t), fabs(q[1] - r->q0[1] - r->v0[1] * t));
  return body_energy(r, t, q, v, &inv[0]);
}

/* ---- the table of runs ------------------------------------------------------------------- */

const drift_sys drift_systems[] = {
    {"skate", "math", M_ALL, "dopri5", 1e-8, 4000.0, 560.0, 0.0, 100000, 0, 1, {"energy"},
     {1.0}, skate_setup, skate_measure},
    {"sleigh", "math", M_ALL, "dopri5", 1e-8, 100.0, 100.0, 1e-3, 100000, 0, 1, {"energy"},
     {1e-3}, sleigh_setup, sleigh_measure},
    {"turntable", "math", M_ALL, "dopri5", 1e-8, 100.0, 100.0, 1e-3, 100000, 0, 2,
     {"c", "w_z"}, {0, 0}, table_setup, table_measure},
    {"rotating_line", "math", M_ALL, "dopri5", 1e-8, 10.0, 10.0, 1e-4, 100000, 0, 1,
     {"jacobi"}, {1.0}, line_setup, line_measure},
    {"hoffmann_primitive", "math", M_ALL, "dopri5", 1e-8, 1200.0, 180.0, 0.0, 100000, 1, 1,
     {"energy"}, {1.0}, hoffprim_setup, hoffprim_measure},
    {"rolling_disk", "disk", M_ALL, "dopri5", 1e-8, 1700.0, 340.0, 0.0, 100000, 0, 1,
     {"energy"}, {1.0}, disk_setup, energy_measure},
    {"heavy_top", "top", M_MIN | M_DAE, "dopri5", 1e-8, 250.0, 80.0, 0.0, 100000, 0, 3,
     {"energy", "L_z", "spin"}, {1.0, 1e-3, 1.0}, top_setup, top_measure},
    {"rattleback", "rattleback", M_ALL, "dopri5", 1e-8, 220.0, 45.0, 0.0, 100000, 0, 1,
     {"energy"}, {1.0}, rattleback_setup, energy_measure},
    {"hoffmann_loop", "hoffmann", M_ALL, "dopri5", 1e-8, 1550.0, 420.0, 0.0, 100000, 1, 1,
     {"energy"}, {1.0}, hoffloop_setup, hoffloop_measure},
    {"sleigh_long", "slow_sleigh", M_ALL, "dopri5", 1e-8, 1000.0, 1000.0, 1e-3, 1000000, 0, 1,
     {"energy"}, {1e-3}, sleigh_setup, sleigh_measure},
    {"rolling_disk_long", "slow_disk", M_ALL, "dopri5", 1e-8, 17000.0, 3300.0, 0.0, 1000000,
     0, 1, {"energy"}, {1.0}, disk_setup, energy_measure},
    {"spinning_ball", "ball", M_ALL, "dopri5", 1e-11, 4.0, 1.5, 0.0, 100000, 0, 3,
     {"energy", "speed", "track"}, {1.0, 0.0, 0.0}, ball_setup, ball_measure},
};
const int drift_nsys = (int)(sizeof drift_systems / sizeof drift_systems[0]);

