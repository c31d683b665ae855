/* A pool of SUNDIALS serial vectors allocated when an integrator is created (nvpool.c).
 * Internal to lib/integrate; functions carry the prefix ap_nvp_. */
#ifndef AP_INTEGRATE_NVPOOL_H
#define AP_INTEGRATE_NVPOOL_H

#include <nvector/nvector_serial.h>

typedef struct ap_nvpool ap_nvpool;

/* count vectors of length n (and one spare) in context ctx, every allocation checked:
 * AP_OK, or AP_ERR_NOMEM with *out NULL and nothing left allocated. */
int ap_nvp_create(sunindextype n, int count, SUNContext ctx, ap_nvpool **out);
/* A vector of the pool for the caller's own use (its clones come from the pool too); NULL when
 * the pool is used up. Give it back with N_VDestroy. */
N_Vector ap_nvp_take(ap_nvpool *p);
/* 1 when a clone found the pool used up and no memory to grow it (it was handed the spare:
 * whatever ran with it must be discarded and AP_ERR_NOMEM reported). */
int ap_nvp_nomem(const ap_nvpool *p);
/* Free the pool and its vectors, after everything that cloned from it has been freed. */
void ap_nvp_free(ap_nvpool *p);

#endif
