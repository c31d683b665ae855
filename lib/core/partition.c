/* Choosing the partition of the speeds and judging redundant constraint rows (double build
 * only: these decisions are taken at the real state, between steps, never inside a derivative).
 *
 * ap_partition: pivoted QR of A at (t, q) picks the dependent speeds (perm[0..rank-1]); rows
 * beyond the rank are redundant: a row-pivoted QR of A^T names them, and their consistency
 * (a0 in the range of the kept rows) decides between dropping them and AP_ERR_INCONSISTENT. A
 * body model with implicit holonomic rows tells rows redundant for every q from rows redundant
 * only where those rows hold, by the rank at a nearby state off them (nearby_rank).
 * ap_core_judge_redundant: the latter kind, judged at an accepted state against manifold_rtol.
 * ap_core_refuse_vanishing_rows: rows that no speed moves but a0 does (an absolute rank floor).
 * Nothing here allocates. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/core.h"
#include "core/structured.h"
#include "linalg/linalg.h"

#define SCRATCH(d) ((ap_scratch *)(d)->internal)  /* first member of the data block */

static double max_abs(const double *x, size_t len) {
  double mx = 0.0;
  for (size_t i = 0; i < len; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

/* Names of the constraint rows a pivoted QR of A^T puts after the rank: the redundant ones. */
static void name_redundant(const ap_model *m, ap_data *d, const int *jpvt, int r,
                           const char *verdict, double resid) {
  char rows[256] = "";
  size_t used = 0;
  for (int s = r; s < m->b && used + 40 < sizeof rows; s++) {
    int len = snprintf(rows + used, sizeof rows - used, "%s'%s'", s > r ? ", " : "",
                       m->constraint_names[jpvt[s]]);
    if (len > 0) used += (size_t)len;
  }
  ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant (%s) at t = %.17g: %s "
              "is a combination of the others; residual %.3g", m->name, m->b - r, m->b,
              verdict, d->t, rows, resid);
}

/* The terms of each row's equation and its floor (core.h): t_r + f_r, t_r = |x_r| + sum_c
 * |A_rc y_c| with (x, y) = (a0, v) or (gamma, v'), into t (b). */
static void row_terms(const ap_model *m, const ap_data *d, int of_gamma, double *t) {
  const double *x = of_gamma ? d->gamma : d->a0, *y = of_gamma ? d->vdot : d->v;
  double fl = of_gamma ? AP_ROW_FLOOR_PER_S2 : AP_ROW_FLOOR_PER_S;
  for (int r = 0; r < m->b; r++) {
    t[r] = fabs(x[r]);
    for (int c = 0; c < m->k; c++) {
      double a = d->A[r + (size_t)c * m->b];
      t[r] += fabs(a * y[c]) + fl * fabs(a) * (m->vscale ? m->vscale[c] : 1.0);
    }
  }
}

/* The dropped rows that contradict the kept ones, each with its own residual: from the pivoted
 * QR A^T P = Q R of ap_la_orth_basis (R in the upper triangle of F, ld k), dropped row j is the
 * combination c = R11^-1 R12[:, j] of the kept rows, and x_j - c . x_kept is its disagreement
 * (x = a0 or gamma, of_gamma says which). It is judged against the terms of the equations it
 * combines, in its own units: tol (t_j + sum_i |c_i| t_i) (row_terms; core.h). Rows within
 * that are consistent; so are rows that no speed moves (|A_j| below rank_rtol times the length
 * scale: their a0 is judged by ap_core_refuse_vanishing_rows). Returns the number of
 * inconsistent rows, named in d->msg. work: 2 b doubles. */
static int name_inconsistent(const ap_model *m, ap_data *d, const double *F, const int *jpvt,
                             int r, int of_gamma, double tol, const char *what, double *work) {
  int k = m->k, nbad = 0;
  const double *x = of_gamma ? d->gamma : d->a0;
  double *t = work + m->b, worst = 0.0;
  row_terms(m, d, of_gamma, t);
  char bad[320] = "";
  size_t used = 0;
  for (int j = r; j < m->b; j++) {
    double *c = work, res = x[jpvt[j]], scale = AP_TERMS_TINY + t[jpvt[j]], an = 0.0;
    for (int i = 0; i < k; i++) an = hypot(an, d->A[jpvt[j] + (size_t)i * m->b]);
    if (!(an > d->rank_rtol * m->lscale)) continue;   /* a row no speed moves: judged by
                                                          ap_core_refuse_vanishing_rows */
    for (int i = r - 1; i >= 0; i--) {   /* R11 c = R12[:, j] */
      double v = F[i + (size_t)j * k];
      for (int l = i + 1; l < r; l++) v -= F[i + (size_t)l * k] * c[l];
      c[i] = v / F[i + (size_t)i * k];
    }
    for (int i = 0; i < r; i++) res -= c[i] * x[jpvt[i]], scale += fabs(c[i]) * t[jpvt[i]];
    if (!(fabs(res) > tol * scale)) continue;
    nbad++;
    worst = fmax(worst, fabs(res) / scale);
    if (used + 60 >= sizeof bad) continue;
    int len = snprintf(bad + used, sizeof bad - used, "%s'%s' (by %.3g)", used ? ", " : "",
                       m->constraint_names[jpvt[j]], res);
    if (len > 0) used += (size_t)len;
  }
  if (nbad)
    ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant and %d of them "
                "inconsistent at t = %.17g: %s disagree%s with the combination of the others "
                "(%s; up to %.3g of the terms of those rows, more than %.3g)", m->name,
                m->b - r, m->b, nbad, d->t, bad, nbad == 1 ? "s" : "", what, worst, tol);
  return nbad;
}

/* ---- partition ---------------------------------------------------------------------------- */

/* Rank of A at a nearby state q + 1e-6 N (vscale . xi) off the holonomic manifold (xi a fixed
 * spread of directions with entries in [-1, 1]; vscale the model's scale of each speed, core.h:
 * every angle moves by at most 1e-6 rad, every length by at most 1e-6 of the model's length
 * scale, in any unit of length): redundancy that holds for every q survives there, redundancy
 * of the manifold does not. The position stage at q is restored (d->perm is overwritten).
 * Returns the rank, -1 when the nearby state cannot be evaluated, -2 when q cannot. */
static int nearby_rank(const ap_model *m, ap_data *d) {
  ap_scratch *s = SCRATCH(d);
  int n = m->n, k = m->k, r = -1;
  for (int c = 0; c < k; c++) s->tk1[c] = sin(1.3 + 2.1 * c) * (m->vscale ? m->vscale[c] : 1.0);
  ap_la_gemv(n, k, d->N, s->tk1, s->tn);   /* tn = N (vscale . xi) */
  if (!(max_abs(s->tn, (size_t)n) > 0)) return -1;
  for (int i = 0; i < n; i++) {
    double qi = d->q[i];
    d->q[i] += 1e-6 * s->tn[i];
    s->tn[i] = qi;
  }
  if (ap_core_position_objects(m, d) == AP_OK &&
      ap_la_pivot_select(m->b, k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork) != AP_OK)
    r = -1;
  memcpy(d->q, s->tn, sizeof(double) * (size_t)n);
  if (ap_core_position_objects(m, d) != AP_OK) return -2;
  return r;
}

static int partition(const ap_model *m, ap_data *d) {
  if (ap_core_st(d)) return ap_st_partition(m, d, ap_core_st(d));   /* the tree path */
  ap_scratch *s = SCRATCH(d);
  d->cnt.partitions++;
  if (m->b == 0) {
    d->rank = 0, d->l = m->k;
    for (int i = 0; i < m->k; i++) d->perm[i] = i;
    return AP_OK;
  }
  int rc = ap_core_position_objects(m, d);
  if (rc != AP_OK) return rc;
  int r = 0;
  rc = ap_la_pivot_select(m->b, m->k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork);
  if (rc != AP_OK) {
    ap_core_msg(d, "system '%s': pivoted QR of A failed at t = %.17g", m->name, d->t);
    return rc;
  }
  d->rank = r, d->l = m->k - r, d->redundant = m->b - r, d->redundant_manifold = 0;
  if (r == m->b) return AP_OK;
  if (m->nhol > 0) {   /* structural or of the manifold? */
    int rn = nearby_rank(m, d);
    if (rn == -2) return AP_ERR_INTERNAL;   /* the state itself evaluated a moment ago */
    d->redundant_manifold = rn > r ? rn - r : 0;
    rc = ap_la_pivot_select(m->b, m->k, d->A, d->rank_rtol, d->perm, &r, s->work, s->iwork);
    if (rc != AP_OK) return rc;
  }
  /* Which rows are redundant, and are they consistent? The row-pivoted QR of A^T says. */
  double resid = 0.0;
  int rr = 0;
  rc = ap_la_orth_basis(m->b, m->k, d->A, d->a0, d->rank_rtol, &rr, s->F, s->tau, s->jpvt,
                        s->Qf, s->gB, s->tk1, &resid, s->work, s->iwork);
  if (rc != AP_OK) return rc;
  double tol = d->redundant_manifold ? d->manifold_rtol : AP_CONSISTENCY_RTOL;
  if (resid > 0 && name_inconsistent(m, d, s->F, s->jpvt, rr, 0, tol, "the free terms a0",
                                     s->work))
    return AP_ERR_INCONSISTENT;   /* each dropped row against its own terms */
  name_redundant(m, d, s->jpvt, rr, !d->redundant_manifold ? "consistent, dropped"
                 : d->redundant_manifold == d->redundant ? "consistent, dropped; only where "
                 "the loops and contacts close" : "consistent, dropped; some only where the "
                 "loops and contacts close", resid);
  return AP_OK;
}

int ap_partition(const ap_model *m, ap_data *d) {
  if (!ap_core_data_ok(m, d)) return AP_ERR_ARG;
  return AP_CORE_GUARDED(m, d, "partition", partition(m, d));
}

/* Rows redundant only on the holonomic manifold, at an accepted state (core.h). The residuals
 * scale like the distance from the manifold: relative to the size of the terms of A v + a0
 * (resp. A v' = gamma; ap_core_row_scale). Which rows: the row-pivoted QR of A^T names them
 * (as ap_partition, each against its own terms where one is beyond them). */
int ap_core_judge_redundant(const ap_model *m, ap_data *d) {
  if (!d->redundant_manifold) return AP_OK;
  if (ap_core_st(d)) return ap_st_judge_redundant(m, d, ap_core_st(d));   /* the tree path */
  ap_scratch *s = SCRATCH(d);
  double sa = ap_core_row_scale(m, d, 0), sg = ap_core_row_scale(m, d, 1);
  double tol = d->manifold_rtol;
  int bad_a = d->resid_a0 > tol * sa, bad_g = !bad_a && d->resid_gamma > tol * sg;
  if (!bad_a && !bad_g) return AP_OK;
  double resid = 0.0;
  int rr = d->rank;
  if (ap_la_orth_basis(m->b, m->k, d->A, d->a0, -1.0, &rr, s->F, s->tau, s->jpvt, s->Qf, s->gB,
                       s->tk1, &resid, s->work, s->iwork) != AP_OK)
    return AP_ERR_INCONSISTENT;
  if (!name_inconsistent(m, d, s->F, s->jpvt, rr, bad_g, tol,
                         bad_a ? "the free terms a0, manifold_rtol" : "gamma, manifold_rtol",
                         s->work)) {
    char verdict[160];
    snprintf(verdict, sizeof verdict, "inconsistent along the motion: %s by %.3g relative, "
             "more than manifold_rtol %.3g", bad_a ? "the rows drifted apart" : "gamma",
             bad_a ? d->resid_a0 / sa : d->resid_gamma / sg, tol);
    name_redundant(m, d, s->jpvt, rr, verdict, bad_a ? d->resid_a0 : d->resid_gamma);
  }
  return AP_ERR_INCONSISTENT;
}

/* A row of A whose norm is below rank_rtol times the model's length scale m->lscale (the scale
 * of A's entries: lever arms in m per rad, 1 for translational speeds; as the DAE mode's and
 * the Gauss-Newton projection's floors) vanishes: no speed moves it. Its a0 must then vanish
 * too, relative to the terms of its equation A v + a0 = 0, which are a0 alone: within
 * AP_CONSISTENCY_RTOL of the rows' terms and floors (ap_core_row_scale; on the tree path,
 * which forms no A, max|a0| plus AP_ROW_FLOOR_PER_S max|A_r| lscale). Otherwise the row is contradictory: a drive demands a speed of the
 * row that no free speed can give, and the relative rank tests, which keep a lone row by its
 * own pivot, gave minimum-norm speeds |a0| / |A_r| of 1e15 rad/s (campaign seed 1004576,
 * tests/scenes/difftest/seed_1004576.yaml). On the tree path, which forms no A, the rows' norms
 * come from its operator A x + a0 (one product per speed: at creation and on a refusal only).
 * A and a0 must be current (after ap_partition, or the tree path's position stage). */
static void row_norms(const ap_model *m, ap_data *d, double *norms) {
  ap_st *st = ap_core_st(d);
  for (int r = 0; r < m->b; r++) norms[r] = 0.0;
  for (int c = 0; c < m->k; c++) {
    if (!st) {
      for (int r = 0; r < m->b; r++) norms[r] = hypot(norms[r], d->A[r + (size_t)c * m->b]);
      continue;
    }
    for (int i = 0; i < m->k; i++) st->tk1[i] = i == c;
    st->ops->amul(st->ws, d, st->tk1, st->tb, NULL);   /* A e_c + a0 */
    for (int r = 0; r < m->b; r++) norms[r] = hypot(norms[r], st->tb[r] - d->a0[r]);
  }
}

int ap_core_refuse_vanishing_rows(const ap_model *m, ap_data *d) {
  if (m->b == 0) return AP_OK;
  double floor_a = d->rank_rtol * m->lscale;
  double *norms = ap_core_st(d) ? ap_core_st(d)->tm : SCRATCH(d)->work, nmax = 0.0;
  row_norms(m, d, norms);
  for (int r = 0; r < m->b; r++) nmax = fmax(nmax, norms[r]);
  double floor_a0 = AP_CONSISTENCY_RTOL *
                    ((ap_core_st(d) ? AP_TERMS_TINY + max_abs(d->a0, (size_t)m->b) +
                                          AP_ROW_FLOOR_PER_S * nmax * m->lscale
                                    : ap_core_row_scale(m, d, 0)) +
                     AP_ROW_FLOOR_PER_S * m->lscale);   /* and 1 lscale/s: a row alone */
  for (int r = 0; r < m->b; r++) {
    double norm = norms[r];
    if (norm > floor_a || !(fabs(d->a0[r]) > floor_a0)) continue;
    ap_core_msg(d, "system '%s': constraint row '%s' is contradictory at t = %.17g: its row of "
                "A has norm %.3g, below rank_rtol %.3g times the model's length scale %.3g m "
                "(no speed moves it), while its free term a0 is %.3g (more than %.3g): the "
                "drives demand a speed no free speed can give (|a0| / |A| = %.3g)", m->name,
                m->constraint_names[r], d->t, norm, d->rank_rtol, m->lscale, d->a0[r],
                floor_a0, norm > 0 ? fabs(d->a0[r]) / norm : HUGE_VAL);
    return AP_ERR_INCONSISTENT;
  }
  return AP_OK;
}
