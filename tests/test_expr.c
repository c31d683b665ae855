/* test_expr: the scene expression evaluator (lib/scene/expr.h).
 *
 * Every function of the grammar: value, first and second derivative by jets at several points
 * against closed forms written independently here (other formulas, in long double), within a
 * few ulps of their magnitude; composite expressions and every power rule (t^2 at t < 0, t^t,
 * 2^3^t right-associative) against hand-derived closed forms; the value path and the jet path
 * agree bit for bit; jets of variables (partial derivatives, derivatives along a motion); the
 * symbol table (dotted names, slots, did-you-mean); the kinks of abs, step and delta;
 * explanations of values that are not finite; numbers under a locale with a decimal comma (when
 * one is installed). Errors, nesting, threads and allocations: test_expr_robust.c. */
#define _GNU_SOURCE
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "appell/appell.h"
#include "check.h"
#include "scene/expr_int.h"
#include "scene/scene_int.h"

#define EPS DBL_EPSILON
#define PI_L 3.141592653589793238462643383279502884L

/* |x - ref| <= n ulps of scale (scale >= |ref|: the magnitude the rounding errors follow). */
#define CHECK_ULPS(x, ref, scale, n) AP_CHECK_NEAR((x), (double)(ref), (n) * EPS * (double)(scale))

static sc_prog *compile(const char *text, const sc_symtab *sym) {
  sc_prog *p = NULL;
  sc_prog_err err;
  int rc = sc_prog_compile(text, sym, &p, &err);
  if (rc != AP_OK) fprintf(stderr, "compile '%s': %s\n", text, err.msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return p;
}

/* ---- every function against closed forms --------------------------------------------------- */

typedef struct ref3 {
  long double f, d1, d2;
} ref3;

static ref3 ref_fn(int fn, long double u) {
  long double s = sinl(u), c = cosl(u), sh = sinhl(u), ch = coshl(u), w;
  switch ((sc_fn)fn) {
    case SC_FN_EXP: return (ref3){expl(u), expl(u), expl(u)};
    case SC_FN_LOG: return (ref3){logl(u), 1 / u, -1 / (u * u)};
    case SC_FN_SQRT: return (ref3){sqrtl(u), 0.5L / sqrtl(u), -0.25L / (u * sqrtl(u))};
    case SC_FN_SIN: return (ref3){s, c, -s};
    case SC_FN_COS: return (ref3){c, -s, -c};
    case SC_FN_TAN: return (ref3){s / c, 1 / (c * c), 2 * s / (c * c * c)};
    case SC_FN_COT: return (ref3){c / s, -1 / (s * s), 2 * c / (s * s * s)};
    case SC_FN_SEC: return (ref3){1 / c, s / (c * c), (1 + s * s) / (c * c * c)};
    case SC_FN_CSC: return (ref3){1 / s, -c / (s * s), (1 + c * c) / (s * s * s)};
    case SC_FN_ASIN: w = 1 - u * u; return (ref3){asinl(u), 1 / sqrtl(w), u / (w * sqrtl(w))};
    case SC_FN_ACOS: w = 1 - u * u; return (ref3){acosl(u), -1 / sqrtl(w), -u / (w * sqrtl(w))};
    case SC_FN_ATAN: w = 1 + u * u; return (ref3){atanl(u), 1 / w, -2 * u / (w * w)};
    case SC_FN_ACOT: w = 1 + u * u; return (ref3){atanl(1 / u), -1 / w, 2 * u / (w * w)};
    case SC_FN_ASEC: case SC_FN_ACSC: {
      long double sg = fn == SC_FN_ASEC ? 1 : -1;
      w = u * u - 1;
      return (ref3){fn == SC_FN_ASEC ? acosl(1 / u) : asinl(1 / u), sg / (fabsl(u) * sqrtl(w)),
                    -sg * (2 * u * u - 1) / (u * fabsl(u) * w * sqrtl(w))};
    }
    case SC_FN_SINH: return (ref3){sh, ch, sh};
    case SC_FN_COSH: return (ref3){ch, sh, ch};
    case SC_FN_TANH: return (ref3){sh / ch, 1 / (ch * ch), -2 * sh / (ch * ch * ch)};
    case SC_FN_COTH: return (ref3){ch / sh, -1 / (sh * sh), 2 * ch / (sh * sh * sh)};
    case SC_FN_SECH: return (ref3){1 / ch, -sh / (ch * ch), (sh * sh - 1) / (ch * ch * ch)};
    case SC_FN_CSCH: return (ref3){1 / sh, -ch / (sh * sh), (ch * ch + 1) / (sh * sh * sh)};
    case SC_FN_ASINH: w = 1 + u * u; return (ref3){asinhl(u), 1 / sqrtl(w), -u / (w * sqrtl(w))};
    case SC_FN_ACOSH: w = u * u - 1; return (ref3){acoshl(u), 1 / sqrtl(w), -u / (w * sqrtl(w))};
    case SC_FN_ATANH: w = 1 - u * u; return (ref3){atanhl(u), 1 / w, 2 * u / (w * w)};
    case SC_FN_ACOTH: w = 1 - u * u; return (ref3){atanhl(1 / u), 1 / w, 2 * u / (w * w)};
    case SC_FN_ASECH:
      w = 1 - u * u;
      return (ref3){acoshl(1 / u), -1 / (u * sqrtl(w)), (1 - 2 * u * u) / (u * u * w * sqrtl(w))};
    case SC_FN_ACSCH:
      w = 1 + u * u;
      return (ref3){asinhl(1 / u), -1 / (fabsl(u) * sqrtl(w)),
                    (1 + 2 * u * u) / (u * fabsl(u) * w * sqrtl(w))};
    case SC_FN_ERF:
      w = 2 / sqrtl(PI_L) * expl(-u * u);
      return (ref3){erfl(u), w, -2 * u * w};
    case SC_FN_ABS: return (ref3){fabsl(u), u > 0 ? 1 : -1, 0};
    case SC_FN_STEP: return (ref3){u < 0 ? 0 : 1, 0, 0};
    case SC_FN_DELTA: return (ref3){0, 0, 0};
    case SC_FN_SIGN: return (ref3){u > 0 ? 1 : -1, 0, 0};
    case SC_FN_FLOOR: return (ref3){floorl(u), 0, 0};
    case SC_FN_COUNT: break;
  }
  return (ref3){NAN, NAN, NAN};
}

/* Points inside each function's domain, away from its singular points; 0 ends a list. */
static const double *points(int fn) {
  static const double all[] = {-1.7, -0.6, 0.3, 0.8, 2.5, 0}, pos[] = {0.3, 0.8, 2.5, 7.0, 0},
                      unit[] = {-0.6, 0.3, 0.45, 0.8, 0}, big[] = {1.5, 2.5, 7.0, 0},
                      out[] = {-2.5, -1.7, 1.5, 2.5, 7.0, 0}, half[] = {0.3, 0.45, 0.8, 0},
                      trig[] = {-1.2, -0.6, 0.3, 0.8, 2.5, 0};
  switch ((sc_fn)fn) {
    case SC_FN_LOG: case SC_FN_SQRT: return pos;
    case SC_FN_ASIN: case SC_FN_ACOS: case SC_FN_ATANH: return unit;
    case SC_FN_ACOSH: return big;
    case SC_FN_ASEC: case SC_FN_ACSC: case SC_FN_ACOTH: return out;
    case SC_FN_ASECH: return half;
    case SC_FN_TAN: case SC_FN_SEC: return trig;
    default: return all;
  }
}

static void test_functions(void) {
  double worst = 0.0;   /* largest error in ulps of the reference's magnitude */
  for (int fn = 0; fn < SC_FN_COUNT; fn++) {
    char text[32];
    snprintf(text, sizeof text, "%s(t)", sc_fn_names[fn]);
    sc_prog *p = compile(text, NULL);
    if (!p) continue;
    for (const double *u = points(fn); *u != 0.0; u++) {
      ref3 r = ref_fn(fn, *u);
      double f[3], v;
      AP_CHECK_EQ_INT(sc_prog_time(p, *u, f), 0);
      AP_CHECK_EQ_INT(sc_prog_value(p, *u, NULL, &v), 0);
      AP_CHECK(memcmp(&v, &f[0], sizeof v) == 0);   /* value path == jet path, bit for bit */
      long double want[3] = {r.f, r.d1, r.d2};
      for (int k = 0; k < 3; k++) {   /* ulps of the coefficient, or of the one before it
                                         where it nearly vanishes (sech'' crosses 0 at 0.88) */
        long double scale = fmaxl(fabsl(want[k]), k ? 0.25L * fabsl(want[k - 1]) : 0);
        if (scale == 0) scale = 1e-300L;
        CHECK_ULPS(f[k], want[k], scale, 8);
        double ulps = (double)(fabsl((long double)f[k] - want[k]) / (EPS * scale));
        if (ulps > worst) worst = ulps;
      }
    }
    sc_prog_free(p);
  }
  printf("functions: largest error %.2f ulps of the magnitude (allowed 8)\n", worst);
}

/* ---- composite expressions and the power rules ---------------------------------------------- */

typedef struct composite {
  const char *text;
  double t;
} composite;

/* Closed forms (f, f', f'') of the composites below. */
static ref3 ref_composite(int i, long double t) {
  long double g = expl(-t / 4), ph = 3 * t + PI_L / 3, w = 1 + t * t, l2 = logl(2.0L);
  long double l3 = logl(3.0L), a = powl(3, t), tt = powl(t, t), lt = logl(t) + 1;
  switch (i) {
    case 0: return (ref3){2 * sinl(3 * t) + t * t, 6 * cosl(3 * t) + 2 * t, -18 * sinl(3 * t) + 2};
    case 1:
      return (ref3){0.2L * g * cosl(ph), 0.2L * g * (-cosl(ph) / 4 - 3 * sinl(ph)),
                    0.2L * g * ((1.0L / 16 - 9) * cosl(ph) + 1.5L * sinl(ph))};
    case 2: return (ref3){t * t * t, 3 * t * t, 6 * t};
    case 3: return (ref3){t * t, 2 * t, 2};
    case 4: return (ref3){1 / t, -1 / (t * t), 2 / (t * t * t)};
    case 5: return (ref3){sqrtl(t), 0.5L / sqrtl(t), -0.25L / (t * sqrtl(t))};
    case 6: return (ref3){powl(2, t), l2 * powl(2, t), l2 * l2 * powl(2, t)};
    case 7: return (ref3){tt, tt * lt, tt * (lt * lt + 1 / t)};
    case 8:
      return (ref3){cbrtl(w), 2 * t / 3 / cbrtl(w * w),
                    2.0L / 3 / cbrtl(w * w) - 8 * t * t / 9 / (w * cbrtl(w * w))};
    case 9: return (ref3){1 / w, -2 * t / (w * w), (6 * t * t - 2) / (w * w * w)};
    case 10: return (ref3){logl(coshl(t)), tanhl(t), 1 / (coshl(t) * coshl(t))};
    case 11: {
      long double f = powl(2, a);
      return (ref3){f, f * l2 * a * l3, f * l2 * a * l3 * l3 * (l2 * a + 1)};
    }
    case 12: return (ref3){-t * t, -2 * t, -2};
    case 13: return (ref3){1 + 3 / (t - 2), -3 / ((t - 2) * (t - 2)), 6 / powl(t - 2, 3)};
    case 14: return (ref3){3 - t + 3 / t + t / 4, -1 - 3 / (t * t) + 0.25L, 6 / (t * t * t)};
    case 15: return (ref3){powl(5, t) + t - 3, logl(5.0L) * powl(5, t) + 1,
                           logl(5.0L) * logl(5.0L) * powl(5, t)};
    case 16: return (ref3){powl(t, 1.5L), 1.5L * sqrtl(t), 0.75L / sqrtl(t)};
  }
  return (ref3){NAN, NAN, NAN};
}

static const composite composites[] = {
    {"2*sin(3*t) + t^2", 0.7}, {"0.2*exp(-t/4)*cos(3*t + pi/3)", 1.9}, {"t^3", -1.3},
    {"t^2", -1.3}, {"t^-1", -1.3}, {"t^0.5", 1.3}, {"2^t", -0.4}, {"t^t", 1.3},
    {"(1 + t^2)^(1/3)", -0.8}, {"1/(1 + t^2)", 0.6}, {"log(cosh(t))", -0.9}, {"2^3^t", 0.7},
    {"-t^2", 3.0}, {"(t+1)/(t-2)", 0.5}, {"3 - t + 3/t + t/4", 1.7}, {"5^t + t - 3", 0.4},
    {"t^1.5", 2.2}};

static void test_composites(void) {
  for (int i = 0; i < (int)(sizeof composites / sizeof composites[0]); i++) {
    sc_prog *p = compile(composites[i].text, NULL);
    if (!p) continue;
    double f[3], t = composites[i].t;
    AP_CHECK_EQ_INT(sc_prog_time(p, t, f), 0);
    ref3 r = ref_composite(i, t);
    long double scale = fabsl(r.f) + fabsl(r.d1) + fabsl(r.d2);
    CHECK_ULPS(f[0], r.f, scale, 16);
    CHECK_ULPS(f[1], r.d1, scale, 16);
    CHECK_ULPS(f[2], r.d2, scale, 16);
    sc_prog_free(p);
  }
  /* Folding and fusing: 2*pi*t is t MULK(2 pi); -2^2 is -(2^2); ^ is right-associative. */
  sc_prog *p = compile("2*pi*t", NULL);
  if (p) AP_CHECK_EQ_INT(p->nins, 2);
  sc_prog_free(p);
  static const struct { const char *text; double value; } values[] = {
      {"-2^2", -4}, {"2^3^2", 512}, {"2^-1", 0.5}, {"2*-3", -6}, {"--2", 2}, {".5 + 5.", 5.5},
      {"1e-3*1E+3", 1}, {"(((1)))", 1}, {"\t2 *\t3 ", 6}, {"90*deg", 1.5707963267948966},
      {"e", 2.718281828459045}, {"atan(1/0)", 1.5707963267948966}, {"8/2/2", 2},
      {"8-2-2", 4}};
  for (size_t i = 0; i < sizeof values / sizeof values[0]; i++) {
    double x = NAN;
    sc_symtab constant = {0, NULL, NULL, NULL, NULL, NULL};
    p = compile(values[i].text, &constant);
    AP_CHECK(p && sc_prog_constant(p, &x));
    AP_CHECK_NEAR(x, values[i].value, 4 * EPS * fabs(values[i].value));
    sc_prog_free(p);
  }
}

/* Numbers read the same whatever the locale's decimal point (a program may set LC_NUMERIC). */
static void test_locale(void) {
  static const char *const locales[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", NULL};
  const char *set = NULL;
  for (int i = 0; locales[i] && !set; i++) set = setlocale(LC_NUMERIC, locales[i]);
  if (!set) return (void)printf("no locale with a decimal comma installed: locale not tested\n");
  double x = 0.0;
  sc_prog *p = compile("2.5 + .25", NULL);
  AP_CHECK(p && sc_prog_constant(p, &x) && x == 2.75);
  sc_prog_free(p);
  setlocale(LC_NUMERIC, "C");
}

/* ---- variables: the symbol table and jets of x ---------------------------------------------- */

static void test_variables(void) {
  static const char *const names[] = {"wl.angle", "wl.rate", "chassis.heading", NULL};
  static const int slots[] = {3, 5, 0};
  sc_symtab sym = {1, names, slots, NULL, NULL, NULL};
  sc_prog *p = compile("wl.rate*t + sin(wl.angle) - chassis.heading^2 + 0*wl.rate", &sym);
  if (!p) return;
  AP_CHECK_EQ_INT(sc_prog_uses_t(p), 1);
  AP_CHECK_EQ_INT(sc_prog_nvars(p), 3);
  AP_CHECK_EQ_INT(sc_prog_nx(p), 6);
  const int *v = sc_prog_vars(p);
  AP_CHECK(v[0] == 0 && v[1] == 3 && v[2] == 5);
  double t = 0.4, a = 0.9, r = -1.3, h = 0.35, va = 0.7, vr = 2.1, vh = -0.4, aa = -1.1,
         ar = 0.25, ah = 3.0;
  sc_jet tj = {{t, 0, 0}}, x[6] = {{{h, 0, 0}}, {{0}}, {{0}}, {{a, 0, 0}}, {{0}}, {{r, 0, 0}}}, f;
  double f0 = r * t + sin(a) - h * h, value;
  AP_CHECK_EQ_INT(sc_prog_value(p, t, (double[]){h, 0, 0, a, 0, r}, &value), 0);
  AP_CHECK_NEAR(value, f0, 4 * EPS);
  x[3].c[1] = 1;   /* d/d(wl.angle) */
  AP_CHECK_EQ_INT(sc_prog_jet(p, &tj, x, &f), 0);
  AP_CHECK(memcmp(&f.c[0], &value, sizeof value) == 0);
  AP_CHECK_NEAR(f.c[1], cos(a), 2 * EPS);
  AP_CHECK_NEAR(2 * f.c[2], -sin(a), 2 * EPS);
  x[3].c[1] = 0, x[0].c[1] = 1;   /* d/d(chassis.heading) */
  AP_CHECK_EQ_INT(sc_prog_jet(p, &tj, x, &f), 0);
  AP_CHECK_NEAR(f.c[1], -2 * h, 2 * EPS);
  AP_CHECK_NEAR(2 * f.c[2], -2, 2 * EPS);
  /* Along a motion: x = (x, x', x''/2), t = (t, 1, 0). */
  tj.c[1] = 1;
  x[0] = (sc_jet){{h, vh, ah / 2}}, x[3] = (sc_jet){{a, va, aa / 2}};
  x[5] = (sc_jet){{r, vr, ar / 2}};
  AP_CHECK_EQ_INT(sc_prog_jet(p, &tj, x, &f), 0);
  double d1 = vr * t + r + cos(a) * va - 2 * h * vh;
  double d2 = ar * t + 2 * vr + cos(a) * aa - sin(a) * va * va - 2 * vh * vh - 2 * h * ah;
  AP_CHECK_NEAR(f.c[1], d1, 16 * EPS * 8);
  AP_CHECK_NEAR(2 * f.c[2], d2, 16 * EPS * 16);
  double g[3];
  AP_CHECK_EQ_INT(sc_prog_time(p, t, g), -1);   /* needs the state */
  AP_CHECK(isnan(g[0]));
  sc_prog_free(p);
  /* slots NULL: names[i] is slot i; a table with only constants used folds to a number. */
  static const char *const ab[] = {"a", "b", NULL};
  sc_symtab plain = {0, ab, NULL, NULL, NULL, NULL};
  p = compile("2*b", &plain);
  if (p) AP_CHECK(sc_prog_nvars(p) == 1 && sc_prog_vars(p)[0] == 1 && !sc_prog_uses_t(p));
  sc_prog_free(p);
  p = compile("sqrt(4) + pi", &plain);
  AP_CHECK(p && sc_prog_constant(p, NULL));
  sc_prog_free(p);
  /* A fixed argument at a kink or a singular point has zero derivatives: sqrt(a) at a = 0. */
  p = compile("sqrt(a) + abs(a) + step(a)", &plain);
  sc_jet z[1] = {{{0, 0, 0}}}, one = {{2, 1, 0}};
  if (p) AP_CHECK(sc_prog_jet(p, &one, z, &f) == 0 && f.c[0] == 1 && f.c[1] == 0 && f.c[2] == 0);
  sc_prog_free(p);
}

/* ---- kinks, and explanations of values that are not finite --------------------------------- */

static void test_kinks(void) {
  static const struct { const char *text; double t, f[3]; int rc; } cases[] = {
      /* at a kink, the derivatives of the side the argument enters (expr.h, "Kinks") */
      {"abs(t)", -2, {2, -1, 0}, 0}, {"abs(t)", 0, {0, 1, 0}, 0}, {"abs(-t)", 0, {0, 1, 0}, 0},
      {"abs(-t*t)", 0, {0, 0, 2}, 0}, {"step(t)", -1, {0, 0, 0}, 0},
      {"step(t)", 2, {1, 0, 0}, 0}, {"step(t)", 0, {1, 0, 0}, 0}, {"delta(t)", 1, {0, 0, 0}, 0},
      {"delta(t)", 0, {INFINITY, NAN, NAN}, -1}, {"abs(t - 0.5)", 0.5, {0, 1, 0}, 0}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    sc_prog *p = compile(cases[i].text, NULL);
    double f[3];
    if (!p) continue;
    AP_CHECK_EQ_INT(sc_prog_time(p, cases[i].t, f), cases[i].rc);
    for (int k = 0; k < 3; k++)
      AP_CHECK(isnan(cases[i].f[k]) ? isnan(f[k]) : f[k] == cases[i].f[k]);
    sc_prog_free(p);
  }
  double v;
  sc_prog *p = compile("step(t)", NULL);
  if (p) {   /* values only: step(0) = 1 is finite; NaN stays NaN */
    AP_CHECK(sc_prog_value(p, 0.0, NULL, &v) == 0 && v == 1.0);
    AP_CHECK(sc_prog_value(p, NAN, NULL, &v) == -1 && isnan(v));
  }
  sc_prog_free(p);
}

/* The functions of two and three arguments against closed forms (long double), their kinks
 * (the side being entered), their event arguments, folding and the argument counts. */
static void test_fn2(void) {
  static const struct { const char *text; double t; long double f[3]; } cases[] = {
      {"atan2(t, 2)", 0.7, {0, 0, 0}}, {"atan2(sin(t), cos(t))", 2.5, {2.5L, 1, 0}},
      {"atan2(sin(t), cos(t))", -0.3, {-0.3L, 1, 0}}, {"hypot(3*t, 4*t)", -0.4, {2, -5, 0}},
      {"hypot(t, 1)", 0.6, {0, 0, 0}}, {"min(t, 1)", 0.5, {0.5L, 1, 0}},
      {"max(t*t, 1)", 2, {4, 4, 2}}, {"clamp(t*t, -1, 2)", 1.5, {2, 0, 0}},
      {"clamp(-t*t, -1, 2)", 0.5, {-0.25L, -1, -2}},
      /* at the kinks: the side being entered */
      {"max(0, t - 1)", 1, {0, 1, 0}}, {"min(t, 2 - t)", 1, {1, -1, 0}},
      {"clamp(t, 0, 1)", 1, {1, 0, 0}}, {"clamp(t, 0, 1)", 0, {0, 1, 0}},
      {"sign(t)", 0, {1, 0, 0}}, {"sign(-t)", 0, {-1, 0, 0}}, {"floor(-t)", 0, {-1, 0, 0}},
      {"floor(t)", 2, {2, 0, 0}}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    long double t = cases[i].t, w[3] = {cases[i].f[0], cases[i].f[1], cases[i].f[2]};
    if (i == 0) w[0] = atanl(t / 2), w[1] = 2 / (4 + t * t), w[2] = -4 * t / ((4 + t * t) * (4 + t * t));
    if (i == 4) w[0] = sqrtl(1 + t * t), w[1] = t / w[0], w[2] = 1 / (w[0] * w[0] * w[0]);
    sc_prog *p = compile(cases[i].text, NULL);
    double f[3];
    if (!p) continue;
    AP_CHECK_EQ_INT(sc_prog_time(p, cases[i].t, f), 0);
    for (int k = 0; k < 3; k++) CHECK_ULPS(f[k], w[k], fmaxl(fabsl(w[k]), 1), 4);
    sc_prog_free(p);
  }
  /* the kinks' event arguments: b - a for min and max, the argument of sign, sin(pi u) of floor */
  sc_prog *p = compile("clamp(t, 0, 1) + sign(t - 3) + floor(2*t)", NULL);
  double args[4] = {0, 0, 0, 0}, v = 0;
  AP_CHECK(p && sc_prog_nkinks(p) == 4 && sc_prog_kinks(p, 0.25, NULL, args) == 4);
  AP_CHECK(args[0] == 0.25 && args[1] == 0.25 - 1 && args[2] == 0.25 - 3);
  AP_CHECK_NEAR(args[3], 1.0, 1e-16);   /* sin(pi * 0.5) */
  AP_CHECK(p && sc_prog_value(p, 0.25, NULL, &v) == 0 && v == 0.25 - 1 + 0);
  sc_prog_free(p);
  /* constant arguments fold; a value at a jump on the value path */
  double k = 0;
  p = compile("clamp(5, 0, 1) + max(1, 2) + atan2(0, -1)", NULL);
  AP_CHECK(p && sc_prog_constant(p, &k) && k == 3 + atan2(0.0, -1.0));
  sc_prog_free(p);
  p = compile("sign(t) + floor(t)", NULL);
  AP_CHECK(p && sc_prog_value(p, 0.0, NULL, &v) == 0 && v == 0.0);
  sc_prog_free(p);
}

static void test_explain(void) {
  static const struct { const char *text; double t; int col; const char *why; } cases[] = {
      {"log(t-1)", 0, 1, "log(-1) = nan (column 1 of the expression)"},
      {"2 + 1/t", 0, 6, "1 / 0 = inf (column 6"},
      {"sqrt(t)", 0, 1, "sqrt(0) has no finite first derivative"},
      {"3*abs(t) + sqrt(t)", 0, 12, "sqrt(0) has no finite first derivative"},
      {"delta(t)", 0, 1, "delta(0) = inf"},
      {"exp(t)", 1000, 1, "exp(1000) = inf"},
      {"t^0.5", 0, 2, "0 ^ 0.5 has no finite first derivative"}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    sc_prog *p = compile(cases[i].text, NULL);
    if (!p) continue;
    sc_jet t = {{cases[i].t, 1, 0}};
    char why[200];
    AP_CHECK_EQ_INT(sc_prog_explain(p, &t, NULL, 2, why, sizeof why), cases[i].col);
    if (!strstr(why, cases[i].why)) fprintf(stderr, "  '%s': got '%s'\n", cases[i].text, why);
    AP_CHECK(strstr(why, cases[i].why) != NULL);
    sc_prog_free(p);
  }
  /* The scene layer puts it at the node: FILE:LINE:COLUMN: key.path. */
  sc_ctx c = {"scene.yaml", "", AP_OK};
  sc_node at = {.kind = SC_SCALAR, .text = "0.5*log(t - 1)", .line = 7, .col = 20,
                .path = "joints.arm.drive.angle"};
  sc_expr e;
  AP_CHECK_EQ_INT(sc_expr_compile(&c, &at, at.text, 1, &e), AP_OK);
  AP_CHECK_EQ_INT(sc_expr_check(&c, &e, 2.0), AP_OK);
  AP_CHECK_EQ_INT(sc_expr_check(&c, &e, 0.0), AP_ERR_ARG);
  AP_CHECK(strcmp(c.msg, "scene.yaml:7:20: joints.arm.drive.angle: '0.5*log(t - 1)' is not "
                         "finite at t = 0: log(-1) = nan (column 5 of the expression)") == 0);
  sc_expr_free(&e);
}

int main(void) {
  test_functions();
  test_composites();
  test_locale();
  test_variables();
  test_kinks();
  test_fn2();
  test_explain();
  return ap_check_finish("test_expr");
}
