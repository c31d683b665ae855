/* The velocity stage of lib/model/kinematics.c (ap_kin_velocity: body velocities and bias
 * accelerations) and ap_kin_bias (h) on traced values, and the whole translation unit of a
 * model: apc_position, apc_velocity, apc_acceleration (emit_acc.c) and the hash it was made
 * for.
 *
 * Mirrors joint_velocity, plane_bias and ap_kin_bias statement by statement. The velocity stage
 * reads what the position stage stored: every traced value of that stage that is not a
 * constant becomes a load from the scratch. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"

/* ap_kin_apply: out = J[:, k] + sum_c v_c J[:, c]. */
static void apply(cg_kin *K, const cg_v *J, cg_v *out) {
  int k = K->M->k;
  for (int i = 0; i < 3; i++) out[i] = J[3 * k + i];
  for (int c = 0; c < k; c++) t_axpy(K->G, cg_ref('v', (size_t)c), J + 3 * c, out);
}

static void plane_bias(cg_kin *K, const kbody *C, const kjoint *J, cg_v *a) {
  cg_gen *G = K->G;
  cg_v ez[3] = {cg_const(0), cg_const(0), cg_const(1)}, wxe[3], ud[3], cd[3], rcd[3], e[3];
  cg_v *w = cg_at(K, C->w), *R = cg_at(K, C->R);
  t_cross(G, w, ez, wxe);
  t_m3tv(G, R, wxe, ud);
  t_m3v(G, cg_at(K, J->H), ud, cd);
  t_m3v(G, R, cd, rcd);
  t_cross_add(G, w, cg_at(K, J->rc), rcd);
  t_cross(G, ez, rcd, e);
  a[2] = cg_add(G, a[2], t_dot(G, e, w));
}

static void joint_velocity(cg_kin *K, int jx) {
  const ap_bmodel *M = K->M;
  const ap_mjoint *j = &M->joints[jx];
  cg_gen *G = K->G;
  kjoint J = ap_kin_joint(M, K->base, jx);
  kbody C = ap_kin_body(M, K->base, j->child);
  cg_v Z3[3] = {cg_const(0), cg_const(0), cg_const(0)}, *wp = Z3, *vp = Z3, *alp = Z3,
       *ap = Z3;
  if (j->parent >= 0) {
    kbody P = ap_kin_body(M, K->base, j->parent);
    wp = cg_at(K, P.w), vp = cg_at(K, P.vo), alp = cg_at(K, P.al), ap = cg_at(K, P.ao);
  }
  cg_v *w = cg_at(K, C.w), *vo = cg_at(K, C.vo), *al = cg_at(K, C.al), *ao = cg_at(K, C.ao);
  cg_v *r1 = cg_at(K, J.r1), *r2 = cg_at(K, J.r2), *r3 = cg_at(K, J.r3);
  apply(K, cg_at(K, C.Jw), w);
  apply(K, cg_at(K, C.Jo), vo);
  cg_v *drv = cg_at(K, J.drv);
  for (int i = 0; i < j->nv; i++)
    cg_at(K, J.vloc)[i] = j->vidx[i] >= 0 ? cg_ref('v', (size_t)j->vidx[i]) : drv[3 * i + 1];
  cg_v wrel[3], vrel[3], r12[3], a[3], wr[3], w3[3];
  for (int i = 0; i < 3; i++) wrel[i] = cg_sub(G, w[i], wp[i]), r12[i] = cg_add(G, r1[i], r2[i]);
  for (int i = 0; i < 3; i++) vrel[i] = cg_sub(G, vo[i], vp[i]);
  t_cross_add(G, w, r3, vrel);
  t_cross_add(G, r12, wp, vrel);
  memcpy(al, alp, 3 * sizeof *al);
  t_cross_add(G, wp, wrel, al);
  t_axpy(G, cg_const(1.0), cg_at(K, J.adw), al);
  memcpy(a, ap, sizeof a);
  t_cross_add(G, alp, r12, a);
  t_cross(G, wp, r12, wr);
  t_cross_add(G, wp, wr, a);
  t_cross(G, wp, vrel, wr);
  t_axpy(G, cg_const(2.0), wr, a);
  t_axpy(G, cg_const(1.0), cg_at(K, J.adv), a);
  if (j->kind == AP_JOINT_PLANE_CONTACT) plane_bias(K, &C, &J, a);
  t_cross(G, al, r3, wr);
  t_axpy(G, cg_const(-1.0), wr, a);
  t_cross(G, w, r3, w3);
  t_cross(G, w, w3, wr);
  t_axpy(G, cg_const(-1.0), wr, a);
  memcpy(ao, a, sizeof a);
  cg_mark(K, C.w, 3), cg_mark(K, C.vo, 3), cg_mark(K, C.al, 3), cg_mark(K, C.ao, 3);
  cg_mark(K, J.vloc, j->nv);
}

static void bias(cg_kin *K) {
  const ap_bmodel *M = K->M;
  cg_gen *G = K->G;
  for (int b = 0; b < M->nb; b++) {
    const ap_mbody *B = &M->bodies[b];
    kbody C = ap_kin_body(M, K->base, b);
    cg_v ac[3], t[3], hw[3], Iww[3], *w = cg_at(K, C.w), *rcom = cg_at(K, C.rcom);
    cg_v *Iw = cg_at(K, C.Iw), *Jc = cg_at(K, C.Jc), *Jw = cg_at(K, C.Jw);
    memcpy(ac, cg_at(K, C.ao), sizeof ac);
    t_cross_add(G, cg_at(K, C.al), rcom, ac);
    t_cross(G, w, rcom, t);
    t_cross_add(G, w, t, ac);
    t_m3v(G, Iw, cg_at(K, C.al), hw);
    t_m3v(G, Iw, w, Iww);
    t_cross_add(G, w, Iww, hw);
    for (int i = 0; i < B->ncols; i++) {
      int c = B->cols[i];
      cg_v s = cg_add(G, cg_mul(G, cg_const(B->mass), t_dot(G, Jc + 3 * c, ac)),
                      t_dot(G, Jw + 3 * c, hw));
      K->out[c] = cg_add(G, K->out[c], s), K->owr[c] = 1;
    }
  }
}

void cg_kin_velocity(cg_kin *K) {
  for (int j = 0; j < K->M->nj; j++) joint_velocity(K, j);
  bias(K);
}

/* ---- the translation unit ---------------------------------------------------------------- */

static void stage_begin(cg_kin *K, int nout) {
  memset(K->wr, 0, K->M->scratch);
  memset(K->owr, 0, (size_t)nout);
  for (int i = 0; i < nout; i++) K->out[i] = cg_const(0.0);
  K->text0 = K->G->len, K->id0 = K->G->ntemp;
}

/* One acceleration stage: the generic one, or the variant for the independent speeds indep. */
static void acc_function(cg_gen *G, const ap_bmodel *M, const cg_v *gpos, const char *name,
                         const int *indep) {
  cg_printf(G, CG_TU_MARK "int %s(" CG_ACC_PARAMS ") {\n  (void)g, (void)B, (void)Q, (void)h, "
            "(void)w, (void)N, (void)v, (void)gB, (void)Phi, (void)tk1, (void)tk2;\n", name);
  cg_kin_acceleration(G, M, gpos, indep);
  cg_printf(G, "  return 0;\n}\n\n");
}

char *cg_source(const ap_bmodel *M, const int *indep, char *why, size_t len) {
  if (cg_kin_supported(M, why, len) != 0) return NULL;
  size_t ns = M->scratch ? M->scratch : 1, kk = (size_t)M->k * M->k + 1;
  cg_gen G = {0};
  cg_kin K = {M, &G, calloc(ns, sizeof(double)), calloc(ns, sizeof(cg_v)), calloc(ns, 1),
              calloc(kk, sizeof(cg_v)), calloc(kk, 1), 0, 0};
  kk = (size_t)M->k * M->k;
  if (!K.base || !K.sh || !K.wr || !K.out || !K.owr) G.fail = 1;
  for (size_t i = 0; !G.fail && i < ns; i++) K.sh[i] = cg_const(0.0);
  cg_printf(&G, "/* Generated by Appell (lib/codegen) for one body model: the kinematics and "
            "g of the position stage, the velocities, biases and h of the velocity stage, the "
            "acceleration stage. */\n"
            "double sin(double), cos(double), tan(double), asin(double), acos(double), "
            "atan(double), atan2(double, double), sqrt(double), fabs(double), exp(double), "
            "log(double), pow(double, double), hypot(double, double);\n"
            "#define isfinite(x) __builtin_isfinite(x)\n\n"
            "typedef int (*apc_plane_fn)(void *ctx, int joint, const double *Rj, double *z);\n"
            "typedef int (*apc_drive_fn)(void *ctx, int joint);\n"
            "extern const char apc_hash[];\n"
            "int apc_acceleration(" CG_ACC_PARAMS ");\n\n" CG_TU_MARK
            "int apc_position(const double *q, double *S, double *g, apc_plane_fn plane, "
            "apc_drive_fn drive, void *ctx) {\n  double z[%d];\n"
            "  (void)plane, (void)drive, (void)ctx, (void)z;\n",
            M->nj + 1);
  if (!G.fail) {
    stage_begin(&K, M->k * M->k);
    cg_kin_position(&K);
    cg_kin_store(&K, "g", M->k * M->k);
  }
  cg_v *gpos = G.fail ? NULL : malloc((kk + 1) * sizeof *gpos);   /* g's structure */
  if (gpos) memcpy(gpos, K.out, kk * sizeof *gpos);
  else G.fail = 1;
  cg_printf(&G, "  return 0;\n}\n\n");
  for (size_t i = 0; !G.fail && i < ns; i++)   /* the position stage's values, from S */
    if (K.sh[i].kind != CG_CONST) K.sh[i] = cg_ref('S', i);
  if (!G.fail) cg_emit_rows(&K);   /* apc_rows: contacts, N (emit_contact.c) */
  cg_printf(&G, CG_TU_MARK "void apc_velocity(const double *v, double *S, double *h) {\n"
            "  (void)v, (void)S, (void)h;\n");
  if (!G.fail) {
    stage_begin(&K, M->k);
    cg_kin_velocity(&K);
    cg_kin_store(&K, "h", M->k);
  }
  cg_printf(&G, "}\n\n");
  if (!G.fail) cg_emit_forces(&K);   /* apc_forces: gravity, gamma (emit_contact.c) */
  if (!G.fail) acc_function(&G, M, gpos, "apc_acceleration", NULL);
  if (!G.fail && indep && M->b > 0 && M->b < M->k)   /* the expected partition's variant */
    acc_function(&G, M, gpos, "apc_acc_part", indep);
  if (!G.fail) cg_emit_basis(&G, M, gpos);
  free(gpos);
  free(K.base), free(K.sh), free(K.wr), free(K.out), free(K.owr);
  if (G.fail) {
    free(G.s);
    snprintf(why, len, "out of memory generating the code");
    return NULL;
  }
  return G.s;
}
