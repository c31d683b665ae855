/* Appell steppers (internal): SUNDIALS integrators behind one const table of function
 * pointers (STYLE.md, "From GSL odeiv2 and SUNDIALS"). A stepper advances a plain ODE
 * y' = f(t, y) of size n; it knows nothing about mechanics. The drivers in sim.c own the
 * mechanics (partition switching, projection) and call ap_step_reset after changing y.
 *
 * Each stepper owns its SUNContext. No SUNDIALS type appears in this header.
 * The right-hand side returns 0 = ok, > 0 = recoverable (retry smaller), < 0 = stop. */
#ifndef AP_STEPPER_H
#define AP_STEPPER_H

#include <stddef.h>

typedef int (*ap_rhs_fn)(double t, const double *y, double *ydot, void *user);

typedef struct ap_step_opts {
  double rtol;        /* relative tolerance (adaptive methods) */
  double atol;        /* absolute tolerance, scalar (adaptive methods) */
  double h_fixed;     /* step size for fixed-step methods (> 0) */
  double h_init;      /* first step, 0 = stepper's choice */
  double h_max;       /* largest step, 0 = unlimited */
  long max_steps;     /* most internal steps per ap_step_one call sequence; 0 = default */
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
  const char *name;           /* "dopri5", "bs3", "verner6", "fehlberg8", "rk4", "adams", "bdf" */
  const char *summary;        /* one line for users */
  int order;                  /* order of the propagated solution, verified by a test */
  int adaptive;               /* 1 error-controlled, 0 fixed step (opts.h_fixed) */
  int table;                  /* backend-specific selector (ARKODE table id, CVODE lmm, ...) */
  const ap_step_backend *backend;
};

/* The methods on offer, in a fixed order. */
int ap_step_method_count(void);
const ap_step_method *ap_step_method_get(int i);
const ap_step_method *ap_step_method_find(const char *name);   /* NULL if unknown */

/* Create a stepper of method meth for y' = f(t, y), y(t0) = y0. */
int ap_step_create(const ap_step_method *meth, int n, ap_rhs_fn f, void *user, double t0,
                   const double *y0, const ap_step_opts *o, ap_stepper **out, char *msg,
                   size_t msg_len);

/* Restart at (t, y): discard history (FSAL stage, multistep history); keep options and,
 * where the method allows, the current step size. */
int ap_step_reset(ap_stepper *s, double t, const double *y);

/* Take one internal step, never past tstop (the step is shortened to land on tstop exactly).
 * On return *t is the time reached and y (n) the solution there. Returns AP_OK, or a negative
 * AP_ERR_* (AP_ERR_CALLBACK when f returned < 0, AP_ERR_SOLVER otherwise) with the message
 * available from ap_step_message. */
int ap_step_one(ap_stepper *s, double tstop, double *t, double *y);

/* Dense output: y at time t inside the last step. */
int ap_step_dky(ap_stepper *s, double t, double *y);

void ap_step_get_stats(const ap_stepper *s, ap_step_stats *st);
const char *ap_step_message(const ap_stepper *s);
void ap_step_free(ap_stepper *s);

#endif
