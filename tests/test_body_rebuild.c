/* The hand-derived reference systems (tests/refsys.h) rebuilt from bodies.
 *
 * Each problem is described with bodies, joints, constraints and effects only (the models of
 * tests/bodysys.c), compiled, and compared with its math-level twin at matching coordinates
 * (random states, same speeds up to a permutation): g, h, Q, A, a0 and gamma must agree to
 * round-off (ROUND = 1e-13 relative to max(1, |entry|): both sides evaluate the same closed
 * expressions through different sums of a few O(1) products, so differences are a few ulps).
 * Then the body models are integrated at rtol 1e-11 and compared with the closed forms of
 * docs/references.md (POS_TOL = 1e-8, the target docs/references.md gives for rtol 1e-11 over these
 * times) or, for Hoffmann's pendulum, with the hand-derived reduced system integrated the same
 * way:
 *   skate on an incline     planar joint on an inclined frame + knife edge + gravity
 *   Chaplygin sleigh        planar joint, centre of mass ahead of the blade + knife edge
 *   ball on a turntable     sphere on the plane-contact joint + rolling on a turntable
 *                           (constant and accelerating Omega: a0, rheonomic gamma)
 *   Hoffmann's pendulum     primitive: revolute rod + planar rod + hinge (coincident points,
 *                           y and z) = refsys primitive system; tree: two revolutes = Kron's
 *                           C^T M C of the printed reduced system; equilibrium under F
 *   Hoffmann's 2nd example  the lower rod's end sliding on a vertical line (point on plane),
 *                           1 degree of freedom: energy, closure, modes agree. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "bodysys.h"
#include "testrand.h"

#define ROUND 1e-13
#define RTOL 1e-11
#define ATOL 1e-13
#define POS_TOL 1e-8
#define MAXK 8

static uint64_t rng = 88172645463325252ull;
static double urand(void) { return ap_test_urand(&rng); }
static double srand1(void) { return ap_test_srand(&rng); }

static ap_model *from_system(ap_system_def *def) {
  ap_model *m = NULL;
  char msg[256];
  AP_CHECK_EQ_INT(ap_model_from_system(def, &m, msg, sizeof msg), AP_OK);
  return m;
}

/* ---- comparing a body model with its math-level twin -------------------------------------- */

/* The orthonormal basis makes the core call the gamma callback of a math-level system (with
 * AP_BASIS_NONE it skips it: the DAE residual does not need gamma). */
static void eval(const ap_model *m, ap_data *d, double t, const double *q, const double *v) {
  d->t = t, d->speeds_from_e = 0;
  d->basis = ap_model_b(m) ? AP_BASIS_ORTHONORMAL : AP_BASIS_NONE;
  memcpy(d->q, q, sizeof(double) * (size_t)ap_model_n(m));
  memcpy(d->v, v, sizeof(double) * (size_t)ap_model_k(m));
  AP_CHECK_EQ_INT(ap_fwd_position(m, d), AP_OK);
  AP_CHECK_EQ_INT(ap_fwd_velocity(m, d), AP_OK);
}

static double dif(double a, double b) { return fabs(a - b) / fmax(1.0, fabs(b)); }

/* Max relative difference of g, h, Q, A, a0, gamma; body speed i is reference speed perm[i]
 * (T = NULL) or, with T (k x k, v_ref = T v_body), the body's g, h, Q are T^T (...) T of the
 * reference's (A, a0, gamma are compared only when T is NULL). */
static double compare(const ap_model *mb, ap_data *db, const ap_model *mr, ap_data *dr,
                      double t, const double *qb, const double *qr, const double *vr,
                      const int *perm, const double *T) {
  int k = ap_model_k(mb), b = ap_model_b(mb);
  double vb[MAXK], e = 0.0;
  for (int i = 0; i < k; i++) vb[i] = perm ? vr[perm[i]] : vr[i];
  if (T) /* v_ref = T v_body: solve by the (lower unit triangular) T used here */
    for (int i = 0; i < k; i++) {
      vb[i] = vr[i];
      for (int j = 0; j < i; j++) vb[i] -= T[i + k * j] * vb[j];
    }
  eval(mb, db, t, qb, vb);
  eval(mr, dr, t, qr, vr);
  for (int i = 0; i < k; i++) {
    double h = 0.0, Q = 0.0;
    for (int a = 0; a < k; a++) {
      double ta = T ? T[a + k * i] : 0.0;
      if (T) h += ta * dr->h[a], Q += ta * dr->Q[a];
    }
    int pi = perm ? perm[i] : i;
    e = fmax(e, dif(db->h[i], T ? h : dr->h[pi]));
    e = fmax(e, dif(db->Q[i], T ? Q : dr->Q[pi]));
    for (int j = 0; j < k; j++) {
      double g = 0.0;
      if (T)
        for (int a = 0; a < k; a++)
          for (int c = 0; c < k; c++) g += T[a + k * i] * dr->g[a + k * c] * T[c + k * j];
      int pj = perm ? perm[j] : j;
      e = fmax(e, dif(db->g[i + k * j], T ? g : dr->g[pi + k * pj]));
    }
    for (int s = 0; !T && s < b; s++) e = fmax(e, dif(db->A[s + b * i], dr->A[s + b * pi]));
  }
  for (int s = 0; !T && s < b; s++) {
    e = fmax(e, dif(db->a0[s], dr->a0[s]));
    e = fmax(e, dif(db->gamma[s], dr->gamma[s]));
  }
  return e;
}

/* ---- simulations ----------------------------------------------------------------------------- */

static ap_sim *start(const ap_model *m, ap_mode mode, const char *method, const double *q0,
                     const double *v0) {
  return bs_start(m, mode, method, RTOL, ATOL, q0, v0);
}

static int advance(ap_sim *s, double t) {
  int rc = ap_sim_advance(s, t);
  if (rc != AP_OK) fprintf(stderr, "advance to %g: %s\n", t, ap_sim_message(s));
  AP_CHECK_EQ_INT(rc, AP_OK);
  return rc;
}

static const ap_mode modes[2] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED};
static const char *const mode_names[2] = {"minimal", "projected"};

/* ---- 1. skate on an inclined plane ----------------------------------------------------------- */

static void test_skate(void) {
  rs_knife p = {2.0, 0.3, 9.81, 0.3};
  ap_system_def def;
  rs_knife_system(&p, &def);
  ap_model *mb = bs_skate_model(&p), *mr = from_system(&def);
  ap_data *db = NULL, *dr = NULL;
  ap_data_create(mb, &db), ap_data_create(mr, &dr);
  double e = 0.0;
  for (int s = 0; s < 20; s++) {
    double q[3] = {srand1(), srand1(), 4 * srand1()}, v[3] = {srand1(), srand1(), srand1()};
    e = fmax(e, compare(mb, db, mr, dr, 0.0, q, q, v, NULL, NULL));
  }
  printf("skate:     g h Q A a0 gamma agree to %.1e\n", e);
  AP_CHECK_LE(e, ROUND);
  double q0[3], v0[3];
  rs_knife_initial(0.1, -0.2, 0.2, 1.0, 1.5, q0, v0);
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = start(mb, modes[mi], "verner6", q0, v0);
    double err = 0.0;
    for (int i = 1; s && i <= 20; i++) {
      double t = 0.5 * i, qe[3];
      if (advance(s, t) != AP_OK) break;
      rs_knife_exact(&p, q0, v0, t, qe, NULL, NULL);
      for (int c = 0; c < 3; c++) err = fmax(err, dif(ap_sim_q(s)[c], qe[c]));
    }
    printf("  %-9s 10 s: max position error %.1e\n", mode_names[mi], err);
    AP_CHECK_LE(err, POS_TOL);
    ap_sim_free(s);
  }
  ap_data_free(db), ap_data_free(dr);
  ap_model_free(mb), ap_model_free(mr);
}

/* ---- 2. Chaplygin sleigh --------------------------------------------------------------------- */

static void test_sleigh(void) {
  rs_sleigh p = {1.0, 1.0, 1.0};
  ap_system_def def;
  rs_sleigh_system(&p, 1, &def);
  ap_model *mb = bs_sleigh_model(&p), *mr = from_system(&def);
  ap_data *db = NULL, *dr = NULL;
  ap_data_create(mb, &db), ap_data_create(mr, &dr);
  double e = 0.0;
  for (int s = 0; s < 20; s++) {
    double q[3] = {srand1(), srand1(), 4 * srand1()}, v[3] = {srand1(), srand1(), srand1()};
    e = fmax(e, compare(mb, db, mr, dr, 0.0, q, q, v, NULL, NULL));
  }
  printf("sleigh:    g h Q A a0 gamma agree to %.1e\n", e);
  AP_CHECK_LE(e, ROUND);
  /* docs/references.md §2 sample: m = I = a = 1, u0 = 0.1, w0 = 0.2, theta0 = pi, at t = 15 */
  const double ref[5] = {-1.5814737061340092, -3.0441567427652534, 4.672022704815886,
                         0.29668571025517837, 0.03144510558402052};
  double q0[3], v0[3];
  rs_sleigh_initial(0.0, 0.0, RS_PI, 0.1, 0.2, q0, v0);
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = start(mb, modes[mi], "dopri5", q0, v0);
    if (!s || advance(s, 15.0) != AP_OK) continue;
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    double u = v[0] * cos(q[2]) + v[1] * sin(q[2]), got[5] = {q[0], q[1], q[2], u, v[2]};
    double err = 0.0;
    for (int i = 0; i < 5; i++) err = fmax(err, dif(got[i], ref[i]));
    printf("  %-9s t = 15: x %.15f y %.15f theta %.15f u %.15f: error %.1e\n", mode_names[mi],
           q[0], q[1], q[2], u, err);
    AP_CHECK_LE(err, POS_TOL);
    ap_sim_free(s);
  }
  ap_data_free(db), ap_data_free(dr);
  ap_model_free(mb), ap_model_free(mr);
}

/* ---- 3. ball on a turntable ------------------------------------------------------------------ */

static void test_turntable(double dOmega) {
  rs_turntable p = {1.2, 0.3, 0.4, 1.1, dOmega};
  ap_system_def def;
  rs_turntable_system(&p, &def);
  ap_model *mb = bs_turntable_model(&p), *mr = from_system(&def);
  ap_data *db = NULL, *dr = NULL;
  ap_data_create(mb, &db), ap_data_create(mr, &dr);
  double e = 0.0;
  for (int s = 0; s < 20; s++) {
    double qr[5] = {srand1(), srand1(), 0, 0, 0}, qb[6] = {qr[0], qr[1]}, v[5], n = 0.0;
    for (int i = 0; i < 4; i++) qb[2 + i] = srand1(), n += qb[2 + i] * qb[2 + i];
    for (int i = 0; i < 4; i++) qb[2 + i] /= sqrt(n);
    for (int i = 0; i < 5; i++) v[i] = srand1();
    e = fmax(e, compare(mb, db, mr, dr, 3 * urand(), qb, qr, v, NULL, NULL));
  }
  printf("turntable (dOmega %g): g h Q A a0 gamma agree to %.1e\n", dOmega, e);
  AP_CHECK_LE(e, ROUND);
  double q0[5], v0[5], qb0[6] = {0, 0, 1, 0, 0, 0};
  rs_turntable_initial(&p, 0.5, -0.2, 1.0, 2.0, 3.0, q0, v0);
  qb0[0] = q0[0], qb0[1] = q0[1];
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = start(mb, modes[mi], "fehlberg8", qb0, v0);
    double err = 0.0;
    for (int i = 1; s && i <= 20; i++) {
      double t = 1.0 * i, qe[5], ve[5];
      if (advance(s, t) != AP_OK) break;
      rs_turntable_exact(&p, q0, v0, t, qe, ve);
      for (int c = 0; c < 2; c++) err = fmax(err, dif(ap_sim_q(s)[c], qe[c]));
      for (int c = 0; c < 5; c++) err = fmax(err, dif(ap_sim_v(s)[c], ve[c]));
    }
    printf("  %-9s 20 s: max error of x, y and the speeds %.1e\n", mode_names[mi], err);
    AP_CHECK_LE(err, POS_TOL);
    ap_sim_free(s);
  }
  ap_data_free(db), ap_data_free(dr);
  ap_model_free(mb), ap_model_free(mr);
}

/* ---- 4. Hoffmann's two-rod pendulum ---------------------------------------------------------- */

static void test_hoffmann(void) {
  rs_hoffmann p = bs_hoffmann_params();
  ap_system_def dprim, dred;
  rs_hoffmann_primitive_system(&p, &dprim);
  rs_hoffmann_reduced_system(&p, &dred);
  ap_model *mp = bs_hoffmann_primitive(&p), *mt = bs_hoffmann_tree(&p, 0, 0.0);
  ap_model *rp = from_system(&dprim), *rr = from_system(&dred);
  ap_data *dp = NULL, *dt = NULL, *ep = NULL, *er = NULL;
  ap_data_create(mp, &dp), ap_data_create(mt, &dt), ap_data_create(rp, &ep),
      ap_data_create(rr, &er);
  const int perm[4] = {0, 2, 3, 1};                /* body (theta, y, z, phi) */
  const double T[4] = {1, 1, 0, 1};                /* (theta, phi) = T (theta, psi) */
  double e1 = 0.0, e2 = 0.0;
  for (int s = 0; s < 20; s++) {
    double qr[4] = {2 * srand1(), 2 * srand1(), srand1(), srand1()}, vr[4], qb[4];
    for (int i = 0; i < 4; i++) vr[i] = 2 * srand1(), qb[i] = qr[perm[i]];
    e1 = fmax(e1, compare(mp, dp, rp, ep, 0.0, qb, qr, vr, perm, NULL));
    double qt[2] = {qr[0], qr[1] - qr[0]};
    e2 = fmax(e2, compare(mt, dt, rr, er, 0.0, qt, qr, vr, NULL, T));
  }
  printf("Hoffmann:  primitive g h Q A a0 gamma agree to %.1e; tree g h Q = T^T (printed) "
         "agree to %.1e\n", e1, e2);
  AP_CHECK_LE(e1, ROUND);
  AP_CHECK_LE(e2, ROUND);
  /* trajectories: the tree against the printed reduced system, same stepper and tolerances */
  double q0[2] = {0.4, -0.3}, v0[2] = {0.5, 1.2}, qt0[2] = {0.4, -0.7}, vt0[2] = {0.5, 0.7};
  ap_sim *sb = start(mt, AP_MODE_MINIMAL, "verner6", qt0, vt0);
  ap_sim *sr = start(rr, AP_MODE_MINIMAL, "verner6", q0, v0);
  double err = 0.0, E0 = rs_hoffmann_energy(&p, q0, v0), dE = 0.0;
  for (int i = 1; sb && sr && i <= 20; i++) {
    if (advance(sb, 0.5 * i) != AP_OK || advance(sr, 0.5 * i) != AP_OK) break;
    const double *qb = ap_sim_q(sb), *vb = ap_sim_v(sb), *q = ap_sim_q(sr);
    double qq[2] = {qb[0], qb[0] + qb[1]}, vv[2] = {vb[0], vb[0] + vb[1]};
    err = fmax(err, fmax(dif(qq[0], q[0]), dif(qq[1], q[1])));
    dE = fmax(dE, fabs(rs_hoffmann_energy(&p, qq, vv) - E0) / fabs(E0));
  }
  printf("  tree vs printed over 10 s: max angle difference %.1e, energy drift %.1e\n", err,
         dE);
  AP_CHECK_LE(err, POS_TOL);
  AP_CHECK_LE(dE, 1e-9);
  ap_sim_free(sb), ap_sim_free(sr);
  /* the equilibrium under F stays put */
  double qs[2], qst[2], zero[2] = {0, 0};
  rs_hoffmann_equilibrium(&p, qs);
  qst[0] = qs[0], qst[1] = qs[1] - qs[0];
  sb = start(mt, AP_MODE_MINIMAL, "dopri5", qst, zero);
  if (sb && advance(sb, 5.0) == AP_OK) {
    double dev = fmax(fabs(ap_sim_q(sb)[0] - qst[0]), fabs(ap_sim_q(sb)[1] - qst[1]));
    printf("  equilibrium theta* %.6f phi* %.6f: moved %.1e in 5 s\n", qs[0], qs[1], dev);
    AP_CHECK_LE(dev, 1e-10);
  }
  ap_sim_free(sb);
  ap_data_free(dp), ap_data_free(dt), ap_data_free(ep), ap_data_free(er);
  ap_model_free(mp), ap_model_free(mt), ap_model_free(rp), ap_model_free(rr);
}

/* ---- 5. Hoffmann's second example: the lower end slides on a vertical line ----------------- */

static double hoff_energy(const rs_hoffmann *p, const ap_model *m, ap_data *d, const double *q,
                          const double *v) {
  double T = 0.0, V = 0.0;
  memcpy(d->q, q, 2 * sizeof *q), memcpy(d->v, v, 2 * sizeof *v);
  AP_CHECK(ap_body_energy(m, d, &T, &V) == AP_OK);
  return T + V - p->F * (2 * p->a1 * sin(q[0]) + p->a2 * sin(q[0] + q[1]));
}

static void test_hoffmann_sliding(void) {
  rs_hoffmann p = bs_hoffmann_params();
  double y_line = 0.3;
  ap_model *m = bs_hoffmann_tree(&p, 1, y_line);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double q0[2], v0[2], change = 0.0, qe[2];
  AP_CHECK_EQ_INT(bs_hoffmann_sliding_state(m, q0, v0, &change), AP_OK);
  double y_end = 2 * p.a1 * sin(q0[0]) + 2 * p.a2 * sin(q0[0] + q0[1]);
  printf("Hoffmann 2nd example: assembled psi = %.12f (moved %.2g), lower end y = %.15f\n",
         q0[1], change, y_end);
  AP_CHECK_NEAR(y_end, y_line, 1e-12);
  double E0 = hoff_energy(&p, m, d, q0, v0);
  for (int mi = 0; mi < 2; mi++) {
    ap_sim *s = start(m, modes[mi], "verner6", q0, v0);
    double dE = 0.0, dy = 0.0;
    for (int i = 1; s && i <= 40; i++) {
      if (advance(s, 0.25 * i) != AP_OK) break;
      const double *q = ap_sim_q(s);
      dE = fmax(dE, fabs(hoff_energy(&p, m, d, q, ap_sim_v(s)) - E0) / fabs(E0));
      dy = fmax(dy, fabs(2 * p.a1 * sin(q[0]) + 2 * p.a2 * sin(q[0] + q[1]) - y_line));
    }
    ap_sim_stats st;
    if (s) ap_sim_get_stats(s, &st);
    printf("  %-9s 10 s: energy drift %.1e, closure %.1e m, theta(10) = %.10f, steps %ld, "
           "restarts %ld\n", mode_names[mi], dE, dy, s ? ap_sim_q(s)[0] : 0.0, st.steps,
           st.restarts);
    AP_CHECK_LE(dE, 1e-9);
    AP_CHECK_LE(dy, 1e-11);
    if (mi == 0 && s) memcpy(qe, ap_sim_q(s), sizeof qe);
    else if (s) AP_CHECK_NEAR(ap_sim_q(s)[0], qe[0], 1e-7);
    ap_sim_free(s);
  }
  ap_data_free(d);
  ap_model_free(m);
}

int main(void) {
  test_skate();
  test_sleigh();
  test_turntable(0.0);
  test_turntable(0.25);
  test_hoffmann();
  test_hoffmann_sliding();
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_body_rebuild");
}
