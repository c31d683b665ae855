/* The acceleration stage of lib/core/forward.c (fwd_acceleration) with the native kernels of
 * lib/linalg/dense.c, on traced values at the model's fixed sizes: tk1 = g w, tk2 = Q - h - tk1,
 * G = B^T g B (g B, then the lower triangle, mirrored), Phi = B^T Q, e'' = B^T tk2, the
 * Cholesky factor of G, the solve, v' = B e'' + w and q' = N v.
 *
 * Mirrors gemv_native, gemv_t_native, symm_lower, congruence_native, chol_native and
 * chol_solve_native operation by operation (each of their sums runs in index order, which is
 * what the traced loops do), with g's and N's structure from the position stage folded: the
 * entries of g that the metric never writes are zero, N is the identity but for the
 * quaternion blocks. It runs only where the core's would take those kernels (the wrapper in
 * compiled.c checks the sizes against ap_la_small_limit, that the number of free speeds is
 * cg_free_speeds, k - b or 0 with more rows than speeds, and that no condition estimate is
 * asked for); a pivot that is not positive or an e'' that is not finite
 * or beyond AP_HUGE returns 1, and the core's own stage then runs and reports it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"

#define ADD(a, b) cg_add(G, a, b)
#define SUB(a, b) cg_sub(G, a, b)
#define MUL(a, b) cg_mul(G, a, b)

static void refs(char base, size_t n, cg_v *out) {
  for (size_t i = 0; i < n; i++) out[i] = cg_ref(base, i);
}

/* ap_la_gemv: zero for no columns, else gemv_native: y = M_0 x_0, then four columns at a
 * time, then one at a time. */
static void gemv(cg_gen *G, int m, int n, const cg_v *M, const cg_v *x, cg_v *y) {
  int j = 1;
  if (n <= 0) {
    for (int i = 0; i < m; i++) y[i] = cg_const(0.0);
    return;
  }
  for (int i = 0; i < m; i++) y[i] = MUL(M[i], x[0]);
  for (; j + 3 < n; j += 4) {
    const cg_v *M0 = M + (size_t)j * m, *M1 = M0 + m, *M2 = M1 + m, *M3 = M2 + m;
    for (int i = 0; i < m; i++)
      y[i] = ADD(y[i], ADD(ADD(MUL(M0[i], x[j]), MUL(M1[i], x[j + 1])),
                           ADD(MUL(M2[i], x[j + 2]), MUL(M3[i], x[j + 3]))));
  }
  for (; j < n; j++)
    for (int i = 0; i < m; i++) y[i] = ADD(y[i], MUL(M[i + (size_t)j * m], x[j]));
}

/* gemv_t_native: y_j = M_j . x, each sum from 0 in index order. */
static void gemv_t(cg_gen *G, int m, int n, const cg_v *M, const cg_v *x, cg_v *y) {
  for (int j = 0; j < n; j++) {
    cg_v s = cg_const(0.0);
    for (int i = 0; i < m; i++) s = ADD(s, MUL(M[i + (size_t)j * m], x[i]));
    y[j] = s;
  }
}

/* congruence_native: gB = g B from g's lower triangle, then G's lower triangle, mirrored. */
static void congruence(cg_gen *G, int k, int l, const cg_v *g, const cg_v *B, cg_v *Gm,
                       cg_v *gB) {
  for (int j = 0; j < l; j++)
    for (int i = 0; i < k; i++) {
      cg_v s = cg_const(0.0);
      for (int p = 0; p < k; p++)
        s = ADD(s, MUL(p < i ? g[i + (size_t)p * k] : g[p + (size_t)i * k], B[p + (size_t)j * k]));
      gB[i + (size_t)j * k] = s;
    }
  for (int j = 0; j < l; j++) {
    gemv_t(G, k, l - j, B + (size_t)j * k, gB + (size_t)j * k, Gm + j + (size_t)j * l);
    for (int i = j + 1; i < l; i++) Gm[j + (size_t)i * l] = Gm[i + (size_t)j * l];
  }
}

/* chol_native on Gm (l x l, lower), pivots checked as the kernel does. */
static void chol(cg_gen *G, int l, cg_v *Gm) {
  char x[48];
  for (int i = 0; i < l; i++)
    for (int j = 0; j <= i; j++) {
      cg_v s = Gm[i + (size_t)j * l];
      for (int p = 0; p < j; p++) s = SUB(s, MUL(Gm[i + (size_t)p * l], Gm[j + (size_t)p * l]));
      if (j < i) {
        Gm[i + (size_t)j * l] = cg_div(G, s, Gm[j + (size_t)j * l]);
        continue;
      }
      cg_text(&s, x, sizeof x);
      cg_printf(G, "  if (!(%s > 0.0) || !isfinite(%s)) return 1;\n", x, x);
      Gm[i + (size_t)i * l] = cg_call(G, "sqrt", s);
    }
}

/* chol_solve_native: forward by rows, backward by the factor's columns. */
static void chol_solve(cg_gen *G, int l, const cg_v *L, cg_v *x) {
  for (int i = 0; i < l; i++) {
    cg_v s = x[i];
    for (int p = 0; p < i; p++) s = SUB(s, MUL(L[i + (size_t)p * l], x[p]));
    x[i] = cg_div(G, s, L[i + (size_t)i * l]);
  }
  for (int i = l - 1; i >= 0; i--) {
    cg_v s = x[i];
    for (int p = i + 1; p < l; p++) s = SUB(s, MUL(L[p + (size_t)i * l], x[p]));
    x[i] = cg_div(G, s, L[i + (size_t)i * l]);
  }
}

/* N's structure (ap_joint_fill_N after the zeroing of position_evaluator; the identity of
 * ap_data_create when n == k): ones, quaternion blocks from the data, zeros. */
static void n_structure(const ap_bmodel *M, cg_v *N) {
  int n = M->n, k = M->k;
  for (int i = 0; i < n * k; i++) N[i] = cg_const(n == k && i % (n + 1) == 0 ? 1.0 : 0.0);
  if (n == k) return;
  for (int jx = 0; jx < M->nj; jx++) {
    const ap_mjoint *j = &M->joints[jx];
    for (int i = 0; i < j->ndrivable; i++)
      if (j->qidx[i] >= 0) N[j->qidx[i] + (size_t)j->vidx[i] * n] = cg_const(1.0);
    if (j->quat < 0) continue;
    for (int r = 0; r < 4; r++)
      for (int c = 0; c < 3; c++) {
        size_t at = (size_t)(j->qidx[j->quat] + r) + (size_t)(j->vidx[j->wofs] + c) * n;
        N[at] = cg_ref('N', at);
      }
  }
}

static void store(cg_gen *G, const char *name, const cg_v *x, size_t n) {
  char t[48];
  for (size_t i = 0; i < n; i++) {
    cg_text(&x[i], t, sizeof t);
    cg_printf(G, "  %s[%zu] = %s;\n", name, i, t);
  }
}

int cg_free_speeds(const ap_bmodel *M) { return M->k > M->b ? M->k - M->b : 0; }

int cg_kin_acceleration(cg_gen *G, const ap_bmodel *M, const cg_v *gpos, const int *indep) {
  int k = M->k, n = M->n, b = M->b, l = k - b > 0 ? k - b : 0;   /* cg_free_speeds */
  size_t kk = (size_t)k * k, kl = (size_t)k * l;
  cg_v *buf = calloc(4 * kk + 3 * kl + (size_t)n * k + (size_t)l * l + 12 * (size_t)k + 8 +
                         (size_t)n,
                     sizeof *buf);
  if (!buf) return G->fail = 1, -1;
  cg_v *g = buf, *B = g + kk, *gB = B + kl, *Gm = gB + kl, *N = Gm + (size_t)l * l + kk;
  cg_v *Q = N + (size_t)n * k, *h = Q + k, *w = h + k, *v = w + k, *tk1 = v + k, *tk2 = tk1 + k;
  cg_v *Phi = tk2 + k, *edd = Phi + k, *vdot = edd + k + 1, *qdot = vdot + k + 1;
  for (size_t i = 0; i < kk; i++) g[i] = gpos[i].kind == CG_CONST ? gpos[i] : cg_ref('g', i);
  refs('B', kl, B), refs('Q', (size_t)k, Q), refs('h', (size_t)k, h), refs('w', (size_t)k, w);
  refs('v', (size_t)k, v);
  for (int i = 0; indep && b > 0 && i < l; i++) {   /* the variant: B's identity rows, w's 0s */
    for (int j = 0; j < l; j++) {
      size_t at = indep[i] + (size_t)j * k;
      cg_printf(G, "  if (B[%zu] != %s) return apc_acceleration(" CG_ACC_ARGS ");\n", at,
                i == j ? "1.0" : "0.0");
      B[at] = cg_const(i == j ? 1.0 : 0.0);
    }
    cg_printf(G, "  if (w[%d] != 0.0) return apc_acceleration(" CG_ACC_ARGS ");\n", indep[i]);
    w[indep[i]] = cg_const(0.0);
  }
  n_structure(M, N);
  gemv(G, k, k, g, w, tk1);
  for (int i = 0; i < k; i++) tk2[i] = SUB(SUB(Q[i], h[i]), tk1[i]);
  if (b == 0) {
    memcpy(Gm, g, kk * sizeof *g), memcpy(Phi, Q, (size_t)k * sizeof *Q);
    memcpy(edd, tk2, (size_t)k * sizeof *tk2);
  } else {
    congruence(G, k, l, g, B, Gm, gB);
    gemv_t(G, k, l, B, Q, Phi);
    gemv_t(G, k, l, B, tk2, edd);
  }
  chol(G, l, Gm);
  chol_solve(G, l, Gm, edd);
  char x[48];
  for (int i = 0; i < l; i++) {   /* the stage's one check: finite and at most AP_HUGE */
    cg_text(&edd[i], x, sizeof x);
    cg_printf(G, "  if (!(fabs(%s) <= %a)) return 1;\n", x, AP_HUGE);
  }
  if (b == 0) {
    memcpy(vdot, edd, (size_t)k * sizeof *edd);
  } else {
    gemv(G, k, l, B, edd, vdot);
    for (int i = 0; i < k; i++) vdot[i] = ADD(vdot[i], w[i]);
  }
  gemv(G, n, k, N, v, qdot);
  /* tk1, tk2 and gB are the core's temporaries, read by nothing after the stage: not stored */
  store(G, "G", Gm, (size_t)l * l), store(G, "Phi", Phi, (size_t)(b ? l : k));
  store(G, "edd", edd, (size_t)l), store(G, "vdot", vdot, (size_t)k);
  store(G, "qdot", qdot, (size_t)n);
  free(buf);
  return 0;
}
