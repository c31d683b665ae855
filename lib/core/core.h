/* Appell core (internal): the compiled model and the data's private scratch.
 *
 * The model is a validated copy of a math-level system definition (DESIGN.md §2, "Math-level
 * systems"); the body layer will compile into the same struct. The data's internal arena holds
 * the factorizations and scratch of the pipeline, sized once in ap_data_create. */
#ifndef AP_CORE_H
#define AP_CORE_H

#include <stddef.h>

#include "appell/system.h"

struct ap_model {
  ap_system_def sys;        /* callbacks and sizes; names point into the arrays below */
  int n, k, b;
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
  double *work;             /* linalg scratch, ap_la_work_size(b, k) doubles */
  int *iwork;               /* linalg scratch, ap_la_iwork_size(b, k) ints */
} ap_scratch;

/* Check that x[0..len-1] is finite; otherwise write a message naming the callback and entry. */
int ap_core_check_finite(const ap_model *m, ap_data *d, const char *what, const double *x,
                         int rows, int cols);

/* Translate a callback's return code into a status with a message. */
int ap_core_callback_status(const ap_model *m, ap_data *d, const char *what, int rc);

/* printf into d->msg. */
void ap_core_msg(ap_data *d, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
