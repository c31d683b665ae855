/* Constraint kinds: rows of A v + a0 = 0 and gamma = -(A' v + a0') (docs/design.md §1).
 *
 * With a point's Jacobian JP (3 x K1, column k = rheonomic part) a row c . (JP [v; 1]) gives
 * A = c^T JP[:, 0..k-1] and a0 = c . JP[:, k] minus the ground surface's velocity. The ground
 * surface moves with Vg(p, t) = V(t) + Omega(t) e_z x (p - center); along a point moving at p'
 * its rate is Ag = V' + Omega' e_z x (p - center) + Omega e_z x p'.
 *
 *  rolling   and the wheel's knife edge: rows at the shape's contact point (contact.c).
 *  knife     n = R dir; row n . (vP - Vg(x)) at the body point x;
 *            gamma = -((w x n) . (vP - Vg) + n . (aP - Ag)), aP = ao + al x r + w x (w x r).
 *  speed     row v_j - f(t); gamma = f'(t).
 *  user      the callbacks' rows.
 *  loops     phi = n . (xA - xB), n a world axis (coincident) or fixed on body B (line, plane):
 *            phi' = n . (vA - vB) + (n x d) . wB, d = xA - xB;
 *            gamma = -((alB x n + wB x (wB x n)) . d + 2 (wB x n) . (vA - vB) + n . (aA - aB)).
 *
 * Per-constraint scratch (CON_STRIDE): Omega, Omega', Vx, Vy, Vx', Vy', f, f' at t.
 * Generic in the scalar (model/model.h; constraint_cs.c): time functions give real values;
 * a user constraint (C callbacks of doubles) makes the complex-step build fail with
 * AP_ERR_UNSUPPORTED naming it; the subtree forces are double build only. */
#include <string.h>

#include "model/model.h"

enum { G_OM = AP_G_OM, G_DOM = AP_G_DOM, G_VX, G_VY, G_DVX, G_DVY, G_F, G_FD };

static ap_sc *con_scr(const ap_bmodel *M, ap_sc *S, int c) {
  return S + M->off_con + (size_t)c * CON_STRIDE;
}

/* ---- time functions ---------------------------------------------------------------------- */

static int time_call(const ap_model *m, ap_data *d, const ap_mcon *c, const char *what,
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
      rc = time_call(m, d, c, "the turntable rate Omega(t)", g->omega_fn, g->user, t, f);
      G[G_OM] = f[0], G[G_DOM] = f[1];
    }
  } else if (g->kind == AP_GROUND_TRANSLATING) {
    for (int i = 0; i < 2 && rc == AP_OK; i++) {
      G[G_VX + i] = g->velocity[i];
      if (!g->velocity_fn[i]) continue;
      rc = time_call(m, d, c, i ? "the ground velocity V_y(t)" : "the ground velocity V_x(t)",
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
    ap_sc *G = con_scr(M, S, ci);
    double f[3];
    memset(G, 0, CON_STRIDE * sizeof *G);
    int rc = ground_time(m, d, c, t, G);
    if (rc == AP_OK && c->def.kind == AP_CON_PRESCRIBED_SPEED) {
      G[G_F] = c->def.speed_value;
      if (c->def.speed_fn) {
        rc = time_call(m, d, c, "the prescribed speed f(t)", c->def.speed_fn, c->def.user, t, f);
        G[G_F] = f[0], G[G_FD] = f[1];
      }
    }
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

/* ---- loop rows ---------------------------------------------------------------------------- */

/* The world normal of loop row s and whether it turns with body2. */
static int loop_normal(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s, ap_sc *n) {
  const double *nb = c->dir;
  if (c->def.kind == AP_CON_COINCIDENT) {
    int axis = -1;
    for (int a = 0, seen = 0; a < 3; a++)
      if (c->def.axes & (1u << a) && seen++ == s) axis = a;
    n[0] = n[1] = n[2] = 0.0;
    n[axis] = 1.0;
    return 0;
  }
  if (c->def.kind == AP_CON_POINT_ON_LINE) nb = s == 0 ? c->n1 : c->n2;
  if (c->def.body2 < 0) {
    v3_copy_d(nb, n);
    return 0;
  }
  kbody B = ap_kin_body(M, S, c->def.body2);
  m3_mul_v_d(B.R, nb, n);
  return 1;
}

/* Row s of a loop: residual phi and the K1 coefficients of [v; 1] in row. */
static ap_sc loop_row(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s, ap_sc *row) {
  ap_sc *JA = S + M->off_tmp, *JB = JA + 3 * M->K1;
  ap_sc n[3], xA[3], xB[3], dd[3], nxd[3];
  int rot = loop_normal(M, S, c, s, n);
  ap_kin_point_d(M, S, c->def.body, c->def.point, xA, NULL, JA);
  ap_kin_point_d(M, S, c->def.body2, c->def.point2, xB, NULL, JB);
  for (int i = 0; i < 3; i++) dd[i] = xA[i] - xB[i];
  v3_cross(n, dd, nxd);
  const ap_sc *JwB = rot ? ap_kin_body(M, S, c->def.body2).Jw : NULL;
  for (int col = 0; col < M->K1; col++) {
    ap_sc r = 0.0;
    for (int i = 0; i < 3; i++) r += n[i] * (JA[i + 3 * col] - JB[i + 3 * col]);
    if (JwB) r += v3_dot(nxd, JwB + 3 * col);
    row[col] = r;
  }
  return v3_dot(n, dd);
}

static ap_sc loop_gamma(const ap_bmodel *M, ap_sc *S, const ap_mcon *c, int s) {
  ap_sc n[3], xA[3], xB[3], rA[3], rB[3], vA[3], vB[3], aA[3], aB[3], dd[3], dv[3];
  int rot = loop_normal(M, S, c, s, n);
  ap_kin_point_d(M, S, c->def.body, c->def.point, xA, rA, NULL);
  ap_kin_point_d(M, S, c->def.body2, c->def.point2, xB, rB, NULL);
  ap_kin_point_motion(M, S, c->def.body, rA, vA, aA);
  ap_kin_point_motion(M, S, c->def.body2, rB, vB, aB);
  ap_sc g = 0.0;
  for (int i = 0; i < 3; i++) {
    dd[i] = xA[i] - xB[i], dv[i] = vA[i] - vB[i];
    g += n[i] * (aA[i] - aB[i]);
  }
  if (rot) {
    kbody B = ap_kin_body(M, S, c->def.body2);
    ap_sc wn[3], t1[3], t2[3];
    v3_cross(B.w, n, wn);
    v3_cross(B.al, n, t1);
    v3_cross(B.w, wn, t2);
    for (int i = 0; i < 3; i++) g += (t1[i] + t2[i]) * dd[i] + 2.0 * wn[i] * dv[i];
  }
  return -g;
}

void ap_con_loops(const ap_bmodel *M, ap_sc *S, ap_sc *phi, ap_sc *JlT) {
  ap_sc *row = S + M->off_tmp + 6 * (size_t)M->K1;
  int s = 0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    for (int r = c->hrow; r < c->hrow + c->nhol; r++, s++) {
      phi[s] = c->wheel >= -1 ? ap_contact_hol_row(M, S, c, row) : loop_row(M, S, c, r, row);
      memcpy(JlT + (size_t)s * M->k, row, (size_t)M->k * sizeof *row);
    }
  }
}

/* ---- rows A, a0 ---------------------------------------------------------------------------- */

/* Row r of A and a0 from K1 coefficients minus a free velocity term. */
static void put_row(const ap_bmodel *M, ap_sc *A, ap_sc *a0, int r, const ap_sc *c3,
                    const ap_sc *J, int stride, ap_sc minus) {
  int k = M->k, b = M->b;
  for (int col = 0; col <= k; col++) {
    ap_sc s = c3 ? v3_dot(c3, J + 3 * col) : J[(size_t)col * stride];
    if (col < k) A[r + (size_t)col * b] = s;
    else a0[r] = s - minus;
  }
}

static void knife_rows(const ap_bmodel *M, ap_sc *S, int ci, ap_sc *A, ap_sc *a0) {
  const ap_mcon *c = &M->cons[ci];
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc *JP = S + M->off_tmp, x[3], n[3], Vg[3];
  ap_kin_point_d(M, S, c->def.body, c->def.point, x, NULL, JP);
  m3_mul_v_d(C.R, c->dir, n);
  ap_con_ground_velocity(c, con_scr(M, S, ci), x, Vg);
  put_row(M, A, a0, c->row, n, JP, 0, v3_dot(n, Vg));
}

#ifdef AP_SC_COMPLEX
/* A user constraint's callbacks are C functions of doubles: no complex-step evaluation. */
static int user_cs(const ap_model *m, ap_data *d, int ci) {
  AP_BM_MSG(d, "model '%s': constraint '%s': a user constraint (C callbacks of doubles) has no "
            "complex-step evaluation", m->name, ap_bm(m)->cons[ci].name);
  return AP_ERR_UNSUPPORTED;
}
#define user_rows(m, d, ci, t, q, S, A, a0) ((void)(t), (void)(q), user_cs(m, d, ci))
#define user_gamma(m, d, ci, t, q, v, S, gamma) ((void)(t), (void)(q), (void)(v), user_cs(m, d, ci))
#else
static int user_rows(const ap_model *m, ap_data *d, int ci, double t, const double *q,
                     double *S, double *A, double *a0) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  int nr = c->nrows, k = M->k;
  double *Au = S + M->off_tmp + 6 * (size_t)M->K1 + 2 * (size_t)k, *au = Au + (size_t)nr * k;
  memset(Au, 0, (size_t)nr * (k + 1) * sizeof *Au);
  int rc = c->def.user_constraint(t, q, Au, au, c->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': constraint '%s': the user constraint callback %s (returned %d) "
              "at t = %.17g", m->name, c->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  for (int r = 0; r < nr; r++) {
    for (int col = 0; col < k; col++) A[c->row + r + (size_t)col * M->b] = Au[r + (size_t)col * nr];
    a0[c->row + r] = au[r];
  }
  return AP_OK;
}
#endif

int ap_con_rows(const ap_model *m, ap_data *d, double t, const ap_sc *q, ap_sc *S, ap_sc *A,
                ap_sc *a0) {
  const ap_bmodel *M = ap_bm(m);
  ap_sc *row = S + M->off_tmp + 6 * (size_t)M->K1;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    int rc = AP_OK;
    switch (c->def.kind) {
      case AP_CON_ROLLING: ap_con_contact_rows(M, S, ci, con_scr(M, S, ci), A, a0); break;
      case AP_CON_KNIFE_EDGE:
        if (c->def.wheel) ap_con_contact_rows(M, S, ci, con_scr(M, S, ci), A, a0);
        else knife_rows(M, S, ci, A, a0);
        break;
      case AP_CON_PRESCRIBED_SPEED:
        A[c->row + (size_t)c->col * M->b] = 1.0;
        a0[c->row] = -con_scr(M, S, ci)[G_F];
        break;
      case AP_CON_USER: rc = user_rows(m, d, ci, t, q, S, A, a0); break;
      case AP_CON_COINCIDENT:
      case AP_CON_POINT_ON_LINE:
      case AP_CON_POINT_ON_PLANE:
        for (int r = 0; r < c->nrows; r++) {
          loop_row(M, S, c, r, row);
          put_row(M, A, a0, c->row + r, NULL, row, 1, 0.0);
        }
        break;
    }
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

/* ---- gamma --------------------------------------------------------------------------------- */

void ap_con_rolling_gamma(const ap_bmodel *M, ap_sc *S, int ci, int surface, ap_sc *gamma) {
  ap_con_contact_gamma(M, S, ci, con_scr(M, S, ci), surface, gamma);
}

static void knife_gamma(const ap_bmodel *M, ap_sc *S, int ci, ap_sc *gamma) {
  const ap_mcon *c = &M->cons[ci];
  const ap_sc *G = con_scr(M, S, ci);
  kbody C = ap_kin_body(M, S, c->def.body);
  ap_sc x[3], r[3], vP[3], aP[3], n[3], wn[3], Vg[3], Ag[3], g = 0.0;
  ap_kin_point_d(M, S, c->def.body, c->def.point, x, r, NULL);
  ap_kin_point_motion(M, S, c->def.body, r, vP, aP);
  m3_mul_v_d(C.R, c->dir, n);
  v3_cross(C.w, n, wn);
  ap_con_ground_velocity(c, G, x, Vg);
  ap_con_ground_accel(c, G, x, vP, Ag);
  for (int i = 0; i < 3; i++) g += wn[i] * (vP[i] - Vg[i]) + n[i] * (aP[i] - Ag[i]);
  gamma[c->row] = -g;
}

#ifndef AP_SC_COMPLEX
static int user_gamma(const ap_model *m, ap_data *d, int ci, double t, const double *q,
                      const double *v, double *S, double *gamma) {
  const ap_bmodel *M = ap_bm(m);
  const ap_mcon *c = &M->cons[ci];
  double *gu = S + M->off_tmp + 6 * (size_t)M->K1 + 2 * (size_t)M->k;
  memset(gu, 0, (size_t)c->nrows * sizeof *gu);
  int rc = c->def.user_gamma(t, q, v, gu, c->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': constraint '%s': the user gamma callback %s (returned %d) at "
              "t = %.17g", m->name, c->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  memcpy(gamma + c->row, gu, (size_t)c->nrows * sizeof *gu);
  return AP_OK;
}
#endif

int ap_con_gamma(const ap_model *m, ap_data *d, double t, const ap_sc *q, const ap_sc *v,
                 ap_sc *S, ap_sc *gamma) {
  const ap_bmodel *M = ap_bm(m);
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    int rc = AP_OK;
    switch (c->def.kind) {
      case AP_CON_ROLLING: ap_con_contact_gamma(M, S, ci, con_scr(M, S, ci), 1, gamma); break;
      case AP_CON_KNIFE_EDGE:
        if (c->def.wheel) ap_con_contact_gamma(M, S, ci, con_scr(M, S, ci), 1, gamma);
        else knife_gamma(M, S, ci, gamma);
        break;
      case AP_CON_PRESCRIBED_SPEED: gamma[c->row] = con_scr(M, S, ci)[G_FD]; break;
      case AP_CON_USER: rc = user_gamma(m, d, ci, t, q, v, S, gamma); break;
      case AP_CON_COINCIDENT:
      case AP_CON_POINT_ON_LINE:
      case AP_CON_POINT_ON_PLANE:
        for (int r = 0; r < c->nrows; r++) gamma[c->row + r] = loop_gamma(M, S, c, r);
        break;
    }
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

/* ---- reaction forces on a subtree (contact forces, evaluate.c) ----------------------------- */
#ifndef AP_SC_COMPLEX

/* Total force (world axes) that the constraint rows with multipliers lambda (g v' + h - Q =
 * A^T lambda) exert on the bodies of the subtree rooted at `root`, except constraint `skip`,
 * after the position stage. A row c . (JP v) is the force lambda c at that point: rolling
 * (lambda_x, lambda_y, 0) at the contact point (no-spin: a torque), knife edge lambda n. A loop
 * row n . (vA - vB) + (n x d) . wB is lambda n on body A and -lambda n on body B at the same
 * world point. A prescribed speed acts inside the subtree (equal and opposite on a joint's two
 * bodies) or on the root's plane-contact joint, where vx, vy are horizontal forces and the
 * angular speeds torques. A user constraint cannot be attributed: AP_ERR_UNSUPPORTED. */
int ap_con_subtree_force(const ap_bmodel *M, double *S, const double *lambda, int root,
                         int skip, double *F) {
  F[0] = F[1] = F[2] = 0.0;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    const double *lam = lambda + c->row;
    if (ci == skip) continue;
    switch (c->def.kind) {
      case AP_CON_ROLLING:
        if (ap_bm_in_subtree(M, c->def.body, root)) ap_con_contact_force(M, S, c, lam, F);
        break;
      case AP_CON_KNIFE_EDGE:
        if (c->def.wheel && ap_bm_in_subtree(M, c->def.body, root))
          ap_con_contact_force(M, S, c, lam, F);
        else if (ap_bm_in_subtree(M, c->def.body, root)) {
          double n[3];
          m3_mul_v(ap_kin_body(M, S, c->def.body).R, c->dir, n);
          v3_axpy(lam[0], n, F);
        }
        break;
      case AP_CON_PRESCRIBED_SPEED: {
        const ap_mjoint *j = &M->joints[M->joint_topo[c->def.joint]];
        if (j->child == root && j->kind == AP_JOINT_PLANE_CONTACT && c->def.speed < 2)
          F[c->def.speed] += lam[0];
        break;
      }
      case AP_CON_USER: return AP_ERR_UNSUPPORTED;
      case AP_CON_COINCIDENT:
      case AP_CON_POINT_ON_LINE:
      case AP_CON_POINT_ON_PLANE: {
        int ina = ap_bm_in_subtree(M, c->def.body, root);
        int inb = c->def.body2 >= 0 && ap_bm_in_subtree(M, c->def.body2, root);
        if (ina == inb) break;
        for (int r = 0; r < c->nrows; r++) {
          double n[3];
          loop_normal(M, S, c, r, n);
          v3_axpy(ina ? lam[r] : -lam[r], n, F);
        }
        break;
      }
    }
  }
  return AP_OK;
}
#endif
