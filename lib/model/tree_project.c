/* The implicit holonomic rows on the tree path (tree_model.h, docs/large.md): the contact rows
 * of wheel contacts, phi = o_z - sigma(u) = 0 (contact.c), closed after each step by the dense
 * path's method (evaluate.c's close_loops): Gauss-Newton steps dv of minimum norm with
 * Jl dv = -phi, q += N(q) dv, until max |phi| <= AP_LOOP_TOL * lscale.
 *
 * Structure: a wheel's row lives on one body, so its gradient Jl_s = c_s J_i involves only the
 * speeds of that body's tree, and Jl is block diagonal over the trees. The minimum-norm
 * solution of a block-diagonal system is the blocks' minimum-norm solutions side by side, so
 * each tree gets its own small least-squares solve (ap_la_lstsq_At on k_t x h_t, the same
 * routine and rank tolerance as the dense path): O(N) for N vehicles of bounded size.
 * Gradient of row s on tree body i: its covector c_s on the body's twist (the kind's tree_row,
 * the velocity row .z) carried to the root, (t; f) -> (t + d_a x f; f) at each joint, and
 * projected on each joint's free columns on the way: O(depth).
 * Workspace (ap_tree_hol_ws_size): phi (nhol), dv (k), Jl^T of one tree (hkmax x hmax), its
 * right-hand side (hmax) and solution (hkmax), the solve's scratch. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linalg/linalg.h"
#include "model/con_kind.h"
#include "model/tree_model.h"

static int hol_tree(const ap_tplan *P, const ap_mcon *c) {
  return P->T.tree[P->M->bodies[c->def.body].joint];
}

int ap_tree_hol_plan(ap_tplan *P) {
  const ap_bmodel *M = P->M;
  const ap_la_tree *T = &P->T;
  int nt = T->ntree, nh = M->nloop, k = T->k;
  P->nhol = nh;
  if (nh == 0) return AP_OK;
  P->hints = calloc((size_t)(3 * (nt + 1) + 3 * nh + k + 1), sizeof(int));
  if (!P->hints) return AP_ERR_NOMEM;
  int *ip = P->hints;
  P->hofs = ip, ip += nt + 1;
  P->tkofs = ip, ip += nt + 1;
  P->hcon = ip, ip += nh;
  P->hrow = ip, ip += nh;
  P->hphi = ip, ip += nh;
  P->kloc = ip, ip += k;
  int *fill = ip;   /* (nt + 1) fill pointers */
  for (int ci = 0; ci < M->nc; ci++)
    if (M->cons[ci].nhol) P->hofs[hol_tree(P, &M->cons[ci]) + 1] += M->cons[ci].nhol;
  for (int t = 0; t < nt; t++) P->hofs[t + 1] += P->hofs[t];
  for (int t = 0; t < nt; t++) fill[t] = P->hofs[t];
  for (int ci = 0, s = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    for (int r = 0; r < c->nhol; r++, s++) {
      int p = fill[hol_tree(P, c)]++;
      P->hcon[p] = ci, P->hrow[p] = c->hrow + r, P->hphi[p] = s;
    }
  }
  for (int t = 0, j = 0; t < nt; t++) {   /* speeds by tree, as kspeed lists them */
    P->tkofs[t] = j;
    int jt = 0;
    for (int a = T->tofs[t]; a < T->tofs[t + 1]; a++)
      for (int c = T->fofs[T->tbody[a]]; c < T->fofs[T->tbody[a] + 1]; c++) P->kloc[c] = jt++;
    j += jt;
    int ht = P->hofs[t + 1] - P->hofs[t];
    if (ht > P->hmax) P->hmax = ht;
    if (ht && jt > P->hkmax) P->hkmax = jt;
  }
  P->tkofs[nt] = k;
  return AP_OK;
}

size_t ap_tree_hol_ws_size(const ap_tplan *P, size_t *nint) {
  *nint = 0;
  if (!P->nhol) return 0;
  size_t hk = (size_t)P->hkmax, h = (size_t)P->hmax;
  *nint = ap_la_iwork_size(P->hkmax, P->hmax);
  return (size_t)P->nhol + (size_t)P->T.k + hk * h + h + hk + 64 +
         ap_la_work_size(P->hkmax, P->hmax);
}

/* phi of every holonomic row (constraint order) from the shadow's kinematics at q. */
static int rows_phi(const ap_tplan *P, ap_data *d, const double *q, double *S, double *phi) {
  const ap_bmodel *Ms = &P->shadow;
  int rc = ap_kin_position(&P->sm, d, d->t, q, S);
  if (rc != AP_OK) return rc;
  double row[8];
  for (int p = 0; p < P->nhol; p++) {
    const ap_mcon *c = &Ms->cons[P->hcon[p]];
    phi[P->hphi[p]] = AP_CON_EVAL(c)->hol(Ms, S, c, P->hrow[p], row);
  }
  return AP_OK;
}

static double max_abs(const double *x, int n) {
  double mx = 0.0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

int ap_tree_hol_residual(const ap_tplan *P, ap_data *d, const double *q, double *phi_max) {
  ap_tree_ws *ws = ap_tree_ws_of(d);
  int rc = rows_phi(P, d, q, ws->S, ws->hp);
  *phi_max = rc == AP_OK ? max_abs(ws->hp, P->nhol) : 0.0;
  return rc;
}

/* Column s of Jl^T of tree t (kt entries at JlT): the row's covector carried to the root. */
static void gradient(const ap_tplan *P, ap_tree_ws *ws, int p, double *JlT) {
  const ap_la_tree *T = &P->T;
  const ap_mcon *c = &P->shadow.cons[P->hcon[p]];
  int i = P->M->bodies[c->def.body].joint;
  double F[6], a0 = 0.0;
  memset(F, 0, sizeof F);
  c->kind->tree_row(&P->shadow, ws->S, c, P->hrow[p], ws->S + P->shadow.off_con +
                    (size_t)P->hcon[p] * CON_STRIDE, ws->rho + 6 * (size_t)i, F, &a0);
  ap_la_tree_row_coeffs(T, &ws->g, i, F, P->kloc, JlT);
}

/* Gradients of tree t's rows into JlT (kt x ht), their right-hand sides -phi into rhs; the
 * largest column norm of Jl (over the tree's speeds): the first pivot of its pivoted QR. */
static double tree_gradients(const ap_tplan *P, ap_tree_ws *ws, int t, const double *phi,
                             double *JlT, double *rhs) {
  int h0 = P->hofs[t], ht = P->hofs[t + 1] - h0, kt = P->tkofs[t + 1] - P->tkofs[t];
  double top = 0.0;
  memset(JlT, 0, sizeof(double) * (size_t)kt * ht);
  for (int s = 0; s < ht; s++) {
    gradient(P, ws, h0 + s, JlT + (size_t)s * kt);
    rhs[s] = -phi[P->hphi[h0 + s]];
  }
  for (int j = 0; j < kt; j++) {
    double nn = 0.0;
    for (int s = 0; s < ht; s++) nn += JlT[j + (size_t)s * kt] * JlT[j + (size_t)s * kt];
    top = fmax(top, sqrt(nn));
  }
  return top;
}

/* One Gauss-Newton step: dv (k) of minimum norm with Jl dv = -phi, tree by tree. The dense
 * path's one solve drops the pivots below 1e-10 of the largest pivot of the whole Jl; pivoted
 * QR of the block-diagonal Jl takes each block's pivots, so each tree's rank tolerance is
 * taken relative to the largest first pivot over all trees (a first pass). A tree whose
 * gradients are all rounding (the contact rows of wheels on a planar chassis are identically
 * zero) then gets dv = 0, not -phi / 1e-17: relative to its own pivot it would move its wheel
 * angles by tens of radians whenever another tree's rows needed a step. */
static int gn_step(const ap_tplan *P, ap_tree_ws *ws, const double *phi, double *dv) {
  int hk = P->hkmax, h = P->hmax;
  double *JlT = dv + P->T.k, *rhs = JlT + (size_t)hk * h, *x = rhs + h, *work = x + hk + 64;
  double top = 0.0;
  memset(dv, 0, sizeof(double) * (size_t)P->T.k);
  ap_tree_geometry(P, ws);
  for (int t = 0; t < P->T.ntree; t++)
    if (P->hofs[t + 1] > P->hofs[t]) top = fmax(top, tree_gradients(P, ws, t, phi, JlT, rhs));
  for (int t = 0; t < P->T.ntree; t++) {
    int ht = P->hofs[t + 1] - P->hofs[t], kt = P->tkofs[t + 1] - P->tkofs[t];
    if (!ht) continue;
    double tt = tree_gradients(P, ws, t, phi, JlT, rhs), resid = 0.0;
    if (!(tt > 1e-10 * top)) continue;   /* every pivot below the tolerance: rank 0 */
    int rc = ap_la_lstsq_At(kt, ht, JlT, rhs, 1e-10 * top / tt, x, &resid, work, ws->hip);
    if (rc != AP_OK) return rc;
    for (int j = 0; j < kt; j++) dv[P->kspeed[P->tkofs[t] + j]] = x[j];
  }
  return AP_OK;
}

int ap_tree_close_rows(const void *plan, ap_data *d, double *q, double *change) {
  const ap_tplan *P = plan;
  const ap_bmodel *M = P->M;
  ap_tree_ws *ws = ap_tree_ws_of(d);
  double *phi = ws->hp, *dv = phi + P->nhol, tol = AP_LOOP_TOL * M->lscale, err = 0.0;
  int worst = 0;
  for (int it = 0; it <= AP_LOOP_ITER; it++) {
    int rc = rows_phi(P, d, q, ws->S, phi);
    if (rc == AP_OK && M->nc) rc = ap_con_time(&P->sm, d, d->t, ws->S);
    if (rc != AP_OK) return rc;
    err = max_abs(phi, P->nhol);
    if (err <= tol) return AP_OK;
    if (it == AP_LOOP_ITER) break;
    if (gn_step(P, ws, phi, dv) != AP_OK) break;
    ap_bm_step_q(M, q, dv);
    for (int c = 0; c < M->k; c++) *change += fabs(dv[c]);
  }
  for (int p = 0; p < P->nhol; p++)
    if (fabs(phi[P->hphi[p]]) > fabs(phi[P->hphi[worst]])) worst = p;
  const ap_mcon *c = &M->cons[P->hcon[worst]];
  AP_BM_MSG(d, "model '%s': the wheel contacts cannot be closed at t = %.17g: row '%s' is off "
            "by %.3g m after %d Gauss-Newton steps (tolerance %.3g m)", P->sm.name, d->t,
            P->sm.constraint_names[c->row + P->hrow[worst]], err, AP_LOOP_ITER, tol);
  return AP_ERR_INCONSISTENT;
}

/* ---- completing speeds in component mode ------------------------------------------------- */

/* The dense path's minimum-norm completion (evaluate.c's min_norm_speeds: least squares on the
 * rows with the given speeds moved to the right) tree by tree on the blocks A_t of the last
 * position stage at d->q: A is block diagonal, so the minimum-norm solution of the whole is the
 * trees' side by side, in O(N) instead of one b x k least-squares problem. */
int ap_tree_complete_min_norm(const ap_model *m, ap_data *d, ap_tree_ws *ws, const int *given,
                              double *v) {
  const ap_tplan *P = ws->P;
  const ap_la_tree *T = &P->T;
  const ap_la_comp_work *C = &ws->CW;
  int km = 1, bm = 1;
  for (int t = 0; t < T->ntree; t++) {
    km = ws->W.kofs[t + 1] - ws->W.kofs[t] > km ? ws->W.kofs[t + 1] - ws->W.kofs[t] : km;
    bm = C->rofs[t + 1] - C->rofs[t] > bm ? C->rofs[t + 1] - C->rofs[t] : bm;
  }
  size_t lw = ap_la_work_size(km, bm), liw = ap_la_iwork_size(km, bm);
  double *AfT = calloc((size_t)km * bm + 2 * (size_t)bm + 2 * (size_t)km + lw + 1, sizeof *AfT);
  int *iw = calloc(liw + (size_t)km + 1, sizeof *iw);
  if (!AfT || !iw) {
    free(AfT), free(iw);
    AP_BM_MSG(d, "model '%s': out of memory completing the speeds", m->name);
    return AP_ERR_NOMEM;
  }
  double *rhs = AfT + (size_t)km * bm, *res = rhs + bm, *x = res + bm, *vt = x + km;
  double *work = vt + km, worst = 0.0, scale = 0.0;
  int *col = iw + liw, rc = AP_OK;
  for (int t = 0; t < T->ntree && rc == AP_OK; t++) {
    int kt = ws->W.kofs[t + 1] - ws->W.kofs[t], bt = C->rofs[t + 1] - C->rofs[t], nf = 0;
    const double *At = C->A + C->aofs[t];
    for (int c = 0; c < kt; c++) {
      int sp = T->fidx[ws->W.kidx[ws->W.kofs[t] + c]];
      vt[c] = v[sp];
      if (!given[sp]) col[nf++] = c;
    }
    for (int j = 0; j < bt; j++) {
      double a0 = d->a0[T->ridx[C->rpos[C->rofs[t] + j]]];
      rhs[j] = -a0, scale = fmax(scale, fabs(a0));
      for (int c = 0, f = 0; c < kt; c++) {
        double a = At[j + (size_t)c * bt];
        scale = fmax(scale, fabs(a * vt[c]));
        if (f < nf && col[f] == c) AfT[f++ + (size_t)j * nf] = a;
        else rhs[j] -= a * vt[c];
      }
    }
    double resid = 0.0;
    if (nf && bt) rc = ap_la_lstsq_At(nf, bt, AfT, rhs, 1e-12, x, &resid, work, iw);
    for (int f = 0; rc == AP_OK && f < nf; f++) vt[col[f]] = bt ? x[f] : 0.0;
    for (int j = 0; rc == AP_OK && j < bt; j++) {   /* A_t v + a0 */
      double r = d->a0[T->ridx[C->rpos[C->rofs[t] + j]]];
      for (int c = 0; c < kt; c++) r += At[j + (size_t)c * bt] * vt[c];
      worst = fmax(worst, fabs(r));
    }
    for (int c = 0; rc == AP_OK && c < kt; c++) v[T->fidx[ws->W.kidx[ws->W.kofs[t] + c]]] = vt[c];
  }
  free(AfT), free(iw);
  if (rc != AP_OK) return rc;
  if (worst > 1e-9 * scale) {
    AP_BM_MSG(d, "model '%s': the given speeds leave the constraints violated by %.3g", m->name,
              worst);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}
