/* Accuracy on demand (include/appell/accuracy.h) against closed forms (docs/references.md):
 * the knife edge on an incline, the Chaplygin sleigh, the ball on a turntable (steady and
 * spinning up) and the bead on a rotating line, 10 output times each.
 *  1. The a-posteriori global error estimate (ap_global_error) lies within a factor 3 of the
 *     true error (against the closed form, in the same norm) from rtol 1e-4 to 1e-12, for
 *     dopri5 and dop853.
 *  2. ap_accuracy_pick reaches the requested accuracy (against the closed form) at 1e-4,
 *     1e-6, 1e-8 and 1e-10.
 *  3. The body-built ball on a turntable: its orientation is free (nothing depends on it);
 *     left out of the error control, the run takes about as many steps as the hand model and
 *     its position error against the closed form stays at the tolerance. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "appell/appell.h"
#include "bodysys.h"
#include "check.h"
#include "refsys.h"

#define NT 10
#define NPROB 5

typedef struct prob {
  const char *name;
  ap_system_def def;
  ap_model *m;
  double q0[8], v0[8], T;
  int npos;
  double exact[NT][3];
  union {
    rs_knife knife;
    rs_sleigh sleigh;
    rs_turntable turn;
    rs_line line;
  } p;
} prob;

static int out_pos(ap_sim *s, double *row, void *user) {
  const prob *pr = user;
  memcpy(row, ap_sim_q(s), sizeof(double) * (size_t)pr->npos);
  return AP_OK;
}

static void times_of(const prob *pr, double *t) {
  for (int i = 0; i < NT; i++) t[i] = pr->T * (i + 1) / NT;
}

static void setup(prob *P) {
  memset(P, 0, sizeof(prob) * NPROB);
  P[0].name = "knife_edge", P[0].p.knife = (rs_knife){.m = 2.0, .J = 0.3, .grav = 9.81,
                                                      .alpha = 0.4};
  rs_knife_system(&P[0].p.knife, &P[0].def);
  rs_knife_initial(0.0, 0.0, 0.3, 1.0, 2.0, P[0].q0, P[0].v0);
  P[0].T = 10.0, P[0].npos = 2;
  P[1].name = "sleigh", P[1].p.sleigh = (rs_sleigh){.m = 1.0, .I = 1.0, .a = 1.0};
  rs_sleigh_system(&P[1].p.sleigh, 1, &P[1].def);
  rs_sleigh_initial(0.0, 0.0, 0.0, 0.5, 2.0, P[1].q0, P[1].v0);
  P[1].T = 6.0, P[1].npos = 2;
  for (int v = 0; v < 2; v++) {
    prob *pr = &P[2 + v];
    pr->name = v ? "turntable_var" : "turntable";
    pr->p.turn = (rs_turntable){.m = 1.0, .R = 0.1, .kI = 0.4, .Omega0 = v ? 0.5 : 2.0,
                                .dOmega = v ? 0.1 : 0.0};
    rs_turntable_system(&pr->p.turn, &pr->def);
    rs_turntable_initial(&pr->p.turn, 0.3, -0.1, 1.0, -2.0, 3.0, pr->q0, pr->v0);
    pr->T = 16.0, pr->npos = 2;
  }
  P[4].name = "rotating_line", P[4].p.line = (rs_line){.m = 1.0, .grav = 9.81, .alpha = 0.6,
                                                       .w = 2.0};
  rs_line_3d_system(&P[4].p.line, &P[4].def);
  rs_line_lift(&P[4].p.line, 0.0, 6.0, 0.2, P[4].q0, P[4].v0);
  P[4].T = 4.0, P[4].npos = 3;
  for (int i = 0; i < NPROB; i++) {
    AP_CHECK_EQ_INT(ap_model_from_system(&P[i].def, &P[i].m, NULL, 0), AP_OK);
    for (int j = 0; j < NT; j++) {
      double t = P[i].T * (j + 1) / NT, q[8], r;
      if (i == 0) rs_knife_exact(&P[i].p.knife, P[i].q0, P[i].v0, t, q, NULL, NULL);
      else if (i == 1) rs_sleigh_exact(&P[i].p.sleigh, P[i].q0, P[i].v0, t, q, NULL);
      else if (i < 4) rs_turntable_exact(&P[i].p.turn, P[i].q0, P[i].v0, t, q, NULL);
      else rs_line_exact(&P[i].p.line, 6.0, 0.2, t, &r, NULL),
           rs_line_lift(&P[i].p.line, t, r, 0.0, q, NULL);
      memcpy(P[i].exact[j], q, sizeof(double) * (size_t)P[i].npos);
    }
  }
}

/* The true error of rows (NT x npos) in the norm of ap_error_norm. */
static double true_error(const prob *pr, const double *rows) {
  double err[3] = {0}, scale[3] = {0};
  for (int j = 0; j < NT; j++) ap_error_fold(pr->npos, rows + j * pr->npos, pr->exact[j], err,
                                             scale);
  return ap_error_norm(pr->npos, err, scale);
}

/* 1. Estimate against truth; returns the worst ratio (max of est/true and true/est). */
static double check_estimate(prob *pr, const char *method, double rtol, int assert_it) {
  ap_sim_def def = ap_sim_def_default();
  def.method = method, def.rtol = def.atol = rtol;
  double t[NT], rows[NT * 3];
  times_of(pr, t);
  ap_error_report rep;
  char msg[512];
  int rc = ap_global_error(pr->m, &def, 0.0, pr->q0, pr->v0, t, NT, pr->npos, out_pos, NULL,
                           pr, rows, NULL, NULL, &rep, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return INFINITY;
  double tru = true_error(pr, rows), ratio = rep.error / tru;
  double worst = fmax(ratio, 1.0 / ratio);
  printf("  %-14s %-7s rtol %.0e: true %.3e estimate %.3e ratio %.3f (evals %ld + %ld)\n",
         pr->name, method, rtol, tru, rep.error, ratio, rep.run.rhs_evals,
         rep.ref_stats.rhs_evals);
  if (assert_it) AP_CHECK_LE(worst, 3.0);
  return worst;
}

static void check_pick(prob *pr, double accuracy) {
  ap_sim_def def = ap_sim_def_default();
  double t[NT], rows[NT * 3];
  times_of(pr, t);
  ap_pick_report pk;
  char msg[512];
  int rc = ap_accuracy_pick(pr->m, &def, 0.0, pr->q0, pr->v0, t, NT, pr->npos, out_pos, NULL,
                            pr, accuracy, &pk, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc != AP_OK) return (void)printf("  pick failed: %s\n", msg);
  ap_error_report rep;
  rc = ap_global_error(pr->m, &pk.def, 0.0, pr->q0, pr->v0, t, NT, pr->npos, out_pos, NULL, pr,
                       rows, NULL, NULL, &rep, msg, sizeof msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  double tru = true_error(pr, rows);
  printf("  %-14s accuracy %.0e: picked %s rtol %.3g, true error %.3e, evals %ld (predicted "
         "%.0f), pilot %ld\n", pr->name, accuracy, pk.def.method, pk.def.rtol, tru,
         rep.run.rhs_evals, pk.predicted_evals, pk.pilot_evals);
  AP_CHECK_LE(tru, accuracy);
}

/* 3. The body-built ball on a turntable (tests/bodysys.c) against the hand model (refsys). */
static void check_free_ball(void) {
  static rs_turntable tp = {1.0, 0.1, 0.4, 2.0, 0.0};
  ap_model *m = bs_turntable_model(&tp), *h = NULL;
  ap_system_def hd;
  rs_turntable_system(&tp, &hd);
  AP_CHECK(m != NULL);
  AP_CHECK_EQ_INT(ap_model_from_system(&hd, &h, NULL, 0), AP_OK);
  if (!m || !h) return;
  double qh[5], vh[5];
  rs_turntable_initial(&tp, 0.3, -0.1, 1.0, -2.0, 3.0, qh, vh);
  double qb[6] = {qh[0], qh[1], 1, 0, 0, 0}, eh, e0, e1;   /* x, y, quaternion (w x y z) */
  int fl[6] = {0};
  long nh = bs_turntable_run(h, &tp, qh, vh, qh, vh, "dopri5", 1e-8, 0, NULL, &eh);
  long n0 = bs_turntable_run(m, &tp, qb, vh, qh, vh, "dopri5", 1e-8, 0, NULL, &e0);
  long n1 = bs_turntable_run(m, &tp, qb, vh, qh, vh, "dopri5", 1e-8, 1, fl, &e1);
  AP_CHECK_EQ_INT(ap_model_n(m), 6);
  for (int i = 0; i < 6; i++) AP_CHECK_EQ_INT(fl[i], i >= 2);   /* the quaternion only */
  printf("ball on a turntable, rtol 1e-8: hand model %ld steps (error %.3g m), body model %ld "
         "steps (%.3g m), orientation uncontrolled %ld steps (%.3g m)\n", nh, eh, n0, e0, n1,
         e1);
  AP_CHECK_LE(n1, nh + nh / 4);   /* about as many steps as the hand model */
  AP_CHECK_LE(e1, 10 * 1e-8);     /* the position still within 10 rtol of the closed form */
  AP_CHECK_LE(e0, 10 * 1e-8);
  ap_model_free(m);
  ap_model_free(h);
}

int main(void) {
  prob P[NPROB];
  setup(P);
  static const double rtols[5] = {1e-4, 1e-6, 1e-8, 1e-10, 1e-12};
  static const char *const methods[2] = {"dopri5", "dop853"};
  printf("global error estimate / true error:\n");
  double worst = 0.0;
  for (int i = 0; i < NPROB; i++)
    for (int m = 0; m < 2; m++)
      for (int r = 0; r < 5; r++)
        worst = fmax(worst, check_estimate(&P[i], methods[m], rtols[r], 1));
  printf("worst factor %.3f\n", worst);
  printf("accuracy picker:\n");
  static const double acc[4] = {1e-4, 1e-6, 1e-8, 1e-10};
  for (int i = 0; i < NPROB; i++)
    for (int a = 0; a < 4; a++) check_pick(&P[i], acc[a]);
  check_free_ball();
  for (int i = 0; i < NPROB; i++) ap_model_free(P[i].m);
  return ap_check_finish("accuracy");
}
