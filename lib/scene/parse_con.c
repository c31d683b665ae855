/* Scene parsing, part 2: the ground motion, constraints and effects (docs/scenes.md).
 *
 * Each constraint and effect kind accepts its own keys only, so a key that would be ignored
 * (no_spin on a knife edge) is reported. Time functions (Omega(t), plane velocity, prescribed
 * speeds, applied forces) are sc_expr held in the scene; the builder definitions point at them
 * through their user pointers. Invariant: s->cons and s->effs do not move after parsing (the
 * definitions hold pointers into them). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static const char *const ground_keys[] = {"kind", "center", "omega", "velocity", "normal",
                                          "offset", "sphere", "z", NULL};
static const char *const sphere_keys[] = {"center", "radius", "inside", NULL};
static const char *const ground_kinds[] = {"fixed", "turntable", "translating", "height_field",
                                           NULL};
/* In the order of ap_constraint_kind (user constraints are C-only: "user" is refused). */
static const char *const con_kinds[] = {"rolling", "knife_edge", "prescribed_speed", "user",
                                        "coincident", "point_on_line", "point_on_plane", NULL};
static const char *const con_keys[][8] = {
    {"kind", "body", "no_spin", "ground", "friction", "unilateral", "restitution", NULL},
    {"kind", "body", "point", "direction", "wheel", "ground", NULL},
    {"kind", "joint", "speed", "value", NULL},
    {"kind", NULL},
    {"kind", "body", "point", "body2", "point2", "axes", NULL},
    {"kind", "body", "point", "body2", "point2", "direction", NULL},
    {"kind", "body", "point", "body2", "point2", "direction", NULL}};
/* The first four in the order of ap_effect_kind; then the joint effects (parse_act.c). */
static const char *const eff_kinds[] = {"gravity", "spring", "joint_damping", "applied",
                                        "joint_torque", "joint_force", "motor", NULL};
static const char *const eff_keys[][10] = {
    {"kind", "g", NULL},
    {"kind", "body", "point", "body2", "point2", "stiffness", "damping", "rest_length", NULL},
    {"kind", "joint", "damping", NULL},
    {"kind", "body", "point", "force", "torque", NULL},
    {"kind", "joint", "speed", "torque", NULL},
    {"kind", "joint", "speed", "force", NULL},
    {"kind", "joint", "speed", "rate", "angle", "position", "kp", "kd", "max", NULL}};

/* ---- ground ----------------------------------------------------------------------------- */

int sc_parse_ground(sc_ctx *c, const sc_node *n, sc_ground *g) {
  int kind = 0;
  if (sc_check_keys(c, n, ground_keys) || sc_get_enum(c, n, "kind", ground_kinds, &kind) ||
      sc_get_vec(c, n, "center", 2, g->def.center) ||
      sc_get_vec(c, n, "normal", 3, g->def.normal) || sc_get_number(c, n, "offset", &g->def.offset))
    return AP_ERR_ARG;
  if (kind == 3 || sc_map_get(n, "z")) return sc_parse_height(c, n, g);   /* height_field */
  const sc_node *nn = sc_map_get(n, "normal"), *sp = sc_map_get(n, "sphere");
  if (nn && !(fabs(g->def.normal[0]) + fabs(g->def.normal[1]) + fabs(g->def.normal[2]) > 0))
    return sc_err(c, nn, "the ground plane's normal must not be zero");
  if (sp) {   /* a fixed sphere instead of the plane */
    if (nn || sc_map_get(n, "offset"))
      return sc_err(c, sp, "the ground is a plane (normal, offset) or a sphere, not both");
    if (sc_check_keys(c, sp, sphere_keys) ||
        sc_get_vec(c, sp, "center", 3, g->def.sphere_center) ||
        sc_get_number(c, sp, "radius", &g->def.sphere_radius) ||
        sc_get_bool(c, sp, "inside", &g->def.inside))
      return AP_ERR_ARG;
    if (!(g->def.sphere_radius > 0))
      return sc_err(c, sp, "a ground sphere needs a positive radius (got %g)",
                    g->def.sphere_radius);
  }
  g->def.kind = (ap_ground_kind)kind;
  const sc_node *om = sc_map_get(n, "omega"), *ve = sc_map_get(n, "velocity");
  if (om && kind != AP_GROUND_TURNTABLE)
    return sc_err(c, om, "omega belongs to a turntable ground (kind: turntable)");
  if (ve && kind != AP_GROUND_TRANSLATING)
    return sc_err(c, ve, "velocity belongs to a translating ground (kind: translating)");
  if (sc_map_get(n, "center") && kind != AP_GROUND_TURNTABLE)
    return sc_err(c, sc_map_get(n, "center"), "center belongs to a turntable ground");
  if (om) {
    if (sc_expr_node(c, om, &g->omega)) return AP_ERR_ARG;
    g->def.omega = g->omega.value;
  }
  if (!ve) return AP_OK;
  if (ve->kind != SC_SEQ || ve->n != 2)
    return sc_err(c, ve, "expected [vx, vy]: two numbers or expressions of t");
  for (int i = 0; i < 2; i++)
    if (sc_expr_node(c, ve->kids[i], &g->vel[i])) return AP_ERR_ARG;
  g->def.velocity[0] = g->vel[0].value, g->def.velocity[1] = g->vel[1].value;
  return AP_OK;
}

/* Velocity functions share ap_ground_motion.user = the sc_ground. */
static int vel_fn(int i, double t, double f[3], void *user) {
  return sc_expr_eval(&((const sc_ground *)user)->vel[i], t, f);
}
static int vel_fn_x(double t, double f[3], void *user) { return vel_fn(0, t, f, user); }
static int vel_fn_y(double t, double f[3], void *user) { return vel_fn(1, t, f, user); }
static int omega_fn(double t, double f[3], void *user) {
  return sc_expr_eval(&((const sc_ground *)user)->omega, t, f);
}

/* Point the ground definition's callbacks at g (after g reached its final address). */
void sc_ground_bind(sc_ground *g) {
  g->def.user = g;
  g->def.omega_fn = g->omega.timed ? omega_fn : NULL;
  g->def.velocity_fn[0] = g->vel[0].timed || g->vel[1].timed ? vel_fn_x : NULL;
  g->def.velocity_fn[1] = g->vel[0].timed || g->vel[1].timed ? vel_fn_y : NULL;
  if (g->def.height_fn) g->def.height_user = &g->height;
}

/* ---- constraints ------------------------------------------------------------------------ */

static int parse_axes(sc_ctx *c, const sc_node *n, unsigned *axes) {
  if (n->kind != SC_SCALAR || !n->text[0] || strspn(n->text, "xyz") != strlen(n->text))
    return sc_err(c, n, "expected the world axes kept, e.g. xyz, xz or y");
  *axes = 0;
  for (const char *p = n->text; *p; p++) *axes |= 1u << (*p - 'x');
  return AP_OK;
}

static int parse_speed_ref(sc_ctx *c, sc_scene *s, const sc_node *n, sc_con *k) {
  const char *jn = NULL, *sp = NULL;
  if (!sc_map_get(n, "joint") || !sc_map_get(n, "speed"))
    return sc_err(c, n, "a prescribed_speed constraint needs joint and speed");
  if (sc_get_name(c, n, "joint", &jn) || sc_get_name(c, n, "speed", &sp)) return AP_ERR_ARG;
  int j = sc_find_joint(s, jn);
  if (j < 0) return sc_err(c, sc_map_get(n, "joint"), "no joint named '%s'", jn);
  int i = sc_joint_speed(s->joints[j].def.kind, sp);
  if (i < 0)
    return sc_err(c, sc_map_get(n, "speed"), "a %s joint has no speed '%s' (see docs/scenes.md, "
                  "\"Joints\")", sc_joint_kind_name(s->joints[j].def.kind), sp);
  k->def.joint = j, k->def.speed = i;
  const sc_node *v = sc_map_get(n, "value");
  if (!v) return sc_err(c, n, "a prescribed_speed constraint needs value (a number or f(t))");
  if (sc_expr_node(c, v, &k->value)) return AP_ERR_ARG;
  k->def.speed_value = k->value.value;
  if (k->value.timed) k->def.speed_fn = sc_expr_time_fn, k->def.user = &k->value;
  return AP_OK;
}

/* A knife edge is a wheel's (at the contact point of a disk or torus, across the wheel plane)
 * when `wheel: true`, or when the body is a disk or torus and neither point nor direction is
 * given; otherwise it is the body point's (docs/scenes.md "constraints"). */
static int parse_knife_wheel(sc_ctx *c, sc_scene *s, const sc_node *n, ap_constraint_def *d) {
  const sc_node *w = sc_map_get(n, "wheel");
  ap_shape_kind sk = s->bodies[d->body].def.shape.kind;
  int disk = sk == AP_SHAPE_DISK || sk == AP_SHAPE_TORUS;
  int pt = sc_map_get(n, "point") || sc_map_get(n, "direction");
  d->wheel = disk && !pt;
  if (!w) return AP_OK;
  if (sc_get_bool(c, n, "wheel", &d->wheel)) return AP_ERR_ARG;
  if (d->wheel && pt)
    return sc_err(c, w, "a wheel knife edge acts at the contact point across the wheel plane: "
                  "drop point and direction, or set wheel: false");
  if (d->wheel && !disk)
    return sc_err(c, w, "a wheel knife edge needs a body shaped as a disk or torus; '%s' is "
                  "not", s->bodies[d->body].name);
  return AP_OK;
}

static int parse_con_body(sc_ctx *c, sc_scene *s, const sc_node *n, sc_con *k) {
  ap_constraint_def *d = &k->def;
  if (!sc_map_get(n, "body")) return sc_err(c, n, "the constraint needs body");
  if (sc_get_body_ref(c, s, n, "body", 0, &d->body) || sc_get_vec(c, n, "point", 3, d->point) ||
      sc_get_vec(c, n, "direction", 3, d->direction) || sc_get_bool(c, n, "no_spin", &d->no_spin) ||
      sc_get_vec(c, n, "point2", 3, d->point2))
    return AP_ERR_ARG;
  if (sc_map_get(n, "body2") && sc_get_body_ref(c, s, n, "body2", 1, &d->body2)) return AP_ERR_ARG;
  if (sc_map_get(n, "axes") && parse_axes(c, sc_map_get(n, "axes"), &d->axes)) return AP_ERR_ARG;
  if (sc_map_get(n, "direction") && !(fabs(d->direction[0]) + fabs(d->direction[1]) +
                                          fabs(d->direction[2]) > 0))
    return sc_err(c, sc_map_get(n, "direction"), "the direction must not be zero");
  if (d->kind == AP_CON_KNIFE_EDGE && parse_knife_wheel(c, s, n, d)) return AP_ERR_ARG;
  if (d->kind == AP_CON_ROLLING && sc_parse_friction(c, n, d)) return AP_ERR_ARG;
  const sc_node *g = sc_map_get(n, "ground");
  if (d->kind != AP_CON_ROLLING && d->kind != AP_CON_KNIFE_EDGE) return AP_OK;
  k->ground = s->ground;
  memset(&k->ground.omega, 0, sizeof k->ground.omega);
  memset(k->ground.vel, 0, sizeof k->ground.vel);
  memset(&k->ground.height, 0, sizeof k->ground.height);
  if (g) k->ground.def.height_fn = NULL;   /* its own ground replaces a top-level height field */
  if (g) return sc_parse_ground(c, g, &k->ground);
  if (sc_height_copy(c, &s->ground, &k->ground)) return AP_ERR_ARG;
  /* Inherit the top-level ground: copy its expressions by recompiling their text (messages
   * then point at the top-level node). */
  if (s->ground.omega.timed &&
      sc_expr_compile(c, s->ground.omega.node, s->ground.omega.text, 1, &k->ground.omega))
    return AP_ERR_ARG;
  for (int i = 0; i < 2; i++) {
    if (s->ground.vel[i].timed &&
        sc_expr_compile(c, s->ground.vel[i].node, s->ground.vel[i].text, 1, &k->ground.vel[i]))
      return AP_ERR_ARG;
    k->ground.vel[i].value = s->ground.vel[i].value;
  }
  k->ground.omega.value = s->ground.omega.value;
  return AP_OK;
}

static int parse_con(sc_ctx *c, sc_scene *s, const sc_node *key, const sc_node *n, sc_con *k) {
  k->name = key->text, k->node = n;
  k->def = ap_constraint_def_default();
  k->def.name = k->name;
  int kind = 0;
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  if (!sc_map_get(n, "kind"))
    return sc_err(c, n, "the constraint needs a kind (rolling, knife_edge, prescribed_speed, "
                  "coincident, point_on_line or point_on_plane)");
  if (sc_get_enum(c, n, "kind", con_kinds, &kind)) return AP_ERR_ARG;
  if (kind == AP_CON_USER)
    return sc_err(c, sc_map_get(n, "kind"), "user constraints need C callbacks; build them with "
                  "the builder API (body.h), not in a scene");
  k->def.kind = (ap_constraint_kind)kind;
  if (sc_check_keys(c, n, con_keys[kind])) return AP_ERR_ARG;
  if (kind == AP_CON_PRESCRIBED_SPEED) return parse_speed_ref(c, s, n, k);
  return parse_con_body(c, s, n, k);
}

/* ---- effects ---------------------------------------------------------------------------- */

static int parse_wrench(sc_ctx *c, const sc_node *n, const char *key, sc_expr *e, double *out,
                        int *timed) {
  const sc_node *v = sc_map_get(n, key);
  if (!v) return AP_OK;
  if (v->kind != SC_SEQ || v->n != 3)
    return sc_err(c, v, "expected three numbers or expressions of t, e.g. [0, 0, \"sin(t)\"]");
  for (int i = 0; i < 3; i++) {
    if (sc_expr_node(c, v->kids[i], &e[i])) return AP_ERR_ARG;
    out[i] = e[i].value;
    *timed |= e[i].timed;
  }
  return AP_OK;
}

static int wrench_fn(double t, double force[3], double torque[3], void *user) {
  const sc_eff *e = user;
  double f[3];
  for (int i = 0; i < 3; i++) {
    if (sc_expr_eval(&e->force[i], t, f)) return -1;
    force[i] = f[0];
    if (sc_expr_eval(&e->torque[i], t, f)) return -1;
    torque[i] = f[0];
  }
  return 0;
}

static int parse_eff_fields(sc_ctx *c, sc_scene *s, const sc_node *n, sc_eff *e) {
  ap_effect_def *d = &e->def;
  const char *jn = NULL;
  if (sc_get_vec(c, n, "g", 3, d->gravity) || sc_get_vec(c, n, "point", 3, d->point) ||
      sc_get_vec(c, n, "point2", 3, d->point2) || sc_get_number(c, n, "stiffness", &d->stiffness) ||
      sc_get_number(c, n, "damping", &d->damping) ||
      sc_get_number(c, n, "rest_length", &d->rest_length) ||
      sc_check_nonneg(c, n, "stiffness", d->stiffness) ||
      sc_check_nonneg(c, n, "damping", d->damping) ||
      sc_check_nonneg(c, n, "rest_length", d->rest_length) ||
      parse_wrench(c, n, "force", e->force, d->force, &e->timed) ||
      parse_wrench(c, n, "torque", e->torque, d->torque, &e->timed))
    return AP_ERR_ARG;
  if (d->kind == AP_EFFECT_SPRING || d->kind == AP_EFFECT_APPLIED) {
    if (!sc_map_get(n, "body")) return sc_err(c, n, "the effect needs body");
    if (sc_get_body_ref(c, s, n, "body", 0, &d->body)) return AP_ERR_ARG;
  }
  if (sc_map_get(n, "body2") && sc_get_body_ref(c, s, n, "body2", 1, &d->body2)) return AP_ERR_ARG;
  if (d->kind == AP_EFFECT_JOINT_DAMPING) {
    if (!sc_map_get(n, "joint")) return sc_err(c, n, "joint_damping needs joint");
    if (sc_get_name(c, n, "joint", &jn)) return AP_ERR_ARG;
    if ((d->joint = sc_find_joint(s, jn)) < 0)
      return sc_err(c, sc_map_get(n, "joint"), "no joint named '%s'", jn);
  }
  if (e->timed) d->wrench = wrench_fn, d->user = e;
  return AP_OK;
}

static int parse_eff(sc_ctx *c, sc_scene *s, const sc_node *key, const sc_node *n, sc_eff *e) {
  e->name = key->text, e->node = n;
  e->def = ap_effect_def_default();
  e->def.name = e->name;
  int kind = 0;
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  if (!sc_map_get(n, "kind"))
    return sc_err(c, n, "the effect needs a kind (gravity, spring, joint_damping, applied, "
                  "joint_torque, joint_force or motor)");
  if (sc_get_enum(c, n, "kind", eff_kinds, &kind)) return AP_ERR_ARG;
  if (sc_check_keys(c, n, eff_keys[kind])) return AP_ERR_ARG;
  if (kind > AP_EFFECT_APPLIED) return sc_parse_joint_effect(c, s, n, e, kind - 4);
  e->def.kind = (ap_effect_kind)kind;
  return parse_eff_fields(c, s, n, e);
}

int sc_parse_con_eff(sc_ctx *c, sc_scene *s) {
  const sc_node *g = sc_map_get(s->root, "ground"), *cn = sc_map_get(s->root, "constraints"),
                *en = sc_map_get(s->root, "effects");
  s->ground.def = ap_constraint_def_default().ground;
  s->ground_node = g;
  if (g && sc_parse_ground(c, g, &s->ground)) return AP_ERR_ARG;
  if ((cn && sc_expect(c, cn, SC_MAP)) || (en && sc_expect(c, en, SC_MAP))) return AP_ERR_ARG;
  s->cons = calloc(cn ? (size_t)cn->n + 1 : 1, sizeof *s->cons);
  s->effs = calloc(en ? (size_t)en->n + 1 : 1, sizeof *s->effs);
  if (!s->cons || !s->effs) return sc_nomem(c);
  /* Counts grow before each element is read so that sc_scene_clear frees a half-read one. */
  for (int i = 0; cn && i < cn->n; i++)
    if (s->nc++, parse_con(c, s, cn->keys[i], cn->kids[i], &s->cons[i])) return AP_ERR_ARG;
  for (int i = 0; en && i < en->n; i++)
    if (s->ne++, parse_eff(c, s, en->keys[i], en->kids[i], &s->effs[i])) return AP_ERR_ARG;
  for (int i = 0; i < s->nc; i++) sc_ground_bind(&s->cons[i].ground);
  for (int i = 0; i < s->nc; i++) s->cons[i].def.ground = s->cons[i].ground.def;
  return AP_OK;
}
