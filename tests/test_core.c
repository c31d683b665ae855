/* Tests of the core: the Appell solve against Gauss's principle (KKT conditions), basis
 * independence, Christoffel terms, reactions, redundant and inconsistent rows, callbacks that
 * fail on purpose, model validation, initial-speed projection, a row that no speed moves,
 * quasi-velocities, and no heap allocation inside ap_forward. */
#define _GNU_SOURCE
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "check.h"
#include "refsys.h"
#include "testrand.h"

/* ---- counting allocations: this program's malloc wraps glibc's (alloc.h) ----------------- */
#include "alloc.h"

/* ---- a random algebraic system: constant g, A, a0, gamma, h, Q at one state -------------- */
enum { RK = 6, RB = 4 };
typedef struct rand_sys {
  double g[RK * RK], A[RB * RK], a0[RB], gam[RB], h[RK], Q[RK];
  int b;
  int fail_metric, fail_force;   /* 1: NaN, 2: return > 0, 3: return < 0 */
} rand_sys;

static uint64_t rng_state = 88172645463325252ULL;
static double urand(void) { return ap_test_srand(&rng_state); } /* in [-1, 1) */

static int rs_metric(double t, const double *q, double *g, void *u) {
  (void)t, (void)q;
  rand_sys *s = u;
  memcpy(g, s->g, sizeof s->g);
  if (s->fail_metric == 1) g[7] = NAN;
  return s->fail_metric == 2 ? 1 : s->fail_metric == 3 ? -1 : 0;
}
static int rs_bias(double t, const double *q, const double *v, double *h, void *u) {
  (void)t, (void)q, (void)v;
  memcpy(h, ((rand_sys *)u)->h, sizeof(double) * RK);
  return 0;
}
static int rs_force(double t, const double *q, const double *v, double *Q, void *u) {
  (void)q, (void)v;
  rand_sys *s = u;
  memcpy(Q, s->Q, sizeof(double) * RK);
  if (s->fail_force == 1 && t > 1.0) Q[2] = NAN;
  return s->fail_force == 2 ? 1 : s->fail_force == 3 ? -7 : 0;
}
static int rs_constraint(double t, const double *q, double *A, double *a0, void *u) {
  (void)t, (void)q;
  rand_sys *s = u;
  for (int j = 0; j < RK; j++)
    for (int i = 0; i < s->b; i++) A[i + j * s->b] = s->A[i + j * RB];
  memcpy(a0, s->a0, sizeof(double) * (size_t)s->b);
  return 0;
}
static int rs_gamma(double t, const double *q, const double *v, double *gam, void *u) {
  (void)t, (void)q, (void)v;
  rand_sys *s = u;
  memcpy(gam, s->gam, sizeof(double) * (size_t)s->b);
  return 0;
}

static const char *row_names[RB] = {"left-wheel", "right-wheel", "skate", "axle-copy"};

static void rand_fill(rand_sys *s, int b, int redundant) {
  memset(s, 0, sizeof *s);
  s->b = b;
  double M[RK * RK];
  for (int i = 0; i < RK * RK; i++) M[i] = urand();
  for (int i = 0; i < RK; i++)       /* g = M^T M + I: SPD */
    for (int j = 0; j < RK; j++) {
      double acc = i == j ? 1.0 : 0.0;
      for (int p = 0; p < RK; p++) acc += M[p + i * RK] * M[p + j * RK];
      s->g[i + j * RK] = acc;
    }
  for (int i = 0; i < RB * RK; i++) s->A[i] = urand();
  for (int i = 0; i < RB; i++) s->a0[i] = urand(), s->gam[i] = urand();
  for (int i = 0; i < RK; i++) s->h[i] = urand(), s->Q[i] = urand();
  if (redundant) {   /* last row = row0 + 2 row1, consistent */
    int r = b - 1;
    for (int j = 0; j < RK; j++) s->A[r + j * RB] = s->A[0 + j * RB] + 2 * s->A[1 + j * RB];
    s->a0[r] = s->a0[0] + 2 * s->a0[1];
    s->gam[r] = s->gam[0] + 2 * s->gam[1];
  }
}

static ap_model *rand_model(rand_sys *s) {
  ap_system_def def = ap_system_def_default();
  def.name = "random";
  def.n = RK, def.k = RK, def.b = s->b;
  def.metric = rs_metric, def.bias = rs_bias, def.force = rs_force;
  def.constraint = rs_constraint, def.gamma = rs_gamma;
  def.constraint_names = row_names;
  def.user = s;
  ap_model *m = NULL;
  char msg[256];
  int rc = ap_model_from_system(&def, &m, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  return m;
}

/* Solve at one state with a given basis; copy v' out. */
static int solve(const ap_model *m, ap_basis basis, const double *v, double *vdot, ap_data **dout) {
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) return -100;
  d->basis = basis;
  d->want_reactions = 1;
  for (int i = 0; i < d->n; i++) d->q[i] = 0.1 * i;
  memcpy(d->v, v, sizeof(double) * (size_t)d->k);
  int rc = basis == AP_BASIS_PARTITIONED ? ap_partition(m, d) : AP_OK;
  if (rc == AP_OK) rc = ap_forward(m, d);
  if (vdot) memcpy(vdot, d->vdot, sizeof(double) * (size_t)d->k);
  *dout = d;
  return rc;
}

/* KKT of Gauss's principle: A v' = gamma, B^T (g v' + h - Q) = 0, A^T lambda = g v' + h - Q. */
static void check_kkt(const rand_sys *s, const ap_data *d) {
  double r[RK], scale = 10.0;
  for (int i = 0; i < RK; i++) {
    r[i] = s->h[i] - s->Q[i];
    for (int j = 0; j < RK; j++) r[i] += s->g[i + j * RK] * d->vdot[j];
  }
  for (int i = 0; i < s->b; i++) {
    double av = 0.0;
    for (int j = 0; j < RK; j++) av += s->A[i + j * RB] * d->vdot[j];
    AP_CHECK_NEAR(av, s->gam[i], 1e-12 * scale);
  }
  for (int c = 0; c < d->l; c++) {
    double bt = 0.0;
    for (int i = 0; i < RK; i++) bt += d->B[i + c * RK] * r[i];
    AP_CHECK_NEAR(bt, 0.0, 1e-12 * scale);
  }
  for (int i = 0; i < RK; i++) {
    double atl = 0.0;
    for (int sidx = 0; sidx < s->b; sidx++) atl += s->A[sidx + i * RB] * d->lambda[sidx];
    AP_CHECK_NEAR(atl, r[i], 1e-11 * scale);
  }
}

static void test_gauss_and_bases(void) {
  for (int trial = 0; trial < 20; trial++) {
    rand_sys s;
    int b = 1 + trial % RB, redundant = b >= 3 && trial % 2;
    rand_fill(&s, b, redundant);
    ap_model *m = rand_model(&s);
    double v[RK] = {0}, vp[RK], vo[RK];
    ap_data *dp = NULL, *dq = NULL;
    AP_CHECK_EQ_INT(solve(m, AP_BASIS_PARTITIONED, v, vp, &dp), AP_OK);
    AP_CHECK_EQ_INT(solve(m, AP_BASIS_ORTHONORMAL, v, vo, &dq), AP_OK);
    AP_CHECK_EQ_INT(dp->l, RK - b + redundant);
    AP_CHECK_EQ_INT(dq->l, RK - b + redundant);
    check_kkt(&s, dp);
    check_kkt(&s, dq);
    for (int i = 0; i < RK; i++) AP_CHECK_NEAR(vp[i], vo[i], 1e-11 * (1 + fabs(vo[i])));
    if (redundant) {   /* the message names one of the three dependent rows */
      AP_CHECK(strstr(dp->msg, "redundant") != NULL && strstr(dp->msg, "consistent") != NULL);
      AP_CHECK(strstr(dp->msg, row_names[b - 1]) || strstr(dp->msg, row_names[0]) ||
               strstr(dp->msg, row_names[1]));
    }
    ap_data_free(dp), ap_data_free(dq);
    ap_model_free(m);
  }
}

static void test_inconsistent(void) {
  rand_sys s;
  rand_fill(&s, 4, 1);
  s.a0[3] += 0.5;   /* the copy of row0 + 2 row1 now disagrees */
  ap_model *m = rand_model(&s);
  double v[RK] = {0};
  ap_data *d = NULL;
  int rc = solve(m, AP_BASIS_PARTITIONED, v, NULL, &d);
  AP_CHECK_EQ_INT(rc, AP_ERR_INCONSISTENT);
  AP_CHECK(strstr(d->msg, "inconsistent") != NULL);
  AP_CHECK(strstr(d->msg, "axle-copy") != NULL || strstr(d->msg, "left-wheel") != NULL ||
           strstr(d->msg, "right-wheel") != NULL);
  ap_data_free(d);
  ap_data *d2 = NULL;
  rc = solve(m, AP_BASIS_ORTHONORMAL, v, NULL, &d2);
  AP_CHECK_EQ_INT(rc, AP_ERR_INCONSISTENT);
  ap_data_free(d2);
  ap_model_free(m);
}

static void test_failing_callbacks(void) {
  const int expect[4] = {AP_OK, AP_ERR_NAN, AP_RECOVERABLE, AP_ERR_CALLBACK};
  for (int mode = 1; mode <= 3; mode++) {
    rand_sys s;
    rand_fill(&s, 2, 0);
    s.fail_metric = mode;
    ap_model *m = rand_model(&s);
    double v[RK] = {0};
    ap_data *d = NULL;
    int rc = solve(m, AP_BASIS_ORTHONORMAL, v, NULL, &d);
    AP_CHECK_EQ_INT(rc, expect[mode]);
    AP_CHECK(strstr(d->msg, "metric") != NULL);
    AP_CHECK(strstr(d->msg, "random") != NULL);
    ap_data_free(d);
    ap_model_free(m);
  }
}

/* A NaN from a force callback in the middle of a run: clean error, last good state kept. */
static void test_nan_mid_run(void) {
  rand_sys s;
  rand_fill(&s, 2, 0);
  memset(s.a0, 0, sizeof s.a0);
  memset(s.gam, 0, sizeof s.gam);   /* consistent with constant A, a0 = 0 */
  s.fail_force = 1;
  ap_model *m = rand_model(&s);
  for (int mode = 0; mode < 2; mode++) {
    ap_sim_def def = ap_sim_def_default();
    def.mode = mode ? AP_MODE_PROJECTED : AP_MODE_MINIMAL;
    double q0[RK] = {0}, v0[RK] = {0};
    ap_sim *sim = NULL;
    char msg[512];
    AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, v0, &sim, msg, sizeof msg), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.5), AP_OK);
    int rc = ap_sim_advance(sim, 3.0);
    AP_CHECK_EQ_INT(rc, AP_ERR_NAN);
    AP_CHECK(strstr(ap_sim_message(sim), "force") != NULL);
    AP_CHECK(ap_sim_time(sim) >= 0.5 && ap_sim_time(sim) <= 1.0 + 1e-12);
    int finite = 1;
    for (int i = 0; i < RK; i++) finite &= isfinite(ap_sim_q(sim)[i]) && isfinite(ap_sim_v(sim)[i]);
    AP_CHECK(finite);
    ap_sim_free(sim);
  }
  ap_model_free(m);
}

static void test_no_alloc_in_step(void) {
  if (!AP_COUNT_ALLOC) {
    printf("allocation count skipped under AddressSanitizer\n");
    return;
  }
  rand_sys s;
  rand_fill(&s, 3, 0);
  ap_model *m = rand_model(&s);
  for (int basis = 0; basis < 2; basis++) {
    double v[RK] = {0};
    ap_data *d = NULL;
    AP_CHECK_EQ_INT(solve(m, (ap_basis)basis, v, NULL, &d), AP_OK);   /* warm-up */
    long before = n_alloc;
    for (int rep = 0; rep < 100; rep++) {
      AP_CHECK_EQ_INT(ap_forward(m, d), AP_OK);
      double change;
      memcpy(v, d->v, sizeof v);
      AP_CHECK_EQ_INT(ap_project_speeds(m, d, v, &change), AP_OK);
    }
    AP_CHECK_EQ_INT(n_alloc - before, 0);
    ap_data_free(d);
  }
  ap_model_free(m);
}

/* ---- Christoffel terms: a particle in polar coordinates ---------------------------------- */
static int polar_metric(double t, const double *q, double *g, void *u) {
  (void)t, (void)u;
  g[0] = 2.0, g[3] = 2.0 * q[0] * q[0];
  return 0;
}
static int polar_dmetric(double t, const double *q, double *dg, void *u) {
  (void)t, (void)u;
  dg[3] = 4.0 * q[0];   /* d/dr of g_thth; d/dtheta block is zero */
  return 0;
}

static void test_christoffel(void) {
  ap_system_def def = ap_system_def_default();
  def.name = "polar";
  def.n = 2, def.k = 2, def.b = 0;
  def.metric = polar_metric, def.metric_deriv = polar_dmetric;
  def.bias_source = AP_BIAS_CHRISTOFFEL;
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, NULL, 0), AP_OK);
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  d->q[0] = 1.7, d->q[1] = 0.3, d->v[0] = -0.4, d->v[1] = 1.3;
  AP_CHECK_EQ_INT(ap_forward(m, d), AP_OK);
  /* free particle: r'' = r th'^2, th'' = -2 r' th' / r */
  AP_CHECK_NEAR(d->h[0], -2.0 * 1.7 * 1.3 * 1.3, 1e-14);
  AP_CHECK_NEAR(d->h[1], 2 * 2.0 * 1.7 * -0.4 * 1.3, 1e-14);
  AP_CHECK_NEAR(d->vdot[0], 1.7 * 1.3 * 1.3, 1e-14);
  AP_CHECK_NEAR(d->vdot[1], -2 * -0.4 * 1.3 / 1.7, 1e-14);
  AP_CHECK_EQ_INT(d->cnt.qr, 0);   /* no constraints: the QR stage is skipped */
  ap_data_free(d);
  ap_model_free(m);
}

/* ---- quasi-velocities: a free planar body with body-frame speeds ------------------------- */
static int body_metric(double t, const double *q, double *g, void *u) {
  (void)t, (void)q, (void)u;
  g[0] = 3.0, g[4] = 3.0, g[8] = 0.7;
  return 0;
}
static int body_bias(double t, const double *q, const double *v, double *h, void *u) {
  (void)t, (void)q, (void)u;
  h[0] = -3.0 * v[2] * v[1], h[1] = 3.0 * v[2] * v[0];
  return 0;
}
static int body_kin(double t, const double *q, double *N, void *u) {
  (void)t, (void)u;
  double c = cos(q[2]), s = sin(q[2]);
  N[0] = c, N[1] = s, N[3] = -s, N[4] = c, N[8] = 1.0;
  return 0;
}

static void test_quasi_velocities(void) {
  ap_system_def def = ap_system_def_default();
  def.name = "planar-body";
  def.n = 3, def.k = 3;
  def.metric = body_metric, def.bias = body_bias, def.kinematic = body_kin;
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, NULL, 0), AP_OK);
  ap_sim_def sd = ap_sim_def_default();
  sd.rtol = 1e-11, sd.atol = 1e-13;
  double q0[3] = {0.5, -1.0, 0.3}, v0[3] = {1.2, -0.4, 2.5};
  ap_sim *sim = NULL;
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &sim, NULL, 0), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(sim, 10.0), AP_OK);
  /* the centre moves on a straight line at the initial world velocity */
  double vx = cos(0.3) * 1.2 - sin(0.3) * -0.4, vy = sin(0.3) * 1.2 + cos(0.3) * -0.4;
  AP_CHECK_NEAR(ap_sim_q(sim)[0], 0.5 + 10.0 * vx, 1e3 * sd.rtol * 10);
  AP_CHECK_NEAR(ap_sim_q(sim)[1], -1.0 + 10.0 * vy, 1e3 * sd.rtol * 10);
  AP_CHECK_NEAR(ap_sim_q(sim)[2], 0.3 + 25.0, 1e3 * sd.rtol * 25);
  ap_sim_free(sim);
  ap_model_free(m);
}

/* ---- validation and initial speeds ------------------------------------------------------- */
static void test_validation(void) {
  char msg[512];
  ap_model *m = NULL;
  ap_system_def def = ap_system_def_default();
  def.name = "broken";
  def.n = 3, def.k = 2;
  def.metric = body_metric, def.bias_source = AP_BIAS_ZERO;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(m == NULL && strstr(msg, "broken") && strstr(msg, "kinematic"));
  def.n = 2, def.b = 1;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "gamma") != NULL);
  def.b = 0, def.metric = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "metric") != NULL);
  def.metric = body_metric, def.bias_source = AP_BIAS_CALLBACK;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "bias") != NULL);
  AP_CHECK(strcmp(ap_strerror(AP_ERR_INCONSISTENT), "inconsistent constraints") == 0);
}

static void test_initial_speeds(void) {
  rand_sys s;
  rand_fill(&s, 2, 0);
  ap_model *m = rand_model(&s);
  double q0[RK] = {0}, v0[RK] = {0};
  ap_sim_def def = ap_sim_def_default();
  ap_sim *sim = NULL;
  char msg[512] = "";
  /* v = 0 violates A v + a0 = 0 by |a0| ~ 1: refused */
  AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, v0, &sim, msg, sizeof msg),
                  AP_ERR_INCONSISTENT);
  AP_CHECK(sim == NULL && strstr(msg, "initial speeds") != NULL);
  /* a slightly perturbed admissible v is projected and the correction reported */
  memset(s.a0, 0, sizeof s.a0);
  for (int i = 0; i < RK; i++) v0[i] = urand();
  def.mode = AP_MODE_PROJECTED;
  AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, v0, &sim, msg, sizeof msg),
                  AP_ERR_INCONSISTENT);
  double vproj[RK];
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(solve(m, AP_BASIS_ORTHONORMAL, v0, NULL, &d), AP_OK);
  memcpy(vproj, v0, sizeof vproj);
  double change;
  AP_CHECK_EQ_INT(ap_project_speeds(m, d, vproj, &change), AP_OK);
  AP_CHECK_LE(ap_constraint_residual(d, vproj), 1e-14);
  vproj[0] += 1e-9;
  AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, vproj, &sim, msg, sizeof msg), AP_OK);
  ap_sim_stats st;
  ap_sim_get_stats(sim, &st);
  AP_CHECK(st.init_correction > 0 && st.init_correction < 1e-8);
  AP_CHECK_LE(ap_constraint_residual(ap_sim_data(sim), ap_sim_v(sim)), 1e-14);
  ap_sim_free(sim);
  ap_data_free(d);
  ap_model_free(m);
}

/* A row of A at round-off (1e-20 of the scale 1 of a math-level system) with a0 = 0.3: the
 * relative rank test keeps a lone row by its own pivot (minimum-norm speeds |a0| / |A| ~ 1e20);
 * refused at creation in every mode, with the row and the numbers. The same row with a0 of its
 * own round-off size vanishes identically and is accepted, as is a small row that is not
 * round-off (1e-6: speeds of 3e5 are the model's). */
static void test_vanishing_row(void) {
  rand_sys s;
  rand_fill(&s, 1, 0);
  for (int j = 0; j < RK; j++) s.A[j * RB] *= 1e-20;
  s.a0[0] = 0.3, s.gam[0] = 0.0;
  ap_model *m = rand_model(&s);
  double q0[RK] = {0}, v0[RK] = {0};
  ap_mode modes[4] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_PLAIN, AP_MODE_DAE};
  ap_sim_def def = ap_sim_def_default();
  ap_sim *sim = NULL;
  char msg[512] = "";
  for (int i = 0; i < 4; i++) {
    def.mode = modes[i];
    AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, v0, &sim, msg, sizeof msg),
                    AP_ERR_INCONSISTENT);
    AP_CHECK(sim == NULL && strstr(msg, "'left-wheel' is contradictory") &&
             strstr(msg, "0.3") && strstr(msg, "rank_rtol 1e-10"));
  }
  double scale[2] = {1.0, 1e14}, a0[2] = {1e-20, 0.3};   /* |A_r| ~ 1e-20, then ~ 1e-6 */
  def.mode = AP_MODE_MINIMAL;
  for (int c = 0; c < 2; c++) {
    double an = 0.0;
    for (int j = 0; j < RK; j++) s.A[j * RB] *= scale[c], an = hypot(an, s.A[j * RB]);
    s.a0[0] = a0[c];
    for (int j = 0; j < RK; j++) v0[j] = -a0[c] * s.A[j * RB] / (an * an);   /* A v + a0 = 0 */
    AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, q0, v0, &sim, msg, sizeof msg), AP_OK);
    ap_sim_free(sim);
  }
  ap_model_free(m);
}

/* CVODE in projected mode: BDF projects natively (no restarts, history kept), Adams is refused
 * with a message saying why. The sleigh against its closed form (docs/references.md §2). */
static void test_cvode_projected(void) {
  rs_sleigh sp = {1.0, 1.0, 1.0};
  double q0[3], v0[3], qe[3];
  ap_system_def def;
  rs_sleigh_initial(0, 0, RS_PI, 0.1, 0.2, q0, v0);
  rs_sleigh_system(&sp, 0, &def);
  ap_model *m = NULL;
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &m, NULL, 0), AP_OK);
  ap_sim_def sd = ap_sim_def_default();
  sd.mode = AP_MODE_PROJECTED, sd.method = "bdf", sd.rtol = 1e-10, sd.atol = 1e-12;
  ap_sim *sim = NULL;
  char msg[512] = "";
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &sim, msg, sizeof msg), AP_OK);
  double err = 0.0;
  for (int i = 1; i <= 30 && sim; i++) {
    AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.5 * i), AP_OK);
    rs_sleigh_exact(&sp, q0, v0, 0.5 * i, qe, NULL);
    for (int c = 0; c < 3; c++) err = fmax(err, fabs(qe[c] - ap_sim_q(sim)[c]));
  }
  ap_sim_stats st;
  ap_sim_get_stats(sim, &st);
  AP_CHECK_LE(err, 1e3 * sd.rtol);            /* BDF's global error: measured 1.7e-9 */
  AP_CHECK(st.projections >= st.steps);       /* projected inside every step ... */
  AP_CHECK_EQ_INT(st.restarts, 0);            /* ... without restarting the multistep method */
  AP_CHECK_LE(st.max_residual, 1e-14);
  ap_sim_free(sim);
  sd.method = "adams";
  AP_CHECK_EQ_INT(ap_sim_create(m, &sd, 0.0, q0, v0, &sim, msg, sizeof msg),
                  AP_ERR_UNSUPPORTED);
  AP_CHECK(strstr(msg, "adams") != NULL && strstr(msg, "BDF") != NULL);
  ap_model_free(m);
}

int main(void) {
  test_cvode_projected();
  test_gauss_and_bases();
  test_inconsistent();
  test_failing_callbacks();
  test_nan_mid_run();
  test_no_alloc_in_step();
  test_christoffel();
  test_quasi_velocities();
  test_validation();
  test_initial_speeds();
  test_vanishing_row();
  return ap_check_finish("core");
}
