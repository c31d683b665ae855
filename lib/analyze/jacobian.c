/* The Jacobian A = dF/dx of the reduced equations at the operating point x0, column by column,
 * each entry with an error estimate (ap_lin_linearize): by complex step, exact to round-off,
 * or by Ridders' extrapolated differences (ridders.c).
 *
 * Complex step. F is evaluated on x0 + i h e_j through the complex-step builds of reduced.c,
 * chart_map.c, lib/core and lib/model (linalg/scalar.h), h = AP_CS_STEP = 1e-100; then
 * A[:, j] = Im F / h. Truncation: F(x0 + i h e) = F + i h F' e - h^2 F'' e e / 2 + ..., and
 * h^2 = 1e-200 is below the last bit of every real part, so the imaginary part carries F' e
 * alone (the arithmetic is that of dual numbers). There is no difference of nearby values, so
 * no cancellation by the step; what remains is round-off: of the tangent operations on the
 * imaginary parts, and of the real intermediate values they are taken at (F'(x~) for the
 * rounded x~). The estimate measures both: the column is evaluated a second time, at x0 moved
 * by 4 ulps of max(1, |x0_i|) in every component (signs alternating: a point no double
 * evaluation tells apart) with the step 3h (3 is not a power of two, so every imaginary part
 * rounds differently), and
 *     E_ij = 2 |A1_ij - A2_ij| + 4 eps |A1_ij|,
 * twice the spread of the two (one sample of a difference of two roundings) and at least four
 * ulps of the entry itself. tests/test_lin_cs.c checks it against closed forms (rolling disk)
 * and against Ridders' on every example scene.
 *
 * Which: def.method; under AP_LIN_AUTO the complex step unless the model cannot be evaluated
 * that way (ap_core_has_cs: math-level systems, user constraints, user effects) or a complex
 * evaluation fails (a state function that gives no partial derivatives, found only then);
 * then Ridders', and L->fallback says why. The complex data and scratch are allocated at the
 * first use. */
#include <complex.h>
#undef I
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "linalg/linalg.h"

/* ---- the complex-step workspace ---------------------------------------------------------- */

void ap_an_ws_cs_free(ap_lin *L) {
  ap_data_free_cs(L->ws_cs.d);
  free(L->ws_cs.delta);
  memset(&L->ws_cs, 0, sizeof L->ws_cs);
  L->xc = L->fc = NULL;
}

/* The complex mirror of the double workspace (sizes as linearize.c's alloc_all). */
static int ws_cs_alloc(ap_lin *L) {
  if (L->ws_cs.d) return AP_OK;
  int n = L->n, k = L->k, b = L->b, np = L->nphi, nc = L->ch.nc;
  size_t mk = (size_t)(k > nc ? k : nc), mb = (size_t)(b > np ? b : np), nv = (size_t)nc + k;
  size_t big = mk * mk + (size_t)np * n + (size_t)b * k + 1;
  an_ws_cs *w = &L->ws_cs;
  struct { double _Complex **p; size_t len; } part[] = {
      {&w->delta, nc}, {&w->dq, (size_t)n * nc}, {&w->Jh, (size_t)np * nc}, {&w->phi, np + 1},
      {&w->Phi_q, big}, {&w->Au, big}, {&w->Bu, big}, {&w->dd, big}, {&w->b0u, mk + 1},
      {&w->F, mb * mk + 1}, {&w->tau, mk + mb + 1}, {&w->u, k}, {&w->full, nv},
      {&w->work, L->nwork}, {&L->xc, nv}, {&L->fc, nv}};
  size_t np_ = sizeof part / sizeof *part, total = 0;
  for (size_t i = 0; i < np_; i++) total += part[i].len + 1;
  double _Complex *p = calloc(total, sizeof *p);
  int rc = p ? ap_data_create_cs(L->m, &w->d) : AP_ERR_NOMEM;
  if (rc != AP_OK) {
    free(p);
    memset(w, 0, sizeof *w);
    return rc;
  }
  for (size_t i = 0; i < np_; i++) *part[i].p = p, p += part[i].len + 1;
  return AP_OK;
}

/* ---- columns ------------------------------------------------------------------------------- */

/* Column j (nx entries) of the complex step at x (real, nx), step s: Im F(x + i s e_j) / s. */
static int cs_column(ap_lin *L, const double *x, int j, double s, double *col) {
  int nx = L->nx;
  for (int i = 0; i < nx; i++) L->xc[i] = x[i];
  L->xc[j] += s * _Complex_I;
  int rc = ap_an_rates_cs(L, L->xc, L->fc);
  for (int i = 0; rc == AP_OK && i < nx; i++) col[i] = cimag(L->fc[i]) / s;
  return rc;
}

/* A and its estimate by complex step (the file's note). */
static int by_complex_step(ap_lin *L) {
  int nx = L->nx, rc = ws_cs_alloc(L);
  if (rc != AP_OK) return rc;
  ap_core_copy_partition(L->d, L->ws_cs.d);
  double *x1 = L->f1, *col2 = L->f1 + nx;   /* f1 holds 2 nx */
  for (int i = 0; i < nx; i++)
    x1[i] = L->x0[i] + (i % 2 ? -4.0 : 4.0) * DBL_EPSILON * fmax(1.0, fabs(L->x0[i]));
  for (int j = 0; j < nx && rc == AP_OK; j++) {
    double *A = L->A + (size_t)j * nx, *E = L->Aerr + (size_t)j * nx;
    rc = cs_column(L, L->x0, j, AP_CS_STEP, A);
    if (rc == AP_OK) rc = cs_column(L, x1, j, 3.0 * AP_CS_STEP, col2);
    for (int i = 0; rc == AP_OK && i < nx; i++)
      E[i] = 2.0 * fabs(A[i] - col2[i]) + 4.0 * DBL_EPSILON * fabs(A[i]);
  }
  return rc;
}

static int rates_fn(const double *x, double *f, void *user) {
  return ap_an_rates((ap_lin *)user, x, f);
}

/* A and its estimate by Ridders' method, the round-off floor from the measured noise of F. */
static int by_ridders(ap_lin *L) {
  int nx = L->nx;
  double *x = L->f1, *noise = L->noise;   /* not touched by ap_an_rates */
  int rc = ap_an_noise(rates_fn, L, nx, L->x0, nx, noise, L->ridders);
  for (int j = 0; j < nx && rc == AP_OK; j++) {
    memcpy(x, L->x0, sizeof *x * (size_t)nx);
    double h = L->def.h0 * fmax(1.0, fabs(L->x0[j]));
    rc = ap_an_ridders(rates_fn, L, nx, x, j, h, AP_AN_EPSF, noise, nx, L->A + (size_t)j * nx,
                       L->Aerr + (size_t)j * nx, L->ridders);
  }
  return rc;
}

int ap_an_jacobian(ap_lin *L) {
  L->fallback[0] = '\0';
  L->used = AP_LIN_RIDDERS;
  if (L->def.method == AP_LIN_RIDDERS) return by_ridders(L);
  char why[sizeof L->fallback];
  if (!ap_core_has_cs(L->m, why, sizeof why)) {
    if (L->def.method == AP_LIN_COMPLEX_STEP) {
      ap_an_msg(L, "no complex-step derivatives: %s", why);
      return AP_ERR_UNSUPPORTED;
    }
    snprintf(L->fallback, sizeof L->fallback, "%s", why);
    return by_ridders(L);
  }
  int rc = by_complex_step(L);
  if (rc == AP_OK) {
    L->used = AP_LIN_COMPLEX_STEP;
    return AP_OK;
  }
  if (rc == AP_ERR_NOMEM) return rc;
  if (rc == AP_ERR_UNSUPPORTED)   /* found at evaluation: a state function without partials */
    ap_an_msg(L, "no complex-step derivatives: %s", L->ws_cs.d->msg);
  if (L->def.method == AP_LIN_COMPLEX_STEP) return rc;
  /* AP_LIN_AUTO: the double evaluation at x0 succeeded a moment ago, so Ridders' can go on */
  snprintf(L->fallback, sizeof L->fallback, "%s", L->msg);
  L->msg[0] = '\0';
  return by_ridders(L);
}
