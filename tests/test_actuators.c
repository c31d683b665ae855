/* test_actuators: joint forces, motors and functions of the state (body.h AP_EFFECT_JOINT_FORCE,
 * AP_EFFECT_MOTOR, ap_state_fn), against closed forms and exact invariants:
 *
 *   rate motor     flywheel (inertia I) on a revolute joint, tau = kd (w* - w): unsaturated
 *                  w = w* + (w0 - w*) exp(-t kd / I); saturated at M: the ramp w0 + M t / I
 *                  until kd (w* - w) = M, then the exponential from there
 *   angle motor    tau = kp (s - a) + kd (s' - a'): a damped oscillator about s, closed form
 *                  of the underdamped second-order system; with a ramp set-point s = c t the
 *                  error e = s - a obeys the same homogeneous equation (feed-forward of s')
 *   state spring   tau = -k a from a state function reading the joint angle: a = a0 cos(W t)
 *                  + (a0' / W) sin(W t), W = sqrt(k / I)
 *   prismatic      a vertical slider under gravity with the state force F = -k x - c x':
 *                  damped oscillation about x_e = -m g / k
 *   energy         a rolling disk carrying a coaxial rotor on a revolute joint, driven by a
 *                  joint torque between them: the change of energy equals the work of the
 *                  torque on the relative rate, exactly (constant torque: tau (phi1 - phi0);
 *                  state spring: the spring's potential), and by quadrature for a rate motor;
 *                  in minimal, projected and DAE modes
 *   partials       ap_body_actuator_partials against central differences
 *   errors         bad definitions are refused by ap_builder_compile with the element named
 *
 * Tolerances: every run uses rtol = RTOL, atol = ATOL; the global error of a well-damped or
 * oscillating scalar system over a few time constants or periods stays below 100 rtol times its
 * scale (measured errors are printed next to each check). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"

#define RTOL 1e-10
#define ATOL 1e-12
#define TOL_FACTOR 100.0
#define PI 3.14159265358979323846

/* ---- a flywheel on a revolute joint (z axis), inertia I about it ---------------------------- */

typedef struct wheel_opts {
  ap_effect_def eff;       /* the effect under test (joint 0, speed 0 set here) */
  double I;
  int prismatic;           /* a slider of mass 1 along z instead, with gravity */
  int drive;               /* drive the joint (for the error tests) */
} wheel_opts;

static int drive_fn(double t, double f[3], void *user) {
  (void)user;
  f[0] = t, f[1] = 1.0, f[2] = 0.0;
  return 0;
}

/* Compile; on failure return NULL and copy the builder's message. */
static ap_model *wheel_model(const wheel_opts *o, char *msg, size_t len) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("wheel", &b) == AP_OK);
  ap_body_def w = ap_body_def_default();
  w.name = "wheel", w.mass = 1.0;
  w.inertia[0] = w.inertia[4] = 0.6 * o->I, w.inertia[8] = o->I;
  ap_builder_add_body(b, &w, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.name = "hinge", j.kind = o->prismatic ? AP_JOINT_PRISMATIC : AP_JOINT_REVOLUTE, j.child = 0;
  if (o->drive) j.drive[0] = drive_fn;
  ap_builder_add_joint(b, &j, NULL);
  if (o->drive) {   /* a second, free wheel so that the model keeps a degree of freedom */
    w.name = "other";
    ap_builder_add_body(b, &w, NULL);
    j = ap_joint_def_default();
    j.name = "other", j.kind = AP_JOINT_REVOLUTE, j.child = 1;
    ap_builder_add_joint(b, &j, NULL);
  }
  if (o->prismatic) {
    ap_effect_def g = ap_effect_def_default();
    ap_builder_add_effect(b, &g, NULL);
  }
  ap_effect_def e = o->eff;
  e.joint = 0;
  ap_builder_add_effect(b, &e, NULL);
  ap_model *m = NULL;
  if (ap_builder_compile(b, &m) != AP_OK && msg) snprintf(msg, len, "%s", ap_builder_message(b));
  ap_builder_free(b);
  return m;
}

static ap_sim *start(const ap_model *m, ap_mode mode, const double *q0, const double *v0) {
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = mode, sd.method = "dopri5", sd.rtol = RTOL, sd.atol = ATOL;
  ap_sim *s = NULL;
  char msg[512] = "";
  int rc = ap_sim_create(m, &sd, 0.0, q0, v0, &s, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "ap_sim_create: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return s;
}

static int advance(ap_sim *s, double t) {
  int rc = ap_sim_advance(s, t);
  if (rc != AP_OK) fprintf(stderr, "advance to %g: %s\n", t, ap_sim_message(s));
  AP_CHECK_EQ_INT(rc, AP_OK);
  return rc;
}

/* Run a one-speed model from (a0, w0) and compare a(t), a'(t) with a closed form at 40
 * times in (0, T]; returns the largest errors. */
typedef void (*closed_fn)(double t, const void *p, double *a, double *w);

static void compare(const ap_model *m, double a0, double w0, double T, closed_fn f,
                    const void *p, double *ea, double *ew) {
  double q0[1] = {a0}, v0[1] = {w0};
  ap_sim *s = start(m, AP_MODE_MINIMAL, q0, v0);
  *ea = *ew = 0.0;
  for (int i = 1; s && i <= 40; i++) {
    double t = T * i / 40.0, a, w;
    if (advance(s, t) != AP_OK) break;
    f(t, p, &a, &w);
    *ea = fmax(*ea, fabs(ap_sim_q(s)[0] - a));
    *ew = fmax(*ew, fabs(ap_sim_v(s)[0] - w));
  }
  ap_sim_free(s);
}

/* ---- 1. rate motor --------------------------------------------------------------------------- */

typedef struct rate_p { double I, kd, M, ws, w0; } rate_p;

/* w(t) and a(t) = int w, a(0) = 0: ramp at M / I while kd (w* - w) > M, then exponential. */
static void rate_closed(double t, const void *pv, double *a, double *w) {
  const rate_p *p = pv;
  double tau = p->I / p->kd, wsat = p->ws - p->M / p->kd, t1 = 0.0, a1 = 0.0, w1 = p->w0;
  if (p->kd * (p->ws - p->w0) > p->M) {
    t1 = (wsat - p->w0) * p->I / p->M;
    if (t <= t1) {
      *w = p->w0 + p->M / p->I * t;
      *a = p->w0 * t + 0.5 * p->M / p->I * t * t;
      return;
    }
    a1 = p->w0 * t1 + 0.5 * p->M / p->I * t1 * t1, w1 = wsat;
  }
  double e = exp(-(t - t1) / tau);
  *w = p->ws + (w1 - p->ws) * e;
  *a = a1 + p->ws * (t - t1) + (w1 - p->ws) * tau * (1.0 - e);
}

static void test_rate_motor(void) {
  for (int saturate = 0; saturate < 2; saturate++) {
    rate_p p = {0.05, 0.2, saturate ? 0.5 : HUGE_VAL, 12.0, -3.0};
    wheel_opts o = {ap_effect_def_default(), p.I, 0, 0};
    o.eff.name = "motor", o.eff.kind = AP_EFFECT_MOTOR, o.eff.motor = AP_MOTOR_RATE;
    o.eff.value = p.ws, o.eff.kd = p.kd, o.eff.max_effort = p.M;
    char msg[512] = "";
    ap_model *m = wheel_model(&o, msg, sizeof msg);
    AP_CHECK(m != NULL);
    if (!m) {
      fprintf(stderr, "%s\n", msg);
      continue;
    }
    double T = 6.0 * p.I / p.kd + (saturate ? (p.ws - p.M / p.kd - p.w0) * p.I / p.M : 0.0);
    double ea, ew, ws = fabs(p.ws) + fabs(p.w0);
    compare(m, 0.0, p.w0, T, rate_closed, &p, &ea, &ew);
    printf("rate motor %s: time constant I/kd = %.3g s, T = %.3g s: max |w - closed| %.2e "
           "rad/s, |a - closed| %.2e rad\n", saturate ? "saturated at 0.5 N m" : "unsaturated",
           p.I / p.kd, T, ew, ea);
    AP_CHECK_LE(ew, TOL_FACTOR * RTOL * ws);
    AP_CHECK_LE(ea, TOL_FACTOR * RTOL * ws * T);
    ap_model_free(m);
  }
}

/* ---- 2. angle motor ------------------------------------------------------------------------- */

typedef struct osc_p { double I, k, c, a_eq, a0, w0, ramp; } osc_p;

/* I e'' + c e' + k e = 0 with e = a - a_eq - ramp t (underdamped): a(t), a'(t). */
static void osc_closed(double t, const void *pv, double *a, double *w) {
  const osc_p *p = pv;
  double W0 = sqrt(p->k / p->I), z = p->c / (2.0 * sqrt(p->k * p->I)), s = z * W0;
  double Wd = W0 * sqrt(1.0 - z * z), e0 = p->a0 - p->a_eq, de0 = p->w0 - p->ramp;
  double A = e0, B = (de0 + s * e0) / Wd, ex = exp(-s * t), C = cos(Wd * t), S = sin(Wd * t);
  double e = ex * (A * C + B * S), de = ex * ((-s * A + Wd * B) * C + (-s * B - Wd * A) * S);
  *a = p->a_eq + p->ramp * t + e;
  *w = p->ramp + de;
}

static int ramp_fn(double t, double f[3], void *user) {
  double c = *(const double *)user;
  f[0] = c * t, f[1] = c, f[2] = 0.0;
  return 0;
}

static void test_angle_motor(void) {
  double c = 1.5;
  for (int ramp = 0; ramp < 2; ramp++) {
    osc_p p = {0.05, 2.0, 0.06, ramp ? 0.0 : 0.8, 0.1, ramp ? 0.0 : -1.0, ramp ? c : 0.0};
    wheel_opts o = {ap_effect_def_default(), p.I, 0, 0};
    o.eff.name = "servo", o.eff.kind = AP_EFFECT_MOTOR, o.eff.motor = AP_MOTOR_ANGLE;
    o.eff.kp = p.k, o.eff.kd = p.c, o.eff.value = p.a_eq;
    if (ramp) o.eff.value_fn = ramp_fn, o.eff.user = &c;
    ap_model *m = wheel_model(&o, NULL, 0);
    AP_CHECK(m != NULL);
    if (!m) continue;
    double W0 = sqrt(p.k / p.I), z = p.c / (2.0 * sqrt(p.k * p.I)), T = 5.0 * 2 * PI / W0;
    double ea, ew, scale = fabs(p.a0 - p.a_eq) * W0 + fabs(p.w0) + c;
    compare(m, p.a0, p.w0, T, osc_closed, &p, &ea, &ew);
    printf("angle motor%s: W0 = %.4g rad/s, damping ratio %.3g, 5 periods: max |a - closed| "
           "%.2e rad, |a' - closed| %.2e rad/s\n", ramp ? " (ramp set-point, fed forward)" : "",
           W0, z, ea, ew);
    AP_CHECK_LE(ea, TOL_FACTOR * RTOL * scale * T);
    AP_CHECK_LE(ew, TOL_FACTOR * RTOL * scale * W0 * T);
    ap_model_free(m);
  }
}

/* ---- 3. torsional spring as a function of the state --------------------------------------- */

typedef struct spring_user { double k, c; long calls, partial_calls; } spring_user;

/* F = -k x0 - c x1 (x0 a coordinate, x1 its speed; c = 0 when only x0 is declared). */
static int spring_fn(const ap_state_args *a, double *f, double *df, void *user) {
  spring_user *u = user;
  u->calls++;
  *f = -u->k * a->x[0] - (a->nx > 1 ? u->c * a->x[1] : 0.0);
  if (df) {
    u->partial_calls++;
    df[0] = 0.0, df[1] = -u->k;
    if (a->nx > 1) df[2] = -u->c;
  }
  return 0;
}

static void spring_closed(double t, const void *pv, double *a, double *w) {
  const osc_p *p = pv;   /* undamped: c = 0 */
  double W = sqrt(p->k / p->I);
  *a = p->a0 * cos(W * t) + p->w0 / W * sin(W * t);
  *w = -p->a0 * W * sin(W * t) + p->w0 * cos(W * t);
}

static void test_state_spring(void) {
  osc_p p = {0.05, 3.0, 0.0, 0.0, 0.4, 2.0, 0.0};
  spring_user u = {p.k, 0.0, 0, 0};
  wheel_opts o = {ap_effect_def_default(), p.I, 0, 0};
  o.eff.name = "spring", o.eff.kind = AP_EFFECT_JOINT_FORCE, o.eff.state_fn = spring_fn;
  o.eff.user = &u, o.eff.ninputs = 1;
  o.eff.inputs[0].joint = 0, o.eff.inputs[0].speed = 0, o.eff.inputs[0].index = 0;
  ap_model *m = wheel_model(&o, NULL, 0);
  AP_CHECK(m != NULL);
  if (!m) return;
  double W = sqrt(p.k / p.I), T = 5.0 * 2 * PI / W, ea, ew;
  double scale = fabs(p.a0) * W + fabs(p.w0);
  compare(m, p.a0, p.w0, T, spring_closed, &p, &ea, &ew);
  printf("state spring tau = -k angle: W = sqrt(k/I) = %.4g rad/s, 5 periods: max |a - closed| "
         "%.2e rad, |a' - closed| %.2e rad/s (%ld calls, %ld with partials)\n", W, ea, ew,
         u.calls, u.partial_calls);
  AP_CHECK_LE(ea, TOL_FACTOR * RTOL * scale * T);
  AP_CHECK_LE(ew, TOL_FACTOR * RTOL * scale * W * T);
  AP_CHECK(u.calls > 100);
  AP_CHECK_EQ_INT(u.partial_calls, 0);   /* ordinary evaluations ask for no partials */
  ap_model_free(m);
}

/* ---- 4. prismatic joint with a force of the state ------------------------------------------ */

static void test_prismatic(void) {
  /* m x'' = -m g - k x - c x': e = x - x_e with x_e = -m g / k is the oscillator of osc_closed */
  double g = 9.81, k = 40.0, c = 0.8;
  spring_user u = {k, c, 0, 0};
  wheel_opts o = {ap_effect_def_default(), 0.05, 1, 0};
  o.eff.name = "suspension", o.eff.kind = AP_EFFECT_JOINT_FORCE, o.eff.state_fn = spring_fn;
  o.eff.user = &u, o.eff.ninputs = 2;
  o.eff.inputs[0].joint = 0, o.eff.inputs[0].speed = 0, o.eff.inputs[0].index = 0;
  o.eff.inputs[1].joint = 0, o.eff.inputs[1].speed = 1, o.eff.inputs[1].index = 0;
  ap_model *m = wheel_model(&o, NULL, 0);
  AP_CHECK(m != NULL);
  if (!m) return;
  osc_p p = {1.0, k, c, -g / k, 0.3, 0.0, 0.0};
  double W0 = sqrt(k), T = 5.0 * 2 * PI / W0, ea, ew;
  double scale = fabs(p.a0 - p.a_eq) * W0;
  compare(m, p.a0, p.w0, T, osc_closed, &p, &ea, &ew);
  printf("prismatic with F = -k x - c x' under gravity: equilibrium %.4g m, 5 periods: max "
         "|x - closed| %.2e m, |x' - closed| %.2e m/s\n", p.a_eq, ea, ew);
  AP_CHECK_LE(ea, TOL_FACTOR * RTOL * scale * T);
  AP_CHECK_LE(ew, TOL_FACTOR * RTOL * scale * W0 * T);
  ap_model_free(m);
}

/* ---- 5. energy balance on a rolling disk with a rotor -------------------------------------- */

/* Disk (plane contact, rolling) carrying a coaxial rotor on a revolute joint about the disk
 * axis; gravity; the effect e acts on the rotor joint (joint 1). */
static ap_model *disk_rotor(ap_effect_def e) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("disk with rotor", &b) == AP_OK);
  ap_body_def disk = ap_body_def_default(), rotor = ap_body_def_default();
  disk.name = "disk", disk.shape.kind = AP_SHAPE_DISK, disk.shape.radius = 0.3;
  AP_CHECK(ap_body_def_uniform(&disk, 1.5) == AP_OK);
  rotor.name = "rotor", rotor.mass = 0.5;
  rotor.inertia[0] = rotor.inertia[4] = 0.006, rotor.inertia[8] = 0.01;
  ap_builder_add_body(b, &disk, NULL);
  ap_builder_add_body(b, &rotor, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.name = "disk", j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  ap_builder_add_joint(b, &j, NULL);
  j = ap_joint_def_default();
  j.name = "spindle", j.kind = AP_JOINT_REVOLUTE, j.parent = 0, j.child = 1;
  ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def r = ap_constraint_def_default();
  r.name = "roll", r.body = 0;
  ap_builder_add_constraint(b, &r, NULL);
  ap_effect_def g = ap_effect_def_default();
  ap_builder_add_effect(b, &g, NULL);
  e.joint = 1;
  ap_builder_add_effect(b, &e, NULL);
  ap_model *m = NULL;
  if (ap_builder_compile(b, &m) != AP_OK) fprintf(stderr, "%s\n", ap_builder_message(b));
  ap_builder_free(b);
  return m;
}

/* Leaning 0.25 rad from upright, rolling at spin 7 rad/s and turning at 1.2 rad/s; rotor at
 * rest relative to the disk. q = (x y qw qx qy qz phi), v = (vx vy wx wy wz phi'). */
static void disk_state(const ap_model *m, double q0[7], double v0[6]) {
  double ex[3] = {1, 0, 0}, a[3] = {0, cos(0.25), -sin(0.25)};
  int given[6] = {0, 0, 1, 1, 1, 1};
  memset(q0, 0, 7 * sizeof *q0);
  ap_quat_from_axis_angle(ex, -(1.5707963267948966 + 0.25), q0 + 2);
  v0[0] = v0[1] = 0.0, v0[5] = 0.0;
  v0[2] = 7.0 * a[0], v0[3] = 7.0 * a[1], v0[4] = 7.0 * a[2] + 1.2;
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  AP_CHECK(ap_body_complete_speeds(m, d, q0, given, v0) == AP_OK);
  ap_data_free(d);
}

static double energy(const ap_model *m, ap_data *d, double t, const double *q, const double *v) {
  double T = 0.0, V = 0.0;
  d->t = t;
  memcpy(d->q, q, (size_t)ap_model_n(m) * sizeof *q);
  memcpy(d->v, v, (size_t)ap_model_k(m) * sizeof *v);
  AP_CHECK(ap_body_energy(m, d, &T, &V) == AP_OK);
  return T + V;
}

typedef struct balance { double dE, W, quad_err, E0; } balance;

/* Run to T with N samples; W from the law: kind 0 constant tau (exact), 1 spring -k phi
 * (exact), 2 rate motor (Simpson on the samples, error estimated against half the samples). */
static balance run_balance(const ap_model *m, ap_mode mode, int kind, const ap_effect_def *e,
                           double T, int N) {
  balance r = {0, 0, 0, 0};
  double q0[7], v0[6];
  disk_state(m, q0, v0);
  if (kind == 1) q0[6] = 0.6;   /* the spring starts stretched */
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  ap_sim *s = start(m, mode, q0, v0);
  if (!s || !d) return ap_data_free(d), ap_sim_free(s), r;
  r.E0 = energy(m, d, 0.0, ap_sim_q(s), ap_sim_v(s));
  double *P = calloc((size_t)N + 1, sizeof *P);
  P[0] = e->kd * (e->value - v0[5]) * v0[5];
  for (int i = 1; i <= N; i++) {
    if (advance(s, T * i / N) != AP_OK) break;
    double w = ap_sim_v(s)[5];
    P[i] = e->kd * (e->value - w) * w;
  }
  double phi0 = q0[6], phi1 = ap_sim_q(s)[6];
  r.dE = energy(m, d, T, ap_sim_q(s), ap_sim_v(s)) - r.E0;
  if (kind == 0) r.W = e->value * (phi1 - phi0);
  if (kind == 1) r.W = -0.5 * ((spring_user *)e->user)->k * (phi1 * phi1 - phi0 * phi0);
  if (kind == 2) {
    double S1 = 0.0, S2 = 0.0, h = T / N;
    for (int i = 0; i <= N; i++) S1 += P[i] * (i == 0 || i == N ? 1 : i % 2 ? 4 : 2);
    for (int i = 0; i <= N; i += 2) S2 += P[i] * (i == 0 || i == N ? 1 : (i / 2) % 2 ? 4 : 2);
    r.W = S1 * h / 3.0, S2 *= 2 * h / 3.0;
    r.quad_err = fabs(r.W - S2) / 15.0;   /* Richardson: Simpson's error is O(h^4) */
  }
  free(P);
  ap_sim_free(s);
  ap_data_free(d);
  return r;
}

static void test_energy_balance(void) {
  static const char *const modes[] = {"minimal", "projected", "dae"};
  static const ap_mode mode_ids[] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
  spring_user u = {0.8, 0.0, 0, 0};
  for (int kind = 0; kind < 3; kind++) {
    ap_effect_def e = ap_effect_def_default();
    e.name = "torque", e.kind = AP_EFFECT_JOINT_FORCE, e.value = 0.05;
    if (kind == 1) {
      e.state_fn = spring_fn, e.user = &u, e.ninputs = 1;
      e.inputs[0].joint = 1, e.inputs[0].speed = 0, e.inputs[0].index = 0;
    }
    if (kind == 2) e.kind = AP_EFFECT_MOTOR, e.value = 20.0, e.kd = 0.004;
    ap_model *m = disk_rotor(e);
    AP_CHECK(m != NULL);
    if (!m) continue;
    for (int mi = 0; mi < 3; mi++) {
      if (kind > 0 && mi == 2) continue;   /* DAE: the constant torque suffices */
      balance r = run_balance(m, mode_ids[mi], kind, &e, 2.0, 2000);
      double tol = TOL_FACTOR * RTOL * r.E0 + 10.0 * r.quad_err;
      printf("energy balance, %s, %s: dE = %.10f J, work = %.10f J, |dE - W| = %.2e J "
             "(tolerance %.1e; E0 = %.4f J%s)\n",
             kind == 0 ? "constant torque 0.05 N m" : kind == 1 ? "state spring -0.8 phi from 0.6"
                                                                : "rate motor 20 rad/s",
             modes[mi], r.dE, r.W, fabs(r.dE - r.W), tol, r.E0,
             kind == 2 ? ", work by Simpson" : "");
      AP_CHECK(fabs(r.W) > 1e-3);
      AP_CHECK_LE(fabs(r.dE - r.W), tol);
    }
    ap_model_free(m);
  }
}

/* ---- 6. partial derivatives ----------------------------------------------------------------- */

static void fd_check(const ap_model *m, int effect, const char *label, int expect_zero) {
  ap_data *d = NULL;
  AP_CHECK(ap_data_create(m, &d) == AP_OK);
  int n = ap_model_n(m), k = ap_model_k(m), col = -1;
  double dq[8] = {0}, dv[8] = {0}, dt = 0, tau = 0, worst = 0.0, h = 1e-5;
  d->t = 0.7;
  for (int i = 0; i < n; i++) d->q[i] = 0.3 + 0.1 * i;
  for (int i = 0; i < k; i++) d->v[i] = -0.4 + 0.2 * i;
  AP_CHECK(ap_body_actuator_partials(m, d, effect, &col, &tau, dq, dv, &dt) == AP_OK);
  for (int w = 0; w < n + k + 1; w++) {
    double *x = w < n ? &d->q[w] : w < n + k ? &d->v[w - n] : &d->t, x0 = *x, tp, tm;
    *x = x0 + h;
    ap_body_actuator_partials(m, d, effect, NULL, &tp, NULL, NULL, NULL);
    *x = x0 - h;
    ap_body_actuator_partials(m, d, effect, NULL, &tm, NULL, NULL, NULL);
    *x = x0;
    double fd = (tp - tm) / (2 * h), an = w < n ? dq[w] : w < n + k ? dv[w - n] : dt;
    worst = fmax(worst, fabs(fd - an));
    if (expect_zero) AP_CHECK_EQ_INT(an != 0.0, 0);
  }
  printf("partials, %s: tau = %.6g on speed %d, max |exact - central difference| = %.1e\n",
         label, tau, col, worst);
  AP_CHECK_LE(worst, 1e-8);   /* central differences at h = 1e-5: O(h^2) plus rounding */
  ap_data_free(d);
}

static int sine_fn(double t, double f[3], void *user) {
  (void)user;
  f[0] = sin(2 * t), f[1] = 2 * cos(2 * t), f[2] = -4 * sin(2 * t);
  return 0;
}

static void test_partials(void) {
  spring_user u = {3.0, 0.7, 0, 0};
  wheel_opts o = {ap_effect_def_default(), 0.05, 0, 0};
  o.eff.name = "f", o.eff.kind = AP_EFFECT_JOINT_FORCE, o.eff.state_fn = spring_fn;
  o.eff.user = &u, o.eff.ninputs = 2;
  o.eff.inputs[1].speed = 1;
  ap_model *m = wheel_model(&o, NULL, 0);
  if (m) fd_check(m, 0, "joint force of the state", 0), ap_model_free(m);
  AP_CHECK(u.partial_calls > 0);
  o.eff.kind = AP_EFFECT_MOTOR, o.eff.motor = AP_MOTOR_ANGLE, o.eff.kp = 2.0, o.eff.kd = 0.3;
  m = wheel_model(&o, NULL, 0);
  if (m) fd_check(m, 0, "angle motor, set-point of the state", 0), ap_model_free(m);
  o.eff.state_fn = NULL, o.eff.ninputs = 0, o.eff.value_fn = sine_fn;
  m = wheel_model(&o, NULL, 0);
  if (m) fd_check(m, 0, "angle motor, set-point sin(2t) fed forward", 0), ap_model_free(m);
  o.eff.motor = AP_MOTOR_RATE, o.eff.kp = 0.0;
  m = wheel_model(&o, NULL, 0);
  if (m) fd_check(m, 0, "rate motor, set-point sin(2t)", 0), ap_model_free(m);
  o.eff.max_effort = 1e-3;
  m = wheel_model(&o, NULL, 0);
  if (m) fd_check(m, 0, "rate motor saturated", 1), ap_model_free(m);
}

/* ---- 7. errors --------------------------------------------------------------------------- */

static void expect_error(wheel_opts o, const char *label, const char *words) {
  char msg[512] = "";
  ap_model *m = wheel_model(&o, msg, sizeof msg);
  printf("refused (%s): %s\n", label, msg);
  AP_CHECK(m == NULL);
  AP_CHECK(strstr(msg, words) != NULL);
  ap_model_free(m);
}

static int failing_fn(const ap_state_args *a, double *f, double *df, void *user) {
  (void)df, (void)user;
  *f = a->t > 0.5 ? NAN : 0.0;
  return 0;
}

static void test_errors(void) {
  wheel_opts o = {ap_effect_def_default(), 0.05, 0, 0};
  o.eff.name = "motor", o.eff.kind = AP_EFFECT_MOTOR, o.eff.kd = 1.0;
  wheel_opts w = o;
  w.drive = 1;
  expect_error(w, "motor on a driven joint", "speed 'angle_dot' of joint 'hinge' is driven");
  w = o, w.eff.kd = 0.0;
  expect_error(w, "rate motor without kd", "needs kd > 0");
  w = o, w.eff.kp = 1.0;
  expect_error(w, "rate motor with kp", "kp must be 0");
  w = o, w.eff.max_effort = 0.0;
  expect_error(w, "no torque allowed", "max_effort 0 must be positive");
  w = o, w.eff.speed = 1;
  expect_error(w, "speed out of range", "has 1 speeds, not speed 1");
  w = o, w.eff.kind = AP_EFFECT_JOINT_FORCE, w.eff.ninputs = 1;
  expect_error(w, "inputs without a function", "no state_fn");
  w = o, w.eff.state_fn = failing_fn, w.eff.ninputs = 1, w.eff.inputs[0].index = 2;
  expect_error(w, "input out of range", "reads coordinate 2 of joint 'hinge', which has 1");
  w = o, w.eff.state_fn = failing_fn, w.eff.ninputs = 1, w.eff.inputs[0].joint = 4;
  expect_error(w, "input of a missing joint", "joint 4, which does not exist");

  /* a failing state function stops the run with its effect named */
  w = o, w.eff.kind = AP_EFFECT_JOINT_FORCE, w.eff.state_fn = failing_fn;
  ap_model *m = wheel_model(&w, NULL, 0);
  double q0[1] = {0}, v0[1] = {1};
  ap_sim *s = m ? start(m, AP_MODE_MINIMAL, q0, v0) : NULL;
  if (s) {
    int rc = ap_sim_advance(s, 1.0);
    printf("refused at run time: %s\n", ap_sim_message(s));
    AP_CHECK(rc != AP_OK);
    AP_CHECK(strstr(ap_sim_message(s), "effect 'motor': the state function gave a non-finite")
             != NULL);
  }
  ap_sim_free(s);
  ap_model_free(m);
}

int main(void) {
  test_rate_motor();
  test_angle_motor();
  test_state_spring();
  test_prismatic();
  test_energy_balance();
  test_partials();
  test_errors();
  return ap_check_finish("test_actuators");
}
