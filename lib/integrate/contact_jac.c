/* CVODE BDF with sliding contacts: the slip velocities handed to the stepper's Jacobian watch
 * after each accepted step (stepper_jwatch.c), so that the Newton matrix made at a slip onset
 * (|s| = 0, where the friction direction s / |s| has an unbounded derivative) is made again
 * as the slip grows instead of stalling the Newton iteration (docs/steppers.md). Contacts that
 * do not slide are watched as 0. Called by the contact modes' stage with the data holding the
 * accepted state's position stage and speeds. */
#include <stdlib.h>

#include "integrate/sim_int.h"
#include "model/con_friction.h"

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
  int rc = ap_step_jacobian_watch(s->st, M->nfric, w);
  free(w);
  return rc == AP_OK ? AP_OK : ap_drv_fail(s, rc, "out of memory");
}
