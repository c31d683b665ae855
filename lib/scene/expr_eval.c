/* Scene expressions: evaluation of a compiled program (expr.h) on values and on second-order
 * Taylor jets, and the explanation of a value that is not finite.
 *
 * A stack machine over the postfix code: pushes (t, x[slot], constant) and operations on the
 * top entries. The stack is a local array of SC_PROG_STACK + 1 entries whose first is never used
 * (the top starts there, so the pointer stays inside the array; the compiler refused any
 * program deeper than SC_PROG_STACK), so evaluation allocates nothing and writes nothing but the
 * caller's outputs. Jet rules, for b OP a with jets (b0, b1, b2) and (a0, a1, a2) of Taylor
 * coefficients (the third is f''/2):
 *   b * a:  r0 = b0 a0,  r1 = b0 a1 + b1 a0,  r2 = b0 a2 + b1 a1 + b2 a0
 *   b / a:  r0 = b0 / a0,  r1 = (b1 - r0 a1) / a0,  r2 = (b2 - r0 a2 - r1 a1) / a0
 *   u ^ k (k constant; also u ^ a when a's jet does not move): r0 = u^k, r1 = k u^(k-1) u1,
 *           r2 = k u^(k-1) u2 + k (k-1) u^(k-2) u1^2 / 2, with k = 0, 1, 2 and a fixed u
 *           exact (so t^2 at t < 0 and t^1 at t = 0 are fine)
 *   b ^ a (a moves): exp(a log b) by the log and exp rules, the value from pow itself
 *   functions: expr_fn.c.
 * The value r0 of every rule is computed exactly as the value-only path computes it, so
 * sc_prog_value and the c[0] of sc_prog_jet agree bit for bit (and constants folded at
 * compile time equal the evaluated ones). x^2 is x*x on both paths. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/expr_int.h"

int sc_op_push(int op) {
  return op <= SC_OP_K ? 1 : op >= SC_OP_ADD && op <= SC_OP_FN2 ? -1 : 0;
}

#if defined(__GNUC__)
#define SC_INLINE inline __attribute__((always_inline))
#else
#define SC_INLINE inline
#endif

static double pow_value(double u, double k) { return k == 2.0 ? u * u : pow(u, k); }

/* One instruction on a stack of values whose top is *top; returns the new top. */
static SC_INLINE double *step_value(const sc_ins *in, const double *k, double t, const double *x,
                                    double *top) {
  switch ((sc_op)in->op) {
    case SC_OP_T: *++top = t; break;
    case SC_OP_X: *++top = x[in->arg]; break;
    case SC_OP_K: *++top = k[in->arg]; break;
    case SC_OP_NEG: *top = -*top; break;
    case SC_OP_FN: *top = sc_fn_value(in->fn, *top); break;
    case SC_OP_ADD: top--, top[0] = top[0] + top[1]; break;
    case SC_OP_SUB: top--, top[0] = top[0] - top[1]; break;
    case SC_OP_MUL: top--, top[0] = top[0] * top[1]; break;
    case SC_OP_DIV: top--, top[0] = top[0] / top[1]; break;
    case SC_OP_POW: top--, top[0] = pow_value(top[0], top[1]); break;
    case SC_OP_FN2: top--, top[0] = sc_fn2_value(in->fn, top[0], top[1]); break;
    case SC_OP_ADDK: *top = *top + k[in->arg]; break;
    case SC_OP_RSUBK: *top = k[in->arg] - *top; break;
    case SC_OP_MULK: *top = *top * k[in->arg]; break;
    case SC_OP_DIVK: *top = *top / k[in->arg]; break;
    case SC_OP_RDIVK: *top = k[in->arg] / *top; break;
    case SC_OP_POWK: *top = pow_value(*top, k[in->arg]); break;
    case SC_OP_RPOWK: *top = pow_value(k[in->arg], *top); break;
  }
  return top;
}

double sc_op_value(const sc_ins *in, const double *k, double b, double a) {
  double st[3] = {b, a, 0.0};   /* room for a push (not called with one) */
  return *step_value(in, k, 0.0, NULL, st + 1);
}

/* ---- jet rules ---------------------------------------------------------------------------- */

static SC_INLINE void jet_mul(const sc_jet *b, const sc_jet *a, sc_jet *r) {
  double r0 = b->c[0] * a->c[0], r1 = b->c[0] * a->c[1] + b->c[1] * a->c[0];
  r->c[2] = b->c[0] * a->c[2] + b->c[1] * a->c[1] + b->c[2] * a->c[0];
  r->c[0] = r0, r->c[1] = r1;
}

static void jet_div(const sc_jet *b, const sc_jet *a, sc_jet *r) {
  double r0 = b->c[0] / a->c[0], r1 = (b->c[1] - r0 * a->c[1]) / a->c[0];
  r->c[2] = (b->c[2] - r0 * a->c[2] - r1 * a->c[1]) / a->c[0];
  r->c[0] = r0, r->c[1] = r1;
}

/* u ^ k for a constant k. */
static void jet_powk(const sc_jet *u, double k, sc_jet *r) {
  double u0 = u->c[0], u1 = u->c[1], u2 = u->c[2], y = pow_value(u0, k), d1, d2;
  if ((u1 == 0.0 && u2 == 0.0) || k == 0.0) {
    r->c[0] = y, r->c[1] = 0.0, r->c[2] = 0.0;
    return;
  }
  if (k == 1.0) {
    *r = *u;
    return;
  }
  if (k == 2.0) {
    d1 = 2.0 * u0, d2 = 2.0;
  } else {
    d1 = k * pow(u0, k - 1.0), d2 = k * (k - 1.0) * pow(u0, k - 2.0);
  }
  r->c[0] = y;
  r->c[1] = d1 * u1;
  r->c[2] = d1 * u2 + 0.5 * d2 * u1 * u1;
}

/* b ^ a = exp(a log b). */
static void jet_pow(const sc_jet *b, const sc_jet *a, sc_jet *r) {
  if (a->c[1] == 0.0 && a->c[2] == 0.0) {
    jet_powk(b, a->c[0], r);
    return;
  }
  double y = pow_value(b->c[0], a->c[0]);
  if (b->c[1] == 0.0 && b->c[2] == 0.0 && y == 0.0) {   /* 0 ^ a near a > 0: 0 */
    r->c[0] = y, r->c[1] = 0.0, r->c[2] = 0.0;
    return;
  }
  double l0 = log(b->c[0]), l1 = b->c[1] / b->c[0], l2 = b->c[2] / b->c[0] - 0.5 * l1 * l1;
  double m1 = a->c[0] * l1 + a->c[1] * l0, m2 = a->c[0] * l2 + a->c[1] * l1 + a->c[2] * l0;
  r->c[0] = y, r->c[1] = y * m1, r->c[2] = y * (m2 + 0.5 * m1 * m1);
}

/* One instruction on a stack of jets whose top is *top; returns the new top. */
static SC_INLINE sc_jet *step_jet(const sc_ins *in, const double *kk, const sc_jet *t,
                                  const sc_jet *x, sc_jet *top) {
  double k = sc_op_reads_k(in->op) ? kk[in->arg] : 0.0;
  sc_jet c = {{k, 0.0, 0.0}};
  switch ((sc_op)in->op) {
    case SC_OP_T: *++top = *t; break;
    case SC_OP_X: *++top = x[in->arg]; break;
    case SC_OP_K: *++top = c; break;
    case SC_OP_NEG: top->c[0] = -top->c[0], top->c[1] = -top->c[1], top->c[2] = -top->c[2]; break;
    case SC_OP_FN: sc_fn_jet(in->fn, top, top); break;
    case SC_OP_ADD:
      top--;
      top->c[0] = top->c[0] + top[1].c[0], top->c[1] += top[1].c[1], top->c[2] += top[1].c[2];
      break;
    case SC_OP_SUB:
      top--;
      top->c[0] = top->c[0] - top[1].c[0], top->c[1] -= top[1].c[1], top->c[2] -= top[1].c[2];
      break;
    case SC_OP_MUL: top--, jet_mul(top, top + 1, top); break;
    case SC_OP_DIV: top--, jet_div(top, top + 1, top); break;
    case SC_OP_POW: top--, jet_pow(top, top + 1, top); break;
    case SC_OP_FN2: top--, sc_fn2_jet(in->fn, top, top + 1, top); break;
    case SC_OP_ADDK: top->c[0] = top->c[0] + k; break;
    case SC_OP_RSUBK: top->c[0] = k - top->c[0], top->c[1] = -top->c[1], top->c[2] = -top->c[2];
      break;
    case SC_OP_MULK: top->c[0] *= k, top->c[1] *= k, top->c[2] *= k; break;
    case SC_OP_DIVK: top->c[0] /= k, top->c[1] /= k, top->c[2] /= k; break;
    case SC_OP_RDIVK: jet_div(&c, top, top); break;
    case SC_OP_POWK: jet_powk(top, k, top); break;
    case SC_OP_RPOWK: jet_pow(&c, top, top); break;
  }
  return top;
}

/* ---- the interpreters --------------------------------------------------------------------- */

int sc_prog_value(const sc_prog *p, double t, const double *x, double *f) {
  double st[SC_PROG_STACK + 1], *top = st;
  for (const sc_ins *in = p->ins, *end = in + p->nins; in < end; in++)
    top = step_value(in, p->k, t, x, top);
  *f = st[1];
  return isfinite(st[1]) ? 0 : -1;
}

int sc_prog_nkinks(const sc_prog *p) {
  int n = 0;
  for (int i = 0; p && i < p->nins; i++) n += sc_is_kink(&p->ins[i]);
  return n;
}

int sc_prog_kinks(const sc_prog *p, double t, const double *x, double *args) {
  double st[SC_PROG_STACK + 1], *top = st;
  int n = 0;
  st[0] = 0.0;   /* the b of a one-operand kink at the bottom (unused by sc_kink_arg) */
  for (const sc_ins *in = p->ins, *end = in + p->nins; in < end; in++) {
    if (sc_is_kink(in)) args[n++] = sc_kink_arg(in, top[-1], top[0]);
    top = step_value(in, p->k, t, x, top);
  }
  return n;
}

int sc_prog_jet(const sc_prog *p, const sc_jet *t, const sc_jet *x, sc_jet *f) {
  sc_jet st[SC_PROG_STACK + 1], *top = st;
  for (const sc_ins *in = p->ins, *end = in + p->nins; in < end; in++)
    top = step_jet(in, p->k, t, x, top);
  *f = st[1];
  return isfinite(f->c[0]) && isfinite(f->c[1]) && isfinite(f->c[2]) ? 0 : -1;
}

int sc_prog_time(const sc_prog *p, double t, double f[3]) {
  if (p->nvars > 0) {
    f[0] = f[1] = f[2] = NAN;
    return -1;
  }
  sc_jet tj = {{t, 1.0, 0.0}}, r;
  int rc = sc_prog_jet(p, &tj, NULL, &r);
  f[0] = r.c[0], f[1] = r.c[1], f[2] = 2.0 * r.c[2];
  return rc;
}

/* ---- explaining a value that is not finite ------------------------------------------------ */

static void num(char *out, size_t len, double x) {
  if (isnan(x)) snprintf(out, len, "nan");
  else snprintf(out, len, "%.10g", x);
}

/* "log(-1) = nan", "1 / 0 = inf", "abs(0) has no derivative: ..." for instruction in, whose
 * operands were b and a and whose result r is not finite in coefficient bad. */
static void describe(const sc_prog *p, const sc_ins *in, const sc_jet *b, const sc_jet *a,
                     const sc_jet *r, int bad, char *buf, size_t len) {
  static const char *const order[] = {"", "first", "second"};
  static const char sym[] = {[SC_OP_ADD] = '+', [SC_OP_SUB] = '-', [SC_OP_MUL] = '*',
                             [SC_OP_DIV] = '/', [SC_OP_POW] = '^', [SC_OP_ADDK] = '+',
                             [SC_OP_RSUBK] = '-', [SC_OP_MULK] = '*', [SC_OP_DIVK] = '/',
                             [SC_OP_RDIVK] = '/', [SC_OP_POWK] = '^', [SC_OP_RPOWK] = '^'};
  char x[40], y[40], z[40], what[256];
  num(x, sizeof x, b->c[0]), num(y, sizeof y, a->c[0]), num(z, sizeof z, r->c[bad]);
  int op = in->op;
  if (sc_op_reads_k(op) && op != SC_OP_K) {   /* a OP k, k OP a */
    int left = op == SC_OP_RSUBK || op == SC_OP_RDIVK || op == SC_OP_RPOWK;
    num(left ? x : y, sizeof x, p->k[in->arg]);
    if (!left) num(x, sizeof x, a->c[0]);
  }
  switch ((sc_op)op) {
    case SC_OP_T: snprintf(what, sizeof what, "t = %s", z); break;
    case SC_OP_X: snprintf(what, sizeof what, "the variable in slot %d is %s", in->arg, z); break;
    case SC_OP_K: snprintf(what, sizeof what, "a constant part is %s", z); break;
    case SC_OP_NEG: snprintf(what, sizeof what, "-(%s) = %s", y, z); break;
    case SC_OP_FN:
      if (bad)
        snprintf(what, sizeof what, "%s(%s) has no finite %s derivative", sc_fn_names[in->fn], y,
                 order[bad]);
      else
        snprintf(what, sizeof what, "%s(%s) = %s", sc_fn_names[in->fn], y, z);
      break;
    case SC_OP_FN2:
      if (bad)
        snprintf(what, sizeof what, "%s(%s, %s) has no finite %s derivative",
                 sc_fn2_names[in->fn], x, y, order[bad]);
      else
        snprintf(what, sizeof what, "%s(%s, %s) = %s", sc_fn2_names[in->fn], x, y, z);
      break;
    default:
      if (bad)
        snprintf(what, sizeof what, "%s %c %s has no finite %s derivative", x, sym[op], y,
                 order[bad]);
      else
        snprintf(what, sizeof what, "%s %c %s = %s", x, sym[op], y, z);
      break;
  }
  snprintf(buf, len, "%s (column %d of the expression)", what, in->col + 1);
}

int sc_prog_explain(const sc_prog *p, const sc_jet *t, const sc_jet *x, int order, char *buf,
                    size_t len) {
  sc_jet st[SC_PROG_STACK + 1], *top = st;
  if (len) buf[0] = '\0';
  for (const sc_ins *in = p->ins, *end = in + p->nins; in < end; in++) {
    sc_jet zero = {{0.0, 0.0, 0.0}};
    int push = sc_op_push(in->op);
    sc_jet a = push > 0 ? zero : top[0], b = push < 0 ? top[-1] : zero;
    top = step_jet(in, p->k, t, x, top);
    for (int c = 0; c <= order && c < 3; c++) {
      if (isfinite(top->c[c])) continue;
      describe(p, in, &b, &a, top, c, buf, len);
      return in->col + 1;
    }
  }
  return 0;
}
