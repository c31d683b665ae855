/* Names of the state in scene expressions: every joint coordinate and speed as JOINT.NAME
 * (docs/scenes.md "Expressions of the state").
 *
 * The table lists, for each joint in file order, its coordinates then its speeds, each under
 * the names the scene already uses for them: the initial-state key (wheel.angle, wheel.rate,
 * sled.heading_rate) and the output column's (wheel.angle_dot, slider.pos, sled.heading_dot).
 * A joint's child body lends its name too (BODY.NAME, as in the output columns) when no joint
 * has that name. Entry i is slot i of the expression evaluator's variable vector; what it
 * reads is refs[i] (joint id, coordinate or speed, local index), or driven[i] = 1 when the
 * coordinate is driven (a function of t, not part of the state: an error to read). After the
 * joints come the bodies' quantities, BODY.x ... BODY.wz (expr_body.c).
 * Invariant: names[count] == NULL; the strings are owned by the table. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

/* Names of local coordinate i (up to two, NULL-padded), by joint kind. */
static void coord_names(ap_joint_kind kind, int i, const char *out[2]) {
  static const char *const q[] = {"qw", "qx", "qy", "qz"}, *const xyz[] = {"x", "y", "z"};
  out[0] = out[1] = NULL;
  switch (kind) {
    case AP_JOINT_REVOLUTE: out[0] = "angle"; break;
    case AP_JOINT_PRISMATIC: out[0] = "position", out[1] = "pos"; break;
    case AP_JOINT_PLANAR: out[0] = i < 2 ? xyz[i] : "heading"; break;
    case AP_JOINT_BALL: out[0] = q[i & 3]; break;
    case AP_JOINT_FREE: out[0] = i < 3 ? xyz[i] : q[(i - 3) & 3]; break;
    case AP_JOINT_PLANE_CONTACT: out[0] = i < 2 ? xyz[i] : q[(i - 2) & 3]; break;
    default: break;
  }
}

/* Names of local speed i: the initial-state name, then the output column's when different. */
static void speed_names(ap_joint_kind kind, int i, const char *out[2]) {
  static const char *const v[] = {"vx", "vy", "vz"}, *const w[] = {"wx", "wy", "wz"},
                           *const pd[] = {"x_dot", "y_dot", "heading_dot"};
  out[0] = out[1] = NULL;
  switch (kind) {
    case AP_JOINT_REVOLUTE: out[0] = "rate", out[1] = "angle_dot"; break;
    case AP_JOINT_PRISMATIC: out[0] = "rate", out[1] = "pos_dot"; break;
    case AP_JOINT_PLANAR: out[0] = i < 2 ? v[i] : "heading_rate", out[1] = pd[i % 3]; break;
    case AP_JOINT_BALL: out[0] = w[i % 3]; break;
    case AP_JOINT_FREE: out[0] = i < 3 ? v[i] : w[(i - 3) % 3]; break;
    case AP_JOINT_PLANE_CONTACT: out[0] = i < 2 ? v[i] : w[(i - 2) % 3]; break;
    default: break;
  }
}

static void counts(ap_joint_kind kind, int *nq, int *nv) {
  static const int tab[7][2] = {{7, 6}, {0, 0}, {1, 1}, {1, 1}, {3, 3}, {4, 3}, {6, 5}};
  int k = kind >= 0 && kind <= AP_JOINT_PLANE_CONTACT ? (int)kind : 1;
  *nq = tab[k][0], *nv = tab[k][1];
}

void sc_state_names_free(sc_state_names *t) {
  for (int i = 0; t->names && i < t->count; i++) free(t->names[i]);
  free(t->names);
  free(t->refs);
  free(t->driven);
  memset(t, 0, sizeof *t);
}

/* Append prefix.name for (joint, speed, index); *cap entries allocated. */
static int add(sc_state_names *t, const char *prefix, const char *name, int joint, int speed,
               int index, int driven) {
  size_t len = strlen(prefix) + strlen(name) + 2;
  char *s = malloc(len);
  if (!s) return AP_ERR_NOMEM;
  snprintf(s, len, "%s.%s", prefix, name);
  t->names[t->count] = s;
  t->refs[t->count] = (ap_state_input){joint, speed, index};
  t->driven[t->count++] = driven;
  return AP_OK;
}

/* The prefixes of joint j: its name, and its child body's when that names no joint. */
static int prefixes(const sc_scene *s, int j, const char *out[2]) {
  const char *body = s->joints[j].def.child >= 0 ? s->bodies[s->joints[j].def.child].name : NULL;
  out[0] = s->joints[j].name, out[1] = NULL;
  if (body && strcmp(body, out[0]) != 0 && sc_find_joint(s, body) < 0) out[1] = body;
  return out[1] ? 2 : 1;
}

static int add_joint(sc_state_names *t, const sc_scene *s, int j) {
  const char *pre[2], *nm[2];
  int np = prefixes(s, j, pre), nq, nv, rc = AP_OK;
  ap_joint_kind kind = s->joints[j].def.kind;
  counts(kind, &nq, &nv);
  for (int p = 0; p < np; p++)
    for (int sp = 0; sp < 2; sp++)
      for (int i = 0; i < (sp ? nv : nq); i++) {
        int driven = i < 3 && s->joints[j].def.drive[i] != NULL;
        (sp ? speed_names : coord_names)(kind, i, nm);
        for (int a = 0; a < 2 && nm[a] && rc == AP_OK; a++)
          rc = add(t, pre[p], nm[a], j, sp, i, driven);
      }
  return rc;
}

int sc_state_names_build(const sc_scene *s, sc_state_names *t) {
  memset(t, 0, sizeof *t);
  size_t cap = 1;   /* at most 2 prefixes x (7 coordinates + 6 speeds) x 2 names per joint */
  for (int j = 0; j < s->nj; j++) cap += 52;
  cap += (size_t)s->nb * AP_BODY_QTY_COUNT;   /* BODY.x ... (expr_body.c) */
  t->names = calloc(cap, sizeof *t->names);
  t->refs = calloc(cap, sizeof *t->refs);
  t->driven = calloc(cap, sizeof *t->driven);
  int rc = t->names && t->refs && t->driven ? AP_OK : AP_ERR_NOMEM;
  for (int j = 0; rc == AP_OK && j < s->nj; j++) rc = add_joint(t, s, j);
  if (rc == AP_OK) rc = sc_state_names_add_bodies(s, t);
  if (rc != AP_OK) sc_state_names_free(t);
  return rc;
}

/* ---- expressions of the state ---------------------------------------------------------------
 *
 * A value is read in two passes: compiled against the whole table (so an unknown name gets the
 * evaluator's "did you mean" from every name of the scene), then, when it reads the state,
 * compiled again against just the names it uses, in the order of their slots: its variables
 * are then exactly the inputs x of its ap_state_fn, in the order declared. */

/* ap_state_fn of a scene expression (user = the sc_expr): the value from the program, and the
 * partials from its jets: t seeded for df[0], each x_i in turn for df[1 + i]. A value that is
 * not finite is returned as such: the model reports it with the effect's name. */
int sc_state_fn(const ap_state_args *a, double *f, double *df, void *user) {
  const sc_prog *p = ((const sc_expr *)user)->prog;
  sc_prog_value(p, a->t, a->x, f);
  if (!df) return 0;
  sc_jet tj = {{a->t, 1.0, 0.0}}, x[AP_STATE_MAX_INPUTS], r;
  for (int i = 0; i < a->nx; i++) x[i] = (sc_jet){{a->x[i], 0.0, 0.0}};
  sc_prog_jet(p, &tj, x, &r);
  df[0] = r.c[1];
  tj.c[1] = 0.0;
  for (int i = 0; i < a->nx; i++) {
    x[i].c[1] = 1.0;
    sc_prog_jet(p, &tj, x, &r);
    df[1 + i] = r.c[1];
    x[i].c[1] = 0.0;
  }
  return 0;
}

/* Recompile e (which uses `count` slots `vars` of t's table) against those names alone. */
static int compact(sc_ctx *c, const sc_node *v, const sc_state_names *t, const int *vars,
                   int count, sc_expr *e) {
  const char *names[AP_STATE_MAX_INPUTS + 1] = {NULL};
  for (int i = 0; i < count; i++) names[i] = t->names[vars[i]];
  sc_symtab sym = {1, names, NULL, NULL, NULL, NULL};
  char *text = e->text;
  e->text = NULL;
  sc_expr_free(e);
  int rc = sc_expr_compile_sym(c, v, text, &sym, e);
  free(text);
  return rc;
}

int sc_bind_state(sc_ctx *c, const sc_node *v, const sc_state_names *t, sc_expr *e,
                  ap_state_input *inputs, int *ninputs) {
  int count = sc_prog_nvars(e->prog);
  const int *vars = sc_prog_vars(e->prog);
  for (int i = 0; i < count; i++)
    if (t->driven[vars[i]])
      return sc_err(c, v, "'%s' is driven: a function of t, not part of the state (write "
                    "that function of t instead)", t->names[vars[i]]);
  if (count > AP_STATE_MAX_INPUTS)
    return sc_err(c, v, "'%s' reads %d names of the state; at most %d are allowed", e->text,
                  count, AP_STATE_MAX_INPUTS);
  *ninputs = count;
  for (int i = 0; i < count; i++) inputs[i] = t->refs[vars[i]];
  int used[AP_STATE_MAX_INPUTS];
  memcpy(used, vars, (size_t)count * sizeof *used);
  return compact(c, v, t, used, count, e) ? AP_ERR_ARG : AP_OK;
}

static int bind(sc_ctx *c, const sc_node *v, const sc_state_names *t, sc_expr *e,
                ap_effect_def *d) {
  if (sc_bind_state(c, v, t, e, d->inputs, &d->ninputs)) return AP_ERR_ARG;
  d->state_fn = sc_state_fn;
  return AP_OK;
}

int sc_read_value(sc_ctx *c, sc_scene *s, const sc_node *v, sc_expr *e, ap_effect_def *d) {
  memset(e, 0, sizeof *e);
  e->node = v;
  if (sc_expect(c, v, SC_SCALAR)) return AP_ERR_ARG;
  char *end = NULL;
  double x = strtod(v->text, &end);
  if (!v->quoted && end != v->text && *end == '\0' && isfinite(x)) {
    e->value = d->value = x;
    return AP_OK;
  }
  sc_state_names t;
  if (sc_state_names_build(s, &t) != AP_OK) return sc_err(c, v, "out of memory");
  sc_symtab sym = {1, (const char *const *)t.names, NULL, NULL, NULL, NULL};
  int rc = sc_expr_compile_sym(c, v, v->text, &sym, e);
  if (rc == AP_OK && e->timed && sc_prog_nvars(e->prog) > 0) rc = bind(c, v, &t, e, d);
  else if (rc == AP_OK && e->timed) d->value_fn = sc_expr_time_fn;
  else if (rc == AP_OK) d->value = e->value;
  sc_state_names_free(&t);
  return rc;
}

/* ---- checked at the initial state ------------------------------------------------------------ */

int sc_state_index(const sc_scene *s, const ap_model *m, const ap_state_input *in) {
  if (in->speed == AP_STATE_BODY) return -1;   /* read from the kinematics (expr_body.c) */
  int first = in->speed ? ap_joint_speed_index(m, in->joint) : ap_joint_coord_index(m, in->joint);
  for (int i = 0; i < in->index && i < 3; i++) first -= s->joints[in->joint].def.drive[i] != NULL;
  return first + in->index;
}

static int check_one(sc_ctx *c, const sc_scene *s, const ap_model *m, ap_data *d, int k,
                     double t, const double *q, const double *v) {
  const ap_effect_def *e = &s->effs[k].def;
  sc_jet tj = {{t, 0.0, 0.0}}, x[AP_STATE_MAX_INPUTS];
  double xv[AP_STATE_MAX_INPUTS];
  int index[AP_STATE_MAX_INPUTS];
  for (int i = 0; i < e->ninputs; i++) index[i] = sc_state_index(s, m, &e->inputs[i]);
  if (sc_state_gather(m, d, e->inputs, index, e->ninputs, q, v, xv) != AP_OK)
    return sc_err(c, s->effs[k].value.node, "cannot evaluate the body quantities it reads");
  for (int i = 0; i < e->ninputs; i++) x[i] = (sc_jet){{xv[i], 0.0, 0.0}};
  return sc_expr_check_jet(c, &s->effs[k].value, &tj, x, 0) != AP_OK ? AP_ERR_ARG : AP_OK;
}

int sc_check_state_exprs(sc_ctx *c, const sc_scene *s, const ap_model *m, double t,
                         const double *q, const double *v) {
  ap_data *d = NULL;
  int rc = AP_OK;
  for (int k = 0; rc == AP_OK && k < s->ne; k++) {
    const ap_effect_def *e = &s->effs[k].def;
    if (e->state_fn != sc_state_fn) continue;
    if (!d && sc_inputs_read_bodies(e->inputs, e->ninputs)) {   /* their kinematics, once */
      if (ap_data_create(m, &d) != AP_OK) return sc_nomem(c);
      rc = sc_state_at(m, d, t, q, v);
      if (rc != AP_OK) rc = sc_err(c, s->effs[k].value.node, "the kinematics at t = %g fail: "
                                   "%s", t, d->msg);
    }
    if (rc == AP_OK) rc = check_one(c, s, m, d, k, t, q, v);
  }
  ap_data_free(d);
  return rc;
}
