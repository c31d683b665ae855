/* Scene expressions: the functions of two arguments (atan2, min, max, hypot; clamp is compiled
 * as min(max(x, lo), hi)), their values and jets, and the kinks of every function.
 *
 * For jets b = (b0, b1, b2), a = (a0, a1, a2) of Taylor coefficients (the third is f''/2):
 *   atan2(y = b, x = a): s = x0^2 + y0^2, r1 = (x0 y1 - y0 x1) / s,
 *                        r2 = (x0 y2 - y0 x2) / s - r1 (x0 x1 + y0 y1) / s
 *     (from f' = (x y' - y x') / s differentiated once more); smooth except at the origin
 *     (not finite there) and across its branch cut x < 0, y = 0, where it jumps by 2 pi (not a
 *     kink: keep the argument off the cut, e.g. atan2(sin, cos) of a lean near 0).
 *   hypot(b, a) = r: r1 = (b0 b1 + a0 a1) / r0, r2 = (b1^2 + a1^2 + 2 (b0 b2 + a0 a2) - r1^2) /
 *     (2 r0), from r^2 = a^2 + b^2 differentiated twice; not finite at the origin.
 *   min, max: the jet of the smaller (larger) operand; when the values are equal, of the one
 *     that becomes smaller (larger) along the jets (the side being entered, expr.h "Kinks"):
 *     the sign of the first non-zero coefficient of b - a.
 * NaN operands give NaN (fmin and fmax would drop them). */
#include <math.h>

#include "scene/expr_int.h"

const char *const sc_fn2_names[SC_FN2_COUNT + 2] = {"atan2", "min", "max", "hypot", "clamp",
                                                     NULL};

double sc_fn2_value(int fn, double b, double a) {
  if (isnan(a) || isnan(b)) return a + b;
  switch ((sc_fn2)fn) {
    case SC_FN2_ATAN2: return atan2(b, a);
    case SC_FN2_MIN: return b < a ? b : a;
    case SC_FN2_MAX: return b > a ? b : a;
    case SC_FN2_HYPOT: return hypot(b, a);
    case SC_FN2_COUNT: break;
  }
  return NAN;
}

/* Which operand min (want < 0) or max (want > 0) takes: 1 for b, 0 for a. */
static int pick_b(const sc_jet *b, const sc_jet *a, double want) {
  for (int i = 0; i < 3; i++) {
    double d = b->c[i] - a->c[i];
    if (d != 0.0) return d * want > 0.0;
  }
  return 1;
}

void sc_fn2_jet(int fn, const sc_jet *b, const sc_jet *a, sc_jet *r) {
  double y = sc_fn2_value(fn, b->c[0], a->c[0]), r1, r2;
  if ((fn == SC_FN2_MIN || fn == SC_FN2_MAX) && !isnan(y)) {
    *r = pick_b(b, a, fn == SC_FN2_MIN ? -1.0 : 1.0) ? *b : *a;
    return;
  }
  if (fn == SC_FN2_ATAN2) {   /* b = y, a = x */
    double s = a->c[0] * a->c[0] + b->c[0] * b->c[0];
    r1 = (a->c[0] * b->c[1] - b->c[0] * a->c[1]) / s;
    r2 = (a->c[0] * b->c[2] - b->c[0] * a->c[2]) / s -
         r1 * (a->c[0] * a->c[1] + b->c[0] * b->c[1]) / s;
  } else {
    r1 = (b->c[0] * b->c[1] + a->c[0] * a->c[1]) / y;
    r2 = (b->c[1] * b->c[1] + a->c[1] * a->c[1] + 2.0 * (b->c[0] * b->c[2] + a->c[0] * a->c[2]) -
          r1 * r1) / (2.0 * y);
  }
  if (b->c[1] == 0.0 && b->c[2] == 0.0 && a->c[1] == 0.0 && a->c[2] == 0.0) r1 = r2 = 0.0;
  r->c[0] = y, r->c[1] = r1, r->c[2] = r2;
}

int sc_is_kink(const sc_ins *in) {
  if (in->op == SC_OP_FN2) return in->fn == SC_FN2_MIN || in->fn == SC_FN2_MAX;
  return in->op == SC_OP_FN && (in->fn == SC_FN_ABS || in->fn == SC_FN_STEP ||
                                in->fn == SC_FN_DELTA || in->fn == SC_FN_SIGN ||
                                in->fn == SC_FN_FLOOR);
}

double sc_kink_arg(const sc_ins *in, double b, double a) {
  if (in->op == SC_OP_FN2) return b - a;
  return in->fn == SC_FN_FLOOR ? sin(3.14159265358979323846 * a) : a;
}
