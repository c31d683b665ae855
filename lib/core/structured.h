/* Appell core (internal): the structured pipeline, for models whose evaluator never forms g,
 * A or B (docs/large.md). The model supplies the operators (ap_ops); the core keeps the
 * Appell solve: G e'' = B^T (Q - h - g w), v' = B e'' + w, with the basis in independent
 * blocks B = sum_t P_t B_t E_t^T (P_t picks block t's speeds, E_t its free speeds) and G
 * block-diagonal, G_t = B_t^T g B_t. Same meaning as the dense path; e' is the same vector
 * (the independent speeds, ascending), only the partition is chosen body by body. */
#ifndef AP_CORE_STRUCTURED_H
#define AP_CORE_STRUCTURED_H

#include <stddef.h>

#include "appell/system.h"

/* The basis blocks, valid after a position stage. */
typedef struct ap_sblocks {
  int n;                      /* blocks */
  const int *kofs, *kidx;     /* speeds of block t: kidx[kofs[t] .. kofs[t+1]-1] (global) */
  const int *lofs, *lidx;     /* free speeds (e' indices) of block t */
  const int *bofs, *gofs;     /* offsets of B_t (k_t x l_t) and G_t (l_t x l_t), column-major */
  const double *B, *G;
} ap_sblocks;

/* A structured evaluator. Every hook returns AP_OK, AP_RECOVERABLE or AP_ERR_* and writes
 * d->msg on failure. ws is the model's per-data workspace. */
/* ops->position's select: 0 keep the partition; 1 choose one; AP_ST_SELECT_PARTITION choose
 * it for ap_partition (and tell rows redundant only on the holonomic manifold,
 * d->redundant_manifold); AP_ST_SELECT_STAGE choose one for a stage of projected mode (such
 * rows' ranks kept from the partition, as the dense path keeps its rank). */
enum { AP_ST_SELECT_PARTITION = 2, AP_ST_SELECT_STAGE = 3 };

typedef struct ap_ops {
  const void *ctx;            /* the model's own data, passed to ws_create */
  /* workspace of one data: allocated once with the data; *gcap = doubles that hold every G_t */
  void *(*ws_create)(const void *ctx, size_t *gcap);
  void (*ws_free)(void *ws);
  /* position stage at (d->t, d->q): a0, the factorization with the partition in d (select:
   * choose it and write perm, rank, l, redundant; AP_ST_SELECT_*), b0, growth, resid_a0, the
   * blocks */
  int (*position)(const ap_model *m, ap_data *d, void *ws, int select);
  /* velocity stage at d->v: h, Q, gamma, w, resid_gamma */
  int (*velocity)(const ap_model *m, ap_data *d, void *ws);
  void (*blocks)(void *ws, ap_sblocks *out);
  void (*gmul)(void *ws, const double *x, double *y);                  /* y = g x */
  /* r = A x + a0; mag (may be NULL): per row, the sum of its terms' magnitudes */
  void (*amul)(void *ws, const ap_data *d, const double *x, double *r, double *mag);
  void (*nmul)(void *ws, const double *q, const double *v, double *qdot); /* q' = N v */
  /* u (k) with A u + r = 0 (a particular solution), after the position stage */
  void (*psolve)(void *ws, const double *r, double *u);
  /* lambda (b) with A^T lambda = r (k), after the position stage */
  void (*reactions)(void *ws, const double *r, double *lambda);
  /* the model's evaluator scratch inside ws (the data's ev scratch on this path) */
  double *(*ev_scratch)(void *ws);
  /* guard build: 0 when the workspace's guard words are intact, else -1 with a message naming
   * the array and the stage; NULL: no guards */
  int (*guard_msg)(const void *ws, const char *stage, char *msg, size_t len);
} ap_ops;

/* The core's part of a structured data: the model, the operators' workspace, the factors of
 * the G blocks and vectors. */
typedef struct ap_st {
  const ap_model *m;
  const ap_ops *ops;
  void *ws;
  double *Gf;                 /* (gcap) Cholesky factors of the blocks of G */
  double *tk1, *tk2, *tb;     /* (k), (k), (b) */
  double *tl, *te;            /* (k), (k) */
  double *tm;                 /* (b) */
  int chosen;                 /* a partition was chosen (ap_st_partition) */
  double floor_geom;          /* max_r sum_c |A_rc| vscale_c at the last partition: the rows'
                                 floors of the consistency judge (core.h), 0 before */
} ap_st;

int ap_st_create(const ap_model *m, const ap_ops *ops, ap_st **out);
void ap_st_free(ap_st *st);

/* The pipeline, as ap_partition, ap_fwd_position ... (system.h) on the dense path. */
int ap_st_partition(const ap_model *m, ap_data *d, ap_st *st);
/* ap_core_judge_redundant on the tree path: rows redundant only on the manifold, at an
 * accepted state (after the position and velocity stages). */
int ap_st_judge_redundant(const ap_model *m, ap_data *d, ap_st *st);
int ap_st_position(const ap_model *m, ap_data *d, ap_st *st);
int ap_st_velocity(const ap_model *m, ap_data *d, ap_st *st);
int ap_st_acceleration(const ap_model *m, ap_data *d, ap_st *st);
/* A^T lambda = g v' + h - Q; redundant rows get zero multipliers (the dense path's least squares
 * spreads them: the forces on the bodies are the same). */
int ap_st_reactions(const ap_model *m, ap_data *d, ap_st *st);
/* v = B e' + b0 (partitioned basis). */
void ap_st_speeds(const ap_model *m, ap_data *d, ap_st *st);
/* v onto A v + a0 = 0, nearest in g, after the position stage; *change = g-norm of the step. */
int ap_st_project_here(const ap_model *m, ap_data *d, ap_st *st, double *v, double *change);
/* x <- B G^-1 B^T g x with the factors left by ap_st_project_here or the acceleration stage. */
void ap_st_project_tangent(const ap_model *m, ap_data *d, ap_st *st, double *x);
/* max |A v + a0| and 1/2 v^T g v at the position stage. */
double ap_st_residual(const ap_data *d, ap_st *st, const double *v);
double ap_st_energy(const ap_data *d, ap_st *st, const double *v);

#endif
