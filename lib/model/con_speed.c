/* Constraint kind: a prescribed speed, 1 row: speed v_j of a joint equals f(t),
 *
 *     row v_j - f(t),   a0 = -f(t),   gamma = f'(t),
 *
 * f and f' are evaluated once per time into the constraint's time scratch (AP_G_F, AP_G_FD).
 * Its force acts inside the subtree (equal and opposite on the joint's two bodies) or, on the
 * root's plane-contact joint, is a horizontal force (vx, vy). Generic in the scalar
 * (con_speed_cs.c); compile, names, forces and the tree path's row are double build only. */
#include <stdio.h>

#include "model/builder.h"
#include "model/con_kind.h"

static int speed_time(const ap_model *m, ap_data *d, const ap_mcon *c, double t, ap_sc *G) {
  double f[3];
  G[AP_G_F] = c->def.speed_value;
  if (!c->def.speed_fn) return AP_OK;
  int rc = ap_con_time_call(m, d, c, "the prescribed speed f(t)", c->def.speed_fn, c->def.user,
                            t, f);
  G[AP_G_F] = f[0], G[AP_G_FD] = f[1];
  return rc;
}

static int speed_rows(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, ap_sc *S,
                      ap_sc *A, ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  (void)d, (void)t, (void)q;
  A[c->row + (size_t)c->col * M->b] = 1.0;
  a0[c->row] = -ap_con_scratch(M, S, ci)[AP_G_F];
  return AP_OK;
}

static int speed_gamma(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                       const ap_sc *v, ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  (void)d, (void)t, (void)q, (void)v;
  gamma[M->cons[ci].row] = ap_con_scratch(M, S, ci)[AP_G_FD];
  return AP_OK;
}

const AP_SC(ap_con_eval) AP_SC(ap_con_speed_eval) = {speed_time, speed_rows, speed_gamma, NULL};

/* ---- double build: the kind table --------------------------------------------------------- */
#ifndef AP_SC_COMPLEX
extern const struct ap_con_eval_cs ap_con_speed_eval_cs;

#define FAIL(...) return ap_builder_fail(b, __VA_ARGS__)

static int speed_compile(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  const ap_constraint_def *d = &c->def;
  if (d->joint < 0 || d->joint >= b->nj)
    FAIL("constraint '%s': joint %d does not exist (%d joints)", nm, d->joint, b->nj);
  const ap_mjoint *J = &M->joints[M->joint_topo[d->joint]];
  if (d->speed < 0 || d->speed >= J->nv)
    FAIL("constraint '%s': joint '%s' has %d speeds, not speed %d", nm, J->name, J->nv, d->speed);
  if (J->vidx[d->speed] < 0)
    FAIL("constraint '%s': speed %d of joint '%s' is driven (eliminated) already", nm, d->speed,
         J->name);
  if (!isfinite(d->speed_value)) FAIL("constraint '%s': speed_value is not finite", nm);
  c->col = J->vidx[d->speed], c->nrows = 1, c->timed = 1;
  return AP_OK;
}

static const char *speed_suffix(const ap_mcon *c, int r, char *buf) {
  (void)c, (void)r, (void)buf;
  return "";
}

/* Inside the subtree the joint's force is internal. On the root's own joint to the ground
 * (plane contact or planar) the translation speeds vx, vy are a force along the joint's x, y
 * axes (through the contact point, or the body origin for a planar joint: a pure translation
 * does not fix the line of action, the joint's other reactions take the rest) and the heading
 * a torque about the joint's normal. */
static int speed_wrench(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                        int root, const double *o, double *F, double *T) {
  const ap_mjoint *j = &M->joints[M->joint_topo[c->def.joint]];
  int s = c->def.speed, pc = j->kind == AP_JOINT_PLANE_CONTACT;
  if (j->child != root || j->parent != AP_GROUND || (!pc && j->kind != AP_JOINT_PLANAR))
    return AP_OK;
  kjoint K = ap_kin_joint(M, S, M->joint_topo[c->def.joint]);
  kbody C = ap_kin_body(M, S, root);
  double e[3], x[3];
  int axis = s < 2 ? s : pc ? s - 2 : 2;   /* plane contact: wx, wy, wz; planar: heading */
  for (int i = 0; i < 3; i++) e[i] = pc ? (double)(i == axis) : K.RFP[i + 3 * axis];
  if (s >= 2) {   /* a torque: no force */
    if (T) v3_axpy(lam[0], e, T);
    return AP_OK;
  }
  for (int i = 0; i < 3; i++) x[i] = C.o[i] + (pc ? K.rc[i] : 0.0), e[i] *= lam[0];
  ap_bm_add_force(e, x, o, F, T);
  return AP_OK;
}

static int speed_tree_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                           size_t len) {
  (void)m, (void)why, (void)len;
  return M->joints[M->joint_topo[c->def.joint]].child;
}

static void speed_tree_row(const ap_bmodel *Ms, double *S, const ap_mcon *c, int rr,
                           const double *G, const double *rho, double *cv, double *a0) {
  (void)Ms, (void)S, (void)c, (void)rr, (void)rho, (void)cv;
  *a0 = -G[AP_G_F];   /* c = 0, a direct term 1 on the speed */
}

const ap_con_kind ap_con_speed = {"prescribed_speed", speed_compile, speed_suffix,
                                  speed_wrench, speed_tree_body, speed_tree_row, NULL, 0,
                                  &ap_con_speed_eval, &ap_con_speed_eval_cs};
#endif
