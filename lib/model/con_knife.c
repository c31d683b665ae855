/* Constraint kind: the knife edge (skate) at a body point, 1 row: the point has no velocity
 * across the body-fixed direction, relative to the ground surface (constraint.c):
 *
 *     n = R dir;   row n . (vP - Vg(x));
 *     gamma = -((w x n) . (vP - Vg) + n . (aP - Ag)),  aP = ao + al x r + w x (w x r).
 *
 * Its force is lambda n at the point. (A knife edge with def.wheel is the wheel's knife edge
 * at the contact point of a disk or torus: contact.c.) Generic in the scalar (con_knife_cs.c);
 * compile, names, forces and the tree path's row are double build only. */
#include <stdio.h>

#include "model/builder.h"
#include "model/con_kind.h"

static int knife_rows(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q, ap_sc *S,
                      ap_sc *A, ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc *JP = S + M->off_tmp, x[3], n[3], Vg[3];
  (void)d, (void)t, (void)q;
  ap_kin_point_d(M, S, c->def.body, c->def.point, x, NULL, JP);
  m3_mul_v_d(C.R, c->dir, n);
  ap_con_ground_velocity(c, ap_con_scratch(M, S, ci), x, Vg);
  ap_con_put_row(M, A, a0, c->row, n, JP, 0, v3_dot(n, Vg));
  return AP_OK;
}

static int knife_gamma(const ap_model *m, ap_data *d, int ci, double t, const ap_sc *q,
                       const ap_sc *v, ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  const ap_sc *G = ap_con_scratch(M, S, ci);
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc x[3], r[3], vP[3], aP[3], n[3], wn[3], Vg[3], Ag[3], g = 0.0;
  (void)d, (void)t, (void)q, (void)v;
  ap_kin_point_d(M, S, c->def.body, c->def.point, x, r, NULL);
  ap_kin_point_motion(M, S, c->def.body, r, vP, aP);
  m3_mul_v_d(C.R, c->dir, n);
  v3_cross(C.w, n, wn);
  ap_con_ground_velocity(c, G, x, Vg);
  ap_con_ground_accel(c, G, x, vP, Ag);
  for (int i = 0; i < 3; i++) g += wn[i] * (vP[i] - Vg[i]) + n[i] * (aP[i] - Ag[i]);
  gamma[c->row] = -g;
  return AP_OK;
}

const AP_SC(ap_con_eval) AP_SC(ap_con_knife_eval) = {NULL, knife_rows, knife_gamma, NULL};

/* ---- double build: the kind table --------------------------------------------------------- */
#ifndef AP_SC_COMPLEX
extern const struct ap_con_eval_cs ap_con_knife_eval_cs;

/* A knife edge with def.wheel is handed to the wheel's knife edge (contact.c). */
static int knife_compile(ap_builder *b, ap_bmodel *M, const char *nm, ap_mcon *c) {
  if (c->def.wheel) {
    c->kind = &ap_con_wheel_knife;
    return ap_con_wheel_knife.compile(b, M, nm, c);
  }
  int rc = ap_cc_body_ref(b, nm, "body", c->def.body, 0);
  if (rc == AP_OK) rc = ap_cc_ground(b, nm, &c->def.ground);
  if (rc != AP_OK) return rc;
  c->timed = c->def.ground.kind != AP_GROUND_FIXED;
  if (!ap_cc_finite(c->def.point, 3)) return ap_builder_fail(b, "constraint '%s': point not finite", nm);
  c->nrows = 1;
  return ap_cc_unit_direction(b, nm, c->def.direction, c->dir);
}

static const char *knife_suffix(const ap_mcon *c, int r, char *buf) {
  (void)c, (void)r, (void)buf;
  return "";
}

static int knife_wrench(const ap_bmodel *M, double *S, const ap_mcon *c, const double *lam,
                        int root, const double *o, double *F, double *T) {
  if (!ap_bm_in_subtree(M, c->def.body, root)) return AP_OK;
  double n[3], x[3];
  m3_mul_v(ap_kin_body(M, S, c->def.body).R, c->dir, n);
  for (int i = 0; i < 3; i++) n[i] *= lam[0];
  ap_kin_point(M, S, c->def.body, c->def.point, x, NULL, NULL);
  ap_bm_add_force(n, x, o, F, T);
  return AP_OK;
}

static int knife_tree_body(const ap_model *m, const ap_bmodel *M, const ap_mcon *c, char *why,
                           size_t len) {
  (void)m, (void)M, (void)why, (void)len;
  return c->def.body;
}

static void knife_tree_row(const ap_bmodel *Ms, double *S, const ap_mcon *c, int rr,
                           const double *G, const double *rho, double *cv, double *a0) {
  kbody C = ap_kin_body(Ms, S, c->def.body);
  double n[3], r[3];
  (void)rr;
  m3_mul_v(C.R, c->dir, n);
  m3_mul_v(C.R, c->def.point, r);
  ap_con_tree_point_row(c, G, C.o, r, n, rho, cv, a0);
}

const ap_con_kind ap_con_knife = {"knife_edge", knife_compile, knife_suffix, knife_wrench,
                                  knife_tree_body, knife_tree_row, NULL, 0,
                                  &ap_con_knife_eval, &ap_con_knife_eval_cs};
#endif
