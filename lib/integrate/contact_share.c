/* The determinate part of a rolling contact's friction force (docs/scenes.md "Friction, slip
 * and lift-off", "Consistent modes"). When a combination n1 a_x + n2 a_y of contact c's two
 * tangential rows lies in the span of rows that carry any force (the rows of constraints
 * without a friction limit, except a unilateral contact's normal row: the other wheel of an
 * axle repeats c's sideways row), the force along n = (n1, n2) is not c's to carry: adding
 * mu n to c's multipliers and taking the same generalized force off those rows changes
 * nothing, and the reactions' split of it (minimum norm in minimal and projected mode, the
 * rows IDA keeps in DAE mode) is arbitrary. The friction cone then holds the rest,
 *     F_t,det = F_t - (F_t . n) n,
 * the least friction c needs among all the splits. (A wheel on one axle with a perfectly rough
 * one: seed 16 of the tester stuck, found the min-norm half of the axle's sideways force
 * outside its cone, slid along it, and stuck again within a microsecond, every microsecond.)
 *
 * Layout: the carrier rows of A (b x k, column-major, the data's rows as the current modes
 * make them: a dropped row is zero) are orthonormalized by modified Gram-Schmidt (twice) into
 * the scratch, c's two tangential rows projected off them; the 2 x 2 Gram matrix of the
 * residuals has a null vector n where its eigenvalue is below rel^2 of the rows' squared
 * length, rel the larger of SHARE_RTOL and the data's manifold_rtol (100 (rtol + 1e-12) in a
 * run: the rows repeat each other on the holonomic manifold only, and a stepper's trial
 * states lie off it by about the tolerance). No allocation: the scratch is the contact modes' (contact_modes.c). */
#include <math.h>
#include <string.h>

#include "integrate/contact_int.h"

#define SHARE_RTOL 1e-9

/* Row r of A (b x k) into x (k). */
static void row_of(const double *A, int b, int k, int r, double *x) {
  for (int j = 0; j < k; j++) x[j] = A[r + (size_t)j * b];
}

static double dot(int k, const double *x, const double *y) {
  double s = 0.0;
  for (int j = 0; j < k; j++) s += x[j] * y[j];
  return s;
}

/* x minus its projection on the m orthonormal rows of Qm (twice, for round-off). */
static void project_off(int k, int m, const double *Qm, double *x) {
  for (int pass = 0; pass < 2; pass++)
    for (int i = 0; i < m; i++) {
      double p = dot(k, Qm + (size_t)i * k, x);
      for (int j = 0; j < k; j++) x[j] -= p * Qm[(size_t)i * k + j];
    }
}

/* Row r of constraint o carries any force (no friction limit; not a unilateral normal). */
static int carrier(const ap_mcon *o, int r) {
  if (o->fric < 0) return 1;
  if (o->def.mu >= 0) return 0;
  return !(ap_cfr_unilateral(o) && r == o->hrow);
}

void ap_drv_cm_determinate(ap_sim *s, const ap_mcon *c, double *ft) {
  const ap_bmodel *M = ap_bm(s->m);
  const double *A = s->d->A;
  int b = s->b, k = s->k, m = 0;
  double *Qm = ap_drv_cm_share_scratch(s), *r1 = Qm + (size_t)b * k, *r2 = r1 + k;
  if (!Qm || !(c->def.mu >= 0)) return;
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *o = &M->cons[ci];
    for (int r = 0; o != c && r < o->nrows; r++) {
      if (!carrier(o, r)) continue;
      double *x = Qm + (size_t)m * k;
      row_of(A, b, k, o->row + r, x);
      double n0 = sqrt(dot(k, x, x));
      project_off(k, m, Qm, x);
      double nx = sqrt(dot(k, x, x));
      if (!(nx > SHARE_RTOL * n0)) continue;   /* zero (dropped) or dependent */
      for (int j = 0; j < k; j++) x[j] /= nx;
      m++;
    }
  }
  if (m == 0) return;
  row_of(A, b, k, c->row, r1), row_of(A, b, k, c->row + 1, r2);
  double scale = fmax(dot(k, r1, r1), dot(k, r2, r2));
  project_off(k, m, Qm, r1), project_off(k, m, Qm, r2);
  double g11 = dot(k, r1, r1), g12 = dot(k, r1, r2), g22 = dot(k, r2, r2);
  double tr = 0.5 * (g11 + g22), det = g11 * g22 - g12 * g12;
  double disc = sqrt(fmax(tr * tr - det, 0.0)), lmin = tr - disc, lmax = tr + disc;
  double rel = fmax(SHARE_RTOL, s->d->manifold_rtol), tol = rel * rel * scale;
  if (!(scale > 0) || lmin > tol) return;
  if (lmax <= tol) {   /* both rows carried by others */
    ft[0] = ft[1] = 0.0;
    return;
  }
  double n[2] = {g12, lmin - g11};   /* (G - lmin I) n = 0 */
  if (fabs(g11 - lmin) < fabs(g22 - lmin)) n[0] = lmin - g22, n[1] = g12;
  double nn = hypot(n[0], n[1]);
  if (!(nn > 0)) n[0] = g11 <= g22 ? 1.0 : 0.0, n[1] = 1.0 - n[0], nn = 1.0;
  n[0] /= nn, n[1] /= nn;
  double p = ft[0] * n[0] + ft[1] * n[1];
  ft[0] -= p * n[0], ft[1] -= p * n[1];
}
