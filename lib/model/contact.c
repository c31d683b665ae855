/* Contacts of a body's shape with the ground: rolling and the wheel's knife edge, on the plane
 * z = 0 (below), on a tilted plane n . x = offset (plane_rows, plane_gamma: e_z, e_x, e_y
 * replaced by n and its tangents t1, t2) or a fixed sphere (a ball; sphere_gamma: n turns with
 * the ball's centre) for bodies not on a plane-contact joint; each kind's table at the end
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
#include <stdio.h>
#include <string.h>

#include "model/builder.h"
#include "model/con_friction.h"
#include "model/con_kind.h"

static const ap_sc EX[3] = {1, 0, 0}, EY[3] = {0, 1, 0}, EZ[3] = {0, 0, 1};

/* Tangents of the unit normal n: t1 = e_y x n / |e_y x n|, t2 = n x t1; returns |e_y x n|. */
static ap_sc tangents(const ap_sc *n, ap_sc *t1, ap_sc *t2) {
  ap_sc a = SC_SQRT(n[0] * n[0] + n[2] * n[2]);   /* e_y x n = (n_z, 0, -n_x) */
  t1[0] = n[2] / a, t1[1] = 0.0, t1[2] = -n[0] / a;
  v3_cross(n, t1, t2);
  return a;
}

/* The ground's normal n and tangents t1, t2 (t1 x t2 = n) in this build's scalar at the body
 * origin o: the constants e_z, e_x, e_y for the plane z = 0, copies of the constraint's for a
 * tilted plane, n = gside (o - gc) / |o - gc| on a sphere (*D = |o - gc|); into gf (9). */
static void ground_frame(const ap_mcon *c, const ap_sc *o, const kwheel *W, ap_sc *gf,
                         const ap_sc **n, const ap_sc **t1, const ap_sc **t2, ap_sc *D) {
  *n = EZ, *t1 = EX, *t2 = EY;
  if (!c->plane) return;
  if (c->plane == 3) {   /* a height field: the frame at the ground point (heightfield.c) */
    *n = W->hf + HF_N, *t1 = W->hf + HF_T1, *t2 = W->hf + HF_T2;
    return;
  }
  *n = gf, *t1 = gf + 3, *t2 = gf + 6;
  if (c->plane == 1) {
    v3_copy_d(c->gn, gf), v3_copy_d(c->gt1, gf + 3), v3_copy_d(c->gt2, gf + 6);
    return;
  }
  for (int i = 0; i < 3; i++) gf[i] = o[i] - c->gc[i];
  ap_sc d = v3_norm(gf);
  for (int i = 0; i < 3; i++) gf[i] = c->gside * gf[i] / d;
  tangents(gf, gf + 3, gf + 6);
  if (D) *D = d;
}

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
  kwheel W = {J.u, J.cb, J.H, J.rc, J.track, NULL};
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
    if (c->plane == 3) {   /* a height field: Newton on the closest point (heightfield.c) */
#ifdef AP_SC_COMPLEX
      return AP_ERR_UNSUPPORTED;   /* refused earlier by ap_bm_cs_blocker */
#else
      int rc = ap_hf_position(m, d, t, S, c);
      if (rc != AP_OK) return rc;
      continue;
#endif
    }
    if (c->plane) {   /* u = -R^T n */
      ap_sc gf[9];
      const ap_sc *gn, *t1, *t2;
      ground_frame(c, C.o, &W, gf, &gn, &t1, &t2, NULL);
      for (int i = 0; i < 3; i++) W.u[i] = -v3_dot(C.R + 3 * i, gn);
    } else
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

static ap_sc contact_hol_row(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, ap_sc *row) {
  ap_sc *JP = S + M->off_tmp, x[3];
  kwheel W = ap_contact_geom(M, S, c);
  ap_kin_point(M, S, c->def.body, W.cb, x, NULL, JP);
  if (c->plane) {   /* the gap n . x - offset; on a sphere n . (x - gc) - gside grad */
    ap_sc gf[9];
    const ap_sc *gn, *t1, *t2;
    ground_frame(c, ap_kin_body(M, S, c->def.body).o, &W, gf, &gn, &t1, &t2, NULL);
    for (int col = 0; col < M->K1; col++) row[col] = v3_dot(JP + 3 * col, gn);
    if (c->plane == 1) return v3_dot_d(x, c->gn) - c->goff;
#ifndef AP_SC_COMPLEX
    if (c->plane == 3) return ap_hf_gap(W.hf, x);
#endif
    ap_sc g = -c->gside * c->grad;
    for (int i = 0; i < 3; i++) g += gn[i] * (x[i] - c->gc[i]);
    return g;
  }
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

static void contact_rows_g(const ap_bmodel *M, ap_sc *S, int ci, const ap_sc *G, ap_sc *A,
                           ap_sc *a0) {
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc *JP = S + M->off_tmp, x[3], Vg[3], n[3];
  ap_kin_point(M, S, c->def.body, W.cb, x, NULL, JP);
  ap_con_ground_velocity(c, G, x, Vg);
  if (c->def.kind == AP_CON_ROLLING) {
    put_row3(M, A, a0, c->row, EX, JP, Vg[0]);
    put_row3(M, A, a0, c->row + 1, EY, JP, Vg[1]);
    if (c->def.no_spin) put_row3(M, A, a0, c->row + 2, EZ, C.Jw, G[0]);
  } else {
    m3_mul_v(C.R, EZ, n);
    put_row3(M, A, a0, c->row, n, JP, v3_dot(n, Vg));
  }
  if (c->nhol) put_row3(M, A, a0, c->row + c->hrow, EZ, JP, 0.0);
}

/* The same on a tilted plane (fixed): the tangents t1, t2, the normal n for no-spin and .z. */
static void plane_rows(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, ap_sc *A, ap_sc *a0) {
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc *JP = S + M->off_tmp, x[3], n[3], gf[9];
  const ap_sc *gn, *t1, *t2;
  ground_frame(c, C.o, &W, gf, &gn, &t1, &t2, NULL);
  ap_kin_point(M, S, c->def.body, W.cb, x, NULL, JP);
  if (c->def.kind == AP_CON_ROLLING) {
    put_row3(M, A, a0, c->row, t1, JP, 0.0);
    put_row3(M, A, a0, c->row + 1, t2, JP, 0.0);
    if (c->def.no_spin) put_row3(M, A, a0, c->row + 2, gn, C.Jw, 0.0);
  } else {
    m3_mul_v(C.R, EZ, n);
    put_row3(M, A, a0, c->row, n, JP, 0.0);
  }
  if (c->nhol) put_row3(M, A, a0, c->row + c->hrow, gn, JP, 0.0);
}

/* ---- gamma ----------------------------------------------------------------------------------- */

/* Velocity vP and rate aP of the material contact point (with the surface term when surface),
 * geometric contact point x and its velocity xd; gn the ground's normal. */
static void contact_motion(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int surface,
                           const ap_sc *gn, ap_sc *vP, ap_sc *aP, ap_sc *x, ap_sc *xd) {
  kbody C = ap_kin_body(M, S, c->def.body);
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc Rcd[3] = {0, 0, 0};
  ap_kin_point_motion(M, S, c->def.body, W.rc, vP, aP);   /* ao + al x rc + w x (w x rc) */
  if (surface) {
    ap_sc wxe[3], ud[3], cd[3];
    v3_cross(C.w, gn, wxe);
    m3t_mul_v(C.R, wxe, ud);                               /* u' = R^T (w x n) */
    m3_mul_v(W.H, ud, cd);                                 /* c_b' = H u' */
    m3_mul_v(C.R, cd, Rcd);
    v3_cross_add(C.w, Rcd, aP);                            /* + w x R c_b' */
  }
  for (int i = 0; i < 3; i++) x[i] = C.o[i] + W.rc[i], xd[i] = vP[i] + Rcd[i];
}

/* gamma on a tilted plane (fixed: n, t1, t2 constant, no ground motion), from the material
 * point's velocity vP and rate aP. */
static void plane_gamma(const ap_mcon *c, const kbody *C, const ap_sc *gn, const ap_sc *t1,
                        const ap_sc *t2, const ap_sc *vP, const ap_sc *aP, ap_sc *gamma) {
  if (c->def.kind == AP_CON_ROLLING) {
    gamma[c->row] = -v3_dot(t1, aP);
    gamma[c->row + 1] = -v3_dot(t2, aP);
    if (c->def.no_spin) gamma[c->row + 2] = -v3_dot(gn, C->al);
  } else {
    ap_sc n[3], wn[3];
    m3_mul_v(C->R, EZ, n);
    v3_cross(C->w, n, wn);
    gamma[c->row] = -(v3_dot(wn, vP) + v3_dot(n, aP));
  }
  if (c->nhol) gamma[c->row + c->hrow] = -v3_dot(gn, aP);
}

/* gamma on a fixed sphere (a sphere-shaped body; rolling): n = s (o - gc) / D turns as the
 * centre moves, n' = s (vo - n (n . vo)) / D, and the tangents with it (t1 = a / |a|, a = e_y x
 * n: t1' = (a' - t1 (t1 . a')) / |a|, t2' = n' x t1 + n x t1'); the material point rc = -r n
 * has (vP)' = ao + al x rc - r w x n'. Each row c . vP (c = t1, t2, n; no-spin n . w) has
 * gamma = -(c' . vP + c . (vP)'). */
static void sphere_gamma(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, const kbody *C,
                         const ap_sc *n, const ap_sc *t1, const ap_sc *t2, ap_sc D,
                         ap_sc *gamma) {
  kwheel W = ap_contact_geom(M, S, c);
  ap_sc vP[3], aP[3], nd[3], ad[3], t1d[3], t2d[3], tmp[3], wwr[3], r = -v3_dot(W.rc, n);
  ap_sc nv = v3_dot(n, C->vo), ey[3] = {0, 1, 0};
  ap_kin_point_motion(M, S, c->def.body, W.rc, vP, aP);   /* ao + al x rc + w x (w x rc) */
  v3_cross(C->w, W.rc, tmp);
  v3_cross(C->w, tmp, wwr);
  for (int i = 0; i < 3; i++) nd[i] = c->gside * (C->vo[i] - n[i] * nv) / D;
  v3_cross(C->w, nd, tmp);
  for (int i = 0; i < 3; i++) aP[i] += -wwr[i] - r * tmp[i];
  v3_cross(ey, nd, ad);
  ap_sc a = SC_SQRT(n[0] * n[0] + n[2] * n[2]), ta = v3_dot(t1, ad);
  for (int i = 0; i < 3; i++) t1d[i] = (ad[i] - t1[i] * ta) / a;
  v3_cross(nd, t1, t2d);
  v3_cross_add(n, t1d, t2d);
  gamma[c->row] = -(v3_dot(t1d, vP) + v3_dot(t1, aP));
  gamma[c->row + 1] = -(v3_dot(t2d, vP) + v3_dot(t2, aP));
  if (c->def.no_spin) gamma[c->row + 2] = -(v3_dot(nd, C->w) + v3_dot(n, C->al));
  if (c->nhol) gamma[c->row + c->hrow] = -(v3_dot(nd, vP) + v3_dot(n, aP));
}

void ap_con_contact_gamma(const ap_bmodel *M, ap_sc *S, int ci, const ap_sc *G, int surface,
                          ap_sc *gamma) {
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc vP[3], aP[3], x[3], xd[3], Ag[3], gf[9], D = 1.0;
  const ap_sc *gn = EZ, *t1 = EX, *t2 = EY;
  if (c->plane == 3) {   /* a height field; the complex-step build refuses it (cs_blocker) */
#ifndef AP_SC_COMPLEX
    ap_hf_gamma(M, S, c, surface, gamma);
#endif
    return;
  }
  if (c->plane) ground_frame(c, C.o, NULL, gf, &gn, &t1, &t2, &D);   /* planes, spheres */
  if (c->plane == 2) return sphere_gamma(M, S, c, &C, gn, t1, t2, D, gamma);
  contact_motion(M, S, c, surface, gn, vP, aP, x, xd);
  if (c->plane) return plane_gamma(c, &C, gn, t1, t2, vP, aP, gamma);
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

/* ---- this build's evaluation table -------------------------------------------------------- */

static int contact_rows(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                        ap_sc *S, ap_sc *A, ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  (void)d, (void)t, (void)q;
  if (M->cons[ci].plane) plane_rows(M, S, &M->cons[ci], A, a0);
  else contact_rows_g(M, S, ci, ap_con_scratch(M, S, ci), A, a0);
#ifndef AP_SC_COMPLEX
  if (M->cons[ci].fric >= 0) ap_cfr_rows(M, S, &M->cons[ci], A, a0);   /* contact modes */
#endif
  return AP_OK;
}

static int contact_gamma(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                         const ap_sc *v, ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  (void)d, (void)t, (void)q, (void)v;
  ap_con_contact_gamma(M, S, ci, ap_con_scratch(M, S, ci), 1, gamma);
#ifndef AP_SC_COMPLEX
  if (M->cons[ci].fric >= 0) ap_cfr_gamma(M, S, &M->cons[ci], gamma);
#endif
  return AP_OK;
}

static ap_sc contact_hol(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int r, ap_sc *row) {
  (void)r;
#ifndef AP_SC_COMPLEX
  if (c->fric >= 0 && ap_cfr_mode(M, S, c) == AP_CM_AIRBORNE) {   /* no contact row */
    for (int col = 0; col < M->K1; col++) row[col] = 0.0;
    return 0.0;
  }
#endif
  return contact_hol_row(M, S, c, row);
}

#ifndef AP_SC_COMPLEX
/* The gap of contact c (its contact row's value whatever its mode), m; the position stage
 * (kinematics and the contact geometry) must hold. */
double ap_contact_gap(const ap_bmodel *M, double *S, const ap_mcon *c) {
  double *row = S + M->off_tmp + 6 * (size_t)M->K1;
  return contact_hol_row(M, S, c, row);
}
#endif

#ifndef AP_SC_COMPLEX
/* The gap of contact c, m, and its rate at the speeds v (k), m/s, into *rate: the contact
 * row's [v; 1] whatever its mode; the position stage must hold. */
double ap_contact_gap_rate(const ap_bmodel *M, double *S, const ap_mcon *c, const double *v,
                           double *rate) {
  double *row = S + M->off_tmp + 6 * (size_t)M->K1, g = contact_hol_row(M, S, c, row);
  *rate = row[M->k];
  for (int j = 0; j < M->k; j++) *rate += row[j] * v[j];
  return g;
}
#endif

const AP_SC(ap_con_eval) AP_SC(ap_con_contact_eval) = {NULL, contact_rows, contact_gamma,
                                                       contact_hol};

/* ---- double build: compile, names, forces, the tree path; the kind tables ----------------- */
#ifndef AP_SC_COMPLEX
extern const struct ap_con_eval_cs ap_con_contact_eval_cs;

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

/* A fixed sphere (c->plane = 2): rolling of a sphere-shaped body, from outside or inside. */
static int ground_sphere(ap_builder *b, const char *nm, ap_mcon *c) {
  const ap_ground_motion *g = &c->def.ground;
  const ap_shape *sh = &b->bodies[c->def.body].def.shape;
  if (!(g->sphere_radius > 0) || !isfinite(g->sphere_radius) || !ap_cc_finite(g->sphere_center, 3))
    FAIL("constraint '%s': the ground sphere's radius %g must be positive and its centre "
         "finite", nm, g->sphere_radius);
  if (c->def.kind != AP_CON_ROLLING || sh->kind != AP_SHAPE_SPHERE)
    FAIL("constraint '%s': a ground sphere takes rolling of a sphere-shaped body (its shape "
         "kind is %d)", nm, (int)sh->kind);
  if (g->kind != AP_GROUND_FIXED)
    FAIL("constraint '%s': a ground sphere cannot move (a moving ground is the plane z = 0)", nm);
  if (g->inside && !(g->sphere_radius > sh->radius))
    FAIL("constraint '%s': a ball of radius %g does not fit inside a ground sphere of radius %g",
         nm, sh->radius, g->sphere_radius);
  c->plane = 2, c->grad = g->sphere_radius, c->gside = g->inside ? -1 : 1;
  v3_copy(g->sphere_center, c->gc);
  return AP_OK;
}

/* A height field z = h(x, y) (c->plane = 3; heightfield.c): fixed, alone. */
static int ground_height(ap_builder *b, const char *nm, ap_mcon *c) {
  const ap_ground_motion *g = &c->def.ground;
  if (g->kind != AP_GROUND_FIXED || g->sphere_radius != 0.0 || v3_norm(g->normal) != 0.0 ||
      g->offset != 0.0)
    FAIL("constraint '%s': a height-field ground is fixed and alone: no ground motion (kind %d), "
         "sphere (radius %g), normal or offset (%g)", nm, (int)g->kind, g->sphere_radius,
         g->offset);
  c->plane = 3;
  return AP_OK;
}

/* The ground plane n . p = offset: c->plane, gn, gt1 = e_y x n / |.| (e_x for n = e_z; from
 * e_x when n is along e_y), gt2 = n x gt1. A tilted plane cannot move. */
static int ground_plane(ap_builder *b, const char *nm, ap_mcon *c) {
  const ap_ground_motion *g = &c->def.ground;
  if (g->height_fn) return ground_height(b, nm, c);
  if (g->sphere_radius != 0.0) return ground_sphere(b, nm, c);
  double nn = v3_norm(g->normal), ey[3] = {0, 1, 0}, ex[3] = {1, 0, 0};
  if (nn == 0.0 && g->offset == 0.0) return AP_OK;
  if (nn == 0.0) c->gn[0] = c->gn[1] = 0.0, c->gn[2] = 1.0;
  else for (int i = 0; i < 3; i++) c->gn[i] = g->normal[i] / nn;
  if (c->gn[0] == 0.0 && c->gn[1] == 0.0 && c->gn[2] > 0.0 && g->offset == 0.0) return AP_OK;
  if (g->kind != AP_GROUND_FIXED)
    FAIL("constraint '%s': a moving ground (turntable or translating) must be the plane z = 0, "
         "not (%g, %g, %g) . p = %g", nm, c->gn[0], c->gn[1], c->gn[2], g->offset);
  c->plane = 1, c->goff = g->offset;
  v3_cross(ey, c->gn, c->gt1);
  if (v3_norm(c->gt1) < 0.1) {
    v3_cross(c->gn, ex, c->gt2);
    double t = v3_norm(c->gt2);
    for (int i = 0; i < 3; i++) c->gt2[i] /= t;
    v3_cross(c->gt2, c->gn, c->gt1);
    return AP_OK;
  }
  double t = v3_norm(c->gt1);
  for (int i = 0; i < 3; i++) c->gt1[i] /= t;
  v3_cross(c->gn, c->gt1, c->gt2);
  return AP_OK;
}

/* Rolling, or a wheel's knife edge: the shape's lowest point touches the ground. On a
 * plane-contact joint the joint holds it there; on any other joint the constraint adds the
 * contact row .z (last row, holonomic) and a geometry block of its own. */
static int contact_compile(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  int rc = ap_cc_body_ref(b, nm, "body", d->body, 0);
  if (rc == AP_OK) rc = ap_cc_ground(b, nm, &d->ground);
  if (rc != AP_OK) return rc;
  c->timed = d->ground.kind != AP_GROUND_FIXED;
  const ap_mbody *B = &M->bodies[d->body];
  const ap_mjoint *J = &M->joints[B->joint];
  ap_shape_kind sk = B->shape.kind;
  int knife = d->kind == AP_CON_KNIFE_EDGE;
  if (knife && sk != AP_SHAPE_DISK && sk != AP_SHAPE_TORUS)
    FAIL("constraint '%s': a wheel knife edge needs body '%s' to be a disk or a torus (its "
         "shape kind is %d): the wheel plane is its body xy plane", nm, B->name, (int)sk);
  if (sk == AP_SHAPE_NONE)
    FAIL("constraint '%s': rolling needs body '%s' to have a shape (sphere, ellipsoid, disk, "
         "torus or point) touching the ground plane", nm, B->name);
  if (!knife && d->wheel)
    FAIL("constraint '%s': wheel = %d belongs to a knife edge (rolling always uses the shape's "
         "contact point)", nm, d->wheel);
  c->nrows = knife ? 1 : d->no_spin ? 3 : 2;
  c->wheel = -1;
  if (ground_plane(b, nm, c) != AP_OK) return AP_ERR_ARG;
  if (c->plane && J->kind == AP_JOINT_PLANE_CONTACT)
    FAIL("constraint '%s': body '%s' is on a plane-contact joint, which rolls on z = 0 only; "
         "for this ground (%s) put the body on a free joint (or a wheel on its axle)", nm,
         B->name, c->plane == 3 ? "a height field" : c->plane == 2 ? "a sphere" :
         "a tilted or raised plane");
  int modes = d->mu >= 0 || d->unilateral == 1 || isnan(d->mu);   /* NaN: refused below */
  if (modes && c->plane == 3)
    FAIL("constraint '%s': friction and lift-off (mu %g, unilateral %d) are not available on a "
         "height-field ground (it is bilateral and perfectly rough)", nm, d->mu, d->unilateral);
  if (modes && (knife || J->kind == AP_JOINT_PLANE_CONTACT))
    FAIL("constraint '%s': friction and lift-off (mu %g, unilateral %d) need a rolling contact "
         "of a body that is not on a plane-contact joint (a free body, a wheel on its axle): "
         "the plane-contact joint cannot leave the ground", nm, d->mu, d->unilateral);
  if (!(d->restitution >= 0 && d->restitution <= 1) || (d->restitution > 0 && !modes))
    FAIL("constraint '%s': restitution %g: it must lie in [0, 1], on a unilateral contact "
         "(unilateral or friction given)", nm, d->restitution);
  if (modes && (!(d->mu <= 1e300) || (d->mu_kinetic >= 0 && !(d->mu_kinetic <= d->mu)) ||
                isnan(d->mu_kinetic)))
    FAIL("constraint '%s': friction mu = %g, mu_kinetic = %g: mu must be a finite number >= 0 "
         "(or absent: perfectly rough) and mu_kinetic between 0 and mu", nm, d->mu,
         d->mu_kinetic);
  if (J->kind == AP_JOINT_PLANE_CONTACT) return AP_OK;
  c->wheel = M->nwheel++;
  if (modes && c->plane && ap_bm_wheel_by_load(M, c))
    FAIL("constraint '%s': friction and lift-off (mu %g) under a planar chassis use the wheel "
         "loads, which assume level ground z = 0 (this ground: %s): put the chassis on a free "
         "joint (docs/vehicles.md)", nm, d->mu, c->plane == 2 ? "a sphere" : "a tilted or "
         "raised plane");
  c->hrow = c->nrows++;
  c->nhol = 1;
  if (modes) c->fric = M->nfric++;
  return AP_OK;
}

static const char *rolling_suffix(const ap_mcon *c, int r, char *buf) {
  static const char *const xyz[] = {".x", ".y", ".z"};
  (void)buf;
  return r < 2 ? xyz[r] : r == c->hrow && c->nhol ? ".z" : ".spin";
}

static const char *wheel_knife_suffix(const ap_mcon *c, int r, char *buf) {
  (void)c, (void)buf;
  return r == 0 ? ".side" : ".z";
}

/* The force of the rows on the body at the contact point: rolling (lambda_x, lambda_y, 0)
 * (no-spin: a torque lambda e_z), the wheel's knife edge lambda n; the contact row lambda e_z. */
static void contact_force(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                          double *F) {
  double gf[9];
  const double *gn, *t1, *t2;
  kwheel W = ap_contact_geom(M, S, c);
  ground_frame(c, ap_kin_body(M, S, c->def.body).o, &W, gf, &gn, &t1, &t2, NULL);
  if (c->def.kind == AP_CON_ROLLING) {
    v3_axpy(lam[0], t1, F), v3_axpy(lam[1], t2, F);
  } else {
    double n[3];
    m3_mul_v(ap_kin_body(M, S, c->def.body).R, EZ, n);
    v3_axpy(lam[0], n, F);
  }
  if (c->nhol) v3_axpy(lam[c->hrow], gn, F);
  if (c->fric >= 0)   /* sliding; under a planar chassis F_n is the wheel's load */
    ap_cfr_friction_force(M, S, c, ap_bm_wheel_by_load(M, c) ? ap_cfr_normal_force(M, S, c)
                                                              : lam[c->hrow], t1, t2, F);
}

static int contact_wrench(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                          int root, const double *o, double *F, double *T) {
  if (!ap_bm_in_subtree(M, c->def.body, root)) return AP_OK;
  double f[3] = {0, 0, 0}, x[3];
  kwheel W = ap_contact_geom(M, S, c);
  kbody C = ap_kin_body(M, S, c->def.body);
  contact_force(M, S, c, lam, f);
  for (int i = 0; i < 3; i++) x[i] = C.o[i] + W.rc[i];
  ap_bm_add_force(f, x, o, F, T);
  if (T && c->def.kind == AP_CON_ROLLING && c->def.no_spin) T[2] += lam[2];
  return AP_OK;
}

/* The tree path takes a contact on a plane-contact joint and a wheel contact on the plane
 * z = 0 or a fixed tilted plane: every row, the contact row .z among them, is n . vP (or
 * n . w) on the wheel's own twist (docs/large.md). Refused: a wheel contact on a sphere (its
 * normal turns with the centre) and one with friction (contact modes rewrite its rows). */
static int contact_tree_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c,
                             char *why, size_t len) {
  if (c->nhol == 0 && c->wheel < 0) return c->def.body;
  const ap_mjoint *J = &M->joints[M->bodies[c->def.body].joint];
  /* A rolling body on a free joint to another body: with bdf the tree path took 8794 steps where
   * the dense path takes 548 and ended 3e-4 off (1.3e-6); dopri5 and adams agree (difftest seed
   * 1001705, tests/scenes/tree_free_hung.yaml). The contact's phi drifts by 5e-9 per step there,
   * the dense path projects q inside CVODE's step (its ev.phi, a dense Jacobian the tree path
   * does not have), the tree path closes it after the step and so restarts BDF at order 1 after
   * nearly every step from t = 0.164 on: refused. */
  int hung = c->wheel >= 0 && J->kind == AP_JOINT_FREE && J->parent != AP_GROUND;
  if (c->wheel >= 0 && c->plane <= 1 && c->fric < 0 && !hung) return c->def.body;
  snprintf(why, len, "model '%s': constraint '%s' is a wheel contact %s", m->name, c->name,
           hung ? "of a body on a free joint to another body (with bdf the tree path's runs "
                  "of such a body took 16 times the dense path's steps)"
           : c->plane == 2 ? "on a sphere (its normal turns with the wheel)"
           : c->plane > 2 ? "on a curved ground" : "with friction (contact modes)");
  return -1;
}

static void contact_tree_row(const ap_bmodel *Ms, double *S, const ap_mcon *c, int rr,
                             const double *G, const double *rho, double *cv, double *a0) {
  kbody C = ap_kin_body(Ms, S, c->def.body);
  kwheel Wg = ap_contact_geom(Ms, S, c);
  double n[3];   /* the ground's frame: z = 0, or the fixed tilted plane's (contact_tree_body) */
  const double *gn = c->plane ? c->gn : EZ, *t1 = c->plane ? c->gt1 : EX;
  const double *t2 = c->plane ? c->gt2 : EY;
  if (c->nhol && rr == c->hrow) {   /* the contact row: gn . vP (the ground's Vg is tangent) */
    ap_con_tree_point_row(c, G, C.o, Wg.rc, gn, rho, cv, a0);
    return;
  }
  if (c->def.kind == AP_CON_ROLLING && rr == 2) {   /* no spin: gn . w - Omega */
    v3_copy(gn, cv);
    *a0 = v3_dot(gn, rho) - G[AP_G_OM];
    return;
  }
  if (c->def.kind == AP_CON_KNIFE_EDGE) m3_mul_v(C.R, EZ, n);
  else v3_copy(rr == 0 ? t1 : t2, n);
  ap_con_tree_point_row(c, G, C.o, Wg.rc, n, rho, cv, a0);
}

const ap_con_kind ap_con_rolling = {"rolling", contact_compile, rolling_suffix, contact_wrench,
                                    contact_tree_body, contact_tree_row, NULL, 1,
                                    &ap_con_contact_eval, &ap_con_contact_eval_cs};
const ap_con_kind ap_con_wheel_knife = {"knife_edge (wheel)", contact_compile,
                                        wheel_knife_suffix, contact_wrench, contact_tree_body,
                                        contact_tree_row, NULL, 0, &ap_con_contact_eval,
                                        &ap_con_contact_eval_cs};
/* The ground's normal and tangents at the contact of c (world). */
void ap_contact_frame(const ap_bmodel *M, double *S, const ap_mcon *c, double *n, double *t1,
                      double *t2) {
  double gf[9];
  const double *gn, *a, *b;
  kwheel W = ap_contact_geom(M, S, c);
  ground_frame(c, ap_kin_body(M, S, c->def.body).o, &W, gf, &gn, &a, &b, NULL);
  v3_copy(gn, n), v3_copy(a, t1), v3_copy(b, t2);
}
#endif
