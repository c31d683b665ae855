/* Kinematics of the body tree: positions, Jacobians, velocities, bias accelerations, g and h.
 *
 * Joints are visited parents first. For a joint with parent p (R_p, o_p, w_p; zero for the
 * ground), frames F_P = (R_p Rpf, o_p + r1) and F_C = (R_FP Rj, o_FP + r2), child
 * R_c = R_FC Rcf^T, o_c = o_FC - r3, where r1 = R_p ppf, r2 = R_FP tj, r3 = R_c pcf:
 *
 *   w_c  = w_p + wrel,                      wrel = R_FP Sw vj
 *   vo_c = vo_p + w_p x (r1 + r2) + vrel - w_c x r3,   vrel = R_FP Sv vj
 *
 * which gives the Jacobians column by column (3 x K1; column k is the rheonomic part from the
 * driven speeds f'). Differentiating at fixed v (free speeds' v' = 0, driven ones f''):
 *
 *   al_c = al_p + w_p x wrel + R_FP Sw f''
 *   ao_c = ao_p + al_p x (r1 + r2) + w_p x (w_p x (r1 + r2)) + 2 w_p x vrel
 *          + R_FP (Sv' vj + Sv f'') - al_c x r3 - w_c x (w_c x r3)
 *
 * (Sv' vj is non-zero only for the plane contact: e_z ((e_z x rc') . w), rc' = w x rc + R H u',
 * u' = R^T (w x e_z): the contact point moving over the surface.) Exact; no differences.
 *
 * Convention for Appell's equations g v' + h = Q (docs/design.md §1): with the com Jacobian
 * Jc = Jo - [R com]x Jw and the com bias ac = ao + al x rcom + w x (w x rcom),
 *   g = sum_b m Jc^T Jc + Jw^T Iw Jw,   h = sum_b m Jc^T ac + Jw^T (Iw al + w x Iw w),
 * Iw = R I R^T (inertia about the com in world axes): dS/dv' of the Gibbs-Appell function.
 * Generic in the scalar (model/model.h; kinematics_cs.c); the layout is double build only. */
#include <stdio.h>
#include <string.h>

#include "linalg/linalg.h"
#include "model/model.h"

static const ap_sc ZERO3[3] = {0, 0, 0};

#ifndef AP_SC_COMPLEX
/* The sections of the scratch, one table (core/arena.h; guard words between them in the guard
 * build, which the core checks after every stage on the dense path). */
void ap_kin_layout(ap_bmodel *M) {
  size_t K1 = (size_t)M->K1, k = (size_t)M->k, nl = (size_t)M->nloop;
  M->body_stride = KBODY_FIXED + 9 * K1;
  M->proj_work = nl ? ap_la_work_size(M->k, M->nloop) : 0;
  M->proj_iwork = nl ? (ap_la_iwork_size(M->k, M->nloop) * sizeof(int) + sizeof(double) - 1) /
                           sizeof(double) : 0;
  size_t tmp = 6 * K1 + 2 * k + (size_t)M->max_user_rows * (k + 2) + 16;
  size_t proj = nl ? nl * k + 2 * nl + 2 * k + (size_t)M->n + M->proj_work + M->proj_iwork : 0;
  ap_arena *L = &M->layout;
  ap_arena_init(L, "body model scratch", sizeof(double), AP_ARENA_GUARDS);
  M->off_body = L->e[ap_arena_add(L, "bodies", (size_t)M->nb * M->body_stride)].offset;
  M->off_joint = L->e[ap_arena_add(L, "joints", (size_t)M->nj * JOINT_STRIDE)].offset;
  M->off_con = L->e[ap_arena_add(L, "constraints", (size_t)M->nc * CON_STRIDE)].offset;
  M->off_wheel = L->e[ap_arena_add(L, "wheels", (size_t)M->nwheel * WHEEL_STRIDE)].offset;
  M->off_cnt = L->e[ap_arena_add(L, "effect counters", (size_t)M->ne)].offset;
  M->off_tmp = L->e[ap_arena_add(L, "assembly scratch", tmp)].offset;
  M->off_proj = L->e[ap_arena_add(L, "loop projection", proj)].offset;
  M->off_fric = L->e[ap_arena_add(L, "contact modes", ap_cfr_scratch_size(M))].offset;
  M->scratch = L->total;
}
#endif

/* out[:, c] += J[:, c] x r for the first ncol columns (the velocity of an offset point). Without
 * drives ncol = k: the rheonomic column k is zero everywhere and is not touched. */
static void cols_cross_r(int ncol, const ap_sc *J, const ap_sc *r, ap_sc *out) {
  for (int c = 0; c < ncol; c++) v3_cross_add(J + 3 * c, r, out + 3 * c);
}

void ap_kin_apply(int K1, const ap_sc *J, const ap_sc *v, ap_sc *out) {
  int k = K1 - 1;
  v3_copy(J + 3 * k, out);
  for (int c = 0; c < k; c++) v3_axpy(v[c], J + 3 * c, out);
}

/* ---- position stage ---------------------------------------------------------------------- */

/* Drives are functions of the real time: their values are real in both builds. */
static int call_drives(const ap_model *m, ap_data *d, const ap_mjoint *j, double t,
                       ap_sc *drv) {
  for (int i = 0; i < j->ndrivable; i++) {
    if (!j->drive[i]) continue;
    double f[3] = {0.0, 0.0, 0.0};
    int rc = j->drive[i](t, f, j->drive_user[i]);
    const char *cn = ap_joint_coord_name(j->kind, i);
    if (rc != 0) {
      AP_BM_MSG(d, "model '%s': joint '%s': the drive of coordinate '%s' %s (returned %d) at "
                "t = %.17g", m->name, j->name, cn, rc > 0 ? "asked for a smaller step" :
                "failed", rc, t);
      return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
    }
    if (!isfinite(f[0]) || !isfinite(f[1]) || !isfinite(f[2])) {
      AP_BM_MSG(d, "model '%s': joint '%s': the drive of coordinate '%s' gave (%g, %g, %g) at "
                "t = %.17g", m->name, j->name, cn, f[0], f[1], f[2], t);
      return AP_ERR_NAN;
    }
    drv[3 * i] = f[0], drv[3 * i + 1] = f[1], drv[3 * i + 2] = f[2];
  }
  return AP_OK;
}

/* Height and contact of a plane-contact body with rotation R: u = -R^T e_z. */
static int plane_contact(const ap_model *m, ap_data *d, const ap_mbody *B, double t,
                         const ap_sc *R, kjoint *J, ap_sc *z) {
  double flat;
  J->u[0] = -R[2], J->u[1] = -R[5], J->u[2] = -R[8];
  if (ap_shape_support(&B->shape, J->u, z, J->cb, J->H, &flat) != 0) {
    AP_BM_MSG(d, "model '%s': body '%s': the %s lies flat on the ground plane at t = %.17g "
              "(its axis is %.3g degrees from the vertical; flat_tol %.3g): the contact point "
              "is undefined", m->name, B->name, B->shape.kind == AP_SHAPE_DISK ? "disk" :
              "torus", t, asin(fmin(1.0, flat)) * 57.29577951308232, B->shape.flat_tol);
    return AP_RECOVERABLE;
  }
  m3_mul_v(R, J->cb, J->rc);
  return AP_OK;
}

#ifndef AP_SC_COMPLEX
int ap_kin_drives(const ap_model *m, ap_data *d, int j, double t, double *S) {
  const ap_bmodel *M = ap_bm(m);
  return call_drives(m, d, &M->joints[j], t, ap_kin_joint(M, S, j).drv);
}

int ap_kin_plane(const ap_model *m, ap_data *d, int j, double t, const double *Rj, double *S,
                 double *z) {
  const ap_bmodel *M = ap_bm(m);
  kjoint J = ap_kin_joint(M, S, j);
  return plane_contact(m, d, &M->bodies[M->joints[j].child], t, Rj, &J, z);
}
#endif

/* The joint's own columns into Jw and Jo (world), driven ones into column k. */
static void joint_columns(const ap_bmodel *M, const ap_mjoint *j, kjoint *J, ap_sc *Jw,
                          ap_sc *Jo) {
  int k = M->k;
  memset(J->adw, 0, 3 * sizeof(ap_sc));
  memset(J->adv, 0, 3 * sizeof(ap_sc));
  for (int i = 0; i < j->nv; i++) {
    ap_sc sw[3], sv[3], W[3], V[3];
    ap_joint_column(j, i, J->rc, sw, sv);
    m3_mul_v(J->RFP, sw, W);
    m3_mul_v(J->RFP, sv, V);
    if (j->vidx[i] >= 0) {
      v3_axpy(1.0, W, Jw + 3 * j->vidx[i]);
      v3_axpy(1.0, V, Jo + 3 * j->vidx[i]);
    } else {
      ap_sc f1 = J->drv[3 * i + 1], f2 = J->drv[3 * i + 2];
      v3_axpy(f1, W, Jw + 3 * k), v3_axpy(f1, V, Jo + 3 * k);
      v3_axpy(f2, W, J->adw), v3_axpy(f2, V, J->adv);
    }
  }
}

static int joint_position(const ap_model *m, ap_data *d, const ap_mjoint *j, double t,
                          const ap_sc *q, ap_sc *S) {
  const ap_bmodel *M = ap_bm(m);
  size_t K3 = 3 * (size_t)M->K1;
  kjoint J = ap_kin_joint(M, S, (int)(j - M->joints));
  kbody C = ap_kin_body(M, S, j->child);
  int rc = call_drives(m, d, j, t, J.drv);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < j->nq; i++) J.qloc[i] = j->qidx[i] >= 0 ? q[j->qidx[i]] : J.drv[3 * i];

  static const ap_sc I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const ap_sc *Rp = I3, *op = ZERO3;
  kbody P = C;   /* replaced by the parent's view when there is one */
  if (j->parent >= 0) P = ap_kin_body(M, S, j->parent), Rp = P.R, op = P.o;
  ap_sc Rj[9], tj[3], RFC[9], r12[3], oFC[3];
  m3_mul_d(Rp, j->Rpf, J.RFP);
  m3_mul_v_d(Rp, j->ppf, J.r1);
  ap_joint_transform(j, J.qloc, Rj, tj);
  if (j->kind == AP_JOINT_PLANE_CONTACT) {
    rc = plane_contact(m, d, &M->bodies[j->child], t, Rj, &J, &tj[2]);
    if (rc != AP_OK) return rc;
  }
  m3_mul_v(J.RFP, tj, J.r2);
  m3_mul(J.RFP, Rj, RFC);
  m3_mul_t_d(RFC, j->Rcf, C.R);
  m3_mul_v_d(C.R, j->pcf, J.r3);
  for (int i = 0; i < 3; i++) {
    r12[i] = J.r1[i] + J.r2[i];
    oFC[i] = op[i] + r12[i];
    C.o[i] = oFC[i] - J.r3[i];
  }
  /* Jacobians: transport the parent's, add the joint's columns, move to the child origin. */
  if (j->parent >= 0) {
    memcpy(C.Jw, P.Jw, K3 * sizeof(ap_sc));
    memcpy(C.Jo, P.Jo, K3 * sizeof(ap_sc));
    cols_cross_r(M->ncol, P.Jw, r12, C.Jo);
  } else {
    memset(C.Jw, 0, K3 * sizeof(ap_sc));
    memset(C.Jo, 0, K3 * sizeof(ap_sc));
  }
  joint_columns(M, j, &J, C.Jw, C.Jo);
  for (int c = 0; c < M->ncol; c++) v3_cross_add(J.r3, C.Jw + 3 * c, C.Jo + 3 * c);
  return AP_OK;
}

/* World inertia, com offset and com Jacobian of a body. */
static void body_mass(const ap_bmodel *M, const ap_mbody *B, kbody *C) {
  ap_sc T[9];
  m3_mul_d(C->R, B->I, T);
  m3_mul_t(T, C->R, C->Iw);
  m3_mul_v_d(C->R, B->com, C->rcom);
  memcpy(C->Jc, C->Jo, 3 * (size_t)M->K1 * sizeof(ap_sc));
  cols_cross_r(M->ncol, C->Jw, C->rcom, C->Jc);
}

int ap_kin_position(const ap_model *m, ap_data *d, double t, const ap_sc *q, ap_sc *S) {
  const ap_bmodel *M = ap_bm(m);
  for (int j = 0; j < M->nj; j++) {
    int rc = joint_position(m, d, &M->joints[j], t, q, S);
    if (rc != AP_OK) return rc;
  }
  for (int b = 0; b < M->nb; b++) {
    kbody C = ap_kin_body(M, S, b);
    body_mass(M, &M->bodies[b], &C);
  }
  return M->nwheel ? ap_contact_position(m, d, t, S) : AP_OK;
}

/* ---- velocity stage ---------------------------------------------------------------------- */

/* e_z ((e_z x rc') . w): the rate of the height's Jacobian row (plane contact). */
static void plane_bias(const kbody *C, const kjoint *J, ap_sc *a) {
  static const ap_sc ez[3] = {0, 0, 1};
  ap_sc wxe[3], ud[3], cd[3], rcd[3], e[3];
  v3_cross(C->w, ez, wxe);
  m3t_mul_v(C->R, wxe, ud);          /* u' = R^T (w x e_z) */
  m3_mul_v(J->H, ud, cd);            /* c' = H u' */
  m3_mul_v(C->R, cd, rcd);
  v3_cross_add(C->w, J->rc, rcd);    /* rc' = w x rc + R c' */
  v3_cross(ez, rcd, e);
  a[2] += v3_dot(e, C->w);
}

static void joint_velocity(const ap_bmodel *M, const ap_mjoint *j, const ap_sc *v,
                           ap_sc *S) {
  kjoint J = ap_kin_joint(M, S, (int)(j - M->joints));
  kbody C = ap_kin_body(M, S, j->child);
  const ap_sc *wp = ZERO3, *vp = ZERO3, *alp = ZERO3, *ap = ZERO3;
  if (j->parent >= 0) {
    kbody P = ap_kin_body(M, S, j->parent);
    wp = P.w, vp = P.vo, alp = P.al, ap = P.ao;
  }
  ap_kin_apply(M->K1, C.Jw, v, C.w);
  ap_kin_apply(M->K1, C.Jo, v, C.vo);
  for (int i = 0; i < j->nv; i++) J.vloc[i] = j->vidx[i] >= 0 ? v[j->vidx[i]] : J.drv[3 * i + 1];
  ap_sc wrel[3], vrel[3], r12[3], a[3];
  for (int i = 0; i < 3; i++) wrel[i] = C.w[i] - wp[i], r12[i] = J.r1[i] + J.r2[i];
  /* vrel = (vo_c + w_c x r3) - (vo_p + w_p x r1) - w_p x r2 */
  for (int i = 0; i < 3; i++) vrel[i] = C.vo[i] - vp[i];
  v3_cross_add(C.w, J.r3, vrel);
  v3_cross_add(r12, wp, vrel);
  /* angular bias */
  v3_copy(alp, C.al);
  v3_cross_add(wp, wrel, C.al);
  v3_axpy(1.0, J.adw, C.al);
  /* linear bias of the child frame origin, then of the body origin */
  ap_sc wr[3];
  v3_copy(ap, a);
  v3_cross_add(alp, r12, a);
  v3_cross(wp, r12, wr);
  v3_cross_add(wp, wr, a);
  v3_cross(wp, vrel, wr);
  v3_axpy(2.0, wr, a);
  v3_axpy(1.0, J.adv, a);
  if (j->kind == AP_JOINT_PLANE_CONTACT) plane_bias(&C, &J, a);
  v3_cross(C.al, J.r3, wr);
  v3_axpy(-1.0, wr, a);
  ap_sc w3[3];
  v3_cross(C.w, J.r3, w3);
  v3_cross(C.w, w3, wr);
  v3_axpy(-1.0, wr, a);
  v3_copy(a, C.ao);
}

void ap_kin_velocity(const ap_bmodel *M, const ap_sc *v, ap_sc *S) {
  for (int j = 0; j < M->nj; j++) joint_velocity(M, &M->joints[j], v, S);
}

/* ---- g and h ----------------------------------------------------------------------------- */

void ap_kin_metric(const ap_bmodel *M, ap_sc *S, ap_sc *g) {
  int k = M->k;
  for (int b = 0; b < M->nb; b++) {
    const ap_mbody *B = &M->bodies[b];
    kbody C = ap_kin_body(M, S, b);
    for (int ib = 0; ib < B->ncols; ib++) {
      int cb = B->cols[ib];
      ap_sc IJ[3];
      m3_mul_v(C.Iw, C.Jw + 3 * cb, IJ);
      for (int ia = 0; ia <= ib; ia++) {
        int ca = B->cols[ia];
        ap_sc s = B->mass * v3_dot(C.Jc + 3 * ca, C.Jc + 3 * cb) + v3_dot(C.Jw + 3 * ca, IJ);
        g[ca + (size_t)cb * k] += s;
        if (ca != cb) g[cb + (size_t)ca * k] += s;
      }
    }
  }
}

void ap_kin_bias(const ap_bmodel *M, ap_sc *S, ap_sc *h) {
  for (int b = 0; b < M->nb; b++) {
    const ap_mbody *B = &M->bodies[b];
    kbody C = ap_kin_body(M, S, b);
    ap_sc ac[3], t[3], hw[3], Iww[3];
    v3_copy(C.ao, ac);
    v3_cross_add(C.al, C.rcom, ac);
    v3_cross(C.w, C.rcom, t);
    v3_cross_add(C.w, t, ac);
    m3_mul_v(C.Iw, C.al, hw);
    m3_mul_v(C.Iw, C.w, Iww);
    v3_cross_add(C.w, Iww, hw);
    for (int i = 0; i < B->ncols; i++) {
      int c = B->cols[i];
      h[c] += B->mass * v3_dot(C.Jc + 3 * c, ac) + v3_dot(C.Jw + 3 * c, hw);
    }
  }
}

/* ---- points ------------------------------------------------------------------------------ */

void ap_kin_point(const ap_bmodel *M, ap_sc *S, int body, const ap_sc *p, ap_sc *x, ap_sc *r,
                  ap_sc *JP) {
  size_t K3 = 3 * (size_t)M->K1;
  if (body < 0) {
    if (x) v3_copy(p, x);
    if (r) memset(r, 0, 3 * sizeof *r);
    if (JP) memset(JP, 0, K3 * sizeof *JP);
    return;
  }
  kbody C = ap_kin_body(M, S, body);
  ap_sc rr[3];
  m3_mul_v(C.R, p, rr);
  if (x) x[0] = C.o[0] + rr[0], x[1] = C.o[1] + rr[1], x[2] = C.o[2] + rr[2];
  if (r) v3_copy(rr, r);
  if (JP) {
    memcpy(JP, C.Jo, K3 * sizeof *JP);
    cols_cross_r(M->ncol, C.Jw, rr, JP);
  }
}

#ifdef AP_SC_COMPLEX
void ap_kin_point_d(const ap_bmodel *M, ap_sc *S, int body, const double *p, ap_sc *x,
                    ap_sc *r, ap_sc *JP) {
  ap_sc pp[3] = {p[0], p[1], p[2]};
  ap_kin_point(M, S, body, pp, x, r, JP);
}
#endif

void ap_kin_point_motion(const ap_bmodel *M, ap_sc *S, int body, const ap_sc *r, ap_sc *vp,
                         ap_sc *ap) {
  if (body < 0) {
    if (vp) memset(vp, 0, 3 * sizeof *vp);
    if (ap) memset(ap, 0, 3 * sizeof *ap);
    return;
  }
  kbody C = ap_kin_body(M, S, body);
  ap_sc t[3];
  if (vp) {
    v3_copy(C.vo, vp);
    v3_cross_add(C.w, r, vp);
  }
  if (ap) {
    v3_copy(C.ao, ap);
    v3_cross_add(C.al, r, ap);
    v3_cross(C.w, r, t);
    v3_cross_add(C.w, t, ap);
  }
}
