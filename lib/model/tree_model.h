/* Appell body layer (internal): the tree path of a body model (docs/large.md).
 *
 * A body model whose constraint rows each live on one body (knife edges, rolling on a
 * plane-contact joint, prescribed speeds; no loop closures, wheel contacts or user constraints)
 * can be evaluated by sweeps over its joint tree (lib/linalg/tree.h) without forming g, A or B.
 * The plan (compiled once with the model) holds the forest and a shadow body model: the same
 * bodies, joints, constraints and effects with no speeds, whose one Jacobian column (K1 = 1)
 * carries a whole twist. On the shadow the body layer's own code runs unchanged and in O(1)
 * per body: ap_kin_position gives positions, plane contacts and the rheonomic twists (the
 * column), ap_kin_velocity gives the bias accelerations once the column holds each body's full
 * twist, ap_con_gamma gives gamma, ap_bm_project_q puts q back on its manifold.
 *
 * Per-data workspace (ap_tree_ws, carved from ap_tree_ws_size doubles and ints): the shadow's
 * scratch, the geometry of ap_la_tree_geom, the rheonomic twists, the tree factorization and
 * temporaries. */
#ifndef AP_MODEL_TREE_MODEL_H
#define AP_MODEL_TREE_MODEL_H

#include "core/core.h"
#include "core/structured.h"
#include "linalg/tree.h"
#include "model/model.h"

typedef struct ap_tplan {
  ap_la_tree T;
  int *ints;                /* every int array below, one block */
  int *body;                /* (nb) body id of tree body i (the child of joint i) */
  int *rcon, *rrow;         /* (b, by position) constraint and its row */
  int *kspeed;              /* (k) global speed of each entry of the blocks' speed lists */
  int lmax;                 /* capacity of one tree's free speeds */
  int comp;                 /* component mode (every tree small: AP_TREE_COMP_K): the dense
                               path's partition on each tree's block (lib/linalg/tree_comp.c) */
  const ap_bmodel *M;       /* the model's own tables (free speeds, effects) */
  ap_bmodel shadow;         /* no speeds, one twist column */
  ap_mjoint *sjoints;       /* the shadow's joints: free speeds removed from the columns */
  ap_model sm;              /* an ap_model around the shadow (names, messages) */
  ap_ops ops;               /* the operators (ap_tree_ops), the model's m->ops */
  size_t nd, ni;            /* workspace: doubles, ints */
  /* implicit holonomic rows (wheel contacts' rows .z; tree_project.c), by tree: */
  int *hints;               /* every int array below, one block (NULL without such rows) */
  int nhol, hmax, hkmax;    /* rows; most rows of one tree; most speeds of a tree with rows */
  int *hofs, *hcon, *hrow;  /* (ntree+1), (nhol), (nhol): rows of tree t, constraint and row */
  int *hphi;                /* (nhol) each row's place in the constraint order of phi */
  int *tkofs, *kloc;        /* (ntree+1) tree t's speeds in kspeed; (k, by position) place in
                               its tree's list */
} ap_tplan;

typedef struct ap_tree_ws {
  const ap_tplan *P;
  double *S;                /* the shadow's scratch */
  ap_la_tree_geom g;
  double *rho;              /* (6 nb) rheonomic twist of each body (zero without drives) */
  double *U, *F;            /* (6 nb) temporaries */
  double *x;                /* (k) temporary */
  double *rb;               /* (b) temporary */
  double *qn;               /* (n) q kept while the rank is taken nearby (tree_eval.c) */
  int *avoid;               /* (k) speeds to keep independent (ap_tree_complete_speeds) */
  int *tkeep;               /* (ntree) component mode: each tree's rank at the partition, kept
                               in projected mode when some rows are redundant only on the
                               manifold (d->redundant_manifold) */
  double *hp;               /* projection of the holonomic rows (ap_tree_hol_ws_size) */
  int *hip;
  ap_la_tree_work W;
  ap_la_comp_work CW;       /* component mode */
} ap_tree_ws;

/* Component mode when every tree has at most this many speeds (a vehicle, a disk; a chain of
 * trailers takes the body-local elimination, whose cost stays linear in its length). */
#define AP_TREE_COMP_K 32

/* The plan of a compiled body model, or AP_ERR_UNSUPPORTED with the reason in why (the
 * element that keeps the model on the dense path). */
int ap_tree_plan_create(const ap_model *m, ap_tplan **out, char *why, size_t why_len);
void ap_tree_plan_free(ap_tplan *P);
/* Carve a workspace from nd doubles and ni ints (P->nd, P->ni); zeroes them. */
void ap_tree_ws_init(const ap_tplan *P, double *dbl, int *ints, ap_tree_ws *ws);
/* Guard build: the workspace's guard words (after each array of its two blocks) intact: 0, else
 * -1 with a message naming the array and the stage (core/arena.h). */
int ap_tree_ws_guard_msg(const ap_tree_ws *ws, const char *stage, char *msg, size_t len);

/* Stages (tree_eval.c). Position: kinematics, rows, a0, the factorization (select = 1: choose
 * the partition: d->perm, rank, l, redundant), b0 and the basis blocks. Velocity: h, Q, gamma
 * at d->v, then w. d->msg names the body or constraint on failure. */
int ap_tree_position(const ap_model *m, ap_data *d, ap_tree_ws *ws, int select);
int ap_tree_velocity(const ap_model *m, ap_data *d, ap_tree_ws *ws);
/* ap_body_complete_speeds on the tree path: the speeds not given from the given ones (d->q
 * set by the caller); the partition in d is replaced. */
int ap_tree_complete_speeds(const ap_model *m, ap_data *d, ap_tree_ws *ws, const int *given,
                            double *v);
/* u = B e + w, A w + rhs = 0 (e, rhs may be NULL), in the plan's mode; the dropped rows'
 * residual. */
double ap_tree_solve(ap_tree_ws *ws, const double *e, const double *rhs, double *u);
/* y = g x;  r = A x (+ a0 when with_a0);  qdot = N v. */
void ap_tree_gmul(ap_tree_ws *ws, const double *x, double *y);
void ap_tree_amul(ap_tree_ws *ws, const ap_data *d, const double *x, int with_a0, double *r,
                  double *mag);
void ap_tree_nmul(const ap_tplan *P, const double *q, const double *v, double *qdot);
/* The geometry of the position stage from the shadow's kinematics (after ap_kin_position on
 * the shadow); each body's full twist J v + rho into the shadow's column (after the geometry),
 * ready for ap_kin_velocity on the shadow. */
void ap_tree_geometry(const ap_tplan *P, ap_tree_ws *ws);
void ap_tree_twists_to_shadow(const ap_tplan *P, ap_tree_ws *ws, const double *v);

/* Body queries (tree_query.c). ap_body_eval on the tree path: positions, velocities, biases.
 * The Jacobian of the world point x of a body (3 x k each, the body's ancestors' columns).
 * com acceleration at v': call with body -1 once per v' (the twists J v' into U, 6 nb doubles
 * the caller owns: ap_tree_twist_len), then per body with the same U. Reads ws only, so
 * threads may query one data at once (ap_body_contact_force takes a const data). */
int ap_tree_body_eval(const ap_model *m, ap_data *d, ap_tree_ws *ws);
void ap_tree_point_jacobian(const ap_tree_ws *ws, int body, const double *x, double *Jw,
                            double *Jv);
void ap_tree_com_accel(const ap_tree_ws *ws, const double *vdot, int body, double *U,
                       double *a);
static inline size_t ap_tree_twist_len(const ap_tree_ws *ws) { return 6 * (size_t)ws->P->T.nb; }

/* Implicit holonomic rows on the tree path (tree_project.c). hol_plan: their lists by tree
 * (after the forest; AP_ERR_NOMEM); hol_ws_size: the projection's doubles and ints.
 * close_rows: the Gauss-Newton projection of phi = 0 (evaluate.c's close_loops for the
 * shadow), minimum-norm tree by tree, q += N dv on the model's joints; the shadow's scratch
 * (ws->S) holds the kinematics at q on return. hol_residual: max |phi| at q. */
int ap_tree_hol_plan(ap_tplan *P);
size_t ap_tree_hol_ws_size(const ap_tplan *P, size_t *nint);
int ap_tree_close_rows(const void *plan, ap_data *d, double *q, double *change);
int ap_tree_hol_residual(const ap_tplan *P, ap_data *d, const double *q, double *phi_max);
/* Component mode: the dense path's minimum-norm completion of the speeds not given, tree by
 * tree on the blocks A_t of the last position stage (at d->q). */
int ap_tree_complete_min_norm(const ap_model *m, ap_data *d, ap_tree_ws *ws, const int *given,
                              double *v);

/* The compile-time choice of the path (system.h, ap_path): on AP_PATH_TREE, or AP_PATH_AUTO
 * with at least AP_TREE_AUTO_K speeds and a model the plan takes, the plan is attached to m
 * (m->ops; project_q and check_q run on the shadow). AP_PATH_TREE on a model the plan cannot
 * take: AP_ERR_UNSUPPORTED with the reason in why. */
int ap_tree_attach(ap_model *m, ap_path path, char *why, size_t why_len);
/* The body layout of the data's evaluator scratch: the shadow's on the tree path. */
static inline const ap_bmodel *ap_tree_layout(const ap_model *m) {
  return m->ops ? &((const ap_tplan *)m->ops_impl)->shadow : ap_bm(m);
}
static inline const ap_tplan *ap_tree_plan(const ap_model *m) {
  return (const ap_tplan *)m->ops_impl;
}

/* The tree workspace of a data made for a model on the tree path. */
static inline ap_tree_ws *ap_tree_ws_of(const ap_data *d) {
  return (ap_tree_ws *)ap_core_st(d)->ws;
}

/* The operators of the core's structured pipeline for this plan. */
void ap_tree_ops(const ap_tplan *P, ap_ops *ops);

#endif
