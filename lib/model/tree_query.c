/* Body queries on the tree path (body.h's ap_body_* on a data whose model evaluates by sweeps;
 * tree_model.h). The shadow's scratch holds every body's position, velocity and bias
 * acceleration in the body layer's own layout, so most queries read it as they read the dense
 * path's; what the dense path takes from a body's Jacobian columns is rebuilt here:
 *
 *   Jacobian of a body point: the free columns of the joints on the body's path to the ground,
 *     each moved from its body's origin o_a to the point x:  (W; V + W x (x - o_a))
 *   acceleration of a body's centre of mass at v':  J_b v' (the twists of v', one sweep down)
 *     moved to the com, plus the bias ao + al x rcom + w x (w x rcom). */
#include <string.h>

#include "model/tree_model.h"

int ap_tree_body_eval(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  int rc = ap_kin_position(&P->sm, d, d->t, d->q, ws->S);
  if (rc == AP_OK && P->M->nc) rc = ap_con_time(&P->sm, d, d->t, ws->S);
  if (rc != AP_OK) return rc;
  ap_tree_geometry(P, ws);
  ap_tree_twists_to_shadow(P, ws, d->v);
  ap_kin_velocity(&P->shadow, d->v, ws->S);
  (void)m;
  return AP_OK;
}

void ap_tree_point_jacobian(const ap_tree_ws *ws, int body, const double *x, double *Jw,
                            double *Jv) {
  const ap_tplan *P = ws->P;
  const ap_la_tree *T = &P->T;
  size_t k = (size_t)T->k;
  memset(Jw, 0, 3 * k * sizeof *Jw);
  memset(Jv, 0, 3 * k * sizeof *Jv);
  for (int i = P->M->bodies[body].joint; i >= 0; i = T->parent[i]) {
    kbody A = ap_kin_body(&P->shadow, ws->S, P->body[i]);
    double r[3] = {x[0] - A.o[0], x[1] - A.o[1], x[2] - A.o[2]};
    for (int c = T->fofs[i]; c < T->fofs[i + 1]; c++) {
      const double *S6 = ws->g.S + 6 * (size_t)c;
      double *jw = Jw + 3 * (size_t)T->fidx[c], *jv = Jv + 3 * (size_t)T->fidx[c];
      v3_copy(S6, jw);
      v3_copy(S6 + 3, jv);
      v3_cross_add(S6, r, jv);
    }
  }
}

void ap_tree_com_accel(const ap_tree_ws *ws, const double *vdot, int body, double *U,
                       double *a) {
  const ap_tplan *P = ws->P;
  if (body < 0) {   /* the twists J v' for every body, once per v' */
    ap_la_tree_twists(&P->T, &ws->g, vdot, U);
    return;
  }
  kbody C = ap_kin_body(&P->shadow, ws->S, body);
  U += 6 * (size_t)P->M->bodies[body].joint;
  double t[3];
  v3_copy(C.ao, a);
  v3_cross_add(C.al, C.rcom, a);
  v3_cross(C.w, C.rcom, t);
  v3_cross_add(C.w, t, a);
  v3_axpy(1.0, U + 3, a);
  v3_cross_add(U, C.rcom, a);
}
