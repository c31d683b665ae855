/* Sweeps of eigenvalues over a parameter, and their characteristic points.
 *
 * Tracking: the eigenvalues at p_i are matched to those at p_{i-1} by the assignment of least
 * total distance (Hungarian algorithm) to the positions predicted by linear extrapolation from
 * p_{i-2} and p_{i-1}: continuity, not sort order, so crossing branches keep their identity.
 *
 * Characteristic points:
 *  - crossing: a tracked eigenvalue of one kind (real, or the upper member of a pair) whose
 *    real part changes sign between two values above the zero threshold, with at most values
 *    of the same kind within the threshold in between (a crossing exactly at a sweep value);
 *  - meeting: a tracked eigenvalue real at one end and complex at the other, with its partner,
 *    the pair's spread above the zero threshold at one end at least (round-off splits a multiple
 *    eigenvalue, e.g. a double zero, into a tiny pair and back: that is no event).
 * Each is located by the Illinois variant of regula falsi on a smooth function of the
 * eigenvalues in a cluster around the predicted event (centre c, radius rho from the interval's
 * ends): for a crossing, Re of the cluster's sum; for a meeting, 2 s2 - s1^2 with
 * s_j = sum (lambda - c)^j (= (lambda_1 - lambda_2)^2 for a lone pair: positive while both are
 * real, negative once complex). Power sums of a cluster are smooth in the matrix even where its
 * eigenvalues are defective and individually ill-conditioned (a meeting point is such a place:
 * a rolling disk at its critical speed has a triple eigenvalue 0), which is what makes the root
 * accurate to the round-off of the matrix rather than to its square root. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"

#define ROOT_ITER 100

/* ---- assignment ------------------------------------------------------------------------- */

/* Minimum-cost perfect matching of an n x n cost matrix C (row-major): row i -> col[i].
 * Kuhn-Munkres with potentials, O(n^3). ws: 4 (n + 1) doubles, iw: 3 (n + 1) ints. */
static void assign(int n, const double *C, int *col, double *ws, int *iw) {
  double *u = ws, *v = u + n + 1, *minv = v + n + 1;
  int *p = iw, *way = p + n + 1, *used = way + n + 1;
  for (int j = 0; j <= n; j++) u[j] = v[j] = 0.0, p[j] = way[j] = 0;
  for (int i = 1; i <= n; i++) {
    int j0 = 0;
    p[0] = i;
    for (int j = 0; j <= n; j++) minv[j] = HUGE_VAL, used[j] = 0;
    do {
      used[j0] = 1;
      int i0 = p[j0], j1 = 0;
      double delta = HUGE_VAL;
      for (int j = 1; j <= n; j++) {
        if (used[j]) continue;
        double cur = C[(size_t)(i0 - 1) * n + (j - 1)] - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= n; j++)
        if (used[j]) u[p[j]] += delta, v[j] -= delta;
        else minv[j] -= delta;
      j0 = j1;
    } while (p[j0] != 0);
    do {
      int j1 = way[j0];
      p[j0] = p[j1], j0 = j1;
    } while (j0);
  }
  for (int j = 1; j <= n; j++) col[p[j] - 1] = j - 1;
}

/* ---- the sweep state ---------------------------------------------------------------------- */

typedef struct sw {
  ap_lin_eig_fn fn;
  void *user;
  int n;
  double *re, *im, *C, *ws;   /* re, im: n scratch for trial evaluations */
  int *col, *iw;
  double zthr;
  char *msg;
  size_t msg_len;
} sw;

static int eval(sw *S, double p) {
  int rc = S->fn(p, S->n, S->re, S->im, S->user);
  if (rc != AP_OK && S->msg) snprintf(S->msg, S->msg_len, "eigenvalues at p = %.17g failed", p);
  return rc;
}

/* Order the trial eigenvalues (S->re, S->im) to follow pre (n re, n im) + t (pre - prev). */
static void follow(sw *S, const double *pr, const double *pi, const double *qr,
                   const double *qi, double t, double *outr, double *outi) {
  int n = S->n;
  for (int a = 0; a < n; a++) {
    double er = pr[a] + (qr ? t * (pr[a] - qr[a]) : 0.0);
    double ei = pi[a] + (qi ? t * (pi[a] - qi[a]) : 0.0);
    for (int b = 0; b < n; b++) S->C[(size_t)a * n + b] = hypot(er - S->re[b], ei - S->im[b]);
  }
  assign(n, S->C, S->col, S->ws, S->iw);
  for (int a = 0; a < n; a++) outr[a] = S->re[S->col[a]], outi[a] = S->im[S->col[a]];
}

/* ---- root functions ------------------------------------------------------------------------ */

typedef struct event {
  ap_lin_event kind;
  double c0r, c0i, c1r, c1i;  /* predicted centre at the interval's ends */
  double rho;                 /* cluster radius */
} event;

/* The smooth function of the cluster at p; *cr, *ci: the cluster's mean (the event's value). */
static int root_fn(sw *S, const event *E, double a, double b, double p, double *g, double *cr,
                   double *ci) {
  int rc = eval(S, p);
  if (rc != AP_OK) return rc;
  double t = b > a ? (p - a) / (b - a) : 0.0;
  double c_r = E->c0r + t * (E->c1r - E->c0r), c_i = E->c0i + t * (E->c1i - E->c0i);
  double s1r = 0, s1i = 0, s2r = 0, m = 0;
  for (int j = 0; j < S->n; j++) {
    double dr = S->re[j] - c_r, di = S->im[j] - c_i;
    if (hypot(dr, di) > E->rho) continue;
    s1r += dr, s1i += di, s2r += dr * dr - di * di, m += 1;
  }
  if (E->kind == AP_LIN_CROSSING) *g = s1r + m * c_r;   /* Re of the cluster's sum */
  else *g = 2.0 * s2r - (s1r * s1r - s1i * s1i);
  *cr = c_r + (m > 0 ? s1r / m : 0.0), *ci = c_i + (m > 0 ? s1i / m : 0.0);
  return AP_OK;
}

/* Illinois regula falsi on [a, b] with g(a) ga, g(b) gb of opposite signs. */
static int locate(sw *S, const event *E, double a, double b, double ga, double gb, double ptol,
                  ap_lin_point *pt) {
  double lo = a, hi = b, glo = ga, ghi = gb, p = 0.5 * (a + b), g = 0, cr = 0, ci = 0;
  int side = 0;
  for (int it = 0; it < ROOT_ITER && hi - lo > ptol; it++) {
    p = (lo * ghi - hi * glo) / (ghi - glo);
    if (!(p > lo && p < hi)) p = 0.5 * (lo + hi);
    int rc = root_fn(S, E, a, b, p, &g, &cr, &ci);
    if (rc != AP_OK) return rc;
    if (g == 0.0) {
      lo = hi = p;
      break;
    }
    if ((g > 0) == (ghi > 0)) {
      hi = p, ghi = g;
      if (side == 1) glo *= 0.5;
      side = 1;
    } else {
      lo = p, glo = g;
      if (side == -1) ghi *= 0.5;
      side = -1;
    }
  }
  pt->p = 0.5 * (lo + hi), pt->p_err = 0.5 * (hi - lo);
  int rc = root_fn(S, E, a, b, pt->p, &g, &cr, &ci);
  pt->re = cr, pt->im = fabs(ci);
  return rc;
}

/* ---- events in one interval ----------------------------------------------------------------- */

static int add_point(ap_lin_sweep *out, const ap_lin_point *pt) {
  ap_lin_point *np = realloc(out->points, sizeof *np * (size_t)(out->npoints + 1));
  if (!np) return AP_ERR_NOMEM;
  out->points = np;
  out->points[out->npoints++] = *pt;
  return AP_OK;
}

/* The partner of meeting row a: the row complex where a is complex (nearest the conjugate of a)
 * and real where a is real. */
static int partner(const sw *S, const double *r0, const double *i0, const double *r1,
                   const double *i1, int a, int complex_end) {
  const double *cr = complex_end ? r1 : r0, *ci = complex_end ? i1 : i0;
  const double *ri = complex_end ? i0 : i1;
  int best = -1;
  double bd = HUGE_VAL;
  for (int b = 0; b < S->n; b++) {
    if (b == a || ri[b] != 0.0 || ci[b] == 0.0) continue;
    double d = hypot(cr[b] - cr[a], ci[b] + ci[a]);
    if (d < bd) bd = d, best = b;
  }
  return best;
}

/* Meetings in [p_{i-1}, p_i]: row j real at one end and complex at the other, j the upper
 * member at its complex end, with its partner. */
static int meetings(sw *S, ap_lin_sweep *out, int i, double ptol) {
  int n = S->n;
  double a = out->p[i - 1], b = out->p[i];
  const double *r0 = out->re + (size_t)(i - 1) * n, *i0 = out->im + (size_t)(i - 1) * n;
  const double *r1 = out->re + (size_t)i * n, *i1 = out->im + (size_t)i * n;
  for (int j = 0; j < n; j++) {
    int real0 = i0[j] == 0.0, real1 = i1[j] == 0.0;
    if (real0 == real1 || (real0 ? i1[j] : i0[j]) < 0) continue;
    int q = partner(S, r0, i0, r1, i1, j, real0);
    if (q < 0) continue;
    double mr0 = 0.5 * (r0[j] + r0[q]), mr1 = 0.5 * (r1[j] + r1[q]);
    double h0 = 0.5 * hypot(r0[j] - r0[q], i0[j] - i0[q]);
    double h1 = 0.5 * hypot(r1[j] - r1[q], i1[j] - i1[q]);
    if (fmax(h0, h1) <= S->zthr) continue;   /* a multiple zero split by round-off */
    event E = {AP_LIN_MEETING, mr0, 0.0, mr1, 0.0, 2.0 * fmax(h0, h1) + S->zthr};
    double g0 = real0 ? 4 * h0 * h0 : -4 * h0 * h0, g1 = real1 ? 4 * h1 * h1 : -4 * h1 * h1;
    ap_lin_point pt = {AP_LIN_MEETING, 0, 0, 0, 0, j, real0};
    int rc = locate(S, &E, a, b, g0, g1, ptol, &pt);
    if (rc == AP_OK) rc = add_point(out, &pt);
    if (rc != AP_OK) return rc;
  }
  return AP_OK;
}

/* Crossings of row j: between two values of the same kind (real, or upper member of a pair)
 * with real parts of opposite signs above the zero threshold, with only values of that kind
 * and real parts within the threshold in between (a crossing exactly at a sweep value). */
static int crossings(sw *S, ap_lin_sweep *out, int j, double ptol) {
  int n = S->n, last = -1, kind = 0;
  for (int i = 0; i < out->count; i++) {
    double re = out->re[j + (size_t)i * n], im = out->im[j + (size_t)i * n];
    int k = im == 0.0 ? 1 : im > 0.0 ? 2 : 3;   /* real, upper, lower */
    if (k != kind || k == 3) last = -1, kind = k;
    if (k == 3 || fabs(re) <= S->zthr) continue;
    if (last >= 0 && (re > 0) != (out->re[j + (size_t)last * n] > 0)) {
      double r0 = out->re[j + (size_t)last * n], i0 = out->im[j + (size_t)last * n];
      event E = {AP_LIN_CROSSING, r0, i0, re, im, 0.5 * hypot(re - r0, im - i0) + S->zthr};
      if (k == 2) E.rho = fmin(E.rho, 0.5 * fmin(i0, im));
      ap_lin_point pt = {AP_LIN_CROSSING, 0, 0, 0, 0, j, re > r0};
      int rc = locate(S, &E, out->p[last], out->p[i], r0, re, ptol, &pt);
      if (rc == AP_OK) rc = add_point(out, &pt);
      if (rc != AP_OK) return rc;
    }
    last = i;
  }
  return AP_OK;
}

/* ---- the sweep ------------------------------------------------------------------------------ */

void ap_lin_sweep_free(ap_lin_sweep *s) {
  if (!s) return;
  free(s->p);
  free(s->re);
  free(s->points);
  memset(s, 0, sizeof *s);
}

static int track(sw *S, ap_lin_sweep *out) {
  int n = S->n;
  for (int i = 0; i < out->count; i++) {
    int rc = eval(S, out->p[i]);
    if (rc != AP_OK) return rc;
    double *r = out->re + (size_t)i * n, *im = out->im + (size_t)i * n;
    if (i == 0) {
      memcpy(r, S->re, sizeof *r * (size_t)n), memcpy(im, S->im, sizeof *im * (size_t)n);
      continue;
    }
    const double *pr = r - n, *pi = im - n, *qr = i > 1 ? pr - n : NULL, *qi = i > 1 ? pi - n : NULL;
    double t = i > 1 ? (out->p[i] - out->p[i - 1]) / (out->p[i - 1] - out->p[i - 2]) : 0.0;
    follow(S, pr, pi, qr, qi, t, r, im);
  }
  return AP_OK;
}

int ap_lin_sweep_run(ap_lin_eig_fn fn, void *user, int n, const double *p, int count,
                     double ptol, double zero_tol, ap_lin_sweep *out, char *msg,
                     size_t msg_len) {
  if (!out) return AP_ERR_ARG;
  memset(out, 0, sizeof *out);
  if (!fn || !p || n < 1 || count < 1 || !(ptol > 0) || !(zero_tol >= 0)) return AP_ERR_ARG;
  for (int i = 1; i < count; i++)
    if (!(p[i] > p[i - 1])) return AP_ERR_ARG;
  sw S = {fn, user, n, NULL, NULL, NULL, NULL, NULL, NULL, 0.0, msg, msg_len};
  size_t nn = (size_t)n;
  out->n = n, out->count = count;
  out->p = malloc(sizeof *out->p * (size_t)count);
  out->re = malloc(sizeof *out->re * 2 * nn * (size_t)count);
  S.re = malloc(sizeof *S.re * (nn * (nn + 6) + 8));
  S.iw = malloc(sizeof *S.iw * (4 * nn + 8));
  int rc = out->p && out->re && S.re && S.iw ? AP_OK : AP_ERR_NOMEM;
  if (rc == AP_OK) {
    out->im = out->re + nn * (size_t)count;
    S.im = S.re + nn, S.C = S.im + nn, S.ws = S.C + nn * nn, S.col = S.iw + 3 * (nn + 1);
    memcpy(out->p, p, sizeof *p * (size_t)count);
    rc = track(&S, out);
  }
  double big = 1.0;
  for (size_t i = 0; rc == AP_OK && i < nn * (size_t)count; i++)
    big = fmax(big, hypot(out->re[i], out->im[i]));
  S.zthr = zero_tol * big;
  for (int i = 1; rc == AP_OK && i < count; i++) rc = meetings(&S, out, i, ptol);
  for (int j = 0; rc == AP_OK && j < n; j++) rc = crossings(&S, out, j, ptol);
  free(S.re), free(S.iw);
  if (rc != AP_OK) ap_lin_sweep_free(out);
  return rc;
}

/* ---- the speed sweep of a linearizer ------------------------------------------------------- */

typedef struct speed_ctx {
  ap_lin *L;
  const int *sel;
  int ns, drop;
} speed_ctx;

static int speed_eig(double s, int n, double *re, double *im, void *user) {
  speed_ctx *c = user;
  int stop = c->L->poll ? c->L->poll(c->L->poll_user) : 0;
  if (stop) {
    ap_an_msg(c->L, "interrupted at speed %.17g (the poll function returned %d)", s, stop);
    return AP_ERR_INTERRUPTED;
  }
  int rc = ap_lin_operating_point(c->L, s);
  if (rc == AP_OK) rc = ap_lin_linearize(c->L);
  if (rc == AP_OK) rc = ap_lin_eigen(c->L, c->sel, c->ns, c->drop);
  if (rc != AP_OK) return rc;
  if (c->L->ne != n) {
    ap_an_msg(c->L, "the subsystem has %d eigenvalues at speed %g, %d before", c->L->ne, s, n);
    return AP_ERR_INCONSISTENT;
  }
  memcpy(re, c->L->ere, sizeof *re * (size_t)n), memcpy(im, c->L->eim, sizeof *im * (size_t)n);
  return AP_OK;
}

int ap_lin_sweep_speed(ap_lin *L, const double *s, int count, const int *sel, int ns,
                       int drop_cyclic, double ptol, ap_lin_sweep *out) {
  if (!L || !s || count < 1 || !out) return AP_ERR_ARG;
  speed_ctx c = {L, sel, ns, drop_cyclic};
  int rc = ap_lin_operating_point(L, s[0]);   /* the size of the subsystem at the start */
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc == AP_OK) rc = ap_lin_eigen(L, sel, ns, drop_cyclic);
  if (rc != AP_OK) return rc;
  char msg[256];
  rc = ap_lin_sweep_run(speed_eig, &c, L->ne, s, count, ptol, 1e-6, out, msg, sizeof msg);
  if (rc != AP_OK && L->msg[0] == '\0') ap_an_msg(L, "%s", msg);
  return rc;
}

void ap_lin_set_poll(ap_lin *L, int (*poll)(void *user), void *user) {
  if (!L) return;
  L->poll = poll, L->poll_user = user;
}
