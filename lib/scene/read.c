/* Scene reading: typed getters on the tree, unknown keys with a "did you mean" suggestion
 * (edit distance with swaps of neighbours), and the one message per load.
 *
 * Every getter takes the map and the key, leaves its output untouched when the key is absent
 * (so callers pre-fill defaults), and on a wrong type or value records
 * "FILE:LINE:COL: key.path: what" through sc_err and returns AP_ERR_ARG. Invariant: the first
 * error wins; later calls do not overwrite the message. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/core.h"
#include "scene/scene_int.h"

static const char *kind_word(sc_kind k) {
  return k == SC_MAP ? "a mapping" : k == SC_SEQ ? "a sequence" : "a scalar";
}

int sc_err(sc_ctx *c, const sc_node *at, const char *fmt, ...) {
  if (c->status != AP_OK) return c->status;
  char what[768];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  char path[128];
  const char *full = at && at->path && at->path[0] ? at->path : "(top level)";
  snprintf(path, sizeof path, "%.100s%s", full, strlen(full) > 100 ? "..." : "");
  const char *file = at && at->file ? at->file : c->file;
  char inst[300] = "";
  if (at && at->inst) snprintf(inst, sizeof inst, " (in %s)", at->inst);
  if (at && at->line == 0)
    snprintf(c->msg, sizeof c->msg, "%s: --set %s: %s%s: %s", file,
             at->origin ? at->origin : "?", path, inst, what);
  else if (at && at->origin)
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: %s (set by --set %s)%s: %s", file, at->line,
             at->col, path, at->origin, inst, what);
  else
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: %s%s: %s", file, at ? at->line : 1,
             at ? at->col : 1, path, inst, what);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

const char *sc_suggest(const char *word, const char *const *keys) {
  return ap_suggest(word, keys, -1);
}

int sc_expect(sc_ctx *c, const sc_node *n, sc_kind kind) {
  if (n->kind == kind) return AP_OK;
  return sc_err(c, n, "expected %s, got %s", kind_word(kind), kind_word(n->kind));
}

static void list_keys(const char *const *keys, char *buf, size_t len) {
  size_t used = 0;
  buf[0] = '\0';
  for (int i = 0; keys[i] && used + 2 < len; i++)
    used += (size_t)snprintf(buf + used, len - used, "%s%s", i ? ", " : "", keys[i]);
}

int sc_check_keys(sc_ctx *c, const sc_node *map, const char *const *keys) {
  int rc = sc_expect(c, map, SC_MAP);
  if (rc == AP_OK && !keys[0] && map->n > 0)
    return sc_err(c, map->keys[0], "unknown key '%s' (nothing can be set here)",
                  map->keys[0]->text);
  for (int i = 0; rc == AP_OK && i < map->n; i++) {
    const char *k = map->keys[i]->text;
    int ok = 0;
    for (int j = 0; keys[j] && !ok; j++) ok = strcmp(k, keys[j]) == 0;
    if (ok) continue;
    const char *s = sc_suggest(k, keys);
    char all[400];
    list_keys(keys, all, sizeof all);
    if (s)
      rc = sc_err(c, map->keys[i], "unknown key '%s' (did you mean '%s'?)", k, s);
    else
      rc = sc_err(c, map->keys[i], "unknown key '%s' (allowed here: %s)", k, all);
  }
  return rc;
}

/* YAML's names of infinity and not-a-number (.inf, -.Inf, .NaN, ...) are not numbers here: a
 * located message instead of the expression parser's "unexpected '.'". */
static int special_float(sc_ctx *c, const sc_node *n) {
  const char *s = n->text + (n->text[0] == '+' || n->text[0] == '-');
  int inf = strcasecmp(s, ".inf") == 0, nan = strcasecmp(s, ".nan") == 0;
  if (!inf && !nan) return AP_OK;
  return sc_err(c, n, "expected a finite number, got '%s' (YAML's %s)", n->text,
                inf ? "infinity" : "not-a-number");
}

/* A number, or an expression of constants (pi, deg, ...) when the text is not one. */
int sc_number(sc_ctx *c, const sc_node *n, double *out) {
  if (sc_expect(c, n, SC_SCALAR) != AP_OK || special_float(c, n) != AP_OK) return AP_ERR_ARG;
  const char *s = n->text;
  char *end = NULL;
  double x = strtod(s, &end);
  while (end && end != s && isspace((unsigned char)*end)) end++;
  int number = end != s && *end == '\0' && !n->quoted;
  if (!number) {
    sc_expr e;
    if (sc_expr_compile(c, n, s, 0, &e) != AP_OK) return AP_ERR_ARG;
    x = e.value;
    sc_expr_free(&e);
  }
  if (number && isinf(x) && !strpbrk(s, "iI"))
    return sc_err(c, n, "expected a finite number, got '%s' (beyond the range of a double)", s);
  if (!isfinite(x)) return sc_err(c, n, "expected a finite number, got '%s'", s);
  *out = x;
  return AP_OK;
}

int sc_expr_node(sc_ctx *c, const sc_node *n, sc_expr *e) {
  memset(e, 0, sizeof *e);
  if (sc_expect(c, n, SC_SCALAR) != AP_OK || special_float(c, n) != AP_OK) return AP_ERR_ARG;
  return sc_expr_read(c, n, e);
}

int sc_get_number(sc_ctx *c, const sc_node *map, const char *key, double *out) {
  const sc_node *n = sc_map_get(map, key);
  return n ? sc_number(c, n, out) : AP_OK;
}

int sc_get_vec(sc_ctx *c, const sc_node *map, const char *key, int len, double *out) {
  const sc_node *n = sc_map_get(map, key);
  if (!n) return AP_OK;
  if (n->kind != SC_SEQ || n->n != len)
    return sc_err(c, n, "expected a sequence of %d numbers, e.g. [%s]", len,
                  len == 2 ? "0, 0" : len == 3 ? "0, 0, 1" : "1, 0, 0, 0");
  double tmp[16];
  for (int i = 0; i < len && i < 16; i++)
    if (sc_number(c, n->kids[i], &tmp[i]) != AP_OK) return AP_ERR_ARG;
  memcpy(out, tmp, sizeof(double) * (size_t)len);
  return AP_OK;
}

int sc_get_bool(sc_ctx *c, const sc_node *map, const char *key, int *out) {
  const sc_node *n = sc_map_get(map, key);
  if (!n) return AP_OK;
  static const char *const yes[] = {"true", "yes", "on", "1", NULL};
  static const char *const no[] = {"false", "no", "off", "0", NULL};
  if (sc_expect(c, n, SC_SCALAR) != AP_OK) return AP_ERR_ARG;
  for (int i = 0; yes[i]; i++)
    if (strcasecmp(n->text, yes[i]) == 0) return *out = 1, AP_OK;
  for (int i = 0; no[i]; i++)
    if (strcasecmp(n->text, no[i]) == 0) return *out = 0, AP_OK;
  return sc_err(c, n, "expected true or false, got '%s'", n->text);
}

int sc_get_int(sc_ctx *c, const sc_node *map, const char *key, long *out) {
  const sc_node *n = sc_map_get(map, key);
  if (!n) return AP_OK;
  double x = 0;
  if (sc_number(c, n, &x) != AP_OK) return AP_ERR_ARG;
  if (x != floor(x) || fabs(x) > 1e15)
    return sc_err(c, n, "expected an integer, got '%s'", n->text);
  *out = (long)x;
  return AP_OK;
}

int sc_get_name(sc_ctx *c, const sc_node *map, const char *key, const char **out) {
  const sc_node *n = sc_map_get(map, key);
  if (!n) return AP_OK;
  if (n->kind != SC_SCALAR) return sc_err(c, n, "expected a name, got %s", kind_word(n->kind));
  if (!n->text[0]) return sc_err(c, n, "expected a name, got an empty value");
  *out = n->text;
  return AP_OK;
}

int sc_get_enum(sc_ctx *c, const sc_node *map, const char *key, const char *const *words,
                int *out) {
  const char *w = NULL;
  if (sc_get_name(c, map, key, &w) != AP_OK) return AP_ERR_ARG;
  if (!w) return AP_OK;
  for (int i = 0; words[i]; i++)
    if (strcmp(w, words[i]) == 0) return *out = i, AP_OK;
  const char *s = sc_suggest(w, words);
  char all[400];
  list_keys(words, all, sizeof all);
  if (s) return sc_err(c, sc_map_get(map, key), "unknown %s '%s' (did you mean '%s'?)", key, w, s);
  return sc_err(c, sc_map_get(map, key), "unknown %s '%s' (one of: %s)", key, w, all);
}

/* A range error at the key's value ("must be ...", the path names the key) or, when the key
 * is absent and its default is out of range, at the map ("radius must be ..."). */
static int range_err(sc_ctx *c, const sc_node *map, const char *key, const char *what,
                     double x) {
  const sc_node *n = sc_map_get(map, key);
  if (n) return sc_err(c, n, "must %s (got %g)", what, x);
  return sc_err(c, map, "%s must %s (it is not given and defaults to %g)", key, what, x);
}

int sc_check_positive(sc_ctx *c, const sc_node *map, const char *key, double x) {
  return x > 0 ? AP_OK : range_err(c, map, key, "be positive", x);
}

int sc_check_nonneg(sc_ctx *c, const sc_node *map, const char *key, double x) {
  return x >= 0 ? AP_OK : range_err(c, map, key, "not be negative", x);
}
