/* Projection of speeds onto the constraints and diagnostics of a state (double build only:
 * they run between steps on accepted states, not inside an evaluation).
 *
 * ap_project_speeds: v <- b0 + B G^-1 B^T g (v - b0), the nearest admissible speeds in the
 * metric g; ap_core_project_tangent: the g-orthogonal projection onto the null space of A;
 * residual and kinetic energy at the data's position stage. Nothing here allocates. */
#include <math.h>
#include <string.h>

#include "core/core.h"
#include "linalg/linalg.h"

#define SCRATCH(d) ((ap_scratch *)(d)->internal)  /* first member of the data block */

/* ---- projection and diagnostics ---------------------------------------------------------- */

int ap_project_speeds(const ap_model *m, ap_data *d, double *v, double *change) {
  int rc = ap_fwd_position(m, d);
  return rc == AP_OK ? ap_core_project_here(m, d, v, change) : rc;
}

int ap_core_project_here(const ap_model *m, ap_data *d, double *v, double *change) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l, rc;
  for (int i = 0; i < k; i++) s->tk1[i] = v[i] - d->b0[i];   /* tk1 = v - b0 */
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);                    /* tk2 = g (v - b0) */
  ap_la_gemv_t(k, l, d->B, s->tk2, s->tl);                   /* tl = B^T g (v - b0) */
  ap_la_congruence(k, l, d->g, d->B, d->G, s->gB);
  rc = ap_la_chol(l, d->G, NULL, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': G = B^T g B is not positive definite at t = %.17g (speed "
                "projection)", m->name, d->t);
    return AP_ERR_SINGULAR;
  }
  ap_la_chol_solve(l, d->G, s->tl);
  ap_la_gemv(k, l, d->B, s->tl, s->tk2);                     /* tk2 = B e */
  for (int i = 0; i < k; i++) {
    double vi = d->b0[i] + s->tk2[i];
    s->tk1[i] = vi - v[i];                                   /* correction */
    v[i] = vi;
  }
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);
  double c2 = 0.0;
  for (int i = 0; i < k; i++) c2 += s->tk1[i] * s->tk2[i];
  if (change) *change = sqrt(fmax(c2, 0.0));
  return AP_OK;
}

void ap_core_project_tangent(const ap_model *m, ap_data *d, double *x) {
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l;
  ap_la_gemv(k, k, d->g, x, s->tk1);                         /* tk1 = g x */
  ap_la_gemv_t(k, l, d->B, s->tk1, s->tl);                   /* tl = B^T g x */
  ap_la_chol_solve(l, d->G, s->tl);                          /* G^-1 B^T g x */
  ap_la_gemv(k, l, d->B, s->tl, x);                          /* x = B G^-1 B^T g x */
}

double ap_constraint_residual(const ap_data *d, const double *v) {
  double mx = 0.0;
  for (int s = 0; s < d->b; s++) {
    double r = d->a0[s];
    for (int j = 0; j < d->k; j++) r += d->A[s + (size_t)j * d->b] * v[j];
    mx = fmax(mx, fabs(r));
  }
  return mx;
}

double ap_kinetic_energy(const ap_data *d, const double *v) {
  double e = 0.0;
  for (int j = 0; j < d->k; j++)
    for (int i = 0; i < d->k; i++) e += v[i] * d->g[i + (size_t)j * d->k] * v[j];
  return 0.5 * e;
}
