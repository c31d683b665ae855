/* Touchdown impacts of contacts with modes (docs/scenes.md "Friction, slip and lift-off",
 * "Impacts"): the velocity jump when an airborne contact touches down, sticking or sliding.
 *
 * Sticking impact: the projection of v- onto the contact's rows (all of them) and the other
 * active rows nearest in the kinetic-energy metric, v+ = v- - g^-1 A^T (A g^-1 A^T)^-1 (A v- +
 * a0 - target), with the normal row's target -e vn (vn < 0 the closing speed of the contact
 * point; e the restitution, 0 when the bounce is slower than AP_CM_BOUNCE_MIN (1 + max |v_i|)).
 * Its impulse P (A^T P = g (v+ - v-), least squares as the reactions) has the normal part P_n
 * and the tangential part P_t. When |P_t| <= mu P_n (or the contact has no friction
 * coefficient) that is the impact.
 *
 * Sliding impact, when the sticking impulse leaves the cone: the contact slides through the
 * impact along the pre-impact slip direction s^ (or against P_t when the slip is round-off),
 * the Coulomb impulse -mu_k P_n s^ at the contact point, i.e. the generalized impulse f P_n
 * with f = -mu_k T^T s^ (model/con_friction.c), and the tangential rows dropped:
 *     g (v+ - v-) = A'^T P + f P_n,    A' v+ + a0' = target     (A': the rows of the sliding mode)
 * solved by superposition: v1 = the frictionless impact (the projection of v- onto A'), with
 * normal impulse P_n1; w = g^-1 f projected onto A' w = 0 (homogeneous) is the response to a
 * unit friction impulse, with normal impulse P_n2 (its constraint reaction); then
 *     P_n = P_n1 / (1 - P_n2),   v+ = v1 + P_n w.
 * 1 - P_n2 <= 0 is Painleve's paradox of impacts (the friction impulse would drive the contact
 * into the ground harder than the normal impulse resists): refused, with the number. For a
 * sphere P_n2 = 0. The slip direction is held through the impact (Coulomb's law integrated
 * with a constant direction; a slip that would turn during the impact is not followed, see the
 * design notes). After the impact the contact flies (a bounce), slides along its slip when that
 * is not round-off, or rolls. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "integrate/sim_int.h"
#include "linalg/linalg.h"
#include "model/con_friction.h"

#define AP_CM_BOUNCE_MIN 1e-6

typedef struct imp_work {
  double *vs, *P, *rhs, *f, *w, *wc, *Lg, *a0, *work;
  int *iwork;
} imp_work;

static int work_alloc(int k, int b, imp_work *w) {
  size_t kk = (size_t)k, bb = (size_t)b, nw = ap_la_work_size(b > k ? b : k, k);
  w->vs = calloc(6 * kk + kk * kk + 2 * bb + nw + 1, sizeof(double));
  w->iwork = calloc(ap_la_iwork_size(b > k ? b : k, k) + 1, sizeof(int));
  if (!w->vs || !w->iwork) return AP_ERR_NOMEM;
  w->P = w->vs + kk, w->rhs = w->P + bb, w->f = w->rhs + kk, w->w = w->f + kk;
  w->wc = w->w + kk, w->Lg = w->wc + kk, w->a0 = w->Lg + kk * kk, w->work = w->a0 + bb;
  return AP_OK;
}

/* The data's position stage at (t, q) for the contact's current mode (orthonormal basis). */
static int position_at(ap_sim *s, double t, const double *q) {
  ap_data *d = s->d;
  d->t = t, d->speeds_from_e = 0, d->basis = AP_BASIS_ORTHONORMAL;
  memcpy(d->q, q, sizeof(double) * (size_t)s->n);
  int rc = ap_partition(s->m, d);
  return rc == AP_OK ? ap_fwd_position(s->m, d) : rc;
}

/* Row r of A dotted with x, plus a0_r. */
static double row_dot(const ap_data *d, int b, int k, int r, const double *x) {
  double y = d->a0[r];
  for (int j = 0; j < k; j++) y += d->A[r + (size_t)j * b] * x[j];
  return y;
}

/* The constraint impulse P of the velocity change dv: A^T P = g dv (least squares). */
static int impulse(ap_sim *s, const double *dv, imp_work *w) {
  ap_data *d = s->d;
  double resid = 0.0;
  ap_la_gemv(s->k, s->k, d->g, dv, w->rhs);
  return ap_la_lstsq_At(s->b, s->k, d->A, w->rhs, d->rank_rtol, w->P, &resid, w->work,
                        w->iwork);
}

/* v projected onto the data's rows with the normal row r's target (a0_r shifted by e vn). */
static int project_to(ap_sim *s, int r, double shift, double *v) {
  s->d->a0[r] += shift;
  int rc = ap_core_project_here(s->m, s->d, v, NULL);
  s->d->a0[r] -= shift;
  return rc;
}

/* The sliding impact of contact c (mode set to sliding along dir): v in, v+ out. */
static int sliding(ap_sim *s, const ap_mcon *c, double t, const double *q, double shift,
                   double *v, imp_work *w) {
  ap_data *d = s->d;
  int k = s->k, b = s->b, r = c->row + c->hrow;
  int rc = position_at(s, t, q);
  memcpy(w->vs, v, sizeof(double) * (size_t)k);
  if (rc == AP_OK) rc = project_to(s, r, shift, w->vs);            /* v1: frictionless */
  for (int j = 0; j < k; j++) w->w[j] = w->vs[j] - v[j];
  if (rc == AP_OK) rc = impulse(s, w->w, w);
  double pn1 = w->P[r];
  ap_cfr_coulomb(ap_bm(s->m), ap_bm_scratch(d), c, w->f);         /* f, w = g^-1 f */
  memcpy(w->Lg, d->g, sizeof(double) * (size_t)k * k);
  if (rc == AP_OK) rc = ap_la_chol(k, w->Lg, NULL, w->work, w->iwork);
  if (rc != AP_OK)
    return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact '%s': sliding impact at "
                       "t = %.17g: %s", c->name, t, d->msg);
  memcpy(w->w, w->f, sizeof(double) * (size_t)k);
  ap_la_chol_solve(k, w->Lg, w->w);
  memcpy(w->wc, w->w, sizeof(double) * (size_t)k);
  memcpy(w->a0, d->a0, sizeof(double) * (size_t)b);
  memset(d->a0, 0, sizeof(double) * (size_t)b);
  rc = ap_core_project_here(s->m, d, w->wc, NULL);                 /* A' wc = 0 */
  memcpy(d->a0, w->a0, sizeof(double) * (size_t)b);
  for (int j = 0; j < k; j++) w->rhs[j] = w->wc[j] - w->w[j];
  memcpy(w->w, w->rhs, sizeof(double) * (size_t)k);
  if (rc == AP_OK) rc = impulse(s, w->w, w);
  double den = 1.0 - w->P[r];
  if (rc == AP_OK && !(den > 1e-12))
    return ap_drv_fail(s, AP_ERR_SINGULAR, "contact '%s': the sliding impact at t = %.17g has "
                       "no solution or several (Painleve's paradox of impacts: 1 - P_n2 = %.6g "
                       "<= 0, the friction impulse pushes the contact into the ground harder "
                       "than the normal impulse can resist): lower mu_kinetic", c->name, t, den);
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact '%s': "
                                      "sliding impact at t = %.17g: %s", c->name, t, d->msg);
  double pn = pn1 / den;
  for (int j = 0; j < k; j++) v[j] = w->vs[j] + pn * w->wc[j];
  return AP_OK;
}

/* The mode after a plastic sliding impact: sliding along the slip when it is not round-off. */
static void after_sliding(ap_sim *s, const ap_mcon *c, const double *v, double vmax) {
  const ap_bmodel *M = ap_bm(s->m);
  double *S = ap_bm_scratch(s->d), sl[2], *dir = ap_cfr_slip_dir(M, S, c);
  ap_cfr_slip(M, S, c, v, sl);
  double ns = hypot(sl[0], sl[1]);
  if (ns > 1e-9 * (1.0 + vmax)) dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
  else ap_cfr_set_mode(M, S, c, AP_CM_ROLLING);
}

/* Sticking or sliding, from the sticking impulse (data at the rolling mode's position stage). */
static int impact(ap_sim *s, const ap_mcon *c, double t, const double *q, double *v,
                  imp_work *w) {
  const ap_bmodel *M = ap_bm(s->m);
  ap_data *d = s->d;
  double *S = ap_bm_scratch(d), e = c->def.restitution, mu = c->def.mu, vmax = 0.0;
  int k = s->k, r = c->row + c->hrow;
  double vn = row_dot(d, s->b, k, r, v);
  for (int j = 0; j < k; j++) vmax = fmax(vmax, fabs(v[j]));
  int bounce = e > 0 && -e * vn > AP_CM_BOUNCE_MIN * (1.0 + vmax);
  double shift = bounce ? e * vn : 0.0;                 /* A_n v+ + a0_n = -e vn */
  memcpy(w->vs, v, sizeof(double) * (size_t)k);
  int rc = project_to(s, r, shift, w->vs);
  if (rc == AP_OK && mu >= 0) {
    for (int j = 0; j < k; j++) w->rhs[j] = w->vs[j] - v[j];
    memcpy(w->w, w->rhs, sizeof(double) * (size_t)k);
    rc = impulse(s, w->w, w);
  }
  if (rc != AP_OK) return ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact '%s': impact "
                                      "at t = %.17g: %s", c->name, t, d->msg);
  double pt = mu >= 0 ? hypot(w->P[c->row], w->P[c->row + 1]) : 0.0;
  /* sticking; also with no tangential impulse at all (a grazing touchdown whose normal
   * impulse is round-off or pulls: there is no slip direction to slide along) */
  if (mu < 0 || pt <= mu * w->P[r] || !(pt > 0)) {
    memcpy(v, w->vs, sizeof(double) * (size_t)k);
    if (bounce) ap_cfr_set_mode(M, S, c, AP_CM_AIRBORNE);
    return AP_OK;
  }
  double sl[2], *dir = ap_cfr_slip_dir(M, S, c);
  ap_cfr_slip(M, S, c, v, sl);
  double ns = hypot(sl[0], sl[1]);
  if (ns > 1e-13 * (1.0 + vmax)) dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
  else dir[0] = -w->P[c->row] / pt, dir[1] = -w->P[c->row + 1] / pt;
  dir[2] = dir[0], dir[3] = dir[1];                      /* the friction's direction */
  ap_cfr_set_mode(M, S, c, AP_CM_SLIDING);
  rc = sliding(s, c, t, q, shift, v, w);
  if (rc == AP_OK && bounce) ap_cfr_set_mode(M, S, c, AP_CM_AIRBORNE);
  else if (rc == AP_OK) after_sliding(s, c, v, vmax);
  return rc;
}

int ap_drv_contact_impact(ap_sim *s, int ci, double t, const double *q, double *v) {
  const ap_bmodel *M = ap_bm(s->m);
  const ap_mcon *c = &M->cons[ci];
  ap_data *d = s->d;
  ap_basis basis = d->basis;
  int sfe = d->speeds_from_e;
  imp_work w = {0};
  ap_cfr_set_mode(M, ap_bm_scratch(d), c, AP_CM_ROLLING);
  int rc = work_alloc(s->k, s->b, &w);
  if (rc != AP_OK) rc = ap_drv_fail(s, rc, "out of memory");
  if (rc == AP_OK) {
    rc = position_at(s, t, q);
    if (rc != AP_OK) rc = ap_drv_fail(s, rc < 0 ? rc : AP_ERR_SINGULAR, "contact '%s': impact "
                                      "at t = %.17g: %s", c->name, t, d->msg);
  }
  if (rc == AP_OK) rc = impact(s, c, t, q, v, &w);
  d->basis = basis, d->speeds_from_e = sfe;
  s->ev_stamp = -1;
  free(w.vs);
  free(w.iwork);
  return rc;
}
