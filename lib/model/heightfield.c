/* Rolling on a fixed height field z = h(x, y) (ap_ground_motion.height_fn; docs/scenes.md
 * "Terrain"): the contact point, the gap and the constraint's gamma (contact.c keeps the rows).
 *
 * Ground point p = (p_x, p_y, h), normal n = N / |N| with N = (-h_x, -h_y, 1). The shape's
 * point facing the ground is its support point along u = -R^T n(p) (shape.c):
 * x = o + R c_b, c_b = grad sigma(u). The closest-point conditions say that x - p lies along N:
 *
 *     F_i(p) = x_i - p_i + (x_z - h) h_i = 0,   i = x, y      (then x - p = (x_z - h) N)
 *
 * solved by Newton's method (each step halved until h is defined and |F| decreases) from the
 * last solution (the body origin's (x, y) the first time), with
 *     dF_i/dp_j = dx_i/dp_j - delta_ij + (dx_z/dp_j - h_j) h_i + (x_z - h) h_ij,
 *     dx/dp_j = -R H R^T dn/dp_j,  dn/dp_j = (I - n n^T) dN/dp_j / |N|,  dN/dp_j = -(h_xj, h_yj, 0)
 * (H the Hessian of sigma). The closest point is unique (a minimum of the distance, the shape
 * touching at one point) while -dF/dp has eigenvalues of positive real part: det > 0 and
 * trace < 0 of dF/dp; for a sphere of radius r at a level point of the ground with Hessian K,
 * dF/dp = -(I - r K): a ground curving up more sharply than the ball would touch it twice.
 * The contact row is the gap phi = n . (x - p), whose gradient is n . JP of the material point
 * (p moves in the tangent plane, n . n' = 0, and n . R H = 0 since H u = 0), so contact.c's rows
 * hold with the frame (n, t1, t2) at p (t1 = e_y x n / |e_y x n|, t2 = n x t1).
 *
 * Along the motion (v fixed) the ground point moves at p' = -(dF/dp)^-1 dF/dt|_p with
 * dF_i/dt|_p = X_i + X_z h_i, X = vP + R H R^T (w x n) (x's rate at fixed n), and
 *     N' = -(h_xx p_x' + h_xy p_y', h_xy p_x' + h_yy p_y', 0),  n' = (I - n n^T) N' / |N|,
 *     t1' = (a' - t1 (t1 . a')) / |a|, a = e_y x n,  t2' = n' x t1 + n x t1';
 * the support point moves over the body at c_b' = H R^T (w x n - n'), so the material point's
 * rate is aP = ao + al x rc + w x (w x rc) + w x R c_b'. Each row c . vP (c = t1, t2, n, or
 * the wheel axis R e_z of a knife edge) has gamma = -(c' . vP + c . aP); no-spin n . w has
 * -(n' . w + n . al). This is exact off the contact manifold too (the finite-difference check
 * runs at random states; without n' it fails). Double build only: h comes from a C function
 * of doubles, so the complex-step build refuses the model (evaluate.c ap_bm_cs_blocker). */
#include <math.h>
#include <stdio.h>

#include "model/model.h"

#define HF_ITER 40          /* Newton iterations before giving up */
#define HF_TOL 1e-10        /* |dp| below HF_TOL (1 + |p|): one more step, then done */

/* Ground values at p = hf[HF_P]: h and derivatives, |N|, n; returns the callback's status. */
static int ground_at(const ap_mcon *c, double *hf) {
  double hv[6];
  int rc = c->def.ground.height_fn(hf[HF_P], hf[HF_P + 1], hv, c->def.ground.height_user);
  for (int i = 0; i < 6; i++) rc |= !isfinite(hv[i]);
  if (rc) return -1;
  hf[HF_H] = hv[0];
  for (int i = 0; i < 5; i++) hf[HF_GRAD + i] = hv[1 + i];
  double N[3] = {-hv[1], -hv[2], 1.0}, nN = v3_norm(N);
  hf[HF_NN] = nN;
  for (int i = 0; i < 3; i++) hf[HF_N + i] = N[i] / nN;
  return 0;
}

/* dn/dp_j (j = 0, 1) into Dn (3 x 2, column-major) from the stored h derivatives. */
static void normal_jacobian(const double *hf, double *Dn) {
  const double *n = hf + HF_N, *hs = hf + HF_HESS;
  double DN[6] = {-hs[0], -hs[1], 0.0, -hs[1], -hs[2], 0.0};
  for (int j = 0; j < 2; j++) {
    double nd = v3_dot(n, DN + 3 * j);
    for (int i = 0; i < 3; i++) Dn[i + 3 * j] = (DN[i + 3 * j] - n[i] * nd) / hf[HF_NN];
  }
}

/* y = R H R^T x. */
static void rhrt(const double *R, const double *H, const double *x, double *y) {
  double a[3], b[3];
  m3t_mul_v(R, x, a);
  m3_mul_v(H, a, b);
  m3_mul_v(R, b, y);
}

/* The support point and F, dF/dp at hf's p: writes W.u, cb, H, rc, hf[HF_J]; F (2). */
static int support_at(const ap_mbody *B, const kbody *C, kwheel *W, const ap_mcon *c,
                      double *F, double *flat) {
  double *hf = W->hf, sigma, Dn[6];
  if (ground_at(c, hf)) return -1;
  for (int i = 0; i < 3; i++) W->u[i] = -v3_dot(C->R + 3 * i, hf + HF_N);
  if (ap_shape_support(&B->shape, W->u, &sigma, W->cb, W->H, flat) != 0) return 1;
  m3_mul_v(C->R, W->cb, W->rc);
  double x[3], gz = C->o[2] + W->rc[2] - hf[HF_H];
  for (int i = 0; i < 3; i++) x[i] = C->o[i] + W->rc[i];
  for (int i = 0; i < 2; i++) F[i] = x[i] - hf[HF_P + i] + gz * hf[HF_GRAD + i];
  normal_jacobian(hf, Dn);
  for (int j = 0; j < 2; j++) {
    double dx[3];
    rhrt(C->R, W->H, Dn + 3 * j, dx);
    for (int i = 0; i < 3; i++) dx[i] = -dx[i];
    double hij[2] = {hf[HF_HESS + j], hf[HF_HESS + j + 1]};   /* h_xj, h_yj */
    for (int i = 0; i < 2; i++)
      hf[HF_J + i + 2 * j] = dx[i] - (i == j) + (dx[2] - hf[HF_GRAD + j]) * hf[HF_GRAD + i] +
                             gz * hij[i];
  }
  return 0;
}

/* The frame's tangents t1 = e_y x n / |e_y x n|, t2 = n x t1 (n_z > 0 on a height field). */
static void frame_tangents(double *hf) {
  const double *n = hf + HF_N;
  double *t1 = hf + HF_T1, a = hypot(n[0], n[2]);
  t1[0] = n[2] / a, t1[1] = 0.0, t1[2] = -n[0] / a;
  v3_cross(n, t1, hf + HF_T2);
}

static int fail(const ap_model *m, ap_data *d, double t, const ap_mcon *c, const char *why,
                const double *hf) {
  AP_BM_MSG(d, "model '%s': body '%s', constraint '%s' (height field): %s at the ground point "
            "(%.9g, %.9g) at t = %.17g", m->name, ap_bm(m)->bodies[c->def.body].name, c->name,
            why, hf[HF_P], hf[HF_P + 1], t);
  return AP_RECOVERABLE;
}

/* After convergence: the closest point is a unique minimum, or the ground is too curved. */
static int check_unique(const ap_model *m, ap_data *d, double t, const ap_mcon *c,
                        const double *hf) {
  const double *J = hf + HF_J, *hs = hf + HF_HESS;
  double det = J[0] * J[3] - J[1] * J[2], tr = J[0] + J[3];
  if (det > 0 && tr < 0) return AP_OK;
  double mid = 0.5 * (hs[0] + hs[2]), rad = hypot(0.5 * (hs[0] - hs[2]), hs[1]);
  char why[320];
  snprintf(why, sizeof why, "the ground curves more sharply than the shape (h's Hessian has "
           "eigenvalues %.6g and %.6g 1/m; closest-point Jacobian det %.3g, trace %.3g): the "
           "shape would touch the ground at more than one point, so the contact point is not "
           "unique (smooth the height field or use a smaller shape)", mid + rad, mid - rad, det,
           tr);
  return fail(m, d, t, c, why, hf);
}

/* One damped Newton step from hf's p with residual F (updated): the full step dp, halved
 * until h is defined there and |F| decreases (taken whole once |dp| is below the tolerance,
 * where |F| is round-off). Returns the full step's length, or -1 when no step is acceptable
 * (*rc: the last evaluation's status). */
static double newton_step(const ap_mbody *B, const kbody *C, kwheel *W, const ap_mcon *c,
                          double *F, double *flat, int *rc) {
  double *hf = W->hf, *J = hf + HF_J, det = J[0] * J[3] - J[1] * J[2];
  double dp[2] = {-(J[3] * F[0] - J[2] * F[1]) / det, -(J[0] * F[1] - J[1] * F[0]) / det};
  double p0[2] = {hf[HF_P], hf[HF_P + 1]}, F0 = hypot(F[0], F[1]), full = hypot(dp[0], dp[1]);
  if (!isfinite(full)) return -1.0;
  int tiny = full <= HF_TOL * (1.0 + hypot(p0[0], p0[1]));
  for (double lam = 1.0; lam > 1e-9; lam *= 0.5) {
    hf[HF_P] = p0[0] + lam * dp[0], hf[HF_P + 1] = p0[1] + lam * dp[1];
    *rc = support_at(B, C, W, c, F, flat);
    if (*rc == 0 && (tiny || hypot(F[0], F[1]) < F0)) return full;
  }
  return -1.0;
}

int ap_hf_position(const ap_model *m, ap_data *d, double t, double *S, const ap_mcon *c) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mbody *B = &M->bodies[c->def.body];
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  double *hf = W.hf, F[2], flat, last = 0.0;
  if (hf[HF_SET] != 1.0 || !isfinite(hf[HF_P]) || !isfinite(hf[HF_P + 1]))
    hf[HF_P] = C.o[0], hf[HF_P + 1] = C.o[1];
  hf[HF_SET] = 0.0;
  int rc = support_at(B, &C, &W, c, F, &flat), small = 0;
  for (int it = 0; it < HF_ITER && rc == 0 && last >= 0; it++) {
    last = newton_step(B, &C, &W, c, F, &flat, &rc);
    small = last >= 0 && last <= HF_TOL * (1.0 + hypot(hf[HF_P], hf[HF_P + 1])) ? small + 1 : 0;
    if (small >= 2) {   /* one more step after the first below the tolerance: round-off */
      hf[HF_SET] = 1.0;
      frame_tangents(hf);
      return check_unique(m, d, t, c, hf);
    }
  }
  if (rc < 0) return fail(m, d, t, c, "the height h(x, y) or one of its derivatives is not finite "
                          "(or its function failed)", hf);
  if (rc > 0)
    return fail(m, d, t, c, "the disk or torus lies flat against the ground (its contact point "
                "is undefined)", hf);
  char why[240];
  snprintf(why, sizeof why, "Newton's method on the closest-point conditions did not converge "
           "(%s; residual %.3g m): no closest point near the last one", last < 0 ?
           "no step reduced the residual" : "iterations exhausted", hypot(F[0], F[1]));
  return fail(m, d, t, c, why, hf);
}

double ap_hf_gap(const double *hf, const double *x) {
  double p[3] = {hf[HF_P], hf[HF_P + 1], hf[HF_H]}, r[3];
  for (int i = 0; i < 3; i++) r[i] = x[i] - p[i];
  return v3_dot(hf + HF_N, r);
}

/* p' = -(dF/dp)^-1 (X_xy + X_z grad h) and n' for the material point velocity vP. */
static void point_rate(const kbody *C, const kwheel *W, const double *vP, double *nd) {
  const double *hf = W->hf, *n = hf + HF_N, *J = hf + HF_J, *hs = hf + HF_HESS;
  double wxn[3], X[3], Ft[2];
  v3_cross(C->w, n, wxn);
  rhrt(C->R, W->H, wxn, X);
  for (int i = 0; i < 3; i++) X[i] += vP[i];
  for (int i = 0; i < 2; i++) Ft[i] = X[i] + X[2] * hf[HF_GRAD + i];
  double det = J[0] * J[3] - J[1] * J[2];
  double pd0 = -(J[3] * Ft[0] - J[2] * Ft[1]) / det, pd1 = -(J[0] * Ft[1] - J[1] * Ft[0]) / det;
  double Nd[3] = {-(hs[0] * pd0 + hs[1] * pd1), -(hs[1] * pd0 + hs[2] * pd1), 0.0};
  double nn = v3_dot(n, Nd);
  for (int i = 0; i < 3; i++) nd[i] = (Nd[i] - n[i] * nn) / hf[HF_NN];
}

/* t1' and t2' from n' (the tangents of frame_tangents). */
static void tangent_rates(const double *hf, const double *nd, double *t1d, double *t2d) {
  const double *n = hf + HF_N, *t1 = hf + HF_T1;
  double a = hypot(n[0], n[2]), ad[3] = {nd[2], 0.0, -nd[0]}, ta = v3_dot(t1, ad);
  for (int i = 0; i < 3; i++) t1d[i] = (ad[i] - t1[i] * ta) / a;
  v3_cross(nd, t1, t2d);
  v3_cross_add(n, t1d, t2d);
}

void ap_hf_gamma(const ap_bmodel *M, double *S, const ap_mcon *c, int curvature,
                 double *gamma) {
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  const double *hf = W.hf, *n = hf + HF_N;
  double vP[3], aP[3], nd[3] = {0, 0, 0}, t1d[3], t2d[3], e[3], Rcd[3];
  ap_kin_point_motion(M, S, c->def.body, W.rc, vP, aP);   /* ao + al x rc + w x (w x rc) */
  if (curvature) point_rate(&C, &W, vP, nd);
  v3_cross(C.w, n, e);
  for (int i = 0; i < 3; i++) e[i] -= nd[i];               /* R u' = w x n - n' */
  rhrt(C.R, W.H, e, Rcd);                                  /* R c_b' */
  v3_cross_add(C.w, Rcd, aP);
  if (c->def.kind == AP_CON_ROLLING) {
    tangent_rates(hf, nd, t1d, t2d);
    gamma[c->row] = -(v3_dot(t1d, vP) + v3_dot(hf + HF_T1, aP));
    gamma[c->row + 1] = -(v3_dot(t2d, vP) + v3_dot(hf + HF_T2, aP));
    if (c->def.no_spin) gamma[c->row + 2] = -(v3_dot(nd, C.w) + v3_dot(n, C.al));
  } else {   /* the wheel's knife edge: its axis R e_z turns with the body */
    double a[3] = {C.R[6], C.R[7], C.R[8]}, wa[3];
    v3_cross(C.w, a, wa);
    gamma[c->row] = -(v3_dot(wa, vP) + v3_dot(a, aP));
  }
  gamma[c->row + c->hrow] = -(v3_dot(nd, vP) + v3_dot(n, aP));
}
