/* Component mode of the tree path (tree.h, docs/large.md "Fleets"): for a forest of small
 * trees (vehicles, disks) each tree's constraint block A_t (b_t x k_t) is formed from its rows
 * and the dense path's own routines run on it: the partition by pivoted QR
 * (ap_la_pivot_select), the basis and b0 (ap_la_partition_basis), w (ap_la_partition_particular)
 * and the reactions (ap_la_lstsq_At). A is block diagonal over the trees, and pivoted QR of a
 * block-diagonal matrix picks, block by block, the columns that pivoted QR of each block
 * picks: the partition is the dense path's (up to the rank tolerance, taken relative to each
 * block's largest pivot), and with it the coordinates e' the integrator sees. The body-local
 * elimination of tree.c picks a wheel's own rate at the wheel and the chassis' x' or y' for
 * the sideways row; the dense choice keeps the wheel rates independent, which the motors
 * drive smoothly (a motor-driven robot: 1434 steps against 3560 at rtol 1e-8).
 * Cost: O(b_t k_t min(b_t, k_t)) per tree, O(N) for N trees of bounded size.
 *
 * Row s of A_t: its covector on its body's twist carried to the root (ap_la_tree_row_coeffs)
 * plus its direct term. Local speed order: the tree's bodies in order, each body's columns
 * (the order of W->kidx and of the blocks' rows). G_t from the twists of B_t's columns. */
#include <math.h>
#include <string.h>

#include "appell/status.h"
#include "linalg/linalg.h"
#include "linalg/tree.h"

#define COMP_INTS(X) X(perm, k) X(kloc, k) X(rank, nt) X(rofs, nt + 1) X(rpos, b) X(aofs, nt + 1) \
  X(iwork, iw)
#define COMP_DOUBLES(X) X(A, ab) X(F, ab) X(tau, k) X(x, km + bm) X(y, km + bm) X(work, wk)
#define COMP_SIZES                                                                          \
  size_t k = (size_t)T->k, b = (size_t)T->b, nt = (size_t)T->ntree, km = 0, bm = 0, ab = 0; \
  comp_sizes(T, &km, &bm, &ab);                                                             \
  size_t wk = ap_la_work_size((int)bm, (int)km) + 64, iw = ap_la_iwork_size((int)bm, (int)km) + 8
#define CW_SUM(f_, c_) +(c_)

/* Most speeds and rows of one tree; sum of b_t k_t. */
static void comp_sizes(const ap_la_tree *T, size_t *km, size_t *bm, size_t *ab) {
  for (int t = 0; t < T->ntree; t++) {
    size_t kt = 0, bt = 0;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
      int i = T->tbody[a];
      kt += (size_t)(T->fofs[i + 1] - T->fofs[i]), bt += (size_t)(T->rofs[i + 1] - T->rofs[i]);
    }
    *km = kt > *km ? kt : *km, *bm = bt > *bm ? bt : *bm, *ab += kt * bt;
  }
  *km = *km ? *km : 1, *bm = *bm ? *bm : 1;
}

size_t ap_la_comp_work_size(const ap_la_tree *T, size_t *nint) {
  COMP_SIZES;
  *nint = 0 COMP_INTS(CW_SUM);
  return 0 COMP_DOUBLES(CW_SUM);
}

int ap_la_comp_work_arrays(const ap_la_tree *T, ap_la_comp_work *C, ap_la_work_array *out) {
  COMP_SIZES;
  int n = 0;
#define CW_LIST_I(f_, c_) out[n++] = (ap_la_work_array){"ap_la_comp_work." #f_, (c_), NULL, &C->f_};
#define CW_LIST_D(f_, c_) out[n++] = (ap_la_work_array){"ap_la_comp_work." #f_, (c_), &C->f_, NULL};
  COMP_INTS(CW_LIST_I)
  COMP_DOUBLES(CW_LIST_D)
#undef CW_LIST_I
#undef CW_LIST_D
  return n;
}

void ap_la_comp_work_init(const ap_la_tree *T, double *dbl, int *ints, ap_la_comp_work *C) {
  ap_la_work_array a[AP_LA_WORK_ARRAYS_MAX];
  memset(C, 0, sizeof *C);
  ap_la_work_carve(a, ap_la_comp_work_arrays(T, C, a), dbl, ints);
  ap_la_comp_work_setup(T, C);
}

void ap_la_comp_work_setup(const ap_la_tree *T, ap_la_comp_work *C) {
  size_t ao = 0;
  for (int t = 0, r = 0; t < T->ntree; t++) {   /* rows and speeds of each tree, local order */
    int kt = 0;
    C->rofs[t] = r, C->aofs[t] = (int)ao;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
      int i = T->tbody[a];
      for (int f = T->fofs[i]; f < T->fofs[i + 1]; f++) C->kloc[f] = kt++;
      for (int q = T->rofs[i]; q < T->rofs[i + 1]; q++) C->rpos[r++] = q;
    }
    ao += (size_t)kt * (size_t)(r - C->rofs[t]);
    C->rofs[t + 1] = r;
  }
  C->aofs[T->ntree] = (int)ao;
}

/* Sizes of tree t: speeds (from the tree work's kofs), rows. */
static void tsize(const ap_la_tree_work *W, const ap_la_comp_work *C, int t, int *kt, int *bt) {
  *kt = W->kofs[t + 1] - W->kofs[t], *bt = C->rofs[t + 1] - C->rofs[t];
}

/* A_t from the rows' covectors (g->C) and direct terms. */
static void form_rows(const ap_la_tree *T, const ap_la_tree_geom *g, const ap_la_tree_work *W,
                      ap_la_comp_work *C, int t) {
  int kt, bt;
  tsize(W, C, t, &kt, &bt);
  double *At = C->A + C->aofs[t], c[6];
  memset(At, 0, sizeof(double) * (size_t)kt * bt);
  for (int j = 0; j < bt; j++) {
    int q = C->rpos[C->rofs[t] + j], i = -1;
    for (int a = T->tofs[t]; a < T->tofs[t + 1] && i < 0; a++)   /* the row's body */
      if (q >= T->rofs[T->tbody[a]] && q < T->rofs[T->tbody[a] + 1]) i = T->tbody[a];
    memcpy(c, g->C + 6 * (size_t)q, sizeof c);
    ap_la_tree_row_coeffs(T, g, i, c, C->kloc, C->y);
    for (int a = i; a >= 0; a = T->parent[a])
      for (int f = T->fofs[a]; f < T->fofs[a + 1]; f++)
        At[j + (size_t)C->kloc[f] * bt] = C->y[C->kloc[f]];
    if (T->rdir[q] >= 0) At[j + (size_t)C->kloc[T->fofs[i] + T->rdir[q]] * bt] += 1.0;
  }
}

/* After a selection: e' indices (ascending in the global speed index), the blocks' columns
 * (lidx) and offsets. The columns of B_t are perm_t[r_t..] (local ascending). */
static int assign(const ap_la_tree *T, ap_la_tree_work *W, ap_la_comp_work *C) {
  int k = T->k, nt = T->ntree, l = 0;
  W->rank_total = 0;
  for (int p = 0; p < k; p++) W->eidx[p] = 0;
  for (int t = 0; t < nt; t++) {
    W->rank_total += C->rank[t];
    for (int a = 0; a < C->rank[t]; a++) W->eidx[W->kidx[W->kofs[t] + C->perm[W->kofs[t] + a]]] = -2;
  }
  for (int sp = 0; sp < k; sp++) {
    int p = W->kpos[sp];
    W->eidx[p] = W->eidx[p] == -2 ? -1 : l++;
  }
  W->l = l;
  size_t go = 0, bo = 0;
  for (int t = 0, lo = 0; t < nt; t++) {
    int kt = W->kofs[t + 1] - W->kofs[t], lt = kt - C->rank[t];
    if (lt > W->lmax) return AP_ERR_UNSUPPORTED;
    W->lofs[t] = lo, W->gofs[t] = (int)go, W->bofs[t] = (int)bo;
    for (int j = 0; j < lt; j++) {
      int p = W->kidx[W->kofs[t] + C->perm[W->kofs[t] + C->rank[t] + j]];
      W->ecol[p] = j, W->lidx[lo + j] = W->eidx[p];
    }
    lo += lt, go += (size_t)lt * lt, bo += (size_t)kt * lt;
    W->lofs[t + 1] = lo;
  }
  W->gofs[nt] = (int)go, W->bofs[nt] = (int)bo;
  return AP_OK;
}

/* G_t from the twists of B_t's columns (one sweep down the tree per column). */
static void gram(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W, int t) {
  int lt = W->lofs[t + 1] - W->lofs[t], kt = W->kofs[t + 1] - W->kofs[t];
  const double *Bt = W->B + W->bofs[t];
  for (int jj = 0; jj < lt; jj++)
    for (int a = T->tofs[t], row = 0; a < T->tofs[t + 1]; a++) {
      int i = T->tbody[a], p = T->parent[i];
      const double *Up = p >= 0 ? W->Y + 6 * ((size_t)lt * W->tpos[p] + jj) : NULL;
      ap_la_tree_body_twist(T, g, i, Up, Bt + row + (size_t)jj * kt,
                            W->Y + 6 * ((size_t)lt * (a - T->tofs[t]) + jj));
      row += T->fofs[i + 1] - T->fofs[i];
    }
  ap_la_tree_gram(T, g, W, t);
}

int ap_la_comp_factor(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                      ap_la_comp_work *C, int select, const int *keep, double rtol,
                      const double *a0, double *b0, double *growth, double *resid, int *bad) {
  *growth = 0.0, *resid = 0.0, *bad = -1;
  C->rtol = rtol;
  for (int t = 0; t < T->ntree; t++) {
    form_rows(T, g, W, C, t);
    if (!select) continue;
    int kt, bt, *perm = C->perm + W->kofs[t];
    tsize(W, C, t, &kt, &bt);
    int rc = bt ? ap_la_pivot_select(bt, kt, C->A + C->aofs[t], rtol, perm, &C->rank[t],
                                     C->work, C->iwork) : AP_OK;
    if (!bt) {
      C->rank[t] = 0;
      for (int c = 0; c < kt; c++) perm[c] = c;
    }
    if (rc != AP_OK) return *bad = T->tbody[T->tofs[t]], rc;
    if (keep && C->rank[t] > keep[t]) C->rank[t] = keep[t];
  }
  if (select) {
    int rc = assign(T, W, C);
    if (rc != AP_OK) return rc;
  }
  for (int t = 0; t < T->ntree; t++) {   /* b0: every speed is in one tree's list */
    int kt, bt, r = C->rank[t];
    tsize(W, C, t, &kt, &bt);
    double gt = 0.0, rs = 0.0, *a0t = C->x, *b0t = C->y;
    for (int j = 0; j < bt; j++) a0t[j] = a0[T->ridx[C->rpos[C->rofs[t] + j]]];
    memset(b0t, 0, sizeof(double) * (size_t)kt);
    int rc = bt ? ap_la_partition_basis(bt, kt, r, C->perm + W->kofs[t], C->A + C->aofs[t], a0t,
                                        C->F + C->aofs[t], C->tau + W->kofs[t],
                                        W->B + W->bofs[t], b0t, &gt, NULL, &rs, C->work,
                                        C->iwork) : AP_OK;
    if (!bt)   /* no rows: B_t = I */
      for (int j = 0; j < kt; j++)
        for (int i = 0; i < kt; i++) W->B[W->bofs[t] + i + (size_t)j * kt] = i == j;
    if (rc != AP_OK) return *bad = T->tbody[T->tofs[t]], AP_ERR_SINGULAR;
    for (int c = 0; c < kt; c++) b0[T->fidx[W->kidx[W->kofs[t] + c]]] = b0t[c];
    *growth = fmax(*growth, gt), *resid = fmax(*resid, rs);
    gram(T, g, W, t);
  }
  return AP_OK;
}

void ap_la_comp_partition(const ap_la_tree *T, const ap_la_tree_work *W,
                          const ap_la_comp_work *C, int *perm, int *rank) {
  int d = 0, f = W->rank_total;
  for (int t = 0; t < T->ntree; t++)
    for (int a = 0; a < C->rank[t]; a++)
      perm[d++] = T->fidx[W->kidx[W->kofs[t] + C->perm[W->kofs[t] + a]]];
  for (int sp = 0; sp < T->k; sp++)
    if (W->eidx[W->kpos[sp]] >= 0) perm[f++] = sp;
  *rank = W->rank_total;
}

double ap_la_comp_solve(const ap_la_tree *T, const ap_la_tree_work *W, ap_la_comp_work *C,
                        const double *e, const double *rhs, double *u) {
  double resid = 0.0;
  for (int t = 0; t < T->ntree; t++) {
    int kt, bt, r = C->rank[t], lt = W->lofs[t + 1] - W->lofs[t];
    tsize(W, C, t, &kt, &bt);
    double *ut = C->y, *gt = C->x, rs = 0.0;
    memset(ut, 0, sizeof(double) * (size_t)kt);
    if (rhs && bt) {   /* A w = -rhs */
      for (int j = 0; j < bt; j++) gt[j] = -rhs[T->ridx[C->rpos[C->rofs[t] + j]]];
      ap_la_partition_particular(bt, kt, r, C->perm + W->kofs[t], C->F + C->aofs[t],
                                 C->tau + W->kofs[t], gt, ut, &rs, C->work);
      resid = fmax(resid, rs);
    }
    const double *Bt = W->B + W->bofs[t];
    for (int j = 0; j < lt && e; j++) {
      double ej = e[W->lidx[W->lofs[t] + j]];
      for (int c = 0; c < kt; c++) ut[c] += Bt[c + (size_t)j * kt] * ej;
    }
    for (int c = 0; c < kt; c++) u[T->fidx[W->kidx[W->kofs[t] + c]]] = ut[c];
  }
  return resid;
}

double ap_la_comp_reactions(const ap_la_tree *T, const ap_la_tree_work *W, ap_la_comp_work *C,
                            const double *r, double *lambda) {
  double worst = 0.0;
  for (int t = 0; t < T->ntree; t++) {
    int kt, bt;
    tsize(W, C, t, &kt, &bt);
    if (!bt) continue;
    double *rt = C->x, *lt = C->y, rs = 0.0;
    for (int c = 0; c < kt; c++) rt[c] = r[T->fidx[W->kidx[W->kofs[t] + c]]];
    if (ap_la_lstsq_At(bt, kt, C->A + C->aofs[t], rt, C->rtol, lt, &rs, C->work, C->iwork) !=
        AP_OK)
      memset(lt, 0, sizeof(double) * (size_t)bt);
    for (int j = 0; j < bt; j++) lambda[T->ridx[C->rpos[C->rofs[t] + j]]] = lt[j];
    worst = fmax(worst, rs);
  }
  return worst;
}
