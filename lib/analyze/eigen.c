/* Eigenvalues of a closed subsystem of the linearization.
 *
 * Closed subsystem K: no state d outside K both depends on K and influences K (through chains
 * of non-zero entries of A outside K). Then, with Up = the outside states that influence K and
 * Down = those that depend on it, the order (Up, K, Down, rest) makes A block triangular and
 * eig(A_KK) is a part of eig(A) (the dropped states add their own blocks).
 *
 * LAPACK dgeevx with balancing (permutation and scaling), right and left eigenvectors and
 * the reciprocal condition numbers RCONDE (of the balanced matrix, as LAPACK computes them) and
 * RCONDV. Error bound of eigenvalue j: eps ||A_bal||_1 / RCONDE_j (LAPACK Users' Guide 4.8,
 * the computation) plus ||E||_F / s_j with E the Ridders error estimates of A_KK and
 * s_j = |y_j^H x_j| / (|x_j| |y_j|) from the eigenvectors of the original matrix (the
 * linearization's own uncertainty, first order). Output order: real part descending, then
 * |imaginary part| descending, the member with positive imaginary part of a pair first. */
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"

int ap_an_eigen_alloc(ap_lin *L) {
  size_t nv = (size_t)L->ch.nc + L->k + 1;
  L->esel = calloc(nv, sizeof *L->esel);
  L->ere = calloc(nv * (2 * nv + 8), sizeof *L->ere);
  if (!L->esel || !L->ere) return AP_ERR_NOMEM;
  L->eim = L->ere + nv, L->ercond = L->eim + nv, L->ercondv = L->ercond + nv;
  L->eerr = L->ercondv + nv, L->evr = L->eerr + nv, L->Asub = L->evr + nv * nv;
  return AP_OK;
}

void ap_an_eigen_free(ap_lin *L) {
  free(L->esel);
  free(L->ere);
}

static int nonzero(const ap_lin *L, int r, int c, double amax) {
  size_t i = r + (size_t)c * L->nx;
  return fabs(L->A[i]) > 4.0 * L->Aerr[i] + L->def.zero_tol * amax;
}

/* Outside states reached from K along edges c -> r (A_rc != 0), forward (down) or backward
 * (up): mark[i] = 1 for them. */
static void reach(const ap_lin *L, const int *inK, int down, int *mark, double amax) {
  int nx = L->nx, changed = 1;
  for (int i = 0; i < nx; i++) mark[i] = 0;
  while (changed) {
    changed = 0;
    for (int d = 0; d < nx; d++) {
      if (inK[d] || mark[d]) continue;
      for (int s = 0; s < nx && !mark[d]; s++) {
        if (!inK[s] && !mark[s]) continue;
        if (down ? nonzero(L, d, s, amax) : nonzero(L, s, d, amax)) mark[d] = 1, changed = 1;
      }
    }
  }
}

static int check_closed(ap_lin *L, const int *inK) {
  int nx = L->nx, *up = calloc((size_t)2 * nx + 1, sizeof *up), rc = AP_OK;
  if (!up) return AP_ERR_NOMEM;
  int *down = up + nx;
  double amax = 0.0;
  for (size_t i = 0; i < (size_t)nx * nx; i++) amax = fmax(amax, fabs(L->A[i]));
  reach(L, inK, 1, down, amax);
  reach(L, inK, 0, up, amax);
  for (int d = 0; d < nx && rc == AP_OK; d++)
    if (up[d] && down[d]) {
      ap_an_msg(L, "the states chosen are not a closed subsystem: '%s', left out, both depends "
                "on them and acts on them; keep it", ap_an_var_name(L, L->xvar[d]));
      rc = AP_ERR_ARG;
    }
  free(up);
  return rc;
}

/* Condition of eigenvalue j from the original-matrix eigenvectors (pair: j, j+1 hold re, im). */
static double eig_s(int n, const double *vl, const double *vr, int j, int pair) {
  const double *a = vl + (size_t)j * n, *c = vr + (size_t)j * n;
  const double *b = pair ? a + n : NULL, *d = pair ? c + n : NULL;
  double re = 0, im = 0, nx = 0, ny = 0;
  for (int i = 0; i < n; i++) {
    double bi = b ? b[i] : 0.0, di = d ? d[i] : 0.0;
    re += a[i] * c[i] + bi * di, im += a[i] * di - bi * c[i];
    nx += c[i] * c[i] + di * di, ny += a[i] * a[i] + bi * bi;
  }
  return hypot(re, im) / sqrt(nx * ny);
}

typedef struct ekey { double re, im; int j; } ekey;

static int cmp_key(const void *pa, const void *pb) {
  const ekey *a = pa, *b = pb;
  if (a->re != b->re) return a->re > b->re ? -1 : 1;
  if (fabs(a->im) != fabs(b->im)) return fabs(a->im) > fabs(b->im) ? -1 : 1;
  return (a->im < b->im) - (a->im > b->im);
}

/* Sort the n results by key, moving pairs' vector columns together. */
static int sort_results(ap_lin *L, int n, double *vr) {
  ekey *k = malloc(sizeof *k * (size_t)n);
  double *tmp = malloc(sizeof *tmp * ((size_t)n * n + 4 * (size_t)n + 1));
  if (!k || !tmp) return free(k), free(tmp), AP_ERR_NOMEM;
  for (int j = 0; j < n; j++) k[j].re = L->ere[j], k[j].im = L->eim[j], k[j].j = j;
  qsort(k, (size_t)n, sizeof *k, cmp_key);
  double *r = tmp + (size_t)n * n, *c = r + n, *cv = c + n, *e = cv + n;
  for (int i = 0; i < n; i++) {
    int j = k[i].j;
    r[i] = L->ercond[j], c[i] = L->ercondv[j], e[i] = L->eerr[j];
    memcpy(tmp + (size_t)i * n, vr + (size_t)j * n, sizeof *tmp * (size_t)n);
    L->ere[i] = k[i].re, L->eim[i] = k[i].im;
  }
  /* a pair keeps its columns (real part, imaginary part): LAPACK stores the member with
   * positive imaginary part first, and the sort puts it first too */
  memcpy(L->ercond, r, sizeof *r * (size_t)n), memcpy(L->ercondv, c, sizeof *c * (size_t)n);
  memcpy(L->eerr, e, sizeof *e * (size_t)n), memcpy(L->evr, tmp, sizeof *tmp * (size_t)n * n);
  free(k), free(tmp);
  return AP_OK;
}

static int run_geevx(ap_lin *L, int n) {
  double *a = malloc(sizeof *a * ((size_t)3 * n * n + (size_t)n + 1));
  if (!a) return AP_ERR_NOMEM;
  double *vl = a + (size_t)n * n, *vr = vl + (size_t)n * n, *scale = vr + (size_t)n * n, abnrm;
  int ilo, ihi, rc = AP_OK;
  memcpy(a, L->Asub, sizeof *a * (size_t)n * n);
  lapack_int info = LAPACKE_dgeevx(LAPACK_COL_MAJOR, 'B', 'V', 'V', 'B', n, a, n, L->ere, L->eim,
                                   vl, n, vr, n, &ilo, &ihi, scale, &abnrm, L->ercond,
                                   L->ercondv);
  if (info == LAPACK_WORK_MEMORY_ERROR || info == LAPACK_TRANSPOSE_MEMORY_ERROR) {
    ap_an_msg(L, "dgeevx: out of memory for its workspace (%d x %d state matrix)", n, n);
    rc = AP_ERR_NOMEM;   /* LAPACKE allocates the workspace itself */
  } else if (info < 0) {
    ap_an_msg(L, "dgeevx: argument %d is invalid (a bug in Appell)", (int)-info);
    rc = AP_ERR_INTERNAL;
  } else if (info > 0) {
    ap_an_msg(L, "dgeevx failed (info %d): the QR algorithm did not converge", (int)info);
    rc = AP_ERR_SINGULAR;
  }
  double ef = 0.0;   /* ||E||_F of the subsystem's Ridders errors */
  for (int c = 0; c < n && rc == AP_OK; c++)
    for (int r = 0; r < n; r++) {
      double e = L->Aerr[L->esel[r] + (size_t)L->esel[c] * L->nx];
      ef += e * e;
    }
  for (int j = 0; j < n && rc == AP_OK; j++) {
    int pair = L->eim[j] != 0.0, first = pair && L->eim[j] > 0;
    double s = eig_s(n, vl, vr, pair && !first ? j - 1 : j, pair);
    double lap = L->ercond[j] > 0 ? DBL_EPSILON * abnrm / L->ercond[j] : HUGE_VAL;
    L->eerr[j] = lap + (s > 0 ? sqrt(ef) / s : HUGE_VAL);
  }
  if (rc == AP_OK) rc = sort_results(L, n, vr);
  free(a);
  return rc;
}

static int eigen(ap_lin *L, const int *sel, int ns, int drop_cyclic);

int ap_lin_eigen(ap_lin *L, const int *sel, int ns, int drop_cyclic) {
  if (!L || !L->linearized) return AP_ERR_ARG;
  L->msg[0] = '\0';
  int rc = eigen(L, sel, ns, drop_cyclic);
  if (rc == AP_ERR_NOMEM && !L->msg[0]) ap_an_msg(L, "eigenvalues: out of memory");
  return rc;
}

static int eigen(ap_lin *L, const int *sel, int ns, int drop_cyclic) {
  int nx = L->nx, n = 0, *inK = calloc((size_t)nx + 1, sizeof *inK);
  if (!inK) return AP_ERR_NOMEM;
  for (int i = 0; i < nx; i++) inK[i] = sel ? 0 : !(drop_cyclic && L->cyclic[i]);
  for (int i = 0; sel && i < ns; i++) {
    if (sel[i] < 0 || sel[i] >= nx || inK[sel[i]]) {
      ap_an_msg(L, "state %d is out of range or chosen twice", sel[i]);
      return free(inK), AP_ERR_ARG;
    }
    inK[sel[i]] = 1;
  }
  int rc = check_closed(L, inK);
  for (int i = 0; i < nx; i++)
    if (inK[i]) L->esel[n++] = i;
  free(inK);
  if (rc != AP_OK) return rc;
  if (sel) /* keep the caller's order */
    for (int i = 0; i < ns; i++) L->esel[i] = sel[i];
  n = sel ? ns : n;
  for (int c = 0; c < n; c++)
    for (int r = 0; r < n; r++)
      L->Asub[r + (size_t)c * n] = L->A[L->esel[r] + (size_t)L->esel[c] * nx];
  L->ne = n;
  return n > 0 ? run_geevx(L, n) : AP_OK;
}

int ap_lin_get_eigen(const ap_lin *L, ap_lin_eig *out) {
  if (!L || !out) return AP_ERR_ARG;
  out->n = L->ne, out->states = L->esel, out->re = L->ere, out->im = L->eim;
  out->rcond = L->ercond, out->rcondv = L->ercondv, out->err = L->eerr, out->vr = L->evr;
  out->Asub = L->Asub;
  return AP_OK;
}
