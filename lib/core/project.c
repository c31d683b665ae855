/* Projection of speeds onto the constraints and diagnostics of a state (double build only:
 * they run between steps on accepted states, not inside an evaluation).
 *
 * ap_project_speeds: the nearest admissible speeds in the metric g, computed from the residual
 * A v + a0 (ap_core_project_here); ap_core_project_tangent: the g-orthogonal projection onto the null space of A;
 * residual and kinetic energy at the data's position stage. Nothing here allocates. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "core/core.h"
#include "core/structured.h"
#include "linalg/linalg.h"

#define SCRATCH(d) ((ap_scratch *)(d)->internal)  /* first member of the data block */

/* ---- projection and diagnostics ---------------------------------------------------------- */

int ap_project_speeds(const ap_model *m, ap_data *d, double *v, double *change) {
  if (!v) return AP_ERR_ARG;
  int rc = ap_fwd_position(m, d);
  if (rc != AP_OK) return rc;
  return AP_CORE_GUARDED(m, d, "projection", ap_core_project_here(m, d, v, change));
}

/* A sticking plastic impact: v+ = v- - g^-1 A^T (A g^-1 A^T)^-1 (A v- + a0), the nearest
 * admissible speeds in the kinetic-energy metric, which is ap_project_speeds; Carnot's theorem:
 * the energy lost is the kinetic energy of the jump, 1/2 (v+ - v-)^T g (v+ - v-). */
int ap_impact(const ap_model *m, ap_data *d, const double *v_minus, double *v_plus,
              double *loss) {
  if (!m || !d || !v_minus || !v_plus) return AP_ERR_ARG;
  double change = 0.0;
  if (v_plus != v_minus) memmove(v_plus, v_minus, (size_t)m->k * sizeof *v_plus);
  int rc = ap_project_speeds(m, d, v_plus, &change);
  if (rc == AP_OK && loss) *loss = 0.5 * change * change;
  return rc;
}

/* a + sum x_i y_i with the products' and the sums' rounding errors carried along (fma and
 * Neumaier's compensation): the result is as accurate as if computed in twice the precision,
 * then rounded. A constraint residual is a small difference of large terms. */
static double dot_compensated(int len, const double *x, int incx, const double *y, double a,
                              double *mag) {
  double sum = a, c = 0.0, m = fabs(a);
  for (int i = 0; i < len; i++) {
    double p = x[(size_t)i * incx] * y[i], pe = fma(x[(size_t)i * incx], y[i], -p);
    double t = sum + p;
    c += fabs(sum) >= fabs(p) ? (sum - t) + p : (p - t) + sum;
    c += pe;
    sum = t, m += fabs(p);
  }
  if (mag) *mag = m;
  return sum + c;
}

/* The correction that takes v onto A v + a0 = 0, nearest in g, computed from the residual
 * r = A v + a0 alone (so a state on the constraints is not touched, and the rounding of the
 * correction is relative to the correction, not to v):
 *
 *     d0 = particular solution of A d0 = -r (the basis stage's factorization),
 *     d  = d0 - B G^-1 B^T g d0      (remove d0's g-projection onto the null space of A).
 *
 * v <- v + d. Rows whose residual is within the round-off of their own terms
 * (|r_s| <= 4 eps sum |A_sj v_j| + |a0_s|) count as satisfied; when all are, v is left as is. */
int ap_core_project_here(const ap_model *m, ap_data *d, double *v, double *change) {
  if (ap_core_st(d)) return ap_st_project_here(m, d, ap_core_st(d), v, change);
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l, b = m->b, rc, any = 0;
  if (change) *change = 0.0;
  if (b == 0) return AP_OK;
  double *r = s->work + ap_la_work_size(b, k) - (size_t)b;  /* the last b doubles of work */
  for (int i = 0; i < b; i++) {
    double mag = 0.0;
    r[i] = -dot_compensated(k, d->A + i, b, v, d->a0[i], &mag);
    if (fabs(r[i]) > 4.0 * DBL_EPSILON * mag) any = 1;
  }
  if (!any) return AP_OK;
  double resid = 0.0;
  if (d->basis == AP_BASIS_ORTHONORMAL)
    rc = ap_la_orth_particular(b, k, d->rank, s->F, s->jpvt, s->Qf, r, s->tk1, &resid, s->work);
  else
    rc = ap_la_partition_particular(b, k, d->rank, d->perm, s->F, s->tau, r, s->tk1, &resid,
                                    s->work);
  if (rc != AP_OK) return rc;
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);                    /* tk2 = g d0 */
  ap_la_gemv_t(k, l, d->B, s->tk2, s->tl);                   /* tl = B^T g d0 */
  ap_la_congruence(k, l, d->g, d->B, d->G, s->gB);
  rc = ap_la_chol(l, d->G, NULL, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': G = B^T g B is not positive definite at t = %.17g (speed "
                "projection)", m->name, d->t);
    return AP_ERR_SINGULAR;
  }
  ap_la_chol_solve(l, d->G, s->tl);
  ap_la_gemv(k, l, d->B, s->tl, s->tk2);                     /* tk2 = B G^-1 B^T g d0 */
  for (int i = 0; i < k; i++) {
    s->tk1[i] -= s->tk2[i];                                  /* the correction d */
    v[i] += s->tk1[i];
  }
  ap_la_gemv(k, k, d->g, s->tk1, s->tk2);
  double c2 = 0.0;
  for (int i = 0; i < k; i++) c2 += s->tk1[i] * s->tk2[i];
  if (change) *change = sqrt(fmax(c2, 0.0));
  return AP_OK;
}

void ap_core_project_tangent(const ap_model *m, ap_data *d, double *x) {
  if (ap_core_st(d)) return ap_st_project_tangent(m, d, ap_core_st(d), x);
  ap_scratch *s = SCRATCH(d);
  int k = m->k, l = d->l;
  ap_la_gemv(k, k, d->g, x, s->tk1);                         /* tk1 = g x */
  ap_la_gemv_t(k, l, d->B, s->tk1, s->tl);                   /* tl = B^T g x */
  ap_la_chol_solve(l, d->G, s->tl);                          /* G^-1 B^T g x */
  ap_la_gemv(k, l, d->B, s->tl, x);                          /* x = B G^-1 B^T g x */
}

double ap_constraint_residual(const ap_data *d, const double *v) {
  if (!d || !v || !d->internal) return NAN;
  if (ap_core_st(d)) return ap_st_residual(d, ap_core_st(d), v);
  double mx = 0.0;
  for (int s = 0; s < d->b; s++) {
    double r = d->a0[s];
    for (int j = 0; j < d->k; j++) r += d->A[s + (size_t)j * d->b] * v[j];
    mx = fmax(mx, fabs(r));
  }
  return mx;
}

double ap_kinetic_energy(const ap_data *d, const double *v) {
  if (!d || !v || !d->internal) return NAN;
  if (ap_core_st(d)) return ap_st_energy(d, ap_core_st(d), v);
  double e = 0.0;
  for (int j = 0; j < d->k; j++)
    for (int i = 0; i < d->k; i++) e += v[i] * d->g[i + (size_t)j * d->k] * v[j];
  return 0.5 * e;
}
