/* Scene parsing, part 1: the top level, bodies and joints (docs/scenes.md).
 *
 * Reads the tree into sc_scene: each body and joint becomes a builder definition
 * (ap_body_def, ap_joint_def) filled from its *_default() and then from the keys present, so
 * defaults live in one place (body.h) and the scene states only differences. Validation that
 * can name a line happens here (negative masses, inertia not positive definite, unknown
 * bodies, a body with no joint or two, cycles); the builder validates again when compiling.
 * Invariant: the names in definitions point into the tree, which lives as long as the scene. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_int.h"

static const char *const top_keys[] = {"name", "description", "bodies", "joints", "constraints",
                                       "effects", "ground", "initial", "simulation", "output",
                                       "linearize", "events", "parameters", "include", "parts",
                                       "instances", "inputs", NULL};
static const char *const body_keys[] = {"mass", "com", "inertia", "shape", "collide", "visual", NULL};
static const char *const shape_keys[] = {"kind", "radius", "tube", "semi_axes", "flat_tol",
                                         NULL};
static const char *const shape_kinds[] = {"none", "point", "sphere", "ellipsoid", "disk", "torus",
                                          NULL};
static const char *const joint_keys[] = {"kind", "parent", "child", "parent_frame",
                                         "child_frame", "axis", "drive", NULL};
static const char *const frame_keys[] = {"pos", "quat", "axis", "angle", NULL};
/* In the order of ap_joint_kind. */
static const char *const joint_kinds[] = {"free", "fixed", "revolute", "prismatic", "planar",
                                          "ball", "plane_contact", NULL};

const char *sc_joint_kind_name(ap_joint_kind kind) {
  return kind >= 0 && kind <= AP_JOINT_PLANE_CONTACT ? joint_kinds[kind] : "?";
}

/* Drivable scalar coordinates of each kind, in local order. */
static const char *const *drivable(ap_joint_kind kind) {
  static const char *const rev[] = {"angle", NULL}, *const pri[] = {"position", NULL},
                           *const pla[] = {"x", "y", "heading", NULL},
                           *const fre[] = {"x", "y", "z", NULL}, *const con[] = {"x", "y", NULL},
                           *const none[] = {NULL};
  switch (kind) {
    case AP_JOINT_REVOLUTE: return rev;
    case AP_JOINT_PRISMATIC: return pri;
    case AP_JOINT_PLANAR: return pla;
    case AP_JOINT_FREE: return fre;
    case AP_JOINT_PLANE_CONTACT: return con;
    default: return none;
  }
}

int sc_joint_drivable(ap_joint_kind kind, const char *coord) {
  const char *const *names = drivable(kind);
  for (int i = 0; names[i]; i++)
    if (strcmp(names[i], coord) == 0) return i;
  return -1;
}

static const char *const *speed_names(ap_joint_kind kind) {
  static const char *const rev[] = {"rate", NULL},
                           *const pla[] = {"vx", "vy", "heading_rate", NULL},
                           *const bal[] = {"wx", "wy", "wz", NULL},
                           *const fre[] = {"vx", "vy", "vz", "wx", "wy", "wz", NULL},
                           *const con[] = {"vx", "vy", "wx", "wy", "wz", NULL},
                           *const none[] = {NULL};
  switch (kind) {
    case AP_JOINT_REVOLUTE:
    case AP_JOINT_PRISMATIC: return rev;
    case AP_JOINT_PLANAR: return pla;
    case AP_JOINT_BALL: return bal;
    case AP_JOINT_FREE: return fre;
    case AP_JOINT_PLANE_CONTACT: return con;
    default: return none;
  }
}

/* The column names of the speeds are accepted too (angle_dot, x_dot, ...). */
static const char *const *speed_aliases(ap_joint_kind kind) {
  static const char *const rev[] = {"angle_dot", NULL}, *const pri[] = {"pos_dot", NULL},
                           *const pla[] = {"x_dot", "y_dot", "heading_dot", NULL},
                           *const none[] = {NULL};
  return kind == AP_JOINT_REVOLUTE ? rev : kind == AP_JOINT_PRISMATIC ? pri
       : kind == AP_JOINT_PLANAR ? pla : none;
}

int sc_joint_speed(ap_joint_kind kind, const char *speed) {
  const char *const *names = speed_names(kind), *const *alias = speed_aliases(kind);
  for (int i = 0; names[i]; i++)
    if (strcmp(names[i], speed) == 0) return i;
  for (int i = 0; alias[i]; i++)
    if (strcmp(alias[i], speed) == 0) return i;
  return -1;
}

int sc_find_body(const sc_scene *s, const char *name) {
  for (int i = 0; i < s->nb; i++)
    if (strcmp(s->bodies[i].name, name) == 0) return i;
  return -1;
}

int sc_find_joint(const sc_scene *s, const char *name) {
  for (int i = 0; i < s->nj; i++)
    if (strcmp(s->joints[i].name, name) == 0) return i;
  return -1;
}

/* Names of elements: identifiers, so that column names and --set paths stay unambiguous. */
static int check_ident(sc_ctx *c, const sc_node *key) {
  const char *s = key->text;
  int ok = s[0] && (s[0] == '_' || (s[0] >= 'A' && s[0] <= 'Z') || (s[0] >= 'a' && s[0] <= 'z'));
  for (const char *p = s; ok && *p; p++)
    ok = *p == '_' || *p == '-' || (*p >= '0' && *p <= '9') || (*p >= 'A' && *p <= 'Z') ||
         (*p >= 'a' && *p <= 'z');
  if (!ok || strlen(s) > 60)
    return sc_err(c, key, "'%s' is not a valid name (letters, digits, _ and -, starting with a "
                  "letter or _, at most 60 characters)", s);
  if (strcmp(s, "ground") == 0) return sc_err(c, key, "'ground' is reserved for the fixed world");
  return AP_OK;
}

int sc_get_body_ref(sc_ctx *c, const sc_scene *s, const sc_node *map, const char *key,
                    int ground_ok, int *id) {
  const char *name = NULL;
  if (sc_get_name(c, map, key, &name) != AP_OK || !name) return c->status;
  if (ground_ok && strcmp(name, "ground") == 0) return *id = AP_GROUND, AP_OK;
  int b = sc_find_body(s, name);
  if (b >= 0) return *id = b, AP_OK;
  const char **names = calloc((size_t)s->nb + 2, sizeof *names);
  if (!names) return sc_nomem(c);
  for (int i = 0; i < s->nb; i++) names[i] = s->bodies[i].name;
  if (ground_ok) names[s->nb] = "ground";
  const char *sug = sc_suggest(name, names);
  if (sug)
    sc_err(c, sc_map_get(map, key), "no body named '%s' (did you mean '%s'?)", name, sug);
  else
    sc_err(c, sc_map_get(map, key), "no body named '%s'%s", name,
           s->nb ? "" : " (the scene has no bodies)");
  free(names);
  return AP_ERR_ARG;
}

/* ---- bodies ----------------------------------------------------------------------------- */

static int parse_shape(sc_ctx *c, const sc_node *n, ap_shape *sh) {
  if (sc_check_keys(c, n, shape_keys) != AP_OK) return AP_ERR_ARG;
  int kind = 0;
  if (!sc_map_get(n, "kind")) return sc_err(c, n, "the shape needs a kind (%s)", "sphere, "
                                            "ellipsoid, disk, torus, point or none");
  if (sc_get_enum(c, n, "kind", shape_kinds, &kind) || sc_get_number(c, n, "radius", &sh->radius) ||
      sc_get_number(c, n, "tube", &sh->tube) || sc_get_vec(c, n, "semi_axes", 3, sh->semi_axes) ||
      sc_get_number(c, n, "flat_tol", &sh->flat_tol))
    return AP_ERR_ARG;
  sh->kind = (ap_shape_kind)kind;
  if (sh->kind == AP_SHAPE_SPHERE || sh->kind == AP_SHAPE_DISK || sh->kind == AP_SHAPE_TORUS)
    if (sc_check_positive(c, n, "radius", sh->radius)) return AP_ERR_ARG;
  if (sh->kind == AP_SHAPE_TORUS && sc_check_positive(c, n, "tube", sh->tube)) return AP_ERR_ARG;
  if (sh->kind == AP_SHAPE_TORUS && sh->tube >= sh->radius)
    return sc_err(c, sc_map_get(n, "tube"), "tube (%g) must be smaller than radius (%g)",
                  sh->tube, sh->radius);
  for (int i = 0; sh->kind == AP_SHAPE_ELLIPSOID && i < 3; i++)
    if (!(sh->semi_axes[i] > 0))
      return sc_err(c, sc_map_get(n, "semi_axes") ? sc_map_get(n, "semi_axes") : n,
                    "semi_axes must be three positive lengths (entry %d is %g)", i,
                    sh->semi_axes[i]);
  return AP_OK;
}

/* Symmetric positive definite by Sylvester's criterion (leading minors). */
static int check_inertia(sc_ctx *c, const sc_node *at, const double *I) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < i; j++)
      if (fabs(I[i + 3 * j] - I[j + 3 * i]) > 1e-12 * (fabs(I[0]) + fabs(I[4]) + fabs(I[8])))
        return sc_err(c, at, "the inertia tensor is not symmetric (entries %d,%d and %d,%d "
                      "differ: %g vs %g)", i, j, j, i, I[i + 3 * j], I[j + 3 * i]);
  double m[3];
  sc_leading_minors(I, m);
  if (!(m[0] > 0 && m[1] > 0 && m[2] > 0))
    return sc_err(c, at, "the inertia tensor is not positive definite (leading minors %g, %g, "
                  "%g; all must be positive)", m[0], m[1], m[2]);
  return AP_OK;
}

void sc_leading_minors(const double *I, double m[3]) {
  m[0] = I[0], m[1] = I[0] * I[4] - I[1] * I[3];
  m[2] = I[0] * (I[4] * I[8] - I[5] * I[7]) - I[3] * (I[1] * I[8] - I[2] * I[7]) +
         I[6] * (I[1] * I[5] - I[2] * I[4]);
}

/* inertia: uniform | [Ixx, Iyy, Izz] | [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] | [[..],[..],[..]] */
static int parse_inertia(sc_ctx *c, const sc_node *n, sc_body *b) {
  double *I = b->def.inertia, v[6] = {0};
  if (n->kind == SC_SCALAR && strcmp(n->text, "uniform") == 0) return b->uniform = 1, AP_OK;
  if (n->kind == SC_SEQ && n->n == 3 && n->kids[0]->kind == SC_SEQ) {
    for (int i = 0; i < 3; i++) {
      const sc_node *row = n->kids[i];
      if (row->kind != SC_SEQ || row->n != 3)
        return sc_err(c, row, "expected a row of 3 numbers");
      for (int j = 0; j < 3; j++)
        if (sc_number(c, row->kids[j], &I[i + 3 * j])) return AP_ERR_ARG;
    }
    return check_inertia(c, n, I);
  }
  if (n->kind != SC_SEQ || (n->n != 3 && n->n != 6))
    return sc_err(c, n, "expected 'uniform', [Ixx, Iyy, Izz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] "
                  "or a 3 x 3 matrix");
  for (int i = 0; i < n->n; i++)
    if (sc_number(c, n->kids[i], &v[i])) return AP_ERR_ARG;
  I[0] = v[0], I[4] = v[1], I[8] = v[2];
  I[3] = I[1] = v[3], I[6] = I[2] = v[4], I[7] = I[5] = v[5];
  return check_inertia(c, n, I);
}

static int parse_body(sc_ctx *c, const sc_node *key, const sc_node *n, sc_body *b) {
  b->name = key->text, b->node = n;
  b->def = ap_body_def_default();
  b->def.name = b->name;
  if (check_ident(c, key) || sc_check_keys(c, n, body_keys) ||
      sc_get_number(c, n, "mass", &b->def.mass) || sc_check_positive(c, n, "mass", b->def.mass) ||
      sc_get_vec(c, n, "com", 3, b->def.com))
    return AP_ERR_ARG;
  const sc_node *sh = sc_map_get(n, "shape"), *in = sc_map_get(n, "inertia");
  if (sh && parse_shape(c, sh, &b->def.shape)) return AP_ERR_ARG;
  if (sc_map_get(n, "visual") && sc_parse_visual(c, sc_map_get(n, "visual"), &b->visual))
    return AP_ERR_ARG;
  if (in && parse_inertia(c, in, b)) return AP_ERR_ARG;
  if (!in) b->uniform = 1;
  int solid = b->def.shape.kind != AP_SHAPE_NONE && b->def.shape.kind != AP_SHAPE_POINT;
  if (b->uniform && !solid)
    return sc_err(c, in ? in : n, "%sa uniform inertia needs a solid shape (sphere, "
                  "ellipsoid, disk or torus); give the inertia tensor instead",
                  in ? "" : "no inertia given, and ");
  if (b->uniform && sc_map_get(n, "com"))
    return sc_err(c, sc_map_get(n, "com"), "a uniform body has its centre of mass at the shape "
                  "centre; remove com or give the inertia tensor");
  return AP_OK;
}

/* ---- joints ----------------------------------------------------------------------------- */

static int parse_axis(sc_ctx *c, const sc_node *map, const char *key, double *axis) {
  const sc_node *n = sc_map_get(map, key);
  if (!n) return AP_OK;
  static const char *const names[] = {"x", "y", "z", "-x", "-y", "-z", NULL};
  if (n->kind == SC_SCALAR) {
    int i = 0;
    if (sc_get_enum(c, map, key, names, &i)) return AP_ERR_ARG;
    axis[0] = axis[1] = axis[2] = 0.0;
    axis[i % 3] = i < 3 ? 1.0 : -1.0;
    return AP_OK;
  }
  if (sc_get_vec(c, map, key, 3, axis)) return AP_ERR_ARG;
  if (!(sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]) > 1e-12))
    return sc_err(c, n, "the axis must not be zero");
  return AP_OK;
}

static int parse_frame(sc_ctx *c, const sc_node *n, ap_frame *f) {
  if (sc_check_keys(c, n, frame_keys) || sc_get_vec(c, n, "pos", 3, f->pos) ||
      sc_get_vec(c, n, "quat", 4, f->quat))
    return AP_ERR_ARG;
  const sc_node *q = sc_map_get(n, "quat"), *ax = sc_map_get(n, "axis"),
                *an = sc_map_get(n, "angle");
  if (q && (ax || an)) return sc_err(c, q, "give either quat or axis and angle, not both");
  if (q && !(sqrt(f->quat[0] * f->quat[0] + f->quat[1] * f->quat[1] + f->quat[2] * f->quat[2] +
                  f->quat[3] * f->quat[3]) > 1e-12))
    return sc_err(c, q, "the quaternion must not be zero");
  if (!ax != !an) return sc_err(c, ax ? ax : an, "a frame rotation needs both axis and angle");
  if (!ax) return AP_OK;
  double axis[3] = {0, 0, 1}, angle = 0;
  if (parse_axis(c, n, "axis", axis) || sc_get_number(c, n, "angle", &angle)) return AP_ERR_ARG;
  double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (int i = 0; i < 3; i++) axis[i] /= len;
  ap_quat_from_axis_angle(axis, angle, f->quat);
  return AP_OK;
}

static int parse_drive(sc_ctx *c, const sc_node *n, sc_joint *j) {
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  const char *const *names = drivable(j->def.kind);
  for (int i = 0; i < n->n; i++) {
    int idx = sc_joint_drivable(j->def.kind, n->keys[i]->text);
    if (idx < 0) {
      if (!names[0])
        return sc_err(c, n->keys[i], "a %s joint has no coordinate that can be driven",
                      sc_joint_kind_name(j->def.kind));
      return sc_check_keys(c, n, names);
    }
    if (sc_expr_node(c, n->kids[i], &j->drive[idx])) return AP_ERR_ARG;
    j->def.drive[idx] = sc_expr_time_fn;
    j->def.drive_user[idx] = &j->drive[idx];
  }
  return AP_OK;
}

static int parse_joint(sc_ctx *c, const sc_scene *s, const sc_node *key, const sc_node *n,
                       sc_joint *j) {
  j->name = key->text, j->node = n;
  j->def = ap_joint_def_default();
  j->def.name = j->name;
  int kind = 0;
  if (check_ident(c, key) || sc_check_keys(c, n, joint_keys)) return AP_ERR_ARG;
  if (!sc_map_get(n, "kind"))
    return sc_err(c, n, "the joint needs a kind (free, fixed, revolute, prismatic, planar, "
                  "ball or plane_contact)");
  if (sc_get_enum(c, n, "kind", joint_kinds, &kind)) return AP_ERR_ARG;
  j->def.kind = (ap_joint_kind)kind;
  if (sc_get_body_ref(c, s, n, "parent", 1, &j->def.parent)) return AP_ERR_ARG;
  if (sc_map_get(n, "child")) {
    if (sc_get_body_ref(c, s, n, "child", 0, &j->def.child)) return AP_ERR_ARG;
  } else if ((j->def.child = sc_find_body(s, j->name)) < 0) {
    return sc_err(c, n, "the joint needs a child body (child: NAME; it defaults to the body "
                  "named like the joint, and there is no body '%s')", j->name);
  }
  if (j->def.child == j->def.parent) return sc_err(c, n, "a body cannot be its own parent");
  const sc_node *pf = sc_map_get(n, "parent_frame"), *cf = sc_map_get(n, "child_frame");
  const sc_node *dr = sc_map_get(n, "drive");
  if ((pf && parse_frame(c, pf, &j->def.parent_frame)) ||
      (cf && parse_frame(c, cf, &j->def.child_frame)) || parse_axis(c, n, "axis", j->def.axis) ||
      (dr && parse_drive(c, dr, j)))
    return AP_ERR_ARG;
  if (sc_map_get(n, "axis") && kind != AP_JOINT_REVOLUTE && kind != AP_JOINT_PRISMATIC)
    return sc_err(c, sc_map_get(n, "axis"), "only revolute and prismatic joints have an axis");
  if (kind == AP_JOINT_PLANE_CONTACT && (pf || cf || j->def.parent != AP_GROUND))
    return sc_err(c, pf ? pf : cf ? cf : sc_map_get(n, "parent"), "a plane_contact joint joins "
                  "a body to the ground plane; it takes no parent and no frames");
  return AP_OK;
}

/* Every body is the child of exactly one joint, and parents lead to the ground. */
static int check_tree(sc_ctx *c, const sc_scene *s) {
  for (int b = 0; b < s->nb; b++) {
    int owner = -1;
    for (int j = 0; j < s->nj; j++) {
      if (s->joints[j].def.child != b) continue;
      if (owner >= 0)
        return sc_err(c, s->joints[j].node, "body '%s' is already the child of joint '%s'; a "
                      "body has one joint to its parent (close loops with constraints)",
                      s->bodies[b].name, s->joints[owner].name);
      owner = j;
    }
    if (owner < 0)
      return sc_err(c, s->bodies[b].node, "body '%s' has no joint: add one under joints: "
                    "with child: %s", s->bodies[b].name, s->bodies[b].name);
  }
  for (int j = 0; j < s->nj; j++) {
    int p = s->joints[j].def.parent, steps = 0;
    while (p != AP_GROUND && steps++ <= s->nb) {
      int owner = 0;
      while (owner < s->nj && s->joints[owner].def.child != p) owner++;
      p = s->joints[owner].def.parent;
    }
    if (p != AP_GROUND)
      return sc_err(c, s->joints[j].node, "the joints form a cycle through joint '%s'; close "
                    "loops with a constraint (coincident, point_on_line, point_on_plane)",
                    s->joints[j].name);
  }
  return AP_OK;
}

static int parse_bodies(sc_ctx *c, sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "bodies");
  if (!n) return sc_err(c, s->root, "the scene has no bodies: section");
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  if (n->n == 0) return sc_err(c, n, "the scene needs at least one body");
  s->bodies = calloc((size_t)n->n, sizeof *s->bodies);
  if (!s->bodies) return sc_nomem(c);
  for (int i = 0; i < n->n; i++, s->nb++)
    if (parse_body(c, n->keys[i], n->kids[i], &s->bodies[i])) return AP_ERR_ARG;
  return AP_OK;
}

static int parse_joints(sc_ctx *c, sc_scene *s) {
  const sc_node *n = sc_map_get(s->root, "joints");
  if (!n) return sc_err(c, s->root, "the scene has no joints: section (every body needs a "
                        "joint to its parent or the ground)");
  if (sc_expect(c, n, SC_MAP)) return AP_ERR_ARG;
  s->joints = calloc((size_t)n->n + 1, sizeof *s->joints);
  if (!s->joints) return sc_nomem(c);
  /* nj grows before each joint is read so that sc_scene_clear frees a half-read one; the child
   * lookups below only use bodies. */
  for (int i = 0; i < n->n; i++)
    if (s->nj++, parse_joint(c, s, n->keys[i], n->kids[i], &s->joints[i])) return AP_ERR_ARG;
  return check_tree(c, s);
}

int sc_parse_scene(sc_ctx *c, sc_scene *s) {
  if (sc_check_keys(c, s->root, top_keys)) return AP_ERR_ARG;
  if (sc_get_name(c, s->root, "name", &s->name)) return AP_ERR_ARG;
  const sc_node *d = sc_map_get(s->root, "description");
  if (d && sc_expect(c, d, SC_SCALAR)) return AP_ERR_ARG;
  if (parse_bodies(c, s) || parse_joints(c, s) || sc_parse_con_eff(c, s)) return AP_ERR_ARG;
  if (sc_parse_run(c, s)) return AP_ERR_ARG;
  if (sc_parse_linearize(c, s)) return AP_ERR_ARG;
  return sc_parse_events(c, s);
}
