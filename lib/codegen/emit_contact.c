/* The contacts, the quaternion blocks of N and gravity on traced values: the support point of a
 * shape on the plane z = 0 (ap_shape_support, shape.c), the rows A, a0 and gamma of rolling and
 * the wheel's knife edge on the fixed plane z = 0 (contact.c: ap_contact_position,
 * contact_rows_g, ap_con_contact_gamma), ap_joint_fill_N (joint.c) and the gravity effect
 * (effect.c), at the model's fixed shapes, masses and row numbers.
 *
 * Mirrors those functions statement by statement, as emit_kin.c mirrors kinematics.c: a change
 * there must be made here too (tests/test_compiled.c compares both paths). Two functions are
 * emitted, each after the stage it completes, reading that stage's values from the scratch:
 *   int apc_rows(q, S, N, A, a0)     after apc_position: the wheel contacts' support points,
 *                                    N's quaternion blocks, the generated constraints' rows;
 *                                    1 when a disk or torus lies flat (the library then runs
 *                                    ap_contact_position, which reports it);
 *   void apc_forces(v, S, Q, gamma)  after apc_velocity: gravity (when every effect is gravity:
 *                                    every entry of Q written) and the generated rows' gamma.
 * A prescribed speed of constant value is generated too (con_speed.c: A's row e_j^T, a0 the
 * negated value, gamma 0; its time scratch is then not written). The other constraints keep
 * the library's code (fast_rows.c calls their tables). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"
#include "model/con_kind.h"

#define ADD(a, b) cg_add(G, a, b)
#define SUB(a, b) cg_sub(G, a, b)
#define MUL(a, b) cg_mul(G, a, b)
#define DIV(a, b) cg_div(G, a, b)

static const double EX[3] = {1, 0, 0}, EY[3] = {0, 1, 0}, EZ[3] = {0, 0, 1};

/* ---- what is generated ------------------------------------------------------------------- */

static int shape_traced(const ap_shape *s) {
  return s->kind == AP_SHAPE_POINT || s->kind == AP_SHAPE_SPHERE ||
         s->kind == AP_SHAPE_ELLIPSOID || s->kind == AP_SHAPE_DISK || s->kind == AP_SHAPE_TORUS;
}

/* Rolling or the wheel's knife edge on the fixed plane z = 0 without contact modes. */
static int contact_traced(const ap_mcon *c) {
  return (c->kind == &ap_con_rolling || c->kind == &ap_con_wheel_knife) && c->plane == 0 &&
         !c->timed && c->fric < 0;
}

int cg_wheels_traced(const ap_bmodel *M) {
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->wheel >= 0 && (!contact_traced(c) || !shape_traced(&M->bodies[c->def.body].shape)))
      return 0;
  }
  return 1;
}

/* A prescribed speed of constant value (no f(t)): row v_j - value, gamma 0. */
static int speed_traced(const ap_mcon *c) {
  return c->kind == &ap_con_speed && !c->def.speed_fn;
}

int cg_con_traced(const ap_bmodel *M, int ci) {
  const ap_mcon *c = &M->cons[ci];
  return speed_traced(c) || (contact_traced(c) && (c->wheel < 0 || cg_wheels_traced(M)));
}

int cg_effects_traced(const ap_bmodel *M) {
  for (int i = 0; i < M->ne; i++)
    if (M->effs[i].def.kind != AP_EFFECT_GRAVITY) return 0;
  return 1;
}

int cg_all_cons_traced(const ap_bmodel *M) {
  for (int ci = 0; ci < M->nc; ci++)
    if (!cg_con_traced(M, ci)) return 0;
  return 1;
}

/* ---- the support point (shape.c) ---------------------------------------------------------- */

static cg_v call2(cg_gen *G, const char *fn, cg_v a, cg_v b) {
  char x[48], y[48];
  cg_text(&a, x, sizeof x), cg_text(&b, y, sizeof y);
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s(%s, %s);\n", r.id, fn, x, y);
  return r;
}

/* sphere_part (dim 3, nrm = |u|) and disk_part (dim 2, nrm = |u_p|) of shape.c: adds r nrm to
 * sigma, r u_i / nrm to c_i and r (delta_ij - u_i u_j / nrm^2) / nrm to H_ij, i, j < dim. */
static void round_part(cg_gen *G, double r, const cg_v *u, int dim, cg_v nrm, cg_v *sigma,
                       cg_v *c, cg_v *H) {
  cg_v R = cg_const(r);
  *sigma = ADD(*sigma, MUL(R, nrm));
  for (int i = 0; i < dim; i++) c[i] = ADD(c[i], DIV(MUL(R, u[i]), nrm));
  for (int j = 0; j < dim; j++)
    for (int i = 0; i < dim; i++)
      H[i + 3 * j] = ADD(H[i + 3 * j], DIV(MUL(R, SUB(cg_const(i == j ? 1.0 : 0.0),
                                                      DIV(MUL(u[i], u[j]), MUL(nrm, nrm)))),
                                           nrm));
}

static void ellipsoid(cg_gen *G, const double *ax, const cg_v *u, cg_v *sigma, cg_v *c,
                      cg_v *H) {
  double D2[3] = {ax[0] * ax[0], ax[1] * ax[1], ax[2] * ax[2]};
  cg_v w[3];
  for (int i = 0; i < 3; i++) w[i] = MUL(cg_const(D2[i]), u[i]);
  cg_v s = cg_call(G, "sqrt", t_dot(G, u, w));
  *sigma = s;
  for (int i = 0; i < 3; i++) c[i] = DIV(w[i], s);
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      H[i + 3 * j] = DIV(SUB(cg_const(i == j ? D2[i] : 0.0), MUL(c[i], c[j])), s);
}

/* ap_shape_support at the traced u: sigma, c, H. A disk or torus within flat_tol of lying flat
 * runs `flat` (C text ending the function) at run time. */
static void support(cg_gen *G, const ap_shape *s, const cg_v *u, cg_v *sigma, cg_v *c, cg_v *H,
                    const char *flat) {
  cg_v n = cg_call(G, "sqrt", t_dot(G, u, u)), rho = call2(G, "hypot", u[0], u[1]);
  *sigma = cg_const(0.0);
  for (int i = 0; i < 3; i++) c[i] = cg_const(0.0);
  for (int i = 0; i < 9; i++) H[i] = cg_const(0.0);
  if (s->kind == AP_SHAPE_SPHERE) round_part(G, s->radius, u, 3, n, sigma, c, H);
  if (s->kind == AP_SHAPE_ELLIPSOID) ellipsoid(G, s->semi_axes, u, sigma, c, H);
  if (s->kind != AP_SHAPE_DISK && s->kind != AP_SHAPE_TORUS) return;
  char x[48], y[48];
  cg_text(&rho, x, sizeof x), cg_text(&n, y, sizeof y);
  cg_printf(G, "  if (!(%s / %s >= %a)) {\n%s  }\n", x, y, s->flat_tol, flat);
  round_part(G, s->radius, u, 2, rho, sigma, c, H);   /* the disk's up = (u0, u1, 0) */
  if (s->kind == AP_SHAPE_TORUS) round_part(G, s->tube, u, 3, n, sigma, c, H);
}

/* The plane contact's support point (kinematics.c plane_contact) in apc_position: u, cb, H, rc
 * into the joint's scratch, the height into *z. 0 when the shape is not traced (the caller
 * then calls the library). When flat, the library's ap_kin_plane runs and reports. */
int cg_plane_support(cg_kin *K, int jx, const cg_v *Rj, kjoint *J, cg_v *z) {
  const ap_mbody *B = &K->M->bodies[K->M->joints[jx].child];
  if (!shape_traced(&B->shape)) return 0;
  cg_gen *G = K->G;
  char flat[600], x[48];
  int len = snprintf(flat, sizeof flat, "    const double R_[9] = {");
  for (int i = 0; i < 9; i++) {
    cg_text(&Rj[i], x, sizeof x);
    len += snprintf(flat + len, sizeof flat - (size_t)len, "%s%s", x, i < 8 ? ", " : "};\n");
  }
  snprintf(flat + len, sizeof flat - (size_t)len,
           "    const int rc_ = plane(ctx, %d, R_, &z[%d]);\n    return rc_ ? rc_ : -1;\n", jx,
           jx);
  cg_v *u = cg_at(K, J->u);
  for (int i = 0; i < 3; i++) u[i] = cg_neg(G, Rj[2 + 3 * i]);
  support(G, &B->shape, u, z, cg_at(K, J->cb), cg_at(K, J->H), flat);
  t_m3v(G, Rj, cg_at(K, J->cb), cg_at(K, J->rc));
  cg_mark(K, J->u, 3), cg_mark(K, J->cb, 3), cg_mark(K, J->H, 9), cg_mark(K, J->rc, 3);
  return 1;
}

/* ---- apc_rows ----------------------------------------------------------------------------- */

static void out(cg_gen *G, const char *arr, size_t i, cg_v v) {
  char x[48];
  cg_text(&v, x, sizeof x);
  cg_printf(G, "  %s[%zu] = %s;\n", arr, i, x);
}

/* The wheel contacts' geometry (ap_contact_position on z = 0): u = -R^T e_z. */
static void wheel_support(cg_kin *K) {
  const ap_bmodel *M = K->M;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->wheel < 0) continue;
    kbody C = ap_kin_body(M, K->base, c->def.body);
    kwheel W = ap_contact_geom(M, K->base, c);
    cg_v *R = cg_at(K, C.R), *u = cg_at(K, W.u), sigma;
    u[0] = cg_neg(K->G, R[2]), u[1] = cg_neg(K->G, R[5]), u[2] = cg_neg(K->G, R[8]);
    support(K->G, &M->bodies[c->def.body].shape, u, &sigma, cg_at(K, W.cb), cg_at(K, W.H),
            "    return 1;\n");
    t_m3v(K->G, R, cg_at(K, W.cb), cg_at(K, W.rc));
    cg_mark(K, W.u, 3), cg_mark(K, W.cb, 3), cg_mark(K, W.H, 9), cg_mark(K, W.rc, 3);
  }
}

/* ap_joint_fill_N, and a zero on N's diagonal where ap_data_create put the identity and the
 * fill puts nothing (so that N needs no zeroing). */
static void fill_N(cg_kin *K) {
  const ap_bmodel *M = K->M;
  cg_gen *G = K->G;
  size_t n = (size_t)M->n, nk = n * (size_t)M->k;
  unsigned char *set = calloc(nk ? nk : 1, 1);
  if (!set) {
    G->fail = 1;
    return;
  }
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    for (int i = 0; i < J->ndrivable; i++)
      if (J->qidx[i] >= 0) {
        size_t at = (size_t)J->qidx[i] + (size_t)J->vidx[i] * n;
        out(G, "N", at, cg_const(1.0)), set[at] = 1;
      }
    if (J->quat < 0) continue;
    size_t row = (size_t)J->qidx[J->quat], col = (size_t)J->vidx[J->wofs];
    cg_v w = MUL(cg_const(0.5), cg_ref('q', row)), x = MUL(cg_const(0.5), cg_ref('q', row + 1));
    cg_v y = MUL(cg_const(0.5), cg_ref('q', row + 2)), z = MUL(cg_const(0.5), cg_ref('q', row + 3));
    cg_v blk[4][3] = {{cg_neg(G, x), cg_neg(G, y), cg_neg(G, z)},
                      {w, z, cg_neg(G, y)},
                      {cg_neg(G, z), w, x},
                      {y, cg_neg(G, x), w}};
    for (size_t r = 0; r < 4; r++)
      for (size_t c = 0; c < 3; c++) {
        size_t at = (row + r) + (col + c) * n;
        out(G, "N", at, blk[r][c]), set[at] = 1;
      }
  }
  for (size_t i = 0; i < n && i < (size_t)M->k; i++)
    if (!set[i + i * n]) out(G, "N", i + i * n, cg_const(0.0));
  free(set);
}

/* put_row3: row r of A and a0 = c3 . (JP [v; 1]) - minus. */
static void put_row3(cg_kin *K, int r, const cg_v *c3, const cg_v *JP, cg_v minus) {
  int k = K->M->k, b = K->M->b;
  for (int col = 0; col < k; col++)
    out(K->G, "A", (size_t)r + (size_t)col * b, t_dot(K->G, c3, JP + 3 * col));
  out(K->G, "a0", (size_t)r, cg_sub(K->G, t_dot(K->G, c3, JP + 3 * k), minus));
}

/* contact_rows_g on the fixed plane z = 0 (Vg = 0, the ground's Omega 0). */
static void contact_rows(cg_kin *K, int ci) {
  const ap_bmodel *M = K->M;
  const ap_mcon *c = &M->cons[ci];
  cg_gen *G = K->G;
  kbody C = ap_kin_body(M, K->base, c->def.body);
  kwheel W = ap_contact_geom(M, K->base, c);
  cg_v *JP = calloc(3 * (size_t)M->K1, sizeof *JP), rr[3], e[3], zero = cg_const(0.0);
  if (!JP) {
    G->fail = 1;
    return;
  }
  cg_v *Jw = cg_at(K, C.Jw), *Gs = cg_at(K, ap_con_scratch(M, K->base, ci));
  t_m3v(G, cg_at(K, C.R), cg_at(K, W.cb), rr);   /* ap_kin_point */
  memcpy(JP, cg_at(K, C.Jo), 3 * (size_t)M->K1 * sizeof *JP);
  for (int col = 0; col < M->ncol; col++) t_cross_add(G, Jw + 3 * col, rr, JP + 3 * col);
  if (c->def.kind == AP_CON_ROLLING) {
    t_consts(EX, 3, e), put_row3(K, c->row, e, JP, zero);
    t_consts(EY, 3, e), put_row3(K, c->row + 1, e, JP, zero);
    if (c->def.no_spin) t_consts(EZ, 3, e), put_row3(K, c->row + 2, e, Jw, Gs[0]);
  } else {
    cg_v ez[3], n[3], Vg[3] = {zero, zero, zero};
    t_consts(EZ, 3, ez);
    t_m3v(G, cg_at(K, C.R), ez, n);
    put_row3(K, c->row, n, JP, t_dot(G, n, Vg));
  }
  if (c->nhol) t_consts(EZ, 3, e), put_row3(K, c->row + c->hrow, e, JP, zero);
  free(JP);
}

/* Entries the function wrote into the scratch: stored, then read back by later stages. */
static void store_scratch(cg_kin *K) {
  cg_kin_store(K, "g", 0);
  for (size_t i = 0; i < K->M->scratch; i++)
    if (K->sh[i].kind != CG_CONST) K->sh[i] = cg_ref('S', i);
}

/* speed_rows (con_speed.c) with f = the constant value: the whole row written. */
static void speed_rows(cg_kin *K, const ap_mcon *c) {
  int k = K->M->k, b = K->M->b;
  for (int col = 0; col < k; col++)
    out(K->G, "A", (size_t)c->row + (size_t)col * b, cg_const(col == c->col ? 1.0 : 0.0));
  out(K->G, "a0", (size_t)c->row, cg_const(-c->def.speed_value));
}

void cg_emit_rows(cg_kin *K) {
  const ap_bmodel *M = K->M;
  cg_tu(K->G);
  cg_printf(K->G, "int apc_rows(const double *q, double *S, double *N, double *A, double *a0) "
            "{\n  (void)q, (void)S, (void)N, (void)A, (void)a0;\n");
  memset(K->wr, 0, M->scratch);
  if (cg_wheels_traced(M)) wheel_support(K);
  if (M->n != M->k) fill_N(K);
  for (int ci = 0; ci < M->nc; ci++)
    if (speed_traced(&M->cons[ci])) speed_rows(K, &M->cons[ci]);
    else if (cg_con_traced(M, ci)) contact_rows(K, ci);
  store_scratch(K);
  cg_printf(K->G, "  return 0;\n}\n\n");
}

/* ---- apc_forces ----------------------------------------------------------------------------- */

/* gravity and add_JtF of effect.c, every effect counted in its scratch slot. */
static void gravity(cg_kin *K, cg_v *Q) {
  const ap_bmodel *M = K->M;
  for (int i = 0; i < M->ne; i++) {
    const ap_effect_def *e = &M->effs[i].def;
    cg_printf(K->G, "  S[%zu] += 1.0;\n", M->off_cnt + (size_t)i);
    for (int b = 0; b < M->nb; b++) {
      const ap_mbody *B = &M->bodies[b];
      kbody C = ap_kin_body(M, K->base, b);
      cg_v F[3], *Jc = cg_at(K, C.Jc);
      for (int r = 0; r < 3; r++) F[r] = cg_const(B->mass * e->gravity[r]);
      for (int ic = 0; ic < B->ncols; ic++) {
        int col = B->cols[ic];
        Q[col] = cg_add(K->G, Q[col], t_dot(K->G, Jc + 3 * col, F));
      }
    }
  }
}

/* ap_con_contact_gamma on the fixed plane z = 0 with the surface term (Ag = 0, Vg = 0). */
static void contact_gamma(cg_kin *K, int ci) {
  const ap_bmodel *M = K->M;
  const ap_mcon *c = &M->cons[ci];
  cg_gen *G = K->G;
  kbody C = ap_kin_body(M, K->base, c->def.body);
  kwheel W = ap_contact_geom(M, K->base, c);
  cg_v *w = cg_at(K, C.w), *R = cg_at(K, C.R), *rc = cg_at(K, W.rc), *al = cg_at(K, C.al);
  cg_v vP[3], aP[3], t[3], ez[3], wxe[3], ud[3], cd[3], Rcd[3], zero = cg_const(0.0);
  cg_v *Gs = cg_at(K, ap_con_scratch(M, K->base, ci));
  t_consts(EZ, 3, ez);
  memcpy(vP, cg_at(K, C.vo), sizeof vP);   /* ap_kin_point_motion */
  t_cross_add(G, w, rc, vP);
  memcpy(aP, cg_at(K, C.ao), sizeof aP);
  t_cross_add(G, al, rc, aP);
  t_cross(G, w, rc, t);
  t_cross_add(G, w, t, aP);
  t_cross(G, w, ez, wxe);                   /* the surface term */
  t_m3tv(G, R, wxe, ud);
  t_m3v(G, cg_at(K, W.H), ud, cd);
  t_m3v(G, R, cd, Rcd);
  t_cross_add(G, w, Rcd, aP);
  if (c->def.kind == AP_CON_ROLLING) {
    out(G, "gamma", (size_t)c->row, cg_neg(G, SUB(aP[0], zero)));
    out(G, "gamma", (size_t)c->row + 1, cg_neg(G, SUB(aP[1], zero)));
    if (c->def.no_spin) out(G, "gamma", (size_t)c->row + 2, cg_neg(G, SUB(al[2], Gs[1])));
  } else {
    cg_v n[3], wn[3], g = zero;
    t_m3v(G, R, ez, n);
    t_cross(G, w, n, wn);
    for (int i = 0; i < 3; i++)
      g = ADD(g, ADD(MUL(wn[i], SUB(vP[i], zero)), MUL(n[i], SUB(aP[i], zero))));
    out(G, "gamma", (size_t)c->row, cg_neg(G, g));
  }
  if (c->nhol) out(G, "gamma", (size_t)(c->row + c->hrow), cg_neg(G, aP[2]));
}

void cg_emit_forces(cg_kin *K) {
  const ap_bmodel *M = K->M;
  for (size_t i = 0; i < M->scratch; i++)   /* the velocity stage's values, from S */
    if (K->sh[i].kind != CG_CONST) K->sh[i] = cg_ref('S', i);
  cg_tu(K->G);
  cg_printf(K->G, "void apc_forces(const double *v, double *S, double *Q, double *gamma) {\n"
            "  (void)v, (void)S, (void)Q, (void)gamma;\n");
  if (cg_effects_traced(M)) {   /* Q written in full, zeros too: inputs add to it later */
    cg_v *Q = calloc((size_t)M->k + 1, sizeof *Q);
    if (!Q) {
      K->G->fail = 1;
      return;
    }
    for (int c = 0; c < M->k; c++) Q[c] = cg_const(0.0);
    gravity(K, Q);
    for (int c = 0; c < M->k; c++) out(K->G, "Q", (size_t)c, Q[c]);   /* every entry */
    free(Q);
  }
  for (int ci = 0; ci < M->nc; ci++)
    if (speed_traced(&M->cons[ci])) out(K->G, "gamma", (size_t)M->cons[ci].row, cg_const(0.0));
    else if (cg_con_traced(M, ci)) contact_gamma(K, ci);
  cg_printf(K->G, "}\n\n");
}
