/* Effects: generalized active forces Q from the effects a model lists, and their potential.
 *
 * A force F at a body point with Jacobian JP and a torque T on a body give Q += JP^T F + Jw^T T
 * (first k columns; the rheonomic column does no virtual work). Per effect:
 *   gravity         Q += sum_b m_b Jc_b^T gvec;          V = -sum_b m_b gvec . x_com
 *   spring-damper   d = xB - xA, L = |d|, e = d/L: tension f = ks (L - L0) + c e . (vB - vA),
 *                   F_A = f e = -F_B; with L0 = 0: F_A = ks d + c (vB - vA);  V = ks (L - L0)^2/2
 *   joint damping   Q_i -= c v_i for every free speed of the joint
 *   applied         F, T (constants or wrench(t)) at a body point
 *   user            the callback adds to a zeroed k-vector
 *   joint force     Q_i += tau on one joint speed, motors likewise (actuator.c)
 * Each evaluation increments the effect's counter in the data's scratch (only listed effects
 * run: a model without springs never touches spring code).
 * Generic in the scalar (model/model.h; effect_cs.c): wrenches are functions of the real time;
 * a user effect (a C callback of doubles) makes the complex-step build fail with
 * AP_ERR_UNSUPPORTED naming it; the potential and the subtree forces are double build only. */
#include <string.h>

#include "model/model.h"

static void add_JtF(const ap_bmodel *M, const ap_mbody *B, const ap_sc *J, const ap_sc *F,
                    ap_sc *Q) {
  for (int i = 0; i < B->ncols; i++) {
    int c = B->cols[i];
    Q[c] += v3_dot(J + 3 * c, F);
  }
  (void)M;
}

/* The bodies a force between A and B (either may be the ground) can move: their union. */
static void add_pair(const ap_bmodel *M, int a, int b, const ap_sc *JA, const ap_sc *JB,
                     const ap_sc *F, ap_sc *Q) {
  for (int c = 0; c < M->k; c++) {
    ap_sc s = 0.0;
    if (a >= 0) s += v3_dot(JA + 3 * c, F);
    if (b >= 0) s -= v3_dot(JB + 3 * c, F);
    Q[c] += s;
  }
}

static void gravity(const ap_bmodel *M, const ap_effect_def *e, ap_sc *S, ap_sc *Q) {
  for (int b = 0; b < M->nb; b++) {
    const ap_mbody *B = &M->bodies[b];
    kbody C = ap_kin_body(M, S, b);
    ap_sc F[3] = {B->mass * e->gravity[0], B->mass * e->gravity[1], B->mass * e->gravity[2]};
    add_JtF(M, B, C.Jc, F, Q);
  }
}

static int spring(const ap_model *m, ap_data *d, const ap_meff *ef, ap_sc *S, ap_sc *Q) {
  const ap_bmodel *M = ap_bm(m);
  const ap_effect_def *e = &ef->def;
  ap_sc *JA = S + M->off_tmp, *JB = JA + 3 * M->K1;
  ap_sc xA[3], xB[3], rA[3], rB[3], vA[3], vB[3], dd[3], dv[3], F[3];
  ap_kin_point_d(M, S, e->body, e->point, xA, rA, JA);
  ap_kin_point_d(M, S, e->body2, e->point2, xB, rB, JB);
  ap_kin_point_motion(M, S, e->body, rA, vA, NULL);
  ap_kin_point_motion(M, S, e->body2, rB, vB, NULL);
  for (int i = 0; i < 3; i++) dd[i] = xB[i] - xA[i], dv[i] = vB[i] - vA[i];
  if (e->rest_length == 0.0) {
    for (int i = 0; i < 3; i++) F[i] = e->stiffness * dd[i] + e->damping * dv[i];
  } else {
    ap_sc L = v3_norm(dd);
    if (!(SC_RE(L) > 1e-12 * M->lscale)) {
      AP_BM_MSG(d, "model '%s': spring '%s': its two points coincide (length %g m) at "
                "t = %.17g: the direction of its force is undefined", m->name, ef->name,
                SC_RE(L), d->t);
      return AP_RECOVERABLE;
    }
    ap_sc f = e->stiffness * (L - e->rest_length) + e->damping * v3_dot(dd, dv) / L;
    for (int i = 0; i < 3; i++) F[i] = f * dd[i] / L;
  }
  add_pair(M, e->body, e->body2, JA, JB, F, Q);
  return AP_OK;
}

static void joint_damping(const ap_bmodel *M, const ap_effect_def *e, const ap_sc *v,
                          ap_sc *Q) {
  const ap_mjoint *j = &M->joints[M->joint_topo[e->joint]];
  for (int i = 0; i < j->nv; i++)
    if (j->vidx[i] >= 0) Q[j->vidx[i]] -= e->damping * v[j->vidx[i]];
}

static int applied(const ap_model *m, ap_data *d, const ap_meff *ef, double t, ap_sc *S,
                   ap_sc *Q) {
  const ap_bmodel *M = ap_bm(m);
  const ap_effect_def *e = &ef->def;
  ap_sc F[3], T[3], *JP = S + M->off_tmp;
  v3_copy_d(e->force, F);
  v3_copy_d(e->torque, T);
  if (e->wrench) {   /* a function of the real time: real values in both builds */
    double Fw[3] = {0, 0, 0}, Tw[3] = {0, 0, 0};
    int rc = e->wrench(t, Fw, Tw, e->user);
    if (rc != 0) {
      AP_BM_MSG(d, "model '%s': effect '%s': the wrench callback %s (returned %d) at "
                "t = %.17g", m->name, ef->name, rc > 0 ? "asked for a smaller step" : "failed",
                rc, t);
      return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
    }
    for (int i = 0; i < 3; i++)
      if (!isfinite(Fw[i]) || !isfinite(Tw[i])) {
        AP_BM_MSG(d, "model '%s': effect '%s': the wrench callback gave a non-finite value "
                  "at t = %.17g", m->name, ef->name, t);
        return AP_ERR_NAN;
      }
    v3_copy_d(Fw, F), v3_copy_d(Tw, T);
  }
  const ap_mbody *B = &M->bodies[e->body];
  kbody C = ap_kin_body(M, S, e->body);
  ap_kin_point_d(M, S, e->body, e->point, NULL, NULL, JP);
  add_JtF(M, B, JP, F, Q);
  add_JtF(M, B, C.Jw, T, Q);
  return AP_OK;
}

#ifdef AP_SC_COMPLEX
/* A user effect's callback is a C function of doubles: no complex-step evaluation. */
static int user_effect(const ap_model *m, ap_data *d, const ap_meff *ef, double t,
                       const ap_sc *q, const ap_sc *v, ap_sc *S, ap_sc *Q) {
  (void)t, (void)q, (void)v, (void)S, (void)Q;
  AP_BM_MSG(d, "model '%s': effect '%s': a user effect (a C callback of doubles) has no "
            "complex-step evaluation", m->name, ef->name);
  return AP_ERR_UNSUPPORTED;
}
#else
static int user_effect(const ap_model *m, ap_data *d, const ap_meff *ef, double t,
                       const double *q, const double *v, double *S, double *Q) {
  const ap_bmodel *M = ap_bm(m);
  double *Qu = S + M->off_tmp + 6 * (size_t)M->K1;
  memset(Qu, 0, (size_t)M->k * sizeof *Qu);
  int rc = ef->def.generalized(t, q, v, Qu, ef->def.user);
  if (rc != 0) {
    AP_BM_MSG(d, "model '%s': effect '%s': the user force callback %s (returned %d) at "
              "t = %.17g", m->name, ef->name, rc > 0 ? "asked for a smaller step" : "failed",
              rc, t);
    return rc > 0 ? AP_RECOVERABLE : AP_ERR_CALLBACK;
  }
  for (int c = 0; c < M->k; c++) Q[c] += Qu[c];
  return AP_OK;
}
#endif

/* After each effect: Q must stay finite and integrable (AP_HUGE), or this effect is named. */
static int check_effect(const ap_model *m, ap_data *d, const ap_meff *ef, const ap_sc *Q,
                        double t) {
  for (int c = 0; c < m->k; c++)
    if (!(SC_MAG(Q[c]) <= AP_HUGE && SC_IM_FINITE(Q[c]))) {
      AP_BM_MSG(d, "model '%s': effect '%s' gives the generalized force %g on speed '%s' at "
                "t = %.17g%s", m->name, ef->name, SC_RE(Q[c]), ap_model_speed_name(m, c), t,
                SC_FINITE(Q[c]) ? " (more than 1e150 in magnitude: too large to integrate)"
                                : "");
      return AP_ERR_NAN;
    }
  return AP_OK;
}

int ap_eff_forces(const ap_model *m, ap_data *d, double t, const ap_sc *q, const ap_sc *v,
                  ap_sc *S, ap_sc *Q) {
  const ap_bmodel *M = ap_bm(m);
  for (int i = 0; i < M->ne; i++) {
    const ap_meff *ef = &M->effs[i];
    int rc = AP_OK;
    S[M->off_cnt + i] += 1.0;
    switch (ef->def.kind) {
      case AP_EFFECT_GRAVITY: gravity(M, &ef->def, S, Q); break;
      case AP_EFFECT_SPRING: rc = spring(m, d, ef, S, Q); break;
      case AP_EFFECT_JOINT_DAMPING: joint_damping(M, &ef->def, v, Q); break;
      case AP_EFFECT_APPLIED: rc = applied(m, d, ef, t, S, Q); break;
      case AP_EFFECT_USER: rc = user_effect(m, d, ef, t, q, v, S, Q); break;
      case AP_EFFECT_JOINT_FORCE:
      case AP_EFFECT_MOTOR: rc = ap_act_force(m, d, ef, t, q, v, Q); break;
    }
    if (rc == AP_OK) rc = check_effect(m, d, ef, Q, t);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

#ifndef AP_SC_COMPLEX
double ap_eff_potential(const ap_bmodel *M, double *S) {
  double V = 0.0;
  for (int i = 0; i < M->ne; i++) {
    const ap_effect_def *e = &M->effs[i].def;
    if (e->kind == AP_EFFECT_GRAVITY) {
      for (int b = 0; b < M->nb; b++) {
        kbody C = ap_kin_body(M, S, b);
        double x[3] = {C.o[0] + C.rcom[0], C.o[1] + C.rcom[1], C.o[2] + C.rcom[2]};
        V -= M->bodies[b].mass * v3_dot(e->gravity, x);
      }
    } else if (e->kind == AP_EFFECT_SPRING) {
      double xA[3], xB[3], dd[3];
      ap_kin_point(M, S, e->body, e->point, xA, NULL, NULL);
      ap_kin_point(M, S, e->body2, e->point2, xB, NULL, NULL);
      for (int j = 0; j < 3; j++) dd[j] = xB[j] - xA[j];
      double ext = v3_norm(dd) - e->rest_length;
      V += 0.5 * e->stiffness * ext * ext;
    }
  }
  return V;
}

/* ---- forces on a subtree (contact forces, evaluate.c) -------------------------------------- */

/* Total force (world axes) of the effects on the bodies of the subtree rooted at `root` (a
 * plane-contact body), after ap_kin_velocity at the same state. Gravity and applied forces on
 * its bodies count; a spring counts at the end in the subtree (nothing when both are); joint
 * damping inside the subtree is internal, and on the root's plane-contact joint it is the
 * horizontal force -c (vx, vy) plus torques. Joint forces and motors are left out: between
 * bodies of the subtree they are internal, and on the root's plane-contact joint they are a
 * horizontal force (vx, vy) or a pure torque, which the contact force (it reads only F[2],
 * the normal) does not need; F[0], F[1] do not include them. A user effect's generalized
 * force cannot be attributed to bodies: AP_ERR_UNSUPPORTED. */
int ap_eff_subtree_force(const ap_bmodel *M, double *S, double t, const double *v, int root,
                         double *F) {
  static const double o[3] = {0, 0, 0};
  return ap_eff_subtree_wrench(M, S, t, v, root, o, F, NULL);
}

/* Joint damping on the root's own joint to the ground (plane contact or planar): the force
 * -c v along the joint's x, y axes (at the contact point, or the body origin of a planar
 * joint) and the torque -c w about its rotation axes. */
static void root_damping(const ap_bmodel *M, double *S, const ap_effect_def *e, const double *v,
                         int root, const double *o, double *F, double *T) {
  const ap_mjoint *j = &M->joints[M->joint_topo[e->joint]];
  int pc = j->kind == AP_JOINT_PLANE_CONTACT;
  if (j->child != root || j->parent != AP_GROUND || (!pc && j->kind != AP_JOINT_PLANAR)) return;
  kjoint K = ap_kin_joint(M, S, M->joint_topo[e->joint]);
  kbody C = ap_kin_body(M, S, root);
  for (int s = 0; s < j->nv; s++) {
    if (j->vidx[s] < 0) continue;
    double f = -e->damping * v[j->vidx[s]], dir[3], x[3];
    int axis = s < 2 ? s : pc ? s - 2 : 2;
    for (int i = 0; i < 3; i++) dir[i] = f * (pc ? (double)(i == axis) : K.RFP[i + 3 * axis]);
    if (s >= 2) {
      if (T) v3_axpy(1.0, dir, T);
      continue;
    }
    for (int i = 0; i < 3; i++) x[i] = C.o[i] + (pc ? K.rc[i] : 0.0);
    ap_bm_add_force(dir, x, o, F, T);
  }
}

/* The same as a wrench: the force F and (T != NULL) its moment T about the world point o. */
int ap_eff_subtree_wrench(const ap_bmodel *M, double *S, double t, const double *v, int root,
                          const double *o, double *F, double *T) {
  F[0] = F[1] = F[2] = 0.0;
  if (T) T[0] = T[1] = T[2] = 0.0;
  for (int i = 0; i < M->ne; i++) {
    const ap_effect_def *e = &M->effs[i].def;
    switch (e->kind) {
      case AP_EFFECT_GRAVITY:
        for (int b = 0; b < M->nb; b++) {
          if (!ap_bm_in_subtree(M, b, root)) continue;
          kbody C = ap_kin_body(M, S, b);
          double f[3], x[3];
          for (int q = 0; q < 3; q++)
            f[q] = M->bodies[b].mass * e->gravity[q], x[q] = C.o[q] + C.rcom[q];
          ap_bm_add_force(f, x, o, F, T);
        }
        break;
      case AP_EFFECT_SPRING: {
        int ina = e->body >= 0 && ap_bm_in_subtree(M, e->body, root);
        int inb = e->body2 >= 0 && ap_bm_in_subtree(M, e->body2, root);
        if (ina == inb) break;
        double xA[3], xB[3], rA[3], rB[3], vA[3], vB[3], dd[3], dv[3], f[3];
        ap_kin_point(M, S, e->body, e->point, xA, rA, NULL);
        ap_kin_point(M, S, e->body2, e->point2, xB, rB, NULL);
        ap_kin_point_motion(M, S, e->body, rA, vA, NULL);
        ap_kin_point_motion(M, S, e->body2, rB, vB, NULL);
        for (int j = 0; j < 3; j++) dd[j] = xB[j] - xA[j], dv[j] = vB[j] - vA[j];
        double L = v3_norm(dd);
        if (e->rest_length == 0.0) {
          for (int j = 0; j < 3; j++) f[j] = e->stiffness * dd[j] + e->damping * dv[j];
        } else {
          if (!(L > 0)) return AP_ERR_SINGULAR;
          double s = e->stiffness * (L - e->rest_length) + e->damping * v3_dot(dd, dv) / L;
          for (int j = 0; j < 3; j++) f[j] = s * dd[j] / L;
        }
        if (!ina)
          for (int j = 0; j < 3; j++) f[j] = -f[j];   /* f acts on A, -f on B */
        ap_bm_add_force(f, ina ? xA : xB, o, F, T);
        break;
      }
      case AP_EFFECT_JOINT_DAMPING: root_damping(M, S, e, v, root, o, F, T); break;
      case AP_EFFECT_APPLIED: {
        if (!ap_bm_in_subtree(M, e->body, root)) break;
        double f[3] = {e->force[0], e->force[1], e->force[2]}, Tq[3] = {0, 0, 0}, x[3];
        if (e->wrench) {
          f[0] = f[1] = f[2] = 0.0;
          if (e->wrench(t, f, Tq, e->user) != 0) return AP_ERR_CALLBACK;
        } else {
          v3_copy(e->torque, Tq);
        }
        ap_kin_point(M, S, e->body, e->point, x, NULL, NULL);
        ap_bm_add_force(f, x, o, F, T);
        if (T) v3_axpy(1.0, Tq, T);
        break;
      }
      case AP_EFFECT_USER: return AP_ERR_UNSUPPORTED;
      case AP_EFFECT_JOINT_FORCE:
      case AP_EFFECT_MOTOR: break;   /* see above */
    }
  }
  return AP_OK;
}
#endif
