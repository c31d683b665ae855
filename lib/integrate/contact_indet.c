/* Friction that is statically indeterminate (docs/scenes.md "Friction, slip and lift-off",
 * "Consistent modes"): a rolling contact with a friction coefficient whose tangential rows
 * (.x, .y) are combinations of the other active rows (two wheels of one axle repeat each
 * other's sideways row; a loop may repeat a wheel's row) has no unique friction force: the
 * reactions split it by minimum norm (in DAE mode the events split IDA's multipliers so too:
 * contact_dae.c), so its slip and stick times follow that choice, not physics. Found at the start, with every contact's rows as when rolling: rank(A) -
 * rank(A without the two rows) < 2 (pivoted QR, the data's rank_rtol); the run's warning
 * names each such contact. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrate/contact_int.h"
#include "linalg/linalg.h"

/* The rank of A (b x k) with rows r0, r0 + 1 zeroed when r0 >= 0. */
static int rank_without(const ap_sim *s, const double *A, int r0, double *X, int *perm,
                        double *work, int *iwork) {
  int b = s->b, k = s->k, rank = 0;
  memcpy(X, A, sizeof(double) * (size_t)b * (size_t)k);
  for (int j = 0; r0 >= 0 && j < k; j++) X[r0 + (size_t)j * b] = X[r0 + 1 + (size_t)j * b] = 0;
  return ap_la_pivot_select(b, k, X, s->d->rank_rtol, perm, &rank, work, iwork) == AP_OK ? rank
                                                                                         : -1;
}

/* A fresh data (its contacts all rolling: the modes' block starts zeroed) at the start's q,
 * with the position stage: A of every row. NULL when it cannot be evaluated. */
static ap_data *rolling_rows(const ap_sim *s) {
  ap_data *d = NULL;
  if (ap_data_create(s->m, &d) != AP_OK) return NULL;
  d->t = s->t, d->speeds_from_e = 0, d->basis = AP_BASIS_ORTHONORMAL;
  memcpy(d->q, s->q, sizeof(double) * (size_t)s->n);
  int rc = ap_partition(s->m, d);
  if (rc == AP_OK) rc = ap_fwd_position(s->m, d);
  if (rc != AP_OK) ap_data_free(d), d = NULL;
  return d;
}

static void warn(ap_sim *s, const ap_mcon *c) {
  size_t used = strlen(s->warning);
  snprintf(s->warning + used, sizeof s->warning - used, "%scontact '%s': its friction rows are "
           "combinations of other rows (e.g. two wheels of one axle), so its friction force is "
           "statically indeterminate: slip and stick follow the minimum-norm split of it, "
           "in every mode",
           used ? "; " : "", c->name);
}

int ap_drv_cm_indeterminate(ap_sim *s) {
  const ap_bmodel *M = ap_bm(s->m);
  int b = s->b, k = s->k;
  if (b < 3 || k < 1) return AP_OK;
  size_t nw = ap_la_work_size(b, k), ni = ap_la_iwork_size(b, k);
  double *X = malloc(sizeof(double) * ((size_t)b * (size_t)k + nw + 1));
  int *iw = malloc(sizeof(int) * ((size_t)k + ni + 1));
  if (!X || !iw) {
    free(X), free(iw);
    return ap_drv_fail(s, AP_ERR_NOMEM, "out of memory");
  }
  ap_data *d = rolling_rows(s);
  int full = d ? rank_without(s, d->A, -1, X, iw, X + (size_t)b * k, iw + k) : -1;
  for (int ci = 0; full > 0 && ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0 || !(c->def.mu >= 0) || ap_bm_wheel_by_load(M, c)) continue;
    int r = rank_without(s, d->A, c->row, X, iw, X + (size_t)b * k, iw + k);
    if (r >= 0 && full - r < 2) warn(s, c);
  }
  ap_data_free(d);
  free(X);
  free(iw);
  return AP_OK;   /* a state the forces cannot be evaluated at is judged by the run itself */
}
