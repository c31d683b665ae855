/* Scene parameters (docs/scenes.md "Parameters"): the parameters: section, named numbers that
 * every number and expression of the scene may use.
 *
 *   parameters:
 *     wheelbase: 1.02
 *     trail: 0.08
 *     half: wheelbase/2        # an expression of other parameters, in any order
 *
 * Each value is a number or a constant expression of other parameters (units as elsewhere:
 * `80*deg`). They are evaluated once, when the scene is loaded, in the order their names are
 * needed (a depth-first walk: evaluating one looks up the names it uses, evaluating those
 * first). A name met again while it is being evaluated closes a cycle: refused at the node of
 * the first parameter of the cycle with the chain ("a -> b -> a"). Unknown names get the
 * expression parser's message with "did you mean" among the parameters.
 *
 * The expression compiler reaches the table through the symbol table's lookup hook (expr.h):
 * sc_params_read points every node of the tree at it, and sc_expr_compile_sym adds the hook
 * for nodes that have one. Names of the state (joint.angle) and t come first; a parameter
 * cannot be named t, pi, e, deg or like a function. Invariant: after sc_params_read returns
 * AP_OK every parameter has its finite value and the table is only read (threads may share
 * it). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/expr_int.h"
#include "scene/scene_int.h"

#define SC_PARAM_NEST 100   /* deepest chain of parameters defined by other parameters */

typedef struct sc_param {
  const char *name;
  const sc_node *node;     /* its value */
  double value;
  int state;               /* 0 not evaluated, 1 being evaluated, 2 done */
} sc_param;

struct sc_params {
  int n;
  sc_param *p;
  const char **names;      /* n names, then NULL: the suggestions of unknown names */
  sc_ctx *c;               /* while sc_params_read runs */
  int stack[SC_PARAM_NEST];   /* the parameters being evaluated, outermost first */
  int depth;
};

int sc_params_count(const sc_params *p) { return p ? p->n : 0; }
const char *sc_params_name(const sc_params *p, int i) {
  return p && i >= 0 && i < p->n ? p->p[i].name : NULL;
}
double sc_params_value(const sc_params *p, int i) {
  return p && i >= 0 && i < p->n ? p->p[i].value : 0.0;
}

void sc_params_free(sc_params *p) {
  if (!p) return;
  free(p->p);
  free(p->names);
  free(p);
}

static int find(const sc_params *p, const char *name, size_t len) {
  for (int i = 0; i < p->n; i++)
    if (strlen(p->p[i].name) == len && strncmp(p->p[i].name, name, len) == 0) return i;
  return -1;
}

/* "a -> b -> a" from the stack entry of i to the top, into buf. */
static void chain(const sc_params *p, int i, char *buf, size_t len) {
  size_t used = 0;
  int from = 0;
  while (from < p->depth && p->stack[from] != i) from++;
  buf[0] = '\0';
  for (int k = from; k < p->depth && used + 8 < len; k++)
    used += (size_t)snprintf(buf + used, len - used, "%s -> ", p->p[p->stack[k]].name);
  if (used + 2 < len) snprintf(buf + used, len - used, "%s", p->p[i].name);
}

static int evaluate(sc_params *p, int i) {
  sc_param *q = &p->p[i];
  if (p->depth == SC_PARAM_NEST)
    return sc_err(p->c, q->node, "parameters defined by parameters nest deeper than %d",
                  SC_PARAM_NEST);
  q->state = 1;
  p->stack[p->depth++] = i;
  int rc = sc_number(p->c, q->node, &q->value);
  p->depth--;
  q->state = rc == AP_OK ? 2 : 0;
  return rc;
}

/* The lookup hook of expr.h: 1 and the value, 0 for a name that is not a parameter, -1 when
 * its value cannot be had (a cycle, or its own expression failed: the message is recorded). */
static int lookup(void *user, const char *name, size_t len, double *value) {
  sc_params *p = user;
  int i = find(p, name, len);
  if (i < 0) return 0;
  if (p->p[i].state == 1) {
    char buf[400];
    chain(p, i, buf, sizeof buf);
    sc_err(p->c, p->p[i].node, "the parameters depend on each other in a cycle: %s", buf);
    return -1;
  }
  if (p->p[i].state == 0 && evaluate(p, i) != AP_OK) return -1;
  *value = p->p[i].value;
  return 1;
}

void sc_params_symtab(const sc_params *p, sc_symtab *sym) {
  sym->lookup = lookup;
  sym->user = (void *)p;   /* written only while sc_params_read evaluates */
  sym->constants = p->names;
}

static void point_at(sc_node *n, const sc_params *p) {
  n->params = p;
  for (int i = 0; i < n->n; i++) {
    if (n->keys) point_at(n->keys[i], p);
    point_at(n->kids[i], p);
  }
}

/* A parameter's name: letters, digits and '_', not t, a constant or a function. */
static int check_name(sc_ctx *c, const sc_node *key) {
  static const char *const taken[] = {"t", "pi", "e", "deg", NULL};
  const char *s = key->text;
  int ok = s[0] && !(s[0] >= '0' && s[0] <= '9');
  for (const char *k = s; ok && *k; k++)
    ok = (*k >= 'a' && *k <= 'z') || (*k >= 'A' && *k <= 'Z') || (*k >= '0' && *k <= '9') ||
         *k == '_';
  if (!ok)
    return sc_err(c, key, "a parameter's name is letters, digits and '_', not starting with a "
                  "digit (got '%s')", s);
  for (int i = 0; taken[i]; i++)
    if (strcmp(s, taken[i]) == 0) return sc_err(c, key, "'%s' is a constant of expressions", s);
  for (int i = 0; sc_fn_names[i]; i++)
    if (strcmp(s, sc_fn_names[i]) == 0)
      return sc_err(c, key, "'%s' is a function of expressions", s);
  for (int i = 0; sc_fn2_names[i]; i++)
    if (strcmp(s, sc_fn2_names[i]) == 0)
      return sc_err(c, key, "'%s' is a function of expressions", s);
  return AP_OK;
}

static int make(sc_ctx *c, const sc_node *sec, sc_params **out) {
  sc_params *p = calloc(1, sizeof *p);
  if (p) p->p = calloc((size_t)sec->n + 1, sizeof *p->p);
  if (p) p->names = calloc((size_t)sec->n + 1, sizeof *p->names);
  if (!p || !p->p || !p->names) return sc_params_free(p), sc_nomem(c);
  p->c = c;
  for (int i = 0; i < sec->n; i++, p->n++) {
    if (check_name(c, sec->keys[i])) return sc_params_free(p), AP_ERR_ARG;
    p->p[i].name = p->names[i] = sec->keys[i]->text;
    p->p[i].node = sec->kids[i];
  }
  *out = p;
  return AP_OK;
}

int sc_params_read(sc_ctx *c, sc_node *root, sc_params **out) {
  *out = NULL;
  const sc_node *sec = sc_map_get(root, "parameters");
  if (!sec) return AP_OK;
  if (sc_expect(c, sec, SC_MAP)) return AP_ERR_ARG;
  sc_params *p = NULL;
  if (make(c, sec, &p)) return c->status;
  point_at(root, p);
  for (int i = 0; i < p->n; i++)
    if (p->p[i].state == 0 && evaluate(p, i) != AP_OK) {
      point_at(root, NULL);
      sc_params_free(p);
      return c->status;
    }
  p->c = NULL;
  *out = p;
  return AP_OK;
}

/* ---- public (include/appell/scene.h) ----------------------------------------------------- */

int ap_scene_parameter_count(const ap_scene *sc) {
  const sc_scene *s = sc_scene_parsed(sc);
  return s ? sc_params_count(s->params) : 0;
}

int ap_scene_parameter(const ap_scene *sc, int i, const char **name, double *value) {
  if (!name || !value || i < 0 || i >= ap_scene_parameter_count(sc)) return AP_ERR_ARG;
  const sc_params *p = sc_scene_parsed(sc)->params;
  *name = sc_params_name(p, i);
  *value = sc_params_value(p, i);
  return AP_OK;
}
