/* CVODE backend: variable-order, variable-step linear multistep methods (SUNDIALS 6.x).
 *   adams  Adams-Moulton orders 1-12, nonlinear systems by fixed-point (functional)
 *          iteration: no Jacobian, for non-stiff problems.
 *   bdf    BDF orders 1-5, Newton iteration with a dense matrix (SUNDenseMatrix +
 *          SUNLinSol_Dense) and CVODE's difference-quotient Jacobian: for stiff problems.
 * One internal step per ap_step_one (CV_ONE_STEP, stop time set before every call: CVODE
 * clears it once reached). CVODE retries recoverable rhs failures itself (h / 4, up to 10
 * times). There is no fixed-step mode (ap_step_create refuses opts.h_fixed).
 * CVODE 6.4.1 with the fixed-point solver (adams) treats f < 0 inside the iteration like a
 * convergence failure and retries with a smaller step instead of stopping; the counted rhs
 * in stepper.c therefore keeps answering f's negative code without calling f again, so the
 * retries fail too and we report AP_ERR_CALLBACK.
 *
 * Layout: s->mem the CVODE memory; s->obj[0] SUNMatrix, obj[1] SUNLinearSolver (bdf),
 * obj[2] SUNNonlinearSolver (adams). CVodeReInit zeroes CVODE's counters, so they are added
 * to s->base first. Invariant: s->mem holds the last accepted state (s->t, s->yacc); after a
 * failed step CVODE is still there, after a non-finite result we re-initialize to it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include "appell/status.h"
#include "integrate/stepper.h"

#define NV(v) N_VGetArrayPointer((N_Vector)(v))

static int cv_rhs(realtype t, N_Vector y, N_Vector ydot, void *user) {
  return ap_step_rhs_eval(user, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
}

static void cv_err(int code, const char *module, const char *function, char *msg, void *user) {
  (void)code, (void)module;
  ap_step_sun_message(user, function, msg);
}

static int cv_flag_fail(ap_stepper *s, int flag) {
  char *name = CVodeGetReturnFlagName(flag);
  int status = ap_step_fail(s, flag, name);
  free(name);
  return status;
}

/* ---- creation ------------------------------------------------------------------------ */

/* The nonlinear solver: fixed point for Adams, dense Newton for BDF. */
/* CVODE clones A (its saved Jacobian) at the first step, and SUNDIALS 6.4's SUNMatClone
 * crashes when that allocation fails: the clone is made here, at creation, and A's clone
 * operation hands it over. The table is A's ops (its first member), freed with A. */
typedef struct cv_mat_ops {
  struct _generic_SUNMatrix_Ops ops;
  SUNMatrix spare;         /* the clone, until CVODE takes it */
} cv_mat_ops;

static SUNMatrix cv_mat_clone(SUNMatrix A) {
  cv_mat_ops *o = (cv_mat_ops *)(void *)A->ops;
  SUNMatrix B = o->spare;
  o->spare = NULL;
  return B ? B : SUNDenseMatrix(SUNDenseMatrix_Rows(A), SUNDenseMatrix_Columns(A), A->sunctx);
}

/* A dense n x n matrix with its clone made now; NULL when out of memory. */
static SUNMatrix cv_matrix(ap_stepper *s) {
  SUNMatrix A = SUNDenseMatrix(s->n, s->n, s->ctx);
  SUNMatrix B = A ? SUNDenseMatrix(s->n, s->n, s->ctx) : NULL;   /* SUNMatClone would crash */
  cv_mat_ops *o = B ? malloc(sizeof *o) : NULL;
  if (!o) {
    if (B) SUNMatDestroy(B);
    if (A) SUNMatDestroy(A);
    return NULL;
  }
  o->ops = *A->ops, o->ops.clone = cv_mat_clone, o->spare = B;
  free(A->ops);
  A->ops = &o->ops;
  return A;
}

static void cv_matrix_free(SUNMatrix A) {
  cv_mat_ops *o = (cv_mat_ops *)(void *)A->ops;
  if (o->spare) SUNMatDestroy(o->spare);
  SUNMatDestroy(A);
}

static int cv_solver(ap_stepper *s) {
  if (s->meth->table == CV_ADAMS) {
    SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(s->y, 0, s->ctx);
    s->obj[2] = nls;
    return nls ? CVodeSetNonlinearSolver(s->mem, nls) : CV_MEM_FAIL;
  }
  SUNMatrix A = cv_matrix(s);
  SUNLinearSolver ls = A ? SUNLinSol_Dense(s->y, A, s->ctx) : NULL;
  s->obj[0] = A, s->obj[1] = ls;
  int flag = ls ? CVodeSetLinearSolver(s->mem, ls, A) : CV_MEM_FAIL;
  return flag == CVLS_MEM_FAIL ? CV_MEM_FAIL : flag;   /* CVLS_MEM_FAIL is CV_CONV_FAILURE's -4 */
}

/* Native projection: CVODE projects the corrected state and its error estimate itself, so
 * the history stays consistent (no restart at order 1). */
static int cv_proj(realtype t, N_Vector ycur, N_Vector corr, realtype eps, N_Vector err,
                   void *user) {
  (void)eps;
  ap_stepper *s = user;
  return s->o.proj(t, NV(ycur), NV(corr), err ? NV(err) : NULL, s->user);
}

/* bdf: the Newton iteration's convergence coefficient, 0.003 instead of CVODE's 0.1. With the
 * Jacobian CVODE keeps for up to 50 steps, the default let iterates off the BDF solution pass
 * the test on a model whose Jacobian turns quickly (campaign seed 1006291: a spinning body on
 * a ball joint beside a knife edge): an error of about 2e-7 per step in one speed, a thousand
 * times the tolerance, that the error test does not see; the run ended 1.4e-5 off at rtol 1e-8
 * and 5e-6 to 2.5e-5 at rtol 1e-6, 1e-7. The Jacobian at every step, or a coefficient of 0.01
 * or less, bring it to 2.4e-8 at rtol 1e-8 (docs/testing.md), the latter at the same number of
 * evaluations (fewer steps, more Newton iterations each); 0.003 also keeps bdf's worst error on
 * the reference problems at rtol 1e-8 within 200 x rtol (accuracy.c; 0.01: 330 x). */
#define CV_NLS_COEF 0.003

/* Error weights with ap_step_opts.weight (stepper.c). */
static int cv_ewt(N_Vector y, N_Vector ewt, void *user) {
  return ap_step_ewt_fill(user, N_VGetArrayPointer(y), N_VGetArrayPointer(ewt));
}

static int cv_configure(ap_stepper *s, double t0) {
  const ap_step_opts *o = &s->o;
  int flag = CVodeInit(s->mem, cv_rhs, t0, s->y);
  if (flag == CV_SUCCESS) flag = CVodeSetUserData(s->mem, s);
  if (flag == CV_SUCCESS) flag = CVodeSStolerances(s->mem, o->rtol, o->atol);
  if (flag == CV_SUCCESS && o->weight)
    flag = CVodeWFtolerances(s->mem, cv_ewt);
  if (flag == CV_SUCCESS) flag = cv_solver(s);
  if (flag == CV_SUCCESS && s->meth->table != CV_ADAMS)
    flag = CVodeSetNonlinConvCoef(s->mem, CV_NLS_COEF);
  if (flag == CV_SUCCESS) flag = CVodeSetMaxNumSteps(s->mem, o->max_steps);
  if (flag == CV_SUCCESS && o->h_init > 0) flag = CVodeSetInitStep(s->mem, o->h_init);
  if (flag == CV_SUCCESS && o->h_max > 0) flag = CVodeSetMaxStep(s->mem, o->h_max);
  if (flag == CV_SUCCESS && o->proj) flag = CVodeSetProjFn(s->mem, cv_proj);
  return flag;
}

static void cv_destroy(ap_stepper *s) {
  if (s->mem) CVodeFree(&s->mem);
  if (s->obj[2]) SUNNonlinSolFree((SUNNonlinearSolver)s->obj[2]);
  if (s->obj[1]) SUNLinSolFree((SUNLinearSolver)s->obj[1]);
  if (s->obj[0]) cv_matrix_free((SUNMatrix)s->obj[0]);
  ap_step_release(s);
}

static int cv_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                     const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                     size_t msg_len) {
  ap_stepper *s = NULL;
  int rc = ap_step_alloc(meth, n, f, user, t0, y0, o, &s, msg, msg_len);
  if (rc != AP_OK) return rc;
  s->mem = CVodeCreate(meth->table, s->ctx);
  int flag = s->mem ? CVodeSetErrHandlerFn(s->mem, cv_err, s) : CV_MEM_FAIL;
  if (flag == CV_SUCCESS) flag = cv_configure(s, t0);
  if (flag != CV_SUCCESS) {
    char *name = CVodeGetReturnFlagName(flag);
    int nomem = flag == CV_MEM_FAIL || flag == CV_MEM_NULL;
    if (msg && msg_len)
      snprintf(msg, msg_len, "%s: %sCVODE setup failed (%s): %s", meth->name,
               nomem ? "out of memory: " : "", name, s->sun_msg);
    free(name);
    cv_destroy(s);
    return nomem ? AP_ERR_NOMEM : AP_ERR_SOLVER;
  }
  *out = s;
  return AP_OK;
}

/* ---- stepping ------------------------------------------------------------------------ */

static void cv_counters(const ap_stepper *s, ap_step_stats *st) {
  long v = 0;
  CVodeGetNumSteps(s->mem, &v), st->steps = v;
  CVodeGetNumErrTestFails(s->mem, &v), st->err_fails = v;
}

/* Re-initialize at (t, y): history, order and counters restart (counters kept in base). */
static int cv_reinit(ap_stepper *s, double t, const double *y) {
  ap_step_stats now;
  cv_counters(s, &now);
  s->base.steps += now.steps, s->base.err_fails += now.err_fails;
  memcpy(NV(s->tmp), y, sizeof(double) * (size_t)s->n);
  ap_step_jw_reset(s);                           /* the first step makes the Jacobian */
  return CVodeReInit(s->mem, t, s->tmp);
}

static int cv_reset(ap_stepper *s, double t, const double *y) {
  int flag = cv_reinit(s, t, y);
  if (flag != CV_SUCCESS) return cv_flag_fail(s, flag);
  ap_step_accept(s, t, y);
  return AP_OK;
}

/* Jacobian evaluations of BDF's linear solver so far (0 for Adams). */
static long cv_jac_evals(const ap_stepper *s) {
  long nje = 0;
  if (s->obj[1]) CVodeGetNumJacEvals(s->mem, &nje);
  return nje;
}

/* CVODE's step with the Jacobian made first when ap_step_jacobian_watch asks for it (a new
 * Newton matrix every step, and a new Jacobian, for this step only; 0 restores the defaults). */
static int cv_step(ap_stepper *s, double tstop, realtype *tret) {
  int force = ap_step_jw_force(s), flag = CV_SUCCESS;
  long nje = cv_jac_evals(s);
  double rho = ap_step_jw_rho(s);
  if (s->obj[1]) flag = CVodeSetJacFn(s->mem, rho > 0 ? ap_step_cv_jac : NULL);
  if (force) flag = CVodeSetLSetupFrequency(s->mem, 1);
  if (force && flag == CV_SUCCESS) flag = CVodeSetJacEvalFrequency(s->mem, 1);
  if (flag == CV_SUCCESS) flag = CVode(s->mem, tstop, s->y, tret, CV_ONE_STEP);
  if (force) CVodeSetLSetupFrequency(s->mem, 0), CVodeSetJacEvalFrequency(s->mem, 0);
  if (flag >= 0) ap_step_jw_stepped(s, cv_jac_evals(s) != nje);
  return flag;
}

static int cv_one(ap_stepper *s, double tstop, double *t, double *y) {
  (void)t, (void)y;                              /* the dispatcher copies (s->t, yacc) out */
  realtype tret = s->t;
  int flag = CVodeSetStopTime(s->mem, tstop);
  if (flag == CV_SUCCESS) flag = cv_step(s, tstop, &tret);
  if (flag < 0) return cv_flag_fail(s, flag);    /* CVODE stays at the last accepted step */
  int finite = 1;
  for (int i = 0; i < s->n; i++) finite = finite && isfinite(NV(s->y)[i]);
  if (!finite || s->rhs_neg) {                   /* roll back to the last accepted state */
    s->rhs_nan = !finite;
    int status = ap_step_fail(s, flag, finite ? "step done after f < 0" : "solution not finite");
    cv_reinit(s, s->t, s->yacc);
    return status;
  }
  ap_step_accept(s, tret, NV(s->y));
  return AP_OK;
}

static int cv_dky(ap_stepper *s, double t, double *y) {
  int flag = CVodeGetDky(s->mem, t, 0, s->tmp);
  if (flag != CV_SUCCESS) {
    char *name = CVodeGetReturnFlagName(flag);
    snprintf(s->msg, sizeof s->msg, "%s: no dense output at t = %.17g (%s): %s",
             s->meth->name, t, name, s->sun_msg);
    free(name);
    return flag == CV_BAD_T ? AP_ERR_ARG : AP_ERR_SOLVER;
  }
  memcpy(y, NV(s->tmp), sizeof(double) * (size_t)s->n);
  return AP_OK;
}

static void cv_stats(const ap_stepper *s, ap_step_stats *st) {
  realtype h = 0.0;
  cv_counters(s, st);
  st->steps += s->base.steps, st->err_fails += s->base.err_fails;
  CVodeGetLastStep(s->mem, &h), st->h_last = h;
}

const ap_step_backend ap_step_cvode = {"CVODE", cv_create, cv_reset, cv_one, cv_dky, cv_stats,
                                       cv_destroy};
