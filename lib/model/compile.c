/* ap_builder_compile: validate the definitions once and build the immutable body model.
 *
 * Order: bodies (mass, inertia symmetric, positive definite and physical, shape), joints
 * (references, frames, axes, drives), tree (each body the child of exactly one joint, no
 * cycles; joints sorted parents first), coordinates and speeds (driven ones eliminated),
 * constraints (compile_con.c: references, directions, row layout), effects, degrees of
 * freedom; then names ("disk.x", "disk.qw", "roll.x"), the scratch layout and the ap_model
 * with its evaluator.
 * Every message names the element and the offending number. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/sizes.h"
#include "model/builder.h"
#include "model/tree_model.h"

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

static int finite_n(const double *x, int n) {
  for (int i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

/* ---- bodies ------------------------------------------------------------------------------- */

static int check_shape(ap_builder *b, const char *nm, const ap_shape *s) {
  const double *ax = s->semi_axes;
  switch (s->kind) {
    case AP_SHAPE_NONE:
    case AP_SHAPE_POINT: return AP_OK;
    case AP_SHAPE_SPHERE:
      if (!(s->radius > 0) || !isfinite(s->radius))
        FAIL("body '%s': sphere radius %g m is not positive", nm, s->radius);
      return AP_OK;
    case AP_SHAPE_ELLIPSOID:
      for (int i = 0; i < 3; i++)
        if (!(ax[i] > 0) || !isfinite(ax[i]))
          FAIL("body '%s': ellipsoid semi-axis %d is %g m, not positive", nm, i, ax[i]);
      return AP_OK;
    case AP_SHAPE_DISK:
    case AP_SHAPE_TORUS:
      if (!(s->radius > 0) || !isfinite(s->radius))
        FAIL("body '%s': %s radius %g m is not positive", nm,
             s->kind == AP_SHAPE_DISK ? "disk" : "torus", s->radius);
      if (s->kind == AP_SHAPE_TORUS && (!(s->tube > 0) || !isfinite(s->tube)))
        FAIL("body '%s': torus tube radius %g m is not positive", nm, s->tube);
      if (!(s->flat_tol > 0 && s->flat_tol <= 0.5))
        FAIL("body '%s': flat_tol %g is not in (0, 0.5]", nm, s->flat_tol);
      return AP_OK;
  }
  FAIL("body '%s': unknown shape kind %d", nm, (int)s->kind);
}

static int check_inertia(ap_builder *b, const char *nm, const double *I) {
  if (!finite_n(I, 9)) FAIL("body '%s': the inertia tensor has a non-finite entry", nm);
  double mx = 0.0, lam[3];
  for (int i = 0; i < 9; i++) mx = fmax(mx, fabs(I[i]));
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      if (fabs(I[i + 3 * j] - I[j + 3 * i]) > 1e-9 * mx)
        FAIL("body '%s': inertia tensor not symmetric (I(%d,%d) = %g, I(%d,%d) = %g kg m^2)",
             nm, i, j, I[i + 3 * j], j, i, I[j + 3 * i]);
  ap_sym3_eig(I, lam);
  if (!(lam[0] > 1e-14 * lam[2]) || !(lam[0] > 0))
    FAIL("body '%s': inertia not positive definite (eigenvalue %g kg m^2)", nm, lam[0]);
  if (lam[0] + lam[1] < lam[2] * (1.0 - 1e-9))
    FAIL("body '%s': inertia eigenvalues %g, %g, %g kg m^2 violate the triangle inequality "
         "(%g + %g < %g): no rigid body has them", nm, lam[0], lam[1], lam[2], lam[0], lam[1],
         lam[2]);
  return AP_OK;
}

static int check_bodies(ap_builder *b) {
  for (int i = 0; i < b->nb; i++) {
    const ap_body_def *d = &b->bodies[i].def;
    const char *nm = b->bodies[i].name;
    for (int j = 0; j < i; j++)
      if (strcmp(b->bodies[j].name, nm) == 0)
        FAIL("bodies %d and %d are both named '%s'", j, i, nm);
    if (!(d->mass > 0) || !isfinite(d->mass))
      FAIL("body '%s': mass %g kg is not positive", nm, d->mass);
    if (!finite_n(d->com, 3)) FAIL("body '%s': the centre of mass is not finite", nm);
    int rc = check_inertia(b, nm, d->inertia);
    if (rc == AP_OK) rc = check_shape(b, nm, &d->shape);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

/* ---- joints and the tree -------------------------------------------------------------------- */

static int check_frame(ap_builder *b, const char *nm, const char *which, const ap_frame *f) {
  double qn = sqrt(f->quat[0] * f->quat[0] + f->quat[1] * f->quat[1] + f->quat[2] * f->quat[2] +
                   f->quat[3] * f->quat[3]);
  if (!finite_n(f->pos, 3) || !finite_n(f->quat, 4) || !(qn > 1e-12))
    FAIL("joint '%s': %s frame is not finite or its quaternion is zero (norm %g)", nm, which,
         qn);
  return AP_OK;
}

static int is_default_frame(const ap_frame *f) {
  return f->pos[0] == 0 && f->pos[1] == 0 && f->pos[2] == 0 && f->quat[1] == 0 &&
         f->quat[2] == 0 && f->quat[3] == 0 && f->quat[0] > 0;
}

static int check_plane_contact(ap_builder *b, const ap_bjoint *J) {
  const ap_joint_def *d = &J->def;
  if (d->parent != AP_GROUND)
    FAIL("joint '%s': a plane-contact joint rests on the ground plane; its parent must be "
         "AP_GROUND (got body '%s')", J->name, b->bodies[d->parent].name);
  if (!is_default_frame(&d->parent_frame) || !is_default_frame(&d->child_frame))
    FAIL("joint '%s': a plane-contact joint uses the body origin as the shape centre; leave "
         "parent_frame and child_frame at their defaults", J->name);
  if (b->bodies[d->child].def.shape.kind == AP_SHAPE_NONE)
    FAIL("joint '%s': body '%s' on a plane-contact joint needs a shape", J->name,
         b->bodies[d->child].name);
  return AP_OK;
}

static int check_joint(ap_builder *b, int i) {
  const ap_joint_def *d = &b->joints[i].def;
  const char *nm = b->joints[i].name;
  int nq, nv, ndr, quat, wofs;
  if ((int)d->kind < 0 || (int)d->kind > 6) FAIL("joint '%s': unknown kind %d", nm, (int)d->kind);
  if (d->child < 0 || d->child >= b->nb)
    FAIL("joint '%s': child body %d does not exist (%d bodies defined)", nm, d->child, b->nb);
  if (d->parent != AP_GROUND && (d->parent < 0 || d->parent >= b->nb))
    FAIL("joint '%s': parent body %d does not exist (%d bodies; AP_GROUND = %d)", nm, d->parent,
         b->nb, AP_GROUND);
  if (d->parent == d->child)
    FAIL("joint '%s': body '%s' is its own parent", nm, b->bodies[d->child].name);
  int rc = check_frame(b, nm, "parent", &d->parent_frame);
  if (rc == AP_OK) rc = check_frame(b, nm, "child", &d->child_frame);
  if (rc != AP_OK) return rc;
  if ((d->kind == AP_JOINT_REVOLUTE || d->kind == AP_JOINT_PRISMATIC) &&
      (!finite_n(d->axis, 3) || !(v3_norm(d->axis) > 1e-12)))
    FAIL("joint '%s': the axis (%g, %g, %g) is zero or not finite", nm, d->axis[0], d->axis[1],
         d->axis[2]);
  ap_joint_counts(d->kind, &nq, &nv, &ndr, &quat, &wofs);
  for (int c = ndr; c < 3; c++)
    if (d->drive[c])
      FAIL("joint '%s': coordinate %d of a %s joint cannot be driven (drivable: the first %d; "
           "prescribe an angular velocity with a prescribed-speed constraint instead)", nm, c,
           ap_joint_kind_name(d->kind), ndr);
  return d->kind == AP_JOINT_PLANE_CONTACT ? check_plane_contact(b, &b->joints[i]) : AP_OK;
}

/* Each body is the child of exactly one joint; owner[body] = that joint. */
static int find_owners(ap_builder *b, int *owner) {
  for (int i = 0; i < b->nb; i++) owner[i] = -1;
  for (int j = 0; j < b->nj; j++) {
    int c = b->joints[j].def.child;
    if (owner[c] >= 0)
      FAIL("body '%s' is the child of two joints, '%s' and '%s': the joints must form a tree "
           "(close loops with loop-closure constraints)", b->bodies[c].name,
           b->joints[owner[c]].name, b->joints[j].name);
    owner[c] = j;
  }
  for (int i = 0; i < b->nb; i++)
    if (owner[i] < 0)
      FAIL("body '%s' has no joint: connect it to a parent (AP_JOINT_FREE for a free body)",
           b->bodies[i].name);
  return AP_OK;
}

/* Depth of every joint's child below the ground; cycles never reach the ground. */
static int joint_depths(ap_builder *b, const int *owner, int *depth) {
  for (int j = 0; j < b->nj; j++) {
    int dep = 0, p = b->joints[j].def.parent;
    while (p != AP_GROUND && dep <= b->nb) p = b->joints[owner[p]].def.parent, dep++;
    if (dep > b->nb)
      FAIL("the joints form a cycle through body '%s': bodies must form a tree rooted at the "
           "ground (close loops with loop-closure constraints)",
           b->bodies[b->joints[j].def.child].name);
    depth[j] = dep;
  }
  return AP_OK;
}

static void frame_matrix(const ap_frame *f, double *R, double *p) {
  ap_quat_normalized_matrix(f->quat, R);
  v3_copy(f->pos, p);
}

static void copy_joint(const ap_bjoint *bj, int id, ap_mjoint *J) {
  const ap_joint_def *d = &bj->def;
  memset(J, 0, sizeof *J);
  snprintf(J->name, sizeof J->name, "%s", bj->name);
  J->kind = d->kind, J->id = id, J->parent = d->parent, J->child = d->child;
  frame_matrix(&d->parent_frame, J->Rpf, J->ppf);
  frame_matrix(&d->child_frame, J->Rcf, J->pcf);
  double an = v3_norm(d->axis);
  for (int i = 0; i < 3; i++) J->axis[i] = an > 0 ? d->axis[i] / an : 0.0;
  ap_joint_counts(d->kind, &J->nq, &J->nv, &J->ndrivable, &J->quat, &J->wofs);
  for (int i = 0; i < 3; i++) J->drive[i] = d->drive[i], J->drive_user[i] = d->drive_user[i];
}

/* Joints sorted by depth (stable): parents before children. */
static int order_joints(ap_builder *b, ap_bmodel *M) {
  int *owner = calloc((size_t)b->nb + (size_t)b->nj + 1, sizeof *owner), *depth = owner + b->nb;
  if (!owner) return AP_ERR_NOMEM;
  int rc = find_owners(b, owner);
  if (rc == AP_OK) rc = joint_depths(b, owner, depth);
  for (int dep = 0, t = 0; rc == AP_OK && t < b->nj; dep++)
    for (int j = 0; j < b->nj; j++)
      if (depth[j] == dep) {
        copy_joint(&b->joints[j], j, &M->joints[t]);
        M->joint_topo[j] = t;
        M->bodies[b->joints[j].def.child].joint = t++;
      }
  free(owner);
  return rc;
}

/* Free coordinates and speeds get consecutive indices; driven ones -1 (coordinate i and
 * speed i of a joint are driven together, i < ndrivable). */
static void layout_coords(ap_bmodel *M) {
  int q = 0, v = 0;
  for (int j = 0; j < M->nj; j++) {
    ap_mjoint *J = &M->joints[j];
    for (int i = 0; i < J->nq; i++)
      J->qidx[i] = i < J->ndrivable && J->drive[i] ? -1 : q++;
    for (int i = 0; i < J->nv; i++)
      J->vidx[i] = i < J->ndrivable && J->drive[i] ? -1 : v++;
    for (int i = 0; i < J->ndrivable; i++) J->ndriven += J->drive[i] != NULL;
    M->has_drive |= J->ndriven > 0;
    M->nquat += J->quat >= 0;
  }
  M->n = q, M->k = v, M->K1 = v + 1;
  M->ncol = M->has_drive ? M->K1 : M->k;
}

static int cmp_int(const void *a, const void *b) { return *(const int *)a - *(const int *)b; }

/* The speeds that move each body: those of the joints on its path to the ground. */
static int body_columns(ap_bmodel *M) {
  for (int bd = 0; bd < M->nb; bd++) {
    ap_mbody *B = &M->bodies[bd];
    B->cols = malloc(((size_t)M->k + 1) * sizeof *B->cols);
    if (!B->cols) return AP_ERR_NOMEM;
    for (int p = bd; p >= 0;) {
      const ap_mjoint *J = &M->joints[M->bodies[p].joint];
      for (int i = 0; i < J->nv; i++)
        if (J->vidx[i] >= 0) B->cols[B->ncols++] = J->vidx[i];
      p = J->parent;
    }
    qsort(B->cols, (size_t)B->ncols, sizeof *B->cols, cmp_int);
    int *fit = realloc(B->cols, ((size_t)B->ncols + 1) * sizeof *B->cols);   /* O(ancestors) */
    if (fit) B->cols = fit;
  }
  return AP_OK;
}

static void copy_bodies(ap_builder *b, ap_bmodel *M) {
  for (int i = 0; i < b->nb; i++) {
    ap_mbody *B = &M->bodies[i];
    const ap_body_def *d = &b->bodies[i].def;
    snprintf(B->name, sizeof B->name, "%s", b->bodies[i].name);
    B->mass = d->mass;
    v3_copy(d->com, B->com);
    memcpy(B->I, d->inertia, sizeof B->I);
    B->shape = d->shape;
    double sz = fmax(v3_norm(d->com), d->shape.radius + d->shape.tube);
    for (int k = 0; k < 3; k++) sz = fmax(sz, d->shape.semi_axes[k]);
    M->lscale = fmax(M->lscale, sz);
  }
}

/* ---- effects --------------------------------------------------------------------------------- */

static int check_effect(ap_builder *b, int i) {
  const ap_effect_def *d = &b->effs[i].def;
  const char *nm = b->effs[i].name;
  switch (d->kind) {
    case AP_EFFECT_GRAVITY:
      if (!finite_n(d->gravity, 3)) FAIL("effect '%s': gravity not finite", nm);
      return AP_OK;
    case AP_EFFECT_SPRING:
      if (d->body < 0 || d->body >= b->nb || d->body == d->body2 ||
          (d->body2 != AP_GROUND && (d->body2 < 0 || d->body2 >= b->nb)))
        FAIL("effect '%s': spring bodies %d and %d are not two different bodies (or the ground "
             "as body2)", nm, d->body, d->body2);
      if (!(d->stiffness >= 0) || !(d->damping >= 0) || !(d->rest_length >= 0) ||
          !isfinite(d->stiffness + d->damping + d->rest_length) || !finite_n(d->point, 3) ||
          !finite_n(d->point2, 3))
        FAIL("effect '%s': stiffness %g, damping %g, rest_length %g must be finite and >= 0",
             nm, d->stiffness, d->damping, d->rest_length);
      return AP_OK;
    case AP_EFFECT_JOINT_DAMPING:
      if (d->joint < 0 || d->joint >= b->nj)
        FAIL("effect '%s': joint %d does not exist", nm, d->joint);
      if (!(d->damping >= 0) || !isfinite(d->damping))
        FAIL("effect '%s': damping %g must be >= 0", nm, d->damping);
      return AP_OK;
    case AP_EFFECT_APPLIED:
      if (d->body < 0 || d->body >= b->nb) FAIL("effect '%s': body %d does not exist", nm, d->body);
      if (!finite_n(d->force, 3) || !finite_n(d->torque, 3) || !finite_n(d->point, 3))
        FAIL("effect '%s': force, torque or point not finite", nm);
      return AP_OK;
    case AP_EFFECT_USER:
      if (!d->generalized) FAIL("effect '%s': a user effect needs the generalized callback", nm);
      return AP_OK;
    case AP_EFFECT_JOINT_FORCE:
    case AP_EFFECT_MOTOR: return AP_OK;   /* ap_act_compile, once the joints are laid out */
  }
  FAIL("effect '%s': unknown kind %d", nm, (int)d->kind);
}

/* ---- names and the model --------------------------------------------------------------------- */

static char *dup_name(const char *a, const char *sep, const char *c) {
  size_t len = strlen(a) + strlen(sep) + strlen(c) + 1;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s%s%s", a, sep, c);
  return s;
}

static int name_coords(const ap_bmodel *M, ap_model *m) {
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    const char *bn = M->bodies[J->child].name;
    for (int i = 0; i < J->nq; i++) {
      if (J->qidx[i] < 0) continue;
      m->coord_names[J->qidx[i]] = dup_name(bn, ".", ap_joint_coord_name(J->kind, i));
      if (!m->coord_names[J->qidx[i]]) return AP_ERR_NOMEM;
    }
    for (int i = 0; i < J->nv; i++) {
      if (J->vidx[i] < 0) continue;
      const char *sn = ap_joint_speed_name(J->kind, i);
      m->speed_names[J->vidx[i]] = dup_name(bn, ".", sn);
      if (!m->speed_names[J->vidx[i]]) return AP_ERR_NOMEM;
      int linear = sn[0] == 'v' || !strcmp(sn, "pos_dot") || !strcmp(sn, "x_dot") ||
                   !strcmp(sn, "y_dot");   /* vx vy vz, pos_dot, x_dot y_dot: m/s */
      m->vscale[J->vidx[i]] = linear ? M->lscale : 1.0;
    }
  }
  return AP_OK;
}

static int name_rows(const ap_bmodel *M, ap_model *m) {
  for (int i = 0; i < M->nc; i++) {
    const ap_mcon *c = &M->cons[i];
    for (int r = 0; r < c->nrows; r++) {
      char buf[16];
      if (!(m->constraint_names[c->row + r] = dup_name(c->name, "", ap_con_row_suffix(c, r, buf))))
        return AP_ERR_NOMEM;
    }
  }
  return AP_OK;
}

static int make_model(ap_builder *b, ap_bmodel *M, ap_model **out) {
  ap_model *m = calloc(1, sizeof *m);
  if (!m) return ap_bm_destroy(M), AP_ERR_NOMEM;
  m->n = M->n, m->k = M->k, m->b = M->b;
  snprintf(m->name, sizeof m->name, "%s", b->name);
  m->coord_names = calloc((size_t)M->n + 1, sizeof(char *));
  m->speed_names = calloc((size_t)M->k + 1, sizeof(char *));
  m->constraint_names = calloc((size_t)M->b + 1, sizeof(char *));
  m->vscale = calloc((size_t)M->k + 1, sizeof(double));
  m->ev.impl = M, m->ev.destroy = ap_bm_destroy;   /* from here the model owns M */
  int rc = m->coord_names && m->speed_names && m->constraint_names && m->vscale ? AP_OK
                                                                                : AP_ERR_NOMEM;
  if (rc == AP_OK) rc = name_coords(M, m);
  if (rc == AP_OK) rc = name_rows(M, m);
  if (rc != AP_OK) {
    ap_model_free(m);
    return rc;
  }
  m->sys = ap_system_def_default();
  m->sys.name = m->name;
  m->sys.n = M->n, m->sys.k = M->k, m->sys.b = M->b;
  m->sys.coord_names = (const char *const *)m->coord_names;
  m->sys.speed_names = (const char *const *)m->speed_names;
  m->sys.constraint_names = (const char *const *)m->constraint_names;
  int timed = 0;
  for (int i = 0; i < M->nc; i++) timed |= M->cons[i].timed;
  m->sys.rheonomic = M->rheonomic = M->has_drive || timed;
  m->ev.scratch = M->scratch;
  m->ev.position = ap_bm_position;
  m->ev.velocity = ap_bm_velocity;
  m->ev.project_q = ap_bm_project_q;
  m->ev.check_q = ap_bm_check_q;
  m->nphi = M->nloop + M->nquat;
  m->nhol = M->nloop;
  m->lscale = M->lscale;
  if (m->nphi > 0) m->ev.phi = ap_bm_phi;
  m->ev.position_cs = ap_bm_position_cs, m->ev.velocity_cs = ap_bm_velocity_cs;
  if (m->nphi > 0) m->ev.phi_cs = ap_bm_phi_cs;
  m->ev.cs_blocker = ap_bm_cs_blocker;
  m->ev.layout = &M->layout;
  *out = m;
  return AP_OK;
}

static int compile_all(ap_builder *b, ap_bmodel *M) {
  int rc = check_bodies(b);
  for (int j = 0; rc == AP_OK && j < b->nj; j++) rc = check_joint(b, j);
  if (rc != AP_OK) return rc;
  M->nb = b->nb, M->nj = b->nj, M->nc = b->nc, M->ne = b->ne;
  M->bodies = calloc((size_t)b->nb + 1, sizeof *M->bodies);
  M->joints = calloc((size_t)b->nj + 1, sizeof *M->joints);
  M->joint_topo = calloc((size_t)b->nj + 1, sizeof *M->joint_topo);
  M->cons = calloc((size_t)b->nc + 1, sizeof *M->cons);
  M->effs = calloc((size_t)b->ne + 1, sizeof *M->effs);
  if (!M->bodies || !M->joints || !M->joint_topo || !M->cons || !M->effs) return AP_ERR_NOMEM;
  copy_bodies(b, M);
  rc = order_joints(b, M);
  if (rc != AP_OK) return rc;
  layout_coords(M);
  if (M->k < 1)
    FAIL("model '%s': no degrees of freedom (%d bodies; every joint is fixed or driven)",
         b->name, b->nb);
  rc = ap_compile_constraints(b, M);   /* body_columns: after the choice of the path */
  for (int i = 0; rc == AP_OK && i < b->ne; i++) {
    rc = check_effect(b, i);
    snprintf(M->effs[i].name, sizeof M->effs[i].name, "%s", b->effs[i].name);
    M->effs[i].def = b->effs[i].def;
    if (rc == AP_OK && (b->effs[i].def.kind == AP_EFFECT_JOINT_FORCE ||
                        b->effs[i].def.kind == AP_EFFECT_MOTOR))
      rc = ap_act_compile(b, M, &M->effs[i]);
  }
  for (int j = 0; j < M->nj; j++)
    M->lscale = fmax(M->lscale, fmax(v3_norm(M->joints[j].ppf), v3_norm(M->joints[j].pcf)));
  if (!(M->lscale > 0)) M->lscale = 1.0;
  ap_kin_layout(M);
  char why[256];
  if (rc == AP_OK && ap_arena_check(&M->layout, why, sizeof why) != 0)
    FAIL("model '%s': %s", b->name, why);
  return rc;
}

int ap_builder_compile(ap_builder *b, ap_model **out) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  if (!b) return AP_ERR_ARG;
  b->msg[0] = '\0';
  if (b->nb < 1) FAIL("model '%s': no bodies", b->name);
  ap_bmodel *M = calloc(1, sizeof *M);
  int rc = M ? compile_all(b, M) : AP_ERR_NOMEM;
  if (rc == AP_OK) rc = make_model(b, M, out);   /* M is the model's (or freed) from here */
  else ap_bm_destroy(M);
  if (rc == AP_OK) {                              /* the evaluation path (docs/large.md) */
    rc = ap_tree_attach(*out, b->path, b->msg, sizeof b->msg);
    /* the dense path's columns of each body (its ancestors' speeds: O(N^2) for a chain); the
     * tree path never reads them */
    if (rc == AP_OK && !(*out)->ops)   /* dense arrays LAPACK can index */
      rc = ap_core_check_sizes(b->name, (*out)->n, (*out)->k, (*out)->b, 0, b->msg,
                               sizeof b->msg);
    if (rc == AP_OK && !(*out)->ops) rc = body_columns((ap_bmodel *)(*out)->ev.impl);
    if (rc != AP_OK) ap_model_free(*out), *out = NULL;
  }
  if (rc == AP_ERR_NOMEM) snprintf(b->msg, sizeof b->msg, "model '%s': out of memory", b->name);
  return rc;
}
