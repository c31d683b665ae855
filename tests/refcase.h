/* The harness of the reference problems (test_reference.c; refcase.c): a case is a system of
 * refsys.h, an initial state at t = 0, its exact solution and invariants; check_case integrates
 * it in both modes with every adaptive method and asserts the targets; check_closed_form checks
 * a closed form against its system without integrating. */
#ifndef AP_TESTS_REFCASE_H
#define AP_TESTS_REFCASE_H

#include "refsys.h"

#define RTOL 1e-11
#define ATOL 1e-13
#define POS_TOL (1e3 * RTOL)
#define T_END 20.0
#define NOUT_MAX 64
#define NQ_MAX 8
#define N_MODES 2
#define N_METHODS 4

extern const ap_mode modes[N_MODES];            /* minimal, projected */
extern const char *const mode_names[N_MODES];
extern const char *const methods[N_METHODS];    /* dopri5, verner6, fehlberg8, dop853 */

/* Monotonic seconds. */
double now(void);

typedef void (*exact_fn)(const void *ctx, double t, double *q, double *v);
/* Invariants I_j and the magnitude of the terms each is a sum of (its round-off and
 * truncation scale: the Jacobi integral of a fast-growing motion is a small difference of large
 * terms). Returns how many invariants it wrote (<= 4). */
typedef int (*invariant_fn)(const void *ctx, double t, const double *q, const double *v,
                            double *out, double *scale);
/* Exact multipliers and their natural magnitude (one scale for all rows). */
typedef void (*lambda_fn)(const void *ctx, double t, double *lambda, double *scale);

typedef struct rcase {
  const char *problem;   /* for the summary table */
  const char *label;
  ap_system_def def;
  double q0[NQ_MAX], v0[NQ_MAX];
  double t_end;
  exact_fn exact;        /* NULL: no closed form */
  invariant_fn inv;      /* NULL: none */
  lambda_fn lambda;      /* NULL: do not check reactions */
  const void *ctx;
} rcase;

typedef struct rrun {
  int ok;                /* created and advanced to t_end */
  int nout;
  double t[NOUT_MAX], q[NOUT_MAX][NQ_MAX];
  double pos_err;        /* max |q_i - q_exact_i| / max(1, |q_exact_i|) */
  double resid;          /* max |A v + a0| / max(1, scale), from the callbacks */
  double resid_scale;    /* largest scale seen */
  double inv_err;        /* max |I - I0| / max(1, |I0|, scale of the terms of I) */
  double lam_err;        /* max |lambda - lambda_exact| / max(1, scale of lambda) */
  double seconds;
  ap_sim_stats st;
} rrun;

/* Integrate a case with outputs every 0.5 s and measure it against its closed form. */
void run_case(const rcase *c, int mode_i, const char *method, double rtol, double atol,
              rrun *r);

/* Run a case in both modes with every method and assert the common targets. The runs are
 * kept in out[mode][method] when out is not NULL. */
void check_case(const rcase *c, rrun out[N_MODES][N_METHODS]);

/* Raise the worst position error of `problem` (a name of the report) in a mode to err. */
void note_pos(const char *problem, int mode_i, double err);

/* Print the worst numbers per problem and mode. */
void report_worst(void);

/* h from dg/dq: h_a = (d_c g_ab - 1/2 d_a g_bc) v^b v^c (independent of the core's). */
void christoffel_h(const ap_system_def *def, double t, const double *q, const double *v,
                   double *h);

/* Check a closed form against its system: q' = v, A v + a0 = 0, A v' = gamma, and
 * g v' + h - Q = A^T lambda for some lambda (returned for b == 1). Tolerances: tol relative. */
void check_closed_form(const char *label, const ap_system_def *def, exact_fn ex,
                       const void *ctx, double t, double tol, double *lambda_out);

#endif
