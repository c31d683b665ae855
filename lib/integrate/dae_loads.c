/* DAE mode with friction under a planar chassis: the sliding wheels' Coulomb force with the
 * wheel's true load as its normal force, solved by IDA together with the accelerations and the
 * multipliers (docs/vehicles.md "Skidding and breaking away").
 *
 * Under a planar chassis a wheel's contact row .z vanishes (the joint holds the chassis up), so
 * IDA has no multiplier for it; its normal force is its load N_j (model/loads.c): the chassis
 * joint's vertical reaction and tilting moments shared among the contacts, from the Newton-Euler
 * balance of the vehicle at the accelerations v' and the multipliers lambda. N_j is affine in
 * (v', lambda) at a given (t, q, v), and v', lambda are IDA's unknowns (y' of v and of the
 * impulses), so the residual evaluates it there:
 *
 *     F_v = g v' + h - Q - (A_s^T + W_s) lambda - sum_j f_j N_j(v', lambda)
 *
 * with f_j = -mu_k T_j^T s^_j the Coulomb force per unit normal force (model/con_friction.c),
 * and IDA's Newton iteration solves the loads with the accelerations (the minimal mode's linear
 * system of con_friction.c, written implicitly). The Newton matrix needs the force's
 * derivatives in v' and lambda, exact since the load is affine: column c of d/dv' is
 * sum_j f_j (N_j(e_c, 0) - N_j(0, 0)), likewise for lambda (k + b + 1 load evaluations per
 * sliding wheel, at the Jacobian's base point only); its derivatives in q and v come from the
 * residual's difference quotients like every other term.
 *
 * The coupling is set when IDA is made (at creation and at each switch of a contact's mode) and
 * only while such a wheel slides: a rolling one needs no force, and the switch events read the
 * load from IDA's own accelerations and multipliers (ap_drv_dae_cm_normal). */
#include <ida/ida.h>
#include <math.h>
#include <string.h>

#include "integrate/contact_int.h"
#include "integrate/dae_int.h"
#include "linalg/linalg.h"

/* 1 when contact c slides with its load as normal force. */
static int sliding_by_load(const ap_bmodel *M, const double *S, const ap_mcon *c) {
  return c->fric >= 0 && ap_bm_wheel_by_load(M, c) && ap_cfr_mode(M, S, c) == AP_CM_SLIDING;
}

static int dae_load(void *user, ap_data *d, const double *vd, const double *lam, double *F,
                    double *work) {
  ap_sim *s = user;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = ap_bm_scratch(d);
  int k = s->k;
  memset(F, 0, sizeof(double) * (size_t)k);
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (!sliding_by_load(M, S, c)) continue;
    double N = 0.0;
    int rc = ap_bm_wheel_load_at(s->m, d, vd, lam, ci, &N, NULL);
    if (rc != AP_OK) return rc;
    ap_cfr_coulomb(M, S, c, work);
    for (int j = 0; j < k; j++) F[j] += work[j] * N;
  }
  return AP_OK;
}

/* Column x of a derivative: f times the change of contact ci's load from N0 when the unit
 * entry of vd or lam (work) is set. */
static int load_column(const ap_sim *s, const ap_data *d, int ci, const double *vd,
                       const double *lam, double N0, const double *f, double *col) {
  double N = 0.0;
  int rc = ap_bm_wheel_load_at(s->m, d, vd, lam, ci, &N, NULL);
  for (int j = 0; rc == AP_OK && j < s->k; j++) col[j] += f[j] * (N - N0);
  return rc;
}

static int dae_load_lin(void *user, ap_data *d, double *Fv, double *Fl, double *work) {
  ap_sim *s = user;
  const ap_bmodel *M = ap_bm(s->m);
  double *S = ap_bm_scratch(d), *lu = work, *vu = lu + s->b, *f = vu + s->k;
  int k = s->k, b = s->b, rc = AP_OK;
  memset(Fv, 0, sizeof(double) * (size_t)k * (size_t)k);
  memset(Fl, 0, sizeof(double) * (size_t)k * (size_t)b);
  memset(work, 0, sizeof(double) * (size_t)(b + k));
  for (int ci = 0; rc == AP_OK && ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (!sliding_by_load(M, S, c)) continue;
    double N0 = 0.0;
    rc = ap_bm_wheel_load_at(s->m, d, vu, lu, ci, &N0, NULL);
    ap_cfr_coulomb(M, S, c, f);
    for (int x = 0; rc == AP_OK && x < k; x++) {
      vu[x] = 1.0;
      rc = load_column(s, d, ci, vu, lu, N0, f, Fv + (size_t)x * k);
      vu[x] = 0.0;
    }
    for (int r = 0; rc == AP_OK && r < b; r++) {
      lu[r] = 1.0;
      rc = load_column(s, d, ci, vu, lu, N0, f, Fl + (size_t)r * k);
      lu[r] = 0.0;
    }
  }
  return rc;
}

ap_dae_couple ap_drv_dae_couple(ap_sim *s) {
  ap_dae_couple cp = {ap_drv_dae_coulomb, s, NULL, NULL};
  if (!s->cm) return cp;   /* no contact modes (cp unused) */
  const ap_bmodel *M = ap_bm(s->m);
  const double *S = ap_bm_scratch(s->d);
  for (int ci = 0; ci < M->nc; ci++)
    if (sliding_by_load(M, S, &M->cons[ci])) cp.load = dae_load, cp.lin = dae_load_lin;
  return cp;
}

int ap_dae_accelerations(ap_dae *s, double t, double *vd) {
  int kused = 0;
  const double *x = N_VGetArrayPointer(s->yp);
  if (IDAGetLastOrder(s->mem, &kused) == IDA_SUCCESS && kused > 0) {
    if (!s->dk) s->dk = N_VNew_Serial(s->ny, s->ctx);
    if (!s->dk) return AP_ERR_NOMEM;
    if (IDAGetDky(s->mem, t, 1, s->dk) != IDA_SUCCESS) return AP_ERR_SOLVER;
    x = N_VGetArrayPointer(s->dk);
  }
  memcpy(vd, x + s->n, sizeof(double) * (size_t)s->k);
  return AP_OK;
}

double ap_drv_dae_cm_normal(ap_sim *s, double t, const double *lam, const ap_mcon *c,
                            double *vd, double *ft) {
  double N = NAN;
  if (!ap_bm_wheel_by_load(ap_bm(s->m), c)) return ap_drv_cm_normal(s, lam, c, ft);
  ft[0] = lam[c->row], ft[1] = lam[c->row + 1];
  if (ap_dae_accelerations(s->dae, t, vd) != AP_OK ||
      ap_bm_wheel_load_at(s->m, s->d, vd, lam, (int)(c - ap_bm(s->m)->cons), &N, NULL) != AP_OK)
    return NAN;
  return N;
}

