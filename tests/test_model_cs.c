/* The complex-step build of lib/core and lib/model (core/core.h, model/model.h) against the
 * double build: derivatives of every per-evaluation object along a direction of the state,
 * checked against Ridders' extrapolated differences of the double build.
 *
 * For each scene (every example scene and the state-function scenes of tests/scenes), at its
 * initial state (q0, v0) and a fixed-seed random direction (dq, dv), the path
 * q(s) = q0 + s dq, v(s) = v0 + s dv (quaternions off the unit sphere are fine: R comes from
 * q / |q|) gives, at s = 0,
 *   objects  g, N, A, a0, h, Q, gamma    (position and velocity stages, no basis)
 *   phi      the implicit holonomic rows and Phi_q (ev.phi)
 *   solve    B, b0, w, v', q'            (partitioned basis, the partition of ap_partition at
 *                                         q0, frozen; v given)
 * The complex-step build evaluates them once at (q0 + i h dq, v0 + i h dv), h = AP_CS_STEP:
 * Im / h is the exact derivative up to round-off; Ridders' method (lib/analyze/ridders.c)
 * differentiates the double build with an error estimate E per entry. Checked per entry:
 *   |cs - ridders| <= E + 1e-13 max(1, |entry scale|)   (1e-13: the floor of Ridders' estimate
 *                      is its round-off model of the double values, itself an estimate);
 *   the real parts equal the double values to 1e-14 relative (complex division and square
 *   root round differently from the real ones by an ulp or two).
 * The models the complex-step build cannot evaluate (user callbacks, math-level systems) are
 * tested with the linearizer's fallback in tests/test_lin_cs.c. The source directory comes as
 * argv[1]. */
#include <complex.h>
#undef I
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "analyze/analyze_int.h"
#include "check.h"
#include "core/core.h"

typedef double _Complex cplx;

static const char *srcdir = ".";

static unsigned long long rng = 0x9E3779B97F4A7C15ull;
static double srand1(void) {
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 2685821657736338717ull) >> 11) / 4503599627370496.0 - 1.0;
}

/* One probe: a model, its double data and complex data, the base state and the direction. */
typedef struct probe {
  const ap_model *m;
  ap_data *d;
  ap_data_cs *dc;
  double t, *q0, *v0, *dq, *dv, *e0, *de;
  int n, k, b, nphi, l, nout;
  double *phi, *Phi_q;       /* double scratch for ev.phi */
  cplx *phic, *Phi_qc;       /* complex scratch */
} probe;

/* The number of outputs: objects, phi, solve. */
static int count_out(const probe *p) {
  int n = p->n, k = p->k, b = p->b;
  return k * k + n * k + b * k + b + k + k + b + p->nphi * (1 + n) + k * p->l + k + k + k + n;
}

/* Writes every output of a data (double or complex through its real / imaginary parts). */
#define GATHER(T, out, d, phi, Phi_q)                                                      \
  do {                                                                                     \
    size_t o_ = 0;                                                                         \
    for (int i_ = 0; i_ < k * k; i_++) out[o_++] = T((d)->g[i_]);                         \
    for (int i_ = 0; i_ < n * k; i_++) out[o_++] = T((d)->N[i_]);                         \
    for (int i_ = 0; i_ < b * k; i_++) out[o_++] = T((d)->A[i_]);                         \
    for (int i_ = 0; i_ < b; i_++) out[o_++] = T((d)->a0[i_]);                            \
    for (int i_ = 0; i_ < k; i_++) out[o_++] = T((d)->h[i_]);                             \
    for (int i_ = 0; i_ < k; i_++) out[o_++] = T((d)->Q[i_]);                             \
    for (int i_ = 0; i_ < b; i_++) out[o_++] = T((d)->gamma[i_]);                         \
    for (int i_ = 0; i_ < p->nphi; i_++) out[o_++] = T((phi)[i_]);                        \
    for (int i_ = 0; i_ < p->nphi * n; i_++) out[o_++] = T((Phi_q)[i_]);                  \
    objects_end = o_;                                                                      \
  } while (0)

#define GATHER_SOLVE(T, out, d)                                                            \
  do {                                                                                     \
    size_t o_ = objects_end;                                                               \
    for (int i_ = 0; i_ < k * p->l; i_++) out[o_++] = T((d)->B[i_]);                      \
    for (int i_ = 0; i_ < k; i_++) out[o_++] = T((d)->b0[i_]);                            \
    for (int i_ = 0; i_ < k; i_++) out[o_++] = T((d)->w[i_]);                             \
    for (int i_ = 0; i_ < k; i_++) out[o_++] = T((d)->vdot[i_]);                          \
    for (int i_ = 0; i_ < n; i_++) out[o_++] = T((d)->qdot[i_]);                          \
  } while (0)

#define ID(x) (x)
#define RE(x) creal(x)
#define IMH(x) (cimag(x) / AP_CS_STEP)

static size_t objects_end;

/* Every output of the double build at s (ap_an_fn: x = &s). */
static int eval_double(const double *x, double *out, void *user) {
  probe *p = user;
  ap_data *d = p->d;
  int n = p->n, k = p->k, b = p->b;
  d->t = p->t;
  for (int i = 0; i < n; i++) d->q[i] = p->q0[i] + x[0] * p->dq[i];
  for (int i = 0; i < k; i++) d->v[i] = p->v0[i] + x[0] * p->dv[i];
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position(p->m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity(p->m, d);
  if (rc == AP_OK && p->nphi) {
    memset(p->Phi_q, 0, sizeof *p->Phi_q * (size_t)p->nphi * n);
    rc = p->m->ev.phi(p->m, d, ((ap_scratch *)d->internal)->ev, p->phi, p->Phi_q);
  }
  if (rc != AP_OK) return rc;
  GATHER(ID, out, d, p->phi, p->Phi_q);
  d->basis = AP_BASIS_PARTITIONED;
  d->speeds_from_e = 1;   /* v = B(q) e + b0 on the constraints: redundant rows stay consistent */
  for (int j = 0; j < p->l; j++) d->e[j] = p->e0[j] + x[0] * p->de[j];
  rc = ap_forward(p->m, d);
  d->speeds_from_e = 0;
  if (rc != AP_OK) return rc;
  GATHER_SOLVE(ID, out, d);
  return AP_OK;
}

/* Every output of the complex-step build at q0 + i h dq, v0 + i h dv: real parts into re,
 * derivatives into der. */
static int eval_cs(probe *p, double *re, double *der) {
  ap_data_cs *d = p->dc;
  int n = p->n, k = p->k, b = p->b;
  d->t = p->t;
  for (int i = 0; i < n; i++) d->q[i] = p->q0[i] + AP_CS_STEP * p->dq[i] * _Complex_I;
  for (int i = 0; i < k; i++) d->v[i] = p->v0[i] + AP_CS_STEP * p->dv[i] * _Complex_I;
  d->basis = AP_BASIS_NONE;
  int rc = ap_fwd_position_cs(p->m, d);
  if (rc == AP_OK) rc = ap_fwd_velocity_cs(p->m, d);
  if (rc == AP_OK && p->nphi) {
    memset(p->Phi_qc, 0, sizeof *p->Phi_qc * (size_t)p->nphi * n);
    rc = p->m->ev.phi_cs(p->m, d, ((ap_scratch_cs *)d->internal)->ev, p->phic, p->Phi_qc);
  }
  if (rc != AP_OK) return rc;
  GATHER(RE, re, d, p->phic, p->Phi_qc);
  GATHER(IMH, der, d, p->phic, p->Phi_qc);
  d->basis = AP_BASIS_PARTITIONED;
  d->speeds_from_e = 1;
  for (int j = 0; j < p->l; j++) d->e[j] = p->e0[j] + AP_CS_STEP * p->de[j] * _Complex_I;
  rc = ap_forward_cs(p->m, d);
  d->speeds_from_e = 0;
  if (rc != AP_OK) return rc;
  GATHER_SOLVE(RE, re, d);
  GATHER_SOLVE(IMH, der, d);
  return AP_OK;
}

typedef struct worst {
  double ratio;        /* largest |cs - ridders| / (E + floor) */
  double diff, est;    /* at the largest ratio */
  double re;           /* largest relative difference of the real parts */
} worst;

/* Compare at the probe's base state. Returns the worst figures. */
static worst compare(probe *p, const char *label) {
  int m = p->nout;
  double *f0 = calloc((size_t)m, sizeof *f0), *re = calloc((size_t)m, sizeof *re);
  double *der = calloc((size_t)m, sizeof *der), *rd = calloc((size_t)m, sizeof *rd);
  double *err = calloc((size_t)m, sizeof *err);
  double *scr = calloc(ap_an_ridders_scratch(m), sizeof *scr);
  worst w = {0, 0, 0, 0};
  double s = 0.0;
  int rc = eval_double(&s, f0, p);
  AP_CHECK_EQ_INT(rc, AP_OK);
  rc = eval_cs(p, re, der);
  if (rc != AP_OK) fprintf(stderr, "%s: complex step: %s\n", label, p->dc->msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  double *noise = calloc((size_t)m, sizeof *noise);
  double *nscr = calloc((size_t)(AP_AN_NOISE_PTS + 1) * m + 1, sizeof *nscr);
  int rr = ap_an_noise(eval_double, p, 1, &s, m, noise, nscr);
  if (rr == AP_OK)
    rr = ap_an_ridders(eval_double, p, 1, &s, 0, 0.01, AP_AN_EPSF, noise, m, rd, err, scr);
  free(nscr);
  AP_CHECK_EQ_INT(rr, AP_OK);
  if (rc == AP_OK && rr == AP_OK) {
    for (int i = 0; i < m; i++) {
      double scale = fmax(1.0, fabs(rd[i])), floor = 1e-13 * scale;
      double diff = fabs(der[i] - rd[i]), ratio = diff / (err[i] + floor);
      if (ratio > w.ratio) w.ratio = ratio, w.diff = diff, w.est = err[i];
      if (ratio > 1.0)
        fprintf(stderr, "  %s entry %d of %d: cs %.17g ridders %.17g E %.3g value %.6g\n", label,
                i, m, der[i], rd[i], err[i], f0[i]);
      /* the real parts: within the measured round-off of the double values (8 noise), or a
       * few ulps where the noise measures 0 */
      w.re = fmax(w.re, fabs(re[i] - f0[i]) / (8.0 * noise[i] + 4 * DBL_EPSILON *
                                                fmax(1.0, fabs(f0[i]))));
    }
    double rel = 0.0;
    for (int i = 0; i < m; i++) rel = fmax(rel, fabs(der[i] - rd[i]) / fmax(1.0, fabs(rd[i])));
    printf("%-22s outputs %4d  max |cs - ridders| / (E + 1e-13) %.3g (diff %.3g, E %.3g)  "
           "rel %.3g real parts / (8 noise + 4 eps) %.3g\n", label, m, w.ratio, w.diff, w.est, rel, w.re);
    AP_CHECK_LE(w.ratio, 1.0);
    AP_CHECK_LE(w.re, 1.0);
  }
  free(f0), free(re), free(der), free(rd), free(err), free(scr), free(noise);
  return w;
}

static int probe_model(const ap_model *m, const double *q0, const double *v0, double t,
                       const char *label) {
  probe p;
  memset(&p, 0, sizeof p);
  p.m = m, p.t = t, p.n = ap_model_n(m), p.k = ap_model_k(m), p.b = ap_model_b(m);
  p.nphi = m->nphi;
  char why[256];
  int has = ap_core_has_cs(m, why, sizeof why);
  AP_CHECK(has);
  if (!has) return fprintf(stderr, "%s: no complex step: %s\n", label, why), -1;
  AP_CHECK_EQ_INT(ap_data_create(m, &p.d), AP_OK);
  AP_CHECK_EQ_INT(ap_data_create_cs(m, &p.dc), AP_OK);
  size_t nn = (size_t)p.n + 1;
  p.q0 = calloc(nn, sizeof *p.q0), p.dq = calloc(nn, sizeof *p.dq);
  p.v0 = calloc((size_t)p.k, sizeof *p.v0), p.dv = calloc((size_t)p.k, sizeof *p.dv);
  p.phi = calloc((size_t)p.nphi + 1, sizeof *p.phi);
  p.Phi_q = calloc((size_t)(p.nphi + 1) * nn, sizeof *p.Phi_q);
  p.phic = calloc((size_t)p.nphi + 1, sizeof *p.phic);
  p.Phi_qc = calloc((size_t)(p.nphi + 1) * nn, sizeof *p.Phi_qc);
  memcpy(p.q0, q0, sizeof *q0 * (size_t)p.n), memcpy(p.v0, v0, sizeof *v0 * (size_t)p.k);
  for (int i = 0; i < p.n; i++) p.dq[i] = 0.3 * srand1();
  for (int i = 0; i < p.k; i++) p.dv[i] = srand1();
  /* the partition at q0, frozen for both builds */
  memcpy(p.d->q, q0, sizeof *q0 * (size_t)p.n);
  p.d->t = t;
  int rc = ap_partition(m, p.d);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc == AP_OK) {
    ap_core_copy_partition(p.d, p.dc);
    p.l = p.d->l;
    p.e0 = calloc((size_t)p.l + 1, sizeof *p.e0), p.de = calloc((size_t)p.l + 1, sizeof *p.de);
    for (int j = 0; j < p.l; j++) p.e0[j] = v0[p.d->perm[p.d->rank + j]], p.de[j] = srand1();
    p.nout = count_out(&p);
    compare(&p, label);
  }
  ap_data_free(p.d), ap_data_free_cs(p.dc);
  free(p.q0), free(p.dq), free(p.v0), free(p.dv), free(p.phi), free(p.Phi_q), free(p.phic);
  free(p.Phi_qc), free(p.e0), free(p.de);
  return 0;
}

static void probe_scene(const char *dir, const char *file) {
  char path[1024], msg[1024];
  snprintf(path, sizeof path, "%s/%s/%s", srcdir, dir, file);
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, NULL, 0, &sc, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) {
    fprintf(stderr, "%s: %s\n", path, msg);
    return;
  }
  const ap_model *m = ap_scene_model(sc);
  double q[64], v[64];
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  rc = ap_scene_initial_state(sc, q, v, NULL, 0, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc == AP_OK) probe_model(m, q, v, run.t0 + 0.3, file);
  ap_scene_free(sc);
}

int main(int argc, char **argv) {
  if (argc > 1) srcdir = argv[1];
  static const char *const examples[] = {
      "bicycle.yaml", "car_ackermann.yaml", "chaplygin_sleigh.yaml", "diff_drive.yaml",
      "diff_drive_caster.yaml", "diff_drive_loops.yaml", "diff_drive_motors.yaml",
      "heavy_top.yaml", "hoffmann.yaml", "rattleback.yaml", "rolling_disk.yaml",
      "skate_incline.yaml", "skate_wheel.yaml", "sleigh_wheel.yaml", "turntable_ball.yaml"};
  for (size_t i = 0; i < sizeof examples / sizeof *examples; i++)
    probe_scene("examples/scenes", examples[i]);
  static const char *const act[] = {"act_spring.yaml", "act_slider.yaml", "act_follow.yaml",
                                    "act_flywheel.yaml", "act_torque_t.yaml"};
  for (size_t i = 0; i < sizeof act / sizeof *act; i++) probe_scene("tests/scenes", act[i]);
  return ap_check_finish("model_cs");
}
