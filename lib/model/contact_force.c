/* The force of the ground on a rolling body, public ap_body_contact_force (docs/bodies.md
 * "Contact forces"): a free body's from Newton's law over its subtree, a wheel's (and a
 * plane-contact body's in a planar chassis' group) from its share of the vehicle's load
 * (loads.c). Reads the data's evaluation; writes only the model's scratch on the dense path
 * and its own memory on the tree path. */
#include <stdlib.h>
#include <string.h>

#include "model/con_friction.h"
#include "model/con_kind.h"
#include "model/tree_model.h"   /* the tree path's layout and queries (m->ops) */

int ap_bm_in_subtree(const ap_bmodel *M, int body, int root) {
  while (body >= 0) {
    if (body == root) return 1;
    body = M->joints[M->bodies[body].joint].parent;
  }
  return 0;
}

static void finish_force(const ap_mcon *c, const double *lam, ap_contact_force *out) {
  out->tangential = hypot(out->force[0], out->force[1]);
  out->friction_ratio = out->normal > 0 ? out->tangential / out->normal : HUGE_VAL;
  out->spin_torque = c->def.no_spin ? lam[c->row + 2] : 0.0;
  out->lift_off = out->normal < 0;
}

/* A wheel contact, or a plane-contact body joined to a planar chassis by loops: its share of
 * its vehicle's load (loads.c). */
static int wheel_force(const ap_model *m, const ap_data *d, const ap_mcon *c, int ci,
                       const double *lam, ap_contact_force *out) {
  const ap_bmodel *M = ap_bm(m);
  double *S = ap_bm_scratch(d);
  memset(out, 0, sizeof *out);
  ap_bm_contact_point(M, S, c, out->point);
  out->force[0] = lam[c->row], out->force[1] = lam[c->row + 1];
  int rc = ap_bm_wheel_load(m, d, lam, ci, &out->normal, &out->load, &out->ncontacts);
  out->force[2] = out->normal;
  if (c->fric >= 0) ap_cfr_friction_force(M, S, c, out->normal, NULL, NULL, out->force);
  finish_force(c, lam, out);
  if (c->plane) {   /* a tilted plane or a sphere: tangents and normal to world axes */
    double t0 = out->force[0], t1 = out->force[1], n[3], e1[3], e2[3];
    ap_contact_frame(M, S, c, n, e1, e2);
    for (int i = 0; i < 3; i++) out->force[i] = t0 * e1[i] + t1 * e2[i] + out->normal * n[i];
  }
  return rc;
}

/* The force of the ground on a rolling body (docs/bodies.md "Contact forces"). Tangential: the
 * rolling rows are e_i . vP with vP the material contact point, so A^T lambda = JP^T
 * (lambda_x, lambda_y, 0): the friction force itself. Normal: the plane-contact joint carries
 * it without a multiplier (z is not a coordinate; the contact point's vertical velocity is
 * identically zero, so the force does no virtual work), so it comes from Newton's law for the
 * vertical over the body's subtree T:
 *     F_n = e_z . (sum_T m_b a_b - F_effects(T) - F_other constraints(T)),
 * a_b = Jc_b v' + ac_b the centre-of-mass accelerations at the data's v'. */
int ap_body_contact_force(const ap_model *m, const ap_data *d, const double *lambda,
                          int constraint, ap_contact_force *out) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !out) return AP_ERR_ARG;
  const ap_bmodel *M = ap_tree_layout(m);
  if (constraint < 0 || constraint >= M->nc || !M->cons[constraint].kind->contact)
    return AP_ERR_ARG;
  const ap_mcon *c = &M->cons[constraint];
  const double *lam = lambda ? lambda : d->lambda, *vd = d->vdot;
  double *S = ap_bm_scratch(d), ma[3] = {0, 0, 0}, Fe[3], Fc[3];
  if (c->wheel >= 0 && m->ops) return AP_ERR_UNSUPPORTED;   /* wheel loads: dense path only */
  if (c->wheel >= 0 || (!m->ops && ap_bm_plane_in_group(M, c)))
    return wheel_force(m, d, c, constraint, lam, out);
  int root = c->def.body, k = M->k;
  /* tree path: the twists of v' in this call's own memory (d is shared: read only) */
  const ap_tree_ws *ws = m->ops ? ap_tree_ws_of(d) : NULL;
  double *U = ws ? malloc(sizeof(double) * ap_tree_twist_len(ws)) : NULL;
  if (ws && !U) return AP_ERR_NOMEM;
  if (ws) ap_tree_com_accel(ws, vd, -1, U, NULL);
  for (int b = 0; b < M->nb; b++) {
    if (!ap_bm_in_subtree(M, b, root)) continue;
    kbody C = ap_kin_body(M, S, b);
    double a[3], t[3];
    if (ws) {   /* tree path: J_b v' from the twists, plus the bias */
      ap_tree_com_accel(ws, vd, b, U, a);
      v3_axpy(M->bodies[b].mass, a, ma);
      continue;
    }
    v3_copy(C.ao, a);                     /* com bias: ao + al x rc + w x (w x rc) */
    v3_cross_add(C.al, C.rcom, a);
    v3_cross(C.w, C.rcom, t);
    v3_cross_add(C.w, t, a);
    for (int col = 0; col < k; col++) v3_axpy(vd[col], C.Jc + 3 * col, a);
    v3_axpy(M->bodies[b].mass, a, ma);
  }
  free(U);
  int rc = ap_eff_subtree_force(M, S, d->t, d->v, root, Fe);
  if (rc == AP_OK) rc = ap_con_subtree_force(M, S, lam, root, constraint, Fc);
  if (rc != AP_OK) return rc;
  kbody C = ap_kin_body(M, S, root);
  kjoint J = ap_kin_joint(M, S, M->bodies[root].joint);
  memset(out, 0, sizeof *out);
  for (int i = 0; i < 3; i++) out->point[i] = C.o[i] + J.rc[i];
  out->point[2] = 0.0;
  out->force[0] = lam[c->row], out->force[1] = lam[c->row + 1];
  out->force[2] = out->normal = ma[2] - Fe[2] - Fc[2];
  out->ncontacts = 1;
  finish_force(c, lam, out);
  return AP_OK;
}
