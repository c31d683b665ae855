/* A pool of SUNDIALS serial vectors, so that the integrators' vectors are allocated when they
 * are created, with every allocation checked.
 *
 * SUNDIALS 6.4's N_VClone and N_VCloneEmpty write into the vector the implementation returned
 * without checking it, so an allocation failure inside a clone (ARKODE's, CVODE's and IDA's
 * work vectors, the difference-quotient Jacobian's empty clones) crashes inside SUNDIALS. The
 * vectors handed to SUNDIALS share one operations table whose clone, clone-empty and destroy
 * take a vector from this pool and give it back: clones never allocate while the pool lasts.
 * When it is used up a clone allocates a new vector (N_VNew_Serial checks its allocations);
 * when that fails it hands out the spare (never NULL, which SUNDIALS would dereference) and
 * sets the nomem flag, which the caller checks after every SUNDIALS call.
 * Layout: the shared table is the pool's first member, so a vector's ops pointer leads back to
 * its pool. Invariant: every vector of the pool keeps its own data array (data[i]); a
 * clone-empty lends the vector without it and the destroy puts it back. */
#include <stddef.h>
#include <stdlib.h>

#include "appell/status.h"
#include "integrate/nvpool.h"

struct ap_nvpool {
  struct _generic_N_Vector_Ops ops;   /* first: shared by every vector handed out */
  sunindextype n;
  SUNContext ctx;
  int count;
  N_Vector *v;              /* (count + 1) the vectors; v[count] is the spare */
  double **data;            /* (count + 1) their own data arrays */
  unsigned char *used;      /* (count + 1) */
  int nomem;
};

static ap_nvpool *pool_of(N_Vector w) { return (ap_nvpool *)(void *)w->ops; }

/* Free a vector made by N_VNew_Serial whose ops are the pool's (or its own when own_ops). */
static void free_vector(N_Vector v, double *data, int own_ops) {
  if (!v) return;
  free(data);
  free(v->content);
  if (own_ops) free(v->ops);
  free(v);
}

/* A new vector with the pool's ops; NULL when out of memory. */
static N_Vector fresh(ap_nvpool *p) {
  N_Vector v = N_VNew_Serial(p->n, p->ctx);
  if (!v) return NULL;
  free(v->ops);
  v->ops = &p->ops;
  return v;
}

static int slot_of(const ap_nvpool *p, N_Vector v) {
  for (int i = 0; i <= p->count; i++)
    if (p->v[i] == v) return i;
  return -1;
}

static N_Vector lend(N_Vector w, int empty) {
  ap_nvpool *p = pool_of(w);
  N_Vector v = NULL;
  for (int i = 0; i < p->count && !v; i++)
    if (!p->used[i]) p->used[i] = 1, v = p->v[i];
  if (!v) v = fresh(p);   /* beyond the pool: an allocation SUNDIALS would not check */
  if (!v) p->nomem = 1, v = p->v[p->count];
  if (empty) {
    int i = slot_of(p, v);
    if (i < 0) free(NV_DATA_S(v));   /* an overflow vector's own array is not needed */
    NV_DATA_S(v) = NULL, NV_OWN_DATA_S(v) = SUNFALSE;
  }
  return v;
}

/* z = sum c_i X_i, as SUNDIALS' fallback computes it (z = c_0 X_0 by N_VScale, then
 * z += c_i X_i by N_VLinearSum's axpy, term by term: the same products and sums in the same
 * order, bit for bit), in one loop per term that the compiler vectorizes. ERKStep forms every
 * stage and the solution this way; the library's own fused version is slower on our sizes. */
static void axpy(sunindextype n, double a, const double *restrict x, double *restrict y) {
  for (sunindextype j = 0; j < n; j++) y[j] += a * x[j];
}

static void scale(sunindextype n, double a, const double *restrict x, double *restrict z) {
  for (sunindextype j = 0; j < n; j++) z[j] = a * x[j];
}

static int pool_linear_combination(int nvec, realtype *c, N_Vector *X, N_Vector z) {
  sunindextype n = NV_LENGTH_S(z);
  double *zd = NV_DATA_S(z);
  const double *x0 = NV_DATA_S(X[0]);
  if (x0 == zd)   /* N_VScale_Serial: z *= c, else z = c x (its copy for c = 1 and negation
                     for c = -1 give the same numbers) */
    for (sunindextype j = 0; j < n; j++) zd[j] *= c[0];
  else
    scale(n, c[0], x0, zd);
  for (int i = 1; i < nvec; i++) {
    const double *xd = NV_DATA_S(X[i]);
    if (xd == zd)   /* z += c z */
      for (sunindextype j = 0; j < n; j++) zd[j] += c[i] * zd[j];
    else if (c[i] == 1.0)
      for (sunindextype j = 0; j < n; j++) zd[j] += xd[j];
    else if (c[i] == -1.0)
      for (sunindextype j = 0; j < n; j++) zd[j] -= xd[j];
    else
      axpy(n, c[i], xd, zd);
  }
  return 0;
}

static N_Vector pool_clone(N_Vector w) { return lend(w, 0); }
static N_Vector pool_clone_empty(N_Vector w) { return lend(w, 1); }

static void pool_destroy(N_Vector v) {
  if (!v) return;
  ap_nvpool *p = pool_of(v);
  int i = slot_of(p, v);
  if (i < 0) {   /* an overflow vector */
    free_vector(v, NV_OWN_DATA_S(v) ? NV_DATA_S(v) : NULL, 0);
    return;
  }
  NV_DATA_S(v) = p->data[i], NV_OWN_DATA_S(v) = SUNTRUE;
  if (i < p->count) p->used[i] = 0;
}

int ap_nvp_create(sunindextype n, int count, SUNContext ctx, ap_nvpool **out) {
  *out = NULL;
  ap_nvpool *p = calloc(1, sizeof *p);
  if (!p) return AP_ERR_NOMEM;
  p->n = n, p->ctx = ctx, p->count = count;
  p->v = calloc((size_t)count + 1, sizeof *p->v);
  p->data = calloc((size_t)count + 1, sizeof *p->data);
  p->used = calloc((size_t)count + 1, 1);
  N_Vector first = p->v && p->data && p->used ? N_VNew_Serial(n, ctx) : NULL;
  if (!first) {
    free(p->v), free(p->data), free(p->used), free(p);
    return AP_ERR_NOMEM;
  }
  p->ops = *first->ops;
  p->ops.nvclone = pool_clone, p->ops.nvcloneempty = pool_clone_empty;
  p->ops.nvdestroy = pool_destroy;
  p->ops.nvlinearcombination = pool_linear_combination;
  free(first->ops);
  first->ops = &p->ops;
  p->v[0] = first, p->data[0] = NV_DATA_S(first);
  for (int i = 1; i <= count; i++) {
    if (!(p->v[i] = fresh(p))) {
      ap_nvp_free(p);
      return AP_ERR_NOMEM;
    }
    p->data[i] = NV_DATA_S(p->v[i]);
  }
  *out = p;
  return AP_OK;
}

N_Vector ap_nvp_take(ap_nvpool *p) {
  for (int i = 0; i < p->count; i++)
    if (!p->used[i]) return p->used[i] = 1, p->v[i];
  return NULL;
}

int ap_nvp_nomem(const ap_nvpool *p) { return p && p->nomem; }

void ap_nvp_free(ap_nvpool *p) {
  if (!p) return;
  for (int i = 0; i <= p->count; i++) free_vector(p->v[i], p->data[i], 0);
  free(p->v), free(p->data), free(p->used);
  free(p);
}
