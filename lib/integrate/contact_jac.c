/* CVODE BDF with sliding contacts: the slip velocities handed to the stepper's Jacobian watch
 * after each accepted step (stepper_jwatch.c), so that the Newton matrix made at a slip onset
 * (|s| = 0, where the friction direction s / |s| has an unbounded derivative) is made again
 * as the slip grows instead of stalling the Newton iteration (docs/steppers.md). Contacts that
 * do not slide are watched as 0. Called by the contact modes' stage with the data holding the
 * accepted state's position stage and speeds. */
#include <math.h>
#include <stdlib.h>

#include "integrate/sim_int.h"
#include "model/con_friction.h"

/* The Jacobian's relative difference increment while a contact slides: JAC_SLIP of the
 * smallest slip speed over the largest speed (a column then moves each slip by about that
 * fraction of it), at least JAC_RHO_MIN (round-off), CVODE's own sqrt(eps) when that is
 * smaller (stepper_cvjac.c). */
#define JAC_SLIP 1e-3
#define JAC_RHO_MIN 1e-13
#define JAC_RHO_MAX 1.4901161193847656e-08

int ap_drv_contacts_watch(ap_sim *s) {
  if (!s->st || !ap_step_native_projection(s->meth)) return AP_OK;   /* no Newton matrix */
  const ap_bmodel *M = ap_bm(s->m);
  double *S = (double *)ap_bm_scratch(s->d);
  double *w = malloc(sizeof(double) * 2 * (size_t)M->nfric);
  if (!w) return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  for (int ci = 0, i = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0) continue;
    w[2 * i] = w[2 * i + 1] = 0.0;
    if (ap_cfr_mode(M, S, c) == AP_CM_SLIDING) ap_cfr_slip(M, S, c, s->d->v, w + 2 * i);
    i++;
  }
  double smin = INFINITY, vmax = 0.0, rho = 0.0;
  for (int i = 0; i < M->nfric; i++)
    if (w[2 * i] != 0.0 || w[2 * i + 1] != 0.0) smin = fmin(smin, hypot(w[2 * i], w[2 * i + 1]));
  for (int j = 0; j < s->k; j++) vmax = fmax(vmax, fabs(s->d->v[j]));
  if (isfinite(smin)) rho = fmax(JAC_SLIP * smin / (vmax + s->def.atol), JAC_RHO_MIN);
  if (rho >= JAC_RHO_MAX) rho = 0.0;   /* CVODE's own increments are small enough */
  int rc = ap_step_jacobian_watch(s->st, M->nfric, w);
  if (rc == AP_OK) rc = ap_step_jacobian_increment(s->st, rho);
  free(w);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "out of memory");
}
