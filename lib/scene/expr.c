/* Scene expressions: constants and functions of time, with their first and second time
 * derivatives, on libmatheval (Debian libmatheval-dev; docs/scenes.md "Expressions").
 *
 * An sc_expr holds either a constant `value` or three evaluators f, f', f'' built once by
 * symbolic differentiation, so drivers, Omega(t) and applied forces get exact derivatives.
 * Names allowed: t (time, where a function of time is allowed) and deg = pi/180; libmatheval
 * adds pi, e and the usual functions. Invariant: an sc_expr that compiled evaluates without
 * further checks; non-finite values are reported by sc_expr_eval's return code. libmatheval
 * stores variable values inside its trees, so one scene must not be evaluated from two
 * threads at once. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <matheval.h>

#include "scene/scene_int.h"

#define SC_EXPR_MAX 1000
#define SC_DEG (3.14159265358979323846 / 180.0)

static double eval_at(void *f, double t) {
  char *names[] = {"t", "deg"};
  double vals[] = {t, SC_DEG};
  return evaluator_evaluate(f, 2, names, vals);
}

void sc_expr_free(sc_expr *e) {
  for (int i = 0; i < 3; i++)
    if (e->f[i]) evaluator_destroy(e->f[i]);
  free(e->text);
  memset(e, 0, sizeof *e);
}

/* Every variable of f must be t (when allowed) or deg. */
static int check_names(sc_ctx *c, const sc_node *at, void *f, int allow_t, int *uses_t) {
  char **names = NULL;
  int count = 0;
  evaluator_get_variables(f, &names, &count);
  *uses_t = 0;
  for (int i = 0; i < count; i++) {
    if (strcmp(names[i], "t") == 0 && allow_t) *uses_t = 1;
    else if (strcmp(names[i], "deg") != 0)
      return sc_err(c, at, "unknown name '%s' in expression '%s' (allowed: %snumbers, pi, e, "
                    "deg, and functions such as sin, cos, exp, sqrt)", names[i], at->text,
                    allow_t ? "t, " : "");
  }
  return AP_OK;
}

/* Position of a '.' that starts no number (libmatheval would echo it), or -1. */
static long stray_dot(const char *s) {
  size_t i = 0;
  while (s[i]) {
    if (isalpha((unsigned char)s[i]) || s[i] == '_') {
      while (isalnum((unsigned char)s[i]) || s[i] == '_') i++;
    } else if (isdigit((unsigned char)s[i]) || (s[i] == '.' && isdigit((unsigned char)s[i + 1]))) {
      while (isdigit((unsigned char)s[i])) i++;
      if (s[i] == '.') i++;
      while (isdigit((unsigned char)s[i])) i++;
    } else if (s[i] == '.') {
      return (long)i;
    } else {
      i++;
    }
  }
  return -1;
}

/* ---- a grammar check before libmatheval sees the text ----------------------------------
 * libmatheval 1.1.11 leaks its partial tree on a syntax error and echoes stray characters,
 * so the text is checked first with the same grammar:
 *   sum := product {(+|-) product};  product := unary {(*|/) unary};
 *   unary := - unary | primary [^ unary];  primary := number | name | function ( sum ) | ( sum )
 */
typedef struct sc_lex {
  const char *s;
  size_t i;
  int depth;
  const char *err;        /* what was expected, or NULL */
  size_t at;
} sc_lex;

static const char *const functions[] = {
    "exp", "log", "sqrt", "sin", "cos", "tan", "cot", "sec", "csc", "asin", "acos", "atan",
    "acot", "asec", "acsc", "sinh", "cosh", "tanh", "coth", "sech", "csch", "asinh", "acosh",
    "atanh", "acoth", "asech", "acsch", "abs", "step", "delta", "nandelta", "erf", NULL};

static void skip_space(sc_lex *x) {
  while (x->s[x->i] == ' ' || x->s[x->i] == '\t') x->i++;
}

static int fail(sc_lex *x, const char *what) {
  if (!x->err) x->err = what, x->at = x->i;
  return -1;
}

static int accept(sc_lex *x, char ch) {
  skip_space(x);
  if (x->s[x->i] != ch) return 0;
  x->i++;
  return 1;
}

static int sum(sc_lex *x);

static int name_or_call(sc_lex *x) {
  size_t start = x->i;
  while (isalnum((unsigned char)x->s[x->i]) || x->s[x->i] == '_') x->i++;
  int fn = 0;
  for (int k = 0; functions[k] && !fn; k++)
    fn = strlen(functions[k]) == x->i - start && !strncmp(functions[k], x->s + start, x->i - start);
  if (!accept(x, '(')) return fn ? fail(x, "'(' after the function name") : 0;
  if (!fn) return x->i--, fail(x, "an operator (only functions take arguments)");
  if (sum(x) != 0) return -1;
  return accept(x, ')') ? 0 : fail(x, "')'");
}

static int primary(sc_lex *x) {
  skip_space(x);
  char ch = x->s[x->i];
  if (isdigit((unsigned char)ch) || ch == '.') {
    while (isdigit((unsigned char)x->s[x->i])) x->i++;
    if (x->s[x->i] == '.') x->i++;
    while (isdigit((unsigned char)x->s[x->i])) x->i++;
    const char *p = x->s + x->i;   /* an exponent: p[1] exists only when p[0] is not NUL */
    if (p[0] == 'e' || p[0] == 'E') {
      int sign = p[1] == '+' || p[1] == '-';
      if (isdigit((unsigned char)p[1 + sign]))
        for (x->i += 1 + sign; isdigit((unsigned char)x->s[x->i]);) x->i++;
    }
    return 0;
  }
  if (isalpha((unsigned char)ch) || ch == '_') return name_or_call(x);
  if (!accept(x, '(')) return fail(x, "a number, a name or '('");
  if (sum(x) != 0) return -1;
  return accept(x, ')') ? 0 : fail(x, "')'");
}

static int unary(sc_lex *x) {
  if (++x->depth > 100) return fail(x, "less nesting");
  int rc = accept(x, '-') ? unary(x) : primary(x);
  if (rc == 0 && accept(x, '^')) rc = unary(x);
  x->depth--;
  return rc;
}

static int sum(sc_lex *x) {
  for (int terms = 0;; terms++) {
    if (terms && !accept(x, '+') && !accept(x, '-')) return 0;
    for (int factors = 0;; factors++) {
      if (factors && !accept(x, '*') && !accept(x, '/')) break;
      if (unary(x) != 0) return -1;
    }
  }
}

/* 0 when text has the grammar above; else -1 with *what and the column in *col. */
static int check_grammar(const char *text, const char **what, size_t *col) {
  sc_lex x = {text, 0, 0, NULL, 0};
  int rc = sum(&x);
  skip_space(&x);
  if (rc == 0 && text[x.i]) rc = fail(&x, "an operator");
  *what = x.err, *col = x.at + 1;
  return rc;
}

/* Text that libmatheval may safely see: known characters, no stray '.', the grammar. */
static int check_text(sc_ctx *c, const sc_node *at, const char *text, int allow_t) {
  size_t len = strlen(text);
  if (len == 0 || len > SC_EXPR_MAX)
    return sc_err(c, at, "expected a number%s, got %s", allow_t ? " or an expression of t" : "",
                  len ? "an expression longer than 1000 characters" : "an empty value");
  /* libmatheval's scanner skips unknown characters and echoes them to stdout: refuse them. */
  size_t bad = strspn(text, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_"
                            ".+-*/^() \t");
  if (bad < len) {
    unsigned char ch = (unsigned char)text[bad];
    if (ch >= 0x20 && ch < 0x7f)
      return sc_err(c, at, "unexpected character '%c' in expression '%s'", ch, text);
    return sc_err(c, at, "unexpected byte 0x%02x in expression (column %zu of the value)", ch,
                  bad + 1);
  }
  if (stray_dot(text) >= 0)
    return sc_err(c, at, "unexpected '.' in expression '%s' (column %ld of the value)", text,
                  stray_dot(text) + 1);
  const char *what = NULL;
  size_t col = 0;
  if (check_grammar(text, &what, &col) != 0)
    return sc_err(c, at, "cannot parse '%s' as a number or an expression%s: expected %s at "
                  "column %zu", text, allow_t ? " of t" : "", what, col);
  return AP_OK;
}

int sc_expr_compile(sc_ctx *c, const sc_node *at, const char *text, int allow_t, sc_expr *e) {
  memset(e, 0, sizeof *e);
  if (check_text(c, at, text, allow_t) != AP_OK) return AP_ERR_ARG;
  size_t len = strlen(text);
  e->text = malloc(len + 1);
  char *copy = malloc(len + 1);   /* evaluator_create takes a non-const string */
  if (e->text) memcpy(e->text, text, len + 1);
  if (copy) memcpy(copy, text, len + 1);
  e->f[0] = copy && e->text ? evaluator_create(copy) : NULL;
  free(copy);
  if (!e->f[0]) {
    sc_expr_free(e);
    return sc_err(c, at, "cannot parse '%s' as a number or an expression%s", text,
                  allow_t ? " of t" : "");
  }
  int uses_t = 0;
  if (check_names(c, at, e->f[0], allow_t, &uses_t) != AP_OK) return sc_expr_free(e), AP_ERR_ARG;
  if (!uses_t) {
    e->value = eval_at(e->f[0], 0.0);
    if (isfinite(e->value)) return AP_OK;
    sc_expr_free(e);
    return sc_err(c, at, "'%s' is not a finite number", text);
  }
  e->timed = 1;
  e->f[1] = evaluator_derivative(e->f[0], "t");
  e->f[2] = e->f[1] ? evaluator_derivative(e->f[1], "t") : NULL;
  if (!e->f[2]) return sc_expr_free(e), sc_err(c, at, "cannot differentiate '%s'", text);
  return AP_OK;
}

int sc_expr_read(sc_ctx *c, const sc_node *n, sc_expr *e) {
  memset(e, 0, sizeof *e);
  if (sc_expect(c, n, SC_SCALAR) != AP_OK) return AP_ERR_ARG;
  char *end = NULL;
  double x = strtod(n->text, &end);
  if (!n->quoted && end != n->text && *end == '\0' && isfinite(x)) {
    e->value = x;
    return AP_OK;
  }
  return sc_expr_compile(c, n, n->text, 1, e);
}

int sc_expr_eval(const sc_expr *e, double t, double f[3]) {
  if (!e->timed) {
    f[0] = e->value, f[1] = 0.0, f[2] = 0.0;
    return 0;
  }
  for (int i = 0; i < 3; i++) f[i] = eval_at(e->f[i], t);
  return isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]) ? 0 : -1;
}

int sc_expr_time_fn(double t, double f[3], void *user) {
  return sc_expr_eval((const sc_expr *)user, t, f);
}
