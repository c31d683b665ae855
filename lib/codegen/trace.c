/* Traced scalars: constants fold at generation time, the rest becomes one C statement per
 * operation (codegen.h). The 3-vector and 3 x 3 helpers mirror model/model.h and rot.c
 * operation by operation, so that the generated code rounds exactly as the interpreted one.
 * Constants are printed in hexadecimal floating point (%a): exact. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"

void cg_printf(cg_gen *G, const char *fmt, ...) {
  if (G->fail) return;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    size_t room = G->cap - G->len;
    int n = G->s ? vsnprintf(G->s + G->len, room, fmt, ap) : -1;
    va_end(ap);
    if (G->s && n >= 0 && (size_t)n < room) {
      G->len += (size_t)n;
      return;
    }
    size_t cap = G->cap ? 2 * G->cap : 1 << 16;
    char *s = realloc(G->s, cap);
    if (!s) {
      G->fail = 1;
      return;
    }
    G->s = s, G->cap = cap;
  }
}

void cg_tu(cg_gen *G) { cg_printf(G, "%s", CG_TU_MARK); }

cg_v cg_const(double c) {
  cg_v v = {CG_CONST, c, 0, 0, 0};
  return v;
}

cg_v cg_ref(char base, size_t idx) {
  cg_v v = {CG_REF, 0.0, 0, base, idx};
  return v;
}

void cg_text(const cg_v *a, char *out, size_t len) {
  if (a->kind == CG_CONST) snprintf(out, len, "(%a)", a->c);
  else if (a->kind == CG_TEMP) snprintf(out, len, "t%d", a->id);
  else snprintf(out, len, "%c[%zu]", a->base, a->idx);
}

static int is_c(cg_v a, double c) { return a.kind == CG_CONST && a.c == c; }

static cg_v emit2(cg_gen *G, cg_v a, const char *op, cg_v b) {
  char x[48], y[48];
  cg_text(&a, x, sizeof x), cg_text(&b, y, sizeof y);
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s %s %s;\n", r.id, x, op, y);
  return r;
}

cg_v cg_add(cg_gen *G, cg_v a, cg_v b) {
  if (a.kind == CG_CONST && b.kind == CG_CONST) return cg_const(a.c + b.c);
  if (is_c(a, 0.0)) return b;
  if (is_c(b, 0.0)) return a;
  return emit2(G, a, "+", b);
}

cg_v cg_neg(cg_gen *G, cg_v a) {
  if (a.kind == CG_CONST) return cg_const(-a.c);
  char x[48];
  cg_text(&a, x, sizeof x);
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = -%s;\n", r.id, x);
  return r;
}

cg_v cg_sub(cg_gen *G, cg_v a, cg_v b) {
  if (a.kind == CG_CONST && b.kind == CG_CONST) return cg_const(a.c - b.c);
  if (is_c(b, 0.0)) return a;
  if (is_c(a, 0.0)) return cg_neg(G, b);
  return emit2(G, a, "-", b);
}

cg_v cg_mul(cg_gen *G, cg_v a, cg_v b) {
  if (a.kind == CG_CONST && b.kind == CG_CONST) return cg_const(a.c * b.c);
  if (is_c(a, 0.0) || is_c(b, 0.0)) return cg_const(0.0);
  if (is_c(a, 1.0)) return b;
  if (is_c(b, 1.0)) return a;
  if (is_c(a, -1.0)) return cg_neg(G, b);
  if (is_c(b, -1.0)) return cg_neg(G, a);
  return emit2(G, a, "*", b);
}

cg_v cg_div(cg_gen *G, cg_v a, cg_v b) {
  if (a.kind == CG_CONST && b.kind == CG_CONST) return cg_const(a.c / b.c);
  if (is_c(b, 1.0)) return a;
  return emit2(G, a, "/", b);
}

cg_v cg_call(cg_gen *G, const char *fn, cg_v a) {
  char x[48];
  cg_text(&a, x, sizeof x);
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s(%s);\n", r.id, fn, x);
  return r;
}

cg_v cg_quat_scale(cg_gen *G, cg_v nn) {
  if (nn.kind == CG_CONST) return cg_const(nn.c > 0 ? 2.0 / nn.c : 0.0);
  char x[48];
  cg_text(&nn, x, sizeof x);
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s > 0 ? 2.0 / %s : 0.0;\n", r.id, x, x);
  return r;
}

/* ---- model/model.h and rot.c, traced ---------------------------------------------------- */

#define ADD(a, b) cg_add(G, a, b)
#define SUB(a, b) cg_sub(G, a, b)
#define MUL(a, b) cg_mul(G, a, b)

cg_v t_dot(cg_gen *G, const cg_v *a, const cg_v *b) {
  return ADD(ADD(MUL(a[0], b[0]), MUL(a[1], b[1])), MUL(a[2], b[2]));
}

void t_cross(cg_gen *G, const cg_v *a, const cg_v *b, cg_v *c) {
  cg_v x = SUB(MUL(a[1], b[2]), MUL(a[2], b[1])), y = SUB(MUL(a[2], b[0]), MUL(a[0], b[2])),
       z = SUB(MUL(a[0], b[1]), MUL(a[1], b[0]));
  c[0] = x, c[1] = y, c[2] = z;
}

void t_axpy(cg_gen *G, cg_v s, const cg_v *a, cg_v *c) {
  for (int i = 0; i < 3; i++) c[i] = ADD(c[i], MUL(s, a[i]));
}

void t_cross_add(cg_gen *G, const cg_v *a, const cg_v *b, cg_v *c) {
  cg_v t[3];
  t_cross(G, a, b, t);
  for (int i = 0; i < 3; i++) c[i] = ADD(c[i], t[i]);
}

void t_m3v(cg_gen *G, const cg_v *M, const cg_v *x, cg_v *y) {
  cg_v r[3];
  for (int i = 0; i < 3; i++)
    r[i] = ADD(ADD(MUL(M[i], x[0]), MUL(M[i + 3], x[1])), MUL(M[i + 6], x[2]));
  memcpy(y, r, sizeof r);
}

void t_m3tv(cg_gen *G, const cg_v *M, const cg_v *x, cg_v *y) {
  cg_v r[3];
  for (int i = 0; i < 3; i++)
    r[i] = ADD(ADD(MUL(M[3 * i], x[0]), MUL(M[3 * i + 1], x[1])), MUL(M[3 * i + 2], x[2]));
  memcpy(y, r, sizeof r);
}

void t_m3m(cg_gen *G, const cg_v *A, const cg_v *B, cg_v *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = ADD(ADD(MUL(A[i], B[3 * j]), MUL(A[i + 3], B[1 + 3 * j])),
                         MUL(A[i + 6], B[2 + 3 * j]));
}

void t_m3mt(cg_gen *G, const cg_v *A, const cg_v *B, cg_v *C) {
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 3; i++)
      C[i + 3 * j] = ADD(ADD(MUL(A[i], B[j]), MUL(A[i + 3], B[j + 3])), MUL(A[i + 6], B[j + 6]));
}

void t_consts(const double *x, int n, cg_v *out) {
  for (int i = 0; i < n; i++) out[i] = cg_const(x[i]);
}

/* Rodrigues as ap_rot_axis_angle: c + (t a_i) a_j, (t a_i) a_j -+ s a_k. */
void t_axis_angle(cg_gen *G, const double *ax, cg_v angle, cg_v *R) {
  cg_v a[3], c = cg_call(G, "cos", angle), s = cg_call(G, "sin", angle);
  cg_v t = SUB(cg_const(1.0), c);
  t_consts(ax, 3, a);
  R[0] = ADD(c, MUL(MUL(t, a[0]), a[0]));
  R[3] = SUB(MUL(MUL(t, a[0]), a[1]), MUL(s, a[2]));
  R[6] = ADD(MUL(MUL(t, a[0]), a[2]), MUL(s, a[1]));
  R[1] = ADD(MUL(MUL(t, a[1]), a[0]), MUL(s, a[2]));
  R[4] = ADD(c, MUL(MUL(t, a[1]), a[1]));
  R[7] = SUB(MUL(MUL(t, a[1]), a[2]), MUL(s, a[0]));
  R[2] = SUB(MUL(MUL(t, a[2]), a[0]), MUL(s, a[1]));
  R[5] = ADD(MUL(MUL(t, a[2]), a[1]), MUL(s, a[0]));
  R[8] = ADD(c, MUL(MUL(t, a[2]), a[2]));
}

/* As ap_quat_normalized_matrix. */
void t_quat_matrix(cg_gen *G, const cg_v *q, cg_v *R) {
  cg_v nn = ADD(ADD(ADD(MUL(q[0], q[0]), MUL(q[1], q[1])), MUL(q[2], q[2])), MUL(q[3], q[3]));
  cg_v s = cg_quat_scale(G, nn), one = cg_const(1.0);
  cg_v w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = SUB(one, MUL(s, ADD(MUL(y, y), MUL(z, z))));
  R[3] = MUL(s, SUB(MUL(x, y), MUL(w, z)));
  R[6] = MUL(s, ADD(MUL(x, z), MUL(w, y)));
  R[1] = MUL(s, ADD(MUL(x, y), MUL(w, z)));
  R[4] = SUB(one, MUL(s, ADD(MUL(x, x), MUL(z, z))));
  R[7] = MUL(s, SUB(MUL(y, z), MUL(w, x)));
  R[2] = MUL(s, SUB(MUL(x, z), MUL(w, y)));
  R[5] = MUL(s, ADD(MUL(y, z), MUL(w, x)));
  R[8] = SUB(one, MUL(s, ADD(MUL(x, x), MUL(y, y))));
}
