/* The builder: definitions with defaults, growing arrays of copied definitions, messages.
 *
 * Layout: one array per element kind, each entry a copy of the user's definition plus its
 * name (copied, at most 63 bytes). Ids are array indices. Nothing is validated here except
 * arguments and name lengths: ap_builder_compile (compile.c) validates everything once. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/defcheck.h"
#include "core/text.h"
#include "model/builder.h"

ap_body_def ap_body_def_default(void) {
  ap_body_def def;
  memset(&def, 0, sizeof def);
  def.internal_check = AP_DEF_CHECK;
  def.mass = 1.0;
  def.shape.flat_tol = 1e-6;
  return def;
}

ap_joint_def ap_joint_def_default(void) {
  ap_joint_def def;
  memset(&def, 0, sizeof def);
  def.internal_check = AP_DEF_CHECK;
  def.kind = AP_JOINT_FREE;
  def.parent = AP_GROUND;
  def.child = AP_NONE;
  def.parent_frame.quat[0] = 1.0;
  def.child_frame.quat[0] = 1.0;
  def.axis[2] = 1.0;
  return def;
}

ap_constraint_def ap_constraint_def_default(void) {
  ap_constraint_def def;
  memset(&def, 0, sizeof def);
  def.internal_check = AP_DEF_CHECK;
  def.kind = AP_CON_ROLLING;
  def.body = AP_NONE;
  def.body2 = AP_GROUND;
  def.direction[1] = 1.0;
  def.axes = 7u;
  def.joint = AP_NONE;
  def.ground.kind = AP_GROUND_FIXED;
  def.mu = def.mu_kinetic = -1.0;
  def.unilateral = -1;
  return def;
}

ap_effect_def ap_effect_def_default(void) {
  ap_effect_def def;
  memset(&def, 0, sizeof def);
  def.internal_check = AP_DEF_CHECK;
  def.kind = AP_EFFECT_GRAVITY;
  def.gravity[2] = -9.81;
  def.body = AP_NONE;
  def.body2 = AP_GROUND;
  def.joint = AP_NONE;
  def.motor = AP_MOTOR_RATE;
  def.max_effort = HUGE_VAL;
  return def;
}

/* Uniform solids about their centre (disk: thin lamina). */
int ap_body_def_uniform(ap_body_def *def, double mass) {
  if (!def || !(mass > 0) || !isfinite(mass)) return AP_ERR_ARG;
  const ap_shape *s = &def->shape;
  double d[3], r = s->radius, a = s->tube;
  const double *ax = s->semi_axes;
  switch (s->kind) {
    case AP_SHAPE_SPHERE: d[0] = d[1] = d[2] = 0.4 * mass * r * r; break;
    case AP_SHAPE_ELLIPSOID:
      d[0] = 0.2 * mass * (ax[1] * ax[1] + ax[2] * ax[2]);
      d[1] = 0.2 * mass * (ax[0] * ax[0] + ax[2] * ax[2]);
      d[2] = 0.2 * mass * (ax[0] * ax[0] + ax[1] * ax[1]);
      break;
    case AP_SHAPE_DISK: d[0] = d[1] = 0.25 * mass * r * r, d[2] = 0.5 * mass * r * r; break;
    case AP_SHAPE_TORUS:
      d[0] = d[1] = mass * (0.5 * r * r + 0.625 * a * a);
      d[2] = mass * (r * r + 0.75 * a * a);
      break;
    default: return AP_ERR_ARG;
  }
  def->mass = mass;
  memset(def->com, 0, sizeof def->com);
  memset(def->inertia, 0, sizeof def->inertia);
  for (int i = 0; i < 3; i++) def->inertia[4 * i] = d[i];
  return AP_OK;
}

/* ---- the builder ---------------------------------------------------------------------------- */

int ap_builder_create(const char *name, ap_builder **out) {
  if (!out) return AP_ERR_ARG;
  ap_builder *b = calloc(1, sizeof *b);
  if (!b) return AP_ERR_NOMEM;
  ap_core_copy_name(b->name, sizeof b->name, name ? name : "bodies");   /* "..." if cut */
  *out = b;
  return AP_OK;
}

int ap_builder_set_path(ap_builder *b, ap_path path) {
  if (!b || (path != AP_PATH_AUTO && path != AP_PATH_DENSE && path != AP_PATH_TREE))
    return AP_ERR_ARG;
  b->path = path;
  return AP_OK;
}

void ap_builder_free(ap_builder *b) {
  if (!b) return;
  free(b->bodies);
  free(b->joints);
  free(b->cons);
  free(b->effs);
  free(b);
}

const char *ap_builder_message(const ap_builder *b) { return b ? b->msg : ""; }

int ap_builder_fail(ap_builder *b, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(b->msg, sizeof b->msg, fmt, ap);
  va_end(ap);
  return AP_ERR_ARG;
}

static int ap_builder_nomem(ap_builder *b, const char *what) {
  snprintf(b->msg, sizeof b->msg, "model '%s': out of memory adding a %s", b->name, what);
  return AP_ERR_NOMEM;
}

/* Grow an array of `size`-byte entries to hold one more; NULL on failure. */
static void *grow(void *arr, int count, int *cap, size_t size) {
  if (count < *cap) return arr;
  int nc = *cap ? 2 * *cap : 8;
  void *p = realloc(arr, (size_t)nc * size);
  if (p) *cap = nc;
  return p;
}

/* A definition that its *_default() function did not make: refused, named by its name or the
 * id it would have had. */
static int not_default(ap_builder *b, const char *type, const char *name, const char *what,
                       int id) {
  if (name) return ap_builder_fail(b, "%s '%.40s%s' was not made by %s_default() (start from "
                                   "%s_default() and set the fields that differ)", type, name,
                                   strlen(name) > 40 ? "..." : "", type, type);
  return ap_builder_fail(b, "%s (%s %d) was not made by %s_default() (start from %s_default() "
                         "and set the fields that differ)", type, what, id, type, type);
}

static int copy_name(ap_builder *b, char *dst, const char *src, const char *what, int id) {
  if (src && strlen(src) >= AP_NAME_MAX)
    return ap_builder_fail(b, "%s %d: name '%.40s...' is longer than %d bytes", what, id,
                           src, AP_NAME_MAX - 1);
  if (src) snprintf(dst, AP_NAME_MAX, "%s", src);
  else snprintf(dst, AP_NAME_MAX, "%s%d", what, id);
  return AP_OK;
}

#define ADD(arr, cnt, cap, T, what)                                                       \
  do {                                                                                    \
    if (!b || !def) return AP_ERR_ARG;                                                    \
    if (def->internal_check != AP_DEF_CHECK)                                              \
      return not_default(b, "ap_" what "_def", def->name, what, b->cnt);                  \
    T *p_ = grow(b->arr, b->cnt, &b->cap, sizeof(T));                                     \
    if (!p_) return ap_builder_nomem(b, what);                                            \
    b->arr = p_;                                                                          \
    T *e_ = &b->arr[b->cnt];                                                              \
    e_->def = *def;                                                                       \
    int rc_ = copy_name(b, e_->name, def->name, what, b->cnt);                            \
    if (rc_ != AP_OK) return rc_;                                                         \
    e_->def.name = NULL;                                                                  \
    if (id) *id = b->cnt;                                                                 \
    b->cnt++;                                                                             \
    return AP_OK;                                                                         \
  } while (0)

int ap_builder_add_body(ap_builder *b, const ap_body_def *def, int *id) {
  ADD(bodies, nb, cb, ap_bbody, "body");
}

int ap_builder_add_joint(ap_builder *b, const ap_joint_def *def, int *id) {
  ADD(joints, nj, cj, ap_bjoint, "joint");
}

int ap_builder_add_constraint(ap_builder *b, const ap_constraint_def *def, int *id) {
  ADD(cons, nc, cc, ap_bcon, "constraint");
}

int ap_builder_add_effect(ap_builder *b, const ap_effect_def *def, int *id) {
  ADD(effs, ne, ce, ap_beff, "effect");
}
