/* include: of other scene files (docs/scenes.md "Parts and include").
 *
 *   include: parts/rod_pendulum.yaml        # or a list of files
 *
 * A file name is relative to the folder of the file that includes it. The included file is
 * read whole (its own include: first, depth-first) and merged into the including tree:
 * the sections of named entries (parameters, parts, instances, bodies, joints, constraints,
 * effects, initial, events) gain its entries, a name defined in both being an error at the
 * included entry; any other section (name, simulation, output, ...) is taken from the
 * included file only when the including file does not have it. Every node read from an
 * included file carries that file's name, so messages name it with the line and column.
 * Includes nest at most SC_INCLUDE_DEPTH deep; a file that includes itself, directly or
 * through others, is refused with the chain. Also the pool of strings the tree's nodes point
 * to (file names, instance notes), freed with the scene. */
#define _XOPEN_SOURCE 700   /* realpath */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

#define SC_INCLUDE_DEPTH 8

const char *sc_strings_add(sc_strings *pool, const char *text) {
  if (pool->n == pool->cap) {
    int cap = pool->cap ? 2 * pool->cap : 8;
    char **s = realloc(pool->s, sizeof *s * (size_t)cap);
    if (!s) return NULL;
    pool->s = s, pool->cap = cap;
  }
  char *copy = sc_strdup_len(text, strlen(text));
  if (copy) pool->s[pool->n++] = copy;
  return copy;
}

void sc_strings_free(sc_strings *pool) {
  for (int i = 0; i < pool->n; i++) free(pool->s[i]);
  free(pool->s);
  memset(pool, 0, sizeof *pool);
}

static const char *const merged[] = {"parameters", "parts", "instances", "bodies", "joints",
                                     "constraints", "effects", "initial", "events", NULL};

typedef struct inc_walk {
  sc_ctx *c;
  sc_strings *pool;
  const char *stack[SC_INCLUDE_DEPTH + 1];   /* real paths of the files being read */
  const char *shown[SC_INCLUDE_DEPTH + 1];   /* their names as written */
  int depth;
} inc_walk;

static void mark_file(sc_node *n, const char *file) {
  if (!n->file) n->file = file;
  for (int i = 0; i < n->n; i++) {
    if (n->keys) mark_file(n->keys[i], file);
    mark_file(n->kids[i], file);
  }
}

/* Move entry i of src (a map) to the end of dst. */
static int move_entry(sc_node *dst, sc_node *src, int i) {
  if (sc_node_push(dst, src->keys[i], src->kids[i]) != AP_OK) return AP_ERR_NOMEM;
  src->keys[i] = src->kids[i] = NULL;
  return AP_OK;
}

static int merge_section(sc_ctx *c, sc_node *dst, sc_node *src) {
  if (sc_expect(c, src, SC_MAP) || sc_expect(c, dst, SC_MAP)) return AP_ERR_ARG;
  for (int i = 0; i < src->n; i++) {
    const sc_node *had = NULL;
    for (int j = 0; j < dst->n && !had; j++)
      if (strcmp(dst->keys[j]->text, src->keys[i]->text) == 0) had = dst->keys[j];
    if (had)
      return sc_err(c, src->keys[i], "'%s' is defined twice: here and at %s:%d:%d",
                    src->keys[i]->text, had->file ? had->file : c->file, had->line, had->col);
    if (move_entry(dst, src, i)) return sc_nomem(c);
  }
  return AP_OK;
}

static int is_merged(const char *key) {
  for (int i = 0; merged[i]; i++)
    if (strcmp(key, merged[i]) == 0) return 1;
  return 0;
}

static int merge(sc_ctx *c, sc_node *root, sc_node *inc) {
  for (int i = 0; i < inc->n; i++) {
    const char *key = inc->keys[i]->text;
    if (strcmp(key, "include") == 0) continue;
    sc_node *have = sc_map_get(root, key);
    if (have && is_merged(key)) {
      if (merge_section(c, have, inc->kids[i])) return AP_ERR_ARG;
    } else if (!have && move_entry(root, inc, i)) {
      return sc_nomem(c);
    }
  }
  return AP_OK;
}

static int expand(inc_walk *w, sc_node *root, const char *file);

/* The file named at node n, relative to the folder of `from`, into path. */
static void relative(const char *from, const char *name, char *path, size_t len) {
  const char *slash = strrchr(from, '/');
  if (name[0] == '/' || !slash) snprintf(path, len, "%s", name);
  else snprintf(path, len, "%.*s/%s", (int)(slash - from), from, name);
}

static int cycle(inc_walk *w, const sc_node *n, const char *real, const char *shown) {
  int from = 0;
  while (from < w->depth && strcmp(w->stack[from], real) != 0) from++;
  if (from == w->depth) return AP_OK;
  char buf[600];
  size_t used = 0;
  buf[0] = '\0';
  for (int k = from; k < w->depth && used + 8 < sizeof buf; k++)
    used += (size_t)snprintf(buf + used, sizeof buf - used, "%s -> ", w->shown[k]);
  snprintf(buf + used, sizeof buf - used, "%s", shown);
  return sc_err(w->c, n, "the files include each other in a cycle: %s", buf);
}

static int include_one(inc_walk *w, sc_node *root, const sc_node *n, const char *from) {
  if (sc_expect(w->c, n, SC_SCALAR)) return AP_ERR_ARG;
  char path[PATH_MAX], real[PATH_MAX], msg[1024];
  relative(from, n->text, path, sizeof path);
  if (!realpath(path, real)) snprintf(real, sizeof real, "%s", path);
  if (cycle(w, n, real, path)) return AP_ERR_ARG;
  if (w->depth >= SC_INCLUDE_DEPTH)
    return sc_err(w->c, n, "includes nest deeper than %d files (at '%s')", SC_INCLUDE_DEPTH,
                  path);
  const char *file = sc_strings_add(w->pool, path), *keep = sc_strings_add(w->pool, real);
  if (!file || !keep) return sc_nomem(w->c);
  char *text = NULL;
  size_t len = 0;
  int rc = ap_scene_read(path, &text, &len, msg, sizeof msg);
  if (rc != AP_OK) return sc_err(w->c, n, "cannot include: %s", msg);
  sc_ctx sub = {file, "", AP_OK};
  sc_node *inc = sc_tree_load(&sub, text, len);
  free(text);
  if (!inc) {
    snprintf(w->c->msg, sizeof w->c->msg, "%s (included at %s:%d:%d)", sub.msg,
             n->file ? n->file : w->c->file, n->line, n->col);
    return w->c->status = sub.status;
  }
  mark_file(inc, file);
  if (inc->kind != SC_MAP) rc = sc_err(w->c, inc, "an included file is a mapping of sections");
  w->stack[w->depth] = keep, w->shown[w->depth++] = file;
  if (rc == AP_OK) rc = expand(w, inc, file);
  w->depth--;
  if (rc == AP_OK) rc = merge(w->c, root, inc);
  sc_tree_free(inc);
  return rc;
}

static int expand(inc_walk *w, sc_node *root, const char *file) {
  const sc_node *n = sc_map_get(root, "include");
  if (!n) return AP_OK;
  if (n->kind != SC_SEQ) return include_one(w, root, n, file);
  for (int i = 0; i < n->n; i++)
    if (include_one(w, root, n->kids[i], file)) return AP_ERR_ARG;
  return AP_OK;
}

int sc_include_expand(sc_ctx *c, sc_node *root, const char *file, sc_strings *pool) {
  if (!root || root->kind != SC_MAP) return AP_OK;
  inc_walk w = {.c = c, .pool = pool};
  char real[PATH_MAX];
  const char *keep = sc_strings_add(pool, realpath(file, real) ? real : file);
  if (!keep) return sc_nomem(c);
  w.stack[0] = keep, w.shown[0] = file, w.depth = 1;
  return expand(&w, root, file);
}
