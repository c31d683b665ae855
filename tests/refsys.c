/* Reference systems with known answers (docs/references.md) as math-level systems.
 *
 * Each problem is a set of callbacks returning the founding paper's objects (docs/design.md §1):
 * g (k x k), h or dg/dq, Q, A (b x k), a0 and gamma = -(A' v + a0'), all column-major, outputs
 * pre-zeroed by the core so only non-zero entries are written. gamma is the total derivative
 * along the motion at fixed v': the q-dependence enters through q' = v and the explicit
 * t-dependence through the rates of the moving parts (turntable, rotating line).
 *
 * The exact solutions are the closed forms of docs/references.md; where a position needs a
 * quadrature (sleigh x, y; turntable with Omega(t)) a composite 16-point Gauss-Legendre rule
 * with panels short against the fastest rate of the integrand is used (error ~1e-15). */
#include "refsys.h"

#include <complex.h>
#include <math.h>
#include <string.h>

/* complex.h's I would clash with the inertia fields; use CI for the imaginary unit. */
#undef I
#define CI _Complex_I

/* Composite Gauss-Legendre panels: a panel spans at most RS_PANEL_TURN radians of the fastest
 * rotation in the integrand and at most RS_PANEL_MAX seconds. */
#define RS_GL_N 16
#define RS_PANEL_TURN 0.5
#define RS_PANEL_MAX 0.5

void rs_gauss_legendre(int n, double *x, double *w) {
  /* Newton on P_n from the Tricomi-type initial guess; weights 2 / ((1 - z^2) P_n'(z)^2). */
  for (int i = 0; i < (n + 1) / 2; i++) {
    double z = cos(RS_PI * (i + 0.75) / (n + 0.5)), pp = 1.0;
    for (int it = 0; it < 100; it++) {
      double p1 = 1.0, p2 = 0.0;
      for (int j = 1; j <= n; j++) {
        double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
      }
      pp = n * (z * p1 - p2) / (z * z - 1.0);
      double dz = p1 / pp;
      z -= dz;
      if (fabs(dz) < 1e-16 && it > 2) break;
    }
    x[i] = -z;
    x[n - 1 - i] = z;
    w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * pp * pp);
  }
}

/* Number of panels for an interval of length |t| whose integrand turns at most at `rate`. */
static int rs_panels(double t, double rate) {
  double hp = RS_PANEL_MAX;
  if (rate * hp > RS_PANEL_TURN) hp = RS_PANEL_TURN / rate;
  int np = (int)ceil(fabs(t) / hp);
  return np < 1 ? 1 : np;
}

double rs_residual(const ap_system_def *def, double t, const double *q, const double *v,
                   double *scale) {
  double A[256], a0[16], worst = 0.0, sc = 0.0;
  int b = def->b, k = def->k;
  if (scale) *scale = 0.0;
  if (b == 0) return 0.0;
  if (b > 16 || k > 16 || b * k > 256) return -1.0;
  memset(A, 0, sizeof A);
  memset(a0, 0, sizeof a0);
  if (def->constraint(t, q, A, a0, def->user) != 0) return -1.0;
  for (int s = 0; s < b; s++) {
    double r = a0[s], mag = fabs(a0[s]);
    for (int c = 0; c < k; c++) {
      r += A[s + b * c] * v[c];
      mag += fabs(A[s + b * c] * v[c]);
    }
    if (fabs(r) > worst) worst = fabs(r);
    if (mag > sc) sc = mag;
  }
  if (scale) *scale = sc;
  return worst;
}

/* ========================================================================================== */
/* 1. Knife edge on an incline.                                                               */

static const char *const knife_coords[] = {"x", "y", "phi"};

static int knife_metric(double t, const double *q, double *g, void *user) {
  const rs_knife *p = user;
  (void)t, (void)q;
  g[0] = p->m;
  g[4] = p->m;
  g[8] = p->J;
  return 0;
}

static int knife_force(double t, const double *q, const double *v, double *Q, void *user) {
  const rs_knife *p = user;
  (void)t, (void)q, (void)v;
  Q[0] = p->m * p->grav * sin(p->alpha);
  return 0;
}

static int knife_constraint(double t, const double *q, double *A, double *a0, void *user) {
  (void)t, (void)a0, (void)user;
  A[0] = sin(q[2]);
  A[1] = -cos(q[2]);
  return 0;
}

/* A' = phi' [cos phi, sin phi, 0], a0 = 0. */
static int knife_gamma(double t, const double *q, const double *v, double *gamma, void *user) {
  (void)t, (void)user;
  gamma[0] = -v[2] * (v[0] * cos(q[2]) + v[1] * sin(q[2]));
  return 0;
}

void rs_knife_system(rs_knife *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "knife edge";
  def->n = 3;
  def->k = 3;
  def->b = 1;
  def->metric = knife_metric;
  def->bias_source = AP_BIAS_ZERO;
  def->force = knife_force;
  def->constraint = knife_constraint;
  def->gamma = knife_gamma;
  def->coord_names = knife_coords;
  def->user = p;
}

void rs_knife_initial(double x0, double y0, double phi0, double u0, double w0, double q0[3],
                      double v0[3]) {
  q0[0] = x0;
  q0[1] = y0;
  q0[2] = phi0;
  v0[0] = u0 * cos(phi0);
  v0[1] = u0 * sin(phi0);
  v0[2] = w0;
}

void rs_knife_exact(const rs_knife *p, const double q0[3], const double v0[3], double t,
                    double *q, double *v, double *lambda) {
  double G = p->grav * sin(p->alpha), w = v0[2], phi0 = q0[2], phi = phi0 + w * t;
  double u0 = v0[0] * cos(phi0) + v0[1] * sin(phi0);
  double c = u0 - (G / w) * sin(phi0);
  double u = u0 + (G / w) * (sin(phi) - sin(phi0));
  double s = sin(phi), s0 = sin(phi0);
  if (q) {
    q[0] = q0[0] + c * (s - s0) / w + G * (s * s - s0 * s0) / (2.0 * w * w);
    q[1] = q0[1] - c * (cos(phi) - cos(phi0)) / w +
           (G / w) * (t / 2.0 - (sin(2.0 * phi) - sin(2.0 * phi0)) / (4.0 * w));
    q[2] = phi;
  }
  if (v) {
    v[0] = u * cos(phi);
    v[1] = u * sin(phi);
    v[2] = w;
  }
  if (lambda) lambda[0] = -p->m * w * u - p->m * G * s;
}

double rs_knife_energy(const rs_knife *p, const double *q, const double *v) {
  return 0.5 * p->m * (v[0] * v[0] + v[1] * v[1]) + 0.5 * p->J * v[2] * v[2] -
         p->m * p->grav * q[0] * sin(p->alpha);
}

/* ========================================================================================== */
/* 2. Chaplygin sleigh.                                                                        */

static const char *const sleigh_coords[] = {"x", "y", "theta"};

static int sleigh_metric(double t, const double *q, double *g, void *user) {
  const rs_sleigh *p = user;
  double ma = p->m * p->a, s = sin(q[2]), c = cos(q[2]);
  (void)t;
  g[0] = p->m;
  g[4] = p->m;
  g[8] = p->I + p->m * p->a * p->a;
  g[2] = g[6] = -ma * s;   /* (2,0), (0,2) */
  g[5] = g[7] = ma * c;    /* (2,1), (1,2) */
  return 0;
}

/* Only g_02 and g_12 depend on q, and only through theta (block 2). */
static int sleigh_metric_deriv(double t, const double *q, double *dg, void *user) {
  const rs_sleigh *p = user;
  double ma = p->m * p->a, *d2 = dg + 18;
  (void)t;
  d2[2] = d2[6] = -ma * cos(q[2]);
  d2[5] = d2[7] = -ma * sin(q[2]);
  return 0;
}

/* The centripetal term of the centre of mass C = P + a e1: h = -m a w^2 e1 (Christoffel). */
static int sleigh_bias(double t, const double *q, const double *v, double *h, void *user) {
  const rs_sleigh *p = user;
  double maw2 = p->m * p->a * v[2] * v[2];
  (void)t;
  h[0] = -maw2 * cos(q[2]);
  h[1] = -maw2 * sin(q[2]);
  return 0;
}

static int sleigh_constraint(double t, const double *q, double *A, double *a0, void *user) {
  (void)t, (void)a0, (void)user;
  A[0] = -sin(q[2]);
  A[1] = cos(q[2]);
  return 0;
}

/* A' = -theta' [cos theta, sin theta, 0]: gamma = w u. */
static int sleigh_gamma(double t, const double *q, const double *v, double *gamma, void *user) {
  (void)t, (void)user;
  gamma[0] = v[2] * (v[0] * cos(q[2]) + v[1] * sin(q[2]));
  return 0;
}

void rs_sleigh_system(rs_sleigh *p, int explicit_bias, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = explicit_bias ? "sleigh (bias)" : "sleigh (christoffel)";
  def->n = 3;
  def->k = 3;
  def->b = 1;
  def->metric = sleigh_metric;
  if (explicit_bias) {
    def->bias = sleigh_bias;
    def->bias_source = AP_BIAS_CALLBACK;
  } else {
    def->metric_deriv = sleigh_metric_deriv;
    def->bias_source = AP_BIAS_CHRISTOFFEL;
  }
  def->constraint = sleigh_constraint;
  def->gamma = sleigh_gamma;
  def->coord_names = sleigh_coords;
  def->user = p;
}

void rs_sleigh_initial(double x0, double y0, double theta0, double u0, double w0, double q0[3],
                       double v0[3]) {
  q0[0] = x0;
  q0[1] = y0;
  q0[2] = theta0;
  v0[0] = u0 * cos(theta0);
  v0[1] = u0 * sin(theta0);
  v0[2] = w0;
}

/* Closed-form u, w, theta: u' = a w^2, J w' = -m a u w. */
typedef struct sleigh_cf {
  int kind;               /* 0 general, 1 straight line (w0 = 0), 2 a = 0 (uniform turn) */
  double u0, w0, th0, V, k, c, coshc, gdc;
} sleigh_cf;

static double gd(double s) { return 2.0 * atan(tanh(0.5 * s)); }

static sleigh_cf sleigh_setup(const rs_sleigh *p, const double q0[3], const double v0[3]) {
  sleigh_cf f;
  double J = p->I + p->m * p->a * p->a;
  memset(&f, 0, sizeof f);
  f.th0 = q0[2];
  f.u0 = v0[0] * cos(f.th0) + v0[1] * sin(f.th0);
  f.w0 = v0[2];
  if (f.w0 == 0.0) {
    f.kind = 1;
  } else if (p->a == 0.0) {
    f.kind = 2;
  } else {
    f.V = sqrt(f.u0 * f.u0 + (J / p->m) * f.w0 * f.w0);
    f.k = p->a * p->m * f.V / J;
    f.c = atanh(f.u0 / f.V);
    f.coshc = cosh(f.c);
    f.gdc = gd(f.c);
  }
  return f;
}

static void sleigh_uwth(const sleigh_cf *f, double t, double *u, double *w, double *th) {
  if (f->kind == 1) {
    *u = f->u0, *w = 0.0, *th = f->th0;
  } else if (f->kind == 2) {
    *u = f->u0, *w = f->w0, *th = f->th0 + f->w0 * t;
  } else {
    double s = f->k * t + f->c;
    *u = f->V * tanh(s);
    *w = f->w0 * f->coshc / cosh(s);
    *th = f->th0 + (f->w0 * f->coshc / f->k) * (gd(s) - f->gdc);
  }
}

void rs_sleigh_exact(const rs_sleigh *p, const double q0[3], const double v0[3], double t,
                     double *q, double *v) {
  sleigh_cf f = sleigh_setup(p, q0, v0);
  double u, w, th;
  sleigh_uwth(&f, t, &u, &w, &th);
  if (v) {
    v[0] = u * cos(th);
    v[1] = u * sin(th);
    v[2] = w;
  }
  if (!q) return;
  /* x' = u cos theta, y' = u sin theta: the fastest rates are |w| <= |w0| cosh c and k. */
  double xg[RS_GL_N], wg[RS_GL_N], X = 0.0, Y = 0.0;
  double rate = fabs(f.w0) * (f.kind == 0 ? f.coshc : 1.0) + fabs(f.k);
  int np = rs_panels(t, rate);
  double hp = t / np;
  rs_gauss_legendre(RS_GL_N, xg, wg);
  for (int i = 0; i < np; i++) {
    double mid = (i + 0.5) * hp, px = 0.0, py = 0.0;
    for (int j = 0; j < RS_GL_N; j++) {
      double uj, wj, thj;
      sleigh_uwth(&f, mid + 0.5 * hp * xg[j], &uj, &wj, &thj);
      px += wg[j] * uj * cos(thj);
      py += wg[j] * uj * sin(thj);
    }
    X += 0.5 * hp * px;
    Y += 0.5 * hp * py;
  }
  q[0] = q0[0] + X;
  q[1] = q0[1] + Y;
  q[2] = th;
}

double rs_sleigh_energy(const rs_sleigh *p, const double *q, const double *v) {
  double u = v[0] * cos(q[2]) + v[1] * sin(q[2]), J = p->I + p->m * p->a * p->a;
  return 0.5 * p->m * u * u + 0.5 * J * v[2] * v[2];
}

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

/* ========================================================================================== */
/* 5. Hoffmann's two-rod pendulum.                                                             */

static const char *const hoff_coords2[] = {"theta", "phi"};
static const char *const hoff_coords4[] = {"theta", "phi", "y", "z"};
static const char *const hoff_rows[] = {"hinge y", "hinge z"};

void rs_hoffmann_printed(const rs_hoffmann *p, const double q2[2], double g[4], double Q[2]) {
  double th = q2[0], ph = q2[1];
  g[0] = p->I1 + p->m1 * p->a1 * p->a1 + 4.0 * p->m2 * p->a1 * p->a1;
  g[1] = g[2] = 2.0 * p->m2 * p->a1 * p->a2 * cos(th - ph);
  g[3] = p->I2 + p->m2 * p->a2 * p->a2;
  Q[0] = -(p->m1 + 2.0 * p->m2) * p->grav * p->a1 * sin(th) + 2.0 * p->a1 * p->F * cos(th);
  Q[1] = p->a2 * p->F * cos(ph) - p->a2 * p->m2 * p->grav * sin(ph);
}

/* Primitive M (diagonal), F and the connection Jacobian C = d(theta, phi, y, z)/d(theta, phi). */
static void hoff_primitive(const rs_hoffmann *p, const double q2[2], double M[4], double F[4],
                           double C[8]) {
  double th = q2[0], ph = q2[1];
  M[0] = p->I1 + p->m1 * p->a1 * p->a1;
  M[1] = p->I2;
  M[2] = M[3] = p->m2;
  F[0] = -p->m1 * p->grav * p->a1 * sin(th);
  F[1] = 0.0;
  F[2] = p->F;
  F[3] = -p->m2 * p->grav;
  double Cc[8] = {1.0, 0.0, 2.0 * p->a1 * cos(th), 2.0 * p->a1 * sin(th),   /* column theta */
                  0.0, 1.0, p->a2 * cos(ph), p->a2 * sin(ph)};              /* column phi */
  memcpy(C, Cc, sizeof Cc);
}

void rs_hoffmann_connected(const rs_hoffmann *p, const double q2[2], double g[4], double Q[2]) {
  double M[4], F[4], C[8];
  hoff_primitive(p, q2, M, F, C);
  for (int a = 0; a < 2; a++) {
    Q[a] = 0.0;
    for (int i = 0; i < 4; i++) Q[a] += C[i + 4 * a] * F[i];
    for (int b = 0; b < 2; b++) {
      double s = 0.0;
      for (int i = 0; i < 4; i++) s += C[i + 4 * a] * M[i] * C[i + 4 * b];
      g[a + 2 * b] = s;
    }
  }
}

static int hoff_reduced_metric(double t, const double *q, double *g, void *user) {
  double Q[2];
  (void)t;
  rs_hoffmann_printed(user, q, g, Q);
  return 0;
}

/* d g_01 / d theta = -2 m2 a1 a2 sin(theta - phi) = -d g_01 / d phi. */
static int hoff_reduced_metric_deriv(double t, const double *q, double *dg, void *user) {
  const rs_hoffmann *p = user;
  double d = 2.0 * p->m2 * p->a1 * p->a2 * sin(q[0] - q[1]);
  (void)t;
  dg[1] = dg[2] = -d;        /* block theta */
  dg[4 + 1] = dg[4 + 2] = d; /* block phi */
  return 0;
}

static int hoff_reduced_force(double t, const double *q, const double *v, double *Q,
                              void *user) {
  double g[4];
  (void)t, (void)v;
  rs_hoffmann_printed(user, q, g, Q);
  return 0;
}

void rs_hoffmann_reduced_system(rs_hoffmann *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "Hoffmann pendulum (reduced)";
  def->n = 2;
  def->k = 2;
  def->b = 0;
  def->metric = hoff_reduced_metric;
  def->metric_deriv = hoff_reduced_metric_deriv;
  def->bias_source = AP_BIAS_CHRISTOFFEL;
  def->force = hoff_reduced_force;
  def->coord_names = hoff_coords2;
  def->user = p;
}

static int hoff_prim_metric(double t, const double *q, double *g, void *user) {
  double M[4], F[4], C[8];
  (void)t;
  hoff_primitive(user, q, M, F, C);
  for (int i = 0; i < 4; i++) g[i + 4 * i] = M[i];
  return 0;
}

static int hoff_prim_force(double t, const double *q, const double *v, double *Q, void *user) {
  double M[4], C[8];
  (void)t, (void)v;
  hoff_primitive(user, q, M, Q, C);
  return 0;
}

/* Rows y' - 2 a1 cos(theta) theta' - a2 cos(phi) phi' = 0 and the same for z with sines. */
static int hoff_prim_constraint(double t, const double *q, double *A, double *a0, void *user) {
  const rs_hoffmann *p = user;
  (void)t, (void)a0;
  A[0 + 2 * 0] = -2.0 * p->a1 * cos(q[0]);
  A[0 + 2 * 1] = -p->a2 * cos(q[1]);
  A[0 + 2 * 2] = 1.0;
  A[1 + 2 * 0] = -2.0 * p->a1 * sin(q[0]);
  A[1 + 2 * 1] = -p->a2 * sin(q[1]);
  A[1 + 2 * 3] = 1.0;
  return 0;
}

static int hoff_prim_gamma(double t, const double *q, const double *v, double *gamma,
                           void *user) {
  const rs_hoffmann *p = user;
  double t2 = v[0] * v[0], p2 = v[1] * v[1];
  (void)t;
  gamma[0] = -(2.0 * p->a1 * sin(q[0]) * t2 + p->a2 * sin(q[1]) * p2);
  gamma[1] = 2.0 * p->a1 * cos(q[0]) * t2 + p->a2 * cos(q[1]) * p2;
  return 0;
}

void rs_hoffmann_primitive_system(rs_hoffmann *p, ap_system_def *def) {
  *def = ap_system_def_default();
  def->name = "Hoffmann pendulum (primitive + connection)";
  def->n = 4;
  def->k = 4;
  def->b = 2;
  def->metric = hoff_prim_metric;
  def->bias_source = AP_BIAS_ZERO;
  def->force = hoff_prim_force;
  def->constraint = hoff_prim_constraint;
  def->gamma = hoff_prim_gamma;
  def->coord_names = hoff_coords4;
  def->constraint_names = hoff_rows;
  def->user = p;
}

void rs_hoffmann_lift(const rs_hoffmann *p, const double q2[2], const double v2[2],
                      double q4[4], double v4[4]) {
  double th = q2[0], ph = q2[1];
  q4[0] = th;
  q4[1] = ph;
  q4[2] = 2.0 * p->a1 * sin(th) + p->a2 * sin(ph);
  q4[3] = -2.0 * p->a1 * cos(th) - p->a2 * cos(ph);
  v4[0] = v2[0];
  v4[1] = v2[1];
  v4[2] = 2.0 * p->a1 * cos(th) * v2[0] + p->a2 * cos(ph) * v2[1];
  v4[3] = 2.0 * p->a1 * sin(th) * v2[0] + p->a2 * sin(ph) * v2[1];
}

double rs_hoffmann_energy(const rs_hoffmann *p, const double q2[2], const double v2[2]) {
  double g[4], Q[2], th = q2[0], ph = q2[1];
  rs_hoffmann_printed(p, q2, g, Q);
  double T = 0.5 * (g[0] * v2[0] * v2[0] + 2.0 * g[2] * v2[0] * v2[1] + g[3] * v2[1] * v2[1]);
  double V = -(p->m1 + 2.0 * p->m2) * p->grav * p->a1 * cos(th) -
             p->m2 * p->grav * p->a2 * cos(ph) -
             p->F * (2.0 * p->a1 * sin(th) + p->a2 * sin(ph));
  return T + V;
}

void rs_hoffmann_equilibrium(const rs_hoffmann *p, double q2[2]) {
  q2[0] = atan2(2.0 * p->F, (p->m1 + 2.0 * p->m2) * p->grav);
  q2[1] = atan2(p->F, p->m2 * p->grav);
}
