/* Scene tree: YAML text -> an sc_node tree that keeps the line and column of every node and
 * its key path. (The --set overrides that edit the tree are in tree_set.c.)
 *
 * The tree is built from libyaml's event stream, not from its document loader: the loader
 * holds every node of the file (1.4 GB for a 16 MiB flow sequence) before we see the first
 * one, while events let each node be counted as it is made. Aliases are expanded by copying
 * the anchored node, and every node made, read or copied, is charged against the limits:
 * SC_MAX_NODES nodes, SC_MAX_BYTES bytes (the node, its key path, its text and its share of
 * the child arrays) and SC_MAX_DEPTH levels. So an alias bomb, a long key above a wide alias
 * tree or deep nesting is refused with a located message while it is read, and the memory of
 * a load stays below SC_MAX_BYTES plus libyaml's parser state (a few times the longest token).
 *
 * Layout: a node is a scalar (text), a sequence (kids) or a mapping (keys[i] -> kids[i]; keys
 * are scalar nodes so that an unknown key can be reported where it is written). Duplicate keys
 * are found with a hash set per mapping under construction, and anchors are found by a hash
 * of their names: both are linear in the size of the input. Invariant: every node owns its
 * children; paths are "a.b[2].c" (sequence items in brackets); a key's path is its value's. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

#include "scene/scene_int.h"

/* ---- strings and nodes -------------------------------------------------------------------- */

char *sc_strdup_len(const char *s, size_t len) {
  char *p = malloc(len + 1);
  if (!p) return NULL;
  memcpy(p, s, len);
  p[len] = '\0';
  return p;
}

char *sc_child_path(const char *parent, const char *key, int index) {
  size_t len = strlen(parent) + (key ? strlen(key) : 24) + 4;
  char *p = malloc(len);
  if (!p) return NULL;
  if (key)
    snprintf(p, len, "%s%s%s", parent, parent[0] ? "." : "", key);
  else
    snprintf(p, len, "%s[%d]", parent, index);
  return p;
}

sc_node *sc_node_new(sc_kind kind, int line, int col, char *path) {
  if (!path) return NULL;
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

int sc_node_push(sc_node *n, sc_node *key, sc_node *kid) {
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

int sc_nomem(sc_ctx *c) {
  if (c->status != AP_OK) return c->status;
  snprintf(c->msg, sizeof c->msg, "%s: out of memory", c->file);
  c->status = AP_ERR_NOMEM;
  return AP_ERR_NOMEM;
}

/* ---- a hash set of strings (string -> int), open addressing ---------------------------------- */

typedef struct str_hash {
  const char **key;        /* (cap) NULL = empty slot; keys point into nodes or events */
  int *val;                /* (cap) */
  size_t cap, n;           /* cap is 0 or a power of two; n <= cap / 2 */
  uint64_t seed;           /* per load, so that colliding keys cannot be prepared */
  long *compares;          /* string comparisons made (sc_ctx.key_compares) */
} str_hash;

static uint64_t hash_of(const str_hash *h, const char *s) {
  uint64_t x = 1469598103934665603ull ^ h->seed;   /* FNV-1a, then a 64-bit finalizer */
  for (; *s; s++) x = (x ^ (unsigned char)*s) * 1099511628211ull;
  x ^= x >> 33, x *= 0xff51afd7ed558ccdull, x ^= x >> 33, x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

/* The slot of s, or of the empty slot where it would go. Needs cap > 0. */
static size_t hash_slot(const str_hash *h, const char *s) {
  size_t i = (size_t)hash_of(h, s) & (h->cap - 1);
  while (h->key[i]) {
    ++*h->compares;
    if (strcmp(h->key[i], s) == 0) break;
    i = (i + 1) & (h->cap - 1);
  }
  return i;
}

static int hash_get(const str_hash *h, const char *s) {
  if (!h->cap) return -1;
  size_t i = hash_slot(h, s);
  return h->key[i] ? h->val[i] : -1;
}

static int hash_grow(str_hash *h) {
  str_hash g = *h;
  g.cap = h->cap ? 2 * h->cap : 16, g.n = 0;
  g.key = calloc(g.cap, sizeof *g.key);
  g.val = malloc(g.cap * sizeof *g.val);
  if (!g.key || !g.val) return free(g.key), free(g.val), AP_ERR_NOMEM;
  for (size_t i = 0; i < h->cap; i++)
    if (h->key[i]) {
      size_t j = (size_t)hash_of(&g, h->key[i]) & (g.cap - 1);
      while (g.key[j]) j = (j + 1) & (g.cap - 1);
      g.key[j] = h->key[i], g.val[j] = h->val[i], g.n++;
    }
  free(h->key);
  free(h->val);
  *h = g;
  return AP_OK;
}

/* Insert or replace s -> v (s must outlive the set). */
static int hash_put(str_hash *h, const char *s, int v) {
  if (2 * (h->n + 1) > h->cap && hash_grow(h) != AP_OK) return AP_ERR_NOMEM;
  size_t i = hash_slot(h, s);
  if (!h->key[i]) h->key[i] = s, h->n++;
  h->val[i] = v;
  return AP_OK;
}

static void hash_free(str_hash *h) {
  free(h->key);
  free(h->val);
  h->key = NULL, h->val = NULL, h->cap = h->n = 0;
}

/* ---- building from events ------------------------------------------------------------------ */

typedef struct anchor {
  char *name;
  sc_node *node;           /* the anchored node (owned by the tree) */
  int open;                /* its collection is still being read: an alias to it recurses */
} anchor;

typedef struct tree_build {
  sc_ctx *c;
  yaml_parser_t *p;
  const char *origin;      /* a --set value: nodes get line 0 and this origin */
  long nodes;
  size_t bytes;
  anchor *anchors;
  int nanchors, capanchors;
  str_hash anchor_index;   /* name -> index into anchors */
  long *compares;          /* string comparisons of the hash lookups */
} tree_build;

static int yaml_error(sc_ctx *c, const yaml_parser_t *p, const char *origin) {
  if (c->status != AP_OK) return c->status;
  if (p->error == YAML_MEMORY_ERROR) return sc_nomem(c);
  const char *what = p->problem ? p->problem : "malformed YAML";
  yaml_mark_t mk = p->problem_mark;
  if (origin)
    snprintf(c->msg, sizeof c->msg, "%s: --set %s: the value is not valid YAML: %s (column %d)",
             c->file, origin, what, (int)mk.column + 1);
  else if (p->context)
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: malformed YAML: %s %s (line %d)", c->file,
             (int)mk.line + 1, (int)mk.column + 1, what, p->context, (int)p->context_mark.line + 1);
  else
    snprintf(c->msg, sizeof c->msg, "%s:%d:%d: malformed YAML: %s", c->file, (int)mk.line + 1,
             (int)mk.column + 1, what);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

static int next_event(tree_build *tb, yaml_event_t *ev) {
  if (yaml_parser_parse(tb->p, ev)) return AP_OK;
  memset(ev, 0, sizeof *ev);
  return yaml_error(tb->c, tb->p, tb->origin);
}

/* An error at a position that has no node yet (takes nothing). */
static int err_at(tree_build *tb, int line, int col, const char *path, const char *what) {
  sc_node tmp = {.line = tb->origin ? 0 : line, .col = col, .path = (char *)path,
                 .origin = tb->origin};
  return sc_err(tb->c, &tmp, "%s", what);
}

/* Charge one node at depth (text: the bytes of its text) against the limits: the node, its
 * path, its text and its slot in its parent's arrays. */
static int charge(tree_build *tb, int line, int col, const char *path, int depth, size_t text) {
  char what[200];
  tb->bytes += text + sizeof(sc_node) + 2 * sizeof(sc_node *) + strlen(path) + 1;
  if (depth > SC_MAX_DEPTH)
    snprintf(what, sizeof what, "nested more than %d levels deep", SC_MAX_DEPTH);
  else if (++tb->nodes > SC_MAX_NODES)
    snprintf(what, sizeof what, "more than %d nodes (aliases count each time they are used: "
             "an alias bomb?)", SC_MAX_NODES);
  else if (tb->bytes > SC_MAX_BYTES)
    snprintf(what, sizeof what, "the scene grows past %d MiB as it is read (aliases are copied "
             "where they are used, with their key paths: an alias bomb, or a very long key?)",
             (int)(SC_MAX_BYTES >> 20));
  else
    return AP_OK;
  return err_at(tb, line, col, path, what);
}

static sc_node *build(tree_build *tb, yaml_event_t *ev, char *path, int depth);

/* Record an anchor for n; *index = its entry (or -1 without a name). */
static int add_anchor(tree_build *tb, const yaml_char_t *name, sc_node *n, int open, int *index) {
  *index = -1;
  if (!name) return AP_OK;
  if (tb->nanchors == tb->capanchors) {
    int cap = tb->capanchors ? 2 * tb->capanchors : 16;
    anchor *a = realloc(tb->anchors, sizeof *a * (size_t)cap);
    if (!a) return sc_nomem(tb->c);
    tb->anchors = a, tb->capanchors = cap;
  }
  anchor *a = &tb->anchors[tb->nanchors];
  a->name = sc_strdup_len((const char *)name, strlen((const char *)name));
  if (!a->name) return sc_nomem(tb->c);
  a->node = n, a->open = open;
  if (hash_put(&tb->anchor_index, a->name, tb->nanchors) != AP_OK) {
    free(a->name);
    return sc_nomem(tb->c);
  }
  *index = tb->nanchors++;
  tb->bytes += strlen(a->name) + 1 + sizeof *a;
  return AP_OK;
}

/* Copy an anchored node to path (takes path). */
static sc_node *copy_tree(tree_build *tb, const sc_node *src, char *path, int depth) {
  if (!path) return sc_nomem(tb->c), NULL;
  size_t text = src->text ? strlen(src->text) + 1 : 0;
  if (charge(tb, src->line, src->col, path, depth, text)) return free(path), NULL;
  sc_node *n = sc_node_new(src->kind, tb->origin ? 0 : src->line, src->col, path);
  if (!n) return sc_nomem(tb->c), NULL;
  n->quoted = src->quoted, n->origin = tb->origin;
  if (src->text && !(n->text = sc_strdup_len(src->text, text - 1)))
    return sc_tree_free(n), sc_nomem(tb->c), NULL;
  int map = src->kind == SC_MAP;
  for (int i = 0; i < src->n; i++) {
    const char *name = map ? src->keys[i]->text : NULL;
    sc_node *key = map ? copy_tree(tb, src->keys[i], sc_child_path(n->path, name, 0), depth + 1)
                       : NULL;
    if (map && !key) return sc_tree_free(n), NULL;
    sc_node *kid = copy_tree(tb, src->kids[i], sc_child_path(n->path, name, i), depth + 1);
    if (!kid) return sc_tree_free(key), sc_tree_free(n), NULL;
    if (sc_node_push(n, key, kid) != AP_OK)
      return sc_tree_free(key), sc_tree_free(kid), sc_tree_free(n), sc_nomem(tb->c), NULL;
  }
  return n;
}

static sc_node *alias(tree_build *tb, const yaml_event_t *ev, char *path, int depth) {
  const char *name = (const char *)ev->data.alias.anchor;
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1, i;
  char what[256];
  if ((i = hash_get(&tb->anchor_index, name)) < 0)
    snprintf(what, sizeof what, "unknown alias '*%.60s' (no anchor '&%.60s' before it)", name,
             name);
  else if (tb->anchors[i].open)
    snprintf(what, sizeof what, "the alias '*%.60s' is inside the node it refers to (a "
             "recursive alias)", name);
  else
    return copy_tree(tb, tb->anchors[i].node, path, depth);
  err_at(tb, line, col, path, what);
  free(path);
  return NULL;
}

static sc_node *scalar(tree_build *tb, const yaml_event_t *ev, char *path, int depth) {
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1;
  const char *v = (const char *)ev->data.scalar.value;
  size_t len = ev->data.scalar.length;
  if (charge(tb, line, col, path, depth, len + 1)) return free(path), NULL;
  sc_node *n = sc_node_new(SC_SCALAR, tb->origin ? 0 : line, col, path);
  if (!n) return sc_nomem(tb->c), NULL;
  n->origin = tb->origin;
  if (memchr(v, '\0', len)) {
    sc_err(tb->c, n, "the value contains a NUL character");
    return sc_tree_free(n), NULL;
  }
  if (!(n->text = sc_strdup_len(v, len))) return sc_tree_free(n), sc_nomem(tb->c), NULL;
  n->quoted = ev->data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
              ev->data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE;
  int index;
  if (add_anchor(tb, ev->data.scalar.anchor, n, 0, &index)) return sc_tree_free(n), NULL;
  return n;
}

/* The path of a key event's value: parent.key (an alias key must name a scalar). */
static char *key_path(tree_build *tb, const sc_node *map, const yaml_event_t *ev) {
  const char *text = NULL;
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1;
  if (ev->type == YAML_SCALAR_EVENT) text = (const char *)ev->data.scalar.value;
  if (ev->type == YAML_ALIAS_EVENT) {
    int i = hash_get(&tb->anchor_index, (const char *)ev->data.alias.anchor);
    if (i < 0 || tb->anchors[i].open) return sc_strdup_len(map->path, strlen(map->path));
    if (tb->anchors[i].node->kind == SC_SCALAR) text = tb->anchors[i].node->text;
  }
  if (!text) {
    err_at(tb, line, col, map->path, ev->type == YAML_MAPPING_START_EVENT
           ? "a mapping key must be a plain name, not a mapping"
           : "a mapping key must be a plain name, not a sequence");
    return NULL;
  }
  char *p = sc_child_path(map->path, text, 0);
  if (!p) sc_nomem(tb->c);
  return p;
}

/* One key and its value; *done when the mapping ended. */
static int map_entry(tree_build *tb, sc_node *n, str_hash *seen, int depth, int *done) {
  yaml_event_t ev;
  if (next_event(tb, &ev)) return tb->c->status;
  if (ev.type == YAML_MAPPING_END_EVENT) return yaml_event_delete(&ev), *done = 1, AP_OK;
  char *kp = key_path(tb, n, &ev);
  sc_node *key = kp ? build(tb, &ev, kp, depth + 1) : (yaml_event_delete(&ev), NULL);
  if (!key) return tb->c->status;
  if (key->kind != SC_SCALAR) {
    sc_err(tb->c, key, "a mapping key must be a plain name, not a %s",
           key->kind == SC_MAP ? "mapping" : "sequence");
    return sc_tree_free(key), AP_ERR_ARG;
  }
  int first = hash_get(seen, key->text);
  if (first >= 0) {
    sc_err(tb->c, key, "duplicate key '%s' (first at line %d)", key->text, n->keys[first]->line);
    return sc_tree_free(key), AP_ERR_ARG;
  }
  if (hash_put(seen, key->text, n->n) != AP_OK) return sc_tree_free(key), sc_nomem(tb->c);
  char *vp = sc_child_path(n->path, key->text, 0);
  if (!vp) return sc_tree_free(key), sc_nomem(tb->c);
  if (next_event(tb, &ev)) return free(vp), sc_tree_free(key), tb->c->status;
  sc_node *val = build(tb, &ev, vp, depth + 1);
  if (!val) return sc_tree_free(key), tb->c->status;
  if (sc_node_push(n, key, val) != AP_OK)
    return sc_tree_free(key), sc_tree_free(val), sc_nomem(tb->c);
  return AP_OK;
}

static int read_map(tree_build *tb, sc_node *n, int depth) {
  str_hash seen = {.seed = tb->anchor_index.seed, .compares = tb->compares};
  int rc = AP_OK;
  for (int done = 0; rc == AP_OK && !done;) rc = map_entry(tb, n, &seen, depth, &done);
  hash_free(&seen);
  return rc;
}

static int read_seq(tree_build *tb, sc_node *n, int depth) {
  for (;;) {
    yaml_event_t ev;
    if (next_event(tb, &ev)) return tb->c->status;
    if (ev.type == YAML_SEQUENCE_END_EVENT) return yaml_event_delete(&ev), AP_OK;
    char *p = sc_child_path(n->path, NULL, n->n);
    if (!p) return yaml_event_delete(&ev), sc_nomem(tb->c);
    sc_node *kid = build(tb, &ev, p, depth + 1);
    if (!kid) return tb->c->status;
    if (sc_node_push(n, NULL, kid) != AP_OK) return sc_tree_free(kid), sc_nomem(tb->c);
  }
}

/* Build the node that starts with *ev (takes ev and path). */
static sc_node *build(tree_build *tb, yaml_event_t *ev, char *path, int depth) {
  sc_node *n = NULL;
  int line = (int)ev->start_mark.line + 1, col = (int)ev->start_mark.column + 1;
  if (ev->type == YAML_ALIAS_EVENT) n = alias(tb, ev, path, depth);
  else if (ev->type == YAML_SCALAR_EVENT) n = scalar(tb, ev, path, depth);
  if (ev->type == YAML_ALIAS_EVENT || ev->type == YAML_SCALAR_EVENT)
    return yaml_event_delete(ev), n;
  int map = ev->type == YAML_MAPPING_START_EVENT;
  if (!map && ev->type != YAML_SEQUENCE_START_EVENT) {
    err_at(tb, line, col, path, "malformed YAML: unexpected event");
    return yaml_event_delete(ev), free(path), NULL;
  }
  if (charge(tb, line, col, path, depth, 0)) return yaml_event_delete(ev), free(path), NULL;
  n = sc_node_new(map ? SC_MAP : SC_SEQ, tb->origin ? 0 : line, col, path);
  const yaml_char_t *name = map ? ev->data.mapping_start.anchor : ev->data.sequence_start.anchor;
  int index = -1;
  if (!n || add_anchor(tb, name, n, 1, &index) != AP_OK) {
    yaml_event_delete(ev);
    return sc_tree_free(n), sc_nomem(tb->c), NULL;
  }
  yaml_event_delete(ev);
  n->origin = tb->origin;
  int rc = map ? read_map(tb, n, depth) : read_seq(tb, n, depth);
  if (index >= 0) tb->anchors[index].open = 0;
  if (rc != AP_OK) return sc_tree_free(n), NULL;
  return n;
}

/* ---- documents ---------------------------------------------------------------------------- */

/* Expect an event of type (after the root: the end of the document or a second one). */
static int expect(tree_build *tb, yaml_event_type_t type, yaml_event_t *ev) {
  if (next_event(tb, ev)) return tb->c->status;
  if (ev->type == type) return AP_OK;
  if (ev->type == YAML_DOCUMENT_START_EVENT && !tb->origin) {
    yaml_event_delete(ev);
    if (next_event(tb, ev)) return tb->c->status;   /* the second document's root */
    snprintf(tb->c->msg, sizeof tb->c->msg, "%s:%d:%d: a scene is one YAML document; a second "
             "one starts here", tb->c->file, (int)ev->start_mark.line + 1,
             (int)ev->start_mark.column + 1);
  } else {
    snprintf(tb->c->msg, sizeof tb->c->msg, "%s:%d:%d: malformed YAML", tb->c->file,
             (int)ev->start_mark.line + 1, (int)ev->start_mark.column + 1);
  }
  yaml_event_delete(ev);
  tb->c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

static sc_node *load(tree_build *tb, const char *path) {
  yaml_event_t ev;
  sc_node *root = NULL;
  if (expect(tb, YAML_STREAM_START_EVENT, &ev)) return NULL;
  yaml_event_delete(&ev);
  if (next_event(tb, &ev)) return NULL;
  if (ev.type != YAML_DOCUMENT_START_EVENT) {   /* the stream ended: nothing in it */
    yaml_event_delete(&ev);
    err_at(tb, 1, 1, "", tb->origin ? "the value is empty" : "the scene is empty");
    return NULL;
  }
  yaml_event_delete(&ev);
  if (next_event(tb, &ev)) return NULL;
  char *p = sc_strdup_len(path, strlen(path));
  if (!p) return yaml_event_delete(&ev), sc_nomem(tb->c), NULL;
  root = build(tb, &ev, p, 0);
  if (root && !expect(tb, YAML_DOCUMENT_END_EVENT, &ev)) yaml_event_delete(&ev);
  if (root && tb->c->status == AP_OK && !expect(tb, YAML_STREAM_END_EVENT, &ev))
    yaml_event_delete(&ev);
  if (tb->c->status != AP_OK) sc_tree_free(root), root = NULL;
  return root;
}

/* Parse text as one YAML document; origin != NULL for a --set value. */
static sc_node *parse(sc_ctx *c, const char *text, size_t len, const char *path,
                      const char *origin, long *compares) {
  yaml_parser_t p;
  if (!yaml_parser_initialize(&p)) return sc_nomem(c), NULL;
  yaml_parser_set_input_string(&p, (const unsigned char *)text, len);
  long ignored = 0;
  tree_build tb = {c, &p, origin, 0, 0, NULL, 0, 0, {0}, compares ? compares : &ignored};
  tb.anchor_index.seed = (uint64_t)(uintptr_t)&tb * 0x9e3779b97f4a7c15ull ^ (uint64_t)len;
  tb.anchor_index.compares = tb.compares;
  sc_node *root = load(&tb, path);
  for (int i = 0; i < tb.nanchors; i++) free(tb.anchors[i].name);
  free(tb.anchors);
  hash_free(&tb.anchor_index);
  yaml_parser_delete(&p);
  return root;
}

sc_node *sc_tree_load(sc_ctx *c, const char *text, size_t len) {
  return parse(c, text, len, "", NULL, NULL);
}

sc_node *sc_tree_load_counted(sc_ctx *c, const char *text, size_t len, long *compares) {
  return parse(c, text, len, "", NULL, compares);
}

sc_node *sc_tree_parse_value(sc_ctx *c, const char *text, const char *path, const char *origin) {
  return parse(c, text, strlen(text), path, origin, NULL);
}
