/* Named output channels (docs/scenes.md "output"): `output.channels` entries that are mappings,
 * NAME: EXPRESSION, each a CSV column NAME whose value is the expression of t and the state
 * (the names of "Expressions of the state", body quantities included) at every row:
 *
 *   output:
 *     channels: [coordinates, {lean: "rear_frame.roll - pi/2", speed: "hypot(rear.vx, rear.vy)"}]
 *
 * Each is compiled when the scene is read, against the state names table (state.c,
 * expr_body.c) and then, like an effect's value, against the names it reads (sc_bind_state):
 * its inputs. A row evaluates it from the row's (t, q, v), and from the kinematics at that
 * state (ap_body_eval into the output data) when it reads a body quantity. Also here: the
 * columns of the `driven` channel, the driven coordinates' functions of t (JOINT.angle ...).
 * Invariant: nothing is written after the scene is read. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

typedef struct sc_named {
  char *name;
  sc_expr e;
  int nin;
  ap_state_input in[AP_STATE_MAX_INPUTS];
} sc_named;

void sc_named_free(sc_scene *s) {
  for (int i = 0; i < s->nnamed; i++) {
    free(s->named[i].name);
    sc_expr_free(&s->named[i].e);
  }
  free(s->named);
  s->named = NULL, s->nnamed = 0;
}

/* A column name: letters, digits, '_', '-' and '.', starting with a letter or '_'. */
static int valid(const char *name) {
  if (!(isalpha((unsigned char)name[0]) || name[0] == '_')) return 0;
  for (const char *p = name; *p; p++)
    if (!(isalnum((unsigned char)*p) || *p == '_' || *p == '-' || *p == '.')) return 0;
  return 1;
}

static int read_one(sc_ctx *c, sc_scene *s, const sc_node *key, const sc_node *v,
                    const sc_state_names *t, sc_named *nc) {
  if (!valid(key->text))
    return sc_err(c, key, "'%s' is not a valid channel name (letters, digits, _, - and ., "
                  "starting with a letter or _)", key->text);
  if (strcmp(key->text, "t") == 0) return sc_err(c, key, "'t' is the time column already");
  for (int i = 0; i < s->nnamed - 1; i++)
    if (strcmp(s->named[i].name, key->text) == 0)
      return sc_err(c, key, "channel '%s' is named twice", key->text);
  nc->name = strdup(key->text);
  if (!nc->name) return sc_nomem(c);
  if (sc_expect(c, v, SC_SCALAR)) return AP_ERR_ARG;
  sc_symtab sym = {1, (const char *const *)t->names, NULL, NULL, NULL, NULL};
  int rc = sc_expr_compile_sym(c, v, v->text, &sym, &nc->e);
  if (rc == AP_OK && nc->e.timed && sc_prog_nvars(nc->e.prog) > 0)
    rc = sc_bind_state(c, v, t, &nc->e, nc->in, &nc->nin);
  return rc;
}

int sc_parse_named_channels(sc_ctx *c, sc_scene *s, const sc_node *map) {
  sc_named *more = realloc(s->named, sizeof *more * (size_t)(s->nnamed + map->n + 1));
  if (!more) return sc_nomem(c);
  s->named = more;
  sc_state_names t;
  if (sc_state_names_build(s, &t) != AP_OK) return sc_nomem(c);
  int rc = AP_OK;
  for (int i = 0; rc == AP_OK && i < map->n; i++) {
    sc_named *nc = &s->named[s->nnamed++];
    memset(nc, 0, sizeof *nc);
    rc = read_one(c, s, map->keys[i], map->kids[i], &t, nc);
  }
  sc_state_names_free(&t);
  return rc;
}

/* ---- columns ------------------------------------------------------------------------------- */

static int driven(const sc_joint *j, int i) { return i < 3 && j->def.drive[i] != NULL; }

/* The output name of drivable coordinate i of a joint kind (as the coordinates columns). */
static const char *coord_name(ap_joint_kind kind, int i) {
  static const char *const xyz[] = {"x", "y", "z"};
  switch (kind) {
    case AP_JOINT_REVOLUTE: return "angle";
    case AP_JOINT_PRISMATIC: return "pos";
    case AP_JOINT_PLANAR: return i < 2 ? xyz[i] : "heading";
    default: return xyz[i % 3];   /* free x, y, z; plane contact x, y */
  }
}

int sc_named_count(const sc_scene *s, const ap_model *m) {
  int n = s->nnamed;
  (void)m;
  for (int j = 0; (s->channels & SC_OUT_DRIVEN) && j < s->nj; j++)
    for (int i = 0; i < 3; i++) n += driven(&s->joints[j], i);
  return n;
}

const char *sc_named_column(const sc_scene *s, int i, char *buf, size_t len) {
  if (i < s->nnamed) return s->named[i].name;
  i -= s->nnamed;
  for (int j = 0; (s->channels & SC_OUT_DRIVEN) && j < s->nj; j++)
    for (int c = 0; c < 3; c++)
      if (driven(&s->joints[j], c) && i-- == 0) {
        snprintf(buf, len, "%s.%s", s->joints[j].name,
                 coord_name(s->joints[j].def.kind, c));
        return buf;
      }
  return "";
}

/* The named and driven columns at the data's (t, q, v) into row; the count written. */
int sc_named_values(const sc_scene *s, const ap_model *m, ap_data *d, double *row) {
  int c = 0, kin = 0;
  for (int i = 0; i < s->nnamed; i++) {
    const sc_named *nc = &s->named[i];
    double x[AP_STATE_MAX_INPUTS];
    int index[AP_STATE_MAX_INPUTS];
    if (!nc->e.timed) {
      row[c++] = nc->e.value;
      continue;
    }
    if (!kin && sc_inputs_read_bodies(nc->in, nc->nin)) {
      int rc = ap_body_eval(m, d);
      if (rc != AP_OK) return rc;
      kin = 1;
    }
    for (int k = 0; k < nc->nin; k++) index[k] = sc_state_index(s, m, &nc->in[k]);
    if (sc_state_gather(m, d, nc->in, index, nc->nin, d->q, d->v, x) != AP_OK)
      return AP_ERR_INTERNAL;
    sc_prog_value(nc->e.prog, d->t, x, &row[c++]);
  }
  for (int j = 0; (s->channels & SC_OUT_DRIVEN) && j < s->nj; j++)
    for (int i = 0; i < 3; i++) {
      double f[3] = {0.0, 0.0, 0.0};
      if (!driven(&s->joints[j], i)) continue;
      sc_expr_eval(&s->joints[j].drive[i], d->t, f);
      row[c++] = f[0];
    }
  return c;
}
