/* lib/linalg's tree work area (linalg/tree.h): its arrays from one table each of ints and
 * doubles, X(field, count) in block order, from which the sizes (ap_la_tree_work_size), the
 * list a caller lays out with guard words between the arrays (ap_la_tree_work_arrays, the
 * tree path's workspace in lib/model/tree_build.c) and the carving without gaps
 * (ap_la_tree_work_init) all come; then the static maps (ap_la_tree_work_setup). Nothing
 * here allocates. */
#include <string.h>

#include "linalg/tree.h"

/* The work's ints and doubles, one table each X(field, count) in block order: the sizes, the
 * list of arrays and the carving all come from it. G holds
 * sum_t l_t^2 <= l lmax, B sum_t k_t l_t <= k lmax; loc is the per-body local scratch. */
#define TREE_WORK_INTS(X)                                                                  \
  X(perm, k) X(eidx, k) X(ecol, k) X(kpos, k) X(pbody, k) X(kidx, k) X(lidx, k) X(rank, nb) \
  X(nrow, nb) X(slot, nb) X(tpos, nb) X(pin, nb) X(lofs, nt + 1) X(kofs, nt + 1)            \
  X(gofs, nt + 1) X(bofs, nt + 1)
#define TREE_WORK_DOUBLES(X)                                                               \
  X(F, cap * nf) X(CX, 6 * cap) X(tau, k) X(T, cap * (nf + 6)) X(rq, cap) X(rs, cap)        \
  X(U, 6 * nb) X(G, k * lc) X(B, k * lc) X(Y, 6 * nb * lc)                                  \
  X(loc, mr * (2 * nf + 8) + nf * lc + 6 * lc + 64)
#define TREE_WORK_SIZES                                                                    \
  size_t nb = (size_t)T->nb, k = (size_t)T->k, cap = (size_t)T->cap, nf = (size_t)T->maxnf, \
         nt = (size_t)T->ntree, lc = (size_t)(lmax > 0 ? lmax : 1), mr = (size_t)T->maxrow
#define TW_SUM(f_, c_) +(c_)

size_t ap_la_tree_work_size(const ap_la_tree *T, int lmax, size_t *nint) {
  TREE_WORK_SIZES;
  if (nint) *nint = 0 TREE_WORK_INTS(TW_SUM);
  return 0 TREE_WORK_DOUBLES(TW_SUM);
}

int ap_la_tree_work_arrays(const ap_la_tree *T, int lmax, ap_la_tree_work *W,
                           ap_la_work_array *out) {
  TREE_WORK_SIZES;
  int n = 0;
#define TW_LIST_I(f_, c_) out[n++] = (ap_la_work_array){"ap_la_tree_work." #f_, (c_), NULL, &W->f_};
#define TW_LIST_D(f_, c_) out[n++] = (ap_la_work_array){"ap_la_tree_work." #f_, (c_), &W->f_, NULL};
  TREE_WORK_INTS(TW_LIST_I)
  TREE_WORK_DOUBLES(TW_LIST_D)
#undef TW_LIST_I
#undef TW_LIST_D
  return n;
}

void ap_la_work_carve(const ap_la_work_array *a, int n, double *dbl, int *ints) {
  for (int j = 0; j < n; j++) {
    if (a[j].dptr) *a[j].dptr = dbl, dbl += a[j].count;
    else *a[j].iptr = ints, ints += a[j].count;
  }
}

void ap_la_tree_work_init(const ap_la_tree *T, int lmax, double *dbl, int *ints,
                          ap_la_tree_work *W) {
  ap_la_work_array a[AP_LA_WORK_ARRAYS_MAX];
  memset(W, 0, sizeof *W);
  ap_la_work_carve(a, ap_la_tree_work_arrays(T, lmax, W, a), dbl, ints);
  ap_la_tree_work_setup(T, lmax, W);
}

void ap_la_tree_work_setup(const ap_la_tree *T, int lmax, ap_la_tree_work *W) {
  W->lmax = lmax > 0 ? lmax : 1;
  /* static maps: the body of each column, the column of each speed, speeds by tree */
  for (int i = 0; i < T->nb; i++)
    for (int c = T->fofs[i]; c < T->fofs[i + 1]; c++) W->pbody[c] = i, W->kpos[T->fidx[c]] = c;
  for (int t = 0, p = 0; t < T->ntree; t++) {
    W->kofs[t] = p;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
      int i = T->tbody[a];
      W->tpos[i] = a - T->tofs[t];
      for (int c = T->fofs[i]; c < T->fofs[i + 1]; c++) W->kidx[p++] = c;
    }
  }
  W->kofs[T->ntree] = T->k;
  for (int c = 0; c < T->k; c++) W->perm[c] = c, W->eidx[c] = W->ecol[c] = -1;
}
