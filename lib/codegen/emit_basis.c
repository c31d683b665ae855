/* The partitioned null-space basis and particular solution of lib/linalg/nullspace.c
 * (ap_la_partition_basis without a condition estimate, ap_la_partition_particular) on traced
 * values at the model's fixed sizes, and the stages' one finiteness check each.
 *
 * Basis: the QR of the dependent columns Ad = A[:, perm[0..r-1]] (b x r, r = min(b, k): the
 * generated path takes rows of full rank only), then C = R^-1 Q^T [A_i a0], B = P [-C ; I],
 * b0 = P [-c0 ; 0], with the growth max |C_ij| and the residual of the redundant rows (rows r..
 * of Q^T [A_i a0]). The partition perm is a run-time input: columns are gathered through it,
 * so a partition change along a run needs no new code. It mirrors max_col_norm, house,
 * house_apply, qr_native, diag_ok and qr_solve_native (linalg/householder.inc) operation by
 * operation, taking the branch those take on ordinary numbers (sums of squares inside the
 * normal range, pivots away from underflow) and the one of a column that is exactly zero below
 * the diagonal (tau = 0: the reflector is skipped, a run-time branch in the generated code too);
 * anywhere the library would take another branch (scaled norms, divisions in place of
 * reciprocals, a singular R11) the generated function returns 1 and the library's routine runs
 * on the same input and decides (and reports). So the results are the library's to the last
 * bit, the sign of zeros included.
 * Particular: c = Q^T gamma, c = R^-1 c (divisions), w = P [c ; 0]; a Householder scalar tau
 * of 0 at run time skips its reflector, as the library does.
 * Checks: the sum of |x| over every output of a stage that is not a constant (g's structural
 * entries, A, a0; h, Q, gamma): a rounded sum of magnitudes is at least each of them, so a sum
 * at most AP_HUGE means every entry is finite and at most AP_HUGE. Otherwise (a NaN, an Inf,
 * or a sum beyond the bound) the core's per-array checks run and name the array and entry. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codegen/codegen.h"

#define ADD(a, b) cg_add(G, a, b)
#define SUB(a, b) cg_sub(G, a, b)
#define MUL(a, b) cg_mul(G, a, b)

/* "if (!(cond)) return 1;" with cond's %s filled by the text of x (twice when it appears
 * twice). */
static void guard(cg_gen *G, const char *cond, cg_v x) {
  char t[48], c[256];
  cg_text(&x, t, sizeof t);
  snprintf(c, sizeof c, cond, t, t);
  cg_printf(G, "  if (!(%s)) return 1;\n", c);
}

/* A run-time branch of the library's (an early return, a tau of 0) in straight-line code: the
 * n values x get mutable copies ("double t = x;"), which the block "if (nz) { ... }" assigns
 * (block_end); outside, x are the copies. */
static void block_begin(cg_gen *G, const char *nz, int n, cg_v *x, int *ids) {
  char t[48];
  for (int i = 0; i < n; i++) {
    ids[i] = G->ntemp++;
    cg_text(&x[i], t, sizeof t);
    cg_printf(G, "  double t%d = %s;\n", ids[i], t);
  }
  cg_printf(G, "  if (%s) {\n", nz);
}

static void block_end(cg_gen *G, int n, const cg_v *res, const int *ids, cg_v *x) {
  char t[48];
  for (int i = 0; i < n; i++) {
    cg_text(&res[i], t, sizeof t);
    cg_printf(G, "  t%d = %s;\n", ids[i], t);
    x[i] = (cg_v){CG_TEMP, 0.0, ids[i], 0, 0};
  }
  cg_printf(G, "  }\n");
}

/* house (x: n traced entries): the plain-sum branch, or, when x_1.. are exactly zero (a row
 * of A with zeros, as on an upright disk), H = I (tau = 0, x unchanged), as the library's
 * scaled branch decides there; any other number returns 1. nz gets the name of the run-time
 * int "tau is not 0" ("" when n <= 1: tau is the constant 0). Returns tau. */
static cg_v house(cg_gen *G, int n, cg_v *x, char *nz) {
  nz[0] = '\0';
  if (n <= 1) return cg_const(0.0);
  cg_v alpha = x[0], ss = cg_const(0.0);
  for (int i = 1; i < n; i++) ss = ADD(ss, MUL(x[i], x[i]));
  cg_v aa = ADD(MUL(alpha, alpha), ss);
  char a[48], s[48], t[48];
  cg_text(&ss, s, sizeof s), cg_text(&aa, a, sizeof a);
  int id = G->ntemp++;
  snprintf(nz, 24, "z%d", id);
  cg_printf(G, "  const int z%d = %s >= 0x1p-969 && %s <= 0x1.fffffffffffffp+1023;\n"
            "  if (!z%d && !(", id, s, a, id);
  for (int i = 1; i < n; i++)
    cg_text(&x[i], t, sizeof t), cg_printf(G, "%s%s == 0.0", i > 1 ? " && " : "", t);
  cg_printf(G, ")) return 1;\n");
  cg_v *res = malloc(((size_t)n + 1) * sizeof *res);
  int *ids = malloc(((size_t)n + 1) * sizeof *ids);
  if (!res || !ids) {
    free(res), free(ids), G->fail = 1;
    return cg_const(0.0);
  }
  memcpy(res, x, (size_t)n * sizeof *x), res[n] = cg_const(0.0);   /* x, then tau */
  block_begin(G, nz, n + 1, res, ids);
  cg_v beta = cg_call(G, "sqrt", aa);
  cg_text(&alpha, a, sizeof a), cg_text(&beta, t, sizeof t);
  cg_v sb = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s >= 0.0 ? -%s : %s;\n", sb.id, a, t, t);
  cg_v tau = cg_div(G, SUB(sb, alpha), sb), d = SUB(alpha, sb), out[1];
  cg_text(&d, t, sizeof t);
  cg_printf(G, "  if (!(fabs(%s) >= 0x1p-1000)) return 1;\n", t);
  cg_v rs = cg_div(G, cg_const(1.0), d);
  cg_v *nx = malloc(((size_t)n + 1) * sizeof *nx);
  if (!nx) {
    free(res), free(ids), G->fail = 1;
    return cg_const(0.0);
  }
  for (int i = 1; i < n; i++) nx[i] = MUL(x[i], rs);
  nx[0] = sb, nx[n] = tau;
  block_end(G, n + 1, nx, ids, res);
  memcpy(x, res, (size_t)n * sizeof *x), out[0] = res[n];
  free(res), free(ids), free(nx);
  return out[0];
}

/* house_apply; nz: the run-time "tau is not 0" (c unchanged otherwise, as the library's early
 * return), "" when tau is a constant. */
static void house_apply(cg_gen *G, int n, const cg_v *v, cg_v tau, const char *nz, cg_v *c) {
  if (tau.kind == CG_CONST && tau.c == 0.0) return;
  int ids[64];
  cg_v old[64];
  if (nz[0]) memcpy(old, c, (size_t)n * sizeof *c), block_begin(G, nz, n, old, ids);
  cg_v s = c[0], res[64];
  for (int i = 1; i < n; i++) s = ADD(s, MUL(v[i], c[i]));
  s = MUL(s, tau);
  res[0] = SUB(c[0], s);
  for (int i = 1; i < n; i++) res[i] = SUB(c[i], MUL(s, v[i]));
  if (nz[0]) block_end(G, n, res, ids, c);
  else memcpy(c, res, (size_t)n * sizeof *c);
}

/* c (r) = R^-1 c, by reciprocals (rinv) or, when rinv is NULL, divisions. */
static void solve_upper(cg_gen *G, int r, const cg_v *R, int ld, const cg_v *rinv, cg_v *c) {
  for (int j = r - 1; j >= 0; j--) {
    const cg_v *Rj = R + (size_t)j * ld;
    cg_v cj = c[j] = rinv ? MUL(c[j], rinv[j]) : cg_div(G, c[j], Rj[j]);
    for (int i = 0; i < j; i++) c[i] = SUB(c[i], MUL(cj, Rj[i]));
  }
}

/* max_abs over an m x n block (ld): v = |x| > v ? |x| : v from 0, in the library's order. */
static void max_abs(cg_gen *G, const char *out, int m, int n, const cg_v *M, int ld) {
  char t[48];
  cg_printf(G, "  *%s = 0.0;\n", out);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) {
      cg_text(&M[i + (size_t)j * ld], t, sizeof t);
      cg_printf(G, "  if (fabs(%s) > *%s) *%s = fabs(%s);\n", t, out, out, t);
    }
}

/* A traced load of column perm[col] of A (ld b), row i. */
static cg_v gather(cg_gen *G, const char *arr, int col, int i) {
  cg_v r = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
  cg_printf(G, "  const double t%d = %s[p%d + %d];\n", r.id, arr, col, i);
  return r;
}

static void emit_basis(cg_gen *G, int b, int k, cg_v *F, cg_v *C) {
  int r = cg_basis_rank(b, k), l = k - r, nc = l + 1;
  cg_tu(G);
  cg_printf(G, "int apc_basis(const int *perm, const double *A, const double *a0, double *F, "
            "double *tau, double *B, double *b0, double *growth, double *resid) {\n"
            "  const double *a = a0;\n");
  for (int j = 0; j < k; j++) cg_printf(G, "  const int p%d = perm[%d] * %d;\n", j, j, b);
  for (int j = 0; j < r; j++)
    for (int i = 0; i < b; i++) F[i + (size_t)j * b] = gather(G, "A", j, i);
  cg_v mx = cg_const(0.0);   /* max_col_norm: squared norms in the normal range */
  for (int j = 0; j < r; j++) {
    cg_v ss = cg_const(0.0);
    for (int i = 0; i < b; i++) ss = ADD(ss, MUL(F[i + (size_t)j * b], F[i + (size_t)j * b]));
    guard(G, "%s >= 0x1p-969 && %s <= 0x1.fffffffffffffp+1023", ss);
    char s[48], m[48];
    cg_text(&ss, s, sizeof s), cg_text(&mx, m, sizeof m);
    cg_v nm = {CG_TEMP, 0.0, G->ntemp++, 0, 0};
    cg_printf(G, "  const double t%d = %s > %s ? %s : %s;\n", nm.id, s, m, s, m);
    mx = nm;
  }
  cg_v tol = MUL(cg_const(64.0 * 0x1p-52), cg_call(G, "sqrt", mx)), tau[64];
  char nz[64][24];
  for (int i = 0; i < r; i++) {   /* qr_native */
    cg_v *v = F + i + (size_t)i * b;
    tau[i] = house(G, b - i, v, nz[i]);
    for (int j = i + 1; j < r; j++)
      house_apply(G, b - i, v, tau[i], nz[i], F + i + (size_t)j * b);
  }
  for (int i = 0; i < r; i++) {   /* diag_ok */
    cg_v dd = F[i + (size_t)i * b];
    char x[48], t[48];
    cg_text(&dd, x, sizeof x), cg_text(&tol, t, sizeof t);
    cg_printf(G, "  if (!(fabs(%s) > %s) || !isfinite(%s)) return 1;\n", x, t, x);
  }
  for (int j = 0; j < l; j++)
    for (int i = 0; i < b; i++) C[i + (size_t)j * b] = gather(G, "A", r + j, i);
  for (int i = 0; i < b; i++) C[i + (size_t)l * b] = cg_ref('a', (size_t)i);
  cg_v rinv[64];
  for (int i = 0; i < r; i++) {   /* qr_solve_native */
    guard(G, "fabs(%s) >= 0x1p-1000", F[i + (size_t)i * b]);
    rinv[i] = cg_div(G, cg_const(1.0), F[i + (size_t)i * b]);
  }
  for (int j = 0; j < nc; j++) {
    cg_v *c = C + (size_t)j * b;
    for (int i = 0; i < r; i++)
      house_apply(G, b - i, F + i + (size_t)i * b, tau[i], nz[i], c + i);
    solve_upper(G, r, F, b, rinv, c);
  }
  max_abs(G, "resid", b - r, nc, C + r, b);
  max_abs(G, "growth", r, l, C, b);
  char t[48];
  for (size_t i = 0; i < (size_t)b * r; i++)
    cg_text(&F[i], t, sizeof t), cg_printf(G, "  F[%zu] = %s;\n", i, t);
  for (int i = 0; i < r; i++)
    cg_text(&tau[i], t, sizeof t), cg_printf(G, "  tau[%d] = %s;\n", i, t);
  for (int j = 0; j < l; j++) {
    for (int i = 0; i < r; i++)
      cg_text(&C[i + (size_t)j * b], t, sizeof t),
          cg_printf(G, "  B[%d + perm[%d]] = -%s;\n", j * k, i, t);
    for (int i = 0; i < l; i++)
      cg_printf(G, "  B[%d + perm[%d]] = %s;\n", j * k, r + i, i == j ? "1.0" : "0.0");
  }
  for (int i = 0; i < k; i++) cg_printf(G, "  b0[%d] = 0.0;\n", i);
  for (int i = 0; i < r; i++)
    cg_text(&C[i + (size_t)l * b], t, sizeof t), cg_printf(G, "  b0[perm[%d]] = -%s;\n", i, t);
  cg_printf(G, "  return 0;\n}\n\n");
}

static void emit_particular(cg_gen *G, int b, int k, cg_v *F, cg_v *c) {
  int r = cg_basis_rank(b, k);
  cg_tu(G);
  cg_printf(G, "int apc_particular(const int *perm, const double *F, const double *tau, "
            "const double *gamma, double *w, double *resid) {\n"
            "  const double *c = gamma, *u = tau;\n");
  for (size_t i = 0; i < (size_t)b * r; i++) F[i] = cg_ref('F', i);
  for (int i = 0; i < r; i++)   /* diag_ok with tol 0 */
    guard(G, "fabs(%s) > 0.0 && isfinite(%s)", F[i + (size_t)i * b]);
  for (int i = 0; i < b; i++) c[i] = cg_ref('c', (size_t)i);
  for (int i = 0; i < r; i++) {   /* qt_apply */
    cg_v tau = b - i <= 1 ? cg_const(0.0) : cg_ref('u', (size_t)i);
    char nz[24] = "";
    if (b - i > 1) snprintf(nz, sizeof nz, "(u[%d] != 0.0)", i);
    house_apply(G, b - i, F + i + (size_t)i * b, tau, nz, c + i);
  }
  solve_upper(G, r, F, b, NULL, c);
  char t[48];
  for (int i = 0; i < k; i++) cg_printf(G, "  w[%d] = 0.0;\n", i);
  for (int i = 0; i < r; i++)
    cg_text(&c[i], t, sizeof t), cg_printf(G, "  w[perm[%d]] = %s;\n", i, t);
  max_abs(G, "resid", b - r, 1, c + r, b);
  cg_printf(G, "  return 0;\n}\n\n");
}

int cg_basis_rank(int b, int k) { return b < k ? b : k; }

int cg_basis_supported(const ap_bmodel *M) { return M->b > 0 && M->b <= 64; }

/* One sum of magnitudes over the listed arrays' entries (those with a NULL or non-constant
 * structure entry). */
static void emit_check(cg_gen *G, const char *name, const char *const arr[3], const int len[3],
                       const cg_v *gstruct) {
  cg_tu(G);
  cg_printf(G, "int %s(const double *%s, const double *%s, const double *%s) {\n"
            "  double s0 = 0.0, s1 = 0.0;\n  (void)%s, (void)%s, (void)%s;\n",
            name, arr[0], arr[1], arr[2], arr[0], arr[1], arr[2]);
  int n = 0;
  for (int a = 0; a < 3; a++)
    for (int i = 0; i < len[a]; i++) {
      if (a == 0 && gstruct && gstruct[i].kind == CG_CONST) continue;   /* folded: finite */
      cg_printf(G, "  s%d += fabs(%s[%d]);\n", n++ & 1, arr[a], i);
    }
  cg_printf(G, "  return s0 + s1 <= %a;\n}\n\n", AP_HUGE);
}

void cg_emit_basis(cg_gen *G, const ap_bmodel *M, const cg_v *gpos) {
  int b = M->b, k = M->k;
  static const char *const pos[3] = {"g", "A", "a0"}, *const vel[3] = {"h", "Q", "gamma"};
  int lp[3] = {k * k, b * k, b}, lv[3] = {k, k, b};
  emit_check(G, "apc_finite_pos", pos, lp, gpos);
  emit_check(G, "apc_finite_vel", vel, lv, NULL);
  if (!cg_basis_supported(M)) return;
  cg_v *buf = calloc((size_t)b * (k + 1) + (size_t)b * b + 1, sizeof *buf);
  if (!buf) {
    G->fail = 1;
    return;
  }
  emit_basis(G, b, k, buf, buf + (size_t)b * b);
  emit_particular(G, b, k, buf, buf + (size_t)b * b);
  free(buf);
}
