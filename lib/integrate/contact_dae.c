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
 * Held direction. While a slip that has just begun (a slip onset, or sliding from t0: the
 * stick event not yet armed, contact_modes.c) is below slip_tol = atol + rtol max |v_i|, the
 * stick event's own tolerance, the residual's friction keeps the slip direction of the last
 * accepted step (at the onset the direction -F_t the switch chose) instead of s / |s|. There
 * s is of round-off size and s / |s| turned with each Newton iterate's slip (1e-8 m/s in any
 * direction, the Jacobian's difference increments as large): IDA, restarted at order 1, failed
 * with "the corrector convergence failed" at steps of 1e-11 s where every explicit run went on
 * (campaign seeds 1000438, 1002577, 1001876: tests/scenes/difftest/dae_slip_onset.yaml,
 * dae_slip_at_start.yaml, dae_axle_slip_onset.yaml). The explicit modes follow s / |s| down to
 * 1e-13 (1 + max |v_i|); the forces differ only while |s| <= slip_tol, for a time of about
 * slip_tol / |s'|. Held on the way to a stick too, it moved the stick times by that much (4e-7
 * s at campaign seed 1001020, whose later motion then differed): a slip on its way to 0 keeps
 * s / |s|.
 *
 * Onset at zero slip. IDA holds the rolling rows only to its tolerance, so at a slip onset the
 * slip was not 0 but 1e-11 m/s in any direction, and the contact stage (contact_modes.c) took
 * that direction as the stick event's reference: in the planar robot's turn at rtol 1e-6 it
 * pointed against the slip to come, the stick fired 4.8e-6 s after the onset and the run's
 * later switches moved by 0.06 s (tests/test_planar_dae.c, turn_coarse). The remake puts v on
 * s = 0 for a young slip below slip_tol first, nearest in g with the other rows held, as the
 * minimal modes' state has it at the onset.
 *
 * Switches. A switch changes which rows are zero rows (rolling: all of the contact's rows;
 * sliding: the normal row only; airborne: none), hence the number of independent rows IDA
 * carries multipliers for. IDA is made again for the new size at the switch state (ap_dae_create
 * chooses the independent rows from A there, the zero rows falling out as redundant rows do);
 * its counters carry on.
 *
 * Events. The slip and lift-off events read IDA's own multipliers (the cross-check), split
 * as the minimal and projected modes split them: IDA carries multipliers for its kept rows
 * only, so where a contact's friction rows repeat others (two wheels of one axle) its
 * tangential force was the kept rows' share, and the DAE run slipped at other times than the
 * minimal modes, whose reactions are the minimum-norm lambda of A^T lambda = g v' + h - Q
 * (core/forward.c). ap_drv_dae_event_multipliers takes IDA's reaction A_s^T lambda_s and
 * splits it the same way. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "integrate/contact_int.h"
#include "integrate/sim_int.h"
#include "linalg/linalg.h"
#include "model/con_friction.h"

int ap_drv_dae_coulomb(void *user, ap_data *d, double *W) {
  ap_sim *s = user;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = ap_bm_scratch(d);
  int k = s->k;
  memset(W, 0, sizeof(double) * (size_t)k * (size_t)s->b);
  double vmax = 0.0;
  for (int j = 0; j < k; j++) vmax = fmax(vmax, fabs(d->v[j]));
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0 || ap_cfr_mode(M, S, c) != AP_CM_SLIDING) continue;
    double *f = W + (size_t)(c->row + c->hrow) * (size_t)k, fn = ap_cfr_normal_force(M, S, c);
    ap_cfr_coulomb(M, S, c, f);
    for (int j = 0; j < k; j++) d->Q[j] -= f[j] * fn;   /* the Appell modes' F_n out again */
    double sl[2], *dir = ap_cfr_slip_dir(M, S, c);
    ap_cfr_slip(M, S, c, d->v, sl);
    if (ap_drv_cm_slip_young(s, c) && hypot(sl[0], sl[1]) <= s->def.atol + s->def.rtol * vmax) {
      dir[2] = dir[0], dir[3] = dir[1];
      ap_cfr_coulomb(M, S, c, f);
    }
    if (ap_bm_wheel_by_load(M, c))   /* no multiplier: its load's force (dae_loads.c) */
      memset(f, 0, sizeof(double) * (size_t)k);
  }
  return AP_OK;
}

/* Contacts whose slip has just begun (young) with |s| <= slip_tol: v onto s = 0 for them too
 * (nearest in g, the other rows held), their mode rolling for the projection only. */
static int onset_slips_zero(ap_sim *s, double t, double *y) {
  const ap_bmodel *M = ap_bm(s->m);
  ap_data *d = s->d;
  double *S = ap_bm_scratch(d), vmax = 0.0, sl[2], change = 0.0;
  int any = 0, rc = AP_OK;
  ap_drv_load_state(s, t, y);
  if (ap_fwd_position(s->m, d) != AP_OK) return AP_OK;   /* ap_forward reports it */
  char *on = calloc((size_t)M->nc + 1, 1);
  if (!on) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(y[s->n + j]));
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0 || ap_cfr_mode(M, S, c) != AP_CM_SLIDING || !ap_drv_cm_slip_young(s, c))
      continue;
    ap_cfr_slip(M, S, c, y + s->n, sl);
    if (hypot(sl[0], sl[1]) > s->def.atol + s->def.rtol * vmax) continue;
    ap_cfr_set_mode(M, S, c, AP_CM_ROLLING), any = 1;
    on[ci] = 1;
  }
  if (any) {
    ap_drv_load_state(s, t, y);
    rc = ap_fwd_position(s->m, d);
    if (rc == AP_OK) rc = ap_core_project_here(s->m, d, y + s->n, &change);
  }
  for (int ci = 0; ci < M->nc; ci++)
    if (on[ci]) ap_cfr_set_mode(M, S, &M->cons[ci], AP_CM_SLIDING);
  free(on);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "%s", d->msg);
}

int ap_drv_dae_remake(ap_sim *s, double t, double *y) {
  ap_data *d = s->d;
  double *yp = malloc(sizeof(double) * (size_t)s->ny);
  if (!yp) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  d->basis = AP_BASIS_ORTHONORMAL;
  int rc = onset_slips_zero(s, t, y);
  ap_drv_load_state(s, t, y);
  if (rc == AP_OK) rc = ap_forward(s->m, d);
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

/* IDA's multipliers at t (b + nphi) with the constraint rows' share split by minimum norm:
 * lambda = A^+ (A_s^T lambda_s), A the data's (the event's state, the position stage there).
 * The rows' reaction is IDA's; only its split over redundant rows changes. */
int ap_drv_dae_event_multipliers(ap_sim *s, double t, double *lam) {
  ap_data *d = s->d;
  ap_scratch *sc = d->internal;
  if (ap_dae_multipliers(s->dae, t, lam) != AP_OK) return -1;
  if (ap_dae_rows(s->dae, NULL) == s->b) return 0;   /* no redundant row: the split is unique */
  ap_la_gemv_t(s->b, s->k, d->A, lam, sc->tk1);
  double resid = 0.0;
  return ap_la_lstsq_At(s->b, s->k, d->A, sc->tk1, d->rank_rtol, lam, &resid, sc->work,
                        sc->iwork) == AP_OK ? 0 : -1;
}
