/* Scene expressions: text -> an immutable program (expr.h), in one pass.
 *
 * Grammar (docs/scenes.md "Expressions"), recursive descent:
 *   sum     := product {(+|-) product}
 *   product := unary {(*|/) unary}
 *   unary   := - unary | primary [^ unary]          (so ^ is right-associative, -2^2 = -4)
 *   primary := number | name | function ( sum {, sum} ) | ( sum )
 * A function takes one argument, except atan2, min, max, hypot (two) and clamp (three:
 * clamp(x, lo, hi) is emitted as min(max(x, lo), hi)).
 * Numbers are digits [. digits] or . digits, with an optional exponent e[+-]digits; names are
 * dot-separated parts of letters, digits and '_' (expr.h, sc_symtab). Nesting deeper than 100
 * levels of unary is refused, which also bounds the evaluation stack.
 *
 * Code: postfix instructions (expr_int.h) into a scratch buffer, with peepholes as each
 * operation is emitted. Every operand's code starts at a known index, and an operand is a
 * constant exactly when its code is one SC_OP_K, so: two constant operands fold into one
 * (computed by sc_op_value, the evaluator's own code), and one constant operand fuses into the
 * operation (t*2 -> t MULK 2; a - k becomes a ADDK (-k), exact). Non-finite intermediate
 * constants are kept (atan(1/0) = pi/2 is a fine constant); a program that folds to a single
 * constant must be finite. Finally the constants used are copied into the program's pool, the
 * slots used are sorted, and the stack depth is computed: one allocation for the program,
 * one for the scratch, each failure AP_ERR_NOMEM. Messages give the 1-based column of the
 * value where the problem was found. */
#include <ctype.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "scene/expr_int.h"
#include "scene/scene_int.h"

#define SC_MAX_NEST 100
#define SC_DEG (3.14159265358979323846 / 180.0)

typedef struct parser {
  const char *s;
  size_t i, len;
  int depth;
  const sc_symtab *sym;
  sc_ins *code;           /* scratch: instructions (cap entries) */
  double *k;              /* scratch: constants (cap entries) */
  int *slots;             /* scratch: slots used, with repeats (cap entries) */
  int n, nk, nslots, cap, uses_t;
  sc_prog_err *err;       /* the first error that stops the parse */
  sc_prog_err late;       /* the first unresolved name (reported when the parse succeeds) */
  char shown[96];         /* the text as messages quote it (long texts shortened) */
} parser;

/* ---- messages ---------------------------------------------------------------------------- */

static int vset(sc_prog_err *e, int status, size_t at, const char *fmt, va_list ap)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 0)))
#endif
    ;
static int vset(sc_prog_err *e, int status, size_t at, const char *fmt, va_list ap) {
  if (e->status != AP_OK) return -1;
  vsnprintf(e->msg, sizeof e->msg, fmt, ap);
  e->status = status;
  e->col = (int)at + 1;
  return -1;
}

/* An error that stops the parse (the first wins). */
static int set_err(parser *p, int status, size_t at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static int set_err(parser *p, int status, size_t at, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vset(p->err, status, at, fmt, ap);
  va_end(ap);
  return -1;
}

/* A name that cannot be resolved: reported only when the whole text parses (as a grammar
 * check before the names did), so parsing goes on with the constant 0 in its place. */
static int name_err(parser *p, size_t at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int emit_k(parser *p, double x, size_t col);
static int name_err(parser *p, size_t at, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vset(&p->late, AP_ERR_ARG, at, fmt, ap);
  va_end(ap);
  return emit_k(p, 0.0, at);
}

/* "a number", "a number or an expression of t", ... */
static const char *expected_kind(const sc_symtab *sym) {
  int vars = sym->names && sym->names[0];
  if (vars) return "a number or an expression";
  return sym->allow_t ? "a number or an expression of t" : "a number";
}

/* The grammar expected `what` at the current position; a '.' there is a stray dot. */
static int expected(parser *p, const char *what) {
  if (p->s[p->i] == '.')
    return set_err(p, AP_ERR_ARG, p->i, "unexpected '.' in expression '%s' (column %zu of the "
                   "value)", p->shown, p->i + 1);
  return set_err(p, AP_ERR_ARG, p->i, "cannot parse '%s' as %s: expected %s at column %zu",
                 p->shown, expected_kind(p->sym), what, p->i + 1);
}

/* Every byte must belong to the grammar's alphabet. */
static int check_bytes(parser *p) {
  size_t bad = strspn(p->s, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_"
                            ".+-*/^(), \t");
  if (bad == p->len) return 0;
  unsigned char ch = (unsigned char)p->s[bad];
  if (ch >= 0x20 && ch < 0x7f)
    return set_err(p, AP_ERR_ARG, bad, "unexpected character '%c' in expression '%s' (column "
                   "%zu of the value)", ch, p->shown, bad + 1);
  return set_err(p, AP_ERR_ARG, bad, "unexpected byte 0x%02x in expression (column %zu of the "
                 "value)", ch, bad + 1);
}

/* ---- emitting ---------------------------------------------------------------------------- */

static int emit(parser *p, int op, int fn, size_t col, int arg) {
  if (p->n >= p->cap) return set_err(p, AP_ERR_ARG, col, "expression too long");
  sc_ins *in = &p->code[p->n++];
  in->op = (unsigned char)op, in->fn = (unsigned char)fn, in->col = (unsigned short)col;
  in->arg = arg;
  return 0;
}

static int constant(parser *p, double x) {
  if (p->nk >= p->cap) return -1;
  p->k[p->nk] = x;
  return p->nk++;
}

static int emit_k(parser *p, double x, size_t col) {
  int c = constant(p, x);
  return c < 0 ? set_err(p, AP_ERR_ARG, col, "expression too long") : emit(p, SC_OP_K, 0, col, c);
}

/* Is the code from start to the end one constant? */
static int is_k(const parser *p, int start) {
  return p->n - start == 1 && p->code[start].op == SC_OP_K;
}

/* A one-operand operation on the operand whose code starts at start. */
static int emit_unary(parser *p, int op, int fn, size_t col, int start) {
  sc_ins in = {(unsigned char)op, (unsigned char)fn, (unsigned short)col, 0};
  if (!is_k(p, start)) return emit(p, op, fn, col, 0);
  double x = sc_op_value(&in, p->k, 0.0, p->k[p->code[start].arg]);
  p->n = start;
  return emit_k(p, x, col);
}

/* b OP a with b's code at lstart and a's at rstart (to the end). */
static int emit_binary(parser *p, int op, size_t col, int lstart, int rstart) {
  static const int with_k[] = {[SC_OP_ADD] = SC_OP_ADDK, [SC_OP_SUB] = SC_OP_ADDK,
                               [SC_OP_MUL] = SC_OP_MULK, [SC_OP_DIV] = SC_OP_DIVK,
                               [SC_OP_POW] = SC_OP_POWK};
  static const int k_with[] = {[SC_OP_ADD] = SC_OP_ADDK, [SC_OP_SUB] = SC_OP_RSUBK,
                               [SC_OP_MUL] = SC_OP_MULK, [SC_OP_DIV] = SC_OP_RDIVK,
                               [SC_OP_POW] = SC_OP_RPOWK};
  int lk = rstart - lstart == 1 && p->code[lstart].op == SC_OP_K, rk = is_k(p, rstart);
  if (lk && rk) {
    sc_ins in = {(unsigned char)op, 0, (unsigned short)col, 0};
    double x = sc_op_value(&in, p->k, p->k[p->code[lstart].arg], p->k[p->code[rstart].arg]);
    p->n = lstart;
    return emit_k(p, x, col);
  }
  if (rk) {
    int c = p->code[rstart].arg;
    p->n = rstart;
    if (op == SC_OP_SUB && (c = constant(p, -p->k[c])) < 0)
      return set_err(p, AP_ERR_ARG, col, "expression too long");
    return emit(p, with_k[op], 0, col, c);
  }
  if (lk) {
    int c = p->code[lstart].arg;
    memmove(p->code + lstart, p->code + lstart + 1, sizeof(sc_ins) * (size_t)(p->n - rstart));
    p->n--;
    return emit(p, k_with[op], 0, col, c);
  }
  return emit(p, op, 0, col, 0);
}

/* ---- lexing ------------------------------------------------------------------------------ */

static void skip_space(parser *p) {
  while (p->s[p->i] == ' ' || p->s[p->i] == '\t') p->i++;
}

static int accept(parser *p, char ch) {
  skip_space(p);
  if (p->s[p->i] != ch) return 0;
  p->i++;
  return 1;
}

static int ident_start(char ch) { return isalpha((unsigned char)ch) || ch == '_'; }
static int ident_char(char ch) { return isalnum((unsigned char)ch) || ch == '_'; }

/* A name: dot-separated parts; returns its length. */
static size_t scan_name(const char *s) {
  size_t i = 0;
  for (;;) {
    while (ident_char(s[i])) i++;
    if (s[i] != '.' || !ident_start(s[i + 1])) return i;
    i++;
  }
}

static int number(parser *p) {
  size_t start = p->i;
  const char *s = p->s;
  while (isdigit((unsigned char)s[p->i])) p->i++;
  if (s[p->i] == '.') p->i++;
  while (isdigit((unsigned char)s[p->i])) p->i++;
  if (s[p->i] == 'e' || s[p->i] == 'E') {   /* s[p->i + 1] exists: s[p->i] is not NUL */
    int sign = s[p->i + 1] == '+' || s[p->i + 1] == '-';
    if (isdigit((unsigned char)s[p->i + 1 + sign]))
      for (p->i += 1 + (size_t)sign; isdigit((unsigned char)s[p->i]);) p->i++;
  }
  char buf[SC_EXPR_MAX + 1], *end = NULL, *dot = NULL;
  memcpy(buf, s + start, p->i - start);
  buf[p->i - start] = '\0';
  double x = strtod(buf, &end);
  if (*end && (dot = strchr(buf, '.')) != NULL) {   /* a locale whose decimal point is not '.' */
    *dot = localeconv()->decimal_point[0];
    x = strtod(buf, &end);
    *dot = '.';
  }
  if (*end)
    return set_err(p, AP_ERR_ARG, start, "cannot read the number '%.40s' in expression '%s' "
                   "(column %zu of the value)", buf, p->shown, start + 1);
  if (!isfinite(x))
    return set_err(p, AP_ERR_ARG, start, "number '%.40s' out of range in expression '%s' "
                   "(column %zu of the value)", buf, p->shown, start + 1);
  return emit_k(p, x, start);
}

/* ---- names ------------------------------------------------------------------------------- */

static int find(const char *const *list, const char *s, size_t len) {
  for (int i = 0; list && list[i]; i++)
    if (strlen(list[i]) == len && strncmp(list[i], s, len) == 0) return i;
  return -1;
}

/* The closest allowed name to word (NULL when none is close). */
static const char *closest(const parser *p, const char *word, int call) {
  static const char *const consts[] = {"t", "pi", "e", "deg", NULL};
  const char *best[4] = {NULL, NULL, NULL, NULL};
  if (call) {
    best[0] = sc_suggest(word, sc_fn_names), best[1] = sc_suggest(word, sc_fn2_names);
    if (!best[0]) best[0] = best[1], best[1] = NULL;
    return best[0] ? sc_suggest(word, best) : NULL;
  }
  best[0] = sc_suggest(word, consts + (p->sym->allow_t ? 0 : 1));
  best[1] = p->sym->names ? sc_suggest(word, p->sym->names) : NULL;
  best[2] = p->sym->constants ? sc_suggest(word, p->sym->constants) : NULL;
  if (!best[1]) best[1] = best[2], best[2] = NULL;
  if (!best[0]) best[0] = best[1], best[1] = best[2], best[2] = NULL;
  return best[0] ? sc_suggest(word, best) : NULL;
}

static int unknown_name(parser *p, size_t at, size_t len, int call) {
  char word[SC_EXPR_MAX + 1];
  memcpy(word, p->s + at, len);
  word[len] = '\0';
  const char *near = closest(p, word, call), *what = call ? "function" : "name";
  if (near)
    return name_err(p, at, "unknown %s '%.60s' in expression '%s' (column %zu of the value; "
                    "did you mean '%s'?)", what, word, p->shown, at + 1, near);
  if (call)
    return name_err(p, at, "unknown function '%.60s' in expression '%s' (column %zu of the "
                    "value; the functions are listed in docs/scenes.md)", word, p->shown, at + 1);
  int vars = p->sym->names && p->sym->names[0];
  return name_err(p, at, "unknown name '%.60s' in expression '%s' (column %zu of the value; "
                  "allowed: %snumbers, pi, e, deg, %s%sand functions such as sin, cos, exp, sqrt)",
                  word, p->shown, at + 1, p->sym->allow_t ? "t, " : "",
                  vars ? "the variable names, " : "",
                  p->sym->lookup ? "the parameters, " : "");
}

/* A name that is not a call: t, a constant or a variable. */
static int variable(parser *p, size_t at, size_t len) {
  const char *w = p->s + at;
  if (len == 1 && w[0] == 't') {
    if (!p->sym->allow_t)
      return name_err(p, at, "the time t is not allowed here: '%s' must be a "
                     "constant (column %zu of the value)", p->shown, at + 1);
    p->uses_t = 1;
    return emit(p, SC_OP_T, 0, at, 0);
  }
  static const char *const consts[] = {"pi", "e", "deg", NULL};
  static const double values[] = {3.14159265358979323846, 2.71828182845904523536, SC_DEG};
  int c = find(consts, w, len);
  if (c >= 0) return emit_k(p, values[c], at);
  int v = find(p->sym->names, w, len);
  double named = 0.0;
  int known = v < 0 && p->sym->lookup ? p->sym->lookup(p->sym->user, w, len, &named) : 0;
  if (known < 0) return set_err(p, AP_ERR_ARG, at, "the parameter '%.*s' has no value", (int)len, w);
  if (known > 0) return emit_k(p, named, at);
  if (v < 0 && (find(sc_fn_names, w, len) >= 0 || find(sc_fn2_names, w, len) >= 0))
    return expected(p, "'(' after the function name");
  if (v < 0) return unknown_name(p, at, len, 0);
  int slot = p->sym->slots ? p->sym->slots[v] : v;
  if (slot < 0) return set_err(p, AP_ERR_ARG, at, "negative slot for the name '%.*s'",
                                (int)len, w);
  if (emit(p, SC_OP_X, 0, at, slot) != 0) return -1;
  p->slots[p->nslots++] = slot;
  return 0;
}

static int sum(parser *p);

/* fn2(b, a) with b's code at lstart and a's at rstart: folded when both are constants. */
static int emit_fn2(parser *p, int fn, size_t col, int lstart, int rstart) {
  if (!(rstart - lstart == 1 && p->code[lstart].op == SC_OP_K && is_k(p, rstart)))
    return emit(p, SC_OP_FN2, fn, col, 0);
  double x = sc_fn2_value(fn, p->k[p->code[lstart].arg], p->k[p->code[rstart].arg]);
  p->n = lstart;
  return emit_k(p, x, col);
}

/* The arguments of a call after its '(' (their code starts in start[], at most 3 kept); the
 * count. For clamp, max(x, lo) is emitted as soon as lo is read, so that the code reads
 * x lo MAX hi MIN (start[1] then holds nothing). */
static int arguments(parser *p, int clamp, size_t at, int start[3]) {
  int n = 0;
  do {
    if (n < 3) start[n] = p->n;
    if (sum(p) != 0) return -1;
    if (++n == 2 && clamp && emit_fn2(p, SC_FN2_MAX, at, start[0], start[1]) != 0) return -1;
  } while (accept(p, ','));
  return accept(p, ')') ? n : (expected(p, "')' or ','"), -1);
}

/* A function of two or three arguments (fn indexes sc_fn2_names) with its n arguments. */
static int call2(parser *p, int fn, size_t at, size_t len, int n, const int start[3]) {
  int want = fn == SC_FN2_COUNT ? 3 : 2;
  if (n != want)
    return set_err(p, AP_ERR_ARG, at, "%.*s takes %d arguments, not %d, in expression '%s' "
                   "(column %zu of the value)", (int)len, p->s + at, want, n, p->shown, at + 1);
  if (fn < SC_FN2_COUNT) return emit_fn2(p, fn, at, start[0], start[1]);
  return emit_fn2(p, SC_FN2_MIN, at, start[0], start[2]);   /* clamp: max(x, lo) is emitted */
}

static int name_or_call(parser *p) {
  size_t at = p->i, len = scan_name(p->s + at);
  p->i += len;
  if (!accept(p, '(')) return variable(p, at, len);
  int fn = find(sc_fn_names, p->s + at, len), fn2 = find(sc_fn2_names, p->s + at, len);
  int start[3] = {0, 0, 0}, n = arguments(p, fn2 == SC_FN2_COUNT, at, start);
  if (n < 0) return -1;
  if (fn2 >= 0) return call2(p, fn2, at, len, n, start);
  if (n != 1 && fn >= 0)
    return set_err(p, AP_ERR_ARG, at, "%.*s takes 1 argument, not %d, in expression '%s' "
                   "(column %zu of the value)", (int)len, p->s + at, n, p->shown, at + 1);
  if (fn >= 0) return emit_unary(p, SC_OP_FN, fn, at, start[0]);
  p->n = start[0];
  return unknown_name(p, at, len, 1);
}

/* ---- the grammar ------------------------------------------------------------------------- */

static int primary(parser *p) {
  skip_space(p);
  char ch = p->s[p->i];
  if (isdigit((unsigned char)ch) || (ch == '.' && isdigit((unsigned char)p->s[p->i + 1])))
    return number(p);
  if (ident_start(ch)) return name_or_call(p);
  if (!accept(p, '(')) return expected(p, "a number, a name or '('");
  if (sum(p) != 0) return -1;
  return accept(p, ')') ? 0 : expected(p, "')'");
}

static int unary(parser *p) {
  if (++p->depth > SC_MAX_NEST) return expected(p, "less nesting");
  int start = p->n, rc;
  skip_space(p);
  size_t col = p->i;
  if (accept(p, '-')) {
    rc = unary(p);
    if (rc == 0) rc = emit_unary(p, SC_OP_NEG, 0, col, start);
  } else {
    rc = primary(p);
    skip_space(p);
    col = p->i;
    if (rc == 0 && accept(p, '^')) {
      int rstart = p->n;
      rc = unary(p);
      if (rc == 0) rc = emit_binary(p, SC_OP_POW, col, start, rstart);
    }
  }
  p->depth--;
  return rc;
}

static int product(parser *p) {
  int start = p->n;
  if (unary(p) != 0) return -1;
  for (;;) {
    skip_space(p);
    size_t col = p->i;
    int op = accept(p, '*') ? SC_OP_MUL : accept(p, '/') ? SC_OP_DIV : -1;
    if (op < 0) return 0;
    int rstart = p->n;
    if (unary(p) != 0 || emit_binary(p, op, col, start, rstart) != 0) return -1;
  }
}

static int sum(parser *p) {
  int start = p->n;
  if (product(p) != 0) return -1;
  for (;;) {
    skip_space(p);
    size_t col = p->i;
    int op = accept(p, '+') ? SC_OP_ADD : accept(p, '-') ? SC_OP_SUB : -1;
    if (op < 0) return 0;
    int rstart = p->n;
    if (product(p) != 0 || emit_binary(p, op, col, start, rstart) != 0) return -1;
  }
}

/* ---- the program ------------------------------------------------------------------------- */

static int cmp_int(const void *a, const void *b) {
  int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

static int stack_depth(const sc_ins *code, int n) {
  int sp = 0, depth = 0;
  for (int i = 0; i < n; i++) {
    sp += sc_op_push(code[i].op);
    if (sp > depth) depth = sp;
  }
  return depth;
}

/* Copy the code, the constants it reads and the sorted distinct slots into one block. */
static sc_prog *finish(parser *p) {
  int nk = 0, nv = 0;
  for (int i = 0; i < p->n; i++) nk += sc_op_reads_k(p->code[i].op);
  qsort(p->slots, (size_t)p->nslots, sizeof(int), cmp_int);
  for (int i = 0; i < p->nslots; i++) nv += i == 0 || p->slots[i] != p->slots[i - 1];
  size_t bytes = sizeof(sc_prog) + sizeof(double) * (size_t)nk + sizeof(sc_ins) * (size_t)p->n +
                 sizeof(int) * (size_t)nv;
  sc_prog *g = malloc(bytes);
  if (!g) return NULL;
  double *k = g->data;
  sc_ins *ins = (sc_ins *)(k + nk);
  int *vars = (int *)(ins + p->n);
  g->nins = p->n, g->nk = nk, g->nvars = nv, g->uses_t = p->uses_t;
  g->k = k, g->ins = ins, g->vars = vars;
  nk = 0;
  for (int i = 0; i < p->n; i++) {
    ins[i] = p->code[i];
    if (sc_op_reads_k(ins[i].op)) k[nk] = p->k[ins[i].arg], ins[i].arg = nk++;
  }
  nv = 0;
  for (int i = 0; i < p->nslots; i++)
    if (i == 0 || p->slots[i] != p->slots[i - 1]) vars[nv++] = p->slots[i];
  g->nx = nv ? vars[nv - 1] + 1 : 0;
  g->depth = stack_depth(ins, p->n);
  return g;
}

static int compile(parser *p, sc_prog **out) {
  const char *kind = expected_kind(p->sym);
  if (p->len == 0 || p->len > SC_EXPR_MAX)
    return set_err(p, AP_ERR_ARG, 0, "expected %s, got %s", kind,
                   p->len ? "an expression longer than 1000 characters" : "an empty value");
  if (check_bytes(p) != 0) return -1;
  if (sum(p) != 0) return -1;
  skip_space(p);
  if (p->s[p->i]) return expected(p, "an operator");
  if (p->late.status != AP_OK) return *p->err = p->late, -1;
  sc_prog *g = finish(p);
  if (!g) return set_err(p, AP_ERR_NOMEM, 0, "out of memory compiling '%s'", p->shown);
  double x = 0.0;
  if (g->depth > SC_PROG_STACK) {
    sc_prog_free(g);
    return set_err(p, AP_ERR_ARG, 0, "'%s' nests too deeply (its evaluation needs more than %d "
                   "stack entries)", p->shown, SC_PROG_STACK);
  }
  if (sc_prog_constant(g, &x) && !isfinite(x)) {
    sc_prog_free(g);
    return set_err(p, AP_ERR_ARG, 0, "'%s' is not a finite number (it is %g)", p->shown, x);
  }
  *out = g;
  return 0;
}

int sc_prog_compile(const char *text, const sc_symtab *sym, sc_prog **out, sc_prog_err *err) {
  static const sc_symtab time_only = {1, NULL, NULL, NULL, NULL, NULL};
  sc_prog_err dummy;
  if (!err) err = &dummy;
  err->status = AP_OK, err->col = 0, err->msg[0] = '\0';
  if (!out || !text) return err->status = AP_ERR_ARG;
  *out = NULL;
  parser p = {text, 0, strlen(text), 0, sym ? sym : &time_only, NULL, NULL, NULL, 0, 0, 0, 0, 0,
              err, {AP_OK, 0, ""}, ""};
  snprintf(p.shown, sizeof p.shown, p.len > 80 ? "%.72s..." : "%s", text);
  if (p.len <= SC_EXPR_MAX) {
    p.cap = (int)p.len + 4;
    p.code = malloc((sizeof(sc_ins) + sizeof(double) + sizeof(int)) * (size_t)p.cap);
    if (!p.code) return set_err(&p, AP_ERR_NOMEM, 0, "out of memory compiling '%s'", p.shown),
                        err->status;
    p.k = (double *)(p.code + p.cap);
    p.slots = (int *)(p.k + p.cap);
  }
  compile(&p, out);
  free(p.code);
  return err->status;
}

void sc_prog_free(sc_prog *p) { free(p); }

int sc_prog_uses_t(const sc_prog *p) { return p ? p->uses_t : 0; }
int sc_prog_nvars(const sc_prog *p) { return p ? p->nvars : 0; }
const int *sc_prog_vars(const sc_prog *p) { return p ? p->vars : NULL; }
int sc_prog_nx(const sc_prog *p) { return p ? p->nx : 0; }

int sc_prog_constant(const sc_prog *p, double *value) {
  if (!p || p->nins != 1 || p->ins[0].op != SC_OP_K) return 0;
  if (value) *value = p->k[p->ins[0].arg];
  return 1;
}
