/* The body model's evaluator hooks on the per-evaluation path (core/core.h): the position and
 * velocity stages and the implicit holonomic rows phi.
 *
 * Position stage: kinematics at (t, q) -> g, N (quaternion blocks), A, a0.
 * Velocity stage: body velocities and bias accelerations at v -> h, Q, gamma.
 * Counters (d->cnt, as the core counts a math-level system's callbacks): metric, kinematic
 * (n != k), constraint (b > 0) and rheonomic (drives or timed constraints only) per position
 * stage; bias, force (effects listed) and gamma (b > 0) per velocity stage. A stage's piece
 * that the model does not have is skipped and not counted.
 * Generic in the scalar (model/model.h): hooks_cs.c compiles this file again into
 * ap_bm_position_cs, ap_bm_velocity_cs and ap_bm_phi_cs, the model's ev.position_cs,
 * ev.velocity_cs and ev.phi_cs. The projection after steps and the public queries are in
 * evaluate.c (double only). */
#include "model/con_friction.h"
#include "model/model.h"

static int bm_position(const ap_model *m, ap_data *d, ap_sc *S, const ap_bm_fast *F) {
  const ap_bmodel *M = ap_bm(m);
  d->cnt.metric++;
  d->cnt.kinematic += M->n != M->k;
  d->cnt.constraint += M->b > 0;
  d->cnt.rheonomic += M->rheonomic;
#ifndef AP_SC_COMPLEX
  int rc = F ? F->position(F, m, d, S) : ap_kin_position(m, d, d->t, d->q, S);
  if (F && F->rows && rc == AP_OK) return F->rows(F, m, d, S);   /* lib/codegen fast_rows.c */
  if (F && rc == AP_OK && M->nwheel) rc = ap_contact_position(m, d, d->t, S);
#else
  (void)F;
  int rc = ap_kin_position(m, d, d->t, d->q, S);
#endif
  if (rc == AP_OK && M->nc) rc = ap_con_time(m, d, d->t, S);
  if (rc != AP_OK) return rc;
#ifndef AP_SC_COMPLEX
  if (!F) ap_kin_metric(M, S, d->g);
#else
  ap_kin_metric(M, S, d->g);
#endif
  if (M->n != M->k)
    for (int j = 0; j < M->nj; j++) ap_joint_fill_N(&M->joints[j], d->q, d->N, M->n);
  return M->b ? ap_con_rows(m, d, d->t, d->q, S, d->A, d->a0) : AP_OK;
}

int ap_bm_position(const ap_model *m, ap_data *d, ap_sc *S) {
  return bm_position(m, d, S, ap_bm(m)->fast);   /* compiled kinematics (lib/codegen) */
}

static int bm_velocity(const ap_model *m, ap_data *d, ap_sc *S, const ap_bm_fast *F) {
  const ap_bmodel *M = ap_bm(m);
  d->cnt.bias++;
  d->cnt.force += M->ne > 0;
  d->cnt.gamma += M->b > 0;
#ifndef AP_SC_COMPLEX
  if (F) {
    F->velocity(F, d->v, S, d->h);
    if (F->forces) return F->forces(F, m, d, S);   /* lib/codegen fast_rows.c */
  } else {
    ap_kin_velocity(M, d->v, S);
    ap_kin_bias(M, S, d->h);
  }
#else
  (void)F;
  ap_kin_velocity(M, d->v, S);
  ap_kin_bias(M, S, d->h);
#endif
  int rc = M->ne ? ap_eff_forces(m, d, d->t, d->q, d->v, S, d->Q) : AP_OK;
  if (rc == AP_OK && M->b) rc = ap_con_gamma(m, d, d->t, d->q, d->v, S, d->gamma);
#ifndef AP_SC_COMPLEX
  if (rc == AP_OK && M->nfric) rc = ap_cfr_friction(m, d, S);   /* sliding contacts */
#endif
  return rc;
}

int ap_bm_velocity(const ap_model *m, ap_data *d, ap_sc *S) {
  return bm_velocity(m, d, S, ap_bm(m)->fast);
}

#ifndef AP_SC_COMPLEX
int ap_bm_position_interp(const ap_model *m, ap_data *d, double *S) {
  return bm_position(m, d, S, NULL);
}

int ap_bm_velocity_interp(const ap_model *m, ap_data *d, double *S) {
  return bm_velocity(m, d, S, NULL);
}
#endif

/* ---- implicit holonomic constraints for the DAE mode (GGL) ----------------------------------
 *
 * Rows 0..nloop-1: the loop closures phi = n . (xA - xB) (constraint.c) and the wheel contacts'
 * rows .z, phi = the contact point's height (contact.c). Their Jacobian with
 * respect to the speeds, Jl = d phi' / d v = Phi_q N, comes from ap_con_loops; it is mapped to
 * q joint by joint: a scalar coordinate has N = 1 against its speed, so its column of Phi_q is
 * Jl's; a quaternion p enters phi only through R(p / |p|), so Phi_q p = 0, and
 * Phi_q N_p = Jl_w with N_p = 1/2 [0; w] (x) p, whose columns are orthogonal with norm |p| / 2:
 * the quaternion block of Phi_q is (4 / |p|^2) Jl_w N_p^T.
 * Rows nloop..nloop+nquat-1: |p|^2 - 1 = 0 for each quaternion joint, Jacobian 2 p^T. */

/* Row s of Phi_q (ld nphi) from the speed Jacobian row jl (k entries, stride 1). */
static void phi_row_to_q(const ap_bmodel *M, const ap_sc *q, const ap_sc *jl, int s,
                         int nphi, ap_sc *Phi_q) {
  for (int j = 0; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    for (int i = 0; i < J->ndrivable; i++)
      if (J->qidx[i] >= 0) Phi_q[s + (size_t)J->qidx[i] * nphi] = jl[J->vidx[i]];
    if (J->quat < 0) continue;
    const ap_sc *p = q + J->qidx[J->quat], *jw = jl + J->vidx[J->wofs];
    ap_sc N[12], pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
    ap_quat_N(p, N, 4, 0, 0);
    for (int r = 0; r < 4; r++)
      Phi_q[s + (size_t)(J->qidx[J->quat] + r) * nphi] =
          4.0 / pp * (N[r] * jw[0] + N[r + 4] * jw[1] + N[r + 8] * jw[2]);
  }
}

int ap_bm_phi(const ap_model *m, ap_data *d, ap_sc *S, ap_sc *phi, ap_sc *Phi_q) {
  const ap_bmodel *M = ap_bm(m);
  int nl = M->nloop, nphi = m->nphi, k = M->k;
  if (nl > 0) {
    ap_sc *JlT = S + M->off_proj;   /* row s of Jl is column s of JlT: contiguous */
    ap_con_loops(M, S, phi, JlT);
    for (int s = 0; s < nl && Phi_q; s++)
      phi_row_to_q(M, d->q, JlT + (size_t)s * k, s, nphi, Phi_q);
  }
  for (int j = 0, s = nl; j < M->nj; j++) {
    const ap_mjoint *J = &M->joints[j];
    if (J->quat < 0) continue;
    const ap_sc *p = d->q + J->qidx[J->quat];
    phi[s] = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - 1.0;
    for (int r = 0; r < 4 && Phi_q; r++)
      Phi_q[s + (size_t)(J->qidx[J->quat] + r) * nphi] = 2.0 * p[r];
    s++;
  }
  return AP_OK;
}
