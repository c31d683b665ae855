/* Appell steppers (internal): SUNDIALS integrators behind one const table of function
 * pointers (STYLE.md, "From GSL odeiv2 and SUNDIALS"). A stepper advances a plain ODE
 * y' = f(t, y) of size n; it knows nothing about mechanics. The drivers in sim.c own the
 * mechanics (partition switching, projection) and call ap_step_reset after changing y.
 *
 * Each stepper owns a SUNContext while it lives (taken from and given back to sunctx.c).
 * No SUNDIALS type appears in this header.
 * The right-hand side returns 0 = ok, > 0 = recoverable (retry smaller), < 0 = stop. */
#ifndef AP_STEPPER_H
#define AP_STEPPER_H

#include <stddef.h>

typedef int (*ap_rhs_fn)(double t, const double *y, double *ydot, void *user);

/* Options; every field 0 means its default, and o == NULL means all defaults.
 * h_fixed: required (> 0) by fixed-step methods (rk4). With an adaptive ERK method
 * (heun2 ... fehlberg8), h_fixed > 0 switches error control off and takes steps of exactly
 * h_fixed (the last step before a tstop is shortened to land on it); tolerances are then
 * unused. CVODE methods (adams, bdf) have no fixed-step mode: h_fixed > 0 gives
 * AP_ERR_UNSUPPORTED. */
/* Projection onto a constraint manifold, for steppers that support it natively (CVODE:
 * CVodeSetProjFn). corr (n) receives proj(y) - y; when err is not NULL it is replaced by its
 * projection onto the manifold's tangent space. Return codes as for ap_rhs_fn. */
typedef int (*ap_proj_fn)(double t, const double *y, double *corr, double *err, void *user);

typedef struct ap_step_opts {
  double rtol;        /* relative tolerance (adaptive methods); 0 = 1e-6 */
  double atol;        /* absolute tolerance, scalar (adaptive methods); 0 = 1e-9 */
  double h_fixed;     /* step size for fixed-step methods (> 0), see above */
  double h_init;      /* first step, 0 = stepper's choice */
  double h_max;       /* largest step, 0 = unlimited */
  long max_steps;     /* most internal steps while heading for one tstop (consecutive
                         ap_step_one calls with the same tstop); 0 = 100000 */
  ap_proj_fn proj;    /* CVODE: project after every step inside the method (NULL = none);
                         ignored by the other backends */
  const double *weight; /* (n) or NULL (all 1): component i's scaled error is multiplied by
                         weight[i] >= 0 in the error test; 0 leaves it out of the step-size
                         control (global_error.c: coordinates nothing depends on). The norm
                         is taken over the components with a nonzero weight. Read at every
                         step: the owner may change the values (not the pointer) later */
} ap_step_opts;

typedef struct ap_step_stats {
  long steps;         /* accepted internal steps */
  long rhs_evals;     /* right-hand-side evaluations */
  long err_fails;     /* error-test failures */
  long rhs_fails;     /* recoverable rhs failures (step retried smaller) */
  double h_last;      /* last step size used */
} ap_step_stats;

typedef struct ap_stepper ap_stepper;
typedef struct ap_step_method ap_step_method;

/* One backend family (ARKODE ERKStep, CVODE, ...). */
typedef struct ap_step_backend {
  const char *family;
  int (*create)(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                size_t msg_len);
  int (*reset)(ap_stepper *s, double t, const double *y);
  int (*one)(ap_stepper *s, double tstop, double *t, double *y);
  int (*dky)(ap_stepper *s, double t, double *y);
  void (*stats)(const ap_stepper *s, ap_step_stats *st);
  void (*destroy)(ap_stepper *s);
} ap_step_backend;

/* One method on offer: a backend plus its configuration. */
struct ap_step_method {
  const char *name;           /* "heun2", "bs3", "dopri5", "verner6", "fehlberg8", "rk4", ... */
  const char *summary;        /* one line for users */
  int order;                  /* order of the propagated solution, verified by a test
                                 (CVODE: the highest order of the variable-order family) */
  int adaptive;               /* 1 error-controlled, 0 fixed step (opts.h_fixed) */
  int table;                  /* backend-specific selector (ARKODE table id, CVODE lmm, ...) */
  const ap_step_backend *backend;
};

/* 1 when the method projects natively through ap_step_opts.proj (CVODE BDF only: CVODE
 * refuses projection with Adams). */
int ap_step_native_projection(const ap_step_method *meth);

/* The methods on offer, in a fixed order. */
int ap_step_method_count(void);
const ap_step_method *ap_step_method_get(int i);
const ap_step_method *ap_step_method_find(const char *name);   /* NULL if unknown */
/* The smallest rtol a method delivers on the reference problems (accuracy.c); 0: no floor. */
double ap_step_rtol_floor(const char *name);

/* Create a stepper of method meth for y' = f(t, y), y(t0) = y0. */
int ap_step_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                   const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                   size_t msg_len);

/* Restart at (t, y): discard history (FSAL stage, multistep history); keep options and,
 * where the method allows, the current step size. */
int ap_step_reset(ap_stepper *s, double t, const double *y);

/* Continue at (t, y), the same trajectory in other coordinates (a change of partition): like
 * ap_step_reset, but the step size and error-controller history carry over, and ydot
 * (n, or NULL) = f(t, y) when the caller knows it, so that a first-same-as-last method need
 * not evaluate f again. Only our own backend (stepper_rk.c) has it; the others reset. */
int ap_step_restart(ap_stepper *s, double t, const double *y, const double *ydot);

/* Continue at the accepted state (t, y) after the right-hand side jumped there (an input
 * changed): the same state, a new f. Single-step methods keep their step size (ours: the
 * FSAL derivative is evaluated again; ERKStep: restarted with the step its error controller
 * proposes, ap_step_ark_jump); multistep methods reset (their history lies across the jump). */
int ap_step_jump(ap_stepper *s, double t, const double *y);
int ap_step_ark_jump(ap_stepper *s, double t, const double *y);

/* Take one internal step, never past tstop (the step is shortened to land on tstop exactly).
 * tstop must lie after the current time (forward integration only).
 * On return *t is the time reached and y (n) the solution there. Returns AP_OK, or a negative
 * AP_ERR_* (AP_ERR_CALLBACK when f returned < 0, AP_ERR_NAN when f kept producing NaN/Inf
 * (treated as recoverable until retries run out), AP_ERR_SOLVER otherwise) with the message
 * available from ap_step_message. On failure *t and y hold the last accepted state and the
 * stepper can continue from it. */
int ap_step_one(ap_stepper *s, double tstop, double *t, double *y);

/* Watch m two-component vectors w (2 m numbers) whose inverse length scales part of f's
 * Jacobian (a sliding contact's slip velocity s: its friction acts along s / |s|). Called
 * after every accepted step with their values there. CVODE BDF makes its Jacobian again
 * before the next step when one moved by more than half the shorter of its length now and
 * where the Jacobian was made (stepper_jwatch.c); the other methods ignore it. AP_OK,
 * AP_ERR_ARG, AP_ERR_NOMEM. */
int ap_step_jacobian_watch(ap_stepper *s, int m, const double *w);
/* CVODE BDF: difference the Jacobian with the relative increment rho (> 0) instead of
 * CVODE's sqrt(eps), from the next step on; 0 gives CVODE's own difference quotients back
 * (stepper_cvjac.c). The other methods ignore it. AP_OK, AP_ERR_ARG, AP_ERR_NOMEM. */
int ap_step_jacobian_increment(ap_stepper *s, double rho);
/* Dense output: y at time t inside the last step. */
int ap_step_dky(ap_stepper *s, double t, double *y);

void ap_step_get_stats(const ap_stepper *s, ap_step_stats *st);
const char *ap_step_message(const ap_stepper *s);
void ap_step_free(ap_stepper *s);

/* The Butcher table an ERK method really hands to ARKODE (after the FSAL repair described
 * in stepper_arkode.c): s stages (s <= max_s), A (s x s, row-major), b, c (s) and the
 * embedding d (s; zeros when the method has none). q = order of b. AP_ERR_UNSUPPORTED for
 * non-RK methods. For tests and docs/steppers.md. */
int ap_step_butcher(const ap_step_method *meth, int max_s, int *s, int *q, double *A,
                    double *b, double *c, double *d);

/* ---- for the backends only (stepper.c, stepper_arkode.c, stepper_cvode.c) ---------------
 * sim.c treats ap_stepper as opaque. SUNDIALS objects are held as void * so that no
 * SUNDIALS type appears here. */
extern const ap_step_backend ap_step_arkode;
extern const ap_step_backend ap_step_cvode;
extern const ap_step_backend ap_step_rk;

/* stepper_rk.c (DOP853): ap_step_butcher's answer (the 12 stages and the FSAL stage, b of
 * order 8, d the order-5 embedding), and for tests the whole 16-stage table (A row-major, c),
 * the order-3 embedding b3 and the weights w of the dense output at theta in [0, 1]
 * (u(theta) = y + h sum_j w_j k_j). */
int ap_step_rk_butcher(const ap_step_method *meth, int max_s, int *s, int *q, double *A,
                       double *b, double *c, double *d);
int ap_step_rk_restart(ap_stepper *s, double t, const double *y, const double *ydot);
int ap_step_rk_tables(int max_s, int *s, double *A, double *c, double *b3, double theta,
                      double *w);

struct ap_stepper {
  const ap_step_method *meth;
  int n;
  ap_rhs_fn f;
  void *user;
  ap_step_opts o;        /* options with defaults filled in */
  void *ctx;             /* SUNContext, one per stepper (sunctx.c) */
  void *mem;             /* ERKStep or CVODE memory */
  void *y;               /* N_Vector (n): the state SUNDIALS advances */
  void *tmp;             /* N_Vector (n): dense output */
  void *pool;            /* ap_nvpool (nvpool.c): y, tmp and every vector SUNDIALS clones */
  void *obj[3];          /* backend objects (CVODE: SUNMatrix, SUNLinearSolver, SUNNonlinSol) */
  double t;              /* time of the last accepted state */
  double *yacc;          /* (n) the last accepted state: returned and restored on failure */
  double tstop;          /* the tstop of the current ap_step_one sequence */
  long nto;              /* steps taken towards tstop */
  long nfe;              /* calls of f */
  long nrecov;           /* calls of f that returned > 0 or a non-finite ydot */
  int rhs_neg, rhs_pos, rhs_nan; /* since the current ap_step_one began: f < 0, f > 0, NaN */
  int rhs_code;          /* f's last nonzero return code */
  ap_step_stats base;    /* SUNDIALS counters accumulated before the last re-init */
  char sun_msg[256];     /* last message of SUNDIALS' error handler (never printed) */
  char msg[512];         /* last failure, for ap_step_message */
  struct ap_step_jwatch *jw; /* ap_step_jacobian_watch's record (stepper_jwatch.c), or NULL */
  int stepping;          /* ARKODE: inside ark_one's ERKStepEvolve (stepper_arkode.c) */
};

/* The weight of component i (1 without weights) and the factor sqrt(n / number of nonzero
 * weights) that keeps a weighted RMS norm over n entries a mean over the weighted ones. */
double ap_step_weight(const ap_stepper *s, int i);
double ap_step_weight_norm(const ap_stepper *s);
/* SUNDIALS' error weights (for ARKODE's and CVODE's ewt functions): ewt_i =
 * weight_i sqrt(n / nw) / (rtol |y_i| + atol). Returns 0. */
int ap_step_ewt_fill(const ap_stepper *s, const double *y, double *ewt);

/* Allocate a stepper with its SUNContext and vectors y = y0, tmp; options defaulted. */
/* Vectors of a stepper's pool (nvpool.c): enough for every clone ARKODE and CVODE make. */
#define AP_STEP_POOL 48
int ap_step_alloc(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                  const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                  size_t msg_len);
/* Free what ap_step_alloc made (the backend frees mem and obj first). */
void ap_step_release(ap_stepper *s);
/* Call f with counting, NaN/Inf detection (turned into a recoverable failure, 1). */
int ap_step_rhs_eval(ap_stepper *s, double t, const double *y, double *ydot);
/* Store a SUNDIALS error-handler message instead of printing it. */
void ap_step_sun_message(ap_stepper *s, const char *function, const char *msg);
/* Record a failed step: status from the rhs flags (or AP_ERR_SOLVER), message naming the
 * method, time, SUNDIALS flag name and SUNDIALS' own words. Returns the status. */
int ap_step_fail(ap_stepper *s, int sun_flag, const char *flag_name);
/* Accept the state the backend reached: s->t = t, yacc = y (SUNDIALS' vector contents). */
void ap_step_accept(ap_stepper *s, double t, const double *y);
/* stepper_jwatch.c, for the CVODE backend: 1 when the Jacobian must be made before the next
 * step; after an accepted step, made = 1 when that step made it; at a re-init (the next
 * step makes it where the watched values are unknown); free the record. */
int ap_step_jw_force(const ap_stepper *s);
void ap_step_jw_stepped(ap_stepper *s, int made);
void ap_step_jw_reset(ap_stepper *s);
double ap_step_jw_rho(const ap_stepper *s);
/* stepper_cvjac.c: CVODE's Jacobian function with ap_step_jw_rho's increments. */
struct _generic_N_Vector;
struct _generic_SUNMatrix;
int ap_step_cv_jac(double t, struct _generic_N_Vector *y, struct _generic_N_Vector *fy,
                   struct _generic_SUNMatrix *J, void *user, struct _generic_N_Vector *tmp1,
                   struct _generic_N_Vector *tmp2, struct _generic_N_Vector *tmp3);
void ap_step_jw_free(ap_stepper *s);

#endif
