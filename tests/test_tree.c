/* Tests of lib/linalg/tree.c: the sweeps over a forest of rigid bodies against the dense
 * matrices they stand for (docs/large.md).
 *
 * Random forests (fixed seed): a few trees, bodies with 0 to 6 free speeds, random motion
 * columns, offsets, inertias, and rows on one body each (some bodies carry more rows than they
 * have speeds, so rows are pushed to the parent; duplicated rows become redundant and reach
 * the ground). Speed and row numbers are shuffled so that no mapping is an identity. From the
 * same numbers the test forms, with plain loops, each body's twist Jacobian J_i (6 x k), the
 * dense A (b x k) and g = sum J_i^T M_i J_i, and checks every product and solve of the tree
 * against them: A B = 0 with B = [unit rows on the independent speeds], u = B e + b0 solves
 * A u + a0 = 0, G_t = B_t^T g B_t, g x, J^T F, A x + a0, the rank against LAPACK's pivoted QR,
 * the partition kept at a nearby geometry, the consistency residual of redundant rows, and the
 * frozen partition's refusals (AP_ERR_SINGULAR, AP_ERR_RANK). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "appell/status.h"
#include "check.h"
#include "linalg/linalg.h"
#include "linalg/tree.h"

#define TOL 1e-11

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double urand(void) {   /* uniform in [-1, 1) */
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 2685821657736338717ull) >> 11) * 0x1.0p-52 - 1.0;
}
static int irand(int n) { return (int)((urand() + 1.0) * 0.5 * n) % n; }

typedef struct forest {
  ap_la_tree T;
  ap_la_tree_geom g;
  int parent[64], fofs[65], fidx[400], rofs[65], ridx[400], rdir[400], cofs[65], cidx[64];
  int tofs[65], tbody[64], tree[64];
  double d[3 * 64], S[6 * 400], M[13 * 64], C[6 * 400];
  double *J, *A, *gm;   /* dense: (6 nb x k) twist Jacobians, (b x k), (k x k) */
} forest;

static void shuffle(int n, int *p) {
  for (int i = 0; i < n; i++) p[i] = i;
  for (int i = n - 1; i > 0; i--) {
    int j = irand(i + 1), t = p[i];
    p[i] = p[j], p[j] = t;
  }
}

/* Inertia: random mass, com offset, SPD inertia about the com. */
static void rand_inertia(double *M13) {
  double L[9];
  M13[0] = 1.0 + urand() * 0.5;
  for (int r = 0; r < 3; r++) M13[1 + r] = 0.5 * urand();
  for (int i = 0; i < 9; i++) L[i] = urand();
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) {
      double s = r == c ? 0.5 : 0.0;
      for (int q = 0; q < 3; q++) s += L[r + 3 * q] * L[c + 3 * q];
      M13[4 + r + 3 * c] = s;
    }
}

/* A forest of nb bodies; dup: the last body duplicates one of its rows (a redundant row). */
static void build(forest *F, int nb, int maxrows, int dup) {
  int sp = 0, rw = 0, perm_k[400], perm_b[400];
  memset(F, 0, offsetof(forest, J));
  for (int i = 0; i < nb; i++) F->parent[i] = i == 0 || urand() < -0.6 ? -1 : irand(i);
  for (int i = 0; i < nb; i++) {   /* free speeds and own rows */
    int nf = irand(7), nr = irand(maxrows + 1);
    if (i == nb - 1 && dup && nr == 0) nr = 1;
    F->fofs[i] = sp, sp += nf;
    F->rofs[i] = rw, rw += nr + (i == nb - 1 && dup);
  }
  F->fofs[nb] = sp, F->rofs[nb] = rw;
  if (sp == 0) F->fofs[nb] = sp = 1;   /* at least one speed: on the last body */
  shuffle(sp, perm_k), shuffle(rw, perm_b);
  for (int c = 0; c < sp; c++) F->fidx[c] = perm_k[c];
  for (int p = 0; p < rw; p++) {
    int i = 0;
    while (F->rofs[i + 1] <= p) i++;
    int nf = F->fofs[i + 1] - F->fofs[i];
    F->ridx[p] = perm_b[p];
    F->rdir[p] = nf > 0 && urand() > 0.7 ? irand(nf) : -1;
    for (int q = 0; q < 6; q++) F->C[6 * p + q] = F->rdir[p] >= 0 ? 0.0 : urand();
  }
  if (dup) {   /* the last row of the last body repeats its first, times 2 */
    int p0 = F->rofs[nb - 1], p1 = F->rofs[nb] - 1;
    F->rdir[p0] = -1;
    for (int q = 0; q < 6; q++) F->C[6 * p0 + q] = urand();
    for (int q = 0; q < 6; q++) F->C[6 * p1 + q] = 2.0 * F->C[6 * p0 + q];
    F->rdir[p1] = F->rdir[p0];
  }
  for (int c = 0; c < 6 * sp; c++) F->S[c] = urand();
  for (int i = 0; i < 3 * nb; i++) F->d[i] = urand();
  for (int i = 0; i < nb; i++) rand_inertia(F->M + 13 * i);
  /* children, trees */
  int nc = 0, nt = 0, root[64];
  for (int i = 0; i < nb; i++) {
    F->cofs[i] = nc;
    for (int j = i + 1; j < nb; j++)
      if (F->parent[j] == i) F->cidx[nc++] = j;
  }
  F->cofs[nb] = nc;
  for (int i = 0; i < nb; i++) {
    F->tree[i] = F->parent[i] < 0 ? nt++ : F->tree[F->parent[i]];
    if (F->parent[i] < 0) root[F->tree[i]] = i;
  }
  (void)root;
  for (int t = 0, a = 0; t < nt; t++) {
    F->tofs[t] = a;
    for (int i = 0; i < nb; i++)
      if (F->tree[i] == t) F->tbody[a++] = i;
  }
  F->tofs[nt] = nb;
  int maxnf = 0;
  for (int i = 0; i < nb; i++) maxnf = F->fofs[i + 1] - F->fofs[i] > maxnf ? F->fofs[i + 1] - F->fofs[i] : maxnf;
  ap_la_tree T = {nb, sp, rw, F->parent, F->fofs, F->fidx, F->rofs, F->ridx, F->rdir, F->cofs,
                  F->cidx, nt, F->tofs, F->tbody, F->tree, maxnf, rw * (nb + 1) + 1, rw + 1};
  F->T = T;
  ap_la_tree_geom g = {F->d, F->S, F->M, F->C};
  F->g = g;
}

/* Dense J (6 nb x k, ld 6 nb), A (b x k), g (k x k) from the forest's numbers. */
static void dense(forest *F) {
  int nb = F->T.nb, k = F->T.k, b = F->T.b, ld = 6 * nb;
  free(F->J), free(F->A), free(F->gm);
  F->J = calloc((size_t)ld * k, sizeof(double));
  F->A = calloc((size_t)(b ? b : 1) * k, sizeof(double));
  F->gm = calloc((size_t)k * k, sizeof(double));
  for (int i = 0; i < nb; i++) {
    int p = F->parent[i];
    for (int c = 0; c < k && p >= 0; c++) {   /* X_i J_p: (w; v + w x d) */
      const double *Jp = F->J + 6 * p + (size_t)c * ld, *d = F->d + 3 * i;
      double *Ji = F->J + 6 * i + (size_t)c * ld;
      for (int q = 0; q < 6; q++) Ji[q] = Jp[q];
      Ji[3] += Jp[1] * d[2] - Jp[2] * d[1], Ji[4] += Jp[2] * d[0] - Jp[0] * d[2];
      Ji[5] += Jp[0] * d[1] - Jp[1] * d[0];
    }
    for (int c = F->fofs[i]; c < F->fofs[i + 1]; c++)
      for (int q = 0; q < 6; q++) F->J[6 * i + q + (size_t)F->fidx[c] * ld] += F->S[6 * c + q];
    for (int p2 = F->rofs[i]; p2 < F->rofs[i + 1]; p2++)
      for (int c = 0; c < k; c++) {
        double s = 0.0;
        for (int q = 0; q < 6; q++) s += F->C[6 * p2 + q] * F->J[6 * i + q + (size_t)c * ld];
        if (F->rdir[p2] >= 0 && F->fidx[F->fofs[i] + F->rdir[p2]] == c) s += 1.0;
        F->A[F->ridx[p2] + (size_t)c * b] = s;
      }
    /* M_i as a 6 x 6 matrix, built independently: m Jc^T Jc + diag(I, 0), Jc = [-[rc]x, I] */
    double Mm[36] = {0}, m = F->M[13 * i], *rc = F->M + 13 * i + 1, *I = F->M + 13 * i + 4;
    double Jc[18] = {0, -rc[2], rc[1], rc[2], 0, -rc[0], -rc[1], rc[0], 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int r = 0; r < 6; r++)
      for (int c = 0; c < 6; c++) {
        double s = r < 3 && c < 3 ? I[r + 3 * c] : 0.0;
        for (int q = 0; q < 3; q++) s += m * Jc[q + 3 * r] * Jc[q + 3 * c];
        Mm[r + 6 * c] = s;
      }
    for (int a = 0; a < k; a++)
      for (int c = 0; c < k; c++) {
        double s = 0.0;
        for (int r = 0; r < 6; r++)
          for (int q = 0; q < 6; q++)
            s += F->J[6 * i + r + (size_t)a * ld] * Mm[r + 6 * q] * F->J[6 * i + q + (size_t)c * ld];
        F->gm[a + (size_t)c * k] += s;
      }
  }
}

static double max_abs(int n, const double *x) {
  double m = 0.0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* Dense B (k x l) from the blocks. */
static void dense_B(const forest *F, const ap_la_tree_work *W, double *B) {
  int k = F->T.k;
  memset(B, 0, sizeof(double) * (size_t)k * (W->l ? W->l : 1));
  for (int t = 0; t < F->T.ntree; t++) {
    int kt = W->kofs[t + 1] - W->kofs[t];
    for (int jj = 0; jj < W->lofs[t + 1] - W->lofs[t]; jj++)
      for (int r = 0; r < kt; r++)
        B[F->fidx[W->kidx[W->kofs[t] + r]] + (size_t)W->lidx[W->lofs[t] + jj] * k] =
            W->B[W->bofs[t] + r + (size_t)jj * kt];
  }
}

typedef struct work {
  double *dbl;
  int *ints;
  ap_la_tree_work W;
} work;

static void work_make(const forest *F, work *w) {
  size_t ni = 0, nd = ap_la_tree_work_size(&F->T, F->T.k, &ni);
  w->dbl = malloc(nd * sizeof(double)), w->ints = malloc(ni * sizeof(int));
  for (size_t i = 0; i < nd; i++) w->dbl[i] = NAN;   /* read before written: poisoned */
  ap_la_tree_work_init(&F->T, F->T.k, w->dbl, w->ints, &w->W);
}

/* Every check on one forest. */
static void check_forest(forest *F, int verbose) {
  int k = F->T.k, b = F->T.b, nb = F->T.nb, bad = -1;
  work w;
  dense(F);
  work_make(F, &w);
  ap_la_tree_work *W = &w.W;
  double growth = 0.0;
  int rc = ap_la_tree_factor(&F->T, &F->g, W, 1, NULL, 1e-10, &growth, &bad);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return;
  /* rank against LAPACK's pivoted QR of the dense A */
  int *perm = malloc(sizeof(int) * (size_t)k), rank = 0, rl = 0, *lp = malloc(sizeof(int) * (size_t)k);
  ap_la_tree_partition(&F->T, W, perm, &rank);
  size_t lw = ap_la_work_size(b, k), liw = ap_la_iwork_size(b, k);
  double *lwork = malloc(lw * sizeof(double));
  int *liwork = malloc(liw * sizeof(int));
  if (b > 0) ap_la_pivot_select(b, k, F->A, 1e-10, lp, &rl, lwork, liwork);
  AP_CHECK_EQ_INT(rank, rl);
  AP_CHECK_EQ_INT(W->l, k - rank);
  int l = W->l;
  double *B = malloc(sizeof(double) * (size_t)k * (l ? l : 1)), *AB = malloc(sizeof(double) * (size_t)(b ? b : 1) * (l ? l : 1));
  double scaleA = fmax(1.0, max_abs(b * k, F->A));
  ap_la_tree_basis(&F->T, &F->g, W);
  dense_B(F, W, B);
  double err = 0.0;   /* A B = 0; unit rows on the independent speeds */
  for (int j = 0; j < l; j++) {
    for (int s = 0; s < b; s++) {
      double x = 0.0;
      for (int c = 0; c < k; c++) x += F->A[s + (size_t)c * b] * B[c + (size_t)j * k];
      err = fmax(err, fabs(x));
    }
    for (int i = 0; i < l; i++) AP_CHECK_NEAR(B[perm[rank + i] + (size_t)j * k], i == j, 0.0);
  }
  double scaleB = fmax(1.0, max_abs(k * l, B));
  AP_CHECK_LE(err, TOL * scaleA * scaleB);
  /* G_t = B_t^T g B_t, and B^T g B is zero between trees */
  double gerr = 0.0, gmax = 1.0;
  for (int t = 0; t < F->T.ntree; t++) {
    int lt = W->lofs[t + 1] - W->lofs[t];
    for (int a = 0; a < lt; a++)
      for (int c = 0; c < lt; c++) {
        int ea = W->lidx[W->lofs[t] + a], ec = W->lidx[W->lofs[t] + c];
        double s = 0.0;
        for (int p = 0; p < k; p++)
          for (int q = 0; q < k; q++)
            s += B[p + (size_t)ea * k] * F->gm[p + (size_t)q * k] * B[q + (size_t)ec * k];
        gmax = fmax(gmax, fabs(s));
        gerr = fmax(gerr, fabs(s - W->G[W->gofs[t] + a + (size_t)c * lt]));
      }
  }
  AP_CHECK_LE(gerr, TOL * scaleB * scaleB * fmax(1.0, max_abs(k * k, F->gm)) * k);
  /* consistent free terms: a0 = -A u* */
  double *us = malloc(sizeof(double) * (size_t)k * 8), *a0 = malloc(sizeof(double) * (size_t)(b + 1) * 2);
  double *u = us + k, *e = u + k, *x = e + k, *y = x + k, *y2 = y + k, *Ut = y2 + k;
  double *U = malloc(sizeof(double) * 12 * (size_t)nb), *Fw = U + 6 * nb, *r = a0 + b + 1;
  for (int c = 0; c < k; c++) us[c] = urand(), e[c] = urand();
  for (int s = 0; s < b; s++) {
    a0[s] = 0.0;
    for (int c = 0; c < k; c++) a0[s] -= F->A[s + (size_t)c * b] * us[c];
  }
  double resid = ap_la_tree_solve(&F->T, &F->g, W, e, b ? a0 : NULL, u);
  err = 0.0;
  for (int s = 0; s < b; s++) {
    double z = a0[s];
    for (int c = 0; c < k; c++) z += F->A[s + (size_t)c * b] * u[c];
    err = fmax(err, fabs(z));
  }
  AP_CHECK_LE(err, TOL * scaleA * fmax(1.0, max_abs(k, u)));
  AP_CHECK_LE(resid, TOL * scaleA * 10);
  for (int j = 0; j < l; j++) AP_CHECK_NEAR(u[perm[rank + j]], e[j], 0.0);
  /* twists of the last sweep = J u */
  err = 0.0;
  for (int i = 0; i < 6 * nb; i++) {
    double z = 0.0;
    for (int c = 0; c < k; c++) z += F->J[i + (size_t)c * 6 * nb] * u[c];
    err = fmax(err, fabs(z - W->U[i]));
  }
  AP_CHECK_LE(err, TOL * fmax(1.0, max_abs(6 * nb, W->U)));
  /* g x, J^T F, A x + a0 */
  for (int c = 0; c < k; c++) x[c] = urand();
  ap_la_tree_gmul(&F->T, &F->g, x, y, U, Fw);
  err = 0.0;
  for (int a = 0; a < k; a++) {
    double z = 0.0;
    for (int c = 0; c < k; c++) z += F->gm[a + (size_t)c * k] * x[c];
    err = fmax(err, fabs(z - y[a]));
  }
  AP_CHECK_LE(err, TOL * fmax(1.0, max_abs(k * k, F->gm)) * k);
  for (int i = 0; i < 6 * nb; i++) Fw[i] = urand();
  double *F0 = malloc(sizeof(double) * 6 * (size_t)nb);
  memcpy(F0, Fw, sizeof(double) * 6 * (size_t)nb);
  memset(y2, 0, sizeof(double) * (size_t)k);
  ap_la_tree_force(&F->T, &F->g, Fw, y2);
  err = 0.0;
  for (int c = 0; c < k; c++) {
    double z = 0.0;
    for (int i = 0; i < 6 * nb; i++) z += F->J[i + (size_t)c * 6 * nb] * F0[i];
    err = fmax(err, fabs(z - y2[c]));
  }
  AP_CHECK_LE(err, TOL * fmax(1.0, max_abs(6 * nb * k, F->J)) * nb);
  ap_la_tree_twists(&F->T, &F->g, x, Ut == NULL ? U : U);
  ap_la_tree_rows(&F->T, &F->g, x, U, a0, r, NULL, NULL);
  err = 0.0;
  for (int s = 0; s < b; s++) {
    double z = a0[s];
    for (int c = 0; c < k; c++) z += F->A[s + (size_t)c * b] * x[c];
    err = fmax(err, fabs(z - r[s]));
  }
  AP_CHECK_LE(err, TOL * scaleA * 10);
  /* w: A w = gamma (rhs = -gamma), zero independent speeds */
  for (int s = 0; s < b; s++) r[s] = -(-a0[s]);   /* gamma = -a0 = A u*: consistent */
  for (int s = 0; s < b; s++) r[s] = a0[s];
  resid = ap_la_tree_solve(&F->T, &F->g, W, NULL, b ? r : NULL, u);
  for (int j = 0; j < l; j++) AP_CHECK_NEAR(u[perm[rank + j]], 0.0, 0.0);
  /* multipliers: A^T lambda = r for r = A^T lambda* */
  {
    double *ls = malloc(sizeof(double) * (size_t)(2 * b + 1)), *lam = ls + b, *rr = malloc(sizeof(double) * (size_t)(2 * k + 1));
    double *chk = rr + k;
    for (int s = 0; s < b; s++) ls[s] = urand();
    for (int c = 0; c < k; c++) {
      rr[c] = 0.0;
      for (int s = 0; s < b; s++) rr[c] += F->A[s + (size_t)c * b] * ls[s];
    }
    double rres = ap_la_tree_reactions(&F->T, &F->g, W, rr, lam, Fw);
    for (int c = 0; c < k; c++) {
      chk[c] = 0.0;
      for (int s = 0; s < b; s++) chk[c] += F->A[s + (size_t)c * b] * lam[s];
    }
    double sr = fmax(1.0, max_abs(k, rr)) * scaleA * fmax(1.0, max_abs(b, lam));
    AP_CHECK_LE(max_abs(k, rr) > 0 ? fabs(rres) : 0.0, TOL * sr * 10);
    err = 0.0;
    for (int c = 0; c < k; c++) err = fmax(err, fabs(chk[c] - rr[c]));
    AP_CHECK_LE(err, TOL * sr * 10);
    free(ls), free(rr);
  }
  /* inconsistent free terms on redundant rows show in the residual */
  if (b > rank) {
    for (int s = 0; s < b; s++) r[s] = urand();
    resid = ap_la_tree_solve(&F->T, &F->g, W, NULL, r, u);
    AP_CHECK(resid > 1e-6);
  }
  /* the partition holds at a nearby geometry, frozen */
  for (int c = 0; c < 6 * k; c++) F->S[c] += 1e-4 * urand();
  for (int i = 0; i < 3 * nb; i++) F->d[i] += 1e-4 * urand();
  for (int p = 0; p < b; p++)
    for (int q = 0; q < 6; q++)
      if (F->rdir[p] < 0) F->C[6 * p + q] += 1e-4 * urand();
  if (b > rank) {   /* keep the duplicated row exactly redundant */
    int p0 = F->rofs[nb - 1], p1 = F->rofs[nb] - 1;
    for (int q = 0; q < 6; q++) F->C[6 * p1 + q] = 2.0 * F->C[6 * p0 + q];
  }
  dense(F);
  rc = ap_la_tree_factor(&F->T, &F->g, W, 0, NULL, 1e-10, &growth, &bad);
  if (b == rank || rc == AP_OK) {
    AP_CHECK_EQ_INT(rc, AP_OK);
    ap_la_tree_basis(&F->T, &F->g, W);
    dense_B(F, W, B);
    err = 0.0;
    for (int j = 0; j < l; j++)
      for (int s = 0; s < b; s++) {
        double z = 0.0;
        for (int c = 0; c < k; c++) z += F->A[s + (size_t)c * b] * B[c + (size_t)j * k];
        err = fmax(err, fabs(z));
      }
    AP_CHECK_LE(err, TOL * scaleA * fmax(1.0, max_abs(k * l, B)));
  }
  if (verbose) printf("forest: %d bodies, %d trees, k %d, b %d, rank %d, growth %.3g\n", nb, F->T.ntree, k, b, rank, growth);
  free(perm), free(lp), free(lwork), free(liwork), free(B), free(AB), free(us), free(a0), free(U), free(F0);
  free(w.dbl), free(w.ints);
}

/* The frozen partition refuses a chosen column that vanished and a pushed row that came to
 * depend on the body's speeds. A chain of two bodies: body 0 (3 speeds), body 1 (1 speed),
 * one row on body 1. */
static void check_refusals(void) {
  forest F;
  memset(&F, 0, offsetof(forest, J));
  F.parent[0] = -1, F.parent[1] = 0;
  F.fofs[0] = 0, F.fofs[1] = 3, F.fofs[2] = 4;
  for (int c = 0; c < 4; c++) F.fidx[c] = c;
  F.rofs[0] = 0, F.rofs[1] = 0, F.rofs[2] = 1;
  F.ridx[0] = 0, F.rdir[0] = -1;
  F.cofs[0] = 0, F.cofs[1] = 1, F.cofs[2] = 1, F.cidx[0] = 1;
  F.tofs[0] = 0, F.tofs[1] = 2, F.tbody[0] = 0, F.tbody[1] = 1;
  for (int c = 0; c < 24; c++) F.S[c] = urand();
  for (int i = 0; i < 6; i++) F.d[i] = urand();
  for (int i = 0; i < 2; i++) rand_inertia(F.M + 13 * i);
  for (int q = 0; q < 6; q++) F.C[q] = urand();
  ap_la_tree T = {2, 4, 1, F.parent, F.fofs, F.fidx, F.rofs, F.ridx, F.rdir, F.cofs, F.cidx,
                  1, F.tofs, F.tbody, F.tree, 3, 8, 4};
  F.T = T;
  ap_la_tree_geom g = {F.d, F.S, F.M, F.C};
  F.g = g;
  work w;
  work_make(&F, &w);
  double growth;
  int bad = -1;
  AP_CHECK_EQ_INT(ap_la_tree_factor(&F.T, &F.g, &w.W, 1, NULL, 1e-10, &growth, &bad), AP_OK);
  AP_CHECK_EQ_INT(w.W.rank[1], 1);   /* resolved by body 1's own speed */
  double keep[6];
  memcpy(keep, F.S + 18, sizeof keep);
  for (int q = 0; q < 6; q++) F.S[18 + q] = 0.0;   /* body 1's column: its row cannot use it */
  AP_CHECK_EQ_INT(ap_la_tree_factor(&F.T, &F.g, &w.W, 0, NULL, 1e-10, &growth, &bad), AP_ERR_SINGULAR);
  AP_CHECK_EQ_INT(bad, 1);
  /* chosen again: the row moves to body 0 */
  AP_CHECK_EQ_INT(ap_la_tree_factor(&F.T, &F.g, &w.W, 1, NULL, 1e-10, &growth, &bad), AP_OK);
  AP_CHECK_EQ_INT(w.W.rank[1], 0);
  AP_CHECK_EQ_INT(w.W.rank[0], 1);
  memcpy(F.S + 18, keep, sizeof keep);   /* back: the pushed row depends on body 1's speed */
  AP_CHECK_EQ_INT(ap_la_tree_factor(&F.T, &F.g, &w.W, 0, NULL, 1e-10, &growth, &bad), AP_ERR_RANK);
  AP_CHECK_EQ_INT(bad, 1);
  free(w.dbl), free(w.ints);
}

int main(void) {
  forest *F = calloc(1, sizeof *F);
  for (int rep = 0; rep < 300; rep++) {
    int nb = 1 + irand(12), maxrows = 1 + irand(3), dup = rep % 3 == 2;
    build(F, nb, maxrows, dup);
    check_forest(F, rep < 6);
  }
  build(F, 40, 2, 1);   /* a larger one */
  check_forest(F, 1);
  free(F->J), free(F->A), free(F->gm);
  free(F);
  check_refusals();
  return ap_check_finish("test_tree");
}
