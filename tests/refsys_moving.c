/* Reference systems 3 and 4 of refsys.h (docs/references.md §3, §5), the rheonomic ones: a
 * ball on a rotating turntable (Omega(t) = Omega0 + dOmega t) and a particle on a rotating
 * inclined line (reduced 1-coordinate and 3-D constrained forms).
 *
 * The callbacks return the founding paper's objects (docs/design.md §1), column-major, outputs
 * pre-zeroed by the core so only non-zero entries are written. gamma is the total derivative
 * along the motion at fixed v': the explicit t-dependence enters through the rates of the
 * moving table and line. The turntable's closed form with Omega(t) needs the composite
 * Gauss-Legendre quadrature of refsys_quad.h (complex arithmetic for the planar position). */
#include "refsys.h"

#include <complex.h>
#include <math.h>
#include <string.h>

#include "refsys_quad.h"

/* complex.h's I would clash with the inertia fields; use CI for the imaginary unit. */
#undef I
#define CI _Complex_I

/* ========================================================================================== */
/* 3. Ball on a rotating turntable.                                                           */

static const char *const turntable_coords[] = {"x", "y", "a1", "a2", "a3"};
static const char *const turntable_speeds[] = {"xdot", "ydot", "wx", "wy", "wz"};

double rs_turntable_omega(const rs_turntable *p, double t) { return p->Omega0 + p->dOmega * t; }

static int turntable_metric(double t, const double *q, double *g, void *user) {
  const rs_turntable *p = user;
  double In = p->kI * p->m * p->R * p->R;
  (void)t, (void)q;
  g[0] = p->m;
  g[6] = p->m;
  g[12] = In;
  g[18] = In;
  g[24] = In;
  return 0;
}

/* Rows: x' - R wy + Omega y = 0, y' + R wx - Omega x = 0 (A is 2 x 5, column-major). */
static int turntable_constraint(double t, const double *q, double *A, double *a0, void *user) {
  const rs_turntable *p = user;
  double Om = rs_turntable_omega(p, t);
  A[0 + 2 * 0] = 1.0;
  A[0 + 2 * 3] = -p->R;
  A[1 + 2 * 1] = 1.0;
  A[1 + 2 * 2] = p->R;
  a0[0] = Om * q[1];
  a0[1] = -Om * q[0];
  return 0;
}

/* A is constant; a0' = (Omega' y + Omega y', -Omega' x - Omega x'). */
static int turntable_gamma(double t, const double *q, const double *v, double *gamma,
                           void *user) {
  const rs_turntable *p = user;
  double Om = rs_turntable_omega(p, t), dOm = p->dOmega;
  gamma[0] = -(dOm * q[1] + Om * v[1]);
  gamma[1] = -(-dOm * q[0] - Om * v[0]);
  return 0;
}

void rs_turntable_system(rs_turntable *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "ball on turntable";
  def->n = 5;
  def->k = 5;
  def->b = 2;
  def->metric = turntable_metric;
  def->bias_source = AP_BIAS_ZERO;
  def->constraint = turntable_constraint;
  def->gamma = turntable_gamma;
  def->rheonomic = p->dOmega != 0.0;
  def->coord_names = turntable_coords;
  def->speed_names = turntable_speeds;
  def->user = p;
}

void rs_turntable_initial(const rs_turntable *p, double x0, double y0, double wx, double wy,
                          double wz, double q0[5], double v0[5]) {
  double Om = rs_turntable_omega(p, 0.0);
  memset(q0, 0, 5 * sizeof *q0);
  q0[0] = x0;
  q0[1] = y0;
  v0[0] = p->R * wy - Om * y0;
  v0[1] = -p->R * wx + Om * x0;
  v0[2] = wx;
  v0[3] = wy;
  v0[4] = wz;
}

/* E(t) = int_0^t exp(-i Phi(s)) ds, Phi(s) = kt (Omega0 s + dOmega s^2 / 2). */
static double complex turntable_E(const rs_turntable *p, double kt, double t) {
  if (p->dOmega == 0.0) {
    double kap = kt * p->Omega0, th = kap * t;
    if (kap == 0.0) return t;
    return sin(th) / kap - CI * (2.0 * sin(0.5 * th) * sin(0.5 * th)) / kap;
  }
  double xg[RS_GL_N], wg[RS_GL_N];
  double rate = kt * fmax(fabs(p->Omega0), fabs(rs_turntable_omega(p, t)));
  int np = rs_panels(t, rate);
  double hp = t / np;
  double complex E = 0.0;
  rs_gauss_legendre(RS_GL_N, xg, wg);
  for (int i = 0; i < np; i++) {
    double mid = (i + 0.5) * hp;
    double complex pe = 0.0;
    for (int j = 0; j < RS_GL_N; j++) {
      double s = mid + 0.5 * hp * xg[j];
      double ph = kt * (p->Omega0 * s + 0.5 * p->dOmega * s * s);
      pe += wg[j] * (cos(ph) - CI * sin(ph));
    }
    E += 0.5 * hp * pe;
  }
  return E;
}

void rs_turntable_exact(const rs_turntable *p, const double q0[5], const double v0[5],
                        double t, double *q, double *v) {
  double kt = p->kI / (1.0 + p->kI), Om = rs_turntable_omega(p, t);
  double complex z0 = q0[0] + CI * q0[1], zd0 = v0[0] + CI * v0[1];
  double complex c = zd0 - CI * kt * p->Omega0 * z0;
  double ph = kt * (p->Omega0 * t + 0.5 * p->dOmega * t * t);
  double complex z = (cos(ph) + CI * sin(ph)) * (z0 + c * turntable_E(p, kt, t));
  double complex zd = CI * kt * Om * z + c;
  /* int_0^t Omega z = Omega0 z0 t + (z - z0 - z0' t) / (i kt), from z' - z0' = i kt (Omega z -
   * Omega0 z0); the angles follow from the constraint wx = (Omega x - y')/R,
   * wy = (x' + Omega y)/R. */
  double complex Oz = p->Omega0 * z0 * t + (z - z0 - zd0 * t) / (CI * kt);
  if (q) {
    q[0] = creal(z);
    q[1] = cimag(z);
    q[2] = q0[2] + (creal(Oz) - (cimag(z) - q0[1])) / p->R;
    q[3] = q0[3] + ((creal(z) - q0[0]) + cimag(Oz)) / p->R;
    q[4] = q0[4] + v0[4] * t;
  }
  if (v) {
    v[0] = creal(zd);
    v[1] = cimag(zd);
    v[2] = (Om * creal(z) - cimag(zd)) / p->R;
    v[3] = (creal(zd) + Om * cimag(z)) / p->R;
    v[4] = v0[4];
  }
}

void rs_turntable_invariant(const rs_turntable *p, double t, const double *q, const double *v,
                            double c[2]) {
  double kt = p->kI / (1.0 + p->kI), Om = rs_turntable_omega(p, t);
  c[0] = v[0] + kt * Om * q[1];
  c[1] = v[1] - kt * Om * q[0];
}

/* ========================================================================================== */
/* 4. Particle on a rotating inclined line.                                                   */

static const char *const line_r_coords[] = {"r"};
static const char *const line_3d_coords[] = {"X", "Y", "Z"};
static const char *const line_3d_rows[] = {"n1", "n2"};

static double line_s(const rs_line *p) { return p->w * sin(p->alpha); }

static int line_reduced_metric(double t, const double *q, double *g, void *user) {
  const rs_line *p = user;
  (void)t, (void)q;
  g[0] = p->m;
  return 0;
}

/* The rheonomic term: y = r d(t), so g r'' - m |d'|^2 r = Q with |d'| = s. */
static int line_reduced_bias(double t, const double *q, const double *v, double *h, void *user) {
  const rs_line *p = user;
  double s = line_s(p);
  (void)t, (void)v;
  h[0] = -p->m * s * s * q[0];
  return 0;
}

static int line_reduced_force(double t, const double *q, const double *v, double *Q,
                              void *user) {
  const rs_line *p = user;
  (void)t, (void)q, (void)v;
  Q[0] = -p->m * p->grav * cos(p->alpha);
  return 0;
}

void rs_line_reduced_system(rs_line *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "rotating line (reduced)";
  def->n = 1;
  def->k = 1;
  def->b = 0;
  def->metric = line_reduced_metric;
  def->bias = line_reduced_bias;
  def->bias_source = AP_BIAS_CALLBACK;
  def->force = line_reduced_force;
  def->coord_names = line_r_coords;
  def->user = p;
}

/* n1, n2 and their first and second time derivatives at t (each 3 entries). */
static void line_normals(const rs_line *p, double t, double n[2][3], double nd[2][3],
                         double ndd[2][3]) {
  double w = p->w, c = cos(w * t), s = sin(w * t), ca = cos(p->alpha), sa = sin(p->alpha);
  double N[2][3] = {{-s, c, 0.0}, {ca * c, ca * s, -sa}};
  double Nd[2][3] = {{-w * c, -w * s, 0.0}, {-w * ca * s, w * ca * c, 0.0}};
  double Ndd[2][3] = {{w * w * s, -w * w * c, 0.0}, {-w * w * ca * c, -w * w * ca * s, 0.0}};
  memcpy(n, N, sizeof N);
  memcpy(nd, Nd, sizeof Nd);
  memcpy(ndd, Ndd, sizeof Ndd);
}

static int line_3d_metric(double t, const double *q, double *g, void *user) {
  const rs_line *p = user;
  (void)t, (void)q;
  g[0] = g[4] = g[8] = p->m;
  return 0;
}

static int line_3d_force(double t, const double *q, const double *v, double *Q, void *user) {
  const rs_line *p = user;
  (void)t, (void)q, (void)v;
  Q[2] = -p->m * p->grav;
  return 0;
}

/* Rows n_i . p' + n_i' . p = 0: A = [n1; n2] (2 x 3), a0 = (n1' . p, n2' . p). */
static int line_3d_constraint(double t, const double *q, double *A, double *a0, void *user) {
  double n[2][3], nd[2][3], ndd[2][3];
  line_normals(user, t, n, nd, ndd);
  for (int i = 0; i < 2; i++) {
    for (int c = 0; c < 3; c++) A[i + 2 * c] = n[i][c];
    a0[i] = nd[i][0] * q[0] + nd[i][1] * q[1] + nd[i][2] * q[2];
  }
  return 0;
}

/* gamma_i = -(n_i' . v + (n_i'' . p + n_i' . v)) = -(2 n_i' . v + n_i'' . p). */
static int line_3d_gamma(double t, const double *q, const double *v, double *gamma,
                         void *user) {
  double n[2][3], nd[2][3], ndd[2][3];
  line_normals(user, t, n, nd, ndd);
  for (int i = 0; i < 2; i++) {
    double g = 0.0;
    for (int c = 0; c < 3; c++) g += 2.0 * nd[i][c] * v[c] + ndd[i][c] * q[c];
    gamma[i] = -g;
  }
  return 0;
}

void rs_line_3d_system(rs_line *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "rotating line (3-D)";
  def->n = 3;
  def->k = 3;
  def->b = 2;
  def->metric = line_3d_metric;
  def->bias_source = AP_BIAS_ZERO;
  def->force = line_3d_force;
  def->constraint = line_3d_constraint;
  def->gamma = line_3d_gamma;
  def->rheonomic = 1;
  def->coord_names = line_3d_coords;
  def->constraint_names = line_3d_rows;
  def->user = p;
}

void rs_line_exact(const rs_line *p, double r0, double rd0, double t, double *r, double *rd) {
  double s = line_s(p), req = p->grav * cos(p->alpha) / (s * s);
  double ch = cosh(s * t), sh = sinh(s * t);
  if (r) *r = req + (r0 - req) * ch + (rd0 / s) * sh;
  if (rd) *rd = (r0 - req) * s * sh + rd0 * ch;
}

void rs_line_lift(const rs_line *p, double t, double r, double rd, double q3[3], double v3[3]) {
  double c = cos(p->w * t), s = sin(p->w * t), ca = cos(p->alpha), sa = sin(p->alpha);
  double d[3] = {sa * c, sa * s, ca}, dd[3] = {-p->w * sa * s, p->w * sa * c, 0.0};
  for (int i = 0; i < 3; i++) {
    if (q3) q3[i] = r * d[i];
    if (v3) v3[i] = rd * d[i] + r * dd[i];
  }
}

double rs_line_jacobi(const rs_line *p, double r, double rd) {
  double s = line_s(p);
  return 0.5 * p->m * (rd * rd - s * s * r * r) + p->m * p->grav * r * cos(p->alpha);
}

double rs_line_jacobi_3d(const rs_line *p, const double *q3, const double *v3) {
  double E = 0.5 * p->m * (v3[0] * v3[0] + v3[1] * v3[1] + v3[2] * v3[2]) +
             p->m * p->grav * q3[2];
  double Lz = p->m * (q3[0] * v3[1] - q3[1] * v3[0]);
  return E - p->w * Lz;
}

