/* URDF import: the scene text (docs/scenes.md) of a robot read by urdf.c.
 *
 * Frames. A scene body's shape is centred at the body origin with its symmetry axis along body
 * z, so a link whose collision sphere or wheel cylinder is offset or turned gets the body frame
 * T_b = the collision origin (in link axes); other links keep T_b = identity. Everything is then
 * expressed in body axes:
 *   com       = T_b^-1 (inertial origin xyz)
 *   inertia   = M I M^T with M = R_b^T R_in (I in the inertial frame, R_in from its rpy)
 *   joint     parent_frame = T_bp^-1 O Q (O the joint origin in the parent link),
 *             child_frame  = T_bc^-1 Q (the child link frame is the joint frame at q = 0),
 * with Q = identity except for planar joints, whose plane normal (the URDF axis) becomes the
 * joint frame's z (Q turns z onto the axis). Revolute and prismatic axes stay in the joint
 * frame as URDF gives them. Quaternions are composed, not matrices, so a pose without a
 * rotation is written exactly. Numbers are written with 17 significant digits (round trip). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/urdf_int.h"

void ur_quat_mul(const double a[4], const double b[4], double out[4]) {
  double r[4] = {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                 a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                 a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                 a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
  memcpy(out, r, sizeof r);
}

/* R = Rz(yaw) Ry(pitch) Rx(roll) as a quaternion. */
void ur_pose_rpy(const double rpy[3], double q[4]) {
  double qx[4] = {cos(rpy[0] / 2), sin(rpy[0] / 2), 0, 0};
  double qy[4] = {cos(rpy[1] / 2), 0, sin(rpy[1] / 2), 0};
  double qz[4] = {cos(rpy[2] / 2), 0, 0, sin(rpy[2] / 2)};
  double t[4];
  ur_quat_mul(qz, qy, t);
  ur_quat_mul(t, qx, q);
}

static void rotate(const double q[4], const double v[3], double out[3]) {
  double p[4] = {0, v[0], v[1], v[2]}, c[4] = {q[0], -q[1], -q[2], -q[3]}, t[4];
  ur_quat_mul(q, p, t);
  ur_quat_mul(t, c, p);
  out[0] = p[1], out[1] = p[2], out[2] = p[3];
}

static void matrix(const double q[4], double R[3][3]) {
  for (int j = 0; j < 3; j++) {
    double e[3] = {j == 0, j == 1, j == 2}, col[3];
    rotate(q, e, col);
    for (int i = 0; i < 3; i++) R[i][j] = col[i];
  }
}

static ur_pose inverse(const ur_pose *a) {
  ur_pose r = {{0, 0, 0}, {a->q[0], -a->q[1], -a->q[2], -a->q[3]}};
  double p[3];
  rotate(r.q, a->p, p);
  for (int i = 0; i < 3; i++) r.p[i] = -p[i];
  return r;
}

static ur_pose compose(const ur_pose *a, const ur_pose *b) {
  ur_pose r;
  double p[3];
  rotate(a->q, b->p, p);
  for (int i = 0; i < 3; i++) r.p[i] = a->p[i] + p[i];
  ur_quat_mul(a->q, b->q, r.q);
  return r;
}

static const ur_pose identity = {{0, 0, 0}, {1, 0, 0, 0}};

/* The body frame of a link in its own axes. */
static ur_pose body_frame(const ur_link *l) {
  int framed = l->shape == UR_SHAPE_SPHERE || (l->shape == UR_SHAPE_CYLINDER && l->wheel);
  return framed ? l->shape_pose : identity;
}

/* The rotation taking z onto the unit vector a. */
static void z_onto(const double a[3], double q[4]) {
  if (a[2] < -1 + 1e-15) {
    q[0] = 0, q[1] = 1, q[2] = q[3] = 0;
    return;
  }
  double w = 1 + a[2], n = sqrt(w * w + a[0] * a[0] + a[1] * a[1]);
  q[0] = w / n, q[1] = -a[1] / n, q[2] = a[0] / n, q[3] = 0;
}

/* A growing text buffer. */
typedef struct ur_buf {
  char *s;
  size_t len, cap;
  int nomem;
} ur_buf;

static void put(ur_buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(ur_buf *b, const char *fmt, ...) {
  if (b->nomem) return;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? b->cap - b->len : 0, fmt, ap);
    va_end(ap);
    if (n < 0) {
      b->nomem = 1;
      return;
    }
    if (b->s && b->len + (size_t)n < b->cap) {
      b->len += (size_t)n;
      return;
    }
    size_t cap = (b->cap ? 2 * b->cap : 4096) + (size_t)n;
    char *s = realloc(b->s, cap);
    if (!s) {
      b->nomem = 1;
      return;
    }
    b->s = s, b->cap = cap;
  }
}

/* The shortest of %.15g, %.16g, %.17g that reads back as x (-0 as 0). */
static void num(ur_buf *b, double x) {
  char t[40];
  for (int digits = 15; digits <= 17; digits++) {
    snprintf(t, sizeof t, "%.*g", digits, x == 0 ? 0.0 : x);
    if (strtod(t, NULL) == x) break;
  }
  put(b, "%s", t);
}

static void vec(ur_buf *b, const double *v, int n) {
  put(b, "[");
  for (int i = 0; i < n; i++) {
    put(b, "%s", i ? ", " : "");
    num(b, v[i]);
  }
  put(b, "]");
}

static void frame(ur_buf *b, const char *key, const ur_pose *f) {
  put(b, "    %s: {pos: ", key);
  vec(b, f->p, 3);
  put(b, ", quat: ");
  vec(b, f->q, 4);
  put(b, "}\n");
}

static void inertia(ur_buf *b, const ur_link *l, const ur_pose *tb) {
  const double *I = l->I;
  double In[3][3] = {{I[0], I[1], I[2]}, {I[1], I[3], I[4]}, {I[2], I[4], I[5]}};
  double cq[4] = {tb->q[0], -tb->q[1], -tb->q[2], -tb->q[3]}, mq[4], M[3][3], Ib[3][3];
  ur_quat_mul(cq, l->inertial.q, mq);
  matrix(mq, M);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double s = 0;
      for (int k = 0; k < 3; k++)
        for (int m = 0; m < 3; m++) s += M[i][k] * In[k][m] * M[j][m];
      Ib[i][j] = s;
    }
  double out[6] = {Ib[0][0], Ib[1][1], Ib[2][2], (Ib[0][1] + Ib[1][0]) / 2,
                   (Ib[0][2] + Ib[2][0]) / 2, (Ib[1][2] + Ib[2][1]) / 2};
  put(b, "    inertia: ");
  vec(b, out, 6);
  put(b, "   # [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] about the centre of mass, body axes\n");
}

static void shape(ur_buf *b, const ur_link *l, const ap_urdf_def *def) {
  int torus = l->wheel && l->shape == UR_SHAPE_CYLINDER && def->wheel_shape == AP_URDF_WHEEL_TORUS;
  if (l->shape == UR_SHAPE_SPHERE || (l->wheel && l->shape == UR_SHAPE_CYLINDER)) {
    put(b, "    shape: {kind: %s, radius: ",
        l->shape == UR_SHAPE_SPHERE ? "sphere" : torus ? "torus" : "disk");
    num(b, torus ? l->radius - l->length / 2 : l->radius);
    if (torus) put(b, ", tube: ");
    if (torus) num(b, l->length / 2);
    put(b, "}\n");
  }
}

static void body(ur_buf *b, const ur_link *l, const ap_urdf_def *def) {
  ur_pose tb = body_frame(l), inv = inverse(&tb);
  double com[3], d[3];
  rotate(inv.q, l->inertial.p, d);
  for (int i = 0; i < 3; i++) com[i] = d[i] + inv.p[i];
  put(b, "  %s:   # link '%s', line %d\n    mass: ", l->name, l->urdf_name, l->line);
  num(b, l->mass);
  put(b, "\n    com: ");
  vec(b, com, 3);
  put(b, "\n");
  inertia(b, l, &tb);
  shape(b, l, def);
}

static const char *const kinds[] = {"revolute", "revolute", "prismatic",
                                    "fixed",    "free",     "planar"};

static void joint(ur_buf *b, const ur_robot *r, const ur_joint *j) {
  const ur_link *p = &r->links[j->parent], *c = &r->links[j->child];
  ur_pose Q = identity, tp = p->world ? identity : body_frame(p), tc = body_frame(c);
  if (j->type == UR_PLANAR) z_onto(j->axis, Q.q);
  ur_pose ip = inverse(&tp), ic = inverse(&tc), t = compose(&ip, &j->origin);
  ur_pose pf = compose(&t, &Q), cf = compose(&ic, &Q);
  put(b, "  %s:   # joint '%s' (%s), line %d\n    kind: %s\n    parent: %s\n    child: %s\n",
      j->name, j->urdf_name, j->type == UR_CONTINUOUS ? "continuous" : j->type == UR_FLOATING ?
      "floating" : kinds[j->type], j->line, kinds[j->type], p->world ? "ground" : p->name,
      c->name);
  frame(b, "parent_frame", &pf);
  frame(b, "child_frame", &cf);
  if (j->type == UR_REVOLUTE || j->type == UR_CONTINUOUS || j->type == UR_PRISMATIC) {
    put(b, "    axis: ");
    vec(b, j->axis, 3);
    put(b, "\n");
  }
}

/* The root link (not 'world') joins the ground by a free joint named after it. */
static void root_joint(ur_buf *b, const ur_robot *r) {
  const ur_link *l = &r->links[r->root];
  ur_pose tb = body_frame(l), cf = inverse(&tb);
  put(b, "  %s:   # the root link floats (add a link 'world' and a joint to fix it)\n"
      "    kind: free\n    child: %s\n", l->name, l->name);
  frame(b, "child_frame", &cf);
}

/* Links in tree order (parents first, children in file order), from the root: O(n). */
static int order(const ur_robot *r, int *out) {
  int *first = malloc(((size_t)r->nlinks + 1) * sizeof *first);
  int *next = malloc(((size_t)r->njoints + 1) * sizeof *next);
  if (!first || !next) {
    free(first);
    free(next);
    return -1;
  }
  for (int i = 0; i < r->nlinks; i++) first[i] = -1;
  for (int j = r->njoints - 1; j >= 0; j--)
    next[j] = first[r->joints[j].parent], first[r->joints[j].parent] = j;
  int n = 0;
  out[n++] = r->root;
  for (int k = 0; k < n; k++)
    for (int j = first[out[k]]; j >= 0; j = next[j]) out[n++] = r->joints[j].child;
  free(first);
  free(next);
  return n;
}

static void effects(ur_buf *b, const ur_robot *r) {
  put(b, "\neffects:\n  gravity: {kind: gravity}\n");
  for (int j = 0; j < r->njoints; j++)
    if (r->joints[j].damping > 0 && r->joints[j].type != UR_FIXED)
    {
      put(b, "  %s_damping: {kind: joint_damping, joint: %s, damping: ", r->joints[j].name,
          r->joints[j].name);
      num(b, r->joints[j].damping);
      put(b, "}\n");
    }
}

static void constraints_events(ur_buf *b, const ur_robot *r) {
  int wheels = 0, limits = 0;
  for (int i = 0; i < r->nlinks; i++) wheels += r->links[i].wheel;
  for (int j = 0; j < r->njoints; j++) limits += r->joints[j].has_limit;
  if (wheels) put(b, "\nconstraints:\n");
  for (int i = 0; i < r->nlinks; i++)
    if (r->links[i].wheel)
      put(b, "  %s_roll: {kind: rolling, body: %s}\n", r->links[i].name, r->links[i].name);
  if (limits)
    put(b, "\n# URDF limits: the run stops when a joint reaches one (action: log goes on)\n"
        "events:\n");
  for (int j = 0; j < r->njoints; j++)
    if (r->joints[j].has_limit) {
      put(b, "  %s_limit: {kind: joint_range, joint: %s, min: ", r->joints[j].name,
          r->joints[j].name);
      num(b, r->joints[j].lower);
      put(b, ", max: ");
      num(b, r->joints[j].upper);
      put(b, "}\n");
    }
}

int ur_emit(const ur_robot *r, const ap_urdf_def *def, const char *file, char **yaml,
            size_t *len, char *msg, size_t msg_len) {
  int *ord = calloc((size_t)r->nlinks + 1, sizeof *ord);
  if (!ord) return AP_ERR_NOMEM;
  int n = order(r, ord);
  if (n < 0) {
    free(ord);
    return AP_ERR_NOMEM;
  }
  ur_buf b = {0};
  put(&b, "# Imported from %s by appell import (docs/urdf.md).\nname: %s\n\nbodies:\n", file,
      r->name);
  for (int k = 0; k < n; k++)
    if (!r->links[ord[k]].world) body(&b, &r->links[ord[k]], def);
  put(&b, "\njoints:\n");
  if (!r->links[r->root].world) root_joint(&b, r);
  for (int k = 1; k < n; k++) joint(&b, r, &r->joints[r->links[ord[k]].parent_joint]);
  effects(&b, r);
  constraints_events(&b, r);
  free(ord);
  if (b.nomem) {
    free(b.s);
    snprintf(msg, msg_len, "%s: out of memory while writing the scene", file);
    return AP_ERR_NOMEM;
  }
  *yaml = b.s;
  *len = b.len;
  return AP_OK;
}
