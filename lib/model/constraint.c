/* Constraints: rows of A v + a0 = 0 and gamma = -(A' v + a0') (docs/design.md §1), each kind
 * through its table of operations (con_kind.h); here the ground motion shared by the contacts,
 * the loops over the constraints, the kind registry and the subtree forces.
 *
 * With a point's Jacobian JP (3 x K1, column k = rheonomic part) a row c . (JP [v; 1]) gives
 * A = c^T JP[:, 0..k-1] and a0 = c . JP[:, k] minus the ground surface's velocity. The ground
 * surface moves with Vg(p, t) = V(t) + Omega(t) e_z x (p - center); along a point moving at p'
 * its rate is Ag = V' + Omega' e_z x (p - center) + Omega e_z x p'.
 *
 *  rolling   and the wheel's knife edge: rows at the shape's contact point (contact.c).
 *  knife     n = R dir; row n . (vP - Vg(x)) at the body point x (con_knife.c).
 *  speed     row v_j - f(t); gamma = f'(t) (con_speed.c).
 *  user      the callbacks' rows (con_user.c).
 *  loops     phi = n . (xA - xB), n a world axis or fixed on body B (con_loop.c).
 *
 * Per-constraint scratch (CON_STRIDE): Omega, Omega', Vx, Vy, Vx', Vy', f, f' at t.
 * Generic in the scalar (model/model.h; constraint_cs.c): time functions give real values;
 * a user constraint (C callbacks of doubles) makes the complex-step build fail with
 * AP_ERR_UNSUPPORTED naming it; the subtree forces are double build only. */
#include <string.h>

#include "model/con_kind.h"

enum { G_OM = AP_G_OM, G_DOM = AP_G_DOM, G_VX = AP_G_VX, G_VY, G_DVX, G_DVY };

/* ---- time functions ---------------------------------------------------------------------- */

int ap_con_time_call(const ap_model *m, ap_data *d, const ap_mcon *c, const char *what,
                     ap_time_fn fn, void *user, double t, double *f) {
  f[0] = f[1] = f[2] = 0.0;
  int rc = fn(t, f, user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': constraint '%s': %s %s (returned %d) at t = %.17g", m->name,
              c->name, what, rc > 0 ? "asked for a smaller step" : "failed", rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  if (!isfinite(f[0]) || !isfinite(f[1])) {
    AP_BM_MSG(d, "model '%s': constraint '%s': %s gave (%g, %g) at t = %.17g", m->name,
              c->name, what, f[0], f[1], t);
    return AP_ERR_NAN;
  }
  return AP_OK;
}

static int ground_time(const ap_model *m, ap_data *d, const ap_mcon *c, double t, ap_sc *G) {
  const ap_ground_motion *g = &c->def.ground;
  double f[3];
  int rc = AP_OK;
  if (g->kind == AP_GROUND_TURNTABLE) {
    G[G_OM] = g->omega;
    if (g->omega_fn) {
      rc = ap_con_time_call(m, d, c, "the turntable rate Omega(t)", g->omega_fn, g->user, t, f);
      G[G_OM] = f[0], G[G_DOM] = f[1];
    }
  } else if (g->kind == AP_GROUND_TRANSLATING) {
    for (int i = 0; i < 2 && rc == AP_OK; i++) {
      G[G_VX + i] = g->velocity[i];
      if (!g->velocity_fn[i]) continue;
      rc = ap_con_time_call(m, d, c, i ? "the ground velocity V_y(t)" : "the ground velocity V_x(t)",
                     g->velocity_fn[i], g->user, t, f);
      G[G_VX + i] = f[0], G[G_DVX + i] = f[1];
    }
  }
  return rc;
}

int ap_con_time(const ap_model *m, ap_data *d, double t, ap_sc *S) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (!c->timed) continue;
    ap_sc *G = ap_con_scratch(M, S, ci);
    memset(G, 0, CON_STRIDE * sizeof *G);
    int rc = ground_time(m, d, c, t, G);
    if (rc == AP_OK && AP_CON_EVAL(c)->time) rc = AP_CON_EVAL(c)->time(m, d, c, t, G);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

/* A fixed ground (c->timed == 0) has no surface velocity or acceleration: those rheonomic terms
 * are skipped, not evaluated as zeros. */
void ap_con_ground_velocity(const ap_mcon *c, const ap_sc *G, const ap_sc *x, ap_sc *Vg) {
  const double *ctr = c->def.ground.center;
  Vg[2] = 0.0;
  if (!c->timed) {
    Vg[0] = Vg[1] = 0.0;
    return;
  }
  Vg[0] = G[G_VX] - G[G_OM] * (x[1] - ctr[1]);
  Vg[1] = G[G_VY] + G[G_OM] * (x[0] - ctr[0]);
}

void ap_con_ground_accel(const ap_mcon *c, const ap_sc *G, const ap_sc *x, const ap_sc *xd,
                         ap_sc *Ag) {
  const double *ctr = c->def.ground.center;
  Ag[2] = 0.0;
  if (!c->timed) {
    Ag[0] = Ag[1] = 0.0;
    return;
  }
  Ag[0] = G[G_DVX] - G[G_DOM] * (x[1] - ctr[1]) - G[G_OM] * xd[1];
  Ag[1] = G[G_DVY] + G[G_DOM] * (x[0] - ctr[0]) + G[G_OM] * xd[0];
}

/* ---- rows, gamma, implicit holonomic rows: each kind's table (con_kind.h) ------------------- */

void ap_con_loops(const ap_bmodel *M, ap_sc *S, ap_sc *phi, ap_sc *JlT) {
  ap_sc *row = S + M->off_tmp + 6 * (size_t)M->K1;
  int s = 0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    for (int r = c->hrow; r < c->hrow + c->nhol; r++, s++) {
      phi[s] = AP_CON_EVAL(c)->hol(M, S, c, r, row);
      memcpy(JlT + (size_t)s * M->k, row, (size_t)M->k * sizeof *row);
    }
  }
}

int ap_con_rows(const ap_model *m, ap_data *d, double t, const ap_sc *q, ap_sc *S, ap_sc *A,
                ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++) {
    int rc = AP_CON_EVAL(&M->cons[ci])->rows(m, d, ci, t, q, S, A, a0);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

int ap_con_gamma(const ap_model *m, ap_data *d, double t, const ap_sc *q, const ap_sc *v,
                 ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++) {
    int rc = AP_CON_EVAL(&M->cons[ci])->gamma(m, d, ci, t, q, v, S, gamma);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

void ap_con_rolling_gamma(const ap_bmodel *M, ap_sc *S, int ci, int surface, ap_sc *gamma) {
  ap_con_contact_gamma(M, S, ci, ap_con_scratch(M, S, ci), surface, gamma);
}

/* ---- double build: the kinds, reaction forces on a subtree, the tree path's point rows ------ */
#ifndef AP_SC_COMPLEX

const ap_con_kind *const ap_con_kinds[AP_CON_NKINDS] = {
    [AP_CON_ROLLING] = &ap_con_rolling,         [AP_CON_KNIFE_EDGE] = &ap_con_knife,
    [AP_CON_PRESCRIBED_SPEED] = &ap_con_speed,  [AP_CON_USER] = &ap_con_user,
    [AP_CON_COINCIDENT] = &ap_con_coincident,   [AP_CON_POINT_ON_LINE] = &ap_con_on_line,
    [AP_CON_POINT_ON_PLANE] = &ap_con_on_plane};

void ap_bm_add_force(const double *f, const double *x, const double *o, double *F, double *T) {
  v3_axpy(1.0, f, F);
  if (!T) return;
  double r[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
  v3_cross_add(r, f, T);
}

/* Total force (world axes) that the constraint rows with multipliers lambda (g v' + h - Q =
 * A^T lambda) exert on the bodies of the subtree rooted at `root`, except constraint `skip`,
 * after the position stage, and (T != NULL) its moment about the world point o: each kind's
 * wrench (con_kind.h). A user constraint cannot be attributed: AP_ERR_UNSUPPORTED. */
int ap_con_subtree_wrench(const ap_bmodel *M, double *S, const double *lambda, int root,
                          int skip, const double *o, double *F, double *T) {
  F[0] = F[1] = F[2] = 0.0;
  if (T) T[0] = T[1] = T[2] = 0.0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (ci == skip) continue;
    int rc = c->kind->wrench(M, S, c, lambda + c->row, root, o, F, T);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

int ap_con_subtree_force(const ap_bmodel *M, double *S, const double *lambda, int root,
                         int skip, double *F) {
  static const double o[3] = {0, 0, 0};
  return ap_con_subtree_wrench(M, S, lambda, root, skip, o, F, NULL);
}

void ap_con_tree_point_row(const ap_mcon *c, const double *G, const double *o, const double *r,
                           const double *n, const double *rho, double *cv, double *a0) {
  double x[3], Vg[3], cr = 0.0;
  for (int q = 0; q < 3; q++) x[q] = o[q] + r[q];
  ap_con_ground_velocity(c, G, x, Vg);
  v3_cross(r, n, cv);   /* n . (v + w x r) = (r x n) . w + n . v */
  v3_copy(n, cv + 3);
  for (int q = 0; q < 6; q++) cr += cv[q] * rho[q];
  *a0 = cr - v3_dot(n, Vg);
}
#endif
