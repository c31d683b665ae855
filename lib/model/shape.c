/* Support functions of the convex shapes, for the plane-contact joint (docs/design.md §1).
 *
 * sigma(u) = max over shape points p of p . u (body axes, shape centred at the body origin,
 * symmetry axis body z). sigma is positively homogeneous of degree 1, so its gradient
 * c(u) = grad sigma (the support point: the contact point when u = -R^T e_z) has degree 0 and
 * its Hessian H(u) degree -1, with H u = 0. With P = diag(1, 1, 0) and u_p = P u:
 *
 *   point      sigma = 0
 *   sphere     sigma = r |u|               c = r u/|u|             H = r (I - uu^T/|u|^2)/|u|
 *   ellipsoid  sigma = s = sqrt(u^T D2 u)  c = D2 u / s            H = (D2 - c c^T) / s
 *   disk       sigma = r |u_p|             c = r u_p/|u_p|         H = r (P - p p^T)/|u_p|,
 *                                                                  p = u_p/|u_p|
 *   torus      disk (radius) + sphere (tube)
 *
 * The disk and the torus are singular when u_p = 0 (lying flat: every rim point touches).
 * Invariant: no division by |u_p| below flat_tol |u|; the caller gets 1 and reports it.
 * Generic in the scalar (model/model.h; shape_cs.c): the flatness test looks at real parts. */
#include <math.h>
#include <string.h>

#include "model/model.h"

static void sphere_part(double r, const ap_sc *u, ap_sc *sigma, ap_sc *c, ap_sc *H) {
  ap_sc n = v3_norm(u);
  *sigma += r * n;
  for (int i = 0; i < 3; i++) c[i] += r * u[i] / n;
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      H[i + 3 * j] += r * ((i == j ? 1.0 : 0.0) - u[i] * u[j] / (n * n)) / n;
}

static void disk_part(double r, const ap_sc *u, ap_sc rho, ap_sc *sigma, ap_sc *c, ap_sc *H) {
  ap_sc up[3] = {u[0], u[1], 0.0};
  *sigma += r * rho;
  for (int i = 0; i < 2; i++) c[i] += r * up[i] / rho;
  for (int j = 0; j < 2; j++)
    for (int i = 0; i < 2; i++)
      H[i + 3 * j] += r * ((i == j ? 1.0 : 0.0) - up[i] * up[j] / (rho * rho)) / rho;
}

static void ellipsoid(const double *ax, const ap_sc *u, ap_sc *sigma, ap_sc *c, ap_sc *H) {
  ap_sc w[3];
  double D2[3] = {ax[0] * ax[0], ax[1] * ax[1], ax[2] * ax[2]};
  for (int i = 0; i < 3; i++) w[i] = D2[i] * u[i];
  ap_sc s = SC_SQRT(v3_dot(u, w));
  *sigma = s;
  for (int i = 0; i < 3; i++) c[i] = w[i] / s;
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++) H[i + 3 * j] = ((i == j ? D2[i] : 0.0) - c[i] * c[j]) / s;
}

int ap_shape_support(const ap_shape *s, const ap_sc *u, ap_sc *sigma, ap_sc *c, ap_sc *H,
                     double *flat) {
  ap_sc n = v3_norm(u), rho = SC_HYPOT(u[0], u[1]);
  *sigma = 0.0;
  memset(c, 0, 3 * sizeof *c);
  memset(H, 0, 9 * sizeof *H);
  *flat = 1.0;
  switch (s->kind) {
    case AP_SHAPE_NONE:
    case AP_SHAPE_POINT:
      return 0;
    case AP_SHAPE_SPHERE:
      sphere_part(s->radius, u, sigma, c, H);
      return 0;
    case AP_SHAPE_ELLIPSOID:
      ellipsoid(s->semi_axes, u, sigma, c, H);
      return 0;
    case AP_SHAPE_DISK:
    case AP_SHAPE_TORUS:
      *flat = SC_RE(rho) / SC_RE(n);
      if (!(*flat >= s->flat_tol)) return 1;
      disk_part(s->radius, u, rho, sigma, c, H);
      if (s->kind == AP_SHAPE_TORUS) sphere_part(s->tube, u, sigma, c, H);
      return 0;
  }
  return 0;
}
