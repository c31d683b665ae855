/* The differential tester's measures of the constraint rows' conditioning (docs/testing.md,
 * "What is run and checked"): how much a change of A v + a0 moves the speeds. */
#ifndef AP_DIFFTEST_COND_H
#define AP_DIFFTEST_COND_H

#include "appell/appell.h"

typedef struct dt_cond {
  double pinv;    /* ||M||_2, M = g^-1 A^T (A g^-1 A^T)^+ the map from a change of A v + a0
                     to the speeds' change normal to the constraints (nearest in g); 0 without
                     rows or rank */
  double anorm;   /* ||A||_2 */
  double amax;    /* max |A_ij| */
  double lscale;  /* the model's length scale (m): the largest lever arm of A's terms */
  double a0;      /* max |a0| */
} dt_cond;

/* The conditioning of the dense model m at (t, q), on the data d (made for m). AP_OK, or the
 * position stage's status (c is then zero). */
int dt_cond_at(const ap_model *m, ap_data *d, double t, const double *q, dt_cond *c);

#endif
