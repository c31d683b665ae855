/* The position stage of lib/model/kinematics.c (joint transforms, Jacobians, world inertias,
 * plane contacts) and ap_kin_metric (g) on traced values, and the translation unit of a model.
 *
 * Mirrors joint_position, joint_columns, body_mass and ap_kin_metric statement by statement;
 * a change there must be made here too (tests/test_compiled.c compares both paths bit for bit
 * up to 1e-13). The plane contact's support point is traced too (emit_contact.c); the library's
 * ap_kin_plane, called through a pointer, reports a disk or torus lying flat (and computes the
 * support of a shape the tracer does not take: the generated code reads u, cb, H, rc back). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"

void cg_mark(cg_kin *K, const double *p, int n) {
  memset(K->wr + (p - K->base), 1, (size_t)n);
}

int cg_kin_supported(const ap_bmodel *M, char *why, size_t len) {
  for (int j = 0; j < M->nj; j++)
    if ((int)M->joints[j].kind < 0 || (int)M->joints[j].kind > AP_JOINT_PLANE_CONTACT) {
      snprintf(why, len, "joint '%s' has an unknown kind", M->joints[j].name);
      return -1;
    }
  return 0;
}

/* ap_joint_transform on traced local coordinates. */
static void transform(cg_gen *G, const ap_mjoint *j, const cg_v *ql, cg_v *Rj, cg_v *tj) {
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, ez[3] = {0, 0, 1};
  t_consts(I3, 9, Rj);
  for (int i = 0; i < 3; i++) tj[i] = cg_const(0.0);
  switch (j->kind) {
    case AP_JOINT_FIXED: break;
    case AP_JOINT_REVOLUTE: t_axis_angle(G, j->axis, ql[0], Rj); break;
    case AP_JOINT_PRISMATIC: {
      cg_v a[3];
      t_consts(j->axis, 3, a);
      t_axpy(G, ql[0], a, tj);
      break;
    }
    case AP_JOINT_PLANAR:
      t_axis_angle(G, ez, ql[2], Rj);
      tj[0] = ql[0], tj[1] = ql[1];
      break;
    case AP_JOINT_BALL: t_quat_matrix(G, ql, Rj); break;
    case AP_JOINT_FREE:
      t_quat_matrix(G, ql + 3, Rj);
      tj[0] = ql[0], tj[1] = ql[1], tj[2] = ql[2];
      break;
    case AP_JOINT_PLANE_CONTACT:
      t_quat_matrix(G, ql + 2, Rj);
      tj[0] = ql[0], tj[1] = ql[1];
      break;
  }
}

/* ap_joint_column on traced values (rc: the plane contact's contact vector). */
static void column(cg_gen *G, const ap_mjoint *j, int i, const cg_v *rc, cg_v *sw, cg_v *sv) {
  for (int r = 0; r < 3; r++) sw[r] = sv[r] = cg_const(0.0);
  switch (j->kind) {
    case AP_JOINT_REVOLUTE: t_consts(j->axis, 3, sw); break;
    case AP_JOINT_PRISMATIC: t_consts(j->axis, 3, sv); break;
    case AP_JOINT_PLANAR:
      if (i < 2) sv[i] = cg_const(1.0);
      else sw[2] = cg_const(1.0);
      break;
    case AP_JOINT_BALL: sw[i] = cg_const(1.0); break;
    case AP_JOINT_FREE:
      if (i < 3) sv[i] = cg_const(1.0);
      else sw[i - 3] = cg_const(1.0);
      break;
    case AP_JOINT_PLANE_CONTACT:
      if (i < 2) {
        sv[i] = cg_const(1.0);
      } else {
        cg_v ez[3] = {cg_const(0), cg_const(0), cg_const(1)}, e[3];
        t_cross(G, ez, rc, e);
        sw[i - 2] = cg_const(1.0);
        sv[2] = e[i - 2];
      }
      break;
    case AP_JOINT_FIXED: break;
  }
}

/* The plane contact: Rj to an array, the library's support function, u cb H rc read back. */
static void plane(cg_kin *K, int jx, const cg_v *Rj, kjoint *J, cg_v *z) {
  char x[48];
  if (cg_plane_support(K, jx, Rj, J, z)) return;   /* traced (emit_contact.c) */
  cg_printf(K->G, "  {\n    const double R_[9] = {");
  for (int i = 0; i < 9; i++) {
    cg_text(&Rj[i], x, sizeof x);
    cg_printf(K->G, "%s%s", x, i < 8 ? ", " : "};\n");
  }
  cg_printf(K->G, "    int rc_ = plane(ctx, %d, R_, &z[%d]);\n    if (rc_ != 0) return rc_;\n"
            "  }\n", jx, jx);
  ap_sc *blocks[4] = {J->u, J->cb, J->H, J->rc};
  int lens[4] = {3, 3, 9, 3};
  for (int b = 0; b < 4; b++)
    for (int i = 0; i < lens[b]; i++)
      *cg_at(K, blocks[b] + i) = cg_ref('S', (size_t)(blocks[b] + i - K->base));
  *z = cg_ref('z', (size_t)jx);
}

/* The joint's own columns into Jw and Jo, driven ones into column k (f' W) and adw, adv. */
static void joint_columns(cg_kin *K, const ap_mjoint *j, kjoint *J, cg_v *Jw, cg_v *Jo) {
  cg_gen *G = K->G;
  int k = K->M->k;
  cg_v *adw = cg_at(K, J->adw), *adv = cg_at(K, J->adv), *drv = cg_at(K, J->drv);
  for (int i = 0; i < 3; i++) adw[i] = adv[i] = cg_const(0.0);
  cg_mark(K, J->adw, 3), cg_mark(K, J->adv, 3);
  for (int i = 0; i < j->nv; i++) {
    cg_v sw[3], sv[3], W[3], V[3];
    column(G, j, i, cg_at(K, J->rc), sw, sv);
    t_m3v(G, cg_at(K, J->RFP), sw, W);
    t_m3v(G, cg_at(K, J->RFP), sv, V);
    if (j->vidx[i] >= 0) {
      t_axpy(G, cg_const(1.0), W, Jw + 3 * j->vidx[i]);
      t_axpy(G, cg_const(1.0), V, Jo + 3 * j->vidx[i]);
    } else {
      cg_v f1 = drv[3 * i + 1], f2 = drv[3 * i + 2];
      t_axpy(G, f1, W, Jw + 3 * k), t_axpy(G, f1, V, Jo + 3 * k);
      t_axpy(G, f2, W, adw), t_axpy(G, f2, V, adv);
    }
  }
}

/* The joint's drives, by the library (ap_kin_drives): their values are read from S. */
static void drives(cg_kin *K, int jx, const ap_mjoint *j, kjoint *J) {
  int any = 0;
  for (int i = 0; i < j->ndrivable; i++) any |= j->drive[i] != NULL;
  if (!any) return;
  cg_printf(K->G, "  {\n    int rc_ = drive(ctx, %d);\n    if (rc_ != 0) return rc_;\n  }\n", jx);
  for (int i = 0; i < 3 * j->ndrivable; i++)
    if (j->drive[i / 3]) *cg_at(K, J->drv + i) = cg_ref('S', (size_t)(J->drv + i - K->base));
}

static void joint_position(cg_kin *K, int jx) {
  const ap_bmodel *M = K->M;
  const ap_mjoint *j = &M->joints[jx];
  cg_gen *G = K->G;
  int K3 = 3 * M->K1;
  kjoint J = ap_kin_joint(M, K->base, jx);
  kbody C = ap_kin_body(M, K->base, j->child);
  cg_v *ql = cg_at(K, J.qloc);
  drives(K, jx, j, &J);
  for (int i = 0; i < j->nq; i++)
    ql[i] = j->qidx[i] >= 0 ? cg_ref('q', (size_t)j->qidx[i]) : cg_at(K, J.drv)[3 * i];
  cg_mark(K, J.qloc, j->nq);
  static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  cg_v I3v[9], Z3[3] = {cg_const(0), cg_const(0), cg_const(0)}, *Rp = I3v, *op = Z3;
  t_consts(I3, 9, I3v);
  kbody P = C;
  if (j->parent >= 0)
    P = ap_kin_body(M, K->base, j->parent), Rp = cg_at(K, P.R), op = cg_at(K, P.o);
  cg_v Rpf[9], ppf[3], Rcf[9], pcf[3], Rj[9], tj[3], RFC[9], r12[3], oFC[3];
  t_consts(j->Rpf, 9, Rpf), t_consts(j->ppf, 3, ppf), t_consts(j->Rcf, 9, Rcf);
  t_consts(j->pcf, 3, pcf);
  cg_v *RFP = cg_at(K, J.RFP), *r1 = cg_at(K, J.r1), *r2 = cg_at(K, J.r2), *r3 = cg_at(K, J.r3);
  t_m3m(G, Rp, Rpf, RFP);
  t_m3v(G, Rp, ppf, r1);
  transform(G, j, ql, Rj, tj);
  if (j->kind == AP_JOINT_PLANE_CONTACT) plane(K, jx, Rj, &J, &tj[2]);
  t_m3v(G, RFP, tj, r2);
  t_m3m(G, RFP, Rj, RFC);
  cg_v *R = cg_at(K, C.R), *o = cg_at(K, C.o);
  t_m3mt(G, RFC, Rcf, R);
  t_m3v(G, R, pcf, r3);
  for (int i = 0; i < 3; i++) {
    r12[i] = cg_add(G, r1[i], r2[i]);
    oFC[i] = cg_add(G, op[i], r12[i]);
    o[i] = cg_sub(G, oFC[i], r3[i]);
  }
  cg_mark(K, J.RFP, 9), cg_mark(K, J.r1, 3), cg_mark(K, J.r2, 3), cg_mark(K, J.r3, 3);
  cg_mark(K, C.R, 9), cg_mark(K, C.o, 3);
  cg_v *Jw = cg_at(K, C.Jw), *Jo = cg_at(K, C.Jo);
  if (j->parent >= 0) {
    memcpy(Jw, cg_at(K, P.Jw), (size_t)K3 * sizeof *Jw);
    memcpy(Jo, cg_at(K, P.Jo), (size_t)K3 * sizeof *Jo);
    for (int c = 0; c < M->ncol; c++) t_cross_add(G, cg_at(K, P.Jw) + 3 * c, r12, Jo + 3 * c);
  } else {
    for (int i = 0; i < K3; i++) Jw[i] = Jo[i] = cg_const(0.0);
  }
  joint_columns(K, j, &J, Jw, Jo);
  for (int c = 0; c < M->ncol; c++) t_cross_add(G, r3, Jw + 3 * c, Jo + 3 * c);
  cg_mark(K, C.Jw, K3), cg_mark(K, C.Jo, K3);
}

static void body_mass(cg_kin *K, int b) {
  const ap_bmodel *M = K->M;
  const ap_mbody *B = &M->bodies[b];
  cg_gen *G = K->G;
  kbody C = ap_kin_body(M, K->base, b);
  cg_v T[9], I[9], com[3], *R = cg_at(K, C.R), *Jw = cg_at(K, C.Jw), *Jc = cg_at(K, C.Jc);
  t_consts(B->I, 9, I), t_consts(B->com, 3, com);
  t_m3m(G, R, I, T);
  t_m3mt(G, T, R, cg_at(K, C.Iw));
  t_m3v(G, R, com, cg_at(K, C.rcom));
  memcpy(Jc, cg_at(K, C.Jo), 3 * (size_t)M->K1 * sizeof *Jc);
  for (int c = 0; c < M->ncol; c++) t_cross_add(G, Jw + 3 * c, cg_at(K, C.rcom), Jc + 3 * c);
  cg_mark(K, C.Iw, 9), cg_mark(K, C.rcom, 3), cg_mark(K, C.Jc, 3 * M->K1);
}

static void metric(cg_kin *K) {
  const ap_bmodel *M = K->M;
  cg_gen *G = K->G;
  int k = M->k;
  for (int b = 0; b < M->nb; b++) {
    const ap_mbody *B = &M->bodies[b];
    kbody C = ap_kin_body(M, K->base, b);
    cg_v *Jw = cg_at(K, C.Jw), *Jc = cg_at(K, C.Jc), mass = cg_const(B->mass);
    for (int ib = 0; ib < B->ncols; ib++) {
      int cb = B->cols[ib];
      cg_v IJ[3];
      t_m3v(G, cg_at(K, C.Iw), Jw + 3 * cb, IJ);
      for (int ia = 0; ia <= ib; ia++) {
        int ca = B->cols[ia];
        cg_v s = cg_add(G, cg_mul(G, mass, t_dot(G, Jc + 3 * ca, Jc + 3 * cb)),
                        t_dot(G, Jw + 3 * ca, IJ));
        size_t i1 = (size_t)ca + (size_t)cb * k, i2 = (size_t)cb + (size_t)ca * k;
        K->out[i1] = cg_add(G, K->out[i1], s), K->owr[i1] = 1;
        if (ca != cb) K->out[i2] = cg_add(G, K->out[i2], s), K->owr[i2] = 1;
      }
    }
  }
}

void cg_kin_position(cg_kin *K) {
  for (int j = 0; j < K->M->nj; j++) joint_position(K, j);
  for (int b = 0; b < K->M->nb; b++) body_mass(K, b);
  metric(K);
}

/* The stage's stores: the scratch entries it wrote (a zero constant is there already: the
 * scratch starts zeroed and no path writes anything else into those entries), then out. A store
 * of a temporary goes right after the statement that computes it (short live ranges: fewer
 * spills, and less work for the compiler's register allocator) when that statement comes after
 * the stage's last statement of another kind (a callback) and the stage never reads that
 * scratch entry back; the others go at the end. The stage's sin and cos of coordinates go
 * first. */
typedef struct store {
  int early;       /* right after the temporary's statement */
  int next;        /* the next early store of the same temporary, or -1 */
  char arr;        /* 'S' or 'o' (out) */
  size_t idx;
  cg_v v;
} store;

static void put(cg_gen *G, const char *out_name, const store *st) {
  char x[48];
  cg_text(&st->v, x, sizeof x);
  cg_printf(G, "  %s[%zu] = %s;\n", st->arr == 'S' ? "S" : out_name, st->idx, x);
}

static const char *next_line(const char *l) { return strchr(l, '\n') + 1; }

/* Where the stage's early stores may start: after its last line that is not a temporary's
 * statement. */
static const char *barrier(const cg_kin *K) {
  const char *b = K->G->s + K->text0, *end = K->G->s + K->G->len;
  for (const char *l = b; l < end; l = next_line(l))
    if (strncmp(l, "  const double t", 16) != 0) b = next_line(l);
  return b;
}

/* Rewrite the stage's text from b on with the early stores (head[id - id0]: the first early
 * store of t<id>). */
static void place(cg_kin *K, const char *out_name, const store *st, const int *head,
                  const char *b) {
  cg_gen *G = K->G, N = {0};
  const char *end = G->s + G->len;
  cg_printf(&N, "%.*s", (int)(b - G->s), G->s);
  for (const char *l = b; l < end && !N.fail; l = next_line(l)) {
    cg_printf(&N, "%.*s", (int)(next_line(l) - l), l);
    for (int i = head[atoi(l + 16) - K->id0]; i >= 0; i = st[i].next) put(&N, out_name, &st[i]);
  }
  free(G->s);
  G->s = N.s, G->len = N.len, G->cap = N.cap, G->fail |= N.fail;
}

/* sin and cos of a coordinate at the start of the stage: nothing is live across those calls
 * then (a call clobbers every floating-point register), so fewer spills. */
static int is_trig(const char *l) {
  const char *e = strchr(l, '=');
  return strncmp(l, "  const double t", 16) == 0 && e &&
         (strncmp(e, "= sin(q[", 8) == 0 || strncmp(e, "= cos(q[", 8) == 0);
}

static void hoist(cg_kin *K) {
  cg_gen *G = K->G, N = {0};
  const char *b = G->s + K->text0, *end = G->s + G->len;
  cg_printf(&N, "%.*s", (int)(b - G->s), G->s);
  for (int pass = 0; pass < 2; pass++)
    for (const char *l = b; l < end && !N.fail; l = next_line(l))
      if (is_trig(l) == !pass) cg_printf(&N, "%.*s", (int)(next_line(l) - l), l);
  free(G->s);
  G->s = N.s, G->len = N.len, G->cap = N.cap, G->fail |= N.fail;
}

void cg_kin_store(cg_kin *K, const char *out_name, int nout) {
  cg_gen *G = K->G;
  if (!G->fail) hoist(K);
  size_t ns = K->M->scratch, n = 0, nt = (size_t)(G->ntemp - K->id0) + 1;
  store *st = malloc((ns + (size_t)nout + 1) * sizeof *st);
  int *head = malloc(nt * sizeof *head);
  unsigned char *read = calloc(ns + 1, 1), *late = calloc(nt, 1);
  if (!st || !head || !read || !late || G->fail) {
    free(st), free(head), free(read), free(late), G->fail = 1;
    return;
  }
  for (const char *p = strstr(G->s + K->text0, "S["); p; p = strstr(p + 2, "S["))
    if ((size_t)atol(p + 2) < ns) read[atol(p + 2)] = 1;   /* entries the stage reads */
  const char *b = barrier(K);
  for (const char *l = b; l < G->s + G->len; l = next_line(l)) late[atoi(l + 16) - K->id0] = 1;
  for (size_t i = 0; i < ns; i++) {
    const cg_v *v = &K->sh[i];
    if (K->wr[i] && !(v->kind == CG_CONST && v->c == 0.0) &&
        !(v->kind == CG_REF && v->base == 'S' && v->idx == i))
      st[n++] = (store){0, -1, 'S', i, *v};
  }
  for (int i = 0; i < nout; i++)
    if (K->owr[i]) st[n++] = (store){0, -1, 'o', (size_t)i, K->out[i]};
  for (size_t i = 0; i < nt; i++) head[i] = -1;
  int any = 0;
  for (size_t i = n; i-- > 0;) {   /* the early ones, linked per temporary in store order */
    int id = st[i].v.id - K->id0;
    if (st[i].v.kind != CG_TEMP || id < 0 || !late[id] || (st[i].arr == 'S' && read[st[i].idx]))
      continue;
    st[i].next = head[id], head[id] = (int)i, st[i].early = any = 1;
  }
  if (any) place(K, out_name, st, head, b);
  for (size_t i = 0; i < n; i++)
    if (!st[i].early) put(G, out_name, &st[i]);
  free(st), free(head), free(read), free(late);
}
