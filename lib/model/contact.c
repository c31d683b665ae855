/* Contacts of a body's shape with the ground plane z = 0: rolling and the wheel's knife edge
 * (docs/design.md §1 "Constraint kinds"; docs/bodies.md "Wheel contacts").
 *
 * The contact point is the shape's support point in the direction u = -R^T e_z (body axes):
 * c_b = grad sigma(u), with Hessian H = grad^2 sigma(u) (shape.c), contact vector rc = R c_b
 * and world point x = o + rc, whose height is o_z + e_z . rc = o_z - sigma(u). A body on a
 * plane-contact joint keeps x on the plane by construction and its geometry lives in the joint's
 * scratch (kinematics.c). Any other body (a wheel on a revolute joint of a chassis, a free
 * body) gets its own geometry block (kwheel, written at the end of the position stage) and one
 * implicit holonomic row, the contact row .z:
 *
 *     phi = o_z - sigma(u),     phi' = e_z . vP,   vP = vo + w x rc  (the material point)
 *
 * since d sigma / dt = c_b . u' = rc . (w x e_z) with u' = R^T (w x e_z): the support point's
 * motion over the surface drops out of the first derivative. The row is projected with the loop
 * closures after each step (evaluate.c) and is a GGL row of the DAE mode (ap_bm_phi).
 *
 * Rows, with the ground surface velocity Vg(x, t) (horizontal; constraint.c):
 *   rolling       e_i . (vP - Vg(x)), i = x, y;  no-spin e_z . w - Omega;  contact e_z . vP
 *   wheel knife   n . (vP - Vg(x)), n = R e_z the wheel axis: no velocity across the wheel
 *                 plane;  contact e_z . vP
 * Along the motion (v fixed) the material point's velocity changes at
 *   aP = ao + al x rc + w x (w x rc) + w x R c_b',   c_b' = H u',
 * where w x R c_b' is the contact point moving over the body surface (rc' = w x rc + R c_b'),
 * and the ground's velocity at the rate Ag taken along the geometric contact point
 * x' = vP + R c_b'. Hence gamma_i = -e_i . (aP - Ag) (Ag_z = 0) and for the knife
 * gamma = -((w x n) . (vP - Vg) + n . (aP - Ag)). For a sphere w x R c_b' cancels
 * w x (w x rc) exactly (rc' = 0).
 * Generic in the scalar (model/model.h; contact_cs.c); contact forces are double build only. */
#include <string.h>

#include "model/model.h"

static const ap_sc EZ[3] = {0, 0, 1};

kwheel ap_contact_geom(const ap_bmodel *M, ap_sc *S, const ap_mcon *c) {
  if (c->wheel >= 0) {
    ap_sc *p = S + M->off_wheel + (size_t)c->wheel * WHEEL_STRIDE;
    kwheel W;
#define KW_VIEW(f, c) W.f = p + KW_##f;
    KWHEEL_FIELDS(KW_VIEW)   /* model/model.h */
#undef KW_VIEW
    return W;
  }
  kjoint J = ap_kin_joint(M, S, M->bodies[c->def.body].joint);
  kwheel W = {J.u, J.cb, J.H, J.rc, J.track};
  return W;
}

/* ---- position stage ------------------------------------------------------------------------ */

int ap_contact_position(const ap_model *m, ap_data *d, double t, ap_sc *S) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->wheel < 0) continue;
    const ap_mbody *B = &M->bodies[c->def.body];
    kbody C = ap_kin_body(M, S, c->def.body);
    kwheel W = ap_contact_geom(M, S, c);
    ap_sc sigma;
    double flat;
    W.u[0] = -C.R[2], W.u[1] = -C.R[5], W.u[2] = -C.R[8];
    if (ap_shape_support(&B->shape, W.u, &sigma, W.cb, W.H, &flat) != 0) {
      AP_BM_MSG(d, "model '%s': body '%s': the %s of constraint '%s' lies flat on the ground "
                "plane at t = %.17g (its axis, the body z axis, is %.3g degrees from the "
                "vertical; flat_tol %.3g): the contact point is undefined (a wheel on an axle "
                "needs its joint frame turned so that body z lies along the axle)", m->name,
                B->name, B->shape.kind == AP_SHAPE_DISK ? "disk" : "torus", c->name, t,
                asin(fmin(1.0, flat)) * 57.29577951308232, B->shape.flat_tol);
      return AP_RECOVERABLE;
    }
    m3_mul_v(C.R, W.cb, W.rc);
  }
  return AP_OK;
}

/* ---- the contact row (holonomic) ----------------------------------------------------------- */

ap_sc ap_contact_hol_row(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, ap_sc *row) {
  ap_sc *JP = S + M->off_tmp, x[3];
  kwheel W = ap_contact_geom(M, S, c);
  ap_kin_point(M, S, c->def.body, W.cb, x, NULL, JP);
  for (int col = 0; col < M->K1; col++) row[col] = JP[2 + 3 * col];
  return x[2];
}

/* ---- rows ------------------------------------------------------------------------------------ */

/* Row r of A and a0: c3 . (JP [v; 1]) - minus. */
static void put_row3(const ap_bmodel *M, ap_sc *A, ap_sc *a0, int r, const ap_sc *c3,
                     const ap_sc *JP, ap_sc minus) {
  int k = M->k, b = M->b;
  for (int col = 0; col < k; col++) A[r + (size_t)col * b] = v3_dot(c3, JP + 3 * col);
  a0[r] = v3_dot(c3, JP + 3 * k) - minus;
}

void ap_con_contact_rows(const ap_bmodel *M, ap_sc *S, int ci, const ap_sc *G, ap_sc *A,
                         ap_sc *a0) {
  static const ap_sc ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc *JP = S + M->off_tmp, x[3], Vg[3], n[3];
  ap_kin_point(M, S, c->def.body, W.cb, x, NULL, JP);
  ap_con_ground_velocity(c, G, x, Vg);
  if (c->def.kind == AP_CON_ROLLING) {
    put_row3(M, A, a0, c->row, ex, JP, Vg[0]);
    put_row3(M, A, a0, c->row + 1, ey, JP, Vg[1]);
    if (c->def.no_spin) put_row3(M, A, a0, c->row + 2, EZ, C.Jw, G[0]);
  } else {
    m3_mul_v(C.R, EZ, n);
    put_row3(M, A, a0, c->row, n, JP, v3_dot(n, Vg));
  }
  if (c->nhol) put_row3(M, A, a0, c->row + c->hrow, EZ, JP, 0.0);
}

/* ---- gamma ----------------------------------------------------------------------------------- */

/* Velocity vP and rate aP of the material contact point (with the surface term when surface),
 * geometric contact point x and its velocity xd. */
static void contact_motion(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int surface,
                           ap_sc *vP, ap_sc *aP, ap_sc *x, ap_sc *xd) {
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc Rcd[3] = {0, 0, 0};
  ap_kin_point_motion(M, S, c->def.body, W.rc, vP, aP);   /* ao + al x rc + w x (w x rc) */
  if (surface) {
    ap_sc wxe[3], ud[3], cd[3];
    v3_cross(C.w, EZ, wxe);
    m3t_mul_v(C.R, wxe, ud);                               /* u' = R^T (w x e_z) */
    m3_mul_v(W.H, ud, cd);                                 /* c_b' = H u' */
    m3_mul_v(C.R, cd, Rcd);
    v3_cross_add(C.w, Rcd, aP);                            /* + w x R c_b' */
  }
  for (int i = 0; i < 3; i++) x[i] = C.o[i] + W.rc[i], xd[i] = vP[i] + Rcd[i];
}

void ap_con_contact_gamma(const ap_bmodel *M, ap_sc *S, int ci, const ap_sc *G, int surface,
                          ap_sc *gamma) {
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc vP[3], aP[3], x[3], xd[3], Ag[3];
  contact_motion(M, S, c, surface, vP, aP, x, xd);
  ap_con_ground_accel(c, G, x, xd, Ag);
  if (c->def.kind == AP_CON_ROLLING) {
    gamma[c->row] = -(aP[0] - Ag[0]);
    gamma[c->row + 1] = -(aP[1] - Ag[1]);
    if (c->def.no_spin) gamma[c->row + 2] = -(C.al[2] - G[1]);
  } else {
    ap_sc n[3], wn[3], Vg[3], g = 0.0;
    m3_mul_v(C.R, EZ, n);
    v3_cross(C.w, n, wn);
    ap_con_ground_velocity(c, G, x, Vg);
    for (int i = 0; i < 3; i++) g += wn[i] * (vP[i] - Vg[i]) + n[i] * (aP[i] - Ag[i]);
    gamma[c->row] = -g;
  }
  if (c->nhol) gamma[c->row + c->hrow] = -aP[2];
}

/* ---- forces on a subtree (contact forces) ----------------------------------------------------- */
#ifndef AP_SC_COMPLEX

void ap_con_contact_force(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                          double *F) {
  if (c->def.kind == AP_CON_ROLLING) {
    F[0] += lam[0], F[1] += lam[1];
  } else {
    double n[3];
    m3_mul_v(ap_kin_body(M, S, c->def.body).R, EZ, n);
    v3_axpy(lam[0], n, F);
  }
  if (c->nhol) F[2] += lam[c->hrow];
}
#endif
