/* The Appell solve on a structured model (structured.h, docs/large.md): the stages of
 * forward.c with g, A and B known only as operators and the basis in independent blocks.
 *
 *     G_t e''_t = B_t^T (Q - h - g w)_t,    G_t = B_t^T g B_t,    v' = w + sum_t P_t B_t e''_t
 *
 * Per block t: the speeds kidx (rows of B_t), the free speeds lidx (its e' entries), B_t and G_t
 * from the model's position stage; the core gathers, factors each G_t (Cholesky, native or
 * LAPACK by size as on the dense path), solves and scatters. Partition: the model chooses it
 * (the dependent speeds body by body) in ap_st_partition and keeps it in ap_st_position; the
 * orthonormal basis of projected mode is replaced by a partition chosen at every position stage:
 * projected mode's state is v, and both the projection v <- b0 + B G^-1 B^T g (v - b0) and
 * v' = B e'' + w do not depend on which basis spans the null space. Consistency of redundant
 * rows: the same relative 1e-8 as forward.c; rows redundant only on the holonomic manifold (the
 * model tells them at the partition, d->redundant_manifold) at accepted states against
 * manifold_rtol, as partition.c. Nothing here allocates after ap_st_create. */
#include "core/structured.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "linalg/linalg.h"

static const double consistency_rtol = 1e-8;

/* The state's doubles, one table X(field, count) in block order (core/arena.h): Gf first (it
 * owns the block). */
#define ST_DOUBLES(X)                                                                      \
  X(st->Gf, gcap) X(st->tk1, k) X(st->tk2, k) X(st->tl, k) X(st->te, k) X(st->tb, b)       \
  X(st->tm, b)
#define ST_ADD(f_, c_) ap_arena_add(&L, #f_, (c_));
#define ST_CARVE(f_, c_) f_ = p + L.e[i++].offset;

int ap_st_create(const ap_model *m, const ap_ops *ops, ap_st **out) {
  *out = NULL;
  size_t k = (size_t)m->k, b = (size_t)(m->b > 0 ? m->b : 1), gcap = 0;
  ap_st *st = calloc(1, sizeof *st);
  if (!st) return AP_ERR_NOMEM;
  st->m = m, st->ops = ops;
  st->ws = ops->ws_create(ops->ctx, &gcap);
  ap_arena L;
  ap_arena_init(&L, "structured state", sizeof(double), 0);
  ST_DOUBLES(ST_ADD)
  double *p = st->ws ? calloc(L.total, sizeof(double)) : NULL;
  if (!p) {
    if (st->ws) ops->ws_free(st->ws);
    free(st);
    return AP_ERR_NOMEM;
  }
  int i = 0;
  ST_DOUBLES(ST_CARVE)
  *out = st;
  return AP_OK;
}

void ap_st_free(ap_st *st) {
  if (!st) return;
  if (st->ws) st->ops->ws_free(st->ws);
  free(st->Gf);
  free(st);
}

static double max_abs(const double *x, int n) {
  double mx = 0.0;
  for (int i = 0; i < n; i++) mx = fmax(mx, fabs(x[i]));
  return mx;
}

/* ---- blocks --------------------------------------------------------------------------------- */

/* y[lidx] = B_t^T x[kidx] for every block. */
static void apply_Bt(const ap_sblocks *bl, const double *x, double *y) {
  for (int t = 0; t < bl->n; t++) {
    int kt = bl->kofs[t + 1] - bl->kofs[t], lt = bl->lofs[t + 1] - bl->lofs[t];
    const double *Bt = bl->B + bl->bofs[t];
    const int *ki = bl->kidx + bl->kofs[t];
    for (int j = 0; j < lt; j++) {
      double s = 0.0;
      for (int r = 0; r < kt; r++) s += Bt[r + (size_t)j * kt] * x[ki[r]];
      y[bl->lidx[bl->lofs[t] + j]] = s;
    }
  }
}

/* y[kidx] += B_t x[lidx] for every block. */
static void apply_B_add(const ap_sblocks *bl, const double *x, double *y) {
  for (int t = 0; t < bl->n; t++) {
    int kt = bl->kofs[t + 1] - bl->kofs[t], lt = bl->lofs[t + 1] - bl->lofs[t];
    const double *Bt = bl->B + bl->bofs[t];
    const int *ki = bl->kidx + bl->kofs[t];
    for (int j = 0; j < lt; j++) {
      double xj = x[bl->lidx[bl->lofs[t] + j]];
      for (int r = 0; r < kt; r++) y[ki[r]] += Bt[r + (size_t)j * kt] * xj;
    }
  }
}

/* Factor every G_t into st->Gf; AP_ERR_SINGULAR with the block in *bad. */
static int factor_G(const ap_sblocks *bl, ap_st *st, int *bad) {
  for (int t = 0; t < bl->n; t++) {
    int lt = bl->lofs[t + 1] - bl->lofs[t];
    double *Gt = st->Gf + bl->gofs[t];
    memcpy(Gt, bl->G + bl->gofs[t], sizeof(double) * (size_t)lt * lt);
    if (ap_la_chol(lt, Gt, NULL, NULL, NULL) != AP_OK) {
      *bad = t;
      return AP_ERR_SINGULAR;
    }
  }
  return AP_OK;
}

/* x[lidx] <- G_t^-1 x[lidx] with the factors (tl: scratch). */
static void solve_G(const ap_sblocks *bl, ap_st *st, double *x) {
  for (int t = 0; t < bl->n; t++) {
    int lt = bl->lofs[t + 1] - bl->lofs[t];
    const int *li = bl->lidx + bl->lofs[t];
    for (int j = 0; j < lt; j++) st->tl[j] = x[li[j]];
    ap_la_chol_solve(lt, st->Gf + bl->gofs[t], st->tl);
    for (int j = 0; j < lt; j++) x[li[j]] = st->tl[j];
  }
}

/* ---- stages --------------------------------------------------------------------------------- */

/* The residual of x (a0 or gamma) outside the rows' range against the largest row's terms plus
 * the largest floor (core/core.h: t_r = |x_r| + sum_c |A_rc y_c|, (x, y) = (a0, v) or (gamma,
 * v'); f_r from sum_c |A_rc| vscale_c): at most max|x| is checked first; beyond it the terms
 * and floors come from the operator A y + a0 with its magnitudes (ops->amul: the sum of each
 * row's terms' magnitudes, |a0_r| included, which is taken out or swapped for |gamma_r|), two
 * sweeps, only then. */
static double floor_geom(const ap_model *m, ap_data *d, ap_st *st) {
  double g = 0.0;
  for (int c = 0; c < m->k; c++) st->tk2[c] = m->vscale ? m->vscale[c] : 1.0;
  st->ops->amul(st->ws, d, st->tk2, st->tb, st->tm);   /* sum_c |A_rc| vscale_c, + |a0_r| */
  for (int r = 0; r < m->b; r++) g = fmax(g, st->tm[r] - fabs(d->a0[r]));
  return g;
}

static int judge(const ap_model *m, ap_data *d, ap_st *st, int of_gamma) {
  const double *x = of_gamma ? d->gamma : d->a0;
  double fl = of_gamma ? AP_ROW_FLOOR_PER_S2 : AP_ROW_FLOOR_PER_S, terms = 0.0;
  double resid = of_gamma ? d->resid_gamma : d->resid_a0;
  /* below max|x| plus half the floor of the last partition (A's magnitudes move little
   * between partitions): consistent, no sweep */
  double scale = AP_TERMS_TINY + max_abs(x, m->b) + 0.5 * fl * st->floor_geom;
  if (!(resid > consistency_rtol * scale)) return AP_OK;
  double floor = fl * floor_geom(m, d, st);
  st->ops->amul(st->ws, d, of_gamma ? d->vdot : d->v, st->tb, st->tm);   /* the terms t_r */
  for (int r = 0; r < m->b; r++)
    terms = fmax(terms, st->tm[r] + (of_gamma ? fabs(x[r]) - fabs(d->a0[r]) : 0));
  scale = fmax(scale, AP_TERMS_TINY + terms + floor);   /* max t_r + max f_r */
  if (!(resid > consistency_rtol * scale)) return AP_OK;
  ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant and inconsistent at "
              "t = %.17g (%s residual %.3g, more than %.3g of the terms of the rows)", m->name,
              m->b - d->rank, m->b, d->t, of_gamma ? "gamma" : "a0", resid, consistency_rtol);
  return AP_ERR_INCONSISTENT;
}

/* Rows redundant only on the holonomic manifold (d->redundant_manifold; the model's position
 * stage tells them at the partition): as ap_core_judge_redundant, their residuals against
 * manifold_rtol times the size of the terms of A v + a0 (resp. A v' = gamma), |A x| from the
 * operator's per-row magnitudes. */
static double row_scale(const ap_model *m, ap_data *d, ap_st *st, const double *x,
                        const double *y, double floor) {
  double mag = 0.0;
  st->ops->amul(st->ws, d, x, st->tb, st->tm);
  for (int s = 0; s < m->b; s++) mag = fmax(mag, st->tm[s]);
  return floor + max_abs(y, m->b) + mag;
}

int ap_st_judge_redundant(const ap_model *m, ap_data *d, ap_st *st) {
  if (!d->redundant_manifold) return AP_OK;
  double sa = row_scale(m, d, st, d->v, d->a0, AP_ROW_FLOOR_PER_S * st->floor_geom), tol = d->manifold_rtol;
  double sg = row_scale(m, d, st, d->vdot, d->gamma, AP_ROW_FLOOR_PER_S2 * st->floor_geom);
  int bad_a = d->resid_a0 > tol * sa, bad_g = !bad_a && d->resid_gamma > tol * sg;
  if (!bad_a && !bad_g) return AP_OK;
  ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant (inconsistent along the "
              "motion: %s by %.3g relative, more than manifold_rtol %.3g) at t = %.17g",
              m->name, d->redundant, m->b, bad_a ? "the rows drifted apart" : "gamma",
              bad_a ? d->resid_a0 / sa : d->resid_gamma / sg, tol, d->t);
  return AP_ERR_INCONSISTENT;
}

int ap_st_partition(const ap_model *m, ap_data *d, ap_st *st) {
  d->cnt.partitions++;
  int rc = st->ops->position(m, d, st->ws, AP_ST_SELECT_PARTITION);
  if (rc != AP_OK) return rc;
  st->chosen = 1;
  st->floor_geom = floor_geom(m, d, st);
  if (d->redundant_manifold) {   /* as partition.c: manifold_rtol against the rows' terms */
    double tol = d->manifold_rtol * row_scale(m, d, st, d->v, d->a0,
                                              AP_ROW_FLOOR_PER_S * st->floor_geom);
    if (d->resid_a0 > tol) {
      ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant and inconsistent at "
                  "t = %.17g (a0 residual %.3g, more than %.3g)", m->name, d->redundant, m->b,
                  d->t, d->resid_a0, tol);
      return AP_ERR_INCONSISTENT;
    }
  } else {
    rc = judge(m, d, st, 0);
  }
  /* a row that no speed moves: named as on the dense path (partition.c) */
  if (rc == AP_ERR_INCONSISTENT) ap_core_refuse_vanishing_rows(m, d);
  if (rc == AP_OK && d->redundant > 0)
    ap_core_msg(d, "system '%s': %d of %d constraint rows are redundant (consistent, dropped%s) "
                "at t = %.17g; residual %.3g", m->name, d->redundant, m->b,
                !d->redundant_manifold ? "" : d->redundant_manifold == d->redundant
                ? "; only where the loops and contacts close"
                : "; some only where the loops and contacts close", d->t, d->resid_a0);
  return rc;
}

int ap_st_position(const ap_model *m, ap_data *d, ap_st *st) {
  d->cnt.position++;
  /* projected mode (and no basis): any valid partition; minimal mode: the one chosen */
  int select = d->basis != AP_BASIS_PARTITIONED || !st->chosen;
  int rc = st->ops->position(m, d, st->ws, select ? AP_ST_SELECT_STAGE : 0);
  d->cnt.qr += m->b > 0;
  d->rcond_R = 1.0;
  if (rc != AP_OK || d->redundant_manifold ||
      ((const ap_scratch *)d->internal)->judge_at_accepted)
    return rc;
  return judge(m, d, st, 0);   /* else judged at accepted states */
}

void ap_st_speeds(const ap_model *m, ap_data *d, ap_st *st) {
  ap_sblocks bl;
  st->ops->blocks(st->ws, &bl);
  memcpy(d->v, d->b0, sizeof(double) * (size_t)m->k);
  apply_B_add(&bl, d->e, d->v);
}

int ap_st_velocity(const ap_model *m, ap_data *d, ap_st *st) {
  d->cnt.velocity++;
  if (d->speeds_from_e && d->basis == AP_BASIS_PARTITIONED) ap_st_speeds(m, d, st);
  int rc = st->ops->velocity(m, d, st->ws);
  if (rc == AP_OK) ap_core_add_inputs(m, d);
  if (rc == AP_OK) rc = ap_core_check_finite(m, d, "bias", d->h, m->k, 1);
  if (rc == AP_OK) rc = ap_core_check_finite(m, d, "force", d->Q, m->k, 1);
  if (rc == AP_OK) rc = ap_core_check_finite(m, d, "gamma", d->gamma, m->b, 1);
  if (rc == AP_OK && !d->redundant_manifold &&
      !((const ap_scratch *)d->internal)->judge_at_accepted)   /* as dense */
    rc = judge(m, d, st, 1);
  return rc;
}

static int singular(const ap_model *m, ap_data *d, const ap_sblocks *bl, int bad,
                    const char *where) {
  ap_core_msg(d, "system '%s': block %d of G = B^T g B (%d x %d) is not positive definite at "
              "t = %.17g%s: the metric g is not positive definite on the free speeds", m->name,
              bad, bl->lofs[bad + 1] - bl->lofs[bad], bl->lofs[bad + 1] - bl->lofs[bad], d->t,
              where);
  return AP_ERR_SINGULAR;
}

int ap_st_acceleration(const ap_model *m, ap_data *d, ap_st *st) {
  int k = m->k, bad = -1;
  ap_sblocks bl;
  d->cnt.acceleration++;
  st->ops->blocks(st->ws, &bl);
  st->ops->gmul(st->ws, d->w, st->tk1);                   /* g w */
  for (int i = 0; i < k; i++) st->tk2[i] = d->Q[i] - d->h[i] - st->tk1[i];
  apply_Bt(&bl, d->Q, d->Phi);                            /* Phi = B^T Q */
  apply_Bt(&bl, st->tk2, d->edd);                         /* B^T (Q - h - g w) */
  d->rcond_G = 1.0;
  if (factor_G(&bl, st, &bad) != AP_OK) return singular(m, d, &bl, bad, "");
  solve_G(&bl, st, d->edd);
  int rc = ap_core_check_finite(m, d, "Appell solve (e'')", d->edd, d->l, 1);
  if (rc != AP_OK) return rc;
  memcpy(d->vdot, d->w, sizeof(double) * (size_t)k);     /* v' = B e'' + w */
  apply_B_add(&bl, d->edd, d->vdot);
  st->ops->nmul(st->ws, d->q, d->v, d->qdot);             /* q' = N v */
  return AP_OK;
}

int ap_st_reactions(const ap_model *m, ap_data *d, ap_st *st) {
  d->cnt.reactions++;
  if (m->b == 0) return AP_OK;
  st->ops->gmul(st->ws, d->vdot, st->tk1);               /* g v' + h - Q */
  for (int i = 0; i < m->k; i++) st->tk1[i] += d->h[i] - d->Q[i];
  st->ops->reactions(st->ws, st->tk1, d->lambda);
  return ap_core_check_finite(m, d, "reactions (lambda)", d->lambda, m->b, 1);
}

/* ---- projection and diagnostics ------------------------------------------------------------ */

/* From the residual, as core/project.c: r = A v + a0, d0 with A d0 + r = 0, the correction
 * (I - B G^-1 B^T g) d0 (the g-nearest). v is not touched when r is zero, and otherwise moves by
 * a correction computed from r alone: no O(eps |v|) rounding per projection accumulates. */
int ap_st_project_here(const ap_model *m, ap_data *d, ap_st *st, double *v, double *change) {
  int k = m->k, bad = -1;
  ap_sblocks bl;
  if (change) *change = 0.0;
  if (m->b == 0) return AP_OK;
  st->ops->amul(st->ws, d, v, st->tb, st->tm);            /* r = A v + a0 */
  /* a residual within the rounding bound of its row leaves v as it is: the row is a dot
   * product of 6 entries of a twist, itself a sum of a few transported terms, so its error is
   * at most about 16 eps times the sum of the magnitudes (the dense path's compensated dot
   * product gets 4 eps) */
  int any = 0;
  for (int s = 0; s < m->b; s++) any |= fabs(st->tb[s]) > 16.0 * DBL_EPSILON * st->tm[s];
  if (!any) return AP_OK;
  st->ops->blocks(st->ws, &bl);
  st->ops->psolve(st->ws, st->tb, st->tk1);               /* d0: A d0 + r = 0 */
  st->ops->gmul(st->ws, st->tk1, st->tk2);                /* g d0 */
  apply_Bt(&bl, st->tk2, st->te);
  if (factor_G(&bl, st, &bad) != AP_OK) return singular(m, d, &bl, bad, " (speed projection)");
  solve_G(&bl, st, st->te);
  for (int i = 0; i < k; i++) st->te[i] = -st->te[i];
  apply_B_add(&bl, st->te, st->tk1);                      /* the correction d0 - B G^-1 B^T g d0 */
  for (int i = 0; i < k; i++) v[i] += st->tk1[i];
  st->ops->gmul(st->ws, st->tk1, st->tk2);
  double c2 = 0.0;
  for (int i = 0; i < k; i++) c2 += st->tk1[i] * st->tk2[i];
  if (change) *change = sqrt(fmax(c2, 0.0));
  return AP_OK;
}

void ap_st_project_tangent(const ap_model *m, ap_data *d, ap_st *st, double *x) {
  (void)d;   /* the factors live in st */
  ap_sblocks bl;
  st->ops->blocks(st->ws, &bl);
  st->ops->gmul(st->ws, x, st->tk1);
  apply_Bt(&bl, st->tk1, st->te);
  solve_G(&bl, st, st->te);
  memset(x, 0, sizeof(double) * (size_t)m->k);
  apply_B_add(&bl, st->te, x);
}

double ap_st_residual(const ap_data *d, ap_st *st, const double *v) {
  if (d->b == 0) return 0.0;
  st->ops->amul(st->ws, d, v, st->tb, NULL);
  return max_abs(st->tb, d->b);
}

double ap_st_energy(const ap_data *d, ap_st *st, const double *v) {
  st->ops->gmul(st->ws, v, st->tk1);
  double e = 0.0;
  for (int i = 0; i < d->k; i++) e += v[i] * st->tk1[i];
  return 0.5 * e;
}
