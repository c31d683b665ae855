/* Appell core (internal): the compiled model and the data's private scratch.
 *
 * The model is a validated copy of a math-level system definition (DESIGN.md §2, "Math-level
 * systems"); the body layer will compile into the same struct. The data's internal arena holds
 * the factorizations and scratch of the pipeline, sized once in ap_data_create. */
#ifndef AP_CORE_H
#define AP_CORE_H

#include <stddef.h>

#include "appell/system.h"

/* A model compiled from bodies (lib/model) evaluates its own g, N, A, a0 and h, Q, gamma in
 * place of user callbacks. Its per-data scratch (ev.scratch doubles) lives in the data, so one
 * model can serve many data at once. Every hook returns AP_OK, AP_RECOVERABLE or AP_ERR_*
 * and writes d->msg on failure. */
typedef struct ap_evaluator {
  size_t scratch;           /* doubles of scratch per data */
  /* position stage: g (k x k), N (n x k), A (b x k), a0 (b) at (d->t, d->q); the arrays are
   * zeroed before the call */
  int (*position)(const ap_model *m, ap_data *d, double *scratch);
  /* velocity stage: h (k), Q (k), gamma (b) at (d->t, d->q, d->v), after position; zeroed
   * before the call */
  int (*velocity)(const ap_model *m, ap_data *d, double *scratch);
  /* after an accepted step: put q back on its manifold (unit quaternions, loop closures);
   * *change = size of the correction. May be NULL. */
  int (*project_q)(const ap_model *m, ap_data *d, double *q, double *scratch, double *change);
  /* Implicit holonomic constraints phi(q, t) = 0 (m->nphi rows: loop closures, unit-quaternion
   * norms) for the DAE mode's stabilized index-2 (GGL) form: phi (nphi) and its Jacobian with
   * respect to q, Phi_q (nphi x n, column-major, ld nphi; zeroed by the caller), at
   * (d->t, d->q) after the position stage there (it reads that stage's kinematics); Phi_q
   * may be NULL (phi only). The hook is NULL when nphi == 0. */
  int (*phi)(const ap_model *m, ap_data *d, double *scratch, double *phi, double *Phi_q);
  /* After an accepted step of a mode that must not move q (DAE): the checks of project_q
   * without the corrections (a disk or torus reaching lying flat). May be NULL. */
  int (*check_q)(const ap_model *m, ap_data *d, const double *q, double *scratch);
  void (*destroy)(void *impl);   /* frees impl with the model */
  void *impl;
} ap_evaluator;

struct ap_model {
  ap_system_def sys;        /* callbacks and sizes; names point into the arrays below */
  ap_evaluator ev;          /* set by the body layer; all NULL for math-level systems */
  int n, k, b;
  int nphi;                 /* rows of ev.phi; 0 for math-level systems */
  int nhol;                 /* implicit holonomic rows among the constraint rows (loop
                               closures, wheel contacts): redundancy among the rows may then
                               hold only where they are closed; 0 for math-level systems */
  char name[64];
  char **coord_names;       /* (n) */
  char **speed_names;       /* (k) */
  char **constraint_names;  /* (b) */
};

/* Scratch owned by one ap_data (no allocation after ap_data_create). */
typedef struct ap_scratch {
  double *F;                /* QR factor: (b x k) partitioned, (k x b) orthonormal */
  double *tau;              /* Householder scalars (max(b, k)) */
  int *jpvt;                /* row order of A (b), orthonormal basis */
  double *Qf;               /* full orthogonal factor of A^T (k x k) */
  double *dg;               /* metric derivative (n x k x k), Christoffel bias only */
  double *gB;               /* g B (k x l) */
  double *tk1, *tk2;        /* k-vectors */
  double *tl;               /* l-vector */
  double *tn;               /* n-vector (ap_partition: q while it tries a nearby state) */
  double *work;             /* linalg scratch, ap_la_work_size(b, k) doubles */
  double *ev;               /* evaluator scratch, m->ev.scratch doubles (may be NULL) */
  int *iwork;               /* linalg scratch, ap_la_iwork_size(b, k) ints */
} ap_scratch;

/* Largest magnitude a model quantity may have: the steppers' error norms square the state's
 * derivatives, and past 1e154 the square overflows (the step size, then the time, become NaN). */
#define AP_HUGE 1e150

/* Check that x[0..len-1] is finite and at most AP_HUGE in magnitude; otherwise write a message
 * naming the callback, the entry and the value. */
int ap_core_check_finite(const ap_model *m, ap_data *d, const char *what, const double *x,
                         int rows, int cols);

/* Translate a callback's return code into a status with a message. */
int ap_core_callback_status(const ap_model *m, ap_data *d, const char *what, int rc);

/* ap_project_speeds without the position stage: the data's g, B, b0 must be current. */
int ap_core_project_here(const ap_model *m, ap_data *d, double *v, double *change);

/* The consistency of redundant rows that hold only on the holonomic manifold, judged at an
 * accepted state (after ap_fwd_position and ap_fwd_velocity there, q projected): the residuals
 * of a0 and gamma on the dropped rows against d->manifold_rtol. AP_ERR_INCONSISTENT with the
 * rows named; AP_OK when the model has no such rows. */
int ap_core_judge_redundant(const ap_model *m, ap_data *d);

/* x <- B G^-1 B^T g x: the g-orthogonal projection onto the null space of A, with the factor
 * of G left by ap_core_project_here. */
void ap_core_project_tangent(const ap_model *m, ap_data *d, double *x);

/* v = B e' + b0 from the data's position stage (partitioned basis). */
void ap_core_speeds(const ap_model *m, ap_data *d);

/* printf into d->msg. */
void ap_core_msg(ap_data *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
