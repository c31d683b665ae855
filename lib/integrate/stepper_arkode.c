/* ARKODE backend: explicit Runge-Kutta methods through ERKStep (SUNDIALS 6.x), adaptive with
 * an embedded pair or at fixed steps (opts.h_fixed), one internal step per ap_step_one in
 * ARK_ONE_STEP mode with the stop time set before every call.
 *
 * The FSAL repair. SUNDIALS 6.4.1 ERKStep (before LLNL/sundials PR #324, issue #311) treats
 * every table with c[s-1] = 1 as first-same-as-last: it takes the last stage derivative
 * F[s-1] = f(t_n + h, Y_s) as f(t_{n+1}, y_{n+1}), the first stage of the next step and the
 * end slope of the dense output, even when the last row of A differs from b, so Y_s differs
 * from y_{n+1}. For Verner 8-5-6 this drops the observed order from 6 to about 3, for
 * Fehlberg 13-7-8 from 8 to about 7; RK4 and Heun-Euler are affected too. We therefore hand
 * ERKStep a table that is genuinely FSAL: when the last row of A is not b we append a stage
 * with row b, c = 1 and weights b = d = 0. Its derivative is exactly f(t_{n+1}, y_{n+1}); the
 * propagated solution and the embedding are unchanged (the new stage carries no weight), and
 * the cost is the same s evaluations per step that a correct non-FSAL step needs.
 *
 * Invariant: s->mem always holds the state (s->t, s->yacc) or one accepted step ahead of it.
 * A recoverable rhs failure (f > 0, or NaN/Inf in ydot) makes ERKStep 6.4.1 give up the step
 * (ARK_UNREC_RHSFUNC_ERR), so the retry is done here: restart from the last accepted state
 * with a step 4 times smaller, at most AP_ARK_RETRIES times. */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>

#include "appell/status.h"
#include "integrate/stepper.h"

#define AP_ARK_RETRIES 10
#define AP_ARK_MAX_STAGES 16
#define NV(v) N_VGetArrayPointer((N_Vector)(v))

/* ---- Butcher tables ------------------------------------------------------------------ */

/* Classic RK4 (Kutta 1901), no embedding. */
static ARKodeButcherTable rk4_table(void) {
  realtype c[4] = {0.0, 0.5, 0.5, 1.0};
  realtype A[16] = {0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0,
                    0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  realtype b[4] = {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0};
  return ARKodeButcherTable_Create(4, 4, 0, c, A, b, NULL);
}

/* 1 when the last stage is y_{n+1} itself (c = 1 and last row of A = b). */
static int is_fsal(ARKodeButcherTable B) {
  int s = B->stages;
  if (B->c[s - 1] != 1.0) return 0;
  for (int j = 0; j < s; j++)
    if (fabs(B->A[s - 1][j] - B->b[j]) > 1e-15) return 0;
  return 1;
}

/* B with a stage appended that makes it FSAL (see the note at the top); B is consumed. */
static ARKodeButcherTable make_fsal(ARKodeButcherTable B) {
  int s = B->stages, t = s + 1;
  if (is_fsal(B) || t > AP_ARK_MAX_STAGES) return B;
  realtype A[AP_ARK_MAX_STAGES * AP_ARK_MAX_STAGES] = {0}, b[AP_ARK_MAX_STAGES] = {0};
  realtype c[AP_ARK_MAX_STAGES] = {0}, d[AP_ARK_MAX_STAGES] = {0};
  for (int i = 0; i < s; i++) {
    for (int j = 0; j < s; j++) A[i * t + j] = B->A[i][j];
    A[s * t + i] = B->b[i];
    b[i] = B->b[i], c[i] = B->c[i], d[i] = B->d ? B->d[i] : 0.0;
  }
  c[s] = 1.0;
  ARKodeButcherTable F = ARKodeButcherTable_Create(t, B->q, B->p, c, A, b, B->d ? d : NULL);
  ARKodeButcherTable_Free(B);
  return F;
}

/* ARKODE's tables, loaded once per process and then copied: SUNDIALS 6.4's
 * ARKodeButcherTable_LoadERK crashes when one of its allocations fails, whereas
 * ARKodeButcherTable_Copy checks them, so after the first ERK stepper of a process (a sweep's
 * first run) creating one cannot crash there. The loaded tables are constants, kept for the
 * life of the process; the mutex makes the first load safe from several threads. */
static pthread_mutex_t tables_mu = PTHREAD_MUTEX_INITIALIZER;
static ARKodeButcherTable tables[ARKODE_MAX_ERK_NUM - ARKODE_MIN_ERK_NUM + 1];

static ARKodeButcherTable load_table(int id) {
  if (id < ARKODE_MIN_ERK_NUM || id > ARKODE_MAX_ERK_NUM) return NULL;
  pthread_mutex_lock(&tables_mu);
  ARKodeButcherTable *t = &tables[id - ARKODE_MIN_ERK_NUM];
  if (!*t) *t = ARKodeButcherTable_LoadERK((ARKODE_ERKTableID)id);
  ARKodeButcherTable B = *t ? ARKodeButcherTable_Copy(*t) : NULL;
  pthread_mutex_unlock(&tables_mu);
  return B;
}

static ARKodeButcherTable method_table(const ap_step_method *meth) {
  ARKodeButcherTable B = meth->table == ARKODE_ERK_NONE ? rk4_table() : load_table(meth->table);
  return B ? make_fsal(B) : NULL;
}

int ap_step_butcher(const ap_step_method *meth, int max_s, int *s, int *q, double *A,
                    double *b, double *c, double *d) {
  if (meth && meth->backend == &ap_step_rk)   /* our own DOP853 (stepper_rk.c) */
    return ap_step_rk_butcher(meth, max_s, s, q, A, b, c, d);
  if (!meth || meth->backend != &ap_step_arkode) return AP_ERR_UNSUPPORTED;
  ARKodeButcherTable B = method_table(meth);
  if (!B) return AP_ERR_NOMEM;
  int ns = B->stages, rc = ns <= max_s ? AP_OK : AP_ERR_ARG;
  for (int i = 0; rc == AP_OK && i < ns; i++) {
    for (int j = 0; j < ns; j++) A[i * ns + j] = B->A[i][j];
    b[i] = B->b[i], c[i] = B->c[i], d[i] = B->d ? B->d[i] : 0.0;
  }
  *s = ns, *q = B->q;
  ARKodeButcherTable_Free(B);
  return rc;
}

/* ---- SUNDIALS callbacks ---------------------------------------------------------------- */

/* The state at the stop time. ERKStep 6.4 returns it through its Hermite interpolant at the
 * new state's own time (tau = 0: the weight of every datum but y_{n+1} is a product by 0),
 * and for degrees 4 and 5 (methods of order 5 and more) that interpolant first evaluates f at
 * t_{n+1} - h/3 (and - 2h/3). Those values do not enter the result, so zeros are handed back
 * in their place: a call during ark_one's step at a time before ERKStep's current time, which
 * has reached the stop time, is that one (the stages are at or after the current time; our
 * own dense output, ark_dky, runs outside ark_one and is always evaluated). The evaluation
 * would cost one call of f per step that ends at an output time, and its result leaves the
 * data describing t_{n+1} - h/3 in place of the step's end. */
static int interpolation_at_stop(ap_stepper *s, realtype t) {
  realtype tcur = t, h = 0.0;
  if (!s->stepping || ERKStepGetCurrentTime(s->mem, &tcur) != ARK_SUCCESS || !(t < tcur))
    return 0;
  ERKStepGetLastStep(s->mem, &h);
  return fabs(tcur - s->tstop) <= 1e3 * DBL_EPSILON * (fabs(tcur) + fabs(h));
}

static int ark_rhs(realtype t, N_Vector y, N_Vector ydot, void *user) {
  if (interpolation_at_stop(user, t)) {
    N_VConst(0.0, ydot);
    return 0;
  }
  return ap_step_rhs_eval(user, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
}

static void ark_err(int code, const char *module, const char *function, char *msg,
                    void *user) {
  (void)code, (void)module;
  ap_step_sun_message(user, function, msg);
}

static int ark_flag_fail(ap_stepper *s, int flag) {
  char *name = ERKStepGetReturnFlagName(flag);
  int status = ap_step_fail(s, flag, name);
  free(name);
  return status;
}

/* ---- creation ------------------------------------------------------------------------ */

/* Error weights with ap_step_opts.weight (stepper.c). */
static int ark_ewt(N_Vector y, N_Vector ewt, void *user) {
  return ap_step_ewt_fill(user, N_VGetArrayPointer(y), N_VGetArrayPointer(ewt));
}

static int ark_configure(ap_stepper *s) {
  const ap_step_opts *o = &s->o;
  int flag = ERKStepSetUserData(s->mem, s);
  ARKodeButcherTable B = method_table(s->meth);
  if (!B) return ARK_MEM_FAIL;
  if (flag == ARK_SUCCESS) flag = ERKStepSetTable(s->mem, B);
  ARKodeButcherTable_Free(B);
  if (flag == ARK_SUCCESS) flag = ERKStepSStolerances(s->mem, o->rtol, o->atol);
  if (flag == ARK_SUCCESS && o->weight)
    flag = ERKStepWFtolerances(s->mem, ark_ewt);
  if (flag == ARK_SUCCESS && o->h_fixed > 0) flag = ERKStepSetFixedStep(s->mem, o->h_fixed);
  if (flag == ARK_SUCCESS) flag = ERKStepSetMaxNumSteps(s->mem, o->max_steps);
  if (flag == ARK_SUCCESS && o->h_init > 0) flag = ERKStepSetInitStep(s->mem, o->h_init);
  if (flag == ARK_SUCCESS && o->h_max > 0) flag = ERKStepSetMaxStep(s->mem, o->h_max);
  return flag;
}

static void ark_destroy(ap_stepper *s) {
  if (s->mem) ERKStepFree(&s->mem);
  ap_step_release(s);
}

/* ERKStep's first-step setup, run at creation. SUNDIALS 6.4.1 allocates the stage array in
 * erkStep_Init at the first ERKStepEvolve and writes into it unchecked (a failed allocation
 * crashes there, with the run half done). With the stop time at t0, ERKStepEvolve's
 * arkInitialSetup runs erkStep_Init (the stage array, the stage vectors from the pool, the
 * arrays of the fused vector operations) and then refuses that stop time (ARK_ILL_INPUT)
 * before it evaluates anything or changes the state; the first real step runs the setup
 * again, finding everything allocated. ark_one sets the stop time before every step. Returns
 * ARK_SUCCESS or the flag of the failure (ARK_MEM_FAIL: out of memory). */
static int ark_first_setup(ap_stepper *s) {
  realtype tret = s->t;
  int flag = ERKStepSetStopTime(s->mem, s->t);
  if (flag == ARK_SUCCESS) flag = ERKStepEvolve(s->mem, s->t + 1.0, s->tmp, &tret, ARK_ONE_STEP);
  if (flag == ARK_ILL_INPUT) flag = ARK_SUCCESS, s->sun_msg[0] = '\0';   /* the expected refusal */
  return flag;
}

static int ark_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                      const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                      size_t msg_len) {
  ap_stepper *s = NULL;
  int rc = ap_step_alloc(meth, n, f, user, t0, y0, o, &s, msg, msg_len);
  if (rc != AP_OK) return rc;
  s->mem = ERKStepCreate(ark_rhs, t0, s->y, s->ctx);
  int flag = s->mem ? ERKStepSetErrHandlerFn(s->mem, ark_err, s) : ARK_MEM_FAIL;
  if (flag == ARK_SUCCESS) flag = ark_configure(s);
  if (flag == ARK_SUCCESS) flag = ark_first_setup(s);
  if (flag != ARK_SUCCESS) {
    char *name = ERKStepGetReturnFlagName(flag);
    /* ERKStepSetTable returns ARK_MEM_NULL when its copy of the table cannot be allocated */
    int nomem = flag == ARK_MEM_FAIL || flag == ARK_MEM_NULL;
    if (msg && msg_len)
      snprintf(msg, msg_len, "%s: %sERKStep setup failed (%s): %s", meth->name,
               nomem ? "out of memory: " : "", name, s->sun_msg);
    free(name);
    ark_destroy(s);
    return nomem ? AP_ERR_NOMEM : AP_ERR_SOLVER;
  }
  *out = s;
  return AP_OK;
}

/* ---- stepping ------------------------------------------------------------------------ */

/* Restart ERKStep at (t, y) with the next step h (0 = ERKStep estimates it). */
static int ark_restart(ap_stepper *s, double t, const double *y, double h) {
  int flag = ARK_SUCCESS;
  if (s->o.h_fixed > 0 && h > 0) flag = ERKStepSetFixedStep(s->mem, h);
  else if (h >= 0) flag = ERKStepSetInitStep(s->mem, h);
  memcpy(NV(s->tmp), y, sizeof(double) * (size_t)s->n);
  if (flag == ARK_SUCCESS) flag = ERKStepReset(s->mem, t, s->tmp);
  return flag;
}

static int ark_reset(ap_stepper *s, double t, const double *y) {
  double h = 0.0;
  if (s->o.h_fixed == 0) ERKStepGetCurrentStep(s->mem, &h);   /* keep the step size */
  int flag = ark_restart(s, t, y, s->o.h_fixed > 0 ? s->o.h_fixed : h);
  if (flag != ARK_SUCCESS) return ark_flag_fail(s, flag);
  ap_step_accept(s, t, y);
  return AP_OK;
}

/* After a jump of f at the accepted state (t, y) (an input changed: docs/control.md): restart
 * with the step the error controller would take next, h_last * 0.9 dsm^(-1/order) within
 * [0.2, 5] h_last (dsm: the weighted RMS norm of the last step's local error estimate, weights
 * 1 / (rtol |y| + atol)). ark_reset's "current step" is the last step taken, which a stop time
 * cut: restarting from it at every controller instant kept a run at two steps per period where
 * one sufficed. */
static int ark_jump(ap_stepper *s, double t, const double *y) {
  double h = 0.0, sum = 0.0;
  ERKStepGetLastStep(s->mem, &h);
  if (s->o.h_fixed > 0 || !(h > 0) || ERKStepGetEstLocalErrors(s->mem, s->tmp) != ARK_SUCCESS)
    return ark_reset(s, t, y);
  const double *ele = NV(s->tmp);
  for (int i = 0; i < s->n; i++) {
    double e = ele[i] / (s->o.rtol * fabs(s->yacc[i]) + s->o.atol);
    sum += e * e;
  }
  double dsm = sqrt(sum / s->n), eta = dsm > 0 ? 0.9 * pow(dsm, -1.0 / s->meth->order) : 5.0;
  int flag = ark_restart(s, t, y, h * fmin(5.0, fmax(0.2, eta)));
  if (flag != ARK_SUCCESS) return ark_flag_fail(s, flag);
  ap_step_accept(s, t, y);
  return AP_OK;
}

int ap_step_ark_jump(ap_stepper *s, double t, const double *y) { return ark_jump(s, t, y); }

/* The step to retry with after a recoverable failure: a quarter of the one that failed. */
static double retry_h(ap_stepper *s, double tstop) {
  double h = 0.0;
  ERKStepGetCurrentStep(s->mem, &h);
  if (!(h > 0)) h = s->o.h_fixed;                /* 0 for adaptive: ERKStep estimates */
  return 0.25 * fmin(h, tstop - s->t);
}

static int ark_one(ap_stepper *s, double tstop, double *t, double *y) {
  (void)t, (void)y;                              /* the dispatcher copies (s->t, yacc) out */
  realtype tret = s->t;
  int flag, tries = 0;
  for (;;) {
    flag = ERKStepSetStopTime(s->mem, tstop);
    s->stepping = 1;   /* s->tstop is tstop (ap_step_one) */
    if (flag == ARK_SUCCESS) flag = ERKStepEvolve(s->mem, tstop, s->y, &tret, ARK_ONE_STEP);
    s->stepping = 0;
    if (flag >= 0 || s->rhs_neg || !s->rhs_pos || tries++ == AP_ARK_RETRIES) break;
    if (ark_restart(s, s->t, s->yacc, retry_h(s, tstop)) != ARK_SUCCESS) break;
  }
  if (tries > 0 && s->o.h_fixed > 0) ERKStepSetFixedStep(s->mem, s->o.h_fixed);
  int finite = 1;
  for (int i = 0; flag >= 0 && i < s->n; i++) finite = finite && isfinite(NV(s->y)[i]);
  if (flag >= 0 && finite) {
    ap_step_accept(s, tret, NV(s->y));
    return AP_OK;
  }
  if (!finite) s->rhs_nan = 1;
  int status = flag < 0 ? ark_flag_fail(s, flag) : ap_step_fail(s, flag, "solution not finite");
  ark_restart(s, s->t, s->yacc, -1.0);           /* back to the last accepted state */
  return status;
}

static int ark_dky(ap_stepper *s, double t, double *y) {
  int flag = ERKStepGetDky(s->mem, t, 0, s->tmp);
  if (flag != ARK_SUCCESS) {
    char *name = ERKStepGetReturnFlagName(flag);
    snprintf(s->msg, sizeof s->msg, "%s: no dense output at t = %.17g (%s): %s",
             s->meth->name, t, name, s->sun_msg);
    free(name);
    return flag == ARK_BAD_T ? AP_ERR_ARG : AP_ERR_SOLVER;
  }
  memcpy(y, NV(s->tmp), sizeof(double) * (size_t)s->n);
  return AP_OK;
}

static void ark_stats(const ap_stepper *s, ap_step_stats *st) {
  long v = 0;
  realtype h = 0.0;
  ERKStepGetNumSteps(s->mem, &v), st->steps = s->base.steps + v;
  ERKStepGetNumErrTestFails(s->mem, &v), st->err_fails = s->base.err_fails + v;
  ERKStepGetLastStep(s->mem, &h), st->h_last = h;
}

const ap_step_backend ap_step_arkode = {"ARKODE ERKStep", ark_create, ark_reset, ark_one,
                                        ark_dky, ark_stats, ark_destroy};
