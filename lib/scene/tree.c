/* Scene tree: a libyaml document copied into sc_node trees that keep the line and column of
 * every node and its key path, plus the --set overrides that edit the tree before it is read.
 *
 * Layout: a node is a scalar (text), a sequence (kids) or a mapping (keys[i] -> kids[i], keys
 * are scalar nodes so that an unknown key can be reported where it is written). Aliases are
 * expanded by copying; SC_MAX_DEPTH and SC_MAX_NODES bound the work, so a recursive alias or
 * an alias bomb is an error, not a hang. Invariant: every node owns its children; paths are
 * "a.b[2].c" (sequence items in brackets). */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

#include "scene/scene_int.h"

typedef struct tree_build {
  sc_ctx *c;
  yaml_document_t *doc;
  long nodes;
} tree_build;

static char *dup_str(const char *s, size_t len) {
  char *p = malloc(len + 1);
  if (!p) return NULL;
  memcpy(p, s, len);
  p[len] = '\0';
  return p;
}

static char *child_path(const char *parent, const char *key, int index) {
  size_t len = strlen(parent) + (key ? strlen(key) : 24) + 4;
  char *p = malloc(len);
  if (!p) return NULL;
  if (key)
    snprintf(p, len, "%s%s%s", parent, parent[0] ? "." : "", key);
  else
    snprintf(p, len, "%s[%d]", parent, index);
  return p;
}

static sc_node *node_new(sc_kind kind, int line, int col, char *path) {
  sc_node *n = calloc(1, sizeof *n);
  if (!n) {
    free(path);
    return NULL;
  }
  n->kind = kind, n->line = line, n->col = col, n->path = path;
  return n;
}

void sc_tree_free(sc_node *n) {
  if (!n) return;
  for (int i = 0; i < n->n; i++) {
    if (n->keys) sc_tree_free(n->keys[i]);
    sc_tree_free(n->kids[i]);
  }
  free(n->keys);
  free(n->kids);
  free(n->text);
  free(n->path);
  free(n);
}

/* Append a child (and its key for maps). */
static int node_push(sc_node *n, sc_node *key, sc_node *kid) {
  if (n->n == n->cap) {
    int cap = n->cap ? 2 * n->cap : 4;
    sc_node **kids = realloc(n->kids, sizeof *kids * (size_t)cap);
    if (!kids) return AP_ERR_NOMEM;
    n->kids = kids;
    if (n->kind == SC_MAP) {
      sc_node **keys = realloc(n->keys, sizeof *keys * (size_t)cap);
      if (!keys) return AP_ERR_NOMEM;
      n->keys = keys;
    }
    n->cap = cap;
  }
  if (n->kind == SC_MAP) n->keys[n->n] = key;
  n->kids[n->n++] = kid;
  return AP_OK;
}

sc_node *sc_map_get(const sc_node *map, const char *key) {
  if (!map || map->kind != SC_MAP) return NULL;
  for (int i = 0; i < map->n; i++)
    if (strcmp(map->keys[i]->text, key) == 0) return map->kids[i];
  return NULL;
}

static sc_node *copy_node(tree_build *tb, yaml_node_t *y, char *path, int depth);

static int nomem(sc_ctx *c) {
  snprintf(c->msg, sizeof c->msg, "%s: out of memory", c->file);
  c->status = AP_ERR_NOMEM;
  return AP_ERR_NOMEM;
}

static sc_node *copy_scalar(tree_build *tb, yaml_node_t *y, char *path) {
  sc_node *n = node_new(SC_SCALAR, (int)y->start_mark.line + 1, (int)y->start_mark.column + 1,
                        path);
  if (!n) return nomem(tb->c), NULL;
  const char *v = (const char *)y->data.scalar.value;
  size_t len = y->data.scalar.length;
  if (memchr(v, '\0', len)) {
    sc_err(tb->c, n, "the value contains a NUL character");
    sc_tree_free(n);
    return NULL;
  }
  n->text = dup_str(v, len);
  if (!n->text) return sc_tree_free(n), nomem(tb->c), NULL;
  n->quoted = y->data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
              y->data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE;
  return n;
}

static int copy_seq(tree_build *tb, yaml_node_t *y, sc_node *n, int depth) {
  int i = 0;
  for (yaml_node_item_t *it = y->data.sequence.items.start; it < y->data.sequence.items.top;
       it++, i++) {
    char *p = child_path(n->path, NULL, i);
    if (!p) return nomem(tb->c);
    sc_node *kid = copy_node(tb, yaml_document_get_node(tb->doc, *it), p, depth + 1);
    if (!kid) return tb->c->status;
    if (node_push(n, NULL, kid) != AP_OK) return sc_tree_free(kid), nomem(tb->c);
  }
  return AP_OK;
}

static int copy_map(tree_build *tb, yaml_node_t *y, sc_node *n, int depth) {
  for (yaml_node_pair_t *pr = y->data.mapping.pairs.start; pr < y->data.mapping.pairs.top;
       pr++) {
    yaml_node_t *yk = yaml_document_get_node(tb->doc, pr->key);
    char *kp = child_path(n->path, "", 0);
    if (!kp) return nomem(tb->c);
    sc_node *key = yk ? copy_node(tb, yk, kp, depth + 1) : NULL;
    if (!yk) free(kp);
    if (!key) return yk ? tb->c->status : sc_err(tb->c, n, "a mapping key is missing");
    free(key->path);
    key->path = key->kind == SC_SCALAR ? child_path(n->path, key->text, 0) : dup_str("", 0);
    if (!key->path) return sc_tree_free(key), nomem(tb->c);
    if (key->kind != SC_SCALAR) {
      sc_err(tb->c, key, "a mapping key must be a plain name, not a %s",
             key->kind == SC_MAP ? "mapping" : "sequence");
      return sc_tree_free(key), AP_ERR_ARG;
    }
    if (sc_map_get(n, key->text)) {
      sc_err(tb->c, key, "duplicate key '%s'", key->text);
      return sc_tree_free(key), AP_ERR_ARG;
    }
    char *p = child_path(n->path, key->text, 0);
    sc_node *val = p ? copy_node(tb, yaml_document_get_node(tb->doc, pr->value), p, depth + 1)
                     : NULL;
    if (!val) return sc_tree_free(key), p ? tb->c->status : nomem(tb->c);
    if (node_push(n, key, val) != AP_OK) return sc_tree_free(key), sc_tree_free(val), nomem(tb->c);
  }
  return AP_OK;
}

/* Copy a libyaml node (takes ownership of path). */
static sc_node *copy_node(tree_build *tb, yaml_node_t *y, char *path, int depth) {
  if (!path) return nomem(tb->c), NULL;
  if (!y) {
    free(path);
    snprintf(tb->c->msg, sizeof tb->c->msg, "%s: malformed YAML document", tb->c->file);
    tb->c->status = AP_ERR_ARG;
    return NULL;
  }
  int line = (int)y->start_mark.line + 1, col = (int)y->start_mark.column + 1;
  if (depth > SC_MAX_DEPTH || ++tb->nodes > SC_MAX_NODES) {
    sc_node tmp = {.line = line, .col = col, .path = path};
    sc_err(tb->c, &tmp, "%s", depth > SC_MAX_DEPTH
           ? "nested too deeply (a recursive alias?)" : "too many nodes (an alias bomb?)");
    free(path);
    return NULL;
  }
  if (y->type == YAML_SCALAR_NODE) return copy_scalar(tb, y, path);
  sc_node *n = node_new(y->type == YAML_MAPPING_NODE ? SC_MAP : SC_SEQ, line, col, path);
  if (!n) return nomem(tb->c), NULL;
  int rc = n->kind == SC_MAP ? copy_map(tb, y, n, depth) : copy_seq(tb, y, n, depth);
  if (rc != AP_OK) {
    sc_tree_free(n);
    return NULL;
  }
  return n;
}

static void yaml_error(sc_ctx *c, const yaml_parser_t *p) {
  /* libyaml's out of memory is not bad input; its loader also fails without setting an error
   * when a strdup of a tag fails (libyaml 0.2.5 loader.c): no error means no memory. */
  if (p->error == YAML_MEMORY_ERROR || p->error == YAML_NO_ERROR) {
    nomem(c);
    return;
  }
  const char *what = p->problem ? p->problem : "malformed YAML";
  yaml_mark_t mk = p->problem_mark;
  if (p->context)
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: malformed YAML: %s %s (line %d)", c->file,
             (int)mk.line + 1, (int)mk.column + 1, what, p->context, (int)p->context_mark.line + 1);
  else
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: malformed YAML: %s", c->file, (int)mk.line + 1,
             (int)mk.column + 1, what);
  c->status = AP_ERR_ARG;
}

/* A second document in the stream is refused: a scene is one document. */
static int check_single(sc_ctx *c, yaml_parser_t *p) {
  yaml_document_t doc2;
  if (!yaml_parser_load(p, &doc2)) return yaml_error(c, p), AP_ERR_ARG;
  yaml_node_t *r2 = yaml_document_get_root_node(&doc2);
  int line = r2 ? (int)r2->start_mark.line + 1 : 0, col = r2 ? (int)r2->start_mark.column + 1 : 0;
  yaml_document_delete(&doc2);
  if (!r2) return AP_OK;
  snprintf(c->msg, sizeof c->msg, "%s:%d:%d: a scene is one YAML document; a second one starts "
           "here", c->file, line, col);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

sc_node *sc_tree_load(sc_ctx *c, const char *text, size_t len) {
  yaml_parser_t p;
  yaml_document_t doc;
  if (!yaml_parser_initialize(&p)) return nomem(c), NULL;
  yaml_parser_set_input_string(&p, (const unsigned char *)text, len);
  sc_node *root = NULL;
  if (!yaml_parser_load(&p, &doc)) {
    yaml_error(c, &p);
    yaml_parser_delete(&p);
    return NULL;
  }
  yaml_node_t *yr = yaml_document_get_root_node(&doc);
  if (!yr) {
    snprintf(c->msg, sizeof c->msg, "%s:1:1: the scene is empty", c->file);
    c->status = AP_ERR_ARG;
  } else {
    tree_build tb = {c, &doc, 0};
    root = copy_node(&tb, yr, dup_str("", 0), 0);
  }
  yaml_document_delete(&doc);
  if (root && check_single(c, &p) != AP_OK) {
    sc_tree_free(root);
    root = NULL;
  }
  yaml_parser_delete(&p);
  return root;
}

/* ---- --set overrides -------------------------------------------------------------------- */

static sc_node *cli_node(sc_kind kind, const char *parent, const char *key, const char *origin) {
  sc_node *n = node_new(kind, 0, 0, child_path(parent, key, 0));
  if (n && !n->path) {
    free(n);
    return NULL;
  }
  if (n) n->origin = origin;
  return n;
}

/* Index of a sequence segment "3"; -1 if not a non-negative integer. */
static long seg_index(const char *seg) {
  if (!seg[0] || strlen(seg) > 9) return -1;
  for (const char *p = seg; *p; p++)
    if (*p < '0' || *p > '9') return -1;
  return strtol(seg, NULL, 10);
}

static int set_fail(sc_ctx *c, const char *arg, const char *fmt, const char *a, const char *b) {
  char what[512];
  snprintf(what, sizeof what, fmt, a, b);
  snprintf(c->msg, sizeof c->msg, "--set %s: %s", arg, what);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

/* Step from n into segment seg, creating a map entry when missing (a scalar when last). */
static int set_step(sc_ctx *c, const char *arg, sc_node **n, const char *seg, int last) {
  sc_node *cur = *n;
  if (cur->kind == SC_SEQ) {
    long i = seg_index(seg);
    if (i < 0 || i >= cur->n)
      return set_fail(c, arg, "%s has no entry '%s' (entries are numbered from 0)",
                      cur->path[0] ? cur->path : "the scene", seg);
    *n = cur->kids[i];
    return AP_OK;
  }
  if (cur->kind != SC_MAP)
    return set_fail(c, arg, "%s is a scalar; it has no key '%s'", cur->path, seg);
  sc_node *kid = sc_map_get(cur, seg);
  if (kid) {
    *n = kid;
    return AP_OK;
  }
  sc_node *key = cli_node(SC_SCALAR, cur->path, seg, arg);
  sc_node *val = cli_node(last ? SC_SCALAR : SC_MAP, cur->path, seg, arg);
  if (key) key->text = dup_str(seg, strlen(seg));
  if (!key || !val || !key->text || node_push(cur, key, val) != AP_OK) {
    sc_tree_free(key);
    sc_tree_free(val);
    return nomem(c);
  }
  *n = val;
  return AP_OK;
}

/* Split "a.b[2].c" into segments "a" "b" "2" "c" (in place). */
static int split_path(char *path, char **segs, int max) {
  int ns = 0;
  for (char *p = path; *p; p++)
    if (*p == '[' || *p == ']') *p = '.';
  for (char *tok = strtok(path, "."); tok; tok = strtok(NULL, "."))
    if (ns < max) segs[ns++] = tok;
    else return -1;
  return ns;
}

int sc_tree_set(sc_ctx *c, sc_node *root, const char *arg) {
  const char *eq = strchr(arg, '=');
  if (!eq || eq == arg)
    return set_fail(c, arg, "expected PATH=VALUE, e.g. bodies.disk.mass=2%s%s", "", "");
  char *path = dup_str(arg, (size_t)(eq - arg)), *segs[SC_MAX_DEPTH];
  if (!path) return nomem(c);
  int ns = split_path(path, segs, SC_MAX_DEPTH), rc = AP_OK;
  if (ns <= 0) rc = set_fail(c, arg, "the path is empty or too long%s%s", "", "");
  sc_node *n = root;
  for (int i = 0; rc == AP_OK && i < ns; i++) rc = set_step(c, arg, &n, segs[i], i == ns - 1);
  free(path);
  if (rc != AP_OK) return rc;
  if (n->kind != SC_SCALAR)
    return set_fail(c, arg, "%s is a %s, not a scalar; set its entries one by one", n->path,
                    n->kind == SC_MAP ? "mapping" : "sequence");
  char *v = dup_str(eq + 1, strlen(eq + 1));
  if (!v) return nomem(c);
  free(n->text);
  n->text = v;
  n->quoted = 0;
  n->origin = arg;
  return AP_OK;
}
