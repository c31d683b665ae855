/* The linearize: section of a scene (docs/linearize.md "Scene section").
 *
 *   linearize:
 *     about: steady | equilibrium        # default steady
 *     initial: {JOINT: {KEY: VALUE}}     # overrides of initial: for the operating point guess
 *     speed: {JOINT: {RATE: COEF}}       # initial rates proportional to the speed parameter
 *     free: [NAME, ...]                  # state variables the Newton may move
 *     independent: [NAME, ...]           # preferred independent coordinates / speeds
 *     inputs: [SPEED, ...]               # model speeds receiving an input generalized force
 *     states: [NAME, ...]                # the subsystem to report (default: non-cyclic)
 *     drop_cyclic: true                  # report without the cyclic coordinates (default)
 *     sweep: {from: 0, to: 10, count: 101}
 *
 * At load the structure is checked with the section's locations (keys, kinds, joint names, the
 * joints' initial: keys, numbers): state names need the linearizer's chart and are checked by
 * it. ap_scene_get_linearize turns the section into
 * override strings and name lists. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static const char *const lin_keys[] = {"about", "initial", "speed", "free", "independent",
                                       "inputs", "states", "drop_cyclic", "sweep", NULL};
static const char *const sweep_keys[] = {"from", "to", "count", NULL};
static const char *const abouts[] = {"steady", "equilibrium", NULL};   /* ap_lin_about */

/* "no joint named 'x' (did you mean 'y'?)" at the key node. */
static int no_joint(sc_ctx *c, const sc_scene *s, const sc_node *key) {
  const char **names = calloc((size_t)s->nj + 1, sizeof *names);
  for (int k = 0; names && k < s->nj; k++) names[k] = s->joints[k].name;
  const char *sug = names ? sc_suggest(key->text, names) : NULL;
  sc_err(c, key, "no joint named '%s'%s%s%s", key->text, sug ? " (did you mean '" : "",
         sug ? sug : "", sug ? "'?)" : "");
  free(names);
  return AP_ERR_ARG;
}

/* A key of initial: that gives a speed: rate, vx vy vz, omega, omega_body, *_rate. */
static int is_rate_key(const char *k) {
  size_t n = strlen(k);
  return strcmp(k, "rate") == 0 || (n == 2 && k[0] == 'v') || strcmp(k, "omega") == 0 ||
         strcmp(k, "omega_body") == 0 || (n > 5 && strcmp(k + n - 5, "_rate") == 0);
}

/* speed: gives rates only (its values are rates per unit of the speed parameter). */
static int check_rates(sc_ctx *c, const sc_node *m) {
  for (int j = 0; j < m->n; j++)
    if (!is_rate_key(m->keys[j]->text))
      return sc_err(c, m->keys[j], "'%s' is a coordinate; speed: gives the initial rates "
                    "proportional to the speed parameter (rate, vx, heading_rate, omega, ...)",
                    m->keys[j]->text);
  return AP_OK;
}

/* JOINT: {KEY: value} maps: joints exist, keys are the joint's initial: keys (for speed:, its
 * rates), no driven coordinate is given, values are numbers (or sequences of numbers), all
 * checked here with the section's own locations (the guess applies them later as overrides of
 * initial:, whose messages would point at a --set the user never gave). */
static int check_joint_map(sc_ctx *c, const sc_scene *s, const sc_node *n, int rates) {
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  for (int i = 0; i < n->n; i++) {
    int jt = sc_find_joint(s, n->keys[i]->text);
    if (jt < 0) return no_joint(c, s, n->keys[i]);
    const sc_node *m = n->kids[i];
    if (sc_check_keys(c, m, sc_init_keys(s->joints[jt].def.kind)) ||
        sc_check_driven(c, m, &s->joints[jt]) || (rates && check_rates(c, m)))
      return AP_ERR_ARG;
    for (int j = 0; j < m->n; j++) {
      const sc_node *v = m->kids[j];
      double x;
      if (v->kind == SC_MAP) return sc_err(c, v, "expected a value, got a mapping");
      if (v->kind == SC_SCALAR && sc_number(c, v, &x)) return AP_ERR_ARG;
      for (int e = 0; v->kind == SC_SEQ && e < v->n; e++)
        if (sc_expect(c, v->kids[e], SC_SCALAR) || sc_number(c, v->kids[e], &x))
          return AP_ERR_ARG;
    }
  }
  return AP_OK;
}

static int check_names(sc_ctx *c, const sc_node *n) {
  if (sc_expect(c, n, SC_SEQ)) return AP_ERR_ARG;
  for (int i = 0; i < n->n; i++)
    if (sc_expect(c, n->kids[i], SC_SCALAR)) return AP_ERR_ARG;
  return AP_OK;
}

static int read_sweep(sc_ctx *c, const sc_node *n, double *from, double *to, long *count) {
  if (sc_check_keys(c, n, sweep_keys) || sc_get_number(c, n, "from", from) ||
      sc_get_number(c, n, "to", to) || sc_get_int(c, n, "count", count))
    return AP_ERR_ARG;
  if (*count < 2 || *count > 100000)
    return sc_err(c, n, "count must be between 2 and 100000 (got %ld)", *count);
  if (!(*to > *from)) return sc_err(c, n, "to (%g) must be greater than from (%g)", *to, *from);
  return AP_OK;
}

int sc_parse_linearize(sc_ctx *c, const sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "linearize");
  if (!n) return AP_OK;
  int about = 0, drop = 1;
  if (sc_check_keys(c, n, lin_keys) || sc_get_enum(c, n, "about", abouts, &about) ||
      sc_get_bool(c, n, "drop_cyclic", &drop))
    return AP_ERR_ARG;
  const sc_node *v;
  if ((v = sc_map_get(n, "initial")) && check_joint_map(c, s, v, 0)) return AP_ERR_ARG;
  if ((v = sc_map_get(n, "speed")) && check_joint_map(c, s, v, 1)) return AP_ERR_ARG;
  static const char *const lists[] = {"free", "independent", "inputs", "states"};
  for (int i = 0; i < 4; i++)
    if ((v = sc_map_get(n, lists[i])) && check_names(c, v)) return AP_ERR_ARG;
  double from = 0, to = 0;
  long count = 0;
  if ((v = sc_map_get(n, "sweep")) && read_sweep(c, v, &from, &to, &count)) return AP_ERR_ARG;
  return AP_OK;
}

/* ---- the public reader ------------------------------------------------------------------- */

static char **name_list(const sc_node *n) {
  if (!n) return NULL;
  char **out = calloc((size_t)n->n + 1, sizeof *out);
  for (int i = 0; out && i < n->n; i++)
    if (!(out[i] = strdup(n->kids[i]->text))) {
      while (i > 0) free(out[--i]);
      free(out);
      return NULL;
    }
  return out;
}

static void free_list(char **l) {
  for (int i = 0; l && l[i]; i++) free(l[i]);
  free(l);
}

/* Every entry of a map JOINT: {KEY: VALUE or [VALUES]} as its path "initial.J.K" (".e" added
 * per entry of a sequence, e.g. omega: [0, 0, 1]) and its value node, passed to f (counted
 * only, when f is NULL). *count: the entries; the first status of f that is not AP_OK. */
typedef int (*entry_fn)(const char *path, const sc_node *value, void *user);

static int each_entry(const sc_node *n, entry_fn f, void *user, int *count) {
  *count = 0;
  for (int i = 0; n && i < n->n; i++) {
    const sc_node *m = n->kids[i];
    for (int j = 0; j < m->n; j++) {
      const sc_node *v = m->kids[j];
      int seq = v->kind == SC_SEQ, ne = seq ? v->n : 1;
      for (int e = 0; e < ne; e++, ++*count) {
        if (!f) continue;
        char idx[16] = "";
        if (seq) snprintf(idx, sizeof idx, ".%d", e);
        size_t len = strlen(n->keys[i]->text) + strlen(m->keys[j]->text) + strlen(idx) + 10;
        char *path = malloc(len);   /* the size it needs: a long key is never cut */
        if (!path) return AP_ERR_NOMEM;
        snprintf(path, len, "initial.%s.%s%s", n->keys[i]->text, m->keys[j]->text, idx);
        int rc = f(path, seq ? v->kids[e] : v, user);
        free(path);
        if (rc != AP_OK) return rc;
      }
    }
  }
  return AP_OK;
}

static int add_set(const char *path, const sc_node *value, void *user) {
  ap_scene_lin *out = user;
  const char *text = value->text ? value->text : "(null)";
  size_t len = strlen(path) + strlen(text) + 2;
  char *buf = malloc(len);   /* the size it needs: a long value is never cut */
  if (!buf) return AP_ERR_NOMEM;
  snprintf(buf, len, "%s=%s", path, text);
  out->sets[out->nsets++] = buf;
  return AP_OK;
}

/* "initial.J.K=V" for every entry of the section's initial: map (overrides of the guess). */
static int override_sets(const sc_node *n, ap_scene_lin *out) {
  int count;
  each_entry(n, NULL, NULL, &count);
  out->sets = calloc((size_t)count + 1, sizeof *out->sets);
  return out->sets ? each_entry(n, add_set, out, &count) : AP_ERR_NOMEM;
}

typedef struct speed_job {
  sc_ctx *c;
  ap_scene_lin *out;
} speed_job;

static int add_speed(const char *path, const sc_node *value, void *user) {
  speed_job *j = user;
  ap_scene_lin *out = j->out;
  if (sc_number(j->c, value, &out->speed_coef[out->nspeed])) return AP_ERR_ARG;
  return (out->speed_keys[out->nspeed++] = strdup(path)) ? AP_OK : AP_ERR_NOMEM;
}

/* "initial.J.K" and its coefficient for every entry of the section's speed: map. */
static int speed_keys(sc_ctx *c, const sc_node *n, ap_scene_lin *out) {
  int count;
  each_entry(n, NULL, NULL, &count);
  out->speed_keys = calloc((size_t)count + 1, sizeof *out->speed_keys);
  out->speed_coef = calloc((size_t)count + 1, sizeof *out->speed_coef);
  if (!out->speed_keys || !out->speed_coef) return AP_ERR_NOMEM;
  speed_job job = {c, out};
  return each_entry(n, add_speed, &job, &count);
}

int ap_scene_get_linearize(const ap_scene *sc, ap_scene_lin *out, char *msg, size_t msg_len) {
  if (!out) return AP_ERR_ARG;
  memset(out, 0, sizeof *out);
  out->drop_cyclic = 1;
  const sc_scene *s = sc_scene_parsed(sc);
  if (!s) return AP_ERR_ARG;
  const sc_node *n = sc_map_get(s->root, "linearize"), *in = sc_map_get(s->root, "inputs");
  if (!n) return in && !(out->inputs = name_list(in)) ? AP_ERR_NOMEM : AP_OK;   /* B = theirs */
  sc_ctx c = {s->file, "", AP_OK};
  int about = 0, rc = AP_OK;
  long count = 0;
  out->present = 1;
  sc_get_enum(&c, n, "about", abouts, &about);
  sc_get_bool(&c, n, "drop_cyclic", &out->drop_cyclic);
  out->about = about ? AP_LIN_EQUILIBRIUM : AP_LIN_STEADY;
  const sc_node *sw = sc_map_get(n, "sweep");
  if (sw) read_sweep(&c, sw, &out->sweep_from, &out->sweep_to, &count);
  out->sweep_count = (int)count;
  rc = override_sets(sc_map_get(n, "initial"), out);
  if (rc == AP_OK) rc = speed_keys(&c, sc_map_get(n, "speed"), out);
  static const char *const lists[] = {"free", "independent", "inputs", "states"};
  char ***dst[] = {&out->free, &out->independent, &out->inputs, &out->states};
  for (int i = 0; rc == AP_OK && i < 4; i++) {
    const sc_node *l = sc_map_get(n, lists[i]);
    if (!l && i == 2) l = sc_map_get(s->root, "inputs");   /* the scene's inputs: (B = theirs) */
    if (l && !(*dst[i] = name_list(l))) rc = AP_ERR_NOMEM;
  }
  if (rc == AP_OK && c.status != AP_OK) rc = c.status;   /* checked at load: cannot happen */
  if (rc != AP_OK) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s", c.msg[0] ? c.msg : "out of memory");
    ap_scene_lin_free(out);
  }
  return rc;
}

void ap_scene_lin_free(ap_scene_lin *l) {
  if (!l) return;
  for (int i = 0; i < l->nsets; i++) free(l->sets[i]);
  free(l->sets);
  for (int i = 0; i < l->nspeed; i++) free(l->speed_keys[i]);
  free(l->speed_keys);
  free(l->speed_coef);
  free_list(l->free), free_list(l->independent), free_list(l->inputs), free_list(l->states);
  memset(l, 0, sizeof *l);
}

int sc_lin_entry_at(const ap_scene *sc, const char *list, int i, char *buf, size_t len) {
  const sc_scene *s = sc_scene_parsed(sc);
  const sc_node *l = s ? sc_map_get(sc_map_get(s->root, "linearize"), list) : NULL;
  if (!l || l->kind != SC_SEQ || i < 0 || i >= l->n) return 0;
  const sc_node *e = l->kids[i];
  if (e->line > 0)
    snprintf(buf, len, "%s:%d:%d: %s", s->file, e->line, e->col, e->path);
  else
    snprintf(buf, len, "%s: --set %s: %s", s->file, e->origin ? e->origin : "?", e->path);
  return 1;
}
