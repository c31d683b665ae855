/* SUNDIALS contexts kept for reuse (sunctx.c). Internal to lib/integrate and lib/batch;
 * functions carry the prefix ap_ctx_. */
#ifndef AP_INTEGRATE_SUNCTX_H
#define AP_INTEGRATE_SUNCTX_H

#include <sundials/sundials_context.h>

/* A context for one integrator, from the idle ones when there is one, else new: AP_OK, or
 * AP_ERR_NOMEM with *out NULL. Give it back with ap_ctx_give once every SUNDIALS object made
 * with it has been freed. */
int ap_ctx_take(SUNContext *out);
/* Back to the idle ones (NULL: nothing). */
void ap_ctx_give(SUNContext ctx);
/* At least n idle contexts, created now (a sweep's workers, before the first run): AP_OK, or
 * AP_ERR_NOMEM (the ones made so far are kept). */
int ap_ctx_reserve(int n);

#endif
