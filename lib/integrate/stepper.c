/* Steppers: the const table of methods, argument checks, dispatch to a backend, and the
 * helpers both backends share (allocation, the counted right-hand side, failure messages).
 *
 * Layout: struct ap_stepper (stepper.h) holds the SUNDIALS objects as void *, the last
 * accepted state (t, yacc) and the counters; each backend (stepper_arkode.c,
 * stepper_cvode.c) owns the SUNDIALS calls. A backend's one() calls ap_step_accept on
 * success; the dispatcher here then copies (t, yacc) out, on success and on failure alike.
 *
 * Invariant: (s->t, s->yacc) is always the last accepted state, and SUNDIALS can continue
 * from it: a failed step leaves the state untouched. Each method's order is measured by
 * tests/test_steppers.c (docs/steppers.md); none is offered on its name alone. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <arkode/arkode_butcher_erk.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "appell/status.h"
#include "integrate/nvpool.h"
#include "integrate/stepper.h"
#include "integrate/sunctx.h"

#define AP_STEP_RTOL 1e-6
#define AP_STEP_ATOL 1e-9
#define AP_STEP_MAX_STEPS 100000L

/* table = ARKODE ERK table id (ARKODE_ERK_NONE: classic RK4 built in stepper_arkode.c), the
 * CVODE linear multistep family, or 0 for our own DOP853 (stepper_rk.c). */
static const ap_step_method methods[] = {
    {"heun2", "Heun-Euler 2(1) explicit RK pair, 2 stages (ARKODE)", 2, 1,
     ARKODE_HEUN_EULER_2_1_2, &ap_step_arkode},
    {"bs3", "Bogacki-Shampine 3(2) explicit RK pair, FSAL (ARKODE)", 3, 1,
     ARKODE_BOGACKI_SHAMPINE_4_2_3, &ap_step_arkode},
    {"dopri5", "Dormand-Prince 5(4) explicit RK pair, FSAL (ARKODE)", 5, 1,
     ARKODE_DORMAND_PRINCE_7_4_5, &ap_step_arkode},
    {"verner6", "Verner 6(5) explicit RK pair, 8 stages (ARKODE)", 6, 1,
     ARKODE_VERNER_8_5_6, &ap_step_arkode},
    {"fehlberg8", "Fehlberg 8(7) explicit RK pair, 13 stages (ARKODE)", 8, 1,
     ARKODE_FEHLBERG_13_7_8, &ap_step_arkode},
    {"dop853", "Dormand-Prince 8(5,3) explicit RK pair, FSAL, dense output of order 7 (Appell)",
     8, 1, 0, &ap_step_rk},
    {"rk4", "classic Runge-Kutta 4, fixed step opts.h_fixed (ARKODE)", 4, 0,
     ARKODE_ERK_NONE, &ap_step_arkode},
    {"adams", "variable-order Adams-Moulton 1-12, fixed-point iteration (CVODE)", 12, 1,
     CV_ADAMS, &ap_step_cvode},
    {"bdf", "variable-order BDF 1-5, dense Newton (CVODE), for stiff problems", 5, 1, CV_BDF,
     &ap_step_cvode},
};

int ap_step_method_count(void) { return (int)(sizeof methods / sizeof methods[0]); }

const ap_step_method *ap_step_method_get(int i) {
  return i >= 0 && i < ap_step_method_count() ? &methods[i] : NULL;
}

const ap_step_method *ap_step_method_find(const char *name) {
  for (int i = 0; name && i < ap_step_method_count(); i++)
    if (strcmp(methods[i].name, name) == 0) return &methods[i];
  return NULL;
}

/* ---- creation and dispatch ------------------------------------------------------------- */

static int all_finite(int n, const double *x) {
  for (int i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

static int say(char *msg, size_t len, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static int say(char *msg, size_t len, int status, const char *fmt, ...) {
  if (msg && len) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, len, fmt, ap);
    va_end(ap);
  }
  return status;
}

static int check_opts(const ap_step_method *meth, const ap_step_opts *o, char *msg,
                      size_t len) {
  if (!o) return AP_OK;
  if (o->rtol < 0 || o->atol < 0 || o->h_fixed < 0 || o->h_init < 0 || o->h_max < 0 ||
      o->max_steps < 0 || !isfinite(o->rtol + o->atol + o->h_fixed + o->h_init + o->h_max))
    return say(msg, len, AP_ERR_ARG, "%s: options must be finite and >= 0 (rtol %g, atol %g, "
               "h_fixed %g, h_init %g, h_max %g, max_steps %ld)", meth->name, o->rtol,
               o->atol, o->h_fixed, o->h_init, o->h_max, o->max_steps);
  if (o->h_fixed > 0 && meth->backend == &ap_step_cvode)
    return say(msg, len, AP_ERR_UNSUPPORTED, "%s: CVODE has no fixed-step mode (h_fixed = %g "
               "given); use an ARKODE method or h_fixed = 0", meth->name, o->h_fixed);
  return AP_OK;
}

int ap_step_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                   const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                   size_t msg_len) {
  if (out) *out = NULL;
  if (!meth || !f || !y0 || !out || n <= 0)
    return say(msg, msg_len, AP_ERR_ARG, "ap_step_create: NULL argument or n = %d", n);
  int rc = check_opts(meth, o, msg, msg_len);
  if (rc != AP_OK) return rc;
  if (!meth->adaptive && !(o && o->h_fixed > 0))
    return say(msg, msg_len, AP_ERR_ARG, "%s is a fixed-step method: opts.h_fixed must be > 0",
               meth->name);
  if (!isfinite(t0) || !all_finite(n, y0))
    return say(msg, msg_len, AP_ERR_ARG, "%s: the initial state is not finite", meth->name);
  rc = meth->backend->create(meth, n, f, user, t0, y0, o, out, msg, msg_len);
  if (rc == AP_OK && ap_nvp_nomem((*out)->pool)) {
    ap_step_free(*out);
    *out = NULL;
    return say(msg, msg_len, AP_ERR_NOMEM, "%s: out of memory (SUNDIALS work vectors)",
               meth->name);
  }
  return rc;
}

/* A SUNDIALS call that was handed the pool's spare vector: its results are void. */
static int pool_failed(ap_stepper *s, int rc) {
  if (rc == AP_OK && ap_nvp_nomem(s->pool))
    rc = say(s->msg, sizeof s->msg, AP_ERR_NOMEM, "%s: out of memory (SUNDIALS work vectors)",
             s->meth->name);
  return rc;
}

int ap_step_reset(ap_stepper *s, double t, const double *y) {
  if (!isfinite(t) || !all_finite(s->n, y))
    return say(s->msg, sizeof s->msg, AP_ERR_ARG, "%s: reset to a non-finite state at t = %g",
               s->meth->name, t);
  return pool_failed(s, s->meth->backend->reset(s, t, y));
}

int ap_step_restart(ap_stepper *s, double t, const double *y, const double *ydot) {
  if (s->meth->backend != &ap_step_rk) return ap_step_reset(s, t, y);
  if (!isfinite(t) || !all_finite(s->n, y) || (ydot && !all_finite(s->n, ydot)))
    return say(s->msg, sizeof s->msg, AP_ERR_ARG, "%s: restart at a non-finite state at "
               "t = %g", s->meth->name, t);
  return ap_step_rk_restart(s, t, y, ydot);
}

int ap_step_jump(ap_stepper *s, double t, const double *y) {
  if (!isfinite(t) || !all_finite(s->n, y))
    return say(s->msg, sizeof s->msg, AP_ERR_ARG, "%s: restart at a non-finite state at "
               "t = %g", s->meth->name, t);
  if (s->meth->backend == &ap_step_rk) return ap_step_rk_restart(s, t, y, NULL);
  if (s->meth->backend == &ap_step_arkode) return ap_step_ark_jump(s, t, y);
  return ap_step_reset(s, t, y);   /* multistep: the history across the jump is void */
}

static void copy_out(const ap_stepper *s, double *t, double *y) {
  *t = s->t;
  memcpy(y, s->yacc, sizeof(double) * (size_t)s->n);
}

int ap_step_one(ap_stepper *s, double tstop, double *t, double *y) {
  int rc = AP_OK;
  if (!(tstop > s->t))
    rc = say(s->msg, sizeof s->msg, AP_ERR_ARG, "%s: tstop = %.17g is not after t = %.17g",
             s->meth->name, tstop, s->t);
  if (rc == AP_OK && tstop != s->tstop) s->tstop = tstop, s->nto = 0;
  if (rc == AP_OK && s->nto >= s->o.max_steps)
    rc = say(s->msg, sizeof s->msg, AP_ERR_SOLVER, "%s: too much work: %ld steps from "
             "t = %.17g have not reached tstop = %.17g (max_steps)", s->meth->name, s->nto,
             s->t, tstop);
  if (rc == AP_OK) {
    s->rhs_neg = s->rhs_pos = s->rhs_nan = 0;
    rc = pool_failed(s, s->meth->backend->one(s, tstop, t, y));
    if (rc == AP_OK) s->nto++;
  }
  copy_out(s, t, y);
  return rc;
}

int ap_step_dky(ap_stepper *s, double t, double *y) { return s->meth->backend->dky(s, t, y); }

void ap_step_get_stats(const ap_stepper *s, ap_step_stats *st) {
  memset(st, 0, sizeof *st);
  s->meth->backend->stats(s, st);
  st->rhs_evals = s->nfe;
  st->rhs_fails = s->nrecov;
}

const char *ap_step_message(const ap_stepper *s) { return s ? s->msg : "no stepper"; }

void ap_step_free(ap_stepper *s) {
  if (s) s->meth->backend->destroy(s);
}

/* ---- helpers for the backends -------------------------------------------------------- */

int ap_step_alloc(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                  const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                  size_t msg_len) {
  ap_stepper *s = calloc(1, sizeof *s);
  if (!s) return say(msg, msg_len, AP_ERR_NOMEM, "%s: out of memory", meth->name);
  s->meth = meth, s->n = n, s->f = f, s->user = user, s->t = t0, s->tstop = t0;
  if (o) s->o = *o;
  if (s->o.rtol == 0) s->o.rtol = AP_STEP_RTOL;
  if (s->o.atol == 0) s->o.atol = AP_STEP_ATOL;
  if (s->o.max_steps == 0) s->o.max_steps = AP_STEP_MAX_STEPS;
  SUNContext ctx = NULL;
  ap_nvpool *pool = NULL;
  s->yacc = malloc(sizeof(double) * (size_t)n);
  if (s->yacc && ap_ctx_take(&ctx) == AP_OK) {
    s->ctx = ctx;
    if (ap_nvp_create(n, AP_STEP_POOL, ctx, &pool) == AP_OK) {
      s->pool = pool;
      s->y = ap_nvp_take(pool);
      s->tmp = ap_nvp_take(pool);
    }
  }
  if (!s->y || !s->tmp) {
    ap_step_release(s);
    return say(msg, msg_len, AP_ERR_NOMEM, "%s: out of memory (SUNDIALS context, vectors)",
               meth->name);
  }
  memcpy(s->yacc, y0, sizeof(double) * (size_t)n);
  memcpy(N_VGetArrayPointer((N_Vector)s->y), y0, sizeof(double) * (size_t)n);
  *out = s;
  return AP_OK;
}

void ap_step_release(ap_stepper *s) {
  if (!s) return;
  if (s->y) N_VDestroy((N_Vector)s->y);
  if (s->tmp) N_VDestroy((N_Vector)s->tmp);
  ap_nvp_free(s->pool);
  ap_ctx_give(s->ctx);   /* kept for the next stepper (sunctx.c) */
  ap_step_jw_free(s);
  free(s->yacc);
  free(s);
}

int ap_step_rhs_eval(ap_stepper *s, double t, const double *y, double *ydot) {
  if (s->rhs_neg) return s->rhs_code;   /* f said stop: no more calls until the next step */
  s->nfe++;
  int rc = s->f(t, y, ydot, s->user);
  if (rc == 0 && !all_finite(s->n, ydot)) s->rhs_nan = 1, rc = 1;
  if (rc < 0) s->rhs_neg = 1;
  if (rc > 0) s->rhs_pos = 1, s->nrecov++;
  if (rc != 0) s->rhs_code = rc;
  return rc;
}

void ap_step_sun_message(ap_stepper *s, const char *function, const char *msg) {
  snprintf(s->sun_msg, sizeof s->sun_msg, "%s: %s", function ? function : "?",
           msg ? msg : "");
}

int ap_step_fail(ap_stepper *s, int sun_flag, const char *flag_name) {
  int status = s->rhs_neg ? AP_ERR_CALLBACK : s->rhs_nan ? AP_ERR_NAN : AP_ERR_SOLVER;
  int nomem = flag_name && strstr(flag_name, "MEM_FAIL");   /* ARK_, CV_MEM_FAIL */
  char why[96];
  if (nomem) status = AP_ERR_NOMEM, snprintf(why, sizeof why, "out of memory");
  else if (s->rhs_neg)
    snprintf(why, sizeof why, "the right-hand side returned %d (stop)", s->rhs_code);
  else if (s->rhs_nan)
    snprintf(why, sizeof why, "NaN or Inf in the right-hand side or the solution");
  else if (s->rhs_pos)
    snprintf(why, sizeof why, "the right-hand side kept failing recoverably (returned %d)",
             s->rhs_code);
  else
    snprintf(why, sizeof why, "the integrator gave up");
  say(s->msg, sizeof s->msg, status, "%s: step from t = %.17g failed: %s [%s (%d)%s%s]",
      s->meth->name, s->t, why, flag_name ? flag_name : "?", sun_flag,
      s->sun_msg[0] ? "; SUNDIALS says " : "", s->sun_msg);
  s->sun_msg[0] = '\0';
  return status;
}

void ap_step_accept(ap_stepper *s, double t, const double *y) {
  s->t = t;
  memcpy(s->yacc, y, sizeof(double) * (size_t)s->n);
}

int ap_step_native_projection(const ap_step_method *meth) {
  return meth && meth->backend == &ap_step_cvode && meth->table == CV_BDF;
}

/* ---- error weights (ap_step_opts.weight) ------------------------------------------------ */

double ap_step_weight(const ap_stepper *s, int i) { return s->o.weight ? s->o.weight[i] : 1.0; }

double ap_step_weight_norm(const ap_stepper *s) {
  if (!s->o.weight) return 1.0;
  int nw = 0;
  for (int i = 0; i < s->n; i++) nw += s->o.weight[i] != 0.0;
  return nw > 0 ? sqrt((double)s->n / nw) : 1.0;
}

int ap_step_ewt_fill(const ap_stepper *s, const double *y, double *ewt) {
  double wn = ap_step_weight_norm(s);
  for (int i = 0; i < s->n; i++)
    ewt[i] = wn * ap_step_weight(s, i) / (s->o.rtol * fabs(y[i]) + s->o.atol);
  return 0;
}
