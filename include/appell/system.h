/* Appell: math-level systems, the model, the data, and the Appell solve.
 *
 * A math-level system is the founding paper's objects handed over as callbacks
 * (docs/design.md §1):
 *
 *     q' = N(q) v                          kinematics (N = I when v = q')
 *     g(q,t) v' + h(q,v,t) = Q(q,v,t)      unconstrained equations of motion, k speeds
 *     A(q,t) v + a0(q,t) = 0               b nonholonomic constraint rows
 *     A v' = gamma(q,v,t)                  the same, differentiated along the motion
 *
 * The compiled model (ap_model) is immutable and may be shared by many ap_data. The data struct
 * holds the state and every intermediate of the pipeline; the stage that writes each field is
 * named beside it. Matrices are column-major. Nothing here allocates after ap_data_create. */
#ifndef APPELL_SYSTEM_H
#define APPELL_SYSTEM_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Callbacks. Each returns 0 = ok, > 0 = recoverable (retry with a smaller step), < 0 = stop.
 * Output arrays are zeroed by the caller before the call, so a callback may write only the
 * non-zero entries. */
typedef int (*ap_metric_fn)(double t, const double *q, double *g, void *user);   /* g: k x k */
typedef int (*ap_metric_deriv_fn)(double t, const double *q, double *dg, void *user);
  /* dg: n blocks of k x k; block c holds dg/dq^c (only with N = I, so n == k) */
typedef int (*ap_bias_fn)(double t, const double *q, const double *v, double *h, void *user);
typedef int (*ap_force_fn)(double t, const double *q, const double *v, double *Q, void *user);
typedef int (*ap_constraint_fn)(double t, const double *q, double *A, double *a0, void *user);
  /* A: b x k, a0: b (leave zero when the constraints are homogeneous) */
typedef int (*ap_gamma_fn)(double t, const double *q, const double *v, double *gamma,
                           void *user);
  /* gamma = -(dA/dt v + da0/dt), the time derivatives taken along the motion at fixed v */
typedef int (*ap_kinematic_fn)(double t, const double *q, double *N, void *user); /* n x k */

/* How h is obtained when no bias callback is given. */
typedef enum ap_bias_source {
  AP_BIAS_CALLBACK = 0,     /* h from the bias callback (required) */
  AP_BIAS_CHRISTOFFEL = 1,  /* h_a = (d_c g_ab - 1/2 d_a g_bc) v^b v^c from metric_deriv */
  AP_BIAS_ZERO = 2          /* h = 0: the metric is constant and nothing else contributes */
} ap_bias_source;

/* The largest n, k and b a math-level system may have. Besides, every dense array of a model
 * on the dense path must have at most INT_MAX entries, the most a 32-bit LAPACK integer
 * indexes: k <= 46340 (k x k), n k and b (k + 1) <= INT_MAX, and n k^2 <= INT_MAX with
 * AP_BIAS_CHRISTOFFEL. A larger model is refused when it is compiled (AP_ERR_ARG, with the
 * array and the numbers in the message). */
#define AP_MAX_SIZE 65536

typedef struct ap_system_def {
  const char *name;            /* for messages; default "system" */
  int n;                       /* number of coordinates q (1 .. AP_MAX_SIZE) */
  int k;                       /* number of speeds v (1 .. AP_MAX_SIZE); n == k unless
                                  kinematic is given */
  int b;                       /* number of constraint rows (0 .. AP_MAX_SIZE) */
  ap_metric_fn metric;         /* required */
  ap_metric_deriv_fn metric_deriv; /* required for AP_BIAS_CHRISTOFFEL */
  ap_bias_fn bias;             /* required for AP_BIAS_CALLBACK */
  ap_bias_source bias_source;  /* default AP_BIAS_CALLBACK */
  ap_force_fn force;           /* generalized active forces Q; NULL means Q = 0 */
  ap_constraint_fn constraint; /* required when b > 0 */
  ap_gamma_fn gamma;           /* required when b > 0 */
  ap_kinematic_fn kinematic;   /* N(q); NULL means N = I (then n must equal k) */
  int rheonomic;               /* nonzero if g, A or a0 depend on t explicitly (informational) */
  const char *const *coord_names; /* optional, n names; default q0, q1, ... */
  const char *const *speed_names; /* optional, k names; default v0, v1, ... */
  const char *const *constraint_names; /* optional, b names; default row0, row1, ... */
  void *user;                  /* passed to every callback */
  int internal_check;       /* set by ap_system_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_system_def;

/* The definition with every default filled in (all callbacks NULL, sizes 0). */
AP_API ap_system_def ap_system_def_default(void);

typedef struct ap_model ap_model;

/* Validate a math-level system and compile it into a model. On failure *out is NULL and, if
 * msg is not NULL, a message of at most msg_len bytes names the offending field; AP_ERR_ARG
 * for a NULL def or out, sizes out of range or a missing callback. */
AP_API int ap_model_from_system(const ap_system_def *def, ap_model **out, char *msg,
                                size_t msg_len);
AP_API void ap_model_free(ap_model *m);   /* NULL: nothing */

/* Sizes of a compiled model; AP_ERR_ARG when m is NULL. */
/* How a model evaluates (docs/large.md). The dense path forms g, A and the basis B; the tree
 * path (body models whose constraint rows each live on one body: knife edges, rolling on a
 * plane-contact joint, prescribed speeds; no loop closures, wheel contacts or user
 * constraints) works by sweeps over the joint tree in O(bodies), and its data has no g, N, A,
 * B, G (those fields are NULL; the DAE mode and linearization need the dense path). AUTO, the
 * default, takes the tree path for such models with at least AP_TREE_AUTO_K speeds. */
typedef enum ap_path { AP_PATH_AUTO = 0, AP_PATH_DENSE = 1, AP_PATH_TREE = 2 } ap_path;
#define AP_TREE_AUTO_K 16

/* AP_PATH_DENSE or AP_PATH_TREE: the path the model was compiled for; AP_ERR_ARG for NULL. */
AP_API int ap_model_path(const ap_model *m);

AP_API int ap_model_n(const ap_model *m);
AP_API int ap_model_k(const ap_model *m);
AP_API int ap_model_b(const ap_model *m);
/* Names (owned by the model); "?" when m is NULL or the index is out of range. */
AP_API const char *ap_model_name(const ap_model *m);
AP_API const char *ap_model_coord_name(const ap_model *m, int i);
AP_API const char *ap_model_speed_name(const ap_model *m, int i);
AP_API const char *ap_model_constraint_name(const ap_model *m, int s);

/* ------------------------------------------------------------------------------------------ */
/* The data: state, pipeline intermediates, counters.                                        */

typedef enum ap_basis {
  AP_BASIS_PARTITIONED = 0,   /* B = P [-R11^-1 R12; I]: smooth in q while the partition holds */
  AP_BASIS_ORTHONORMAL = 1,   /* Z from QR of A^T: orthonormal columns, best conditioned */
  AP_BASIS_NONE = 2           /* no basis: position and velocity stages give only g, N, A,
                                 a0, h, Q (the DAE residual needs nothing more) */
} ap_basis;

typedef struct ap_counters {
  long forward;        /* calls of ap_forward */
  long position;       /* position stages run */
  long velocity;       /* velocity stages run */
  long acceleration;   /* acceleration stages run */
  long reactions;      /* reaction solves */
  long qr;             /* QR factorizations of A (skipped when b == 0) */
  long partitions;     /* pivoted partition selections */
  long metric, bias, force, constraint, gamma, kinematic; /* callback calls (body models:
                          evaluations of the same objects by the body layer) */
  long rheonomic;      /* body models: position stages that evaluated time-dependent terms
                          (drives, moving ground, prescribed speeds); 0 when scleronomic */
  long energy;         /* energy evaluations (ap_body_energy: scene energy outputs) */
} ap_counters;

typedef struct ap_data {
  /* sizes (copied from the model) */
  int n, k, b;

  /* inputs */
  double t;            /* time */
  double *q;           /* (n) coordinates */
  double *v;           /* (k) speeds; input unless speeds_from_e, then written by velocity */
  double *e;           /* (k, first l used) kinematic parameters e' (partitioned basis) */
  ap_basis basis;      /* which null-space basis the position stage builds */
  int speeds_from_e;   /* partitioned basis: v = B e + b0 (1) or v given (0) */
  int want_reactions;  /* compute lambda in ap_forward */
  int estimate_cond;   /* estimate rcond_R and rcond_G (LAPACK condition estimators); the
                          drivers turn it on at output times only, not in the hot path */
  double rank_rtol;    /* relative tolerance for the numerical rank, dimensionless: a pivot
                          counts when |R_ii| > rank_rtol |R_00|; default 1e-10 */
  double manifold_rtol; /* relative tolerance on the consistency of redundant rows that are
                           redundant only where the implicit holonomic rows (loop closures,
                           wheel contacts) hold: judged by ap_partition and at accepted steps,
                           not at every evaluation (a stepper's trial states are off that
                           manifold); default 1e-8, the drivers set 100 (rtol + 1e-12) */

  /* partition (partitioned basis): set by ap_partition, frozen between calls */
  int *perm;           /* (k) perm[0..rank-1] dependent speeds, perm[rank..k-1] independent */
  int rank;            /* numerical rank of A; l = k - rank free speeds (may be 0: the
                          constraints then prescribe the motion) */
  int l;               /* number of free speeds */
  int redundant;       /* rows beyond the rank, b - rank: dropped */
  int redundant_manifold; /* of those, the rows redundant only on the holonomic manifold: the
                          rank is then kept (projected mode too) and their consistency is
                          judged against manifold_rtol; the others hold for every q and are
                          judged at every evaluation (relative 1e-8: round-off) */

  /* position stage: ap_fwd_position */
  double *g;           /* (k x k) metric */
  double *N;           /* (n x k) kinematic matrix; identity when the model has none */
  double *A;           /* (b x k) constraint matrix */
  double *a0;          /* (b) free term */
  double *B;           /* (k x l) null-space basis: A B = 0 */
  double *b0;          /* (k) particular speed: A b0 = -a0 */
  double growth;       /* partitioned: max |R11^-1 R12|; large means re-partition */
  double rcond_R;      /* reciprocal condition of R11 (1-norm); 1 unless estimate_cond */
  double resid_a0;     /* consistency residual of a0 on dropped (redundant) rows */

  /* velocity stage: ap_fwd_velocity */
  double *h;           /* (k) Coriolis, gyroscopic and rheonomic terms */
  double *Q;           /* (k) generalized active forces */
  double *gamma;       /* (b) A v' = gamma */
  double *w;           /* (k) particular acceleration: A w = gamma */
  double resid_gamma;  /* consistency residual of gamma on dropped rows */

  /* acceleration stage: ap_fwd_acceleration */
  double *G;           /* (l x l) B^T g B, overwritten by its Cholesky factor */
  double *Phi;         /* (l) B^T (Q - h - g w): the right-hand side of Appell's equations */
  double rcond_G;      /* reciprocal condition estimate of G (1-norm); 1 unless estimate_cond */
  double *edd;         /* (l) e'' */
  double *vdot;        /* (k) v' = B e'' + w */
  double *qdot;        /* (n) q' = N v */

  /* optional stage: ap_fwd_reactions */
  double *lambda;      /* (b) multipliers: A^T lambda = g v' + h - Q */

  ap_counters cnt;
  char msg[512];       /* last detailed message (error, or a note on dropped rows) */
  void *internal;      /* scratch arena and factorizations, owned by the data */
} ap_data;

/* Allocate a data struct for a model (all buffers, scratch sized once). A data struct belongs
 * to the model it was made for: every function below that takes (m, d) returns AP_ERR_ARG
 * when m or d is NULL or d was made for another model. */
AP_API int ap_data_create(const ap_model *m, ap_data **out);   /* AP_ERR_ARG: m or out NULL */
AP_API void ap_data_free(ap_data *d);                          /* NULL: nothing */

/* Pick the partition of the speeds by pivoted QR of A at (d->t, d->q): writes perm, rank, l,
 * redundant, redundant_manifold. Redundant rows that are consistent are dropped (and named in
 * d->msg); inconsistent ones give AP_ERR_INCONSISTENT with their names. A body model with loop
 * closures or wheel contacts tells apart, once, rows redundant for every q from rows redundant
 * only where those holonomic rows hold (the rank rises at a nearby state off them). */
AP_API int ap_partition(const ap_model *m, ap_data *d);

/* The pipeline stages, in the order ap_forward runs them. */
AP_API int ap_fwd_position(const ap_model *m, ap_data *d);
AP_API int ap_fwd_velocity(const ap_model *m, ap_data *d);
AP_API int ap_fwd_acceleration(const ap_model *m, ap_data *d);
AP_API int ap_fwd_reactions(const ap_model *m, ap_data *d);

/* The Appell solve, one entry point: from (t, q, v or e) to e'', v', q' (and lambda when
 * want_reactions). With the partitioned basis the partition in d must have been chosen by
 * ap_partition. Returns AP_OK, AP_RECOVERABLE, or a negative AP_ERR_* with d->msg set. */
AP_API int ap_forward(const ap_model *m, ap_data *d);

/* Project speeds onto the constraint set A v + a0 = 0, nearest in the metric g:
 * v <- b0 + B G^-1 B^T g (v - b0). Runs the position stage at (d->t, d->q). On return
 * *change (may be NULL) is the g-norm of the correction. AP_ERR_ARG when v is NULL. */
AP_API int ap_project_speeds(const ap_model *m, ap_data *d, double *v, double *change);

/* A sticking plastic impact onto the constraints at (d->t, d->q) (a contact touching down, its
 * rows now active): the speeds after, v+ = v- - g^-1 A^T (A g^-1 A^T)^-1 (A v- + a0), the
 * nearest admissible speeds in the kinetic-energy metric (ap_project_speeds, with d's basis:
 * for AP_BASIS_PARTITIONED the partition chosen by ap_partition), and *loss (J, may be NULL)
 * the kinetic energy lost, 1/2 (v+ - v-)^T g (v+ - v-) (Carnot's theorem). v_plus may be
 * v_minus. AP_ERR_ARG for a NULL m, d, v_minus or v_plus. */
AP_API int ap_impact(const ap_model *m, ap_data *d, const double *v_minus, double *v_plus,
                     double *loss);

/* Largest |A v + a0| at the data's position stage for the speeds v; NaN when d or v is NULL. */
AP_API double ap_constraint_residual(const ap_data *d, const double *v);

/* Kinetic energy 1/2 v^T g v at the data's position stage; NaN when d or v is NULL. */
AP_API double ap_kinetic_energy(const ap_data *d, const double *v);

#ifdef __cplusplus
}
#endif
#endif
