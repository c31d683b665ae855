/* Reusable parts (docs/scenes.md "Parts and include"): a parts: entry is a piece of a scene
 * (bodies, joints, constraints, effects, initial, events) written once with placeholders, and
 * each instances: entry copies it into the scene with its own values:
 *
 *   parts:
 *     wheel:
 *       parameters: {parent: chassis, y: 0}           # defaults; an empty value is required
 *       bodies: {${prefix}wheel: {mass: 1, shape: {kind: disk, radius: 0.15}}}
 *       joints: {${prefix}wheel: {kind: revolute, parent: $parent, parent_frame: {pos: [0, $y, 0]}}}
 *   instances:
 *     rl: {part: wheel, parameters: {y: 0.4}}         # prefix defaults to 'rl_'
 *
 * In every key and scalar of the part, `$NAME` or `${NAME}` stands for the instance's value of
 * the part parameter NAME (or its default), `$name` for the instance's name and `$prefix` for
 * its prefix. The value is put in as written when it is one number or one name, and in
 * parentheses otherwise (`2*$y` with y = `a + b` reads `2*(a + b)`), so names of the scene's
 * parameters and expressions work inside. A default may use other placeholders; they are
 * replaced in turn, at most SC_PART_NEST levels deep (deeper is refused: a cycle).
 *
 * Every copied node keeps the line and column (and file) of the part's text and carries the
 * note "part 'P' as 'I' (FILE:LINE:COL of the instance)", so messages about it name both. A
 * name the copy defines that the scene (or another instance) defines already is an error,
 * unless the scene wrote it without a value (`rear_wheel:`): the copy then takes that entry's
 * place, so the scene decides where in the order of elements (and of the state) it comes.
 * Runs after the --set overrides of parts and instances (`--set instances.rl.parameters.y=0.5`)
 * and before the others, which may change what the copies define (scene.c). The copies
 * of all instances together are at most SC_MAX_NODES nodes (the reader's limit: a few lines
 * of instances of a large part must not grow without bound). */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

#define SC_PART_NEST 8
#define SC_PART_TEXT 4096   /* longest text after the placeholders are put in */

static const char *const part_keys[] = {"parameters", "bodies", "joints", "constraints",
                                        "effects", "initial", "events", NULL};
static const char *const inst_keys[] = {"part", "prefix", "parameters", NULL};

typedef struct inst_ctx {
  sc_ctx *c;
  long *nodes;               /* nodes copied by every instance so far (SC_MAX_NODES at most) */
  const sc_node *defaults;   /* the part's parameters: (or NULL) */
  const sc_node *given;      /* the instance's parameters: (or NULL) */
  const char *name, *prefix, *note, *part;
} inst_ctx;

/* ---- placeholders ---------------------------------------------------------------------------- */

static int subst(inst_ctx *x, const sc_node *at, const char *text, char *out, size_t len,
                 int depth);

/* One number or one name: put in without parentheses. */
static int one_token(const char *s) {
  char *end = NULL;
  (void)strtod(s, &end);
  if (end != s && *end == '\0') return 1;
  if (!(isalpha((unsigned char)s[0]) || s[0] == '_')) return 0;
  for (; *s; s++)
    if (!(isalnum((unsigned char)*s) || *s == '_' || *s == '.')) return 0;
  return 1;
}

/* The value text of placeholder `name` (its own placeholders replaced), into out. */
static int value_of(inst_ctx *x, const sc_node *at, const char *name, char *out, size_t len,
                    int depth) {
  if (strcmp(name, "name") == 0) return snprintf(out, len, "%s", x->name), AP_OK;
  if (strcmp(name, "prefix") == 0) return snprintf(out, len, "%s", x->prefix), AP_OK;
  const sc_node *v = x->given ? sc_map_get(x->given, name) : NULL;
  if (!v && x->defaults) v = sc_map_get(x->defaults, name);
  if (!v || !sc_map_get(x->defaults, name))
    return sc_err(x->c, at, "unknown placeholder '$%s' (the parameters of part '%s', $name "
                  "and $prefix may be used)", name, x->part);
  if (sc_expect(x->c, v, SC_SCALAR)) return AP_ERR_ARG;
  if (!v->text[0] || strcmp(v->text, "~") == 0)
    return sc_err(x->c, v, "part '%s' needs a value of '%s' from instance '%s'", x->part, name,
                  x->name);
  char inner[SC_PART_TEXT];
  if (subst(x, v, v->text, inner, sizeof inner, depth + 1)) return AP_ERR_ARG;
  int n = snprintf(out, len, one_token(inner) ? "%s" : "(%s)", inner);
  if (n < 0 || (size_t)n >= len) return sc_err(x->c, at, "longer than %d characters with its "
                                               "placeholders put in", SC_PART_TEXT);
  return AP_OK;
}

static int subst(inst_ctx *x, const sc_node *at, const char *text, char *out, size_t len,
                 int depth) {
  if (depth > SC_PART_NEST)
    return sc_err(x->c, at, "placeholders nest deeper than %d (the parameters of part '%s' "
                  "refer to each other in a cycle?)", SC_PART_NEST, x->part);
  size_t used = 0;
  for (const char *s = text; *s;) {
    if (*s != '$') {
      if (used + 1 >= len) return sc_err(x->c, at, "longer than %d characters with its "
                                         "placeholders put in", SC_PART_TEXT);
      out[used++] = *s++;
      continue;
    }
    int brace = s[1] == '{';
    const char *b = s + 1 + brace, *e = b;
    while (isalnum((unsigned char)*e) || *e == '_') e++;
    if (e == b || (brace && *e != '}'))
      return sc_err(x->c, at, "'$' must be followed by a parameter's name or {name}");
    char name[128], val[SC_PART_TEXT];
    snprintf(name, sizeof name, "%.*s", (int)(e - b), b);
    if (value_of(x, at, name, val, sizeof val, depth)) return AP_ERR_ARG;
    size_t vl = strlen(val);
    if (used + vl >= len) return sc_err(x->c, at, "longer than %d characters with its "
                                        "placeholders put in", SC_PART_TEXT);
    memcpy(out + used, val, vl);
    used += vl;
    s = e + brace;
  }
  out[used] = '\0';
  return AP_OK;
}

/* A copy of part node n at path (taken) with the placeholders replaced and the note set. */
static sc_node *instantiate(inst_ctx *x, const sc_node *n, char *path) {
  if (++*x->nodes > SC_MAX_NODES) {
    sc_err(x->c, n, "the instances of parts copy more than %d nodes", SC_MAX_NODES);
    return free(path), NULL;
  }
  sc_node *m = sc_node_new(n->kind, n->line, n->col, path);
  if (!m) return sc_nomem(x->c), NULL;
  m->quoted = n->quoted, m->origin = n->origin, m->file = n->file, m->inst = x->note;
  char buf[SC_PART_TEXT];
  if (n->text && (subst(x, m, n->text, buf, sizeof buf, 0) ||
                  !(m->text = sc_strdup_len(buf, strlen(buf)))))
    return sc_tree_free(m), x->c->status ? NULL : (sc_nomem(x->c), NULL);
  for (int i = 0; i < n->n; i++) {
    sc_node *k = NULL;
    if (n->keys) {
      if (subst(x, n->keys[i], n->keys[i]->text, buf, sizeof buf, 0))
        return sc_tree_free(m), NULL;
      k = instantiate(x, n->keys[i], sc_child_path(m->path, buf, 0));
      if (!k) return sc_tree_free(m), NULL;
    }
    sc_node *v = instantiate(x, n->kids[i], sc_child_path(m->path, k ? k->text : NULL, i));
    if (!v || sc_node_push(m, k, v) != AP_OK) {
      if (v) sc_nomem(x->c);
      return sc_tree_free(k), sc_tree_free(v), sc_tree_free(m), NULL;
    }
  }
  return m;
}

/* ---- instances ------------------------------------------------------------------------------- */

/* The section `name` of root, created empty when missing. */
static sc_node *section(sc_ctx *c, sc_node *root, const char *name) {
  sc_node *s = sc_map_get(root, name);
  if (s) return sc_expect(c, s, SC_MAP) ? NULL : s;
  sc_node *k = sc_node_new(SC_SCALAR, root->line, root->col, sc_child_path("", name, 0));
  s = sc_node_new(SC_MAP, root->line, root->col, sc_child_path("", name, 0));
  if (k) k->text = sc_strdup_len(name, strlen(name));
  if (!k || !s || !k->text || sc_node_push(root, k, s) != AP_OK)
    return sc_tree_free(k), sc_tree_free(s), sc_nomem(c), NULL;
  return s;
}

/* An entry written without a value (`rear_wheel:`) keeps its place in the order of its section
 * for the instance that defines it: elements are built in the order of the file. */
static int kept_place(const sc_node *v) {
  return v->kind == SC_SCALAR && !v->quoted && (!v->text[0] || strcmp(v->text, "~") == 0);
}

static int add_entries(inst_ctx *x, sc_node *root, const char *name, const sc_node *src) {
  if (sc_expect(x->c, src, SC_MAP)) return AP_ERR_ARG;
  sc_node *dst = section(x->c, root, name);
  if (!dst) return x->c->status;
  for (int i = 0; i < src->n; i++) {
    sc_node *k = instantiate(x, src->keys[i], sc_strdup_len(name, strlen(name)));
    if (!k) return x->c->status;
    free(k->path);
    k->path = sc_child_path(name, k->text, 0);
    sc_node *v = k->path ? instantiate(x, src->kids[i], sc_child_path(name, k->text, 0)) : NULL;
    const sc_node *had = v ? sc_map_get(dst, k->text) : NULL;
    int rc = !v ? (x->c->status ? x->c->status : sc_nomem(x->c)) : AP_OK;
    for (int j = 0; had && j < dst->n; j++)
      if (dst->kids[j] == had) {
        if (kept_place(had)) {   /* the copy takes the place the scene kept for it */
          sc_tree_free(dst->keys[j]), sc_tree_free(dst->kids[j]);
          dst->keys[j] = k, dst->kids[j] = v;
          k = v = NULL, had = NULL;
          break;
        }
        had = dst->keys[j];
      }
    if (!k) continue;
    if (rc == AP_OK && had)
      rc = sc_err(x->c, k, "'%s' is defined twice: here and at %s:%d:%d%s%s", k->text,
                  had->file ? had->file : x->c->file, had->line, had->col,
                  had->inst ? " in " : "", had->inst ? had->inst : "");
    if (rc == AP_OK && sc_node_push(dst, k, v) != AP_OK) rc = sc_nomem(x->c);
    if (rc != AP_OK) return sc_tree_free(k), sc_tree_free(v), rc;
  }
  return AP_OK;
}

static const sc_node *find_part(sc_ctx *c, const sc_node *parts, const sc_node *inst) {
  const char *name = NULL;
  if (sc_get_name(c, inst, "part", &name)) return NULL;
  if (!name) return sc_err(c, inst, "an instance names its part (part: NAME)"), NULL;
  const sc_node *p = parts ? sc_map_get(parts, name) : NULL;
  if (p) return p;
  const char *list[64] = {NULL};
  for (int i = 0; parts && i < parts->n && i < 63; i++) list[i] = parts->keys[i]->text;
  const char *near = sc_suggest(name, list);
  sc_err(c, sc_map_get(inst, "part"), "no part named '%s'%s%s%s", name,
         near ? " (did you mean '" : "", near ? near : "", near ? "'?)" : "");
  return NULL;
}

/* The instance's parameters must be the part's. */
static int check_given(inst_ctx *x) {
  if (!x->given) return AP_OK;
  if (sc_expect(x->c, x->given, SC_MAP)) return AP_ERR_ARG;
  const char *list[64] = {NULL};
  for (int i = 0; x->defaults && i < x->defaults->n && i < 63; i++)
    list[i] = x->defaults->keys[i]->text;
  for (int i = 0; i < x->given->n; i++)
    if (!x->defaults || !sc_map_get(x->defaults, x->given->keys[i]->text)) {
      const char *near = sc_suggest(x->given->keys[i]->text, list);
      return sc_err(x->c, x->given->keys[i], "part '%s' has no parameter '%s'%s%s%s", x->part,
                    x->given->keys[i]->text, near ? " (did you mean '" : "",
                    near ? near : "", near ? "'?)" : "");
    }
  return AP_OK;
}

static int one_instance(sc_ctx *c, sc_node *root, const sc_node *parts, const sc_node *key,
                        const sc_node *inst, sc_strings *pool, long *nodes) {
  if (sc_check_keys(c, inst, inst_keys)) return AP_ERR_ARG;
  const sc_node *part = find_part(c, parts, inst);
  if (!part || sc_check_keys(c, part, part_keys)) return AP_ERR_ARG;
  char prefix[128], note[600];
  snprintf(prefix, sizeof prefix, "%.100s_", key->text);
  const sc_node *pn = sc_map_get(inst, "prefix");
  if (pn && sc_expect(c, pn, SC_SCALAR)) return AP_ERR_ARG;
  if (pn) snprintf(prefix, sizeof prefix, "%.100s", pn->text);
  const char *pname = sc_map_get(inst, "part")->text;
  snprintf(note, sizeof note, "part '%.100s' as '%.100s', %s:%d:%d", pname, key->text,
           key->file ? key->file : c->file, key->line, key->col);
  inst_ctx x = {c, nodes, sc_map_get(part, "parameters"), sc_map_get(inst, "parameters"), key->text,
                NULL, sc_strings_add(pool, note), pname};
  x.prefix = sc_strings_add(pool, prefix);
  if (!x.prefix || !x.note) return sc_nomem(c);
  if ((x.defaults && sc_expect(c, x.defaults, SC_MAP)) || check_given(&x)) return AP_ERR_ARG;
  for (int i = 0; i < part->n; i++)
    if (strcmp(part->keys[i]->text, "parameters") != 0 &&
        add_entries(&x, root, part->keys[i]->text, part->kids[i]))
      return AP_ERR_ARG;
  return AP_OK;
}

int sc_parts_expand(sc_ctx *c, sc_node *root, sc_strings *pool) {
  if (!root || root->kind != SC_MAP) return AP_OK;
  const sc_node *parts = sc_map_get(root, "parts"), *inst = sc_map_get(root, "instances");
  if (parts && sc_expect(c, parts, SC_MAP)) return AP_ERR_ARG;
  if (!inst) return AP_OK;
  if (sc_expect(c, inst, SC_MAP)) return AP_ERR_ARG;
  long nodes = 0;
  for (int i = 0; i < inst->n; i++)
    if (one_instance(c, root, parts, inst->keys[i], inst->kids[i], pool, &nodes))
      return AP_ERR_ARG;
  return AP_OK;
}
