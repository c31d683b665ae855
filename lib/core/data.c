/* The data struct: state, pipeline intermediates, scratch (include/appell/system.h).
 *
 * Layout: one block of scalars and one of ints, carved into the fields in the order they are
 * declared; sizes are fixed by the model, so no stage ever allocates. The identity basis
 * (b == 0) and identity N (no kinematic callback) are written here once and never touched.
 * Generic in the scalar (linalg/scalar.h): data_cs.c compiles this file again into
 * ap_data_create_cs, which makes the complex-step mirror ap_data_cs (core/core.h). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "core/structured.h"
#include "linalg/linalg.h"

typedef struct ap_data_block {
  ap_scratch s;
  ap_sc *dbl;
  int *ints;
} ap_data_block;

static ap_sc *carve(ap_sc **p, size_t count) {
  ap_sc *out = *p;
  *p += count;
  return out;
}

static int *carve_int(int **p, size_t count) {
  int *out = *p;
  *p += count;
  return out;
}

#ifndef AP_SC_COMPLEX
/* The tree path's data (m->ops): the vectors only, O(n + k + b); g, N, A, B, G stay NULL and
 * the structured state (core/structured.c) holds the operators' workspace, whose shadow
 * scratch is the data's evaluator scratch. */
static int create_structured(const ap_model *m, ap_data **out) {
  size_t n = (size_t)m->n, k = (size_t)m->k, b = (size_t)m->b, nb = b > 0 ? b : 1;
  size_t nd = n + 3 * k + nb + k + k + k + nb + k + k + k + k + n + nb + 4 * k + n;
  ap_data *d = calloc(1, sizeof *d);
  ap_data_block *blk = calloc(1, sizeof *blk);
  double *dbl = calloc(nd, sizeof *dbl);
  int *ints = calloc(k + nb, sizeof *ints);
  ap_st *st = NULL;
  int rc = d && blk && dbl && ints ? ap_st_create(m, m->ops, &st) : AP_ERR_NOMEM;
  if (rc != AP_OK) {
    free(d), free(blk), free(dbl), free(ints);
    return rc;
  }
  double *p = dbl;
  int *ip = ints;
  d->n = m->n, d->k = m->k, d->b = m->b;
  d->q = carve(&p, n), d->v = carve(&p, k), d->e = carve(&p, k), d->a0 = carve(&p, nb);
  d->b0 = carve(&p, k), d->h = carve(&p, k), d->Q = carve(&p, k), d->gamma = carve(&p, nb);
  d->w = carve(&p, k), d->Phi = carve(&p, k), d->edd = carve(&p, k), d->vdot = carve(&p, k);
  d->qdot = carve(&p, n), d->lambda = carve(&p, nb);
  ap_scratch *s = &blk->s;
  s->tk1 = carve(&p, k), s->tk2 = carve(&p, k), s->tl = carve(&p, k);
  s->tau = carve(&p, k), s->tn = carve(&p, n);
  s->ev = m->ops->ev_scratch(st->ws);
  s->model = m, s->st = st;
  d->perm = carve_int(&ip, k), s->jpvt = carve_int(&ip, nb);
  blk->dbl = dbl, blk->ints = ints;
  d->internal = blk;
  d->basis = AP_BASIS_PARTITIONED;
  d->rank_rtol = 1e-10;
  d->manifold_rtol = 1e-8;
  d->rank = 0, d->l = m->k;
  for (int i = 0; i < m->k; i++) d->perm[i] = i;
  d->rcond_R = 1.0, d->rcond_G = 1.0;
  *out = d;
  return AP_OK;
}
#endif

int AP_SC(ap_data_create)(const ap_model *m, ap_data **out) {
  if (!m || !out) return AP_ERR_ARG;
#ifdef AP_SC_COMPLEX
  if (!m->ev.position_cs) return AP_ERR_UNSUPPORTED;
#else
  if (m->ops) {
    *out = NULL;
    return create_structured(m, out);
  }
#endif
  *out = NULL;
  size_t n = (size_t)m->n, k = (size_t)m->k, b = (size_t)m->b;
  size_t nb = b > 0 ? b : 1, mk = b > k ? b : k;
  size_t ndg = m->sys.bias_source == AP_BIAS_CHRISTOFFEL ? n * k * k : 0;
  size_t lw = ap_la_work_size(m->b, m->k), liw = ap_la_iwork_size(m->b, m->k);
  size_t nd = n + k + k + k * k + n * k + nb * k + nb + k * k + k  /* q v e g N A a0 B b0 */
            + k + k + nb + k + k * k + k + k + k + n + nb          /* h Q gamma w G Phi edd vdot qdot lambda */
            + nb * k + mk + k * k + ndg + k * k + 3 * k + lw + n  /* scratch */
            + m->ev.scratch;
  size_t ni = k + nb + liw;

  ap_data *d = calloc(1, sizeof *d);
  ap_data_block *blk = calloc(1, sizeof *blk);
  ap_sc *dbl = calloc(nd, sizeof *dbl);
  int *ints = calloc(ni, sizeof *ints);
  if (!d || !blk || !dbl || !ints) {
    free(d), free(blk), free(dbl), free(ints);
    return AP_ERR_NOMEM;
  }
  ap_sc *p = dbl;
  int *ip = ints;
  d->n = m->n, d->k = m->k, d->b = m->b;
  d->q = carve(&p, n), d->v = carve(&p, k), d->e = carve(&p, k);
  d->g = carve(&p, k * k), d->N = carve(&p, n * k), d->A = carve(&p, nb * k);
  d->a0 = carve(&p, nb), d->B = carve(&p, k * k), d->b0 = carve(&p, k);
  d->h = carve(&p, k), d->Q = carve(&p, k), d->gamma = carve(&p, nb), d->w = carve(&p, k);
  d->G = carve(&p, k * k), d->Phi = carve(&p, k), d->edd = carve(&p, k);
  d->vdot = carve(&p, k), d->qdot = carve(&p, n), d->lambda = carve(&p, nb);
  ap_scratch *s = &blk->s;
  s->F = carve(&p, nb * k), s->tau = carve(&p, mk), s->Qf = carve(&p, k * k);
  s->dg = ndg ? carve(&p, ndg) : NULL;
  s->gB = carve(&p, k * k), s->tk1 = carve(&p, k), s->tk2 = carve(&p, k), s->tl = carve(&p, k);
  s->work = carve(&p, lw), s->tn = carve(&p, n);
  s->ev = m->ev.scratch ? carve(&p, m->ev.scratch) : NULL;
  s->model = m;
  d->perm = carve_int(&ip, k), s->jpvt = carve_int(&ip, nb), s->iwork = carve_int(&ip, liw);
  blk->dbl = dbl, blk->ints = ints;
  d->internal = blk;

  /* Defaults: no constraints means the identity basis; no kinematics means N = I. */
  d->basis = AP_BASIS_PARTITIONED;
  d->rank_rtol = 1e-10;
  d->manifold_rtol = 1e-8;
  d->rank = 0, d->l = m->k;
  for (int i = 0; i < m->k; i++) d->perm[i] = i, d->B[i + (size_t)i * k] = 1.0;
  /* N is n x k: its identity has min(n, k) ones (body models with quaternions have n > k and
   * write N in their position stage). */
  if (!m->sys.kinematic)
    for (int i = 0; i < m->n && i < m->k; i++) d->N[i + (size_t)i * n] = 1.0;
  d->rcond_R = 1.0, d->rcond_G = 1.0;
  *out = d;
  return AP_OK;
}

void AP_SC(ap_data_free)(ap_data *d) {
  if (!d) return;
  ap_data_block *blk = d->internal;
  if (blk) {
#ifndef AP_SC_COMPLEX
    ap_st_free(blk->s.st);
#endif
    free(blk->dbl);
    free(blk->ints);
    free(blk);
  }
  free(d);
}

void AP_SC(ap_core_msg)(ap_data *d, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(d->msg, sizeof d->msg, fmt, ap);
  va_end(ap);
}

#ifndef AP_SC_COMPLEX
void ap_core_copy_partition(const ap_data *src, ap_data_cs *dst) {
  dst->rank_rtol = src->rank_rtol, dst->manifold_rtol = src->manifold_rtol;
  dst->rank = src->rank, dst->l = src->l, dst->redundant = src->redundant;
  dst->redundant_manifold = src->redundant_manifold;
  memcpy(dst->perm, src->perm, sizeof *dst->perm * (size_t)src->k);
}
#endif
