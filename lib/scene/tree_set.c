/* Scene overrides: "--set PATH=VALUE" edits the tree before it is read (docs/scenes.md,
 * "Overrides").
 *
 * PATH is a dotted key path ("bodies.disk.mass", "output.channels.1" or "channels[1]" for a
 * sequence entry). The walk follows existing nodes; where a key is missing it decides by the
 * schema of the section:
 *   - the names under bodies, joints, constraints and effects are elements the scene defines:
 *     a missing one is an error with the closest existing name ("did you mean"), never a new
 *     element;
 *   - the names under initial are joints: one that the joints section defines may be added;
 *   - every other key is a setting and is created (a mapping on the way, the value at the
 *     end), and the parser then checks it like a key written in the file, so a misspelt
 *     setting gets its "did you mean" there;
 *   - sequence entries are addressed by index and must exist.
 * VALUE replaces the node at PATH whatever it was: text starting with '[' or '{' is a YAML
 * flow sequence or mapping (bodies.disk.com=[0,0,0.1]); anything else is one scalar, taken
 * verbatim (inertia=uniform may replace a sequence). Invariant: nodes that came from --set
 * carry the argument as their origin, so messages about them name it. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static int set_fail(sc_ctx *c, const char *arg, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int set_fail(sc_ctx *c, const char *arg, const char *fmt, ...) {
  if (c->status != AP_OK) return c->status;
  char what[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  snprintf(c->msg, sizeof c->msg, "%s: --set %.200s: %s", c->file, arg, what);
  c->status = AP_ERR_ARG;
  return AP_ERR_ARG;
}

/* Sections keyed by element names, and what one element is called. */
static const char *const element_sections[][2] = {
    {"bodies", "body"}, {"joints", "joint"}, {"constraints", "constraint"}, {"effects", "effect"},
    {"parameters", "parameter"}};

static const char *element_word(const char *section) {
  for (size_t i = 0; i < sizeof element_sections / sizeof element_sections[0]; i++)
    if (strcmp(section, element_sections[i][0]) == 0) return element_sections[i][1];
  return NULL;
}

/* "did you mean 'x'?" or the list of the map's keys, into buf. */
static void name_hint(const sc_node *map, const char *word, char *buf, size_t len) {
  buf[0] = '\0';
  if (!map || map->kind != SC_MAP || map->n == 0) {
    snprintf(buf, len, "there are none");
    return;
  }
  const char **names = calloc((size_t)map->n + 1, sizeof *names);
  if (!names) return;
  for (int i = 0; i < map->n; i++) names[i] = map->keys[i]->text;
  const char *s = sc_suggest(word, names);
  if (s) {
    snprintf(buf, len, "did you mean '%s'?", s);
  } else {
    size_t used = (size_t)snprintf(buf, len, "there are ");
    for (int i = 0; i < map->n && used + 8 < len; i++)
      used += (size_t)snprintf(buf + used, len - used, "%s%s", i ? ", " : "", names[i]);
  }
  free(names);
}

/* May the missing key seg be created in map (the node at segs[0..i-1])? */
static int may_create(sc_ctx *c, const char *arg, const sc_node *root, char *const *segs, int i) {
  char hint[300];
  const char *word = i == 1 ? element_word(segs[0]) : NULL;
  const sc_node *map = sc_map_get(root, segs[0]);
  if (word) {
    name_hint(map, segs[1], hint, sizeof hint);
    return set_fail(c, arg, "%s has no %s '%s' (%s); --set changes the %s of the scene but does "
                    "not add one", segs[0], word, segs[1], hint, segs[0]);
  }
  if (i == 1 && strcmp(segs[0], "initial") == 0) {
    const sc_node *joints = sc_map_get(root, "joints");
    if (sc_map_get(joints, segs[1])) return AP_OK;
    name_hint(joints, segs[1], hint, sizeof hint);
    return set_fail(c, arg, "there is no joint '%s' (%s); the entries of initial are joints",
                    segs[1], hint);
  }
  return AP_OK;
}

/* Index of a sequence segment "3"; -1 if not a non-negative integer. */
static long seg_index(const char *seg) {
  if (!seg[0] || strlen(seg) > 9) return -1;
  for (const char *p = seg; *p; p++)
    if (*p < '0' || *p > '9') return -1;
  return strtol(seg, NULL, 10);
}

/* Add the key seg to map with an empty value (a scalar when last, else a mapping). */
static sc_node **add_key(sc_ctx *c, const char *arg, sc_node *map, const char *seg, int last) {
  sc_node *key = sc_node_new(SC_SCALAR, 0, 0, sc_child_path(map->path, seg, 0));
  sc_node *val = sc_node_new(last ? SC_SCALAR : SC_MAP, 0, 0, sc_child_path(map->path, seg, 0));
  if (key) key->text = sc_strdup_len(seg, strlen(seg)), key->origin = arg;
  if (val) val->text = last ? sc_strdup_len("", 0) : NULL, val->origin = arg;
  if (!key || !val || !key->text || (last && !val->text) || sc_node_push(map, key, val)) {
    sc_tree_free(key);
    sc_tree_free(val);
    sc_nomem(c);
    return NULL;
  }
  return &map->kids[map->n - 1];
}

/* The slot (parent's pointer) of the node at segs, creating settings on the way. */
static sc_node **walk(sc_ctx *c, const char *arg, sc_node *root, char *const *segs, int ns) {
  sc_node **slot = NULL, *cur = root;
  for (int i = 0; i < ns; i++, cur = *slot) {
    const char *where = cur->path[0] ? cur->path : "the scene";
    if (cur->kind == SC_SEQ) {
      long k = seg_index(segs[i]);
      if (k < 0 || k >= cur->n)
        return set_fail(c, arg, "%s has no entry '%s' (it has %d, numbered from 0)", where,
                        segs[i], cur->n), NULL;
      slot = &cur->kids[k];
      continue;
    }
    if (cur->kind != SC_MAP)
      return set_fail(c, arg, "%s is a scalar; it has no key '%s'", where, segs[i]), NULL;
    int j = 0;
    while (j < cur->n && strcmp(cur->keys[j]->text, segs[i]) != 0) j++;
    if (j < cur->n) {
      slot = &cur->kids[j];
      continue;
    }
    if (seg_index(segs[i]) >= 0)
      return set_fail(c, arg, "%s has no entry '%s'; give a whole sequence instead, e.g. "
                      "%s=[...]", where, segs[i], where), NULL;
    if (may_create(c, arg, root, segs, i) != AP_OK) return NULL;
    if (!(slot = add_key(c, arg, cur, segs[i], i == ns - 1))) return NULL;
  }
  return slot;
}

/* Replace *slot by VALUE. */
static int assign(sc_ctx *c, const char *arg, sc_node **slot, const char *value) {
  sc_node *old = *slot, *n;
  const char *v = value + strspn(value, " \t");
  if (*v == '[' || *v == '{') {
    n = sc_tree_parse_value(c, value, old->path, arg);
    if (!n) return c->status;
  } else {
    n = sc_node_new(SC_SCALAR, old->line, old->col, sc_strdup_len(old->path, strlen(old->path)));
    if (!n || !(n->text = sc_strdup_len(value, strlen(value))))
      return sc_tree_free(n), sc_nomem(c);
  }
  n->origin = arg;
  sc_tree_free(old);
  *slot = n;
  return AP_OK;
}

/* Split "a.b[2].c" into segments "a" "b" "2" "c" (in place); -1 when there are too many. */
static int split_path(char *path, char **segs, int max) {
  int ns = 0;
  for (char *p = path; *p; p++)
    if (*p == '[' || *p == ']') *p = '.';
  for (char *p = path; *p;) {
    char *end = p + strcspn(p, ".");
    int more = *end != '\0';
    *end = '\0';
    if (p[0] && ns == max) return -1;
    if (p[0]) segs[ns++] = p;
    p = more ? end + 1 : end;
  }
  return ns;
}

int sc_tree_set(sc_ctx *c, sc_node *root, const char *arg) {
  const char *eq = strchr(arg, '=');
  if (!eq || eq == arg) return set_fail(c, arg, "expected PATH=VALUE, e.g. bodies.disk.mass=2");
  char *path = sc_strdup_len(arg, (size_t)(eq - arg)), *segs[SC_MAX_DEPTH];
  if (!path) return sc_nomem(c);
  int ns = split_path(path, segs, SC_MAX_DEPTH);
  sc_node **slot = NULL;
  if (ns <= 0)
    set_fail(c, arg, "the path is %s", ns == 0 ? "empty" : "deeper than the scene may nest");
  else if (root->kind != SC_MAP)
    set_fail(c, arg, "the scene is not a mapping of sections");
  else
    slot = walk(c, arg, root, segs, ns);
  free(path);
  return slot ? assign(c, arg, slot, eq + 1) : c->status;
}
