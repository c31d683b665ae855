/* Appell: simulation drivers.
 *
 * A simulation integrates one model from an initial state, in one of the modes of docs/design.md:
 *
 *   AP_MODE_MINIMAL    state (q, e'), partitioned basis frozen during a step, re-partitioned
 *                      between steps when R11 degrades; the constraints hold to round-off.
 *   AP_MODE_PLAIN      as projected, without the projection (drifts; for comparison).
 *   AP_MODE_DAE        IDA on (q, v, lambda, mu), index 2; loop closures and unit quaternions
 *                      of body models in stabilized (GGL) form (see docs/architecture.md).
 *   AP_MODE_PROJECTED  state (q, v), orthonormal basis, v projected onto A v + a0 = 0 in the
 *                      metric g after every step.
 *
 * Stepping is done by SUNDIALS (ARKODE explicit pairs, fixed-step RK4, CVODE Adams/BDF);
 * ap_method_count / ap_method_info list what is offered. */
#ifndef APPELL_SIM_H
#define APPELL_SIM_H

#include "appell/export.h"
#include "appell/system.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ap_mode {
  AP_MODE_MINIMAL = 0,
  AP_MODE_PROJECTED = 1,
  AP_MODE_DAE = 2,         /* SUNDIALS IDA on (q, v, lambda): the cross-check */
  AP_MODE_PLAIN = 3        /* as projected but never projected: the velocity constraints drift
                              with the integration error. For comparison only. */
} ap_mode;

typedef struct ap_sim_def {
  ap_mode mode;            /* default AP_MODE_MINIMAL */
  const char *method;      /* stepper name (see ap_method_info); default "dopri5" */
  double rtol;             /* relative tolerance; default 1e-8 */
  double atol;             /* absolute tolerance; default 1e-10 */
  double h_fixed;          /* step for fixed-step methods (s); default 1e-3 */
  double h_init;           /* first step (s); 0 = let the stepper choose (default) */
  double h_max;            /* largest step (s); 0 = unlimited (default) */
  long max_steps;          /* internal steps allowed per ap_sim_advance; default 1000000 */
  double rank_rtol;        /* relative rank tolerance, dimensionless; default 1e-10. A pivot of
                              the QR of A counts when |R_ii| > rank_rtol |R_00| (relative to
                              the largest pivot); a row of the holonomic rows' gradient Phi_q
                              counts when its largest entry exceeds rank_rtol times the model's
                              length scale (the largest frame offset, contact point or shape
                              size, m; 1 for math-level systems): smaller ones vanish
                              identically; a row of A whose norm is below that at t0 while
                              its a0 is not round-off is refused by ap_sim_create
                              (docs/api.md "Tolerances") */
  double switch_growth;    /* minimal mode: re-partition when max|R11^-1 R12| exceeds this;
                              default 2 */
  double init_tol;         /* initial speeds violating A v + a0 = 0 by more than this (in the
                              metric g, relative to |v|) are refused; smaller violations are
                              projected and reported. Body models: initial coordinates whose
                              loop closures are open by more than init_tol (m) are refused too
                              (ap_body_project_q assembles them); smaller gaps are closed and
                              quaternions normalized. Default 1e-6 */
  int internal_check;       /* set by ap_sim_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_sim_def;

AP_API ap_sim_def ap_sim_def_default(void);

typedef struct ap_sim_stats {
  long steps;              /* accepted internal steps */
  long rhs_evals;          /* right-hand-side (ap_forward) evaluations by the stepper */
  long err_fails;          /* steps rejected by the error test */
  long rhs_fails;          /* recoverable failures reported by the right-hand side */
  long partition_switches; /* minimal mode: re-partitions (each restarts the stepper) */
  long projections;        /* projected mode: velocity projections */
  long restarts;           /* stepper restarts of any cause */
  double max_residual;     /* largest |A v + a0| seen at step ends */
  double max_projection;   /* projected mode: largest projection correction (g-norm) */
  double init_correction;  /* g-norm of the correction applied to the initial speeds */
  double min_rcond;        /* smallest reciprocal condition of G = B^T g B (and of R11 in
                              minimal mode) seen at output times */
  double max_phi;          /* DAE mode: largest |phi(q, t)| of a body model's implicit
                              holonomic rows (loop closures in m, |p|^2 - 1 of quaternions)
                              at step ends; 0 in the other modes (project_q holds loops to
                              1e-12 x the length scale there) */
} ap_sim_stats;

typedef struct ap_sim ap_sim;

/* Create a simulation at time t0 with coordinates q0 (n) and speeds v0 (k). Speeds slightly off
 * the constraint set are projected (stats.init_correction says by how much); speeds far off it
 * are refused with AP_ERR_INCONSISTENT. On failure *out is NULL and msg (may be NULL) names
 * the problem: AP_ERR_ARG for a NULL m, def, q0, v0 or out, an unknown mode or method, or a
 * setting out of its range. */
AP_API int ap_sim_create(const ap_model *m, const ap_sim_def *def, double t0, const double *q0,
                         const double *v0, ap_sim **out, char *msg, size_t msg_len);

/* Integrate to tout (finite, >= current time; AP_ERR_ARG otherwise or when s is NULL). The
 * stepper stops exactly at tout. On failure the state is left at the last accepted step
 * (ap_sim_time, ap_sim_q, ap_sim_v and ap_sim_data all describe it) and ap_sim_message says
 * what failed. */
AP_API int ap_sim_advance(ap_sim *s, double tout);
/* After an advance that failed: the state at which the model was last evaluated (t, q (n),
 * v (k): the trial state of the failing step, where a force or drive may have stopped being
 * finite), owned by s and valid until the next advance. AP_ERR_ARG when s is NULL or the
 * last advance did not fail; any of t, q, v may be NULL. */
AP_API int ap_sim_failed_state(const ap_sim *s, double *t, const double **q, const double **v);

/* Queries; with s NULL: NaN, NULL, NULL, NULL. */
AP_API double ap_sim_time(const ap_sim *s);
AP_API const double *ap_sim_q(const ap_sim *s);    /* (n) */
AP_API const double *ap_sim_v(const ap_sim *s);    /* (k) */
/* The pipeline evaluated at the current state (accelerations, metric, basis, ...). */
AP_API const ap_data *ap_sim_data(const ap_sim *s);
/* Multipliers at the current state (b entries) into *lambda (lambda may be NULL); AP_ERR_ARG
 * when s is NULL. */
AP_API int ap_sim_reactions(ap_sim *s, const double **lambda);
/* *st zeroed when s is NULL; nothing written when st is NULL. */
AP_API void ap_sim_get_stats(const ap_sim *s, ap_sim_stats *st);

/* Interrupting a long advance. ap_sim_advance calls poll(t, user) before every internal step,
 * t being the time reached; when it returns non-zero, the advance stops and returns
 * AP_ERR_INTERRUPTED with the simulation at its last accepted step (ap_sim_time, ap_sim_q,
 * ap_sim_v and ap_sim_data describe it) and can be advanced again. The function runs in the
 * caller's thread and should be cheap: read a flag (set by a signal handler or another thread
 * through an atomic or sig_atomic_t variable), check a deadline, draw progress. The library
 * installs no signal handler and reads no global state of its own. poll = NULL (the default)
 * removes it. Nothing happens when s is NULL. */
typedef int (*ap_sim_poll_fn)(double t, void *user);
AP_API void ap_sim_set_poll(ap_sim *s, ap_sim_poll_fn poll, void *user);
/* The last message; "" when s is NULL. */
AP_API const char *ap_sim_message(const ap_sim *s);
/* The first warning of the run, or "" when there is none (or s is NULL). A warning is issued
 * when the condition number of G (or R11) times the machine epsilon exceeds rtol: the linear
 * solves then cannot deliver the requested accuracy. It names the matrix, the condition
 * number and the time. */
AP_API const char *ap_sim_warning(const ap_sim *s);
AP_API void ap_sim_free(ap_sim *s);   /* NULL: nothing */

/* The cross-check (docs/design.md §1): the same model run in minimal, projected and DAE modes with
 * the same tolerances, compared at n_out equally spaced times in (t0, t_end]. Differences are
 * absolute, the largest over all compared times and entries. */
typedef struct ap_crosscheck_report {
  double dq_projected, dq_dae;      /* max |q - q_minimal| */
  double dv_projected, dv_dae;      /* max |v - v_minimal| */
  double dlambda_projected, dlambda_dae; /* max |lambda - lambda_minimal| (0 when b == 0) */
  double max_q, max_v, max_lambda;  /* max |q|, |v|, |lambda| of the minimal run (for scale) */
  double residual[3];               /* max |A v + a0| per mode: minimal, projected, DAE */
  ap_sim_stats stats[3];            /* per mode: minimal, projected, DAE */
  double t_fail;                    /* time reached when a mode failed, else t_end */
} ap_crosscheck_report;

/* Run all three modes from (t0, q0, v0) to t_end. def gives the tolerances and the stepper of
 * the two Appell modes (def->mode is ignored). On failure the message names the mode;
 * AP_ERR_ARG for a NULL argument (msg may be NULL), n_out < 1 or t_end not finite and after
 * t0. */
AP_API int ap_crosscheck(const ap_model *m, const ap_sim_def *def, double t0,
                         const double *q0, const double *v0, double t_end, int n_out,
                         ap_crosscheck_report *rep, char *msg, size_t msg_len);

/* Methods (steppers) on offer. */
typedef struct ap_method_info {
  const char *name;        /* e.g. "dopri5" */
  const char *summary;     /* e.g. "Dormand-Prince 5(4), ARKODE ERKStep" */
  int order;               /* classical order of the propagated solution */
  int adaptive;            /* 1: error-controlled steps; 0: fixed step h_fixed */
  double rtol_floor;       /* below this rtol the method's global error on the reference
                              problems grew past 200 x rtol (docs/steppers.md, "Accuracy");
                              0: no such floor down to rtol 1e-12 */
} ap_method_info;

AP_API int ap_method_count(void);
/* Fill *info for method i (0 <= i < ap_method_count()); AP_ERR_ARG when out of range or info
 * is NULL. */
AP_API int ap_method_get(int i, ap_method_info *info);
/* Fill *info for the method called name; AP_ERR_ARG when there is none or an argument is
 * NULL. */
AP_API int ap_method_find(const char *name, ap_method_info *info);

#ifdef __cplusplus
}
#endif
#endif
