/* Scene events (docs/scenes.md "Events"): the events: section, the collide: key of bodies,
 * and their event functions for the simulation's events (include/appell/event.h).
 *
 *   events:
 *     lean:   {when: "hinge.angle - 60*deg", direction: rising, action: stop}
 *     ground: {kind: collide, body: frame}           # the shape's lowest point reaches z = 0
 *     lift:   {kind: lift_off, constraint: front}    # a rolling contact's normal force, 0
 *     range:  {kind: joint_range, joint: steer, min: -1, max: 1}
 *   bodies:
 *     frame: {..., shape: {...}, collide: stop}      # the same as kind: collide
 *
 * Event functions: `when` is an expression of t and the state (the names of effects'
 * expressions, state.c), compiled against the names it reads; collide is z_origin -
 * sigma(-R^T e_z), the height of the shape's lowest point (sigma the shape's support
 * function: sphere r, disk r |u_xy|, torus r |u_xy| + tube, ellipsoid sqrt(sum a_i^2 u_i^2),
 * u = -R^T e_z); lift_off is the contact's normal force F_n (ap_body_contact_force, after the
 * multipliers); joint_range is min(q - min, max - q) of the joint's first coordinate.
 * Defaults: direction either for when, falling for the others; action stop.
 * An expression that reads body quantities (expr_body.c) is evaluated at the acceleration
 * stage, whose kinematics it reads from d.
 * Implicit events: the kinks (abs, step, sign, floor, min, max; expr_fn2.c) of every
 * expression of the scene, on their arguments, and the saturation switching of motors with a limit, u = +-max for the
 * unsaturated PD law u (set-points constant or of t; lib/model/actuator.c has the law); both
 * restart the stepper where they cross (a switch with no change of state).
 * Invariant: after sc_events_bind nothing here is written; the functions read the scene and
 * the model only, so one scene's events may run in many simulations at once. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/event.h"
#include "scene/scene_int.h"

enum { SC_EV_WHEN = 0, SC_EV_COLLIDE, SC_EV_LIFT_OFF, SC_EV_RANGE };

typedef struct sc_event {
  char *name;
  const sc_node *node;
  int kind, direction, action;
  sc_expr when;
  int nin;
  ap_state_input in[AP_STATE_MAX_INPUTS];
  int index[AP_STATE_MAX_INPUTS]; /* global q or v index of each input (after bind) */
  int body, constraint, joint;    /* collide, lift_off, joint_range */
  ap_shape shape;                 /* collide: the body's shape */
  double lo, hi;                  /* joint_range */
  int qi;                         /* joint_range: the coordinate's index in q */
  const ap_model *m;
} sc_event;

/* A kink of a scene expression (abs, step, delta): an implicit event on its argument. */
typedef struct sc_kink {
  char name[128];                 /* "kink 1 of effects.push.force" */
  const sc_expr *e;
  int which;                      /* its place among the program's kinks */
  int nin;
  const ap_state_input *in;       /* its inputs (the effect's) */
  int index[AP_STATE_MAX_INPUTS]; /* global q or v index of each input */
  const ap_model *m;              /* for the body quantities among its inputs */
} sc_kink;

/* A motor's saturation switching, |u| = max_effort of its unsaturated PD law u: the events
 * u - max (sign +1) and u + max (sign -1). */
typedef struct sc_sat {
  char name[128];
  const sc_eff *e;
  int qi, vi;                     /* global indices of its coordinate and speed */
  double sign;
} sc_sat;

static const char *const kinds[] = {"when", "collide", "lift_off", "joint_range", NULL};
static const char *const dirs[] = {"either", "rising", "falling", NULL};
static const char *const actions[] = {"stop", "log", NULL};
static const char *const keys[] = {"kind", "when", "body", "constraint", "joint", "min", "max",
                                   "direction", "action", NULL};

void sc_events_free(sc_scene *s) {
  for (int i = 0; i < s->nev; i++) {
    free(s->events[i].name);
    sc_expr_free(&s->events[i].when);
  }
  free(s->events);
  free(s->kinks);
  free(s->sats);
  s->events = NULL, s->nev = 0, s->kinks = NULL, s->nkink = 0, s->sats = NULL, s->nsat = 0;
}

/* ---- reading ------------------------------------------------------------------------------ */

static int read_when(sc_ctx *c, sc_scene *s, const sc_node *n, sc_event *e) {
  const sc_node *w = sc_map_get(n, "when");
  if (!w) return sc_err(c, n, "an event needs when: (an expression of t and the state that "
                        "crosses zero) or kind: collide, lift_off or joint_range");
  if (sc_expect(c, w, SC_SCALAR)) return AP_ERR_ARG;
  sc_state_names t;
  if (sc_state_names_build(s, &t) != AP_OK) return sc_nomem(c);
  sc_symtab sym = {1, (const char *const *)t.names, NULL, NULL, NULL, NULL};
  int rc = sc_expr_compile_sym(c, w, w->text, &sym, &e->when);
  if (rc == AP_OK && !e->when.timed)
    rc = sc_err(c, w, "'%s' is a constant: an event's when: must depend on t or the state",
                w->text);
  if (rc == AP_OK && sc_prog_nvars(e->when.prog) > 0)
    rc = sc_bind_state(c, w, &t, &e->when, e->in, &e->nin);
  sc_state_names_free(&t);
  return rc;
}

static int read_kind(sc_ctx *c, sc_scene *s, const sc_node *n, sc_event *e) {
  const char *name = NULL;
  if (e->kind == SC_EV_COLLIDE) {
    if (sc_get_body_ref(c, s, n, "body", 0, &e->body)) return AP_ERR_ARG;
    if (!sc_map_get(n, "body")) return sc_err(c, n, "kind: collide needs body:");
    if (s->bodies[e->body].def.shape.kind == AP_SHAPE_NONE)
      return sc_err(c, sc_map_get(n, "body"), "body '%s' has no shape: collide needs one "
                    "(bodies.%s.shape)", s->bodies[e->body].name, s->bodies[e->body].name);
    e->shape = s->bodies[e->body].def.shape;
    return AP_OK;
  }
  const char *key = e->kind == SC_EV_LIFT_OFF ? "constraint" : "joint";
  if (sc_get_name(c, n, key, &name)) return AP_ERR_ARG;
  if (!name) return sc_err(c, n, "kind: %s needs %s:", kinds[e->kind], key);
  if (e->kind == SC_EV_LIFT_OFF) {
    for (e->constraint = 0; e->constraint < s->nc; e->constraint++)
      if (strcmp(s->cons[e->constraint].name, name) == 0) break;
    if (e->constraint == s->nc || s->cons[e->constraint].def.kind != AP_CON_ROLLING)
      return sc_err(c, sc_map_get(n, key), "'%s' is not a rolling constraint of the scene",
                    name);
    return AP_OK;
  }
  e->joint = sc_find_joint(s, name);
  if (e->joint < 0) return sc_err(c, sc_map_get(n, key), "no joint '%s'", name);
  e->lo = -INFINITY, e->hi = INFINITY;
  if (sc_get_number(c, n, "min", &e->lo) || sc_get_number(c, n, "max", &e->hi)) return AP_ERR_ARG;
  if (!(e->lo < e->hi)) return sc_err(c, n, "joint_range: min (%g) must be below max (%g)",
                                      e->lo, e->hi);
  return AP_OK;
}

static int read_event(sc_ctx *c, sc_scene *s, const sc_node *key, const sc_node *n,
                      sc_event *e) {
  e->node = n;
  e->name = strdup(key->text);
  if (!e->name) return sc_nomem(c);
  if (sc_check_keys(c, n, keys)) return AP_ERR_ARG;
  e->kind = sc_map_get(n, "when") && !sc_map_get(n, "kind") ? SC_EV_WHEN : SC_EV_COLLIDE;
  if (sc_map_get(n, "kind") && sc_get_enum(c, n, "kind", kinds, &e->kind)) return AP_ERR_ARG;
  int dir = e->kind == SC_EV_WHEN ? 0 : 2;
  if (sc_get_enum(c, n, "direction", dirs, &dir) || sc_get_enum(c, n, "action", actions,
                                                                   &e->action))
    return AP_ERR_ARG;
  e->direction = dir == 0 ? AP_EVENT_EITHER : dir == 1 ? AP_EVENT_RISING : AP_EVENT_FALLING;
  return e->kind == SC_EV_WHEN ? read_when(c, s, n, e) : read_kind(c, s, n, e);
}

/* A body's collide: stop | log. */
static int read_collide(sc_ctx *c, sc_scene *s, int b, const sc_node *v, sc_event *e) {
  size_t len = strlen(s->bodies[b].name) + sizeof ".collide";
  e->node = v, e->kind = SC_EV_COLLIDE, e->body = b, e->direction = AP_EVENT_FALLING;
  e->name = malloc(len);
  if (!e->name) return sc_nomem(c);
  snprintf(e->name, len, "%s.collide", s->bodies[b].name);
  if (sc_expect(c, v, SC_SCALAR)) return AP_ERR_ARG;
  e->action = strcmp(v->text, "log") == 0 ? AP_EVENT_LOG : AP_EVENT_STOP;
  if (strcmp(v->text, "stop") != 0 && strcmp(v->text, "log") != 0)
    return sc_err(c, v, "'%s': collide is stop or log", v->text);
  if (s->bodies[b].def.shape.kind == AP_SHAPE_NONE)
    return sc_err(c, v, "body '%s' has no shape: collide needs one (bodies.%s.shape)",
                  s->bodies[b].name, s->bodies[b].name);
  e->shape = s->bodies[b].def.shape;
  return AP_OK;
}

int sc_parse_events(sc_ctx *c, sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "events"), *bodies = sc_map_get(s->root, "bodies");
  if (n && sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  int count = n ? n->n : 0;
  for (int b = 0; b < s->nb; b++) count += sc_map_get(bodies->kids[b], "collide") != NULL;
  if (count == 0) return AP_OK;
  s->events = calloc((size_t)count, sizeof *s->events);
  if (!s->events) return sc_nomem(c);
  for (int i = 0; n && i < n->n; i++)
    if (s->nev++, read_event(c, s, n->keys[i], n->kids[i], &s->events[i])) return AP_ERR_ARG;
  for (int b = 0; b < s->nb; b++) {
    const sc_node *v = sc_map_get(bodies->kids[b], "collide");
    if (v && (s->nev++, read_collide(c, s, b, v, &s->events[s->nev - 1]))) return AP_ERR_ARG;
  }
  return AP_OK;
}

/* The kinks of e (reading the state inputs in[nin], or none) into s->kinks when k is not
 * NULL; returns their number. */
static int add_kinks(sc_scene *s, const ap_model *m, const sc_expr *e, const ap_state_input *in,
                     int nin, sc_kink *k) {
  int n = e->timed ? sc_prog_nkinks(e->prog) : 0;
  for (int i = 0; k && i < n; i++, k++) {
    snprintf(k->name, sizeof k->name, "kink %d of %.100s", i + 1,
             e->node && e->node->path ? e->node->path : "an expression");
    k->e = e, k->which = i, k->nin = nin, k->in = in, k->m = m;
    for (int j = 0; j < nin; j++) k->index[j] = sc_state_index(s, m, &in[j]);
  }
  return n;
}

/* Every expression of the scene through add_kinks; the count. */
static int each_kink(sc_scene *s, const ap_model *m, sc_kink *k) {
  int n = 0;
#define AP_KINKS(e, in, nin) (n += add_kinks(s, m, (e), (in), (nin), k ? k + n : NULL))
  for (int j = 0; j < s->nj; j++)
    for (int i = 0; i < 3; i++) AP_KINKS(&s->joints[j].drive[i], NULL, 0);
  for (int i = 0; i < 2; i++) AP_KINKS(&s->ground.vel[i], NULL, 0);
  AP_KINKS(&s->ground.omega, NULL, 0);
  for (int c = 0; c < s->nc; c++) {
    AP_KINKS(&s->cons[c].value, NULL, 0);
    AP_KINKS(&s->cons[c].ground.omega, NULL, 0);
    for (int i = 0; i < 2; i++) AP_KINKS(&s->cons[c].ground.vel[i], NULL, 0);
  }
  for (int e = 0; e < s->ne; e++) {
    const ap_effect_def *d = &s->effs[e].def;
    for (int i = 0; i < 3; i++) {
      AP_KINKS(&s->effs[e].force[i], NULL, 0);
      AP_KINKS(&s->effs[e].torque[i], NULL, 0);
    }
    AP_KINKS(&s->effs[e].value, d->inputs, d->state_fn == sc_state_fn ? d->ninputs : 0);
  }
#undef AP_KINKS
  return n;
}

/* Motors with a finite limit and a set-point of t (or constant) into s->sats when sat is not
 * NULL; their number. */
static int each_sat(const sc_scene *s, const ap_model *m, sc_sat *sat) {
  int n = 0;
  for (int i = 0; i < s->ne; i++) {
    const ap_effect_def *d = &s->effs[i].def;
    if (d->kind != AP_EFFECT_MOTOR || !isfinite(d->max_effort) || d->state_fn) continue;
    for (int j = 0; sat && j < 2; j++) {
      sc_sat *x = &sat[n + j];
      ap_state_input vin = {d->joint, 1, d->speed}, qin = {d->joint, 0, d->speed};
      x->e = &s->effs[i], x->sign = j ? -1.0 : 1.0;
      x->vi = sc_state_index(s, m, &vin);
      x->qi = d->motor == AP_MOTOR_ANGLE ? sc_state_index(s, m, &qin) : -1;
      snprintf(x->name, sizeof x->name, "saturation of %.80s (%cmax)", s->effs[i].name,
               j ? '-' : '+');
    }
    n += 2;
  }
  return n;
}

int sc_events_bind(sc_ctx *c, sc_scene *s, const ap_model *m) {
  int ns = each_sat(s, m, NULL);
  if (ns > 0) {
    s->sats = calloc((size_t)ns, sizeof *s->sats);
    if (!s->sats) return sc_nomem(c);
    s->nsat = each_sat(s, m, s->sats);
  }
  int nk = each_kink(s, m, NULL);
  if (nk > 0) {
    s->kinks = calloc((size_t)nk, sizeof *s->kinks);
    if (!s->kinks) return sc_nomem(c);
    s->nkink = each_kink(s, m, s->kinks);
  }
  for (int i = 0; i < s->nev; i++) {
    sc_event *e = &s->events[i];
    e->m = m;
    for (int j = 0; j < e->nin; j++) e->index[j] = sc_state_index(s, m, &e->in[j]);
    if (e->kind == SC_EV_RANGE) e->qi = ap_joint_coord_index(m, e->joint);
  }
  return AP_OK;
}

/* ---- the event functions ----------------------------------------------------------------------- */

/* Height of the lowest point of a shape centred at z0 with axes R (column-major). */
static double lowest(const ap_shape *sh, double z0, const double *R) {
  double u[3] = {-R[2], -R[5], -R[8]}, uxy = hypot(u[0], u[1]), sigma = 0.0;
  switch (sh->kind) {
    case AP_SHAPE_SPHERE: sigma = sh->radius; break;
    case AP_SHAPE_DISK: sigma = sh->radius * uxy; break;
    case AP_SHAPE_TORUS: sigma = sh->radius * uxy + sh->tube; break;
    case AP_SHAPE_ELLIPSOID:
      for (int i = 0; i < 3; i++) sigma += sh->semi_axes[i] * sh->semi_axes[i] * u[i] * u[i];
      sigma = sqrt(sigma);
      break;
    default: break;
  }
  return z0 - sigma;
}

static int event_fn(double t, const double *q, const double *v, const ap_data *d, void *user,
                    double *f) {
  const sc_event *e = user;
  double x[AP_STATE_MAX_INPUTS];
  ap_body_state st;
  ap_contact_force cf;
  int rc = AP_OK;
  switch (e->kind) {
    case SC_EV_WHEN:
      if (sc_state_gather(e->m, d, e->in, e->index, e->nin, q, v, x) != AP_OK) return -1;
      sc_prog_value(e->when.prog, t, x, f);
      return 0;
    case SC_EV_COLLIDE:
      rc = ap_body_get_state(e->m, d, e->body, &st);
      *f = lowest(&e->shape, st.pos[2], st.R);
      break;
    case SC_EV_LIFT_OFF:
      rc = ap_body_contact_force(e->m, d, NULL, e->constraint, &cf);
      *f = cf.normal;
      break;
    default: *f = fmin(q[e->qi] - e->lo, e->hi - q[e->qi]); break;
  }
  return rc == AP_OK ? 0 : -1;
}

static int kink_fn(double t, const double *q, const double *v, const ap_data *d, void *user,
                   double *f) {
  const sc_kink *k = user;
  double x[AP_STATE_MAX_INPUTS], args[SC_EXPR_MAX];
  if (sc_state_gather(k->m, d, k->in, k->index, k->nin, q, v, x) != AP_OK) return -1;
  sc_prog_kinks(k->e->prog, t, x, args);
  *f = args[k->which];
  return 0;
}

static int sat_fn(double t, const double *q, const double *v, const ap_data *d, void *user,
                  double *f) {
  (void)d;
  const sc_sat *x = user;
  const ap_effect_def *e = &x->e->def;
  double s[3] = {e->value, 0.0, 0.0};
  if (e->value_fn && sc_expr_eval(&x->e->value, t, s) != 0) return -1;
  double u = x->qi < 0 ? e->kd * (s[0] - v[x->vi])
                       : e->kp * (s[0] - q[x->qi]) + e->kd * (s[1] - v[x->vi]);
  *f = u - x->sign * e->max_effort;
  return 0;
}

/* A kink: the stepper restarts there, nothing else changes. */
static int kink_restart(const ap_event_record *ev, double *q, double *v, void *user) {
  (void)ev, (void)q, (void)v, (void)user;
  return 0;
}

static int add_kink_events(const sc_scene *s, ap_sim *sim) {
  for (int i = 0; i < s->nsat; i++) {
    ap_event_def def = ap_event_def_default();
    def.name = s->sats[i].name, def.fn = sat_fn, def.user = (void *)&s->sats[i];
    def.action = AP_EVENT_SWITCH, def.on_switch = kink_restart;
    int rc = ap_sim_add_event(sim, &def);
    if (rc != AP_OK) return rc;
  }
  for (int i = 0; i < s->nkink; i++) {
    ap_event_def def = ap_event_def_default();
    def.name = s->kinks[i].name, def.fn = kink_fn, def.user = (void *)&s->kinks[i];
    def.action = AP_EVENT_SWITCH, def.on_switch = kink_restart;
    def.of_time = s->kinks[i].nin == 0;
    if (sc_inputs_read_bodies(s->kinks[i].in, s->kinks[i].nin))   /* the kinematics of d */
      def.stage = AP_EVENT_ACCELERATION;
    int rc = ap_sim_add_event(sim, &def);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

int ap_scene_add_events(const ap_scene *sc, ap_sim *sim, char *msg, size_t msg_len) {
  if (msg && msg_len) msg[0] = '\0';
  if (!sc || !sim) return AP_ERR_ARG;
  const sc_scene *s = sc_scene_parsed(sc);
  const ap_data *sd = ap_sim_data(sim);   /* the simulation must be of the scene's model */
  const ap_model *m = ap_scene_model(sc);
  if (sd->n != ap_model_n(m) || sd->k != ap_model_k(m) || sd->b != ap_model_b(m)) {
    if (msg && msg_len) snprintf(msg, msg_len, "%s: the simulation is not of this scene's model",
                                 s->file);
    return AP_ERR_ARG;
  }
  for (int i = 0; i < s->nev; i++) {
    const sc_event *e = &s->events[i];
    ap_event_def def = ap_event_def_default();
    def.name = e->name, def.fn = event_fn, def.user = (void *)e;
    def.direction = e->direction;
    def.action = e->action == 1 ? AP_EVENT_LOG : AP_EVENT_STOP;
    def.stage = e->kind == SC_EV_LIFT_OFF ? AP_EVENT_REACTIONS
                : e->kind == SC_EV_COLLIDE ? AP_EVENT_POSITION
                : sc_inputs_read_bodies(e->in, e->nin) ? AP_EVENT_ACCELERATION : AP_EVENT_STATE;
    int rc = ap_sim_add_event(sim, &def);
    if (rc != AP_OK) {
      if (msg && msg_len) snprintf(msg, msg_len, "%s: %s", s->file, ap_sim_message(sim));
      return rc;
    }
  }
  int rc = add_kink_events(s, sim);
  if (rc != AP_OK && msg && msg_len) snprintf(msg, msg_len, "%s: %s", s->file,
                                               ap_sim_message(sim));
  return rc;
}
