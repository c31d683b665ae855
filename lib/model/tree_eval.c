/* The tree path's stages (tree_model.h, docs/large.md): the body layer's geometry turned into
 * the forest's inputs (lib/linalg/tree.h), then the sweeps.
 *
 * Position: ap_kin_position on the shadow (positions, plane contacts, rheonomic twists rho_i in
 * the one Jacobian column), then for tree body i: d_i = o_i - o_p; the joint's free columns at
 * o_i, (W; V + r3 x W) with W = R_FP sw, V = R_FP sv (as kinematics.c moves them from the child
 * joint frame to the body origin); the inertia (m, R com, R I R^T); and each row's covector on
 * the body's twist with a0 = c . rho_i minus the ground's velocity, as constraint.c and
 * contact.c write them from a point Jacobian:
 *   knife edge at point r = R p, n = R dir:   c = (r x n; n),   a0 = c . rho - n . Vg(x)
 *   rolling at the contact vector rc:         c = (rc x e_i; e_i), a0 = c . rho - Vg_i (i = x, y);
 *                                             no spin c = (e_z; 0), a0 = e_z . rho_w - Omega
 *   wheel knife edge (plane-contact joint):   n = R e_z at rc, as the knife edge
 *   prescribed speed:                         c = 0, direct term 1, a0 = -f(t).
 * Velocity: twists J v plus rho into the shadow's column, ap_kin_velocity on the shadow (bias
 * accelerations), h = J^T (inertial wrenches), Q = J^T (effect wrenches) plus the effects'
 * joint-space terms, gamma from ap_con_gamma on the shadow, w from the rows with -gamma.
 * Effects as wrenches (t; f) at the body origin (effect.c gives the same as J^T F):
 *   gravity m g at the com; applied F at R p and T; spring +-F at its two points;
 *   joint damping -c v_i, joint forces, motors and user effects straight into Q. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/con_kind.h"
#include "model/tree_model.h"


static double *con_time(const ap_tplan *P, const ap_tree_ws *ws, int ci) {
  return ws->S + P->shadow.off_con + (size_t)ci * CON_STRIDE;
}

/* ---- position ----------------------------------------------------------------------------- */

/* Offsets, free columns, inertias and rheonomic twists of every tree body. */
void ap_tree_geometry(const ap_tplan *P, ap_tree_ws *ws) {
  const ap_bmodel *Ms = &P->shadow;
  const ap_la_tree *T = &P->T;
  for (int i = 0; i < T->nb; i++) {
    const ap_mjoint *J = &P->M->joints[i];
    kbody C = ap_kin_body(Ms, ws->S, P->body[i]);
    kjoint K = ap_kin_joint(Ms, ws->S, i);
    double *rho = ws->rho + 6 * (size_t)i, *M13 = ws->g.M + 13 * (size_t)i;
    if (T->parent[i] >= 0) {
      kbody Pb = ap_kin_body(Ms, ws->S, P->body[T->parent[i]]);
      for (int r = 0; r < 3; r++) ws->g.d[3 * i + r] = C.o[r] - Pb.o[r];
    }
    for (int r = 0; r < 3; r++)
      rho[r] = Ms->ncol ? C.Jw[r] : 0.0, rho[3 + r] = Ms->ncol ? C.Jo[r] : 0.0;
    M13[0] = Ms->bodies[P->body[i]].mass;
    v3_copy(C.rcom, M13 + 1);
    memcpy(M13 + 4, C.Iw, 9 * sizeof(double));
    for (int a = 0, f = T->fofs[i]; a < J->nv; a++) {
      if (J->vidx[a] < 0) continue;
      double sw[3], sv[3], *S6 = ws->g.S + 6 * (size_t)f++;
      ap_joint_column(J, a, K.rc, sw, sv);
      m3_mul_v(K.RFP, sw, S6);
      m3_mul_v(K.RFP, sv, S6 + 3);
      v3_cross_add(K.r3, S6, S6 + 3);
    }
  }
}

/* Row p (on tree body i): its covector into C and its a0 (the kind's tree_row). */
static void row(const ap_tplan *P, ap_tree_ws *ws, int i, int p, double *a0) {
  const ap_bmodel *Ms = &P->shadow;
  const ap_mcon *c = &Ms->cons[P->rcon[p]];
  double *cv = ws->g.C + 6 * (size_t)p;
  memset(cv, 0, 6 * sizeof *cv);
  c->kind->tree_row(Ms, ws->S, c, P->rrow[p], con_time(P, ws, P->rcon[p]),
                    ws->rho + 6 * (size_t)i, cv, a0 + P->T.ridx[p]);
}

static int check_finite(const ap_model *m, ap_data *d, const char *what, const double *x,
                        size_t len) {
  double z = 0.0;   /* x * 0 is 0 for a finite x, NaN for an infinite or NaN one */
  for (size_t i = 0; i < len; i++) z += x[i] * 0.0;
  if (z == 0.0) return AP_OK;
  for (size_t i = 0; i < len; i++)
    if (!isfinite(x[i])) {
      AP_BM_MSG(d, "model '%s': the tree path's %s has %g in entry %zu at t = %.17g", m->name,
                what, x[i], i, d->t);
      return AP_ERR_NAN;
    }
  return AP_OK;
}

static int factor_status(const ap_model *m, ap_data *d, const ap_tplan *P, int rc, int bad) {
  const char *body = bad >= 0 ? P->M->bodies[P->body[bad]].name : "?";
  if (rc == AP_ERR_SINGULAR || rc == AP_ERR_RANK) {
    AP_BM_MSG(d, "model '%s': %s at body '%s' at t = %.17g: re-partition needed", m->name,
              rc == AP_ERR_SINGULAR ? "the dependent speeds' block is singular to working "
              "precision" : "constraint rows left to the parent depend on the body's own speeds",
              body, d->t);
    return AP_RECOVERABLE;
  }
  AP_BM_MSG(d, "model '%s': the constraint rows gathered at body '%s' exceed the tree path's "
            "capacity (%d rows at one body, %d row slots, %d free speeds per tree) at "
            "t = %.17g", m->name, body, P->T.maxrow, P->T.cap, P->lmax, d->t);
  return AP_ERR_UNSUPPORTED;
}

/* Component mode: the dense path's partition, basis and b0 on each tree's block. select:
 * AP_ST_SELECT_STAGE keeps each tree's rank of the partition when rows are redundant only on
 * the manifold (ws->tkeep), as the dense path's orthonormal basis keeps the rank. */
static int comp_factor(const ap_model *m, ap_data *d, ap_tree_ws *ws, int select) {
  const ap_tplan *P = ws->P;
  double growth = 0.0, resid = 0.0;
  int keep = select == AP_ST_SELECT_STAGE && d->redundant_manifold > 0;
  int bad = -1, rc = ap_la_comp_factor(&P->T, &ws->g, &ws->W, &ws->CW, select != 0,
                                       keep ? ws->tkeep : NULL, d->rank_rtol, d->a0, d->b0,
                                       &growth, &resid, &bad);
  if (rc != AP_OK) return factor_status(m, d, P, rc, bad);
  if (select) {
    ap_la_comp_partition(&P->T, &ws->W, &ws->CW, d->perm, &d->rank);
    d->l = m->k - d->rank, d->redundant = m->b - d->rank;
    if (!keep) d->redundant_manifold = 0;
  }
  d->growth = growth, d->resid_a0 = resid;
  return AP_OK;
}

double ap_tree_solve(ap_tree_ws *ws, const double *e, const double *rhs, double *u) {
  const ap_tplan *P = ws->P;
  return P->comp ? ap_la_comp_solve(&P->T, &ws->W, &ws->CW, e, rhs, u)
                 : ap_la_tree_solve(&P->T, &ws->g, &ws->W, e, rhs, u);
}

/* Kinematics, the rows and a0 at (d->t, d->q). */
static int objects(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M;
  int rc = ap_kin_position(&P->sm, d, d->t, d->q, ws->S);
  if (rc == AP_OK && M->nc) rc = ap_con_time(&P->sm, d, d->t, ws->S);
  if (rc != AP_OK) return rc;
  ap_tree_geometry(P, ws);
  for (int i = 0; i < P->T.nb; i++)
    for (int p = P->T.rofs[i]; p < P->T.rofs[i + 1]; p++) row(P, ws, i, p, d->a0);
  rc = check_finite(m, d, "metric (body positions and inertias)", ws->g.M, 13 * (size_t)P->T.nb);
  if (rc == AP_OK) rc = check_finite(m, d, "joint columns", ws->g.S, 6 * (size_t)M->k);
  if (rc == AP_OK) rc = check_finite(m, d, "constraint rows", ws->g.C, 6 * (size_t)M->b);
  if (rc == AP_OK) rc = check_finite(m, d, "constraint (a0)", d->a0, (size_t)M->b);
  return rc;
}

/* After the partition's selection (component mode): are the redundant rows redundant for every
 * q, or only on the holonomic manifold (a free chassis on four wheels with struts)? As the
 * dense path (core/partition.c, nearby_rank): the rank at q + N xi, xi a fixed spread of
 * directions of size 1e-6 max(1, |q|), where the manifold's redundancy is gone. The rank of
 * each tree is kept for projected mode's stages (ws->tkeep); the position stage at q is
 * restored. */
static int manifold_rows(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M;
  int r = d->rank, rn = r, rc = AP_OK;
  if (M->nloop > 0 && d->redundant > 0) {
    double qmax = 1.0;
    for (int i = 0; i < M->n; i++) qmax = fmax(qmax, fabs(d->q[i]));
    memcpy(ws->qn, d->q, sizeof(double) * (size_t)M->n);
    for (int c = 0; c < M->k; c++) ws->x[c] = 1e-6 * qmax * sin(1.3 + 2.1 * c);
    ap_bm_step_q(M, d->q, ws->x);
    if (objects(m, d, ws) == AP_OK && comp_factor(m, d, ws, 1) == AP_OK) rn = d->rank;
    memcpy(d->q, ws->qn, sizeof(double) * (size_t)M->n);
    rc = objects(m, d, ws);
    if (rc == AP_OK) rc = comp_factor(m, d, ws, 1);
    if (rc != AP_OK) return rc;
  }
  d->redundant_manifold = rn > r ? rn - r : 0;
  for (int t = 0; t < P->T.ntree; t++) ws->tkeep[t] = ws->CW.rank[t];
  return AP_OK;
}

static int position(const ap_model *m, ap_data *d, ap_tree_ws *ws, int select,
                    const int *avoid) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M;
  d->cnt.metric++;
  d->cnt.kinematic += M->n != M->k;
  d->cnt.constraint += M->b > 0;
  d->cnt.rheonomic += M->rheonomic;
  int rc = objects(m, d, ws);
  if (rc != AP_OK) return rc;
  double growth = 0.0;
  int bad = -1;
  if (P->comp && !avoid) {   /* avoid: body-local */
    rc = comp_factor(m, d, ws, select);
    return rc == AP_OK && select == AP_ST_SELECT_PARTITION ? manifold_rows(m, d, ws) : rc;
  }
  rc = ap_la_tree_factor(&P->T, &ws->g, &ws->W, select != 0, avoid, d->rank_rtol, &growth,
                         &bad);
  if (rc != AP_OK) return factor_status(m, d, P, rc, bad);
  if (select) {
    ap_la_tree_partition(&P->T, &ws->W, d->perm, &d->rank);
    d->l = M->k - d->rank, d->redundant = M->b - d->rank, d->redundant_manifold = 0;
  }
  d->growth = growth;
  d->resid_a0 = ap_la_tree_solve(&P->T, &ws->g, &ws->W, NULL, d->a0, d->b0);
  ap_la_tree_basis(&P->T, &ws->g, &ws->W);
  return AP_OK;
}

int ap_tree_position(const ap_model *m, ap_data *d, ap_tree_ws *ws, int select) {
  return position(m, d, ws, select, NULL);
}

/* The partition that keeps the given speeds independent where the rows allow it; then
 * v = B e + b0 with e the given values (zero for a free speed the rows leave undetermined),
 * checked against the given values (a given speed that came out dependent must agree). */
int ap_tree_complete_speeds(const ap_model *m, ap_data *d, ap_tree_ws *ws, const int *given,
                            double *v) {
  const ap_tplan *P = ws->P;
  int k = m->k;
  for (int p = 0; p < k; p++) ws->avoid[p] = given[P->T.fidx[p]] != 0;
  int rc = position(m, d, ws, 1, ws->avoid);
  if (rc != AP_OK) return rc;
  ap_la_tree_partition(&P->T, &ws->W, d->perm, &d->rank);
  d->l = k - d->rank, d->redundant = m->b - d->rank, d->redundant_manifold = 0;
  for (int j = 0; j < d->l; j++) d->e[j] = given[d->perm[d->rank + j]] ? v[d->perm[d->rank + j]] : 0.0;
  double resid = ap_la_tree_solve(&P->T, &ws->g, &ws->W, d->e, d->a0, ws->x), worst = 0.0;
  double sc = 1.0;
  if (P->comp && (rc = comp_factor(m, d, ws, 1)) != AP_OK) return rc;   /* its own partition */
  for (int c = 0; c < k; c++)
    if (given[c]) worst = fmax(worst, fabs(ws->x[c] - v[c])), sc = fmax(sc, fabs(v[c]));
  for (int s = 0; s < m->b; s++) sc = fmax(sc, fabs(d->a0[s]));
  if (worst > 1e-9 * sc || resid > 1e-9 * sc) {
    AP_BM_MSG(d, "model '%s': the given speeds leave the constraints violated by %.3g", m->name,
              fmax(worst, resid));
    return AP_ERR_INCONSISTENT;
  }
  memcpy(v, ws->x, sizeof(double) * (size_t)k);
  return AP_OK;
}

/* ---- velocity ----------------------------------------------------------------------------- */

void ap_tree_twists_to_shadow(const ap_tplan *P, ap_tree_ws *ws, const double *v) {
  ap_la_tree_twists(&P->T, &ws->g, v, ws->U);
  for (int i = 0; i < P->T.nb; i++) {
    kbody C = ap_kin_body(&P->shadow, ws->S, P->body[i]);
    const double *U = ws->U + 6 * (size_t)i, *rho = ws->rho + 6 * (size_t)i;
    for (int r = 0; r < 3; r++) C.Jw[r] = U[r] + rho[r], C.Jo[r] = U[3 + r] + rho[3 + r];
  }
}

/* Inertial wrench of a body: f = m ac, t = rcom x f + Iw al + w x Iw w. */
static void bias_wrench(const ap_bmodel *Ms, const double *S, int body, double *F) {
  kbody C = ap_kin_body(Ms, (double *)S, body);
  double ac[3], t[3], Iww[3], m = Ms->bodies[body].mass;
  v3_copy(C.ao, ac);
  v3_cross_add(C.al, C.rcom, ac);
  v3_cross(C.w, C.rcom, t);
  v3_cross_add(C.w, t, ac);
  for (int r = 0; r < 3; r++) F[3 + r] = m * ac[r];
  v3_cross(C.rcom, F + 3, F);
  m3_mul_v(C.Iw, C.al, t);
  m3_mul_v(C.Iw, C.w, Iww);
  v3_cross_add(C.w, Iww, t);
  for (int r = 0; r < 3; r++) F[r] += t[r];
}

/* Add force f at offset r (and torque T) to a body's wrench. */
static void add_force(double *F, const double *r, const double *f, const double *T) {
  v3_cross_add(r, f, F);
  if (T) v3_axpy(1.0, T, F);
  v3_axpy(1.0, f, F + 3);
}

static double *wrench_of(const ap_tplan *P, ap_tree_ws *ws, int body) {
  return ws->F + 6 * (size_t)P->M->bodies[body].joint;
}

static int spring(const ap_model *m, ap_data *d, const ap_tplan *P, ap_tree_ws *ws,
                  const ap_meff *ef) {
  const ap_bmodel *Ms = &P->shadow;
  const ap_effect_def *e = &ef->def;
  double xA[3], xB[3], rA[3], rB[3], vA[3], vB[3], dd[3], dv[3], f[3], mf[3];
  ap_kin_point(Ms, ws->S, e->body, e->point, xA, rA, NULL);
  ap_kin_point(Ms, ws->S, e->body2, e->point2, xB, rB, NULL);
  ap_kin_point_motion(Ms, ws->S, e->body, rA, vA, NULL);
  ap_kin_point_motion(Ms, ws->S, e->body2, rB, vB, NULL);
  for (int i = 0; i < 3; i++) dd[i] = xB[i] - xA[i], dv[i] = vB[i] - vA[i];
  if (e->rest_length == 0.0) {
    for (int i = 0; i < 3; i++) f[i] = e->stiffness * dd[i] + e->damping * dv[i];
  } else {
    double L = v3_norm(dd);
    if (!(L > 1e-12 * P->M->lscale)) {
      AP_BM_MSG(d, "model '%s': spring '%s': its two points coincide (length %g m) at "
                "t = %.17g: the direction of its force is undefined", m->name, ef->name, L, d->t);
      return AP_RECOVERABLE;
    }
    double s = e->stiffness * (L - e->rest_length) + e->damping * v3_dot(dd, dv) / L;
    for (int i = 0; i < 3; i++) f[i] = s * dd[i] / L;
  }
  for (int i = 0; i < 3; i++) mf[i] = -f[i];
  if (e->body >= 0) add_force(wrench_of(P, ws, e->body), rA, f, NULL);
  if (e->body2 >= 0) add_force(wrench_of(P, ws, e->body2), rB, mf, NULL);
  return AP_OK;
}

static int applied(const ap_model *m, ap_data *d, const ap_tplan *P, ap_tree_ws *ws,
                   const ap_meff *ef) {
  const ap_effect_def *e = &ef->def;
  double F[3], T[3], r[3];
  v3_copy(e->force, F);
  v3_copy(e->torque, T);
  if (e->wrench) {
    memset(F, 0, sizeof F);
    memset(T, 0, sizeof T);
    int rc = e->wrench(d->t, F, T, e->user);
    if (rc != 0) {
      AP_BM_MSG(d, "model '%s': effect '%s': the wrench callback %s (returned %d) at t = %.17g",
                m->name, ef->name, rc > 0 ? "asked for a smaller step" : "failed", rc, d->t);
      return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
    }
    for (int i = 0; i < 3; i++)
      if (!isfinite(F[i]) || !isfinite(T[i])) {
        AP_BM_MSG(d, "model '%s': effect '%s': the wrench callback gave a non-finite value at "
                  "t = %.17g", m->name, ef->name, d->t);
        return AP_ERR_NAN;
      }
  }
  ap_kin_point(&P->shadow, ws->S, e->body, e->point, NULL, r, NULL);
  add_force(wrench_of(P, ws, e->body), r, F, T);
  return AP_OK;
}

static int user_effect(const ap_model *m, ap_data *d, ap_tree_ws *ws, const ap_meff *ef) {
  memset(ws->x, 0, sizeof(double) * (size_t)m->k);
  int rc = ef->def.generalized(d->t, d->q, d->v, ws->x, ef->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': effect '%s': the user force callback %s (returned %d) at "
              "t = %.17g", m->name, ef->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, d->t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  for (int c = 0; c < m->k; c++) d->Q[c] += ws->x[c];
  return AP_OK;
}

/* One effect: its wrenches into ws->F, its joint-space terms into d->Q. */
static int one_effect(const ap_model *m, ap_data *d, ap_tree_ws *ws, const ap_meff *ef) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M;
  int rc = AP_OK;
  switch (ef->def.kind) {
    case AP_EFFECT_GRAVITY:
      for (int b = 0; b < M->nb; b++) {
        double f[3];
        for (int r = 0; r < 3; r++) f[r] = M->bodies[b].mass * ef->def.gravity[r];
        add_force(wrench_of(P, ws, b), ap_kin_body(&P->shadow, ws->S, b).rcom, f, NULL);
      }
      break;
    case AP_EFFECT_SPRING: rc = spring(m, d, P, ws, ef); break;
    case AP_EFFECT_JOINT_DAMPING: {
      const ap_mjoint *j = &M->joints[M->joint_topo[ef->def.joint]];
      for (int a = 0; a < j->nv; a++)
        if (j->vidx[a] >= 0) d->Q[j->vidx[a]] -= ef->def.damping * d->v[j->vidx[a]];
      break;
    }
    case AP_EFFECT_APPLIED: rc = applied(m, d, P, ws, ef); break;
    case AP_EFFECT_USER: rc = user_effect(m, d, ws, ef); break;
    case AP_EFFECT_JOINT_FORCE:   /* straight into Q (actuator.c reads t, q, v only) */
    case AP_EFFECT_MOTOR: rc = ap_act_force(m, d, ef, d->t, d->q, d->v, d->Q); break;
  }
  return rc;
}

static int q_ok(const ap_model *m, const ap_data *d) {
  for (int c = 0; c < m->k; c++)
    if (!(fabs(d->Q[c]) <= AP_HUGE)) return 0;
  return 1;
}

/* Q is not finite or past AP_HUGE: evaluate the effects one at a time to name the first that
 * makes it so, in effect.c's words (this path runs only on that error). */
static int name_effect(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  for (int i = 0; i < P->M->ne; i++) {
    const ap_meff *ef = &P->M->effs[i];
    memset(d->Q, 0, sizeof(double) * (size_t)m->k);
    memset(ws->F, 0, sizeof(double) * 6 * (size_t)P->T.nb);
    int rc = one_effect(m, d, ws, ef);
    if (rc != AP_OK) return rc;
    ap_la_tree_force(&P->T, &ws->g, ws->F, d->Q);
    for (int c = 0; c < m->k; c++)
      if (!(fabs(d->Q[c]) <= AP_HUGE)) {
        AP_BM_MSG(d, "model '%s': effect '%s' gives the generalized force %g on speed '%s' at "
                  "t = %.17g%s", m->name, ef->name, d->Q[c], ap_model_speed_name(m, c), d->t,
                  isfinite(d->Q[c]) ? " (more than 1e150 in magnitude: too large to "
                  "integrate)" : "");
        return AP_ERR_NAN;
      }
  }
  return AP_OK;   /* only their sum: the core's check names the entry */
}

/* Q: the effects' wrenches into ws->F, gathered up the tree, and their joint-space terms. */
static int forces(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M;
  memset(ws->F, 0, sizeof(double) * 6 * (size_t)P->T.nb);
  for (int i = 0; i < M->ne; i++) {
    ws->S[P->shadow.off_cnt + i] += 1.0;
    int rc = one_effect(m, d, ws, &M->effs[i]);
    if (rc != AP_OK) return rc;
  }
  ap_la_tree_force(&P->T, &ws->g, ws->F, d->Q);
  return q_ok(m, d) ? AP_OK : name_effect(m, d, ws);
}

int ap_tree_velocity(const ap_model *m, ap_data *d, ap_tree_ws *ws) {
  const ap_tplan *P = ws->P;
  const ap_bmodel *M = P->M, *Ms = &P->shadow;
  int nb = P->T.nb, k = M->k, b = M->b;
  d->cnt.bias++;
  d->cnt.force += M->ne > 0;
  d->cnt.gamma += b > 0;
  ap_tree_twists_to_shadow(P, ws, d->v);
  ap_kin_velocity(Ms, d->v, ws->S);
  for (int i = 0; i < nb; i++) bias_wrench(Ms, ws->S, P->body[i], ws->F + 6 * (size_t)i);
  memset(d->h, 0, sizeof(double) * (size_t)k);
  ap_la_tree_force(&P->T, &ws->g, ws->F, d->h);
  memset(d->Q, 0, sizeof(double) * (size_t)k);
  int rc = M->ne ? forces(m, d, ws) : AP_OK;
  if (rc != AP_OK || b == 0) return rc;
  memset(d->gamma, 0, sizeof(double) * (size_t)b);
  rc = ap_con_gamma(&P->sm, d, d->t, d->q, d->v, ws->S, d->gamma);
  if (rc != AP_OK) return rc;
  for (int s = 0; s < b; s++) ws->rb[s] = -d->gamma[s];   /* A w = gamma */
  d->resid_gamma = ap_tree_solve(ws, NULL, ws->rb, d->w);
  return AP_OK;
}

/* ---- products ----------------------------------------------------------------------------- */

void ap_tree_gmul(ap_tree_ws *ws, const double *x, double *y) {
  ap_la_tree_gmul(&ws->P->T, &ws->g, x, y, ws->U, ws->F);
}

void ap_tree_amul(ap_tree_ws *ws, const ap_data *d, const double *x, int with_a0, double *r,
                  double *mag) {
  ap_la_tree_twists(&ws->P->T, &ws->g, x, ws->U);
  if (mag) ap_la_tree_twists_abs(&ws->P->T, &ws->g, x, ws->F);   /* F: a 6 nb temporary */
  ap_la_tree_rows(&ws->P->T, &ws->g, x, ws->U, with_a0 ? d->a0 : NULL, r, mag ? ws->F : NULL,
                  mag);
}

void ap_tree_nmul(const ap_tplan *P, const double *q, const double *v, double *qdot) {
  const ap_bmodel *M = P->M;
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    for (int i = 0; i < J->ndrivable; i++)
      if (J->qidx[i] >= 0) qdot[J->qidx[i]] = v[J->vidx[i]];
    if (J->quat < 0) continue;
    /* p' = N(p) w with ap_quat_N's N = [-x -y -z; w z -y; -z w x; y -x w] / 2, term by term */
    const double *w = v + J->vidx[J->wofs], *p = q + J->qidx[J->quat];
    double a = 0.5 * p[0], x = 0.5 * p[1], y = 0.5 * p[2], z = 0.5 * p[3];
    double *pd = qdot + J->qidx[J->quat];
    pd[0] = -x * w[0] + -y * w[1] + -z * w[2];
    pd[1] = a * w[0] + z * w[1] + -y * w[2];
    pd[2] = -z * w[0] + a * w[1] + x * w[2];
    pd[3] = y * w[0] + -x * w[1] + a * w[2];
  }
}

/* ---- the operators of the core's structured pipeline (core/structured.h) ------------------ */


static int ops_position(const ap_model *m, ap_data *d, void *ws, int select) {
  return ap_tree_position(m, d, ws, select);
}
static int ops_velocity(const ap_model *m, ap_data *d, void *ws) {
  return ap_tree_velocity(m, d, ws);
}
static void ops_blocks(void *wsp, ap_sblocks *out) {
  const ap_tree_ws *ws = wsp;
  const ap_la_tree_work *W = &ws->W;
  out->n = ws->P->T.ntree;
  out->kofs = W->kofs, out->kidx = ws->P->kspeed;
  out->lofs = W->lofs, out->lidx = W->lidx;
  out->bofs = W->bofs, out->gofs = W->gofs;
  out->B = W->B, out->G = W->G;
}
static void ops_gmul(void *ws, const double *x, double *y) { ap_tree_gmul(ws, x, y); }
static void ops_amul(void *ws, const ap_data *d, const double *x, double *r, double *mag) {
  ap_tree_amul(ws, d, x, 1, r, mag);
}
static void ops_psolve(void *wsp, const double *r, double *u) {
  ap_tree_solve(wsp, NULL, r, u);
}
static void ops_nmul(void *wsp, const double *q, const double *v, double *qdot) {
  const ap_tree_ws *ws = wsp;
  ap_tree_nmul(ws->P, q, v, qdot);
}


/* One allocation: the struct, then the doubles, then the ints. */
static void *ops_ws_create(const void *ctx, size_t *gcap) {
  const ap_tplan *P = ctx;
  size_t head = (sizeof(ap_tree_ws) + sizeof(double) - 1) / sizeof(double);
  double *blk = calloc(head + P->nd + (P->ni * sizeof(int) + sizeof(double) - 1) / sizeof(double) + 1,
                       sizeof(double));
  if (!blk) return NULL;
  ap_tree_ws *ws = (ap_tree_ws *)blk;
  ap_tree_ws_init(P, blk + head, (int *)(blk + head + P->nd), ws);
  *gcap = (size_t)P->T.k * (size_t)P->lmax;
  return ws;
}

static void ops_ws_free(void *ws) { free(ws); }

static void ops_reactions(void *wsp, const double *r, double *lambda) {
  ap_tree_ws *ws = wsp;
  if (ws->P->comp) ap_la_comp_reactions(&ws->P->T, &ws->W, &ws->CW, r, lambda);
  else ap_la_tree_reactions(&ws->P->T, &ws->g, &ws->W, r, lambda, ws->F);
}

static double *ops_ev_scratch(void *wsp) { return ((ap_tree_ws *)wsp)->S; }
static int ops_guard_msg(const void *ws, const char *stage, char *msg, size_t len) {
  return ap_tree_ws_guard_msg(ws, stage, msg, len);
}

void ap_tree_ops(const ap_tplan *P, ap_ops *ops) {
  ap_ops o = {P, ops_ws_create, ops_ws_free, ops_position, ops_velocity, ops_blocks, ops_gmul,
              ops_amul, ops_nmul, ops_psolve, ops_reactions, ops_ev_scratch, ops_guard_msg};
  *ops = o;
}
