/* Scene parsing of joint effects: joint_torque, joint_force and motor (docs/scenes.md
 * "effects"), into AP_EFFECT_JOINT_FORCE and AP_EFFECT_MOTOR definitions (body.h).
 *
 * Each names a joint and one of its speeds (`speed:`, defaulting to the joint's only speed of
 * the right sort): a torque or an angle set-point needs an angular speed, a force or a position
 * set-point a linear one, a rate set-point any speed. Checks that can point at a line happen
 * here (torque on a prismatic joint, motor on a driven joint, gains, limits); the builder
 * checks again when compiling. The value (torque, force or set-point) is a number or an
 * expression of t and the state, read by sc_read_value (state.c); its sc_expr lives in the
 * sc_eff, which the definition's user pointer refers to (s->effs does not move after
 * parsing). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene_int.h"

/* Is local speed i of a joint kind angular (a rotation rate) rather than linear? */
static int angular(ap_joint_kind kind, int i) {
  switch (kind) {
    case AP_JOINT_REVOLUTE: return 1;
    case AP_JOINT_PLANAR: return i == 2;
    case AP_JOINT_BALL: return 1;
    case AP_JOINT_FREE: return i >= 3;
    case AP_JOINT_PLANE_CONTACT: return i >= 2;
    default: return 0;
  }
}

static int speed_count(ap_joint_kind kind) {
  static const int nv[] = {6, 0, 1, 1, 3, 3, 5};   /* in the order of ap_joint_kind */
  return kind >= 0 && kind <= AP_JOINT_PLANE_CONTACT ? nv[kind] : 0;
}

/* The scene name of local speed i (the initial-state name: rate, vx, heading_rate, wx ...). */
static const char *speed_word(ap_joint_kind kind, int i) {
  static const char *const pla[] = {"vx", "vy", "heading_rate"},
                           *const fre[] = {"vx", "vy", "vz", "wx", "wy", "wz"},
                           *const con[] = {"vx", "vy", "wx", "wy", "wz"};
  switch (kind) {
    case AP_JOINT_REVOLUTE:
    case AP_JOINT_PRISMATIC: return "rate";
    case AP_JOINT_PLANAR: return pla[i % 3];
    case AP_JOINT_BALL: return fre[3 + i % 3];
    case AP_JOINT_FREE: return fre[i % 6];
    case AP_JOINT_PLANE_CONTACT: return con[i % 5];
    default: return "?";
  }
}

/* The scene name of drivable coordinate i (< 3). */
static const char *coord_word(ap_joint_kind kind, int i) {
  static const char *const xyz[] = {"x", "y", "z"};
  switch (kind) {
    case AP_JOINT_REVOLUTE: return "angle";
    case AP_JOINT_PRISMATIC: return "position";
    case AP_JOINT_PLANAR: return i == 2 ? "heading" : xyz[i % 3];
    default: return xyz[i % 3];
  }
}

/* sort: 1 angular, 0 linear, -1 any. The speeds of that sort, listed into buf; their count. */
static int speeds_of(ap_joint_kind kind, int sort, char *buf, size_t len, int *only) {
  int count = 0;
  buf[0] = '\0';
  for (int i = 0; i < speed_count(kind); i++) {
    if (sort >= 0 && angular(kind, i) != sort) continue;
    size_t used = strlen(buf);
    snprintf(buf + used, len - used, "%s%s", count ? ", " : "", speed_word(kind, i));
    *only = i, count++;
  }
  return count;
}

static int no_joint(sc_ctx *c, const sc_scene *s, const sc_node *at, const char *name) {
  const char *names[64] = {NULL}, *sug = NULL;
  if (s->nj < 64) {
    for (int i = 0; i < s->nj; i++) names[i] = s->joints[i].name;
    sug = sc_suggest(name, names);
  }
  return sc_err(c, at, "no joint named '%s'%s%s%s", name, sug ? " (did you mean '" : "",
                sug ? sug : "", sug ? "'?)" : "");
}

/* The joint and speed of a joint effect: `joint`, and `speed` or the only one of the sort;
 * hint: what to write instead when the joint has no speed of the sort. */
static int joint_speed(sc_ctx *c, const sc_scene *s, const sc_node *n, const char *what,
                       int sort, const char *hint, ap_effect_def *d) {
  static const char *const sorts[] = {"a linear", "an angular"};
  const char *jn = NULL, *sp = NULL;
  const sc_node *jk = sc_map_get(n, "joint"), *sk = sc_map_get(n, "speed");
  if (!jk) return sc_err(c, n, "a %s needs joint", what);
  if (sc_get_name(c, n, "joint", &jn) || sc_get_name(c, n, "speed", &sp)) return AP_ERR_ARG;
  int j = sc_find_joint(s, jn);
  if (j < 0) return no_joint(c, s, jk, jn);
  ap_joint_kind kind = s->joints[j].def.kind;
  char list[96];
  int only = 0, count = speeds_of(kind, sort, list, sizeof list, &only);
  if (count == 0)
    return sc_err(c, jk, "a %s acts along %s speed, and the %s joint '%s' has none (%s)", what,
                  sorts[sort > 0], sc_joint_kind_name(kind), jn, hint);
  int i = only;
  if (sk) {
    i = sc_joint_speed(kind, sp);
    if (i < 0)
      return sc_err(c, sk, "the %s joint '%s' has no speed '%s' (%s: %s)",
                    sc_joint_kind_name(kind), jn, sp, sort < 0 ? "speeds" : "its speeds here",
                    list);
    if (sort >= 0 && angular(kind, i) != sort)
      return sc_err(c, sk, "speed '%s' of joint '%s' is %s; a %s needs %s speed (%s)", sp, jn,
                    sort ? "linear" : "angular", what, sorts[sort > 0], list);
  } else if (count > 1) {
    return sc_err(c, n, "the %s joint '%s' has several speeds: choose one with speed: (%s)",
                  sc_joint_kind_name(kind), jn, list);
  }
  if (i < 3 && s->joints[j].def.drive[i])
    return sc_err(c, sk ? sk : jk, "the %s of joint '%s' is driven (drive: a function of t), "
                  "so a %s on its speed '%s' has no degree of freedom to act on",
                  coord_word(kind, i), jn, what, speed_word(kind, i));
  d->joint = j, d->speed = i;
  return AP_OK;
}

/* The value node into the effect's sc_expr and the definition's value / value_fn / state_fn. */
static int read_value(sc_ctx *c, sc_scene *s, const sc_node *v, sc_eff *e) {
  if (sc_read_value(c, s, v, &e->value, &e->def)) return AP_ERR_ARG;
  if (e->def.value_fn || e->def.state_fn) e->def.user = &e->value;
  return AP_OK;
}

static int parse_joint_force(sc_ctx *c, sc_scene *s, const sc_node *n, sc_eff *e, int torque) {
  const char *key = torque ? "torque" : "force";
  const sc_node *v = sc_map_get(n, key);
  if (joint_speed(c, s, n, torque ? "joint torque" : "joint force", torque,
                  torque ? "kind: joint_force pushes along a linear speed"
                         : "kind: joint_torque turns about an angular speed",
                  &e->def))
    return AP_ERR_ARG;
  if (!v) return sc_err(c, n, "a joint %s needs %s (a number or an expression)", key, key);
  e->def.kind = AP_EFFECT_JOINT_FORCE, e->is_torque = torque;
  return read_value(c, s, v, e);
}

/* Exactly one set-point key: rate, angle or position. */
static int set_point(sc_ctx *c, const sc_node *n, int *which) {
  static const char *const keys[] = {"rate", "angle", "position"};
  const sc_node *first = NULL;
  *which = -1;
  for (int i = 0; i < 3; i++) {
    const sc_node *v = sc_map_get(n, keys[i]);
    if (!v) continue;
    if (first)
      return sc_err(c, v, "a motor holds one set-point, and %s is given too", keys[*which]);
    first = v, *which = i;
  }
  if (!first)
    return sc_err(c, n, "a motor needs a set-point: rate (rad/s or m/s), angle (rad) or "
                  "position (m)");
  return AP_OK;
}

static int parse_gains(sc_ctx *c, const sc_node *n, ap_effect_def *d) {
  if (sc_get_number(c, n, "kp", &d->kp) || sc_get_number(c, n, "kd", &d->kd) ||
      sc_get_number(c, n, "max", &d->max_effort) || sc_check_nonneg(c, n, "kp", d->kp) ||
      sc_check_nonneg(c, n, "kd", d->kd) ||
      (sc_map_get(n, "max") && sc_check_positive(c, n, "max", d->max_effort)))
    return AP_ERR_ARG;
  if (d->motor == AP_MOTOR_RATE) {
    if (sc_map_get(n, "kp"))
      return sc_err(c, sc_map_get(n, "kp"), "belongs to a motor that holds an angle or a "
                    "position; a rate motor's torque is kd (rate - speed)");
    if (!(d->kd > 0))
      return sc_err(c, sc_map_get(n, "kd") ? sc_map_get(n, "kd") : n, "a rate motor needs "
                    "kd > 0 (N m s/rad or N s/m): its torque is kd (rate - speed)");
  } else if (!(d->kp + d->kd > 0)) {
    return sc_err(c, n, "a motor that holds an angle or a position needs kp > 0 or kd > 0");
  }
  return AP_OK;
}

static int parse_motor(sc_ctx *c, sc_scene *s, const sc_node *n, sc_eff *e) {
  static const char *const keys[] = {"rate", "angle", "position"};
  int which = -1;
  e->def.kind = AP_EFFECT_MOTOR;
  if (set_point(c, n, &which)) return AP_ERR_ARG;
  e->def.motor = which == 0 ? AP_MOTOR_RATE : AP_MOTOR_ANGLE;
  if (joint_speed(c, s, n, which == 0 ? "motor" : which == 1 ? "motor holding an angle"
                                                             : "motor holding a position",
                  which == 0 ? -1 : which == 1,
                  which == 1 ? "hold a position with position:" : "hold an angle with angle:",
                  &e->def))
    return AP_ERR_ARG;
  /* speeds 0..ndrivable-1 are the rates of scalar coordinates; the others are the angular
   * velocity of a quaternion, which has no angle to hold */
  static const int ndrivable[] = {3, 0, 1, 1, 3, 0, 2};
  const ap_joint_def *jd = &s->joints[e->def.joint].def;
  if (which > 0 && e->def.speed >= ndrivable[jd->kind])
    return sc_err(c, sc_map_get(n, keys[which]), "speed '%s' of the %s joint '%s' is an "
                  "angular velocity, not the rate of an angle coordinate (the orientation is a "
                  "quaternion): a motor can hold its rate only", speed_word(jd->kind, e->def.speed),
                  sc_joint_kind_name(jd->kind), s->joints[e->def.joint].name);
  if (parse_gains(c, n, &e->def)) return AP_ERR_ARG;
  return read_value(c, s, sc_map_get(n, keys[which]), e);
}

int sc_parse_joint_effect(sc_ctx *c, sc_scene *s, const sc_node *n, sc_eff *e, int which) {
  return which == SC_EFF_MOTOR ? parse_motor(c, s, n, e)
                               : parse_joint_force(c, s, n, e, which == SC_EFF_TORQUE);
}

