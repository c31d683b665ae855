/* Partitions and operating points.
 *
 * Partitions, chosen once at the first operating point and then frozen: the chart coordinates
 * by a pivoted QR of the holonomic rows' chart Jacobian Jh (pivots = dependent coordinates), the
 * speeds by a pivoted QR of the constraint matrix A (pivots = dependent speeds; at the reference
 * the heading frames are the identity, so A S^T = A). Variables the user prefers as independent
 * (def.independent, the freed variables, the speeds the speed parameter sets) have their columns
 * scaled by 1e-6 before pivoting, so they become pivots only when the rank needs them. The core
 * keeps its own partition for the Appell solve (ap_partition).
 *
 * Operating point: Gauss-Newton on the residual r(z) = (rates of the independent speeds, rates
 * of the freed coordinates) over the freed states z: Jacobian by central differences (step
 * 1e-6 max(1, |z_j|): it only steers the iteration; the accuracy is the residual's), the
 * minimum-norm least-squares step (cyclic directions leave the Jacobian rank-deficient) cut
 * to a trust region (no state moves by more than 0.25 max(1, |x_j|): an undamped step from a
 * rough guess can land near another equilibrium, e.g. an inverted one), and step halving until
 * the 2-norm of the residual decreases (Armijo). Converged when max |r| <= tol * scale,
 * scale = max(1, max |rate| at the start, max |u|^2). Equilibrium: independent speeds zero,
 * every independent coordinate freed. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "linalg/linalg.h"

#define PREFER 1e-6
#define MAX_STEP 0.25   /* trust region of one Newton step, relative to max(1, |x_j|) */

static int in_list(const char *const *list, const char *name) {
  for (; list && *list; list++)
    if (strcmp(*list, name) == 0) return 1;
  return 0;
}

/* Variable i is preferred as independent. */
static int preferred(const ap_lin *L, int i) {
  const char *name = ap_an_var_name(L, i);
  if (in_list(L->def.independent, name) || in_list(L->def.free, name)) return 1;
  int s = i - L->ch.nc;
  return s >= 0 && L->speed_dir && L->speed_dir[s] != 0.0;
}

/* Pivoted QR of M (rows x cols) with preferred columns scaled down: perm, rank. */
static int choose(ap_lin *L, int rows, int cols, const double *M, int var0, int *perm,
                  int *rank) {
  double *S = L->Bu;  /* scratch, rows x cols */
  for (int c = 0; c < cols; c++) {
    double f = preferred(L, var0 + c) ? PREFER : 1.0;
    for (int r = 0; r < rows; r++) S[r + (size_t)c * rows] = f * M[r + (size_t)c * rows];
  }
  return ap_la_pivot_select(rows, cols, S, L->d->rank_rtol, perm, rank, L->work, L->iwork);
}

static int holo_jacobian(ap_lin *L) {
  ap_data *d = L->d;
  int n = L->n, nc = L->ch.nc, np = L->nphi;
  memset(L->delta, 0, sizeof *L->delta * (size_t)nc);
  memcpy(d->q, L->q_ref, sizeof *d->q * (size_t)n);
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(L->m, d);
  d->basis = AP_BASIS_PARTITIONED;
  if (rc != AP_OK) return rc;
  double *Phi_q = L->Au;  /* nphi x n */
  memset(Phi_q, 0, sizeof *Phi_q * (size_t)np * n);
  rc = L->m->ev.phi(L->m, d, ((ap_scratch *)d->internal)->ev, L->phi, Phi_q);
  if (rc != AP_OK) return rc;
  ap_an_chart_jacobian(&L->ch, n, d->q, L->delta, L->dq);
  for (int c = 0; c < nc; c++)
    for (int r = 0; r < np; r++) {
      double s = 0.0;
      for (int i = 0; i < n; i++) s += Phi_q[r + (size_t)i * np] * L->dq[i + (size_t)c * n];
      L->Jh[r + (size_t)c * np] = s;
    }
  return AP_OK;
}

int ap_an_partition(ap_lin *L) {
  ap_data *d = L->d;
  int nc = L->ch.nc, k = L->k, rc;
  d->t = L->t;
  memcpy(d->q, L->q_ref, sizeof *d->q * (size_t)L->n);
  rc = ap_partition(L->m, d);
  if (rc != AP_OK) {
    ap_an_msg(L, "no partition of the speeds at the guess: %s", d->msg);
    return rc;
  }
  L->rh = 0;
  for (int c = 0; c < nc; c++) L->cperm[c] = c;
  if (L->nphi > 0) {
    rc = holo_jacobian(L);
    if (rc == AP_OK) rc = choose(L, L->nphi, nc, L->Jh, 0, L->cperm, &L->rh);
    if (rc != AP_OK) {
      ap_an_msg(L, "the holonomic rows cannot be partitioned at the guess: %s", d->msg);
      return rc;
    }
  }
  L->nci = nc - L->rh;
  L->ru = 0;
  for (int s = 0; s < k; s++) L->uperm[s] = s;
  if (L->b > 0) {
    d->basis = AP_BASIS_NONE;
    rc = ap_fwd_position(L->m, d);
    d->basis = AP_BASIS_PARTITIONED;
    if (rc == AP_OK) rc = choose(L, L->b, k, d->A, nc, L->uperm, &L->ru);
    if (rc != AP_OK) return rc;
  }
  L->l = k - L->ru;
  L->nx = L->nci + L->l;
  for (int i = 0; i < L->nci; i++) L->xvar[i] = L->cperm[L->rh + i];
  for (int j = 0; j < L->l; j++) L->xvar[L->nci + j] = nc + L->uperm[L->ru + j];
  L->parted = 1;
  return AP_OK;
}

int ap_an_recentre(ap_lin *L, const double *x) {
  int rc = ap_an_state(L, x);
  if (rc != AP_OK) return rc;
  memcpy(L->q_ref, L->d->q, sizeof *L->q_ref * (size_t)L->n);
  memcpy(L->v_ref, L->d->v, sizeof *L->v_ref * (size_t)L->k);
  for (int i = 0; i < L->ch.nquat; i++) {   /* unit quaternions at the new reference */
    double *p = L->q_ref + L->ch.quat[i].q;
    double nn = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
    for (int j = 0; j < 4; j++) p[j] /= nn;
  }
  ap_an_chart_centre(&L->ch, L->q_ref, 1);
  for (int i = 0; i < L->nci; i++) L->x0[i] = 0.0;
  for (int j = 0; j < L->l; j++) L->x0[L->nci + j] = L->v_ref[L->uperm[L->ru + j]];
  return AP_OK;
}

/* ---- Gauss-Newton ---------------------------------------------------------------------- */

typedef struct gn {
  int nf, nr;
  int *unk, *row;           /* freed states; residual rows (states) */
  double *r, *J, *dz, *z, *xt, *rt, *work;
  int *iwork;
} gn;

static int residual(ap_lin *L, const gn *G, const double *x, double *r) {
  int rc = ap_an_rates(L, x, L->f1);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < G->nr; i++) r[i] = L->f1[G->row[i]];
  return AP_OK;
}

static double norm2(const double *x, int n) {
  double s = 0.0;
  for (int i = 0; i < n; i++) s += x[i] * x[i];
  return sqrt(s);
}

static double norm_inf(const double *x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* J (nr x nf) by central differences. */
static int gn_jacobian(ap_lin *L, gn *G, double *x) {
  for (int j = 0; j < G->nf; j++) {
    int s = G->unk[j];
    double xs = x[s], h = 1e-6 * fmax(1.0, fabs(xs)), xp = xs + h, xm = xs - h;
    x[s] = xp;
    int rc = residual(L, G, x, G->rt);
    x[s] = xm;
    if (rc == AP_OK) rc = residual(L, G, x, G->dz);
    x[s] = xs;
    if (rc != AP_OK) return rc;
    for (int i = 0; i < G->nr; i++) G->J[j + (size_t)i * G->nf] = (G->rt[i] - G->dz[i]) / (xp - xm);
  }
  return AP_OK;
}

static int gn_setup(ap_lin *L, gn *G) {
  int nx = L->nx;
  memset(G, 0, sizeof *G);
  G->unk = calloc((size_t)nx + 1, sizeof *G->unk);
  G->row = calloc((size_t)nx + 1, sizeof *G->row);
  size_t nw = ap_la_work_size(nx, nx);
  G->r = calloc((size_t)nx * (nx + 6) + nw + 8, sizeof *G->r);
  G->iwork = calloc(ap_la_iwork_size(nx, nx) + 1, sizeof *G->iwork);
  if (!G->unk || !G->row || !G->r || !G->iwork) return AP_ERR_NOMEM;
  G->J = G->r + nx, G->dz = G->J + (size_t)nx * nx, G->z = G->dz + nx, G->xt = G->z + nx;
  G->rt = G->xt + nx, G->work = G->rt + nx;
  int equil = L->def.about == AP_LIN_EQUILIBRIUM;
  for (int i = 0; i < nx; i++) {
    int coord = i < L->nci;
    int freed = equil ? coord : in_list(L->def.free, ap_an_var_name(L, L->xvar[i]));
    if (freed) G->unk[G->nf++] = i;
    if (!coord || freed) G->row[G->nr++] = i;
  }
  return AP_OK;
}

static void gn_free(gn *G) {
  free(G->unk), free(G->row), free(G->r), free(G->iwork);
}

/* One damped step from x (residual G->r, norm rn): returns the new norm in *rn. */
static int gn_step(ap_lin *L, gn *G, double *x, double *rn) {
  int nx = L->nx, rc = gn_jacobian(L, G, x);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < G->nr; i++) G->rt[i] = -G->r[i];
  double resid = 0.0;   /* J dz = -r: A^T lambda = rhs with A = J^T (nf x nr) */
  rc = ap_la_lstsq_At(G->nf, G->nr, G->J, G->rt, 1e-10, G->dz, &resid, G->work, G->iwork);
  if (rc != AP_OK) return rc;
  double big = 0.0, r2 = norm2(G->r, G->nr);   /* trust region: no state moves by more than */
  for (int j = 0; j < G->nf; j++)               /* MAX_STEP max(1, |x_j|) in one step */
    big = fmax(big, fabs(G->dz[j]) / (MAX_STEP * fmax(1.0, fabs(x[G->unk[j]]))));
  for (int j = 0; j < G->nf && big > 1.0; j++) G->dz[j] /= big;
  for (double t = 1.0; t > 1e-4; t *= 0.5) {
    memcpy(G->xt, x, sizeof *x * (size_t)nx);
    for (int j = 0; j < G->nf; j++) G->xt[G->unk[j]] += t * G->dz[j];
    if (residual(L, G, G->xt, G->z) != AP_OK) continue;
    double rt = norm_inf(G->z, G->nr);
    if (norm2(G->z, G->nr) <= (1.0 - 1e-4 * t) * r2 || (rt < *rn && *rn < 1e-6)) {
      memcpy(x, G->xt, sizeof *x * (size_t)nx);
      memcpy(G->r, G->z, sizeof *G->r * (size_t)G->nr);
      *rn = rt;
      return AP_OK;
    }
  }
  return AP_RECOVERABLE;   /* no decrease: the residual is at its noise floor */
}

int ap_an_newton(ap_lin *L) {
  gn G;
  int rc = gn_setup(L, &G);
  double *x = L->x0, rn = 0.0, scale = 1.0;
  if (rc == AP_OK && L->def.about == AP_LIN_EQUILIBRIUM)
    for (int j = 0; j < L->l; j++) x[L->nci + j] = 0.0;
  if (rc == AP_OK && G.nf > 0) rc = residual(L, &G, x, G.r);
  if (rc == AP_OK && G.nf > 0) {
    scale = fmax(1.0, norm_inf(L->f1, L->nx));
    for (int j = 0; j < L->l; j++) scale = fmax(scale, x[L->nci + j] * x[L->nci + j]);
    rn = norm_inf(G.r, G.nr);
    int it = 0;
    for (; it < L->def.max_iter && rn > L->def.tol * scale; it++) {
      rc = gn_step(L, &G, x, &rn);
      if (rc != AP_OK) break;
    }
    if (rc == AP_RECOVERABLE && rn <= 1e3 * L->def.tol * scale) rc = AP_OK;
    if (rc == AP_OK && rn > L->def.tol * scale) rc = AP_ERR_SOLVER;
    if (rc != AP_OK && rc != AP_ERR_NOMEM) {
      char why[sizeof L->msg];
      memcpy(why, L->msg, sizeof why);
      ap_an_msg(L, "no operating point: Newton stopped after %d steps with residual %.3g "
                "(tolerance %.3g)%s%.300s", it, rn, L->def.tol * scale, why[0] ? ": " : "",
                why);
    }
    if (rc == AP_RECOVERABLE) rc = AP_ERR_SOLVER;
  }
  if (rc == AP_OK) rc = ap_an_recentre(L, x);
  gn_free(&G);
  return rc;
}
