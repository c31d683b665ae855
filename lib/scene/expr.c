/* Scene expressions: numbers, constant expressions and functions of time in a scene file, on
 * the evaluator of expr.h (docs/scenes.md "Expressions").
 *
 * An sc_expr is either a constant `value` (timed = 0; numbers and expressions that fold to a
 * number) or a compiled program (timed = 1) with its text and the node it was read from, so
 * a value that is not finite where it is evaluated is reported at FILE:LINE:COLUMN of that
 * node with the operation and column inside the text (sc_expr_check). Invariant: an sc_expr
 * is never written after compile, so the model's callbacks (sc_expr_time_fn) may run from any
 * number of threads; they allocate nothing. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

void sc_expr_free(sc_expr *e) {
  sc_prog_free(e->prog);
  free(e->text);
  memset(e, 0, sizeof *e);
}

/* Out of memory: the message, and AP_ERR_NOMEM as the load's status. */
static int nomem(sc_ctx *c, const sc_node *at, const char *text) {
  int first = c->status == AP_OK;
  sc_err(c, at, "out of memory compiling the expression '%.60s'", text);
  if (first) c->status = AP_ERR_NOMEM;
  return AP_ERR_NOMEM;
}

int sc_expr_compile_sym(sc_ctx *c, const sc_node *at, const char *text, const sc_symtab *sym,
                        sc_expr *e) {
  memset(e, 0, sizeof *e);
  e->node = at;
  sc_prog_err err;
  sc_prog *p = NULL;
  sc_symtab named = *sym;   /* the scene's parameters, unless the caller has its own lookup */
  if (at && at->params && !named.lookup) sc_params_symtab(at->params, &named);
  int rc = sc_prog_compile(text, &named, &p, &err);
  if (rc == AP_ERR_NOMEM) return nomem(c, at, text);
  if (rc != AP_OK) return sc_err(c, at, "%s", err.msg);
  if (sc_prog_constant(p, &e->value)) {
    sc_prog_free(p);
    return AP_OK;
  }
  size_t len = strlen(text);
  e->text = malloc(len + 1);
  if (!e->text) {
    sc_prog_free(p);
    return nomem(c, at, text);
  }
  memcpy(e->text, text, len + 1);
  e->prog = p;
  e->timed = 1;
  return AP_OK;
}

int sc_expr_compile(sc_ctx *c, const sc_node *at, const char *text, int allow_t, sc_expr *e) {
  sc_symtab sym = {allow_t, NULL, NULL, NULL, NULL, NULL};
  return sc_expr_compile_sym(c, at, text, &sym, e);
}

int sc_expr_read(sc_ctx *c, const sc_node *n, sc_expr *e) {
  memset(e, 0, sizeof *e);
  e->node = n;
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
  return sc_prog_time(e->prog, t, f);
}

int sc_expr_time_fn(double t, double f[3], void *user) {
  return sc_expr_eval((const sc_expr *)user, t, f);
}

/* ---- located messages ---------------------------------------------------------------------- */

int sc_expr_check_jet(sc_ctx *c, const sc_expr *e, const sc_jet *t, const sc_jet *x,
                      int order) {
  sc_jet f;
  if (!e->timed || sc_prog_jet(e->prog, t, x, &f) == 0) return AP_OK;
  int bad = -1;
  for (int i = 0; i <= order && i < 3 && bad < 0; i++)
    if (!isfinite(f.c[i])) bad = i;
  if (bad < 0) return AP_OK;   /* only a coefficient beyond the order asked for */
  static const char *const what[] = {"is not finite", "has no finite first %sderivative",
                                     "has no finite second %sderivative"};
  char why[200], head[64];
  snprintf(head, sizeof head, what[bad], t->c[1] != 0.0 ? "time " : "");
  sc_prog_explain(e->prog, t, x, order, why, sizeof why);
  return sc_err(c, e->node, "'%.200s%s' %s at t = %.17g: %s", e->text,
                strlen(e->text) > 200 ? "..." : "", head, t->c[0], why);
}

int sc_expr_check(sc_ctx *c, const sc_expr *e, double t) {
  sc_jet tj = {{t, 1.0, 0.0}};
  if (e->timed && sc_prog_nvars(e->prog) > 0) return AP_OK;   /* needs the state */
  return sc_expr_check_jet(c, e, &tj, NULL, 2);
}
