/* Terrain: rolling on a ground plane other than z = 0 (ap_ground_motion.normal, .offset;
 * docs/vehicles.md "Ground planes").
 *
 *  incline = turned gravity: a uniform ball (r = 0.1 m, m = 2 kg) on a free joint rolling on
 *    the plane n . p = d, n = Rx(a) e_z, a = 25 deg, d = 0.3 m, against the same ball on z = 0
 *    under the gravity turned by Rx(-a): the state mapped by p -> Q p + d n, R -> Q R, v -> Q v
 *    (Q = Rx(a)) is the same function, and RK4 at a fixed step is covariant under that linear
 *    map, so in projected mode the two runs agree to round-off (1e-12) over 2 s;
 *  closed form: on the incline the centre accelerates at 5/7 g sin(a) down the slope and keeps
 *    its speed across it: x(t) = x0 + v0 t, s(t) = (5/14) g sin(a) t^2 (dopri5, rtol 1e-11);
 *    the contact point stays on the plane (the gap to 1e-12 m); the contact force has
 *    F_n = m g cos(a) and friction 2/7 m g sin(a) up the slope;
 *  the gamma of the tilted contact against central differences of A v + a0 along the motion
 *    (a disk leaning and turning on the incline), with and without the surface term;
 *  the touchdown impact (ap_impact): a spinning sphere dropped on the plane, v+ against the
 *    closed form of a sticking plastic impact and Carnot's energy loss;
 *  refusals: a tilted plane under a plane-contact joint or with a moving ground. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "fdcheck.h"

#define PI RS_PI_
#define G 9.81

static const double ALPHA = 25 * PI / 180, OFFSET = 0.3, RADIUS = 0.1, MASS = 2.0;

/* A ball (shape kind) on a free joint rolling on the plane n . p = d under gravity g. */
static ap_model *ball(ap_shape_kind shape, const double *n, double d, const double *g,
                      char *msg) {
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll";
  if (n) memcpy(c.ground.normal, n, sizeof c.ground.normal);
  c.ground.offset = d;
  msg[0] = '\0';   /* a failure is printed by bodysys */
  return bs_free_ball(shape, RADIUS, MASS, &c, g);
}

/* Q = Rx(a): columns e_x, (0, cos a, sin a), n = (0, -sin a, cos a). */
static void rot_x(double a, double *Q) {
  double R[9] = {1, 0, 0, 0, cos(a), sin(a), 0, -sin(a), cos(a)};
  memcpy(Q, R, sizeof R);
}

static void mulv(const double *Q, const double *x, double *y) {
  for (int i = 0; i < 3; i++) y[i] = Q[i] * x[0] + Q[i + 3] * x[1] + Q[i + 6] * x[2];
}

/* Free-joint state (x y z qw qx qy qz; vx vy vz wx wy wz) mapped by p -> Q p + d n. */
static void map_state(const double *Q, double d, const double *q, const double *v, double *q2,
                      double *v2) {
  double qQ[4], ax[3] = {1, 0, 0};
  ap_quat_from_axis_angle(ax, ALPHA, qQ);
  mulv(Q, q, q2);
  for (int i = 0; i < 3; i++) q2[i] += d * Q[6 + i];
  ap_quat_mul(qQ, q + 3, q2 + 3);
  mulv(Q, v, v2);
  mulv(Q, v + 3, v2 + 3);
}

static ap_sim *start(const ap_model *m, const ap_sim_def *def, const double *q, const double *v) {
  ap_sim *s = NULL;
  char msg[1024] = "";
  int rc = ap_sim_create(m, def, 0.0, q, v, &s, msg, sizeof msg);
  if (rc != AP_OK) printf("  sim_create: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return s;
}

/* The level ball's initial state: centre at (0, 0, r), turned, rolling at v0 = (0.7, -0.4) with
 * a spin 3 rad/s about the normal. */
static void level_initial(double *q, double *v) {
  double ax[3] = {0.3, -0.5, 0.8};
  memset(q, 0, 7 * sizeof *q), memset(v, 0, 6 * sizeof *v);
  q[2] = RADIUS;
  ap_quat_from_axis_angle(ax, 0.9, q + 3);
  v[0] = 0.7, v[1] = -0.4;
  v[3] = 0.4 / RADIUS, v[4] = 0.7 / RADIUS, v[5] = 3.0;   /* v = w x (r e_z) */
}

static void test_turned_gravity(void) {
  double Q[9], n[3], g_level[3], g_world[3] = {0, 0, -G}, QT[9];
  char m1[512] = "", m2[512] = "";
  rot_x(ALPHA, Q);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) QT[i + 3 * j] = Q[j + 3 * i];
  mulv(Q, (double[3]){0, 0, 1}, n);
  mulv(QT, g_world, g_level);
  ap_model *ml = ball(AP_SHAPE_SPHERE, NULL, 0.0, g_level, m1);
  ap_model *mi = ball(AP_SHAPE_SPHERE, n, OFFSET, g_world, m2);
  AP_CHECK(ml && mi);
  if (!ml || !mi) return (void)printf("  %s %s\n", m1, m2);
  double ql[7], vl[6], qi[7], vi[6];
  level_initial(ql, vl);
  map_state(Q, OFFSET, ql, vl, qi, vi);
  ap_sim_def def = ap_sim_def_default();
  def.mode = AP_MODE_PROJECTED, def.method = "rk4", def.h_fixed = 1e-3;
  ap_sim *sl = start(ml, &def, ql, vl), *si = start(mi, &def, qi, vi);
  double worst = 0.0;
  for (int k = 1; k <= 20 && sl && si; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(sl, 0.1 * k), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(si, 0.1 * k), AP_OK);
    double q2[7], v2[6];
    map_state(Q, OFFSET, ap_sim_q(sl), ap_sim_v(sl), q2, v2);
    for (int i = 0; i < 7; i++) worst = fmax(worst, fabs(q2[i] - ap_sim_q(si)[i]));
    for (int i = 0; i < 6; i++) worst = fmax(worst, fabs(v2[i] - ap_sim_v(si)[i]) * 0.1);
  }
  printf("  ball on the %.0f deg incline vs level under turned gravity (projected, rk4, h = "
         "1e-3, 2 s): largest difference %.2e\n", ALPHA * 180 / PI, worst);
  AP_CHECK_LE(worst, 1e-12);
  ap_sim_free(sl), ap_sim_free(si);
  ap_model_free(ml), ap_model_free(mi);
}

/* The closed form of the ball rolling on the incline, and its contact force. */
static void test_incline_closed_form(void) {
  double Q[9], n[3], g[3] = {0, 0, -G};
  char msg[512] = "";
  rot_x(ALPHA, Q);
  mulv(Q, (double[3]){0, 0, 1}, n);
  ap_model *m = ball(AP_SHAPE_SPHERE, n, OFFSET, g, msg);
  AP_CHECK(m != NULL);
  if (!m) return (void)printf("  %s\n", msg);
  double ql[7], vl[6], q[7], v[6];
  level_initial(ql, vl);
  map_state(Q, OFFSET, ql, vl, q, v);
  ap_sim_def def = ap_sim_def_default();
  def.rtol = 1e-11, def.atol = 1e-13;
  ap_sim *s = start(m, &def, q, v);
  double err = 0.0, gap = 0.0, ferr = 0.0, T = 2.0, up[3] = {0, cos(ALPHA), sin(ALPHA)};
  for (int k = 1; k <= 20 && s; k++) {
    double t = 0.1 * k;
    AP_CHECK_EQ_INT(ap_sim_advance(s, t), AP_OK);
    const double *x = ap_sim_q(s);
    double s_down = 5.0 / 14.0 * G * sin(ALPHA) * t * t;   /* along -up */
    double ex[3];
    for (int i = 0; i < 3; i++)
      ex[i] = q[i] + (vl[0] * Q[i] + vl[1] * Q[i + 3]) * t - s_down * up[i];
    for (int i = 0; i < 3; i++) err = fmax(err, fabs(x[i] - ex[i]));
    gap = fmax(gap, fabs(n[0] * x[0] + n[1] * x[1] + n[2] * x[2] - OFFSET - RADIUS));
    const double *lambda = NULL;
    ap_contact_force f;
    AP_CHECK_EQ_INT(ap_sim_reactions(s, &lambda), AP_OK);
    AP_CHECK_EQ_INT(ap_body_contact_force(m, ap_sim_data(s), lambda, 0, &f), AP_OK);
    double fe[3];
    for (int i = 0; i < 3; i++)
      fe[i] = MASS * G * cos(ALPHA) * n[i] + 2.0 / 7.0 * MASS * G * sin(ALPHA) * up[i];
    for (int i = 0; i < 3; i++) ferr = fmax(ferr, fabs(f.force[i] - fe[i]));
    ferr = fmax(ferr, fabs(f.normal - MASS * G * cos(ALPHA)));
  }
  printf("  ball on the incline over %.0f s: centre %.2e m from the closed form, gap %.2e m, "
         "contact force %.2e N from m g cos a n + 2/7 m g sin a up\n", T, err, gap, ferr);
  AP_CHECK_LE(err, 1e-9);
  AP_CHECK_LE(gap, 1e-12);
  AP_CHECK_LE(ferr, 1e-9);
  ap_sim_free(s);
  ap_model_free(m);
}

/* gamma of the tilted contact (rolling and the wheel knife edge, sphere, ellipsoid, disk,
 * torus on a free joint) against d/ds (A v + a0) along the motion; without the term of the
 * contact point moving over the body surface the check fails. */
static void test_fd_incline(void) {
  double n[3] = {0.3, -0.4, 0.8};
  printf("  tilted-plane contacts, finite differences along the motion:\n");
  for (int knife = 0; knife < 2; knife++)
    for (int kind = knife ? AP_SHAPE_DISK : AP_SHAPE_SPHERE; kind <= AP_SHAPE_TORUS; kind++) {
      ap_constraint_def c = ap_constraint_def_default();
      c.name = "contact", c.no_spin = !knife;
      if (knife) c.kind = AP_CON_KNIFE_EDGE, c.wheel = 1;
      memcpy(c.ground.normal, n, sizeof n), c.ground.offset = -0.2;
      ap_model *m = fd_free_shape("shape on an incline", kind, &c);
      if (!m) continue;
      ap_data *d = NULL;
      AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
      double good = 0.0, bad = 1e300, gapd = 0.0;
      for (int s = 0; s < 6; s++) {
        static meas a, der;
        double q[MAXK], v[MAXK], t, gb[MAXR], mb[MAXR], mg[MAXR];
        fd_result r;
        do rand_state(m, q, v, &t);
        while (measure(m, d, t, q, v, &a) != AP_OK || fabs(a.R[0][6] * n[0] + a.R[0][7] * n[1] +
                                                            a.R[0][8] * n[2]) > 0.95 * 0.9434);
        AP_CHECK_EQ_INT(fd_check(m, d, t, q, v, 1e-3, &r, &a, &der), AP_OK);
        AP_CHECK_EQ_INT(measure(m, d, t, q, v, &a), AP_OK);
        ap_con_rolling_gamma(ap_bm(m), ap_bm_scratch(d), 0, 0, gb);
        for (int i = 0; i < m->b; i++) mb[i] = -gb[i], mg[i] = -a.gamma[i];
        good = fmax(good, err_rel(mg, der.c, m->b));
        bad = fmin(bad, err_rel(mb, der.c, m->b));
        /* the contact row .z (last) is n . vP of the material point */
        double nv = 0.0, nn = 0.9433981132056603;
        for (int i = 0; i < 3; i++) nv += n[i] / nn * der.xm[0][i];
        gapd = fmax(gapd, err_rel(&a.c[m->b - 1], &nv, 1));
      }
      printf("    %-9s %-7s gamma %.1e (without the surface term at least %.1e), row .z vs "
             "n . vP %.1e\n", kind == AP_SHAPE_SPHERE ? "sphere" : kind == AP_SHAPE_ELLIPSOID ?
             "ellipsoid" : kind == AP_SHAPE_DISK ? "disk" : "torus", knife ? "knife" : "rolling",
             good, bad, gapd);
      AP_CHECK_LE(good, FD_TOL);
      AP_CHECK_LE(gapd, FD_TOL);
      AP_CHECK(bad > 100 * FD_TOL);
      ap_data_free(d);
      ap_model_free(m);
    }
}

/* A ball (r = 0.1 m) on a free joint rolling on a fixed sphere (radius 1 m, centre (0, 0, 1)):
 * inside (a bowl) or outside (a dome); random com and inertia for the finite differences. */
static ap_model *ball_on_sphere(int inside, int random_body) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  if (ap_builder_create(inside ? "ball in a bowl" : "ball on a dome", &b) != AP_OK) return NULL;
  ap_body_def bd = ap_body_def_default();
  bd.name = "ball", bd.shape.kind = AP_SHAPE_SPHERE, bd.shape.radius = RADIUS;
  int rc = ap_body_def_uniform(&bd, MASS);
  if (random_body) rand_vec(bd.com, 3, 0.03), rand_inertia(bd.inertia, 0.01);
  if (rc == AP_OK) rc = ap_builder_add_body(b, &bd, NULL);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_FREE, j.child = 0;
  if (rc == AP_OK) rc = ap_builder_add_joint(b, &j, NULL);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0, c.no_spin = random_body;
  c.ground.sphere_radius = 1.0, c.ground.sphere_center[2] = 1.0, c.ground.inside = inside;
  if (rc == AP_OK) rc = ap_builder_add_constraint(b, &c, NULL);
  ap_effect_def e = ap_effect_def_default();
  if (rc == AP_OK) rc = ap_builder_add_effect(b, &e, NULL);
  if (rc == AP_OK) rc = ap_builder_compile(b, &m);
  if (rc != AP_OK) printf("  %s\n", ap_builder_message(b));
  ap_builder_free(b);
  return m;
}

/* gamma on the sphere against central differences of A v + a0 along the motion. */
static void test_fd_sphere(void) {
  for (int inside = 0; inside < 2; inside++) {
    ap_model *m = ball_on_sphere(inside, 1);
    AP_CHECK(m != NULL);
    if (!m) continue;
    ap_data *d = NULL;
    AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
    double worst = 0.0;
    for (int s = 0; s < 6; s++) {
      static meas a, der;
      double q[MAXK], v[MAXK], t, mg[MAXR];
      fd_result r;
      do rand_state(m, q, v, &t);
      while (measure(m, d, t, q, v, &a) != AP_OK);
      AP_CHECK_EQ_INT(fd_check(m, d, t, q, v, 1e-3, &r, &a, &der), AP_OK);
      for (int i = 0; i < m->b; i++) mg[i] = -a.gamma[i];
      worst = fmax(worst, err_rel(mg, der.c, m->b));
    }
    printf("  ball %s a sphere (rolling, no-spin, contact row): gamma against finite "
           "differences %.1e\n", inside ? "inside" : "outside", worst);
    AP_CHECK_LE(worst, FD_TOL);
    ap_data_free(d);
    ap_model_free(m);
  }
}

/* A ball rolling in a spherical bowl, released at rest theta0 = 0.01 rad from the bottom:
 * (7/5)(R - r) theta'' = -g sin(theta), a pendulum of length 7 (R - r) / 5, period
 * T = 2 pi sqrt(7 (R - r) / (5 g)) (1 + theta0^2 / 16 + O(theta0^4)); the energy is kept. */
static void test_bowl(void) {
  ap_model *m = ball_on_sphere(1, 0);
  AP_CHECK(m != NULL);
  if (!m) return;
  double th0 = 0.01, L = 1.0 - RADIUS, T0 = 2 * PI * sqrt(7 * L / (5 * G));
  double Tref = T0 * (1 + th0 * th0 / 16), q[7] = {L * sin(th0), 0, 1 - L * cos(th0), 1, 0, 0, 0};
  double v[6] = {0, 0, 0, 0, 0, 0};
  ap_sim_def def = ap_sim_def_default();
  def.rtol = 1e-12, def.atol = 1e-14;
  ap_sim *s = start(m, &def, q, v);
  ap_data *de = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &de), AP_OK);
  double dt = T0 / 400, prev_x = q[0], cross[8], E0 = 0, dE = 0;
  int nc = 0;
  for (int k = 1; k <= 1300 && s && nc < 8; k++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, k * dt), AP_OK);
    const double *x = ap_sim_q(s), *w = ap_sim_v(s);
    double T = 0, V = 0;
    memcpy(de->q, x, 7 * sizeof *x), memcpy(de->v, w, 6 * sizeof *w);
    AP_CHECK_EQ_INT(ap_body_energy(m, de, &T, &V), AP_OK);
    if (k == 1) E0 = T + V;
    dE = fmax(dE, fabs(T + V - E0));
    if ((prev_x < 0) != (x[0] < 0)) cross[nc++] = k * dt - x[0] / w[0];   /* Newton step */
    prev_x = x[0];
  }
  AP_CHECK(nc >= 5);
  double Tm = (cross[nc - 1] - cross[0]) / ((nc - 1) / 2.0);
  printf("  ball in a bowl (R = 1, r = 0.1, theta0 = 0.01): period %.12g s, closed form %.12g s "
         "(relative %.1e); energy kept to %.1e J\n", Tm, Tref, fabs(Tm / Tref - 1), dE);
  AP_CHECK_NEAR(Tm, Tref, 1e-8 * Tref);
  AP_CHECK_LE(dE, 1e-12);
  ap_data_free(de);
  ap_sim_free(s);
  ap_model_free(m);
}

/* A spinning sphere dropped onto the plane, sticking plastic impact (ap_impact): with I = 2/5 m
 * r^2, the angular momentum about the contact point is kept, so vx+ = (5 vx- + 2 r wy-) / 7,
 * vy+ = (5 vy- - 2 r wx-) / 7, vz+ = 0, w+ = (-vy+, vx+, .) / r, wz kept; Carnot: the energy
 * lost equals 1/2 (v+ - v-)^T g (v+ - v-) and T(v-) - T(v+). On z = 0 and on the incline (the
 * same impact turned by Q). */
static void test_impact(void) {
  double Q[9], n[3], g[3] = {0, 0, -G}, I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  rot_x(ALPHA, Q);
  mulv(Q, (double[3]){0, 0, 1}, n);
  for (int tilted = 0; tilted < 2; tilted++) {
    char msg[512] = "";
    const double *T = tilted ? Q : I3;
    ap_model *m = ball(AP_SHAPE_SPHERE, tilted ? n : NULL, tilted ? OFFSET : 0.0, g, msg);
    AP_CHECK(m != NULL);
    if (!m) continue;
    double ql[7] = {0.2, -0.1, RADIUS, 1, 0, 0, 0}, vl[6] = {1.3, -0.6, -2.5, 4.0, 7.0, 11.0};
    double q[7], vm[6], vp[6], ex[6], loss = -1.0;
    ex[0] = (5 * vl[0] + 2 * RADIUS * vl[4]) / 7, ex[1] = (5 * vl[1] - 2 * RADIUS * vl[3]) / 7;
    ex[2] = 0.0, ex[3] = -ex[1] / RADIUS, ex[4] = ex[0] / RADIUS, ex[5] = vl[5];
    if (tilted) {
      double e2[6];
      map_state(Q, OFFSET, ql, vl, q, vm);
      mulv(T, ex, e2), mulv(T, ex + 3, e2 + 3);
      memcpy(ex, e2, sizeof e2);
    } else {
      memcpy(q, ql, sizeof q), memcpy(vm, vl, sizeof vm);
    }
    ap_data *d = NULL;
    AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
    memcpy(d->q, q, sizeof q);
    d->basis = AP_BASIS_ORTHONORMAL;
    AP_CHECK_EQ_INT(ap_impact(m, d, vm, vp, &loss), AP_OK);
    double err = 0.0, Tm = ap_kinetic_energy(d, vm), Tp = ap_kinetic_energy(d, vp);
    for (int i = 0; i < 6; i++) err = fmax(err, fabs(vp[i] - ex[i]) * (i < 3 ? 1.0 : RADIUS));
    printf("  sticking impact of a spinning sphere%s: v+ %.2e m/s from the closed form, "
           "Carnot loss %.12g J, T- - T+ = %.12g J\n", tilted ? " on the incline" : "", err, loss,
           Tm - Tp);
    AP_CHECK_LE(err, 1e-13);
    AP_CHECK_NEAR(loss, Tm - Tp, 1e-12 * Tm);
    AP_CHECK_LE(ap_constraint_residual(d, vp), 1e-14);
    ap_data_free(d);
    ap_model_free(m);
  }
}

/* A tilted plane needs a body that is not on a plane-contact joint, and a fixed ground. */
static void test_refusals(void) {
  double n[3] = {0, -0.5, 1};
  for (int c = 0; c < 2; c++) {
    ap_constraint_def k = ap_constraint_def_default();
    k.name = "roll";
    memcpy(k.ground.normal, n, sizeof n);
    if (c) k.ground.kind = AP_GROUND_TURNTABLE, k.ground.omega = 1.0;
    char msg[512];
    int rc = bs_ball_refused(c ? AP_JOINT_FREE : AP_JOINT_PLANE_CONTACT, RADIUS, MASS, &k, msg,
                             sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_ERR_ARG);
    printf("  refused: %s\n", msg);
    AP_CHECK(strstr(msg, "roll") != NULL);
    AP_CHECK(strstr(msg, c ? "moving ground" : "plane-contact joint") != NULL);
  }
}

int main(void) {
  printf("rolling on a tilted ground plane:\n");
  test_turned_gravity();
  test_incline_closed_form();
  test_fd_incline();
  test_impact();
  test_fd_sphere();
  test_bowl();
  test_refusals();
  return ap_check_finish("test_terrain");
}
