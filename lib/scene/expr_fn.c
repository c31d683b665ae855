/* Scene expressions: the functions of the grammar, their values and their jets.
 *
 * For a function phi and an argument jet a = (a0, a1, a2) (Taylor coefficients: a1 = u',
 * a2 = u''/2), the result is the chain rule truncated at second order,
 *   r0 = phi(a0),  r1 = phi'(a0) a1,  r2 = phi'(a0) a2 + phi''(a0) a1^2 / 2,
 * with phi' and phi'' the closed forms below (written with phi's own value y where that saves
 * a libm call without a cancellation: tanh' is 1/cosh^2, not 1 - tanh^2). An argument jet
 * with a1 = a2 = 0 (the argument does not move) gives r1 = r2 = 0 whatever phi' is there, so
 * sqrt(x) of a variable x = 0 held fixed is fine.
 *
 * Definitions, as libmatheval 1.1 (the evaluator this one replaced) gave them: cot = 1/tan,
 * sec = 1/cos, csc = 1/sin, acot(u) = atan(1/u), asec(u) = acos(1/u), acsc(u) = asin(1/u),
 * coth = 1/tanh, sech = 1/cosh, csch = 1/sinh, acoth(u) = atanh(1/u), asech(u) = acosh(1/u),
 * acsch(u) = asinh(1/u); step(u) = 0 for u < 0 and 1 for u >= 0; delta(u) = 0 for u != 0 and
 * +inf at 0. The derivative of acoth is 1/(1 - u^2) (libmatheval had the sign wrong). At the
 * kinks of abs and step (u = 0) phi' and phi'' are those of the side the argument's jet
 * enters, delta's are NaN: expr.h, "Kinks". NaN arguments
 * give NaN (libmatheval's step(NaN) was 1). sign(u) is -1, 0, 1 and floor(u) the largest
 * integer <= u; both have derivatives 0. At their jumps (u = 0, u an integer) with a moving
 * argument the jet takes the value of the side being entered (sign(t) at t = 0 is 1 on the jet,
 * floor(-t) at t = 0 is -1): a run restarted exactly at the jump integrates the next piece. The
 * value path gives sign(0) = 0 and floor(n) = n. */
#include <math.h>

#include "scene/expr_int.h"

#define SC_2_SQRTPI 1.12837916709551257390 /* 2/sqrt(pi) */

const char *const sc_fn_names[SC_FN_COUNT + 1] = {
    "exp",   "log",   "sqrt",  "sin",   "cos",   "tan",   "cot",   "sec",   "csc",
    "asin",  "acos",  "atan",  "acot",  "asec",  "acsc",  "sinh",  "cosh",  "tanh",
    "coth",  "sech",  "csch",  "asinh", "acosh", "atanh", "acoth", "asech", "acsch",
    "erf",   "abs",   "step",  "delta", "sign",  "floor", NULL};

double sc_fn_value(int fn, double u) {
  switch ((sc_fn)fn) {
    case SC_FN_EXP: return exp(u);
    case SC_FN_LOG: return log(u);
    case SC_FN_SQRT: return sqrt(u);
    case SC_FN_SIN: return sin(u);
    case SC_FN_COS: return cos(u);
    case SC_FN_TAN: return tan(u);
    case SC_FN_COT: return 1.0 / tan(u);
    case SC_FN_SEC: return 1.0 / cos(u);
    case SC_FN_CSC: return 1.0 / sin(u);
    case SC_FN_ASIN: return asin(u);
    case SC_FN_ACOS: return acos(u);
    case SC_FN_ATAN: return atan(u);
    case SC_FN_ACOT: return atan(1.0 / u);
    case SC_FN_ASEC: return acos(1.0 / u);
    case SC_FN_ACSC: return asin(1.0 / u);
    case SC_FN_SINH: return sinh(u);
    case SC_FN_COSH: return cosh(u);
    case SC_FN_TANH: return tanh(u);
    case SC_FN_COTH: return 1.0 / tanh(u);
    case SC_FN_SECH: return 1.0 / cosh(u);
    case SC_FN_CSCH: return 1.0 / sinh(u);
    case SC_FN_ASINH: return asinh(u);
    case SC_FN_ACOSH: return acosh(u);
    case SC_FN_ATANH: return atanh(u);
    case SC_FN_ACOTH: return atanh(1.0 / u);
    case SC_FN_ASECH: return acosh(1.0 / u);
    case SC_FN_ACSCH: return asinh(1.0 / u);
    case SC_FN_ERF: return erf(u);
    case SC_FN_ABS: return fabs(u);
    case SC_FN_STEP: return isnan(u) ? u : u < 0.0 ? 0.0 : 1.0;
    case SC_FN_DELTA: return isnan(u) ? u : u == 0.0 ? INFINITY : 0.0;
    case SC_FN_SIGN: return isnan(u) ? u : u > 0.0 ? 1.0 : u < 0.0 ? -1.0 : 0.0;
    case SC_FN_FLOOR: return floor(u);
    case SC_FN_COUNT: break;
  }
  return NAN;
}

/* phi'(u) and phi''(u) of the inverse trigonometric and hyperbolic functions; y = phi(u). */
static void inverse_derivs(int fn, double u, double *d1, double *d2) {
  double s;
  switch ((sc_fn)fn) {
    case SC_FN_ASIN: case SC_FN_ACOS:                 /* +-1/sqrt(1-u^2), +-u/(1-u^2)^1.5 */
      s = 1.0 - u * u;
      *d1 = (fn == SC_FN_ASIN ? 1.0 : -1.0) / sqrt(s), *d2 = u * *d1 / s;
      return;
    case SC_FN_ATAN: case SC_FN_ACOT:                 /* +-1/(1+u^2), -+2u/(1+u^2)^2 */
      s = 1.0 + u * u;
      *d1 = (fn == SC_FN_ATAN ? 1.0 : -1.0) / s, *d2 = -2.0 * u * *d1 / s;
      return;
    case SC_FN_ASEC: case SC_FN_ACSC:                 /* +-1/(|u| sqrt(u^2-1)) */
      s = u * u - 1.0;
      *d1 = (fn == SC_FN_ASEC ? 1.0 : -1.0) / (fabs(u) * sqrt(s));
      *d2 = -*d1 * (2.0 * u * u - 1.0) / (u * s);
      return;
    case SC_FN_ASINH:                                 /* 1/sqrt(1+u^2), -u/(1+u^2)^1.5 */
      s = 1.0 + u * u;
      *d1 = 1.0 / sqrt(s), *d2 = -u * *d1 / s;
      return;
    case SC_FN_ACOSH:                                 /* 1/sqrt(u^2-1), -u/(u^2-1)^1.5 */
      s = u * u - 1.0;
      *d1 = 1.0 / sqrt(s), *d2 = -u * *d1 / s;
      return;
    case SC_FN_ATANH: case SC_FN_ACOTH:               /* 1/(1-u^2), 2u/(1-u^2)^2 */
      s = 1.0 - u * u;
      *d1 = 1.0 / s, *d2 = 2.0 * u * *d1 / s;
      return;
    case SC_FN_ASECH:                                 /* -1/(u sqrt(1-u^2)) */
      s = 1.0 - u * u;
      *d1 = -1.0 / (u * sqrt(s)), *d2 = -*d1 * (1.0 - 2.0 * u * u) / (u * s);
      return;
    case SC_FN_ACSCH:                                 /* -1/(|u| sqrt(1+u^2)) */
      s = 1.0 + u * u;
      *d1 = -1.0 / (fabs(u) * sqrt(s)), *d2 = -*d1 * (1.0 + 2.0 * u * u) / (u * s);
      return;
    default: *d1 = *d2 = NAN; return;
  }
}

/* phi'(u) and phi''(u); y = phi(u). */
static void derivs(int fn, double u, double y, double *d1, double *d2) {
  double c;
  switch ((sc_fn)fn) {
    case SC_FN_EXP: *d1 = y, *d2 = y; return;
    case SC_FN_LOG: *d1 = 1.0 / u, *d2 = -*d1 * *d1; return;
    case SC_FN_SQRT: *d1 = 0.5 / y, *d2 = -0.5 * *d1 / u; return;
    case SC_FN_SIN: *d1 = cos(u), *d2 = -y; return;
    case SC_FN_COS: *d1 = -sin(u), *d2 = -y; return;
    case SC_FN_TAN: *d1 = 1.0 + y * y, *d2 = 2.0 * y * *d1; return;
    case SC_FN_COT: *d1 = -(1.0 + y * y), *d2 = -2.0 * y * *d1; return;
    case SC_FN_SEC: c = tan(u), *d1 = y * c, *d2 = y * (c * c + y * y); return;
    case SC_FN_CSC: c = 1.0 / tan(u), *d1 = -y * c, *d2 = y * (c * c + y * y); return;
    case SC_FN_SINH: *d1 = cosh(u), *d2 = y; return;
    case SC_FN_COSH: *d1 = sinh(u), *d2 = y; return;
    case SC_FN_TANH: c = cosh(u), *d1 = 1.0 / (c * c), *d2 = -2.0 * y * *d1; return;
    case SC_FN_COTH: c = sinh(u), *d1 = -1.0 / (c * c), *d2 = -2.0 * y * *d1; return;
    case SC_FN_SECH: c = sinh(u), *d1 = -c * y * y, *d2 = (c * c - 1.0) * y * y * y; return;
    case SC_FN_CSCH: c = 1.0 / tanh(u), *d1 = -y * c, *d2 = y * (c * c + y * y); return;
    case SC_FN_ERF: *d1 = SC_2_SQRTPI * exp(-u * u), *d2 = -2.0 * u * *d1; return;
    case SC_FN_ABS: *d1 = u > 0.0 ? 1.0 : u < 0.0 ? -1.0 : NAN, *d2 = u != 0.0 ? 0.0 : NAN; return;
    case SC_FN_STEP: case SC_FN_DELTA: *d1 = *d2 = u != 0.0 ? 0.0 : NAN; return;
    case SC_FN_SIGN: case SC_FN_FLOOR: *d1 = *d2 = 0.0; return;   /* piecewise constant */
    default: inverse_derivs(fn, u, d1, d2); return;
  }
}

void sc_fn_jet(int fn, const sc_jet *a, sc_jet *r) {
  double u = a->c[0], a1 = a->c[1], a2 = a->c[2], y = sc_fn_value(fn, u), d1, d2;
  if (a1 == 0.0 && a2 == 0.0) {
    r->c[0] = y, r->c[1] = 0.0, r->c[2] = 0.0;
    return;
  }
  if (u == 0.0 && (fn == SC_FN_ABS || fn == SC_FN_STEP)) {   /* the side being entered */
    double side = a1 != 0.0 ? a1 : a2;
    d1 = fn == SC_FN_STEP ? 0.0 : side > 0 ? 1.0 : -1.0, d2 = 0.0;
  } else if ((fn == SC_FN_SIGN && u == 0.0) || (fn == SC_FN_FLOOR && y == u)) {
    double side = a1 != 0.0 ? a1 : a2;   /* at the jump: the value of the side being entered */
    y = fn == SC_FN_SIGN ? (side > 0 ? 1.0 : -1.0) : side > 0 ? y : y - 1.0;
    d1 = d2 = 0.0;
  } else {
    derivs(fn, u, y, &d1, &d2);
  }
  r->c[0] = y;
  r->c[1] = d1 * a1;
  r->c[2] = d1 * a2 + 0.5 * d2 * a1 * a1;
}
