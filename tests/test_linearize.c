/* Linearization (lib/analyze) against closed forms: the rolling disk, Hoffmann's pendulum,
 * the Chaplygin sleigh, and the sweep machinery.
 *
 * Tolerances follow from the method. Entries of A come from the complex step (the default for
 * these models; its estimate E_ij measures the round-off, jacobian.c; tests/test_lin_cs.c
 * compares it with Ridders' extrapolated differences on every example scene): an entry must
 * equal its closed form within 2 E_ij + 16 ulps of the matrix's scale (RK below). Eigenvalues
 * must equal their closed forms within the error bound reported with them (first-order
 * perturbation with E and LAPACK's bound), and within the absolute figure stated per test.
 *
 *  - Rolling disk (docs/references.md §4), three parameter sets, upright rolling at four
 *    speeds. With the chart (tilt, heading, spin) and heading-frame speeds (wx, wy, wz),
 *    w_a = wz - w tilt and w_n = -wy at heading 0 (axis along -y), so §4's linearized equations
 *    become
 *    tilt' = wx, wx' = (m g r - (C + m r^2) w^2) / (A + m r^2) tilt + (C + m r^2) w / (A + m r^2) wz,
 *    wz' = w (1 - C / A) wx, wy' = 0 (w = v / r): A's non-cyclic block is checked entry by entry.
 *    Eigenvalues lambda^2 = (m g r - (C + m r^2) C w^2 / A) / (A + m r^2), 0, 0; the cyclic set
 *    is {x, y, heading, spin}; the sweep finds the critical speed sqrt(g r / 3) to 1e-10.
 *  - Rolling disk in a steady turn: the body model (tilt freed, Newton from 5 degrees off) and
 *    §4's equations as a math-level system have the same non-cyclic eigenvalues.
 *  - Hoffmann's pendulum (docs/references.md §6): equilibrium tan(theta*) = 2F/((m1 + 2 m2) g),
 *    tan(phi*) = F/(m2 g); at it the small oscillations solve det(K - w^2 g) = 0 with
 *    K = diag(a1 H1, a2 H2), H1 = |((m1 + 2 m2) g, 2F)|, H2 = |(m2 g, F)| (the Hessian of
 *    V = -(m1 + 2 m2) g a1 cos(theta) - m2 g a2 cos(phi) - F (2 a1 sin(theta) + a2 sin(phi))),
 *    so A = [[0, I], [-g^-1 K, 0]] and B = [0; g^-1 e_theta] for a torque on theta. Both the
 *    hand-derived system (tests/refsys.c) and the body model with its loop closure (the example
 *    scene, two parameter sets) are checked. A and B are compared at the operating point
 *    Newton found (K = diag(a1 ((m1 + 2 m2) g cos theta + 2 F sin theta),
 *    a2 (m2 g cos phi + F sin phi)), the Hessian there, and g there): Newton stops at a residual
 *    of 1e-12, which moves the angles by a few 1e-14 and A by a few 1e-13, more than the
 *    complex step's round-off. At a point that is an equilibrium only to the rates F0 Newton
 *    left, A also has terms g^-1 (dg/dq) F0 that the formula lacks: |g^-1 dg/dq| < 0.5 for
 *    these rods, so the entries are compared within max |F0| more.
 *  - Chaplygin sleigh (docs/references.md §2) moving straight at u: u' = a w^2,
 *    J w' = -m a u w give the eigenvalue -m a u / J (stable forwards, unstable backwards)
 *    besides 0.
 * The sweep machinery on a synthetic spectrum, the scene section and the error paths are in
 * tests/test_lin_misc.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "check.h"
#include "clitest.h"
#include "refsys.h"

#define RK 2.0   /* entries within RK Ridders estimates */

static char srcdir[1024];

static double worst_entry = 0.0;   /* largest |A - closed form| / error estimate seen */
static double worst_eig = 0.0;     /* largest |eigenvalue - closed form| seen */

/* A[state r, state c] equals ref within RK error estimates (+ 16 ulps of max |A|, + the
 * reference's own error extra). */
static void check_entry(const ap_lin *L, const char *r, const char *c, double ref,
                        double extra) {
  int i = ap_lin_find_state(L, r), j = ap_lin_find_state(L, c), nx = ap_lin_nx(L);
  AP_CHECK(i >= 0 && j >= 0);
  if (i < 0 || j < 0) return;
  const double *A = ap_lin_A(L), *E = ap_lin_A_error(L);
  double amax = 0.0;
  for (int k = 0; k < nx * nx; k++) amax = fmax(amax, fabs(A[k]));
  double d = fabs(A[i + j * nx] - ref), e = E[i + j * nx];
  double floor = 16 * DBL_EPSILON * amax + extra;
  if (d > floor) worst_entry = fmax(worst_entry, d / e);
  if (!(d <= RK * e + floor))
    fprintf(stderr, "  A[%s, %s] = %.17g, closed form %.17g, error estimate %.3g (%s)\n", r,
            c, A[i + j * nx], ref, e,
            ap_lin_method_used(L) == AP_LIN_COMPLEX_STEP ? "complex step" : "Ridders");
  AP_CHECK(d <= RK * e + floor);
}

/* Every eigenvalue of the last ap_lin_eigen has a partner in (re, im) within its error bound
 * and within tol. */
static void check_eigs(const ap_lin *L, int n, const double *re, const double *im, double tol) {
  ap_lin_eig e;
  AP_CHECK_EQ_INT(ap_lin_get_eigen(L, &e), AP_OK);
  AP_CHECK_EQ_INT(e.n, n);
  int used[32] = {0};
  for (int i = 0; i < e.n && i < 32; i++) {
    int best = -1;
    double bd = HUGE_VAL;
    for (int j = 0; j < n; j++)
      if (!used[j] && hypot(e.re[i] - re[j], e.im[i] - im[j]) < bd)
        bd = hypot(e.re[i] - re[j], e.im[i] - im[j]), best = j;
    if (best >= 0) used[best] = 1;
    worst_eig = fmax(worst_eig, bd);
    if (!(bd <= fmax(e.err[i], 4 * DBL_EPSILON) && bd <= tol))
      fprintf(stderr, "  eigenvalue %.17g%+.17gi: closest closed form off by %.3g (bound %.3g)\n",
              e.re[i], e.im[i], bd, e.err[i]);
    AP_CHECK(bd <= fmax(e.err[i], 4 * DBL_EPSILON));
    AP_CHECK_LE(bd, tol);
  }
}

/* ---- the rolling disk ------------------------------------------------------------------- */

typedef struct disk {
  double m, r, g;
} disk;

static ap_model *disk_model(const disk *p) {
  ap_builder *b = NULL;
  AP_CHECK(ap_builder_create("rolling disk", &b) == AP_OK);
  ap_body_def d = ap_body_def_default();
  d.name = "disk", d.mass = p->m, d.shape.kind = AP_SHAPE_DISK, d.shape.radius = p->r;
  d.inertia[0] = d.inertia[4] = p->m * p->r * p->r / 4, d.inertia[8] = p->m * p->r * p->r / 2;
  AP_CHECK(ap_builder_add_body(b, &d, NULL) == AP_OK);
  ap_joint_def j = ap_joint_def_default();
  j.kind = AP_JOINT_PLANE_CONTACT, j.child = 0;
  AP_CHECK(ap_builder_add_joint(b, &j, NULL) == AP_OK);
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.body = 0;
  AP_CHECK(ap_builder_add_constraint(b, &c, NULL) == AP_OK);
  ap_effect_def e = ap_effect_def_default();
  e.gravity[2] = -p->g;
  AP_CHECK(ap_builder_add_effect(b, &e, NULL) == AP_OK);
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_builder_compile(b, &m), AP_OK);
  ap_builder_free(b);
  return m;
}

/* Disk state in the convention of tests/test_body_disk.c at heading 0: lean theta from the
 * vertical (the reference's theta), axis a = (0, cos theta, -sin theta), b_up = (0, sin theta,
 * cos theta), body axes R = [e_x, -b_up, a]; angular velocity -thd e_x + wa b_up + wn a; the
 * centre's velocity from rolling (ap_body_complete_speeds). */
static void disk_state(const ap_model *m, double th, double thd, double wa, double wn,
                       double *q, double *v) {
  double e1[3] = {1, 0, 0}, a[3] = {0, cos(th), -sin(th)}, bu[3] = {0, sin(th), cos(th)};
  double R[9] = {1, 0, 0, 0, -sin(th), -cos(th), 0, cos(th), -sin(th)};
  q[0] = q[1] = 0.0;
  ap_quat_from_matrix(R, q + 2);
  for (int i = 0; i < 3; i++) v[2 + i] = -thd * e1[i] + wa * bu[i] + wn * a[i];
  int given[5] = {0, 0, 1, 1, 1};
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  d->t = 0.0;
  AP_CHECK_EQ_INT(ap_body_complete_speeds(m, d, q, given, v), AP_OK);
  ap_data_free(d);
}

static const char *const disk_indep[] = {"disk.wx", "disk.wy", "disk.wz", NULL};

/* Upright rolling at speed v: the operating point, the non-cyclic block entry by entry, the
 * cyclic set and the eigenvalues. */
static void disk_upright(const disk *p, double v) {
  ap_model *m = disk_model(p);
  double q[6], u[5], r = p->r, w = v / r, A = p->m * r * r / 4, C = 2 * A, mr2 = p->m * r * r;
  disk_state(m, 0.0, 0.0, 0.0, w, q, u);
  ap_lin *L = NULL;
  ap_lin_def def = ap_lin_def_default();
  def.independent = disk_indep;   /* else r > 1 makes wx, wy dependent (larger pivots) */
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, u, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L, NAN), AP_OK);
  int rc = ap_lin_linearize(L);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  static const char *const cyc[] = {"disk.x", "disk.y", "disk.heading", "disk.spin"};
  for (int i = 0; i < 4; i++) AP_CHECK_EQ_INT(ap_lin_is_cyclic(L, ap_lin_find_state(L, cyc[i])), 1);
  AP_CHECK_EQ_INT(ap_lin_is_cyclic(L, ap_lin_find_state(L, "disk.tilt")), 0);
  static const char *const nc[] = {"disk.tilt", "disk.wx", "disk.wy", "disk.wz"};
  double ref[4][4] = {{0}};   /* rows, columns in the order of nc */
  ref[0][1] = -1.0;
  ref[1][0] = ((C + mr2) * w * w - p->m * p->g * r) / (A + mr2);
  ref[1][3] = (C + mr2) * w / (A + mr2);
  ref[3][1] = w * (1.0 - C / A);
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) check_entry(L, nc[i], nc[j], ref[i][j], 0.0);
  AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 1), AP_OK);
  double lam2 = (p->m * p->g * r - (C + mr2) * C * w * w / A) / (A + mr2), s = sqrt(fabs(lam2));
  double re[4] = {lam2 > 0 ? s : 0, lam2 > 0 ? -s : 0, 0, 0};
  double im[4] = {lam2 > 0 ? 0 : s, lam2 > 0 ? 0 : -s, 0, 0};
  check_eigs(L, 4, re, im, 1e-11 * fmax(1.0, s));
  ap_lin_free(L);
  ap_model_free(m);
}

static void disk_critical(const disk *p) {
  ap_model *m = disk_model(p);
  double q[6], u[5], dir[5] = {0}, vc = sqrt(p->g * p->r / 3.0), s[101];
  disk_state(m, 0.0, 0.0, 0.0, 0.0, q, u);
  dir[0] = 1.0, dir[3] = 1.0 / p->r;   /* per unit speed: vx = 1, wy = w_n = 1 / r */
  ap_lin_def def = ap_lin_def_default();
  def.speed_dir = dir;
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, u, &L), AP_OK);
  for (int i = 0; i < 101; i++) s[i] = 4.0 * vc * i / 100;
  ap_lin_sweep sw;
  int rc = ap_lin_sweep_speed(L, s, 101, NULL, 0, 1, 1e-14, &sw);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(sw.npoints, 1);
  if (rc == AP_OK && sw.npoints == 1) {
    printf("disk m=%g r=%g g=%g: critical speed %.17g, sqrt(g r / 3) = %.17g, off by %.2g\n",
           p->m, p->r, p->g, sw.points[0].p, vc, fabs(sw.points[0].p - vc));
    AP_CHECK_NEAR(sw.points[0].p, vc, 1e-10);
    AP_CHECK_EQ_INT(sw.points[0].kind, AP_LIN_MEETING);
    AP_CHECK_EQ_INT(sw.points[0].rising, 1);
  }
  ap_lin_sweep_free(&sw);
  ap_lin_free(L);
  ap_model_free(m);
}

/* docs/references.md §4's equations as a math-level system: q = (theta, alpha, beta),
 * v = (theta', w_a, w_n) with alpha' = w_a, beta' = w_n cyclic. */
static int ref_metric(double t, const double *q, double *g, void *user) {
  const disk *p = user;
  double r2 = p->m * p->r * p->r;
  (void)t, (void)q;
  g[0] = r2 / 4 + r2, g[4] = r2 / 4, g[8] = r2 / 2 + r2;
  return 0;
}

static int ref_bias(double t, const double *q, const double *v, double *h, void *user) {
  const disk *p = user;
  double r2 = p->m * p->r * p->r, A = r2 / 4, C = r2 / 2, tn = tan(q[0]);
  (void)t;
  h[0] = (C + r2) * v[1] * v[2] + A * v[1] * v[1] * tn;
  h[1] = -v[0] * (C * v[2] + A * v[1] * tn);
  h[2] = -r2 * v[0] * v[1];
  return 0;
}

static int ref_force(double t, const double *q, const double *v, double *Q, void *user) {
  const disk *p = user;
  (void)t, (void)v;
  Q[0] = p->m * p->g * p->r * sin(q[0]);
  return 0;
}

/* Non-cyclic eigenvalues of a linearizer, sorted by the library (re desc). */
static int eigs_of(ap_lin *L, double *re, double *im) {
  ap_lin_eig e;
  if (ap_lin_eigen(L, NULL, 0, 1) != AP_OK || ap_lin_get_eigen(L, &e) != AP_OK) return -1;
  memcpy(re, e.re, sizeof *re * (size_t)e.n), memcpy(im, e.im, sizeof *im * (size_t)e.n);
  return e.n;
}

static void disk_turn(const disk *p, double th, double Om) {
  double r2 = p->m * p->r * p->r, A = r2 / 4, C = r2 / 2;
  double wa = Om * cos(th), wn = (p->m * p->g * p->r * sin(th) / (Om * cos(th)) -
                                  A * Om * sin(th)) / (C + r2);
  /* the math-level system */
  ap_system_def sd = ap_system_def_default();
  sd.name = "disk equations", sd.n = sd.k = 3, sd.metric = ref_metric, sd.bias = ref_bias;
  sd.force = ref_force, sd.user = (void *)p;
  ap_model *mr = NULL, *mb = disk_model(p);
  AP_CHECK_EQ_INT(ap_model_from_system(&sd, &mr, NULL, 0), AP_OK);
  double q3[3] = {th, 0, 0}, v3[3] = {0, wa, wn}, re1[8], im1[8], re2[8], im2[8];
  ap_lin_def def = ap_lin_def_default();
  ap_lin *L1 = NULL, *L2 = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(mr, &def, 0.0, q3, v3, &L1), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L1, NAN), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_linearize(L1), AP_OK);
  int n1 = eigs_of(L1, re1, im1);
  /* the body model, its lean freed and guessed 5 degrees off */
  double q[6], u[5], qg[6], ug[5];
  disk_state(mb, th, 0.0, wa, wn, q, u);
  disk_state(mb, th + 5 * RS_PI / 180, 0.0, wa, wn, qg, ug);
  static const char *const fr[] = {"disk.tilt", NULL};
  def.free = fr;
  AP_CHECK_EQ_INT(ap_lin_create(mb, &def, 0.0, qg, u, &L2), AP_OK);
  int rc = ap_lin_operating_point(L2, NAN);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L2));
  AP_CHECK_EQ_INT(rc, AP_OK);
  const double *qp = ap_lin_q(L2);   /* the lean found: a_z = -sin(theta) */
  double R[9];
  ap_quat_to_matrix(qp + 2, R);
  AP_CHECK_NEAR(asin(-R[8]), th, 1e-12);
  rc = ap_lin_linearize(L2);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L2));
  AP_CHECK_EQ_INT(rc, AP_OK);
  int n2 = eigs_of(L2, re2, im2);
  AP_CHECK_EQ_INT(n1, 4);
  AP_CHECK_EQ_INT(n2, 4);
  ap_lin_eig e1, e2;
  ap_lin_get_eigen(L1, &e1), ap_lin_get_eigen(L2, &e2);
  int used[8] = {0};
  for (int i = 0; i < n2 && n1 == n2; i++) {   /* each body eigenvalue: the nearest unused one */
    int j = -1;
    for (int c = 0; c < n1; c++)
      if (!used[c] && (j < 0 || hypot(re1[c] - re2[i], im1[c] - im2[i]) <
                                    hypot(re1[j] - re2[i], im1[j] - im2[i])))
        j = c;
    used[j] = 1;
    double d = hypot(re1[j] - re2[i], im1[j] - im2[i]), tol = e1.err[j] + e2.err[i];
    printf("disk turn lean %.3g Omega %.3g: %.15g%+.15gi vs equations %.15g%+.15gi (%.2g, "
           "bound %.2g)\n", th, Om, re2[i], im2[i], re1[j], im1[j], d, tol);
    AP_CHECK(d <= tol);
    AP_CHECK_LE(d, 1e-10);
  }
  ap_lin_free(L1), ap_lin_free(L2);
  ap_model_free(mr), ap_model_free(mb);
}

static void test_disk(void) {
  static const disk ps[] = {{1.0, 0.5, 9.81}, {2.3, 0.3, 9.81}, {0.7, 1.2, 3.7}};
  for (int i = 0; i < 3; i++) {
    double vc = sqrt(ps[i].g * ps[i].r / 3.0);
    static const double f[] = {0.0, 0.5, 1.7, 5.0};
    for (int j = 0; j < 4; j++) disk_upright(&ps[i], f[j] * vc);
    disk_critical(&ps[i]);
  }
  disk_turn(&ps[0], 0.3, 2.0);
  disk_turn(&ps[1], -0.5, 4.0);
}

/* ---- Hoffmann's pendulum ------------------------------------------------------------------ */

/* Equilibrium angles, the metric there, K = diag(a1 H1, a2 H2) and w^2 of det(K - w^2 g) = 0. */
static void hoff_closed(const rs_hoffmann *p, double *th, double *ph, double g[4], double K[2],
                        double w2[2]) {
  double Q[2], H1 = hypot((p->m1 + 2 * p->m2) * p->grav, 2 * p->F), H2 = hypot(p->m2 * p->grav, p->F);
  *th = atan2(2 * p->F, (p->m1 + 2 * p->m2) * p->grav), *ph = atan2(p->F, p->m2 * p->grav);
  double q2[2] = {*th, *ph};
  rs_hoffmann_printed(p, q2, g, Q);
  K[0] = p->a1 * H1, K[1] = p->a2 * H2;
  double a = g[0] * g[3] - g[1] * g[1], b = K[0] * g[3] + K[1] * g[0], c = K[0] * K[1];
  double disc = sqrt(b * b - 4 * a * c);
  w2[0] = (b + disc) / (2 * a), w2[1] = (b - disc) / (2 * a);
}

/* A and B of a linearizer with states (theta, phi, theta', phi') under the given names against
 * [[0, I], [-g^-1 K, 0]] and [0; g^-1 e_theta]; eigenvalues +-i w. */
static void hoff_check(const ap_lin *L, const rs_hoffmann *p, const char *const names[4]) {
  double th, ph, g[4], K[2], w2[2], Q[2];
  hoff_closed(p, &th, &ph, g, K, w2);
  int ia = ap_model_find_coord(L->m, names[0]), ih = ap_model_find_coord(L->m, names[1]);
  AP_CHECK(ia >= 0 && ih >= 0);
  if (ia < 0 || ih < 0) return;
  double q2[2] = {ap_lin_q(L)[ia], ap_lin_q(L)[ih]};   /* the operating point found */
  rs_hoffmann_printed(p, q2, g, Q);
  K[0] = p->a1 * ((p->m1 + 2 * p->m2) * p->grav * cos(q2[0]) + 2 * p->F * sin(q2[0]));
  K[1] = p->a2 * (p->m2 * p->grav * cos(q2[1]) + p->F * sin(q2[1]));
  double fres = 0.0;   /* the rates left at the point: A's terms in them are not in ref */
  for (int i = 0; i < ap_lin_nx(L); i++) fres = fmax(fres, fabs(ap_lin_rates(L)[i]));
  double det = g[0] * g[3] - g[1] * g[2], gi[4] = {g[3] / det, -g[1] / det, -g[2] / det,
                                                   g[0] / det};   /* column-major inverse */
  double ref[4][4] = {{0, 0, 1, 0}, {0, 0, 0, 1}, {-gi[0] * K[0], -gi[2] * K[1], 0, 0},
                      {-gi[1] * K[0], -gi[3] * K[1], 0, 0}};
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) check_entry(L, names[i], names[j], ref[i][j], fres);
  const double *B = ap_lin_B(L);
  int nx = ap_lin_nx(L), i2 = ap_lin_find_state(L, names[2]), i3 = ap_lin_find_state(L, names[3]);
  AP_CHECK_EQ_INT(ap_lin_nu(L), 1);
  if (B && i2 >= 0 && i3 >= 0) {   /* exact: to round-off */
    AP_CHECK_NEAR(B[i2], gi[0], 1e-13 * fabs(gi[0]));
    AP_CHECK_NEAR(B[i3], gi[1], 1e-13 * fabs(gi[0]));
    AP_CHECK_NEAR(B[ap_lin_find_state(L, names[0])], 0.0, 0.0);
  }
  (void)nx;
  double re[4] = {0, 0, 0, 0}, im[4] = {sqrt(w2[0]), -sqrt(w2[0]), sqrt(w2[1]), -sqrt(w2[1])};
  check_eigs(L, 4, re, im, 1e-11);
}

static void hoff_reduced(rs_hoffmann *p) {
  ap_system_def sd;
  rs_hoffmann_reduced_system(p, &sd);
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&sd, &m, NULL, 0), AP_OK);
  double q[2] = {0.3, -0.2}, v[2] = {0, 0}, th, ph, g[4], K[2], w2[2];
  static const char *const in[] = {"v0", NULL};
  ap_lin_def def = ap_lin_def_default();
  def.about = AP_LIN_EQUILIBRIUM, def.inputs = in;
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, v, &L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_operating_point(L, NAN), AP_OK);
  hoff_closed(p, &th, &ph, g, K, w2);
  AP_CHECK_NEAR(ap_lin_q(L)[0], th, 1e-13);
  AP_CHECK_NEAR(ap_lin_q(L)[1], ph, 1e-13);
  AP_CHECK_EQ_INT(ap_lin_linearize(L), AP_OK);
  AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 1), AP_OK);
  static const char *const names[4] = {"theta", "phi", "v0", "v1"};
  hoff_check(L, p, names);
  ap_lin_free(L);
  ap_model_free(m);
}

/* The body model of the example scene (upper rod on a revolute, lower rod on a planar joint,
 * the hinge a loop closure); sets override its parameters. */
static void hoff_body(rs_hoffmann *p, const char *const *sets, int nsets) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/hoffmann.yaml", srcdir);
  ap_scene *sc = NULL;
  int rc = ap_scene_load(file, sets, nsets, &sc, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return;
  const ap_model *m = ap_scene_model(sc);
  double q[4], v[4], th, ph, g[4], K[2], w2[2];
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  static const char *const ind[] = {"upper.angle", "lower.heading", "upper.angle_dot",
                                    "lower.heading_dot", NULL};
  static const char *const in[] = {"upper.angle_dot", NULL};
  ap_lin_def def = ap_lin_def_default();
  def.about = AP_LIN_EQUILIBRIUM, def.independent = ind, def.inputs = in;
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, v, &L), AP_OK);
  rc = ap_lin_operating_point(L, NAN);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  hoff_closed(p, &th, &ph, g, K, w2);
  int ia = ap_model_find_coord(m, "upper.angle"), ih = ap_model_find_coord(m, "lower.heading");
  printf("Hoffmann body model: theta* %.17g (closed form %.17g), phi* %.17g (%.17g)\n",
         ap_lin_q(L)[ia], th, ap_lin_q(L)[ih], ph);
  AP_CHECK_NEAR(ap_lin_q(L)[ia], th, 1e-12);
  AP_CHECK_NEAR(ap_lin_q(L)[ih], ph, 1e-12);
  rc = ap_lin_linearize(L);
  if (rc != AP_OK) fprintf(stderr, "%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK_EQ_INT(ap_lin_nx(L), 4);
  AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 1), AP_OK);
  static const char *const names[4] = {"upper.angle", "lower.heading", "upper.angle_dot",
                                       "lower.heading_dot"};
  hoff_check(L, p, names);
  ap_lin_free(L);
  ap_scene_free(sc);
}

static void test_hoffmann(void) {
  double I = 0.0833333333333333;   /* the scene's rod inertia, as written there */
  rs_hoffmann p1 = {1.0, 1.0, 0.5, 0.5, I, I, 9.81, 2.0};
  hoff_reduced(&p1);
  hoff_body(&p1, NULL, 0);
  rs_hoffmann p2 = {1.0, 0.8, 0.5, 0.5, I, 0.8 * I, 9.81, 5.0};
  hoff_reduced(&p2);
  static const char *const sets[] = {"effects.push.force.1=5", "bodies.lower.mass=0.8",
                                     "bodies.lower.inertia.1=0.8*0.0833333333333333",
                                     "bodies.lower.inertia.2=0.8*0.0833333333333333"};
  hoff_body(&p2, sets, 4);
}

/* ---- the Chaplygin sleigh ----------------------------------------------------------------- */

static void test_sleigh(void) {
  char file[1200], msg[1024];
  snprintf(file, sizeof file, "%s/examples/scenes/chaplygin_sleigh.yaml", srcdir);
  static const char *const sets[] = {"initial.sleigh.heading_rate=0"};
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(file, sets, 1, &sc, msg, sizeof msg), AP_OK);
  const ap_model *m = ap_scene_model(sc);
  double q[3], v[3], dir[3];
  AP_CHECK_EQ_INT(ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg), AP_OK);
  /* heading pi: the speed parameter is u along the heading, from rest */
  dir[0] = cos(q[2]), dir[1] = sin(q[2]), dir[2] = 0.0;
  v[0] = v[1] = v[2] = 0.0;
  ap_lin_def def = ap_lin_def_default();
  def.speed_dir = dir;
  ap_lin *L = NULL;
  AP_CHECK_EQ_INT(ap_lin_create(m, &def, 0.0, q, v, &L), AP_OK);
  double mass = 1.0, a = 1.0, Jc = 1.0 + mass * a * a;   /* the scene: m = I = a = 1 */
  static const double us[] = {0.5, -0.5, 2.0};
  for (int i = 0; i < 3; i++) {
    AP_CHECK_EQ_INT(ap_lin_operating_point(L, us[i]), AP_OK);
    AP_CHECK_EQ_INT(ap_lin_linearize(L), AP_OK);
    AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 1), AP_OK);
    double re[2] = {-mass * a * us[i] / Jc, 0.0}, im[2] = {0, 0};
    check_eigs(L, 2, re, im, 1e-12);
  }
  ap_lin_free(L);
  ap_scene_free(sc);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  test_disk();
  test_hoffmann();
  test_sleigh();
  printf("linearize: largest |A - closed form| / error estimate: %.2f; largest |eigenvalue - "
         "closed form|: %.2g\n", worst_entry, worst_eig);
  return ap_check_finish("linearize");
}
