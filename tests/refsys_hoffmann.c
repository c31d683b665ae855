/* Reference system 5 of refsys.h (docs/references.md §6): Hoffmann's two-rod pendulum by
 * Kron's method, as the printed reduced system (theta, phi) and as the primitive 4-coordinate
 * system with the two hinge rows, with its lift, energy and equilibrium.
 *
 * The callbacks return the founding paper's objects (docs/design.md §1), column-major, outputs
 * pre-zeroed by the core so only non-zero entries are written. */
#include "refsys.h"

#include <math.h>
#include <string.h>

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
