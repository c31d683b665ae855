/* Ridders' extrapolated central differences (C. J. F. Ridders, "Accurate computation of F'(x)
 * and F'(x) F''(x)", Advances in Engineering Software 4 (1982) 75-76).
 *
 * For one column j of the Jacobian of a vector function: central differences
 * D(h) = (f(x + h e_j) - f(x - h e_j)) / (2h) at h_i = h / 1.4^i, i = 0..NTAB-1, form the first
 * column of a Neville tableau; since D(h) = f' + c2 h^2 + c4 h^4 + ..., each further column
 * eliminates one power of h^2: T[i][p] = (T[i][p-1] c^p - T[i-1][p-1]) / (c^p - 1), c = 1.4^2.
 * The error estimate of an entry is the larger of its distances to the two entries it was made
 * from; each component keeps the entry with the least estimate. A component stops when the
 * newest diagonal entry differs from the previous one by more than SAFE times its best
 * estimate: round-off has taken over. The estimate is what the tests compare against: the true
 * error of a smooth component is below it (measured in tests/test_linearize.c).
 * Round-off: two tableau entries can agree by chance far below the round-off of the differences
 * they come from, so the estimate is never less than the round-off of the entry chosen: with
 * function values accurate to epsf relative or to noise_c absolute (the caller's model or
 * measurement), the difference at the smallest step h_i it uses carries
 * max(epsf (|f+| + |f-|), 4 noise_c) / (2 h_i), and Neville's weights at level p
 * amplify it by prod_{j<=p} (c^j + 1) / (c^j - 1) (3.1, 5.2, 6.9, ... 8.5).
 * Steps are made exact in binary (the difference (x + h) - (x - h) is what divides). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "analyze/analyze_int.h"

#define NTAB 10
#define CON 1.4
#define CON2 (CON * CON)
#define SAFE 2.0

size_t ap_an_ridders_scratch(int m) { return (size_t)(2 * NTAB + 6) * (size_t)(m > 0 ? m : 1); }

/* col (m) = (f(x + h e_j) - f(x - h e_j)) / (x_j+ - x_j-); fp, fm: m scratch each. */
/* col (m) = (f(x + h e_j) - f(x - h e_j)) / (x_j+ - x_j-); fp, fm: m scratch each; rnd (m):
 * the round-off of each component, max(epsf (|f+| + |f-|), 4 noise) / (x_j+ - x_j-). */
static int central(ap_an_fn fn, void *user, double *x, int j, double h, double epsf,
                   const double *noise, int m, double *col, double *fp, double *fm,
                   double *rnd) {
  double xj = x[j], xp = xj + h, xm = xj - h;
  x[j] = xp;
  int rc = fn(x, fp, user);
  x[j] = xm;
  if (rc == AP_OK) rc = fn(x, fm, user);
  x[j] = xj;
  if (rc != AP_OK) return rc;
  double den = xp - xm;
  for (int c = 0; c < m; c++)
    col[c] = (fp[c] - fm[c]) / den,
    rnd[c] = fmax(epsf * (fabs(fp[c]) + fabs(fm[c])), noise ? 4.0 * noise[c] : 0.0) / den;
  return AP_OK;
}

int ap_an_ridders(ap_an_fn fn, void *user, int n, double *x, int j, double h, double epsf,
                  const double *noise, int m, double *df, double *err, double *scratch) {
  (void)n;
  double *prev = scratch, *cur = prev + (size_t)NTAB * m, *fp = cur + (size_t)NTAB * m;
  double *fm = fp + m, *active = fm + m, *rnd = active + m, *best = rnd + m;
  int rc = central(fn, user, x, j, h, epsf, noise, m, prev, fp, fm, rnd);
  if (rc != AP_OK) return rc;
  for (int c = 0; c < m; c++) df[c] = prev[c], best[c] = HUGE_VAL, active[c] = 1.0;
  for (int i = 1; i < NTAB; i++) {
    h /= CON;
    rc = central(fn, user, x, j, h, epsf, noise, m, cur, fp, fm, rnd);
    if (rc != AP_OK) return rc;
    double fac = CON2, amp = 1.0;
    for (int p = 1; p <= i; p++, fac *= CON2) {
      double *tp = cur + (size_t)p * m, *tl = cur + (size_t)(p - 1) * m;
      const double *tu = prev + (size_t)(p - 1) * m;
      amp *= (fac + 1.0) / (fac - 1.0);
      for (int c = 0; c < m; c++) {
        tp[c] = (tl[c] * fac - tu[c]) / (fac - 1.0);
        double e = fmax(fabs(tp[c] - tl[c]), fabs(tp[c] - tu[c]));
        if (active[c] != 0.0 && e <= best[c])
          best[c] = e, df[c] = tp[c], err[c] = fmax(e, amp * rnd[c]);
      }
    }
    int any = 0;
    for (int c = 0; c < m; c++) {
      double jump = fabs(cur[(size_t)i * m + c] - prev[(size_t)(i - 1) * m + c]);
      if (active[c] != 0.0 && jump >= SAFE * best[c]) active[c] = 0.0;
      any |= active[c] != 0.0;
    }
    if (!any) break;
    double *t = prev;
    prev = cur, cur = t;
  }
  return AP_OK;
}

/* ---- noise ---------------------------------------------------------------------------------
 * Sixth differences of equally spaced values, D_i = sum_k (-1)^k C(6, k) f_{i+k}: for
 * independent noise of deviation s each has deviation s sqrt(sum C(6, k)^2) = s sqrt(924); the
 * noise is the root mean square of the AP_AN_NOISE_PTS - 6 differences over sqrt(924). (After
 * J. J. More and S. M. Wild, "Estimating computational noise", SIAM J. Sci. Comput. 33 (2011),
 * which picks the order adaptively; the sixth is enough for the smooth rates here.) */
int ap_an_noise(ap_an_fn fn, void *user, int n, const double *x, int m, double *noise,
                double *scratch) {
  static const double c6[7] = {1, -6, 15, -20, 15, -6, 1};
  const int np = AP_AN_NOISE_PTS;
  double *f = scratch, *xs = f + (size_t)np * m;
  for (int i = 0; i < np; i++) {
    for (int j = 0; j < n; j++) {   /* a fixed direction with entries of both signs */
      double pj = ((j * 7 + 3) % 5 - 2.0) / 2.0;
      if (pj == 0.0) pj = 0.75;
      xs[j] = x[j] + i * 1e-5 * pj * fmax(1.0, fabs(x[j]));
    }
    int rc = fn(xs, f + (size_t)i * m, user);
    if (rc != AP_OK) return rc;
  }
  for (int c = 0; c < m; c++) {
    double ss = 0.0;
    for (int i = 0; i + 6 < np; i++) {
      double d = 0.0;
      for (int k = 0; k <= 6; k++) d += c6[k] * f[(size_t)(i + k) * m + c];
      ss += d * d;
    }
    noise[c] = sqrt(ss / (np - 6) / 924.0);
  }
  return AP_OK;
}
