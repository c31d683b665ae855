/* The DAE cross-check: SUNDIALS IDA with Lagrange multipliers (docs/design.md §1, "The DAE
 * cross-check").
 *
 * Variables y = (q, v, lambda, mu), n + k + b + nphi of them, and the residual
 *
 *     F_q   = q' - N(q) v - Phi_q^T mu
 *     F_v   = g v' + h - Q - A^T lambda
 *     F_c   = A v + a0
 *     F_phi = phi(q, t)
 *
 * The last rows are the implicit holonomic constraints (loop closures, unit-quaternion norms)
 * of a body model in the stabilized index-2 form of Gear, Gupta and Leimkuhler (1985): their
 * velocity form is already among the rows of A (loops) or holds identically (quaternions,
 * Phi_q N = 0), and the extra multipliers mu move q along Phi_q^T, the gradient of phi in q,
 * which Phi_q Phi_q^T (non-singular for independent rows) turns into a correction of phi. On
 * the exact solution phi' = Phi_q N v + phi_t + Phi_q Phi_q^T mu = Phi_q Phi_q^T mu = 0, so
 * mu = 0; numerically mu is what keeps phi = 0 at each step instead of letting it drift with
 * the integrated velocity rows. Phi_q is the Jacobian in q (not in v): for N != I this is
 * what makes Phi_q^T mu a vector of q-space, and it lets the quaternion rows |p|^2 - 1
 * (whose gradient 2 p is normal to every N v) correct the norm.
 *
 * lambda and mu are algebraic (IDASetId 0) and left out of the error test
 * (IDASetSuppressAlg), as index-2 multipliers must be. Consistent initial values come from the
 * Appell solve (v' and lambda are known exactly there; mu = 0), so IDACalcIC is never called.
 * The residual runs the core's position and velocity stages with AP_BASIS_NONE: no
 * null-space basis is built. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "core/core.h"
#include "integrate/dae.h"
#include "linalg/linalg.h"

struct ap_dae {
  const ap_model *m;
  ap_data *d;
  SUNContext ctx;
  void *mem;
  N_Vector yy, yp, id, atol;
  SUNMatrix J;
  SUNLinearSolver LS;
  int ny, nphi;
  double *Phi_q, *dq;       /* (nphi x n) Jacobian of phi in q, (n) Phi_q^T mu */
  int res_status;           /* last failure of the residual */
  int nomem;                /* SUNDIALS reported a failed allocation */
  char res_msg[512];
  char msg[1024];
};

static int residual(double t, N_Vector yy, N_Vector yp, N_Vector rr, void *user) {
  ap_dae *s = user;
  const ap_model *m = s->m;
  ap_data *d = s->d;
  int n = m->n, k = m->k, b = m->b;
  const double *y = N_VGetArrayPointer(yy), *y1 = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  d->t = t;
  memcpy(d->q, y, sizeof(double) * (size_t)n);
  memcpy(d->v, y + n, sizeof(double) * (size_t)k);
  d->basis = AP_BASIS_NONE, d->speeds_from_e = 0;
  int rc = ap_fwd_position(m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(m, d);
  if (rc != AP_OK) {
    s->res_status = rc;
    memcpy(s->res_msg, d->msg, sizeof s->res_msg);
    return rc > 0 ? 1 : -1;
  }
  const double *lambda = y + n + k, *mu = lambda + b;
  ap_la_gemv(n, k, d->N, d->v, r);                         /* F_q = q' - N v - Phi_q^T mu */
  for (int i = 0; i < n; i++) r[i] = y1[i] - r[i];
  if (s->nphi > 0) {
    int np = s->nphi;
    memset(s->Phi_q, 0, sizeof(double) * (size_t)np * (size_t)n);
    rc = m->ev.phi(m, d, ((ap_scratch *)d->internal)->ev, r + n + k + b, s->Phi_q);
    if (rc != AP_OK) {
      s->res_status = rc;
      memcpy(s->res_msg, d->msg, sizeof s->res_msg);
      return rc > 0 ? 1 : -1;
    }
    ap_la_gemv_t(np, n, s->Phi_q, mu, s->dq);
    for (int i = 0; i < n; i++) r[i] -= s->dq[i];
  }
  ap_la_gemv(k, k, d->g, y1 + n, r + n);                   /* F_v = g v' + h - Q - A^T l */
  if (b > 0) {
    ap_la_gemv_t(b, k, d->A, lambda, d->w);                /* w is free here: A^T lambda */
    ap_la_gemv(b, k, d->A, d->v, r + n + k);               /* F_c = A v + a0 */
    for (int s2 = 0; s2 < b; s2++) r[n + k + s2] += d->a0[s2];
  } else {
    memset(d->w, 0, sizeof(double) * (size_t)k);
  }
  for (int i = 0; i < k; i++) r[n + i] += d->h[i] - d->Q[i] - d->w[i];
  return 0;
}

static void err_handler(int code, const char *module, const char *function, char *text,
                        void *user) {
  ap_dae *s = user;
  snprintf(s->msg, sizeof s->msg, "%s.%s (flag %d): %s", module, function, code, text);
  if ((code == IDA_MEM_FAIL && !strcmp(module, "IDA")) ||
      (code == IDALS_MEM_FAIL && !strcmp(module, "IDALS")))
    s->nomem = 1;
}

static int ap_dae_nomem(const ap_model *m, char *msg, size_t msg_len) {
  if (msg && msg_len) snprintf(msg, msg_len, "IDA setup for system '%s': out of memory", m->name);
  return AP_ERR_NOMEM;
}

int ap_dae_create(const ap_model *m, ap_data *d, double t0, const double *y0,
                  const double *yp0, const ap_step_opts *o, ap_dae **out, char *msg,
                  size_t msg_len) {
  *out = NULL;
  ap_dae *s = calloc(1, sizeof *s);
  if (!s) return ap_dae_nomem(m, msg, msg_len);
  s->m = m, s->d = d, s->nphi = m->ev.phi ? m->nphi : 0;
  s->ny = m->n + m->k + m->b + s->nphi;
  if (s->nphi > 0) {
    s->Phi_q = calloc((size_t)s->nphi * (size_t)m->n + (size_t)m->n, sizeof *s->Phi_q);
    if (!s->Phi_q) {
      free(s);
      return ap_dae_nomem(m, msg, msg_len);
    }
    s->dq = s->Phi_q + (size_t)s->nphi * (size_t)m->n;
  }
  int ok = SUNContext_Create(NULL, &s->ctx) == 0;
  if (ok) {
    s->yy = N_VNew_Serial(s->ny, s->ctx), s->yp = N_VNew_Serial(s->ny, s->ctx);
    s->id = N_VNew_Serial(s->ny, s->ctx);
    s->mem = IDACreate(s->ctx);
    ok = s->yy && s->yp && s->id && s->mem;
  }
  if (ok) {
    memcpy(N_VGetArrayPointer(s->yy), y0, sizeof(double) * (size_t)s->ny);
    memcpy(N_VGetArrayPointer(s->yp), yp0, sizeof(double) * (size_t)s->ny);
    double *id = N_VGetArrayPointer(s->id);
    for (int i = 0; i < s->ny; i++) id[i] = i < m->n + m->k ? 1.0 : 0.0;
    s->atol = N_VNew_Serial(s->ny, s->ctx);
    ok = s->atol != NULL;
  }
  if (ok) {
    double *at = N_VGetArrayPointer(s->atol);
    /* Index-2 multipliers are out of the error test (IDASetSuppressAlg) but still weigh in
     * IDA's Newton convergence test, where their updates scale like 1/h: with the user's
     * atol there, the first tiny steps fail to converge (measured: the knife edge at
     * rtol 1e-9). They get 10 rtol (1 + |lambda0|); so do the GGL multipliers mu (zero on
     * the exact solution; tighter or looser values, 1e-12 to 1e-3, changed the cross-check
     * differences only irregularly, measured on the body models of test_dae_bodies). */
    double lam0 = 0.0;
    for (int i = m->n + m->k; i < s->ny; i++) lam0 = fmax(lam0, fabs(y0[i]));
    for (int i = 0; i < s->ny; i++)
      at[i] = i < m->n + m->k ? o->atol : 10.0 * o->rtol * (1.0 + lam0);
    ok = IDASetErrHandlerFn(s->mem, err_handler, s) == IDA_SUCCESS &&
         IDAInit(s->mem, residual, t0, s->yy, s->yp) == IDA_SUCCESS &&
         IDASVtolerances(s->mem, o->rtol, s->atol) == IDA_SUCCESS &&
         IDASetUserData(s->mem, s) == IDA_SUCCESS &&
         IDASetId(s->mem, s->id) == IDA_SUCCESS &&
         IDASetSuppressAlg(s->mem, SUNTRUE) == IDA_SUCCESS &&
         IDASetMaxNumSteps(s->mem, o->max_steps > 0 ? o->max_steps : 100000) == IDA_SUCCESS;
    if (ok && o->h_init > 0) ok = IDASetInitStep(s->mem, o->h_init) == IDA_SUCCESS;
    if (ok && o->h_max > 0) ok = IDASetMaxStep(s->mem, o->h_max) == IDA_SUCCESS;
  }
  if (ok) {
    s->J = SUNDenseMatrix(s->ny, s->ny, s->ctx);
    s->LS = s->J ? SUNLinSol_Dense(s->yy, s->J, s->ctx) : NULL;
    ok = s->LS && IDASetLinearSolver(s->mem, s->LS, s->J) == IDA_SUCCESS;
  }
  if (!ok) {   /* no message from IDA: an object could not be allocated */
    int rc = s->nomem || !s->msg[0] ? AP_ERR_NOMEM : AP_ERR_SOLVER;
    if (msg && msg_len)
      snprintf(msg, msg_len, "IDA setup failed for system '%s': %.300s", m->name,
               s->msg[0] ? s->msg : "out of memory");
    ap_dae_free(s);
    return rc;
  }
  *out = s;
  return AP_OK;
}

int ap_dae_one(ap_dae *s, double tstop, double *t, double *y) {
  s->res_status = AP_OK;
  if (IDASetStopTime(s->mem, tstop) != IDA_SUCCESS) return AP_ERR_SOLVER;
  double tret = *t;
  int flag = IDASolve(s->mem, tstop, &tret, s->yy, s->yp, IDA_ONE_STEP);
  if (flag < 0) {
    if (s->res_status < 0) {
      snprintf(s->msg, sizeof s->msg, "%s", s->res_msg);
      return s->res_status;
    }
    char tmp[256];
    memcpy(tmp, s->msg, sizeof tmp);   /* the handler's text, cut to fit */
    tmp[sizeof tmp - 1] = '\0';
    snprintf(s->msg, sizeof s->msg, "IDA failed at t = %.17g for system '%s': %.200s%s%.200s",
             tret, s->m->name, tmp, s->res_status > 0 ? "; last residual failure: " : "",
             s->res_status > 0 ? s->res_msg : "");
    return flag == IDA_MEM_FAIL ? AP_ERR_NOMEM : AP_ERR_SOLVER;
  }
  *t = tret;
  memcpy(y, N_VGetArrayPointer(s->yy), sizeof(double) * (size_t)s->ny);
  return AP_OK;
}

void ap_dae_stats(const ap_dae *s, ap_step_stats *st) {
  long v = 0;
  memset(st, 0, sizeof *st);
  if (IDAGetNumSteps(s->mem, &v) == IDA_SUCCESS) st->steps = v;
  if (IDAGetNumResEvals(s->mem, &v) == IDA_SUCCESS) st->rhs_evals = v;
  if (IDAGetNumErrTestFails(s->mem, &v) == IDA_SUCCESS) st->err_fails = v;
  if (IDAGetNumNonlinSolvConvFails(s->mem, &v) == IDA_SUCCESS) st->rhs_fails = v;
  double h = 0;
  if (IDAGetLastStep(s->mem, &h) == IDA_SUCCESS) st->h_last = h;
}

const char *ap_dae_message(const ap_dae *s) { return s->msg; }

void ap_dae_free(ap_dae *s) {
  if (!s) return;
  if (s->mem) IDAFree(&s->mem);
  if (s->LS) SUNLinSolFree(s->LS);
  if (s->J) SUNMatDestroy(s->J);
  if (s->yy) N_VDestroy(s->yy);
  if (s->yp) N_VDestroy(s->yp);
  if (s->id) N_VDestroy(s->id);
  if (s->atol) N_VDestroy(s->atol);
  if (s->ctx) SUNContext_Free(&s->ctx);
  free(s->Phi_q);
  free(s);
}
