/* The DAE driver's callbacks for IDA (dae_int.h; the method is described at the top of
 * dae.c): the residual F = (F_q, F_v, F_c, F_phi) of (q, v, Lambda, M), the error weights of
 * the impulses from the maps Pl and Pm (independent of the step size), and the Newton matrix
 * dF/dy + cj dF/dy', exact where F is linear in y and by difference quotients in q and v.
 * With the loads' coupled force (ap_dae_couple.load: a sliding wheel under a planar chassis,
 * dae_loads.c) F_v has - F(v', lambda) besides, affine in v' and lambda: the Newton matrix's
 * v' and lambda columns get -cj times its derivatives (ap_dae_couple.lin, at the base point). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "integrate/dae_int.h"
#include "linalg/linalg.h"

/* ---- the residual ------------------------------------------------------------------------- */

static int res_fail(ap_dae *s, int rc) {
  s->res_status = rc;
  memcpy(s->res_msg, s->d->msg, sizeof s->res_msg);
  return rc > 0 ? 1 : -1;
}

int ap_dae_residual(double t, N_Vector yy, N_Vector yp, N_Vector rr, void *user) {
  ap_dae *s = user;
  const ap_model *m = s->m;
  ap_data *d = s->d;
  int n = s->n, k = s->k, b = s->b, bs = s->bs, np = s->nphi;
  const double *y = N_VGetArrayPointer(yy), *y1 = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  s->nres++;
  for (int i = 0; i < n + k; i++)
    if (!isfinite(y[i]) || !isfinite(y1[i]) || !isfinite(t)) {
      ap_core_msg(d, "system '%s': IDA's trial point has %s = %g (derivative %g) at t = %g: "
                  "the step diverged", m->name, i < n ? ap_model_coord_name(m, i) :
                  ap_model_speed_name(m, i - n), y[i], y1[i], t);
      return res_fail(s, AP_ERR_NAN);
    }
  d->t = t;
  memcpy(d->q, y, sizeof(double) * (size_t)n);
  memcpy(d->v, y + n, sizeof(double) * (size_t)k);
  d->basis = AP_BASIS_NONE, d->speeds_from_e = 0;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(m, d);
  if (rc == AP_OK && s->cp.fn) rc = s->cp.fn(s->cp.user, d, s->W);   /* before F_v reads Q */
  const double *lambda = y1 + n + k, *mu = lambda + bs;   /* the impulses' derivatives */
  if (rc == AP_OK && s->cp.load) {                         /* the loads' force at (v', lambda) */
    memset(s->lamf, 0, sizeof(double) * (size_t)b);
    for (int c = 0; c < bs; c++) s->lamf[s->rows[c]] = lambda[c];
    rc = s->cp.load(s->cp.user, d, y1 + n, s->lamf, s->lF, s->lw);
  }
  if (rc != AP_OK) return res_fail(s, rc);
  ap_la_gemv(n, k, d->N, d->v, r);                         /* F_q = q' - N v - Phi_s^T mu */
  for (int i = 0; i < n; i++) r[i] = y1[i] - r[i];
  if (np > 0) {
    memset(s->Phi_q, 0, sizeof(double) * (size_t)np * (size_t)n);
    rc = m->ev.phi(m, d, ((ap_scratch *)d->internal)->ev, s->phi, s->Phi_q);
    if (rc != AP_OK) return res_fail(s, rc);
    for (int c = 0; c < s->nps; c++) {
      int row = s->prows[c];
      r[n + k + bs + c] = s->phi[row];
      for (int i = 0; i < n; i++) r[i] -= s->Phi_q[row + (size_t)i * np] * mu[c];
    }
  }
  ap_la_gemv(k, k, d->g, y1 + n, r + n);                   /* F_v = g v' + h - Q - A_s^T l */
  for (int i = 0; i < k; i++) r[n + i] += d->h[i] - d->Q[i];
  for (int i = 0; s->cp.load && i < k; i++) r[n + i] -= s->lF[i];   /* - F */
  for (int c = 0; c < bs; c++) {                           /* F_c = A_s v + a0_s */
    int row = s->rows[c];
    double fc = d->a0[row];
    for (int i = 0; i < k; i++) {
      double a = d->A[row + (size_t)i * b];
      fc += a * d->v[i];
      r[n + i] -= a * lambda[c];
    }
    r[n + k + c] = fc;
  }
  for (int c = 0; s->cp.fn && c < bs; c++) {               /* - W_s lambda */
    const double *w = s->W + (size_t)s->rows[c] * k;
    for (int i = 0; i < k; i++) r[n + i] -= w[i] * lambda[c];
  }
  return 0;
}

/* ---- weights and the Newton matrix --------------------------------------------------------- */

int ap_dae_load_lin(ap_dae *s, double *jA) {
  if (!s->cp.load) return AP_OK;
  int k = s->k, bs = s->bs, rc = s->cp.lin(s->cp.user, s->d, s->lFv, s->lFl, s->lw);
  if (rc != AP_OK) {
    res_fail(s, rc);
    return rc;
  }
  for (int c = 0; jA && c < bs; c++)
    for (int i = 0; i < k; i++) jA[c + (size_t)i * bs] += s->lFl[i + (size_t)s->rows[c] * k];
  return AP_OK;
}

/* The multipliers' maps (after a residual evaluation, from the data's g, A and s->Phi_q):
 * Pl = (A_s g^-1 A_s^T)^-1 A_s g^-1 g = (A_s M)^-1 A_s with M = g^-1 A_s^T (bs x k), the
 * change of lambda that moves v by a given dv along the constraint forces' directions (P M = I),
 * and Pm = (Phi_s Phi_s^T)^-1 Phi_s (nps x n), the same for mu and q. A factorization that fails
 * (rows become dependent) keeps the last maps. */
void ap_dae_multiplier_scales(ap_dae *s) {
  int k = s->k, b = s->b, n = s->n, bs = s->bs, nps = s->nps, np = s->nphi;
  double *S = s->Sf, *M = s->Ms;
  if (bs > 0) {
    memcpy(s->gf, s->d->g, sizeof(double) * (size_t)k * k);
    if (ap_la_chol(k, s->gf, NULL, NULL, NULL) == AP_OK) {
      for (int c = 0; c < bs; c++) {
        double *col = M + (size_t)c * k;
        for (int i = 0; i < k; i++) col[i] = s->d->A[s->rows[c] + (size_t)i * b];
        ap_la_chol_solve(k, s->gf, col);
      }
      for (int c = 0; c < bs; c++)                       /* S = A_s M (lower triangle) */
        for (int r = c; r < bs; r++) {
          double x = 0.0;
          for (int i = 0; i < k; i++)
            x += s->d->A[s->rows[r] + (size_t)i * b] * M[i + (size_t)c * k];
          S[r + (size_t)c * bs] = x;
        }
      if (ap_la_chol(bs, S, NULL, NULL, NULL) == AP_OK) {
        double *col = s->colw;
        for (int i = 0; i < k; i++) {                     /* Pl(:, i) = S^-1 A_s(:, i) */
          for (int c = 0; c < bs; c++) col[c] = s->d->A[s->rows[c] + (size_t)i * b];
          ap_la_chol_solve(bs, S, col);
          memcpy(s->Pl + (size_t)i * bs, col, sizeof(double) * (size_t)bs);
        }
      }
    }
  }
  if (nps > 0) {
    for (int c = 0; c < nps; c++)                          /* S = Phi_s Phi_s^T */
      for (int r = c; r < nps; r++) {
        double x = 0.0;
        for (int i = 0; i < n; i++)
          x += s->Phi_q[s->prows[r] + (size_t)i * np] * s->Phi_q[s->prows[c] + (size_t)i * np];
        S[r + (size_t)c * nps] = x;
      }
    if (ap_la_chol(nps, S, NULL, NULL, NULL) == AP_OK) {
      double *col = s->colw;
      for (int i = 0; i < n; i++) {
        for (int c = 0; c < nps; c++) col[c] = s->Phi_q[s->prows[c] + (size_t)i * np];
        ap_la_chol_solve(nps, S, col);
        memcpy(s->Pm + (size_t)i * nps, col, sizeof(double) * (size_t)nps);
      }
    }
  }
}

/* IDA's error weights (IDAWFtolerances): 1 / (rtol |y_i| + atol) for q and v. An impulse is
 * weighed by how far it moves when v (or q) moves within its tolerance along the constraint
 * forces: v moves by M dLambda, so dLambda = Pl dv and Lambda_c's tolerance is
 * sum_i |Pl_ci| tol(v_i); M_r's is sum_i |Pm_ri| tol(q_i) (see the note at the top). */
int ap_dae_weights(N_Vector yv, N_Vector ewt, void *user) {
  ap_dae *s = user;
  int n = s->n, k = s->k, bs = s->bs, nps = s->nps;
  const double *y = N_VGetArrayPointer(yv);
  double *w = N_VGetArrayPointer(ewt);
  for (int i = 0; i < n + k; i++) {
    double tol = s->rtol * fabs(y[i]) + fmax(s->atol, AP_DAE_ATOL_EPS * DBL_EPSILON *
                                                         (i < n ? s->qtyp : s->vtyp));
    if (!(tol > 0)) return -1;
    w[i] = 1.0 / tol;
  }
  for (int c = 0; c < bs; c++) {
    double tol = 0.0;
    for (int i = 0; i < k; i++) tol += fabs(s->Pl[c + (size_t)i * bs]) / w[n + i];
    w[n + k + c] = 1.0 / tol;
  }
  for (int r = 0; r < nps; r++) {
    double tol = 0.0;
    for (int i = 0; i < n; i++) tol += fabs(s->Pm[r + (size_t)i * nps]) / w[i];
    w[n + k + bs + r] = 1.0 / tol;
  }
  for (int i = n + k; i < s->ny; i++)
    if (!(w[i] > 0) || !isfinite(w[i])) w[i] = 1.0 / (s->rtol * fabs(y[i]) + s->atol);
  return 0;
}

/* The Newton matrix J = dF/dy + cj dF/dy' (IDALsJacFn; see the note at the top). */
int ap_dae_jacobian(double t, double cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                    void *user, N_Vector t1, N_Vector t2, N_Vector t3) {
  ap_dae *s = user;
  int n = s->n, k = s->k, b = s->b, bs = s->bs, np = s->nps, nd = n + k;
  double *y = N_VGetArrayPointer(yy), *y1 = N_VGetArrayPointer(yp), h = 0.0;
  const double *f0 = N_VGetArrayPointer(t3), *f1 = N_VGetArrayPointer(t2);
  (void)rr, (void)t1;
  IDAGetCurrentStep(s->mem, &h);
  int rc = ap_dae_residual(t, yy, yp, t3, s);                     /* the data at the base point */
  if (rc != 0) return rc;
  memcpy(s->jg, s->d->g, sizeof(double) * (size_t)k * k);
  memcpy(s->jN, s->d->N, sizeof(double) * (size_t)n * k);
  for (int c = 0; c < bs; c++)
    for (int i = 0; i < k; i++) s->jA[c + (size_t)i * bs] = s->d->A[s->rows[c] + (size_t)i * b];
  for (int c = 0; c < np; c++)
    for (int i = 0; i < n; i++)
      s->jP[c + (size_t)i * np] = s->Phi_q[s->prows[c] + (size_t)i * s->nphi];
  if (s->cp.fn) memcpy(s->jW, s->W, sizeof(double) * (size_t)k * b);
  if (ap_dae_load_lin(s, NULL) != AP_OK) return s->res_status > 0 ? 1 : -1;
  ap_dae_multiplier_scales(s);
  SUNMatZero(J);
  for (int j = 0; j < nd; j++) {                           /* q and v columns */
    double yj = y[j], typ = j < n ? s->qtyp : s->vtyp;
    double inc = sqrt(DBL_EPSILON) * fmax(fmax(fabs(yj), fabs(h * y1[j])), typ);
    y[j] = yj + inc;
    inc = y[j] - yj;
    rc = ap_dae_residual(t, yy, yp, t2, s);
    y[j] = yj;
    if (rc != 0) return rc;
    double *col = SUNDenseMatrix_Column(J, j);
    for (int i = 0; i < nd + bs; i++) col[i] = (f1[i] - f0[i]) / inc;
    if (j < n) {
      col[j] += cj;                                        /* dF_q/dq' = I */
      for (int r = 0; r < np; r++) col[nd + bs + r] = s->jP[r + (size_t)j * np];
    } else {
      int c = j - n;
      for (int i = 0; i < n; i++) col[i] = -s->jN[i + (size_t)c * n];
      for (int i = 0; i < k; i++) col[n + i] += cj * s->jg[i + (size_t)c * k];
      for (int i = 0; s->cp.load && i < k; i++) col[n + i] -= cj * s->lFv[i + (size_t)c * k];
      for (int r = 0; r < bs; r++) col[nd + r] = s->jA[r + (size_t)c * bs];
    }
  }
  for (int c = 0; c < bs; c++) {                    /* cj dF_v/dlambda = -cj (A_s^T + W_s) */
    double *col = SUNDenseMatrix_Column(J, nd + c);
    for (int i = 0; i < k; i++) col[n + i] = -cj * s->jA[c + (size_t)i * bs];
    for (int i = 0; s->cp.fn && i < k; i++) col[n + i] -= cj * s->jW[i + (size_t)s->rows[c] * k];
    for (int i = 0; s->cp.load && i < k; i++) col[n + i] -= cj * s->lFl[i + (size_t)s->rows[c] * k];
  }
  for (int r = 0; r < np; r++) {                           /* cj dF_q/dmu = -cj Phi_q^T */
    double *col = SUNDenseMatrix_Column(J, nd + bs + r);
    for (int i = 0; i < n; i++) col[i] = -cj * s->jP[r + (size_t)i * np];
  }
  return 0;
}

void ap_dae_err_handler(int code, const char *module, const char *function, char *text,
                        void *user) {
  ap_dae *s = user;
  snprintf(s->msg, sizeof s->msg, "%s.%s (flag %d): %s", module, function, code, text);
  if ((code == IDA_MEM_FAIL && !strcmp(module, "IDA")) ||
      (code == IDALS_MEM_FAIL && !strcmp(module, "IDALS")))
    s->nomem = 1;
}

