/* The rolling disk from bodies (docs/references.md §4): a thin uniform disk (m, r; A = m r^2/4,
 * C = m r^2/2) on the plane-contact joint, rolling without slip, under gravity.
 *
 * The disk's state is read in docs/references.md §4's variables: the axis a = R e_z has
 * a_z = -sin(theta) (theta = lean; the centre sits r b_up above the contact, b_up the upward
 * unit vector in the disk plane), w_a = w . b_up = psi' cos(theta), w_n = w . a = phi' - psi' sin(theta), and
 * theta' from a' = w x a. Checks (tolerances from rtol 1e-11, atol 1e-13):
 *   - the reference's energy equals T + V of the body model at the same state (round-off, 1e-14);
 *   - energy conserved to 1e-9 relative over 10 s, constraint residual at round-off, in the
 *     minimal and projected modes;
 *   - theta, w_a, w_n follow the reference's three equations (integrated as a math-level system by
 *     the same driver) to 1e-8 over 10 s;
 *   - steady circular rolling (theta' = 0, Omega, w_n from the steady relation) held for 5 s:
 *     theta, w_a, w_n constant to 1e-8;
 *   - upright rolling at 1.05 and 0.95 of the critical speed sqrt(g r / 3) with a 1e-3 rad/s
 *     lean-rate kick: the tilt stays below 3e-3 rad above (linear theory: amplitude ~6e-4) and
 *     grows past 0.1 rad below (linear growth rate 1.6/s);
 *   - near lying flat: the Euler-disk steady motion 0.1 degree from flat (and 0.1 degree
 *     beyond) integrated accurately (energy 1e-9, lean constant to 1e-6 degree); a disk and a
 *     torus falling flat stop with an error naming the body, never NaN;
 *   - the three modes (minimal, projected, DAE) agree (ap_crosscheck). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "bodysys.h"

#define RTOL 1e-11
#define ATOL 1e-13

static double ref_energy(const bs_disk *p, double th, double thd, double wa, double wn) {
  double mr2 = p->m * p->r * p->r;
  return 0.5 * mr2 * (wn * wn + thd * thd) +
         0.5 * (p->A * thd * thd + p->A * wa * wa + p->C * wn * wn) +
         p->m * p->grav * p->r * cos(th);
}

/* ---- docs/references.md §4's equations as a math-level system -------------------------------
 * q = (theta, alpha, beta), v = (theta', w_a, w_n) with alpha' = w_a, beta' = w_n pseudo-
 * coordinates that never enter the dynamics; g = diag(A + m r^2, A, C + m r^2),
 * h = ((C + m r^2) w_a w_n + A w_a^2 tan(theta), -theta' (C w_n + A w_a tan(theta)),
 * -m r^2 theta' w_a), Q = (m g r sin(theta), 0, 0). */
static int ref_metric(double t, const double *q, double *g, void *user) {
  const bs_disk *p = user;
  (void)t, (void)q;
  g[0] = p->A + p->m * p->r * p->r, g[4] = p->A, g[8] = p->C + p->m * p->r * p->r;
  return 0;
}
static int ref_bias(double t, const double *q, const double *v, double *h, void *user) {
  const bs_disk *p = user;
  double tn = tan(q[0]), mr2 = p->m * p->r * p->r;
  (void)t;
  h[0] = (p->C + mr2) * v[1] * v[2] + p->A * v[1] * v[1] * tn;
  h[1] = -v[0] * (p->C * v[2] + p->A * v[1] * tn);
  h[2] = -mr2 * v[0] * v[1];
  return 0;
}
static int ref_force(double t, const double *q, const double *v, double *Q, void *user) {
  const bs_disk *p = user;
  (void)t, (void)v;
  Q[0] = p->m * p->grav * p->r * sin(q[0]);
  return 0;
}

static ap_sim *start(const ap_model *m, ap_mode mode, const char *method, const double *q0,
                     const double *v0) {
  return bs_start(m, mode, method, RTOL, ATOL, q0, v0);
}

/* ---- energy over 10 s, and the reference's equations ----------------------------------------- */

static void test_energy_and_equations(void) {
  bs_disk p = bs_disk_default();
  ap_model *m = bs_disk_model(&p);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double q0[6], v0[5], th, thd, wa, wn;
  AP_CHECK_EQ_INT(bs_disk_state(m, d, 0.3, 0.25, 0.7, 0.4, 1.2, 7.0, q0, v0), AP_OK);
  bs_disk_read(q0, v0, &th, &thd, &wa, &wn);
  double E0 = bs_energy(m, d, q0, v0), Er = ref_energy(&p, th, thd, wa, wn);
  printf("rolling disk: theta %.3f theta' %.3f w_a %.3f w_n %.3f; energy %.15f (reference: "
         "%.15f)\n", th, thd, wa, wn, E0, Er);
  AP_CHECK_NEAR(E0, Er, 1e-14 * fabs(Er));
  AP_CHECK_NEAR(th, 0.25, 1e-14);
  AP_CHECK_NEAR(thd, 0.4, 1e-14);

  ap_system_def def = ap_system_def_default();
  def.name = "reference 4", def.n = def.k = 3, def.metric = ref_metric, def.bias = ref_bias;
  def.force = ref_force, def.user = &p;
  ap_model *mr = NULL;
  char msg[256];
  AP_CHECK_EQ_INT(ap_model_from_system(&def, &mr, msg, sizeof msg), AP_OK);
  double qr0[3] = {th, 0, 0}, vr0[3] = {thd, wa, wn};
  ap_sim *sr = start(mr, AP_MODE_MINIMAL, "verner6", qr0, vr0);
  const char *methods[2] = {"verner6", "fehlberg8"};
  double refs[21][4];   /* the reference solution at the output times */
  for (int i = 1; sr && i <= 20; i++) {
    AP_CHECK_EQ_INT(ap_sim_advance(sr, 0.5 * i), AP_OK);
    const double *qr = ap_sim_q(sr), *vr = ap_sim_v(sr);
    refs[i][0] = qr[0], refs[i][1] = vr[0], refs[i][2] = vr[1], refs[i][3] = vr[2];
  }
  for (int mode = 0; mode < 2; mode++) {
    ap_sim *s = start(m, mode ? AP_MODE_PROJECTED : AP_MODE_MINIMAL, methods[mode], q0, v0);
    double dE = 0.0, dref = 0.0;
    for (int i = 1; s && i <= 20; i++) {
      double t = 0.5 * i;
      if (ap_sim_advance(s, t) != AP_OK) {
        fprintf(stderr, "%s\n", ap_sim_message(s));
        AP_CHECK(0);
        break;
      }
      dE = fmax(dE, fabs(bs_energy(m, d, ap_sim_q(s), ap_sim_v(s)) - E0) / fabs(E0));
      bs_disk_read(ap_sim_q(s), ap_sim_v(s), &th, &thd, &wa, &wn);
      double got[4] = {th, thd, wa, wn}, *ref = refs[i];
      for (int c = 0; c < 4; c++) dref = fmax(dref, fabs(got[c] - ref[c]) / fmax(1, fabs(ref[c])));
    }
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    printf("  %-9s %-9s 10 s: energy drift %.1e, the reference's equations %.1e, residual %.1e, "
           "steps %ld, switches %ld\n", mode ? "projected" : "minimal", methods[mode], dE, dref,
           st.max_residual, st.steps, st.partition_switches);
    AP_CHECK_LE(dE, 1e-9);
    AP_CHECK_LE(dref, 1e-8);
    AP_CHECK_LE(st.max_residual, mode ? 1e-10 : 1e-13);
    ap_sim_free(s);
  }
  ap_sim_free(sr);
  ap_model_free(mr);

  /* the three modes agree */
  ap_sim_def sd = ap_sim_def_default();
  ap_crosscheck_report rep;
  sd.rtol = 1e-10, sd.atol = 1e-12;
  int rc = ap_crosscheck(m, &sd, 0.0, q0, v0, 2.0, 20, &rep, msg, sizeof msg);
  if (rc != AP_OK) fprintf(stderr, "crosscheck: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  printf("  crosscheck 2 s: |dq| projected %.1e DAE %.1e; |dlambda| projected %.1e DAE %.1e "
         "(|lambda| %.2g)\n", rep.dq_projected, rep.dq_dae, rep.dlambda_projected,
         rep.dlambda_dae, rep.max_lambda);
  AP_CHECK_LE(rep.dq_projected, 1e-7);
  AP_CHECK_LE(rep.dq_dae, 1e-7);   /* IDA (BDF, index 2) at rtol 1e-10: a few 1e-9 seen */
  ap_data_free(d);
  ap_model_free(m);
}

/* ---- steady circular rolling ----------------------------------------------------------------- */

static void test_steady(void) {
  bs_disk p = bs_disk_default();
  ap_model *m = bs_disk_model(&p);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  const double cases[3][2] = {{0.3, 2.0}, {-0.5, -3.0}, {1.2, 6.0}};   /* theta, Omega */
  for (int c = 0; c < 3; c++) {
    double th0 = cases[c][0], Om = cases[c][1], wa0, wn0;
    bs_disk_steady_rates(&p, th0, Om, &wa0, &wn0);
    double q0[6], v0[5], th, thd, wa, wn, dev = 0.0;
    AP_CHECK_EQ_INT(bs_disk_state(m, d, 0.4, th0, 0.0, 0.0, wa0, wn0, q0, v0), AP_OK);
    ap_sim *s = start(m, AP_MODE_MINIMAL, "verner6", q0, v0);
    for (int i = 1; s && i <= 10; i++) {
      AP_CHECK_EQ_INT(ap_sim_advance(s, 0.5 * i), AP_OK);
      bs_disk_read(ap_sim_q(s), ap_sim_v(s), &th, &thd, &wa, &wn);
      dev = fmax(dev, fmax(fabs(th - th0), fmax(fabs(wa - wa0), fabs(wn - wn0))));
    }
    printf("steady rolling theta %.2f Omega %.1f (w_n %.4f): max deviation over 5 s %.1e\n",
           th0, Om, wn0, dev);
    AP_CHECK_LE(dev, 1e-8);
    ap_sim_free(s);
  }
  ap_data_free(d);
  ap_model_free(m);
}

/* ---- the critical speed of upright rolling --------------------------------------------------- */

static double max_tilt(const ap_model *m, ap_data *d, double speed) {
  const bs_disk p = bs_disk_default();
  double q0[6], v0[5], th, thd, wa, wn, mx = 0.0;
  AP_CHECK_EQ_INT(bs_disk_state(m, d, 0.0, 0.0, 0.0, 1e-3, 0.0, speed / p.r, q0, v0), AP_OK);
  ap_sim *s = start(m, AP_MODE_MINIMAL, "dopri5", q0, v0);
  for (int i = 1; s && i <= 100; i++) {
    AP_CHECK_EQ_INT(ap_sim_advance(s, 0.05 * i), AP_OK);
    bs_disk_read(ap_sim_q(s), ap_sim_v(s), &th, &thd, &wa, &wn);
    mx = fmax(mx, fabs(th));
    if (mx > 0.3) break;
  }
  ap_sim_free(s);
  return mx;
}

static void test_critical(void) {
  bs_disk p = bs_disk_default();
  ap_model *m = bs_disk_model(&p);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double vc = sqrt(p.grav * p.r / 3);
  double hi = max_tilt(m, d, 1.05 * vc), lo = max_tilt(m, d, 0.95 * vc);
  printf("critical speed %.4f m/s: max tilt over 5 s at 1.05 vc %.2e rad, at 0.95 vc %.2e rad\n",
         vc, hi, lo);
  AP_CHECK_LE(hi, 3e-3);
  AP_CHECK(lo > 0.1);
  ap_data_free(d);
  ap_model_free(m);
}

/* ---- near lying flat ------------------------------------------------------------------------- */

/* The Euler-disk steady motion 0.1 degree from flat: w_n = 0, Omega^2 A cos(theta) = m g r, the
 * centre at rest and the contact point running round the rim at Omega. flip turns the body
 * upside down (axis 0.1 degree beyond flat, the same motion). */
static void euler_disk(int flip) {
  bs_disk p = bs_disk_default();
  ap_model *m = bs_disk_model(&p);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double th0 = (90.0 - 0.1) * RS_PI / 180, Om = sqrt(p.m * p.grav * p.r / (p.A * cos(th0)));
  double q0[6], v0[5], th, thd, wa, wn, dth = 0.0, dE = 0.0;
  AP_CHECK_EQ_INT(bs_disk_state(m, d, 0.0, th0, 0.0, 0.0, Om * cos(th0), 0.0, q0, v0), AP_OK);
  if (flip) {
    double qf[4] = {0, 1, 0, 0}, qn[4];
    ap_quat_mul(q0 + 2, qf, qn);
    memcpy(q0 + 2, qn, sizeof qn);
  }
  double E0 = bs_energy(m, d, q0, v0);
  ap_sim *s = start(m, AP_MODE_MINIMAL, "verner6", q0, v0);
  for (int i = 1; s && i <= 20; i++) {
    int rc = ap_sim_advance(s, 0.01 * i);
    if (rc != AP_OK) fprintf(stderr, "%s\n", ap_sim_message(s));
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) break;
    bs_disk_read(ap_sim_q(s), ap_sim_v(s), &th, &thd, &wa, &wn);
    dth = fmax(dth, fabs(fabs(th) - th0));
    dE = fmax(dE, fabs(bs_energy(m, d, ap_sim_q(s), ap_sim_v(s)) - E0) / E0);
  }
  ap_sim_stats st;
  ap_sim_get_stats(s, &st);
  printf("Euler disk %s flat (Omega %.1f rad/s), 0.2 s: lean change %.1e deg, energy drift "
         "%.1e, steps %ld\n", flip ? "0.1 deg beyond" : "0.1 deg from", Om, dth * 180 / RS_PI, dE,
         st.steps);
  AP_CHECK_LE(dth * 180 / RS_PI, 1e-6);
  AP_CHECK_LE(dE, 1e-9);
  ap_sim_free(s);
  ap_data_free(d);
  ap_model_free(m);
}

/* Released at rest at a 0.5 rad lean, a disk (or torus) falls flat: the simulation must stop
 * with an error naming the body, with a finite state. */
static void falls_flat(int torus) {
  bs_disk p = bs_disk_default();
  p.torus = torus;
  ap_model *m = bs_disk_model(&p);
  ap_data *d = NULL;
  ap_data_create(m, &d);
  double q0[6], v0[5];
  AP_CHECK_EQ_INT(bs_disk_state(m, d, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, q0, v0), AP_OK);
  ap_sim *s = start(m, AP_MODE_MINIMAL, "dopri5", q0, v0);
  int rc = s ? ap_sim_advance(s, 3.0) : AP_OK;
  const char *msg = s ? ap_sim_message(s) : "";
  printf("%s released at a 0.5 rad lean: status %d at t = %.6f: %s\n", torus ? "torus" : "disk",
         rc, s ? ap_sim_time(s) : 0.0, msg);
  AP_CHECK(rc < 0);
  AP_CHECK(strstr(msg, torus ? "body 'wheel'" : "body 'disk'") != NULL);
  AP_CHECK(strstr(msg, "flat") != NULL);
  for (int i = 0; s && i < 6; i++) AP_CHECK(isfinite(ap_sim_q(s)[i]));
  ap_sim_free(s);
  ap_data_free(d);
  ap_model_free(m);
}

int main(void) {
  test_energy_and_equations();
  test_steady();
  test_critical();
  euler_disk(0);
  euler_disk(1);
  falls_flat(0);
  falls_flat(1);
  AP_CHECK_EQ_INT(bs_failures(), 0);
  return ap_check_finish("test_body_disk");
}
