/* Contact modes of rolling contacts: the rows each mode drops, and the Coulomb force of the
 * sliding ones with their normal forces solved together with the accelerations (model/
 * con_friction.h; docs/scenes.md "Friction, slip and lift-off").
 *
 * Sliding contact j has slip velocity s_j = (t1 . (vP - Vg), t2 . (vP - Vg)) = T_j [v; 1], T_j
 * its two tangent rows (kept before they are zeroed), and friction force -mu_k F_n,j s^_j at
 * the material contact point, i.e. the generalized force F_n,j f_j with f_j = -mu_k T_j^T s^_j
 * (s^_j = s_j / |s_j|, or the driver's slip direction while |s_j| is round-off). With the
 * active rows A (the reactions A^T lambda, lambda's entry n_j the normal force F_n,j):
 *
 *     g v' = Q - h + A^T lambda + sum_j f_j F_n,j,      A v' = gamma
 *  => lambda = lambda0 - sum_j u_j F_n,j,   S = A g^-1 A^T,
 *     lambda0 = S^-1 (gamma - A g^-1 (Q - h)),   u_j = S^-1 A g^-1 f_j,
 *     (I + U) F_n = lambda0_n,                   U_ij = (u_j)_{n_i}.
 *
 * Then Q += sum_j f_j F_n,j and the Appell solve gives the same v'. For one contact 1 + u is
 * the Painleve indicator: with it <= 0 the sliding motion has no solution or two (Painleve's
 * paradox) and the evaluation stops, saying so; with several, I + U must have positive leading
 * minors (elimination without pivoting). Active rows that repeat others (the two sideways rows
 * of one axle) are left out of S (their share of the reactions is carried by the rows they
 * repeat; v' is unchanged); a sliding contact's normal row that depends on the others is
 * refused (its F_n is not unique). A sphere has u = 0 (its friction has no moment about
 * its centre along the normal).
 *
 * A wheel under a planar chassis has no normal row (it vanishes there: the joint holds the
 * chassis up); its F_n is its load N_j(v', lambda) (model/loads.c), affine in the
 * accelerations and multipliers. A unit F_n,i moves them by (g^-1 f_i - X u_i, -u_i), X =
 * g^-1 A^T, so the loads are N = N0 + B F_n with B_ji the change of N_j it makes (evaluated
 * exactly, the load being affine), and such a row of the system above reads
 * (I - B)_j F_n = N0_j: the loads are solved with the accelerations, not lagged. They are
 * unique for three non-collinear contacts; with four or more rigid ones a sliding wheel stops
 * the run as on a free chassis (statically indeterminate). Cost: only while a contact
 * slides; a model without modes has an empty block and never calls this. Double build only. */
#include <math.h>
#include <string.h>

#include "model/con_friction.h"

/* The friction direction of a sliding contact (docs/scenes.md "Slip direction near zero
 * slip"): s_ref (its slip direction at the last accepted step, or the onset's) while
 * |s| <= sig = FR_PIN (1 + max |v_i|) (round-off); beyond, in the second pass of
 * ap_cfr_friction, along s + wt g with g = -F* / (mu_k F_n) (F* the sticking force of the
 * first pass) and wt = FR_FOLLOW sig times a weight that is 1 while |g| >= 1 (the sticking force
 * at or beyond the cone), 0 below 1 - FR_BAND (0.9), and times max(0, cos(g, s_ref)) (a slip that
 * decays towards sticking keeps s / |s|). Held at the onset's direction, a slip that started
 * at 0 grew across it as the needed force turned, and the friction jumped onto s / |s| once
 * |s| outgrew round-off, where every stepper stalled (the car after breakaway with
 * mu_kinetic = mu). */
#define FR_PIN 1e-13
#define FR_FOLLOW 1e5
#define FR_BAND 1e-1   /* a smoothing width, not an accuracy: see below */
/* FR_BAND does not follow from the tolerance. It is the width, in |g| (a ratio of forces), over
 * which the weight turns on, so that f stays continuous in the state; whatever its value the
 * friction leaves s / |s| by at most sig FR_FOLLOW / |s| rad, so it matters only while the slip
 * is within a few sig of 0. A width from the tolerance (1000 rtol, as the settle's band) would
 * make the direction turn by O(1) over a change of |g| of 1e-5: a near-discontinuity in f that
 * the steppers resolve by rejecting steps (with 1e-3, bdf failed on the car after its third
 * slip; with 0.1 it runs). The quantity that sets the accuracy is sig FR_FOLLOW
 * (1e-8 (1 + max |v_i|)). */
#define FR_HEAD 8   /* mode, F_n, slip direction (2), direction of the last friction (2), gamma of
                       the tangential rows (2) */
static size_t fr_stride(const ap_bmodel *M) { return FR_HEAD + 2 * ((size_t)M->k + 1); }

static double *block(const ap_bmodel *M, const double *S, const ap_mcon *c) {
  return (double *)S + M->off_fric + (size_t)c->fric * fr_stride(M);
}

size_t ap_cfr_scratch_size(const ap_bmodel *M) {
  if (!M->nfric) return 0;
  size_t k = (size_t)M->k, b = (size_t)M->b, nf = (size_t)M->nfric;
  return nf * fr_stride(M) + k * k + k * b + b * b + 2 * k + 4 * b + b * nf + k * nf +
         nf * nf + 2 * nf + 3 * k + 2 * nf + (M->nwheel ? 2 * k + 2 * b + nf : 0);
}

int ap_cfr_mode(const ap_bmodel *M, const double *S, const ap_mcon *c) {
  return (int)block(M, S, c)[0];
}

void ap_cfr_set_mode(const ap_bmodel *M, double *S, const ap_mcon *c, int mode) {
  block(M, S, c)[0] = mode;
}

double *ap_cfr_slip_dir(const ap_bmodel *M, double *S, const ap_mcon *c) {
  return block(M, S, c) + 2;
}

double ap_cfr_normal_force(const ap_bmodel *M, const double *S, const ap_mcon *c) {
  return block(M, S, c)[1];
}

/* Row r of c dropped by its mode (a sliding wheel under a planar chassis keeps no row: its
 * row .z vanishes there, its F_n is its load). */
static int dropped(const ap_bmodel *M, const double *S, const ap_mcon *c, int r) {
  int mode = ap_cfr_mode(M, S, c);
  return mode == AP_CM_AIRBORNE ||
         (mode == AP_CM_SLIDING && (r != c->hrow || ap_bm_wheel_by_load(M, c)));
}

void ap_cfr_rows(const ap_bmodel *M, double *S, const ap_mcon *c, double *A, double *a0) {
  int k = M->k, b = M->b;
  double *T = block(M, S, c) + FR_HEAD;
  for (int r = 0; r < 2; r++) {
    for (int col = 0; col < k; col++) T[r * (k + 1) + col] = A[c->row + r + (size_t)col * b];
    T[r * (k + 1) + k] = a0[c->row + r];
  }
  if (ap_cfr_mode(M, S, c) == AP_CM_ROLLING) return;
  for (int r = 0; r < c->nrows; r++) {
    if (!dropped(M, S, c, r)) continue;
    for (int col = 0; col < k; col++) A[c->row + r + (size_t)col * b] = 0.0;
    a0[c->row + r] = 0.0;
  }
}

void ap_cfr_gamma(const ap_bmodel *M, const double *S, const ap_mcon *c, double *gamma) {
  if (ap_cfr_mode(M, S, c) == AP_CM_ROLLING) return;
  block(M, S, c)[6] = gamma[c->row], block(M, S, c)[7] = gamma[c->row + 1];
  for (int r = 0; r < c->nrows; r++)
    if (dropped(M, S, c, r)) gamma[c->row + r] = 0.0;
}

void ap_cfr_slip(const ap_bmodel *M, double *S, const ap_mcon *c, const double *v, double *s) {
  int k = M->k;
  const double *T = block(M, S, c) + FR_HEAD;
  for (int r = 0; r < 2; r++) {
    double x = T[r * (k + 1) + k];
    for (int col = 0; col < k; col++) x += T[r * (k + 1) + col] * v[col];
    s[r] = x;
  }
}

/* ---- small dense solves (column-major, n of a few dozen at most) --------------------------- */

static void chol_solve(int n, const double *L, double *x) {
  for (int i = 0; i < n; i++) {
    for (int p = 0; p < i; p++) x[i] -= L[i + (size_t)p * n] * x[p];
    x[i] /= L[i + (size_t)i * n];
  }
  for (int i = n - 1; i >= 0; i--) {
    for (int p = i + 1; p < n; p++) x[i] -= L[p + (size_t)i * n] * x[p];
    x[i] /= L[i + (size_t)i * n];
  }
}

/* M x = y by elimination without pivoting; the smallest pivot, or -1 at the first pivot
 * <= 1e-12 (then x is not written). */
static double solve_nopivot(int n, double *Mx, double *y) {
  double small = INFINITY;
  for (int j = 0; j < n; j++) {
    double p = Mx[j + (size_t)j * n];
    if (!(p > 1e-12)) return -1.0;
    small = fmin(small, p);
    for (int i = j + 1; i < n; i++) {
      double f = Mx[i + (size_t)j * n] / p;
      for (int c = j; c < n; c++) Mx[i + (size_t)c * n] -= f * Mx[j + (size_t)c * n];
      y[i] -= f * y[j];
    }
  }
  for (int i = n - 1; i >= 0; i--) {
    for (int c = i + 1; c < n; c++) y[i] -= Mx[i + (size_t)c * n] * y[c];
    y[i] /= Mx[i + (size_t)i * n];
  }
  return small;
}

/* ---- the sliding contacts' forces ------------------------------------------------------------ */

typedef struct fr_work {
  double *Lg, *X, *Sm, *y, *z, *rhs, *lam0, *U, *F, *Mp, *lamN, *act, *nidx, *drop;
  double *ex, *gs;                    /* (3 k) sticking forces' scratch, (2 nf) -F* / (mu F_n) */
  double *vd0, *vd, *lf0, *lf, *N0;   /* wheel loads: v', lambda (all rows), loads at F_n = 0 */
  int na, nrow;                       /* active rows; sliding contacts with a normal row */
} fr_work;

static fr_work carve(const ap_bmodel *M, double *S) {
  size_t k = (size_t)M->k, b = (size_t)M->b, nf = (size_t)M->nfric;
  fr_work w;
  w.Lg = S + M->off_fric + nf * fr_stride(M);
  w.X = w.Lg + k * k, w.Sm = w.X + k * b, w.y = w.Sm + b * b, w.z = w.y + k;
  w.rhs = w.z + k, w.lam0 = w.rhs + b, w.act = w.lam0 + b, w.U = w.act + b;
  w.F = w.U + b * nf, w.Mp = w.F + k * nf, w.lamN = w.Mp + nf * nf, w.nidx = w.lamN + nf;
  w.drop = w.nidx + nf;
  w.ex = w.drop + b, w.gs = w.ex + 3 * k;
  w.vd0 = w.gs + 2 * nf, w.vd = w.vd0 + k, w.lf0 = w.vd + k, w.lf = w.lf0 + b, w.N0 = w.lf + b;
  w.na = w.nrow = 0;
  return w;
}

/* The active rows (not dropped by a mode; a wheel's row .z under a planar chassis, zero up to
 * round-off, left out) into w->act, the sliding contacts' normal rows last
 * (so that a row that repeats others is dropped before them, see frictionless); the normal row
 * of sliding contact j (in the order of M->cons) at w->nidx[j], -1 for a wheel whose F_n is
 * its load; returns the number of sliding contacts. */
static int active_rows(const ap_bmodel *M, const double *S, fr_work *w) {
  int p = 0;
  for (int pass = 0; pass < 2; pass++)
    for (int ci = 0; ci < M->nc; ci++) {
      const ap_mcon *c = &M->cons[ci];
      int sliding = c->fric >= 0 && ap_cfr_mode(M, S, c) == AP_CM_SLIDING;
      if (pass && sliding) {
        int by_load = ap_bm_wheel_by_load(M, c);
        w->nidx[p++] = by_load ? -1 : w->na;
        if (!by_load) w->act[w->na++] = c->row + c->hrow, w->nrow++;
      }
      int zero_z = c->wheel >= 0 && ap_bm_wheel_by_load(M, c);   /* .z vanishes: planar */
      for (int r = 0; !pass && r < c->nrows; r++)
        if (!(c->fric >= 0 && dropped(M, S, c, r)) && !(sliding && r == c->hrow) &&
            !(zero_z && r == c->hrow))
          w->act[w->na++] = c->row + r;
    }
  return p;
}

/* Cholesky A = L L^T in the lower triangle, skipping the rows that repeat earlier ones (pivot
 * <= rel = 1e-12 of their diagonal: a wheel's sideways row that repeats the other wheel's on one
 * axle): such a row gets a unit diagonal and no coupling, drop[j] = 1, and its entries of every
 * right-hand side are zeroed (zero_dropped) so that its multiplier is 0. The rows it repeats
 * carry its share: the accelerations do not change. Returns the first dropped row at or after
 * `from`, or -1. With drop NULL (the metric g, rel 0) the first such row is returned at
 * once (not positive definite). */
static int chol_skip(int n, double *A, double *drop, int from, double rel) {
  int first = -1;
  for (int j = 0; j < n; j++) {
    double dj = A[j + (size_t)j * n], d0 = dj;
    for (int p = 0; p < j; p++) dj -= A[j + (size_t)p * n] * A[j + (size_t)p * n];
    int dep = !(dj > rel * d0);
    if (dep && !drop) return j;
    if (drop) drop[j] = dep;
    if (dep) {
      if (j >= from && first < 0) first = j;
      for (int p = 0; p < j; p++) A[j + (size_t)p * n] = 0.0;
      for (int i = j; i < n; i++) A[i + (size_t)j * n] = 0.0;
      A[j + (size_t)j * n] = 1.0;
      continue;
    }
    dj = sqrt(dj);
    A[j + (size_t)j * n] = dj;
    for (int i = j + 1; i < n; i++) {
      double x = A[i + (size_t)j * n];
      for (int p = 0; p < j; p++) x -= A[i + (size_t)p * n] * A[j + (size_t)p * n];
      A[i + (size_t)j * n] = x / dj;
    }
  }
  return first;
}

static void zero_dropped(const fr_work *w, double *x) {
  for (int a = 0; a < w->na; a++)
    if (w->drop[a] != 0.0) x[a] = 0.0;
}

/* Row a of the active rows of A dotted with x (k). */
static double arow_dot(const ap_bmodel *M, const ap_data *d, const fr_work *w, int a,
                       const double *x) {
  int r = (int)w->act[a];
  double s = 0.0;
  for (int j = 0; j < M->k; j++) s += d->A[r + (size_t)j * M->b] * x[j];
  return s;
}

/* w->Lg = chol(g), X = g^-1 A^T, Sm = chol(A g^-1 A^T), lam0. */
static int frictionless(const ap_model *m, ap_data *d, fr_work *w) {
  const ap_bmodel *M = ap_bm(m);
  int k = M->k, na = w->na;
  memcpy(w->Lg, d->g, sizeof(double) * (size_t)k * k);
  if (chol_skip(k, w->Lg, NULL, 0, 0.0) >= 0) {
    AP_BM_MSG(d, "model '%s': sliding contacts: the metric g is not positive definite at "
              "t = %.17g", m->name, d->t);
    return AP_ERR_SINGULAR;
  }
  for (int a = 0; a < na; a++) {
    double *x = w->X + (size_t)a * k;
    for (int j = 0; j < k; j++) x[j] = d->A[(int)w->act[a] + (size_t)j * M->b];
    chol_solve(k, w->Lg, x);
  }
  for (int a = 0; a < na; a++)
    for (int c = 0; c < na; c++)
      w->Sm[a + (size_t)c * na] = arow_dot(M, d, w, a, w->X + (size_t)c * k);
  if (chol_skip(na, w->Sm, w->drop, na - w->nrow, 1e-12) >= 0) {
    AP_BM_MSG(d, "model '%s': sliding contacts: a sliding contact's normal row depends on the "
              "other %d active constraint rows at t = %.17g (the normal forces are not unique: "
              "statically indeterminate contacts)", m->name, na - 1, d->t);
    return AP_ERR_SINGULAR;
  }
  for (int j = 0; j < k; j++) w->y[j] = d->Q[j] - d->h[j];
  chol_solve(k, w->Lg, w->y);
  for (int a = 0; a < na; a++)
    w->lam0[a] = d->gamma[(int)w->act[a]] - arow_dot(M, d, w, a, w->y);
  zero_dropped(w, w->lam0);
  chol_solve(na, w->Sm, w->lam0);
  return AP_OK;
}

/* The weight (0 ... 1) with which g = -F* / (mu_k F_n) turns a sliding contact's friction
 * off its slip (1 while |g| >= 1, 0 below 1 - FR_BAND or against dir, the slip's reference
 * direction): 0 for every contact means pass 1 of ap_cfr_friction would repeat pass 0. */
static double follow_weight(const double *g, const double *dir) {
  double ng = hypot(g[0], g[1]), cs = ng > 0 ? (g[0] * dir[0] + g[1] * dir[1]) / ng : 0.0;
  return fmin(fmax((ng - 1.0) / FR_BAND + 1.0, 0.0), 1.0) * fmax(cs, 0.0);
}

/* f_j of sliding contact c into F (k), u_j into U (na). */
static void coulomb(const ap_bmodel *M, ap_data *d, double *S, const ap_mcon *c, fr_work *w,
                    double *F, double *U, const double *g) {
  int k = M->k;
  double s[2], mu = c->def.mu_kinetic >= 0 ? c->def.mu_kinetic : c->def.mu, vmag = 0.0;
  ap_cfr_slip(M, S, c, d->v, s);
  for (int j = 0; j < k; j++) vmag = fmax(vmag, fabs(d->v[j]));
  double *dir = ap_cfr_slip_dir(M, S, c), sig = FR_PIN * (1.0 + vmag), ns = hypot(s[0], s[1]);
  if (g && ns > sig) {   /* while the sticking force is at or beyond the cone: |g| >= 1 */
    double wt = follow_weight(g, dir) * FR_FOLLOW * sig;
    s[0] += wt * g[0], s[1] += wt * g[1];
  }
  else if (ns <= sig) s[0] = dir[0], s[1] = dir[1];   /* round-off: the pinned direction */
  ns = hypot(s[0], s[1]);
  if (ns > 0) s[0] /= ns, s[1] /= ns;
  else s[0] = dir[0], s[1] = dir[1];
  dir[2] = s[0], dir[3] = s[1];   /* for ap_cfr_friction_force */
  const double *T = block(M, S, c) + FR_HEAD;
  for (int j = 0; j < k; j++) F[j] = -mu * (s[0] * T[j] + s[1] * T[k + 1 + j]);
  memcpy(w->z, F, sizeof(double) * (size_t)k);
  chol_solve(k, w->Lg, w->z);
  for (int a = 0; a < w->na; a++) U[a] = arow_dot(M, d, w, a, w->z);
  zero_dropped(w, U);
  chol_solve(w->na, w->Sm, U);
}

/* Wheels whose F_n is their load (under a planar chassis): v'0 = g^-1 (Q - h + A^T lambda0)
 * and lambda0 on every row (0 on the dropped ones) at F_n = 0, and each such wheel's load
 * there, N0. */
static int load_base(const ap_model *m, ap_data *d, fr_work *w, const ap_mcon *const *sl,
                     int p) {
  const ap_bmodel *M = ap_bm(m);
  int k = M->k;
  memcpy(w->vd0, w->y, sizeof(double) * (size_t)k);
  memset(w->lf0, 0, sizeof(double) * (size_t)M->b);
  for (int a = 0; a < w->na; a++) {
    for (int j = 0; j < k; j++) w->vd0[j] += w->X[(size_t)a * k + j] * w->lam0[a];
    w->lf0[(int)w->act[a]] = w->lam0[a];
  }
  for (int i = 0; i < p; i++) {
    if (w->nidx[i] >= 0) continue;
    int unique = 1, ci = (int)(sl[i] - M->cons);
    int rc = ap_bm_wheel_load_at(m, d, w->vd0, w->lf0, ci, &w->N0[i], &unique);
    if (rc != AP_OK) return rc;
    if (!unique) {
      AP_BM_MSG(d, "model '%s': contact '%s' slides under a planar chassis whose wheel loads "
                "are statically indeterminate (4 or more rigid contacts, or collinear ones) at "
                "t = %.17g: the normal forces are not unique: statically indeterminate "
                "contacts (give the wheels a suspension on a free chassis, docs/vehicles.md)",
                m->name, sl[i]->name, d->t);
      return AP_ERR_SINGULAR;
    }
  }
  return AP_OK;
}

/* Column j of I - B for the wheels whose F_n is their load: a unit F_n,j changes v' by
 * g^-1 f_j - X u_j (w->z holds g^-1 f_j) and lambda by -u_j, and load i by B_ij (exact: the
 * load is affine in v' and lambda). */
static int load_column(const ap_model *m, ap_data *d, fr_work *w, const ap_mcon *const *sl,
                       int p, int j) {
  const ap_bmodel *M = ap_bm(m);
  int k = M->k;
  const double *u = w->U + (size_t)j * w->na;
  memcpy(w->lf, w->lf0, sizeof(double) * (size_t)M->b);
  for (int i = 0; i < k; i++) w->vd[i] = w->vd0[i] + w->z[i];
  for (int a = 0; a < w->na; a++) {
    for (int i = 0; i < k; i++) w->vd[i] -= w->X[(size_t)a * k + i] * u[a];
    w->lf[(int)w->act[a]] -= u[a];
  }
  for (int i = 0; i < p; i++) {
    if (w->nidx[i] >= 0) continue;
    double L;
    int rc = ap_bm_wheel_load_at(m, d, w->vd, w->lf, (int)(sl[i] - M->cons), &L, NULL);
    if (rc != AP_OK) return rc;
    w->Mp[i + (size_t)j * p] = (i == j) - (L - w->N0[i]);
  }
  return AP_OK;
}

/* The sliding contacts' friction directions and normal forces (w->F, w->U, w->lamN): pass 0
 * along their slip (the pinned direction within round-off), pass 1 along
 * s + FR_FOLLOW sig w->gs (sticking). A status (the message set). */
static int normals(const ap_model *m, ap_data *d, double *S, fr_work *w,
                   const ap_mcon *const *sl, int p, int pass) {
  const ap_bmodel *M = ap_bm(m);
  int k = M->k, rc = AP_OK;
  if (p > w->nrow) rc = load_base(m, d, w, sl, p);
  for (int j = 0; rc == AP_OK && j < p; j++) {
    coulomb(M, d, S, sl[j], w, w->F + (size_t)j * k, w->U + (size_t)j * w->na,
            pass ? w->gs + 2 * j : NULL);
    if (p > w->nrow) rc = load_column(m, d, w, sl, p, j);
  }
  if (rc != AP_OK) return rc;
  for (int i = 0; i < p; i++) {
    int n = (int)w->nidx[i];
    w->lamN[i] = n >= 0 ? w->lam0[n] : w->N0[i];
    for (int j = 0; n >= 0 && j < p; j++)
      w->Mp[i + (size_t)j * p] = (i == j) + w->U[n + (size_t)j * w->na];
  }
  double m00 = w->Mp[0], small = solve_nopivot(p, w->Mp, w->lamN);
  if (small < 0) {
    AP_BM_MSG(d, "model '%s': contact '%s' slides in a state where the normal force has no "
              "solution or several (Painleve's paradox: 1 + u = %.6g <= 0, the friction "
              "pushes the contact into the ground harder than the normal force can resist) at "
              "t = %.17g: lower mu_kinetic or model the impact", m->name, sl[0]->name,
              p == 1 ? m00 : small, d->t);
    return AP_ERR_SINGULAR;
  }
  return AP_OK;
}

/* W = T P T^T (2 x 2, column-major) of a sliding contact (rows T, stride k + 1). */
static void delassus(const ap_bmodel *M, ap_data *d, fr_work *w, const double *T, double *W) {
  int k = M->k, na = w->na;
  double *z = w->ex + k, *pt = w->ex + 2 * k;
  for (int r = 0; r < 2; r++) {
    memcpy(z, T + r * (k + 1), sizeof(double) * (size_t)k);
    chol_solve(k, w->Lg, z);
    for (int a = 0; a < na; a++) w->rhs[a] = arow_dot(M, d, w, a, z);
    zero_dropped(w, w->rhs);
    chol_solve(na, w->Sm, w->rhs);
    memcpy(pt, z, sizeof(double) * (size_t)k);
    for (int a = 0; a < na; a++)
      for (int i = 0; i < k; i++) pt[i] -= w->X[(size_t)a * k + i] * w->rhs[a];
    for (int q = 0; q < 2; q++) {
      double x = 0.0;
      for (int i = 0; i < k; i++) x += T[q * (k + 1) + i] * pt[i];
      W[q + 2 * r] = x;
    }
  }
}

/* x = W^+ y for the symmetric 2 x 2 W (column-major): its eigenvalues below rel of the largest
 * left out (a tangential direction the contact cannot slip in: the other wheel of an axle
 * repeats its sideways row, and the force along it is not the contact's). -1 when W is 0. */
static int pinv_solve(const double *W, const double *y, double rel, double *x) {
  double a = W[0], b = 0.5 * (W[1] + W[2]), c = W[3];
  double tr = 0.5 * (a + c), disc = sqrt(0.25 * (a - c) * (a - c) + b * b);
  double l[2] = {tr + disc, tr - disc}, th = 0.5 * atan2(2.0 * b, a - c);
  double e[2][2] = {{cos(th), sin(th)}, {-sin(th), cos(th)}};
  if (!(l[0] > 0)) return -1;
  x[0] = x[1] = 0.0;
  for (int i = 0; i < 2; i++) {
    if (!(l[i] > rel * l[0])) continue;
    double p = (e[i][0] * y[0] + e[i][1] * y[1]) / l[i];
    x[0] += p * e[i][0], x[1] += p * e[i][1];
  }
  return 0;
}

/* The sticking force F* of each sliding contact at the solve of pass 0: the tangential force
 * that would make its slip acceleration s' = A_t v' - gamma_t vanish, all else alike,
 * F* = F - W^-1 s', F its friction there, W = T P T^T with P = g^-1 - X S^-1 X^T the
 * constrained response (its normal row active: F_n answers). Into w->gs: -F* / (mu_k F_n),
 * along which a slip of round-off size grows (of length 1 at the cone's edge). */
static void sticking(const ap_bmodel *M, ap_data *d, double *S, fr_work *w,
                     const ap_mcon *const *sl, int p) {
  int k = M->k, na = w->na;
  double *vd = w->ex, *z = w->ex + k;
  memcpy(vd, w->y, sizeof(double) * (size_t)k);
  for (int a = 0; a < na; a++)
    for (int i = 0; i < k; i++) vd[i] += w->X[(size_t)a * k + i] * w->lam0[a];
  for (int j = 0; j < p; j++) {   /* v' = y + X lam0 + sum_j (g^-1 f_j - X u_j) F_n,j */
    memcpy(z, w->F + (size_t)j * k, sizeof(double) * (size_t)k);
    chol_solve(k, w->Lg, z);
    for (int i = 0; i < k; i++) vd[i] += z[i] * w->lamN[j];
    for (int a = 0; a < na; a++)
      for (int i = 0; i < k; i++)
        vd[i] -= w->X[(size_t)a * k + i] * w->U[a + (size_t)j * na] * w->lamN[j];
  }
  for (int j = 0; j < p; j++) {
    const double *b = block(M, S, sl[j]), *T = b + FR_HEAD;
    double sa[2], W[4], *gs = w->gs + 2 * j;
    double mu = sl[j]->def.mu_kinetic >= 0 ? sl[j]->def.mu_kinetic : sl[j]->def.mu;
    double fmu = mu * w->lamN[j];
    for (int r = 0; r < 2; r++) {
      sa[r] = -b[6 + r];
      for (int i = 0; i < k; i++) sa[r] += T[r * (k + 1) + i] * vd[i];
    }
    delassus(M, d, w, T, W);
    double x[2];
    gs[0] = gs[1] = 0.0;
    if (!(fmu > 0) || pinv_solve(W, sa, fmax(1e-9, d->manifold_rtol), x) != 0) continue;
    gs[0] = b[4] + x[0] / fmu, gs[1] = b[5] + x[1] / fmu;   /* -F* / (mu F_n) */
  }
}

/* The sticking forces after pass 0 (sticking); 1 when some contact's friction follows them,
 * so that pass 1 changes the solve. */
static int follows(const ap_bmodel *M, ap_data *d, double *S, fr_work *w,
                   const ap_mcon *const *sl, int p) {
  sticking(M, d, S, w, sl, p);
  for (int j = 0; j < p; j++)
    if (follow_weight(w->gs + 2 * j, ap_cfr_slip_dir(M, S, sl[j])) > 0) return 1;
  return 0;
}

int ap_cfr_friction(const ap_model *m, ap_data *d, double *S) {
  const ap_bmodel *M = ap_bm(m);
  fr_work w = carve(M, S);
  int p = active_rows(M, S, &w), k = M->k;
  if (p == 0) return AP_OK;
  int rc = frictionless(m, d, &w);
  if (rc != AP_OK) return rc;
  const ap_mcon *sl[64];
  int ns = 0;
  for (int ci = 0; ci < M->nc && ns < 64; ci++)
    if (M->cons[ci].fric >= 0 && ap_cfr_mode(M, S, &M->cons[ci]) == AP_CM_SLIDING)
      sl[ns++] = &M->cons[ci];
  rc = normals(m, d, S, &w, sl, p, 0);
  if (rc == AP_OK && follows(M, d, S, &w, sl, p)) rc = normals(m, d, S, &w, sl, p, 1);
  if (rc != AP_OK) return rc;
  for (int j = 0; j < p; j++) {
    for (int i = 0; i < k; i++) d->Q[i] += w.F[(size_t)j * k + i] * w.lamN[j];
    block(M, S, sl[j])[1] = w.lamN[j];
  }
  return AP_OK;
}

double ap_cfr_contact_normal(const ap_model *m, const ap_data *d, const double *lam,
                             const ap_mcon *c) {
  const ap_bmodel *M = ap_bm(m);
  double fn = NAN;
  if (!ap_bm_wheel_by_load(M, c)) return lam[c->row + c->hrow];
  return ap_bm_wheel_load_at(m, d, d->vdot, lam, (int)(c - M->cons), &fn, NULL) == AP_OK ? fn
                                                                                    : NAN;
}

/* ---- choosing the modes from a state ------------------------------------------------------ */

int ap_cfr_unilateral(const ap_mcon *c) {
  return c->def.unilateral == 1 || (c->def.unilateral < 0 && c->def.mu >= 0);
}

int ap_body_contact_modes(const ap_model *m, ap_data *d, const double *v, double tol) {
  if (!ap_model_is_body_model(m) || !ap_core_data_ok(m, d) || !(tol > 0)) return AP_ERR_ARG;
  const ap_bmodel *M = ap_bm(m);
  if (M->nfric == 0) return 0;
  double *S = ap_bm_scratch(d), vmax = 0.0;
  int off = 0;
  ap_basis basis = d->basis;
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(m, d);
  d->basis = basis;
  if (rc != AP_OK) return rc;
  for (int i = 0; v && i < M->k; i++) vmax = fmax(vmax, fabs(v[i]));
  for (int ci = 0; ci < M->nc; ci++) {
    const ap_mcon *c = &M->cons[ci];
    if (c->fric < 0) continue;
    double sl[2] = {0, 0}, *dir = ap_cfr_slip_dir(M, S, c);
    if (v) ap_cfr_slip(M, S, c, v, sl);
    double ns = hypot(sl[0], sl[1]);
    int mode = AP_CM_ROLLING;
    if (ap_cfr_unilateral(c) && ap_contact_gap(M, S, c) > tol) mode = AP_CM_AIRBORNE;
    else if (c->def.mu >= 0 && ns > tol * (1.0 + vmax)) {
      mode = AP_CM_SLIDING;
      dir[0] = sl[0] / ns, dir[1] = sl[1] / ns;
    }
    ap_cfr_set_mode(M, S, c, mode);
    off += mode != AP_CM_ROLLING;
  }
  return off;
}

void ap_cfr_friction_force(const ap_bmodel *M, const double *S, const ap_mcon *c, double fn,
                           const double *t1, const double *t2, double *F) {
  if (ap_cfr_mode(M, S, c) != AP_CM_SLIDING) return;
  const double *b = block(M, S, c);
  double mu = c->def.mu_kinetic >= 0 ? c->def.mu_kinetic : c->def.mu;
  if (!t1) F[0] -= mu * fn * b[4], F[1] -= mu * fn * b[5];
  else
    for (int i = 0; i < 3; i++) F[i] -= mu * fn * (b[4] * t1[i] + b[5] * t2[i]);
}

void ap_cfr_coulomb(const ap_bmodel *M, const double *S, const ap_mcon *c, double *f) {
  const double *b = block(M, S, c), *T = b + FR_HEAD;
  double mu = c->def.mu_kinetic >= 0 ? c->def.mu_kinetic : c->def.mu;
  int k = M->k;
  for (int j = 0; j < k; j++) f[j] = -mu * (b[4] * T[j] + b[5] * T[k + 1 + j]);
}
