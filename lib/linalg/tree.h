/* Appell linear algebra over a forest of rigid bodies (internal): the null-space basis, the
 * reduced metric G = B^T g B and the products with g, A and J^T, by sweeps over the tree, in
 * O(bodies), never forming g, A or B densely (docs/large.md).
 *
 * Raw arrays only: the caller (the body layer) describes the forest once (ap_la_tree: parents,
 * free speeds, constraint rows, components) and writes the position-dependent geometry
 * (ap_la_tree_geom) at every position stage. Nothing here allocates; the workspace is sized by
 * ap_la_tree_work_size and carved by ap_la_tree_work_init, or laid out by the caller from
 * ap_la_tree_work_arrays.
 *
 * Conventions. Bodies are numbered parents first (parent[i] < i, -1 = the ground). A twist is
 * (w; v): angular velocity and the velocity of the body origin o_i, world axes; a wrench or a
 * covector is (t; f) with V . F = t . w + f . v. With d_i = o_i - o_p the twists obey
 *
 *     U_i = X_i U_p + S_i u_i,    X_i (w; v) = (w; v + w x d_i)
 *
 * (u_i the body's free speeds, S_i their 6 x nf_i columns at o_i); a wrench moves to the
 * parent as X_i^T (t; f) = (t + d_i x f; f). Constraint row s lives on one body:
 * c_s . U_i + u_i[dir_s] + a0_s = 0 (dir_s = -1: no direct term; a prescribed speed has
 * c_s = 0). The rheonomic twists belong in a0, so every sweep here is linear in the speeds. */
#ifndef AP_LINALG_TREE_H
#define AP_LINALG_TREE_H

#include <stddef.h>

/* The forest, fixed when the model is compiled. */
typedef struct ap_la_tree {
  int nb, k, b;             /* bodies, speeds, constraint rows */
  const int *parent;        /* (nb) parent body, -1 for the ground */
  const int *fofs, *fidx;   /* (nb+1), (k): free speeds of body i are fidx[fofs[i] .. fofs[i+1]-1]
                               (global indices); every speed belongs to exactly one body */
  const int *rofs, *ridx;   /* (nb+1), (b): rows of body i are ridx[rofs[i] .. rofs[i+1]-1] */
  const int *rdir;          /* (b, by position p in ridx) local column of a direct term, or -1 */
  const int *cofs, *cidx;   /* (nb+1), (nb): children of body i, ascending */
  int ntree;                /* trees of the forest: the independent components */
  const int *tofs, *tbody;  /* (ntree+1), (nb): bodies of tree t, parents first */
  const int *tree;          /* (nb) tree of each body */
  int maxnf;                /* most free speeds of one body */
  int cap;                  /* row slots: rows summed over the bodies they pass (own + pushed) */
  int maxrow;               /* most rows at one body (own + pushed from its children) */
} ap_la_tree;

/* Position-dependent geometry, written by the caller before ap_la_tree_factor. */
typedef struct ap_la_tree_geom {
  double *d;                /* (3 nb) o_i - o_p(i) (unused for roots) */
  double *S;                /* (6 k, by position in fidx) motion columns (w; v) at o_i */
  double *M;                /* (13 nb) mass, R com (3), inertia about the com, world (9) */
  double *C;                /* (6 b, by position in ridx) row covectors on the body's twist */
} ap_la_tree_geom;

/* Factorization, partition and basis blocks; carved from one block of doubles and one of
 * ints. Row slots: the rows at body i (its own, then those pushed from each child in cidx
 * order) are slots slot[i] .. slot[i] + nrow[i] - 1. */
typedef struct ap_la_tree_work {
  int *perm;                /* (k, by position in fidx) local column order of body i: its
                               rank[i] dependent columns first */
  int *rank;                /* (nb) local rank */
  int *nrow, *slot;         /* (nb) rows at body i and its first slot */
  int *eidx;                /* (k, by position) e' index of an independent column, -1 if dependent */
  int *ecol;                /* (k, by position) its column in its tree's block B_t, or -1 */
  int *kpos, *pbody;        /* (k) position of each speed; body of each position */
  int *tpos;                /* (nb) place of each body in its tree's list */
  int *pin;                 /* (nb) first row, among its parent's rows, of those it pushed */
  int *lofs, *lidx;         /* (ntree+1), (k): e' indices of tree t, ascending */
  int *kofs, *kidx;         /* (ntree+1), (k): positions (in fidx) of the speeds of tree t */
  int *gofs, *bofs;         /* (ntree+1): offsets of G_t (l_t x l_t) and B_t (k_t x l_t) */
  int l, rank_total;        /* free speeds; sum of the local ranks */
  double *F;                /* (cap x maxnf, slot-major) Q^T D: Householder vectors below R11 */
  double *CX;               /* (cap x 6) rotated covectors, moved to the parent's twist */
  double *tau;              /* (k, by position) Householder scalars of body i's columns */
  double *T;                /* (cap x (maxnf + 6)): R11^-1 [R12, C1 X_i] in the first rank[i]
                               slots of body i */
  double *rq;               /* (cap) rotated right-hand sides of the last affine solve */
  double *rs;               /* (cap) size of the rows each slot came from (rank decisions) */
  double *U;                /* (6 nb) twists of the last sweep down */
  double *G;                /* (sum_t l_t^2) blocks G_t, column-major */
  double *B;                /* (sum_t k_t l_t) blocks B_t: rows kidx order, columns lidx order */
  double *Y;                /* (6 nb lmax) twists J_i B_t of the bodies of one tree (scratch) */
  double *loc;              /* (maxrow (2 maxnf + 8) + maxnf lmax + 6 lmax + 64) local scratch */
  int lmax;                 /* capacity of one tree's free speeds in Y */
} ap_la_tree_work;

/* Doubles and ints of workspace (lmax: most free speeds of one tree, at most maxnf * bodies). */
size_t ap_la_tree_work_size(const ap_la_tree *T, int lmax, size_t *nint);
/* Carve W from dbl and ints (one array after the other, no gaps) and set it up. */
void ap_la_tree_work_init(const ap_la_tree *T, int lmax, double *dbl, int *ints,
                          ap_la_tree_work *W);

/* The layout of a workspace (ap_la_tree_work, ap_la_comp_work) for a caller that carves it
 * itself, e.g. from a layout table with guard words between the arrays (lib/model/tree_build.c,
 * core/arena.h): each array's name ("ap_la_tree_work.F"), its element count and the field it
 * is carved into (dptr for doubles, iptr for ints; the other NULL), ints first, then doubles,
 * in block order. The caller points every field at its count of zeroed elements, then calls the
 * setup function (the static maps). */
typedef struct ap_la_work_array {
  const char *name;
  size_t count;
  double **dptr;
  int **iptr;
} ap_la_work_array;
#define AP_LA_WORK_ARRAYS_MAX 32   /* arrays of one workspace, at most */
int ap_la_tree_work_arrays(const ap_la_tree *T, int lmax, ap_la_tree_work *W,
                           ap_la_work_array *out);
void ap_la_tree_work_setup(const ap_la_tree *T, int lmax, ap_la_tree_work *W);
/* Point the n arrays' fields one after the other into dbl and ints (no gaps). */
void ap_la_work_carve(const ap_la_work_array *a, int n, double *dbl, int *ints);

/* Factor every body's rows, bottom-up. select = 1: choose the local partitions (pivoted QR,
 * rank by |R_jj| > rtol * scale of the body's rows) and the blocks of e'; avoid (k, by
 * position; may be NULL) flags speeds to keep independent where the rows allow it; select = 0:
 * keep the partition (unpivoted QR of the chosen columns; avoid unused). growth =
 * max |R11^-1 R12| over the bodies.
 * Returns AP_OK; AP_ERR_SINGULAR (*bad = body) when a chosen pivot is tiny against its column
 * (frozen partition); AP_ERR_RANK (*bad = body) when rows pushed to the parent still depend on
 * the body's speeds (the partition no longer holds; select again); AP_ERR_UNSUPPORTED
 * (*bad = body) when the rows pushed up exceed the slots (cap) or a body's rows maxrow. */
int ap_la_tree_factor(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                      int select, const int *avoid, double rtol, double *growth, int *bad);

/* The partition as the dense path states it: perm[0..rank-1] dependent speeds (bodies in
 * order), perm[rank..k-1] independent ones ascending (the order of e'). */
void ap_la_tree_partition(const ap_la_tree *T, const ap_la_tree_work *W, int *perm, int *rank);

/* u = B e + particular: the speeds whose independent entries are e (l, may be NULL: zero) and
 * that satisfy the rows with free terms rhs (b, may be NULL: homogeneous), i.e. A u + rhs = 0.
 * With rhs = a0 this is v = B e' + b0; with rhs = -gamma and e = NULL it is w. Twists of the
 * sweep in W->U. Returns the largest |residual| of the rows pushed to the ground (the
 * redundant rows' consistency; 0 when none). */
double ap_la_tree_solve(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                        const double *e, const double *rhs, double *u);

/* The basis blocks B_t (columns of B over the tree's speeds) and G_t = B_t^T g B_t. */
void ap_la_tree_basis(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W);

/* G_t = sum_i Y_i^T M_i Y_i of tree t from the twists of its basis columns in W->Y (6 lt per
 * body, by place in the tree). U = X_i Up + S_i u (u: body i's nf speeds, local order; Up NULL:
 * a root). Row coefficients: c (6, overwritten) a covector on body i's twist; y[map[f]] =
 * S_f . (X^T ... c) for every free column f (by position) of i and its ancestors: the row's
 * entries of A (or of a gradient) on those speeds, O(depth). */
void ap_la_tree_gram(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W, int t);
void ap_la_tree_body_twist(const ap_la_tree *T, const ap_la_tree_geom *g, int i,
                           const double *Up, const double *u, double *U);
void ap_la_tree_row_coeffs(const ap_la_tree *T, const ap_la_tree_geom *g, int i, double *c,
                           const int *map, double *y);

/* ---- component mode (tree_comp.c): the dense path's routines on each tree's block A_t ---- */

typedef struct ap_la_comp_work {
  int *perm;                /* (k, by tree: kofs) local pivot order of tree t: rank[t] dependent
                               columns first, then the independent ones ascending */
  int *kloc;                /* (k, by position) local column of each free column in its tree */
  int *rank;                /* (ntree) rank of A_t */
  int *rofs, *rpos;         /* (ntree+1), (b): rows of tree t (positions in ridx), local order */
  int *aofs;                /* (ntree+1) offsets of A_t and F_t (b_t x k_t) */
  int *iwork;
  double *A, *F, *tau;      /* A_t and its QR (ap_la_partition_basis), tau (k, by tree) */
  double *x, *y, *work;     /* scratch */
  double rtol;              /* rank tolerance of the last factorization (reactions) */
} ap_la_comp_work;

size_t ap_la_comp_work_size(const ap_la_tree *T, size_t *nint);
void ap_la_comp_work_init(const ap_la_tree *T, double *dbl, int *ints, ap_la_comp_work *C);
int ap_la_comp_work_arrays(const ap_la_tree *T, ap_la_comp_work *C, ap_la_work_array *out);
void ap_la_comp_work_setup(const ap_la_tree *T, ap_la_comp_work *C);
/* As ap_la_tree_factor with b0 = the particular v of a0 (A b0 + a0 = 0) and resid = how far
 * the dropped rows are from consistent; the blocks B_t, G_t in W as ap_la_tree_basis leaves
 * them (W->lmax must hold every tree's speeds). AP_ERR_SINGULAR (*bad = the tree's root):
 * R11 of the frozen partition singular to working precision (re-partition). keep (ntree, may
 * be NULL), on a selection: each tree's rank at most keep[t] (rows redundant only on the
 * holonomic manifold look independent off it; the pivots are taken in pivoted QR's order). */
int ap_la_comp_factor(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                      ap_la_comp_work *C, int select, const int *keep, double rtol,
                      const double *a0, double *b0, double *growth, double *resid, int *bad);
void ap_la_comp_partition(const ap_la_tree *T, const ap_la_tree_work *W,
                          const ap_la_comp_work *C, int *perm, int *rank);
/* u = B e + w with A w + rhs = 0 (rhs, e may be NULL), as ap_la_tree_solve; returns the
 * dropped rows' residual. */
double ap_la_comp_solve(const ap_la_tree *T, const ap_la_tree_work *W, ap_la_comp_work *C,
                        const double *e, const double *rhs, double *u);
/* lambda with A^T lambda = r by least squares on each A_t (the dense path's method); returns
 * the largest residual. */
double ap_la_comp_reactions(const ap_la_tree *T, const ap_la_tree_work *W, ap_la_comp_work *C,
                            const double *r, double *lambda);

/* U (6 nb) = J x: the twists of the speeds x (k). */
void ap_la_tree_twists(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                       double *U);
/* y (k) += J^T F: F (6 nb) the wrenches at the body origins; F is overwritten (accumulated
 * towards the roots). */
void ap_la_tree_force(const ap_la_tree *T, const ap_la_tree_geom *g, double *F, double *y);
/* y = g x (U, F: 6 nb scratch each). */
void ap_la_tree_gmul(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x, double *y,
                     double *U, double *F);
/* r (b) = A x + a0 for the speeds x with twists U = J x (a0 may be NULL); mag (b, may be
 * NULL): a bound of the sum of the magnitudes of each row's terms, the scale of its rounding
 * error: |c| . Ua + |direct speed| + |a0|, with Ua from ap_la_tree_twists_abs (or |U| when Ua
 * is NULL). */
void ap_la_tree_rows(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                     const double *U, const double *a0, double *r, const double *Ua,
                     double *mag);
/* Ua (6 nb) >= |J x| entry by entry: the twists' sweep on magnitudes (each body's terms
 * |S_c x_c| and its parent's transported bound). */
void ap_la_tree_twists_abs(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                           double *Ua);
/* Multipliers lambda (b) with A^T lambda = r (k), r in the range of A^T (as g v' + h - Q at
 * the solution of Appell's equations): the rows that reached the ground (redundant) get zero.
 * Fw: 6 nb scratch. Returns the largest residual of the equations of the independent speeds
 * (round-off when r is in the range). Uses the last factorization; overwrites rq. */
double ap_la_tree_reactions(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                            const double *r, double *lambda, double *Fw);
/* F = M_i U: the wrench at o_i of the momentum of a body (M13: mass, com offset, inertia). */
void ap_la_tree_inertia(const double *M13, const double *U, double *F);

#endif
