/* Sweeps over a forest of rigid bodies: the partitioned null-space basis by local resolution,
 * the reduced metric G = B^T g B per tree, and the products with g, A and J^T (docs/large.md,
 * "The null-space basis in O(N)"; notation in tree.h).
 *
 * Factorization (bottom-up). At body i the rows are its own (covector c on U_i, direct term on
 * one of its speeds) and those pushed from its children (covectors already moved to U_i).
 * With D_i = C_i S_i + direct (n_i x nf_i), a Householder QR of the chosen (dependent) columns,
 * Q^T D_i P = [R11 R12; 0 R22], gives
 *     rows 0..r-1:   R11 u_dep + R12 u_ind + (Q^T C_i)_1 X_i U_p + (Q^T a)_1 = 0
 *     rows r..n-1:   (Q^T C_i)_2 X_i U_p + (Q^T a)_2 = 0   (R22 = 0: pushed to the parent)
 * Stored per body: the Householder vectors and R in F, T = R11^-1 [R12, (Q^T C_i)_1 X_i], and
 * every rotated covector moved to the parent (X_i^T c) in CX. Rows that leave a root are the
 * redundant rows: their rotated right-hand sides must vanish.
 * Sweeps down (parents first) then give u_dep = -(T [u_ind; U_p] + R11^-1 (Q^T a)_1) and the
 * twists U_i = X_i U_p + S_i u_i. Sizes per body are tiny (a handful of rows and speeds): plain
 * loops, no BLAS. Invariant: the partition (perm, rank, slots) changes only with select = 1. */
#include "linalg/tree.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "appell/status.h"

/* Row slots of F, CX and T: rows of the slot-major arrays. */
#define FROW(W, T_, s) ((W)->F + (size_t)(s) * (T_)->maxnf)
#define TROW(W, T_, s) ((W)->T + (size_t)(s) * ((T_)->maxnf + 6))

/* Frozen-partition check: rows pushed up must not depend on the body's speeds beyond this,
 * relative to the body's scale (round-off when the rank deficiency is structural). */
static const double pushed_rtol = 1e-8;

/* ---- small spatial helpers -------------------------------------------------------------- */

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross3(const double *a, const double *b, double *c) {
  double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
         z = a[0] * b[1] - a[1] * b[0];
  c[0] = x, c[1] = y, c[2] = z;
}
static double dot6(const double *a, const double *b) { return dot3(a, b) + dot3(a + 3, b + 3); }

/* U = X_i Up: (w; v + w x d). */
static void transport_twist(const double *d, const double *Up, double *U) {
  double t[3];
  cross3(Up, d, t);
  for (int r = 0; r < 3; r++) U[r] = Up[r], U[3 + r] = Up[3 + r] + t[r];
}

/* c <- X_i^T c: (t + d x f; f), for a covector or a wrench. */
static void transport_wrench(const double *d, double *c) {
  double t[3];
  cross3(d, c + 3, t);
  for (int r = 0; r < 3; r++) c[r] += t[r];
}

void ap_la_tree_inertia(const double *M13, const double *U, double *F) {
  double vc[3], t[3];
  const double m = M13[0], *rc = M13 + 1, *I = M13 + 4;
  cross3(U, rc, vc);                                   /* vc = v + w x rc */
  for (int r = 0; r < 3; r++) vc[r] += U[3 + r], F[3 + r] = m * vc[r];
  cross3(rc, F + 3, t);                                /* t = I w + rc x (m vc) */
  for (int r = 0; r < 3; r++)
    F[r] = I[r] * U[0] + I[r + 3] * U[1] + I[r + 6] * U[2] + t[r];
}

/* ---- Householder QR of a small column-major matrix --------------------------------------- */

/* Reflector for x (len n, stride 1): x <- [beta; v_2..], returns tau (H = I - tau v v^T,
 * v_1 = 1, H x = beta e_1). */
static double house(int n, double *x) {
  double s = 0.0;
  for (int i = 1; i < n; i++) s += x[i] * x[i];
  if (s == 0.0) return 0.0;
  double a = x[0], nrm = sqrt(a * a + s), beta = a <= 0 ? nrm : -nrm;
  double tau = (beta - a) / beta, sc = 1.0 / (a - beta);
  for (int i = 1; i < n; i++) x[i] *= sc;
  x[0] = beta;
  return tau;
}

/* Apply H = I - tau v v^T (v = [1; x[1..n-1]]) to the column y (len n). */
static void house_apply(int n, const double *v, double tau, double *y) {
  if (tau == 0.0) return;
  double s = y[0];
  for (int i = 1; i < n; i++) s += v[i] * y[i];
  s *= tau;
  y[0] -= s;
  for (int i = 1; i < n; i++) y[i] -= s * v[i];
}

/* Pivoted QR of D (n x nf, ld n) to choose the columns: perm gets the chosen column order,
 * the return value the rank (|R_jj| > tol). Columns flagged in avoid (may be NULL) are chosen
 * only when no other column is left above tol. D is destroyed. */
static int choose_columns(int n, int nf, double *D, double tol, int *perm, const int *avoid) {
  int r = 0;
  for (int c = 0; c < nf; c++) perm[c] = c;
  for (int j = 0; j < nf && j < n; j++) {
    int best = -1;
    double bn = -1.0;
    for (int pass = 0; pass < 2 && best < 0; pass++)
      for (int c = j; c < nf; c++) {   /* the largest remaining column below row j */
        if (avoid && (avoid[perm[c]] != 0) != pass) continue;
        double s = 0.0;
        for (int i = j; i < n; i++) s += D[i + (size_t)c * n] * D[i + (size_t)c * n];
        if (s > bn && sqrt(s) > tol) bn = s, best = c;
      }
    if (best < 0) break;
    if (best != j) {
      int ti = perm[j];
      perm[j] = perm[best], perm[best] = ti;
      for (int i = 0; i < n; i++) {
        double t = D[i + (size_t)j * n];
        D[i + (size_t)j * n] = D[i + (size_t)best * n], D[i + (size_t)best * n] = t;
      }
    }
    double tau = house(n - j, D + j + (size_t)j * n);
    for (int c = j + 1; c < nf; c++) house_apply(n - j, D + j + (size_t)j * n, tau,
                                                 D + j + (size_t)c * n);
    r++;
  }
  /* independent columns in ascending local order */
  for (int a = r; a < nf; a++)
    for (int b = a + 1; b < nf; b++)
      if (perm[b] < perm[a]) {
        int t = perm[a];
        perm[a] = perm[b], perm[b] = t;
      }
  return r;
}

/* ---- factorization ------------------------------------------------------------------------ */

/* Rows at body i into D (n x nf, ld n) and C (n x 6, ld n); returns n, or -1 when more than
 * maxrow. Columns of D in local order. scale: bound of |D| from the rows' and columns' sizes
 * (the rank decisions are relative to it); rscale: the rows' size. A row pushed up carries the
 * size of the rows it came from, not its own: a row that cancelled to round-off (a redundant
 * one) must not look independent against its own tiny norm. */
static int gather_rows(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                       int i, double *D, double *C, double *scale, double *rscale) {
  int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, n = T->rofs[i + 1] - T->rofs[i];
  for (int a = T->cofs[i]; a < T->cofs[i + 1]; a++) {
    int c = T->cidx[a];
    n += W->nrow[c] - W->rank[c];
  }
  if (n > T->maxrow) return -1;
  int j = 0;
  double cmax = 0.0, smax = 0.0;
  for (int p = T->rofs[i]; p < T->rofs[i + 1]; p++, j++) {
    const double *cp = g->C + 6 * (size_t)p;
    for (int q = 0; q < 6; q++) C[j + (size_t)q * n] = cp[q];
    for (int c = 0; c < nf; c++) D[j + (size_t)c * n] = T->rdir[p] == c ? 1.0 : 0.0;
    if (T->rdir[p] >= 0) cmax = fmax(cmax, 1.0), smax = fmax(smax, 1.0);
    cmax = fmax(cmax, sqrt(dot3(cp, cp)) + sqrt(dot3(cp + 3, cp + 3)));
  }
  for (int a = T->cofs[i]; a < T->cofs[i + 1]; a++) {   /* pushed rows keep their scale */
    int c = T->cidx[a];
    W->pin[c] = j;
    for (int s = W->slot[c] + W->rank[c]; s < W->slot[c] + W->nrow[c]; s++, j++) {
      for (int q = 0; q < 6; q++) C[j + (size_t)q * n] = W->CX[6 * (size_t)s + q];
      for (int col = 0; col < nf; col++) D[j + (size_t)col * n] = 0.0;
      cmax = fmax(cmax, W->rs[s]);
    }
  }
  *rscale = cmax;
  for (int c = 0; c < nf; c++) {
    const double *Sc = g->S + 6 * (size_t)(f0 + c);
    smax = fmax(smax, sqrt(dot3(Sc, Sc)) + sqrt(dot3(Sc + 3, Sc + 3)));
    for (j = 0; j < n; j++) {
      double s = 0.0;
      for (int q = 0; q < 6; q++) s += C[j + (size_t)q * n] * Sc[q];
      D[j + (size_t)c * n] += s;
    }
  }
  *scale = cmax * smax;
  return n;
}

/* Factor the rows at body i (module note). With select, the partition of the body is chosen
 * first and its slots allocated at *top. */
static int factor_body(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W, int i,
                       int select, const int *avoid, double rtol, double *growth, int *top) {
  int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, mr = T->maxrow, *perm = W->perm + f0;
  double *D = W->loc, *C = D + (size_t)mr * T->maxnf, *Dp = C + 6 * (size_t)mr, scale = 0.0;
  double rscale = 0.0;
  int n = gather_rows(T, g, W, i, D, C, &scale, &rscale);
  if (n < 0) return AP_ERR_UNSUPPORTED;
  if (select) {
    if (*top + n > T->cap) return AP_ERR_UNSUPPORTED;
    W->slot[i] = *top, W->nrow[i] = n, *top += n;
    memcpy(Dp, D, sizeof(double) * (size_t)n * nf);
    W->rank[i] = choose_columns(n, nf, Dp, rtol * scale, perm, avoid ? avoid + f0 : NULL);
  }
  int r = W->rank[i], s0 = W->slot[i];
  for (int c = 0; c < nf; c++) memcpy(Dp + (size_t)c * n, D + (size_t)perm[c] * n,
                                      sizeof(double) * (size_t)n);
  double colmax = 0.0;
  for (int c = 0; c < r; c++) {
    double s = 0.0;
    for (int j = 0; j < n; j++) s += Dp[j + (size_t)c * n] * Dp[j + (size_t)c * n];
    colmax = fmax(colmax, sqrt(s));
  }
  for (int j = 0; j < r; j++) {   /* QR of the dependent columns, applied to the rest and C */
    double *v = Dp + j + (size_t)j * n, tau = house(n - j, v);
    W->tau[f0 + j] = tau;
    for (int c = j + 1; c < nf; c++) house_apply(n - j, v, tau, Dp + j + (size_t)c * n);
    for (int q = 0; q < 6; q++) house_apply(n - j, v, tau, C + j + (size_t)q * n);
    if (!(fabs(v[0]) > 64 * DBL_EPSILON * colmax) || !isfinite(v[0])) return AP_ERR_SINGULAR;
  }
  for (int c = r; c < nf; c++)   /* pushed rows must not depend on the body's speeds */
    for (int j = r; j < n; j++)
      if (!(fabs(Dp[j + (size_t)c * n]) <= pushed_rtol * scale)) return AP_ERR_RANK;
  for (int j = 0; j < n; j++) {
    double *Fr = FROW(W, T, s0 + j), *cx = W->CX + 6 * (size_t)(s0 + j);
    for (int c = 0; c < nf; c++) Fr[c] = Dp[j + (size_t)c * n];
    for (int q = 0; q < 6; q++) cx[q] = C[j + (size_t)q * n];
    if (T->parent[i] >= 0) transport_wrench(g->d + 3 * (size_t)i, cx);
    W->rs[s0 + j] = rscale * (1.0 + (T->parent[i] >= 0 ? sqrt(dot3(g->d + 3 * (size_t)i,
                                                                      g->d + 3 * (size_t)i)) : 0.0));
  }
  /* T = R11^-1 [R12, C1 X_i] by back substitution, one column at a time */
  int nc = nf - r + 6;
  for (int c = 0; c < nc; c++) {
    for (int j = r - 1; j >= 0; j--) {
      double x = c < nf - r ? Dp[j + (size_t)(r + c) * n] : W->CX[6 * (size_t)(s0 + j) + c - (nf - r)];
      for (int p = j + 1; p < r; p++) x -= Dp[j + (size_t)p * n] * TROW(W, T, s0 + p)[c];
      x /= Dp[j + (size_t)j * n];
      TROW(W, T, s0 + j)[c] = x;
      if (c < nf - r) *growth = fmax(*growth, fabs(x));
    }
  }
  return AP_OK;
}

/* After a selection: the global rank, the e' index and block column of every independent
 * speed (e' ascending in the global speed index), and the blocks of each tree. */
static int assign_blocks(const ap_la_tree *T, ap_la_tree_work *W) {
  int k = T->k, nt = T->ntree, l = 0;
  W->rank_total = 0;
  for (int i = 0; i < T->nb; i++) {
    W->rank_total += W->rank[i];
    for (int a = 0; a < W->rank[i]; a++) W->eidx[T->fofs[i] + W->perm[T->fofs[i] + a]] = -2;
  }
  for (int sp = 0; sp < k; sp++) {
    int p = W->kpos[sp];
    W->eidx[p] = W->eidx[p] == -2 ? -1 : l++;
    W->ecol[p] = -1;
  }
  W->l = l;
  for (int t = 0; t <= nt; t++) W->lofs[t] = 0;
  for (int p = 0; p < k; p++)
    if (W->eidx[p] >= 0) W->lofs[T->tree[W->pbody[p]] + 1]++;
  for (int t = 0; t < nt; t++) W->lofs[t + 1] += W->lofs[t];
  for (int t = 0; t < nt; t++) W->gofs[t] = W->lofs[t];   /* fill pointers */
  for (int sp = 0; sp < k; sp++) {
    int p = W->kpos[sp], t = T->tree[W->pbody[p]];
    if (W->eidx[p] < 0) continue;
    W->ecol[p] = W->gofs[t] - W->lofs[t];
    W->lidx[W->gofs[t]++] = W->eidx[p];
  }
  size_t go = 0, bo = 0;
  for (int t = 0; t < nt; t++) {
    int lt = W->lofs[t + 1] - W->lofs[t], kt = W->kofs[t + 1] - W->kofs[t];
    if (lt > W->lmax) return AP_ERR_UNSUPPORTED;
    W->gofs[t] = (int)go, W->bofs[t] = (int)bo;
    go += (size_t)lt * lt, bo += (size_t)kt * lt;
  }
  W->gofs[nt] = (int)go, W->bofs[nt] = (int)bo;
  return AP_OK;
}

int ap_la_tree_factor(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                      int select, const int *avoid, double rtol, double *growth, int *bad) {
  int top = 0, rc = AP_OK;
  *growth = 0.0, *bad = -1;
  for (int i = T->nb - 1; i >= 0 && rc == AP_OK; i--) {
    rc = factor_body(T, g, W, i, select, avoid, rtol, growth, &top);
    if (rc != AP_OK) *bad = i;
  }
  if (rc == AP_OK && select) rc = assign_blocks(T, W);
  return rc;
}

void ap_la_tree_partition(const ap_la_tree *T, const ap_la_tree_work *W, int *perm, int *rank) {
  int d = 0, f = W->rank_total;
  for (int i = 0; i < T->nb; i++)
    for (int a = 0; a < W->rank[i]; a++) perm[d++] = T->fidx[T->fofs[i] + W->perm[T->fofs[i] + a]];
  for (int sp = 0; sp < T->k; sp++)
    if (W->eidx[W->kpos[sp]] >= 0) perm[f++] = sp;
  *rank = W->rank_total;
}

/* ---- sweeps ------------------------------------------------------------------------------- */

static const double ZERO6[6] = {0, 0, 0, 0, 0, 0};

/* Rotate the right-hand sides of body i's rows (own from rhs, pushed from the children's
 * rotated ones) by Q^T; the first rank of them become R11^-1 (Q^T a)_1. Returns the largest
 * rotated entry that leaves a root. */
static double rotate_rhs(const ap_la_tree *T, ap_la_tree_work *W, int i, const double *rhs) {
  int f0 = T->fofs[i], n = W->nrow[i], r = W->rank[i], s0 = W->slot[i], j = 0;
  double *z = W->rq + s0, resid = 0.0;
  for (int p = T->rofs[i]; p < T->rofs[i + 1]; p++) z[j++] = rhs[T->ridx[p]];
  for (int a = T->cofs[i]; a < T->cofs[i + 1]; a++) {
    int c = T->cidx[a];
    for (int s = W->slot[c] + W->rank[c]; s < W->slot[c] + W->nrow[c]; s++) z[j++] = W->rq[s];
  }
  for (int c = 0; c < r; c++) {   /* H_c = I - tau v v^T, v = [1; F[c+1.., c]] */
    double tau = W->tau[f0 + c], s = z[c];
    if (tau == 0.0) continue;
    for (int q = c + 1; q < n; q++) s += FROW(W, T, s0 + q)[c] * z[q];
    s *= tau;
    z[c] -= s;
    for (int q = c + 1; q < n; q++) z[q] -= s * FROW(W, T, s0 + q)[c];
  }
  if (T->parent[i] < 0)
    for (int q = r; q < n; q++) resid = fmax(resid, fabs(z[q]));
  for (int q = r - 1; q >= 0; q--) {   /* R11^-1 */
    double x = z[q];
    for (int p = q + 1; p < r; p++) x -= FROW(W, T, s0 + q)[p] * z[p];
    z[q] = x / FROW(W, T, s0 + q)[q];
  }
  return resid;
}

/* Speeds of body i (local order, ld 1) from its independent ones (already in u) and the
 * parent's twist Up: u_dep = -(T [u_ind; Up] + z). */
static void body_speeds(const ap_la_tree *T, const ap_la_tree_work *W, int i, const double *Up,
                        const double *z, double *u) {
  int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, r = W->rank[i], s0 = W->slot[i];
  const int *perm = W->perm + f0;
  for (int j = 0; j < r; j++) {
    const double *Tr = TROW(W, T, s0 + j);
    double x = z ? z[j] : 0.0;
    for (int b = 0; b < nf - r; b++) x += Tr[b] * u[perm[r + b]];
    for (int q = 0; q < 6; q++) x += Tr[nf - r + q] * Up[q];
    u[perm[j]] = -x;
  }
}

/* U_i = X_i Up + S_i u (u local, nf entries). */
static void body_twist(const ap_la_tree *T, const ap_la_tree_geom *g, int i, const double *Up,
                       const double *u, double *U) {
  double a[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};   /* the sums in registers, U written once */
  if (T->parent[i] >= 0) transport_twist(g->d + 3 * (size_t)i, Up, a);
  const double *Sc = g->S + 6 * (size_t)T->fofs[i];
  for (int c = 0, nf = T->fofs[i + 1] - T->fofs[i]; c < nf; c++, Sc += 6) {
    double uc = u[c];
    a[0] += Sc[0] * uc, a[1] += Sc[1] * uc, a[2] += Sc[2] * uc;
    a[3] += Sc[3] * uc, a[4] += Sc[4] * uc, a[5] += Sc[5] * uc;
  }
  for (int q = 0; q < 6; q++) U[q] = a[q];
}

double ap_la_tree_solve(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                        const double *e, const double *rhs, double *u) {
  double resid = 0.0, *ul = W->loc;
  for (int i = T->nb - 1; i >= 0 && rhs; i--) resid = fmax(resid, rotate_rhs(T, W, i, rhs));
  for (int i = 0; i < T->nb; i++) {
    int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, p = T->parent[i];
    const double *Up = p >= 0 ? W->U + 6 * (size_t)p : ZERO6;
    for (int c = 0; c < nf; c++) {
      int ei = W->eidx[f0 + c];
      ul[c] = ei >= 0 && e ? e[ei] : 0.0;
    }
    body_speeds(T, W, i, Up, rhs ? W->rq + W->slot[i] : NULL, ul);
    for (int c = 0; c < nf; c++) u[T->fidx[f0 + c]] = ul[c];
    body_twist(T, g, i, Up, ul, W->U + 6 * (size_t)i);
  }
  return resid;
}

/* The basis block of tree t: one homogeneous sweep per free speed, all at once. */
static void tree_basis(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W, int t) {
  int lt = W->lofs[t + 1] - W->lofs[t], kt = W->kofs[t + 1] - W->kofs[t], row = 0;
  double *Bt = W->B + W->bofs[t], *ul = W->loc;
  if (lt == 0) return;
  for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
    int i = T->tbody[a], f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, p = T->parent[i];
    double *Yi = W->Y + 6 * (size_t)lt * (a - T->tofs[t]);
    const double *Yp = p >= 0 ? W->Y + 6 * (size_t)lt * W->tpos[p] : NULL;
    for (int jj = 0; jj < lt; jj++) {
      const double *Up = Yp ? Yp + 6 * (size_t)jj : ZERO6;
      for (int c = 0; c < nf; c++) ul[c] = W->ecol[f0 + c] == jj ? 1.0 : 0.0;
      body_speeds(T, W, i, Up, NULL, ul);
      for (int c = 0; c < nf; c++) Bt[row + c + (size_t)jj * kt] = ul[c];
      body_twist(T, g, i, Up, ul, Yi + 6 * (size_t)jj);
    }
    row += nf;
  }
  ap_la_tree_gram(T, g, W, t);
}

void ap_la_tree_gram(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W, int t) {
  int lt = W->lofs[t + 1] - W->lofs[t];
  double *Gt = W->G + W->gofs[t], F[6];
  memset(Gt, 0, sizeof(double) * (size_t)lt * lt);
  for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++) {
    const double *Yi = W->Y + 6 * (size_t)lt * (a - T->tofs[t]), *Mi = g->M + 13 * (size_t)T->tbody[a];
    for (int jj = 0; jj < lt; jj++) {
      ap_la_tree_inertia(Mi, Yi + 6 * (size_t)jj, F);
      for (int ii = 0; ii <= jj; ii++) Gt[ii + (size_t)jj * lt] += dot6(Yi + 6 * (size_t)ii, F);
    }
  }
  for (int jj = 0; jj < lt; jj++)
    for (int ii = jj + 1; ii < lt; ii++) Gt[ii + (size_t)jj * lt] = Gt[jj + (size_t)ii * lt];
}

void ap_la_tree_body_twist(const ap_la_tree *T, const ap_la_tree_geom *g, int i,
                           const double *Up, const double *u, double *U) {
  body_twist(T, g, i, Up ? Up : ZERO6, u, U);
}

void ap_la_tree_row_coeffs(const ap_la_tree *T, const ap_la_tree_geom *g, int i, double *c,
                           const int *map, double *y) {
  for (int a = i; a >= 0; a = T->parent[a]) {
    for (int f = T->fofs[a]; f < T->fofs[a + 1]; f++) y[map[f]] = dot6(g->S + 6 * (size_t)f, c);
    if (T->parent[a] >= 0) transport_wrench(g->d + 3 * (size_t)a, c);
  }
}

void ap_la_tree_basis(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W) {
  for (int t = 0; t < T->ntree; t++) tree_basis(T, g, W, t);
}

void ap_la_tree_twists(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                       double *U) {
  double ul[6];   /* a joint has at most 6 speeds */
  for (int i = 0; i < T->nb; i++) {
    int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, p = T->parent[i];
    for (int c = 0; c < nf && c < 6; c++) ul[c] = x[T->fidx[f0 + c]];
    body_twist(T, g, i, p >= 0 ? U + 6 * (size_t)p : ZERO6, ul, U + 6 * (size_t)i);
  }
}

void ap_la_tree_twists_abs(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                           double *Ua) {
  for (int i = 0; i < T->nb; i++) {
    double *U = Ua + 6 * (size_t)i;
    int p = T->parent[i];
    memset(U, 0, 6 * sizeof *U);
    if (p >= 0) {   /* |w|, |v| + |w x d| bounded entry by entry */
      const double *Up = Ua + 6 * (size_t)p, *d = g->d + 3 * (size_t)i;
      for (int r = 0; r < 3; r++) {
        int a = (r + 1) % 3, b = (r + 2) % 3;
        U[r] = Up[r];
        U[3 + r] = Up[3 + r] + Up[a] * fabs(d[b]) + Up[b] * fabs(d[a]);
      }
    }
    for (int c = T->fofs[i]; c < T->fofs[i + 1]; c++) {
      const double *Sc = g->S + 6 * (size_t)c;
      for (int q = 0; q < 6; q++) U[q] += fabs(Sc[q] * x[T->fidx[c]]);
    }
  }
}

void ap_la_tree_force(const ap_la_tree *T, const ap_la_tree_geom *g, double *F, double *y) {
  for (int i = T->nb - 1; i >= 0; i--) {
    double *Fi = F + 6 * (size_t)i;
    for (int c = T->fofs[i]; c < T->fofs[i + 1]; c++) y[T->fidx[c]] += dot6(g->S + 6 * (size_t)c, Fi);
    int p = T->parent[i];
    if (p < 0) continue;
    transport_wrench(g->d + 3 * (size_t)i, Fi);
    for (int q = 0; q < 6; q++) F[6 * (size_t)p + q] += Fi[q];
  }
}

void ap_la_tree_gmul(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x, double *y,
                     double *U, double *F) {
  ap_la_tree_twists(T, g, x, U);
  for (int i = 0; i < T->nb; i++) ap_la_tree_inertia(g->M + 13 * (size_t)i, U + 6 * (size_t)i, F + 6 * (size_t)i);
  memset(y, 0, sizeof(double) * (size_t)T->k);
  ap_la_tree_force(T, g, F, y);
}

void ap_la_tree_rows(const ap_la_tree *T, const ap_la_tree_geom *g, const double *x,
                     const double *U, const double *a0, double *r, const double *Ua,
                     double *mag) {
  for (int i = 0; i < T->nb; i++)
    for (int p = T->rofs[i]; p < T->rofs[i + 1]; p++) {
      const double *c = g->C + 6 * (size_t)p, *u = U + 6 * (size_t)i;
      double s = dot6(c, u), xd = T->rdir[p] >= 0 ? x[T->fidx[T->fofs[i] + T->rdir[p]]] : 0.0;
      double a = a0 ? a0[T->ridx[p]] : 0.0;
      r[T->ridx[p]] = s + xd + a;
      if (!mag) continue;
      double m = fabs(xd) + fabs(a);
      const double *ua = Ua ? Ua + 6 * (size_t)i : u;
      for (int j = 0; j < 6; j++) m += fabs(c[j]) * fabs(ua[j]);
      mag[T->ridx[p]] = m;
    }
}

/* ---- multipliers ---------------------------------------------------------------------------- */

/* Sweep up: with the wrench Fi of the rows already settled below body i (at o_i), its speeds
 * need D_i^T mu = r_i - S_i^T Fi from the multipliers mu of its rows (own and pushed up from its
 * children); rotated, R11^T nu1 = (r_i - S_i^T Fi)_dep and R12^T nu1 = (...)_ind (consistency),
 * while nu2, the multipliers of the rows pushed on, are settled above. The parent receives
 * X_i^T Fi + (C1 X_i)^T nu1. Sweep down: nu2 from the parent's multipliers of those rows (zero at
 * the ground: the redundant rows carry no force), mu = Q nu, own rows' entries into lambda. */
double ap_la_tree_reactions(const ap_la_tree *T, const ap_la_tree_geom *g, ap_la_tree_work *W,
                            const double *r, double *lambda, double *Fw) {
  double resid = 0.0, rl[6];
  memset(Fw, 0, sizeof(double) * 6 * (size_t)T->nb);
  for (int i = T->nb - 1; i >= 0; i--) {
    int f0 = T->fofs[i], nf = T->fofs[i + 1] - f0, rk = W->rank[i], s0 = W->slot[i];
    const int *perm = W->perm + f0;
    double *Fi = Fw + 6 * (size_t)i, *nu = W->rq + s0;
    for (int c = 0; c < nf && c < 6; c++) rl[c] = r[T->fidx[f0 + c]] - dot6(g->S + 6 * (size_t)(f0 + c), Fi);
    for (int j = 0; j < rk; j++) {   /* R11^T nu1 = rhs_dep, forward */
      double x = rl[perm[j]];
      for (int p = 0; p < j; p++) x -= FROW(W, T, s0 + p)[j] * nu[p];
      nu[j] = x / FROW(W, T, s0 + j)[j];
    }
    for (int c = rk; c < nf; c++) {   /* R12^T nu1 = rhs_ind */
      double x = rl[perm[c]];
      for (int p = 0; p < rk; p++) x -= FROW(W, T, s0 + p)[c] * nu[p];
      resid = fmax(resid, fabs(x));
    }
    if (T->parent[i] < 0) continue;
    double up[6];
    memcpy(up, Fi, sizeof up);
    transport_wrench(g->d + 3 * (size_t)i, up);
    for (int j = 0; j < rk; j++)
      for (int q = 0; q < 6; q++) up[q] += nu[j] * W->CX[6 * (size_t)(s0 + j) + q];
    for (int q = 0; q < 6; q++) Fw[6 * (size_t)T->parent[i] + q] += up[q];
  }
  for (int i = 0; i < T->nb; i++) {
    int f0 = T->fofs[i], n = W->nrow[i], rk = W->rank[i], s0 = W->slot[i], own = T->rofs[i + 1] - T->rofs[i];
    double *mu = W->rq + s0;
    for (int j = rk; j < n; j++) mu[j] = 0.0;   /* nu2: set by the parent below, or zero */
    if (T->parent[i] >= 0)   /* the pushed rows are rows of the parent, from its row pin[i] */
      for (int j = rk; j < n; j++) mu[j] = W->rq[W->slot[T->parent[i]] + W->pin[i] + j - rk];
    for (int c = rk - 1; c >= 0; c--) {   /* mu = H_0 ... H_{r-1} nu */
      double tau = W->tau[f0 + c], s = mu[c];
      if (tau == 0.0) continue;
      for (int q = c + 1; q < n; q++) s += FROW(W, T, s0 + q)[c] * mu[q];
      s *= tau;
      mu[c] -= s;
      for (int q = c + 1; q < n; q++) mu[q] -= s * FROW(W, T, s0 + q)[c];
    }
    for (int j = 0; j < own; j++) lambda[T->ridx[T->rofs[i] + j]] = mu[j];
  }
  return resid;
}
