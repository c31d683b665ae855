/* Reference systems 1 and 2 of refsys.h (docs/references.md §1, §2): the knife edge on an
 * incline and the Chaplygin sleigh, a blade contact each. q = (x, y, heading) of the contact
 * point, v = q'; one row A = [sin, -cos, 0] (knife) or the sleigh's no-sideslip row.
 *
 * The callbacks return the founding paper's objects (docs/design.md §1), column-major, outputs
 * pre-zeroed by the core so only non-zero entries are written. The exact solutions are the
 * closed forms of docs/references.md; the sleigh's x, y need the composite Gauss-Legendre
 * quadrature of refsys_quad.h. */
#include "refsys.h"

#include <math.h>
#include <string.h>

#include "refsys_quad.h"

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

/* The same blade state as the knife edge's: contact point, heading, speed along the blade. */
void rs_sleigh_initial(double x0, double y0, double theta0, double u0, double w0, double q0[3],
                       double v0[3]) {
  rs_knife_initial(x0, y0, theta0, u0, w0, q0, v0);
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

