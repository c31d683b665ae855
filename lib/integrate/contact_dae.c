/* DAE mode with contact modes (docs/design.md "Contact modes in DAE mode"): the sliding
 * contacts' Coulomb forces in IDA's residual, with the normal force IDA's own multiplier, and
 * IDA made again at each switch of a contact's mode.
 *
 * Residual. A sliding contact j applies -mu_k F_n,j s^_j at its contact point, the generalized
 * force f_j F_n,j with f_j = -mu_k T_j^T s^_j (model/con_friction.c). In the residual F_n,j is
 * the multiplier of the contact's normal row, an algebraic variable of IDA (a wheel under a
 * planar chassis has none: its F_n is its load, dae_loads.c):
 *     F_v = g v' + h - Q - A_s^T lambda - sum_j f_j lambda_n,j
 * so the friction is coupled to the normal force through IDA's Newton iteration (the Newton
 * matrix's multiplier column of row n,j is -cj (A_n,j^T + f_j)). The body model's velocity
 * stage adds the friction with the Appell modes' normal force (solved with the accelerations)
 * to Q; ap_drv_dae_coulomb takes that term out again and hands f_j to the residual as the
 * column W(:, n_j).
 *
 * Switches. A switch changes which rows are zero rows (rolling: all of the contact's rows;
 * sliding: the normal row only; airborne: none), hence the number of independent rows IDA
 * carries multipliers for. IDA is made again for the new size at the switch state (ap_dae_create
 * chooses the independent rows from A there, the zero rows falling out as redundant rows do);
 * its counters carry on. */
#include <stdlib.h>
#include <string.h>

#include "integrate/sim_int.h"
#include "model/con_friction.h"

int ap_drv_dae_coulomb(void *user, ap_data *d, double *W) {
  ap_sim *s = user;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = ap_bm_scratch(d);
  int k = s->k;
  memset(W, 0, sizeof(double) * (size_t)k * (size_t)s->b);
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0 || ap_cfr_mode(M, S, c) != AP_CM_SLIDING) continue;
    double *f = W + (size_t)(c->row + c->hrow) * (size_t)k, fn = ap_cfr_normal_force(M, S, c);
    ap_cfr_coulomb(M, S, c, f);
    for (int j = 0; j < k; j++) d->Q[j] -= f[j] * fn;   /* the Appell modes' F_n out again */
    if (ap_bm_wheel_by_load(M, c))   /* no multiplier: its load's force (dae_loads.c) */
      memset(f, 0, sizeof(double) * (size_t)k);
  }
  return AP_OK;
}

int ap_drv_dae_remake(ap_sim *s, double t, double *y) {
  ap_data *d = s->d;
  double *yp = malloc(sizeof(double) * (size_t)s->ny);
  if (!yp) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  d->basis = AP_BASIS_ORTHONORMAL;
  ap_drv_load_state(s, t, y);
  int rc = ap_forward(s->m, d);
  d->basis = AP_BASIS_NONE;
  if (rc != AP_OK) {
    free(yp);
    return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SOLVER, "%s", d->msg);
  }
  ap_dae *old = s->dae;
  s->dae = NULL;
  rc = ap_drv_dae_make(s, t, y, yp);
  free(yp);
  if (rc != AP_OK) {
    char why[sizeof s->msg];
    memcpy(why, s->msg, sizeof why);
    s->dae = old;   /* the simulation stays in DAE mode, failed */
    return ap_drv_fail(s, rc, "contact modes at t = %.17g: %s", t, why);
  }
  ap_dae_carry_stats(s->dae, old);
  ap_dae_free(old);
  s->ev_stamp = -1;
  return AP_OK;
}
