/* The data struct: state, pipeline intermediates, scratch (include/appell/system.h).
 *
 * Layout: one block of scalars and one of ints, each described by one table of its arrays
 * (DENSE_DOUBLES, ... below; core/arena.h): sizes, offsets and carving come from the table and
 * are checked here; sizes are fixed by the model, so no stage ever allocates. In the guard build
 * (meson -Dguards=true) guard words follow every array and ap_core_guards checks them after
 * each stage. The identity basis
 * (b == 0) and identity N (no kinematic callback) are written here once and never touched.
 * Generic in the scalar (linalg/scalar.h): data_cs.c compiles this file again into
 * ap_data_create_cs, which makes the complex-step mirror ap_data_cs (core/core.h). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arena.h"
#include "core/core.h"
#include "core/structured.h"
#include "linalg/linalg.h"

typedef struct ap_data_block {
  ap_scratch s;
  ap_sc *dbl;
  int *ints;
  ap_arena dl, il;          /* the layouts of dbl and ints (their guards in the guard build) */
  const char *hit_stage;    /* guard build: the stage after which a guard was first seen hit */
} ap_data_block;

/* ---- the layout tables -------------------------------------------------------------------
 * Each block is one table X(field, count, null_when_empty) in block order: the sizes, the
 * offsets and the carving all come from it (core/arena.h), and ap_data_create checks the
 * result. Counts use the locals of data_sizes. */

typedef struct data_sizes {
  size_t n, k, nb, mk, ndg, lw, liw, ev;
} data_sizes;

/* The dense path: every object of the pipeline, then the scratch. */
#define DENSE_DOUBLES(X)                                                                   \
  X(d->q, z.n, 0) X(d->v, z.k, 0) X(d->e, z.k, 0) X(d->g, z.k * z.k, 0)                    \
  X(d->N, z.n * z.k, 0) X(d->A, z.nb * z.k, 0) X(d->a0, z.nb, 0) X(d->B, z.k * z.k, 0)     \
  X(d->b0, z.k, 0) X(d->h, z.k, 0) X(d->Q, z.k, 0) X(d->gamma, z.nb, 0) X(d->w, z.k, 0)    \
  X(d->G, z.k * z.k, 0) X(d->Phi, z.k, 0) X(d->edd, z.k, 0) X(d->vdot, z.k, 0)             \
  X(d->qdot, z.n, 0) X(d->lambda, z.nb, 0)                                                 \
  X(s->F, z.nb * z.k, 0) X(s->tau, z.mk, 0) X(s->Qf, z.k * z.k, 0) X(s->dg, z.ndg, 1)      \
  X(s->gB, z.k * z.k, 0) X(s->tk1, z.k, 0) X(s->tk2, z.k, 0) X(s->tl, z.k, 0)              \
  X(s->work, z.lw, 0) X(s->tn, z.n, 0) X(s->ev, z.ev, 1)
#define DENSE_INTS(X) X(d->perm, z.k, 0) X(s->jpvt, z.nb, 0) X(s->iwork, z.liw, 0)

/* The tree path (m->ops): the vectors only, O(n + k + b); g, N, A, B, G stay NULL and the
 * structured state (core/structured.c) holds the operators' workspace. */
#define TREE_DOUBLES(X)                                                                    \
  X(d->q, z.n, 0) X(d->v, z.k, 0) X(d->e, z.k, 0) X(d->a0, z.nb, 0) X(d->b0, z.k, 0)       \
  X(d->h, z.k, 0) X(d->Q, z.k, 0) X(d->gamma, z.nb, 0) X(d->w, z.k, 0) X(d->Phi, z.k, 0)   \
  X(d->edd, z.k, 0) X(d->vdot, z.k, 0) X(d->qdot, z.n, 0) X(d->lambda, z.nb, 0)            \
  X(s->tk1, z.k, 0) X(s->tk2, z.k, 0) X(s->tl, z.k, 0) X(s->tau, z.k, 0) X(s->tn, z.n, 0)
#define TREE_INTS(X) X(d->perm, z.k, 0) X(s->jpvt, z.nb, 0)

#define LAYOUT_ADD(f_, c_, nul_) ap_arena_add(L, #f_, (c_));
#define LAYOUT_CARVE(f_, c_, nul_)                                                         \
  f_ = (nul_) && L->e[i].count == 0 ? NULL : base_ + L->e[i].offset;                       \
  i++;

static data_sizes sizes_of(const ap_model *m) {
  data_sizes z = {0};
  z.n = (size_t)m->n, z.k = (size_t)m->k;
  z.nb = m->b > 0 ? (size_t)m->b : 1;
  z.mk = z.nb > z.k ? z.nb : z.k;
  z.ndg = m->sys.bias_source == AP_BIAS_CHRISTOFFEL ? z.n * z.k * z.k : 0;
  z.lw = ap_la_work_size(m->b, m->k), z.liw = ap_la_iwork_size(m->b, m->k);
  z.ev = m->ev.scratch;
  return z;
}

/* Both tables of a block pair (tree: the tree path's) into blk->dl and blk->il. */
static void data_layout(const ap_model *m, int tree, ap_data_block *blk) {
  data_sizes z = sizes_of(m);
  ap_arena *L = &blk->dl;
  ap_arena_init(L, "data scalars", sizeof(ap_sc), AP_ARENA_GUARDS);
  if (tree) {
    TREE_DOUBLES(LAYOUT_ADD)
  } else {
    DENSE_DOUBLES(LAYOUT_ADD)
  }
  L = &blk->il;
  ap_arena_init(L, "data ints", sizeof(int), AP_ARENA_GUARDS);
  if (tree) {
    TREE_INTS(LAYOUT_ADD)
  } else {
    DENSE_INTS(LAYOUT_ADD)
  }
}

/* The fields of d and its scratch pointed into the blocks (the tables' order). */
static void data_carve(ap_data *d, int tree, ap_data_block *blk) {
  ap_scratch *s = &blk->s;
  const ap_arena *L = &blk->dl;
  int i = 0;
  {
    ap_sc *base_ = blk->dbl;
    if (tree) {
      TREE_DOUBLES(LAYOUT_CARVE)
    } else {
      DENSE_DOUBLES(LAYOUT_CARVE)
    }
  }
  L = &blk->il, i = 0;
  {
    int *base_ = blk->ints;
    if (tree) {
      TREE_INTS(LAYOUT_CARVE)
    } else {
      DENSE_INTS(LAYOUT_CARVE)
    }
  }
}

/* The evaluator's sections (dense path) in this build's scalar: the model's table counts
 * elements, and the complex-step scratch holds as many complex ones at the same offsets. */
static int ev_layout(const ap_model *m, ap_arena *out) {
  if (!m->ev.layout) return 0;
  *out = *m->ev.layout;
  out->elsize = sizeof(ap_sc);
  return 1;
}

/* Allocate d, its block pair and their tables; carve the fields; check the layout. */
static int data_alloc(const ap_model *m, int tree, ap_data **out, ap_data_block **blk_out) {
  ap_data *d = calloc(1, sizeof *d);
  ap_data_block *blk = calloc(1, sizeof *blk);
  if (!d || !blk) {
    free(d), free(blk);
    return AP_ERR_NOMEM;
  }
  data_layout(m, tree, blk);
  int bad = ap_arena_check(&blk->dl, d->msg, sizeof d->msg) ||
            ap_arena_check(&blk->il, d->msg, sizeof d->msg);
  blk->dbl = bad ? NULL : calloc(blk->dl.total, sizeof(ap_sc));
  blk->ints = bad ? NULL : calloc(blk->il.total, sizeof(int));
  if (bad || !blk->dbl || !blk->ints) {
    free(blk->dbl), free(blk->ints), free(d), free(blk);
    return bad ? AP_ERR_INTERNAL : AP_ERR_NOMEM;
  }
  ap_arena_fill_guards(&blk->dl, blk->dbl);
  ap_arena_fill_guards(&blk->il, blk->ints);
  data_carve(d, tree, blk);
  ap_arena evl;
  if (!tree && ev_layout(m, &evl)) ap_arena_fill_guards(&evl, blk->s.ev);
  blk->s.model = m;
  d->internal = blk;
  d->n = m->n, d->k = m->k, d->b = m->b;
  d->basis = AP_BASIS_PARTITIONED;
  d->rank_rtol = 1e-10;
  d->manifold_rtol = 1e-8;
  d->rank = 0, d->l = m->k;
  for (int i = 0; i < m->k; i++) d->perm[i] = i;
  d->rcond_R = 1.0, d->rcond_G = 1.0;
  *out = d, *blk_out = blk;
  return AP_OK;
}

int AP_SC(ap_core_guards)(const ap_model *m, ap_data *d, const char *stage, int rc) {
  ap_data_block *blk = d->internal;
  char what[400];
  if (blk->hit_stage) stage = blk->hit_stage;
  ap_arena evl;   /* the evaluator's sections (dense path; both builds) */
#ifndef AP_SC_COMPLEX
  const ap_st *st = blk->s.st;   /* the tree path's workspace */
  int ev = !st && ev_layout(m, &evl);
  int ws = st && st->ops->guard_msg && st->ops->guard_msg(st->ws, stage, what, sizeof what) != 0;
#else
  int ev = ev_layout(m, &evl), ws = 0;   /* no tree path in the complex-step build */
#endif
  if (ws || ap_arena_guard_msg(&blk->dl, blk->dbl, stage, what, sizeof what) != 0 ||
      ap_arena_guard_msg(&blk->il, blk->ints, stage, what, sizeof what) != 0 ||
      (ev && ap_arena_guard_msg(&evl, blk->s.ev, stage, what, sizeof what) != 0)) {
    blk->hit_stage = stage;
    AP_SC(ap_core_msg)(d, "model '%s': %s", m->name, what);
    return AP_ERR_INTERNAL;
  }
  return rc;
}

/* Guard build: a guard hit while the data was made is reported by the first stage, naming
 * ap_data_create (ap_data_create itself has no message to return). */
static void guards_at_create(ap_data_block *blk) {
  if (AP_GUARDS && (ap_arena_guard_hit(&blk->dl, blk->dbl, NULL) >= 0 ||
                    ap_arena_guard_hit(&blk->il, blk->ints, NULL) >= 0))
    blk->hit_stage = "ap_data_create";
}

#ifndef AP_SC_COMPLEX
/* The tree path's data: its structured state gives the evaluator scratch. */
static int create_structured(const ap_model *m, ap_data **out) {
  ap_st *st = NULL;
  int rc = ap_st_create(m, m->ops, &st);
  if (rc != AP_OK) return rc;
  ap_data *d = NULL;
  ap_data_block *blk = NULL;
  rc = data_alloc(m, 1, &d, &blk);
  if (rc != AP_OK) {
    ap_st_free(st);
    return rc;
  }
  blk->s.ev = m->ops->ev_scratch(st->ws);
  blk->s.st = st;
  guards_at_create(blk);
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
  ap_data *d = NULL;
  ap_data_block *blk = NULL;
  int rc = data_alloc(m, 0, &d, &blk);
  if (rc != AP_OK) return rc;
  size_t k = (size_t)m->k, n = (size_t)m->n;
  /* Defaults: no constraints means the identity basis; no kinematics means N = I. */
  for (int i = 0; i < m->k; i++) d->B[i + (size_t)i * k] = 1.0;
  /* N is n x k: its identity has min(n, k) ones (body models with quaternions have n > k and
   * write N in their position stage). */
  if (!m->sys.kinematic)
    for (int i = 0; i < m->n && i < m->k; i++) d->N[i + (size_t)i * n] = 1.0;
  guards_at_create(blk);
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
