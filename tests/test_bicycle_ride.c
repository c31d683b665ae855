/* The Whipple bicycle built from bodies (examples/scenes/bicycle.yaml, docs/vehicles.md), riding
 * (its accelerations against Basu-Mandal's benchmark are in test_bicycle.c):
 * 10 s from the scene's state (4.6 m/s, roll rate 0.5 rad/s) in the three modes at rtol 1e-10:
 * energy, contact rows, A v, and the lean and steer against a run at rtol 1e-13; and a roll
 * rate of 1e-4 rad/s against Meijaard's linearized equations (his M, C1, K0, K2), Meijaard,
 * Papadopoulos, Ruina and Schwab, Proc. R. Soc. A 463 (2007) 1955-1982. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

static const double grav = 9.81;
static const double pi = 3.14159265358979323846;

/* ---- riding: 10 s from the scene's initial state (4.6 m/s, roll rate 0.5 rad/s) -------------- */

#define RIDE_OUT 1000          /* outputs every 0.01 s */

typedef struct ride {
  double drift;                /* max |E - E0| / E0 */
  double front, rear;          /* max |contact row| at the outputs (m) */
  double resid;                /* max |A v| at the outputs */
  double lean[RIDE_OUT + 1], steer[RIDE_OUT + 1];
  ap_sim_stats st;
  int rc;
} ride;

static void ride_run(const bike *bk, ap_mode mode, double rtol, ride *out) {
  ap_scene_run run;
  ap_scene_get_run(bk->sc, &run);
  run.sim.mode = mode, run.sim.rtol = rtol, run.sim.atol = 1e-2 * rtol;
  double q[10], v[9], E0, E, h[2], res;
  char msg[1024] = "";
  ap_sim *sim = NULL;
  ap_data *d = NULL;
  memset(out, 0, sizeof *out);
  out->rc = ap_scene_initial_state(bk->sc, q, v, NULL, 0, msg, sizeof msg);
  if (out->rc == AP_OK) out->rc = ap_data_create(bk->m, &d);
  if (out->rc == AP_OK) out->rc = ap_scene_energy(bk->sc, 0, q, v, &E0);
  if (out->rc == AP_OK) out->rc = ap_sim_create(bk->m, &run.sim, 0, q, v, &sim, msg, sizeof msg);
  for (int i = 0; out->rc == AP_OK && i <= RIDE_OUT; i++) {
    if (i > 0 && (out->rc = ap_sim_advance(sim, 0.01 * i)) != AP_OK) {
      snprintf(msg, sizeof msg, "%s", ap_sim_message(sim));
      break;
    }
    const double *qs = ap_sim_q(sim), *vs = ap_sim_v(sim), *p = qs + bk->cq;
    out->rc = scene_eval(bk, d, qs, vs, h, NULL, NULL);
    if (out->rc == AP_OK) out->rc = ap_scene_energy(bk->sc, 0.01 * i, qs, vs, &E);
    if (out->rc == AP_OK) out->rc = ap_scene_residual(bk->sc, 0.01 * i, qs, vs, &res);
    out->drift = fmax(out->drift, fabs(E - E0) / fabs(E0));
    out->rear = fmax(out->rear, fabs(h[0])), out->front = fmax(out->front, fabs(h[1]));
    out->resid = fmax(out->resid, res);
    /* lean (roll, + right) = tilt - pi/2; the tilt's cosine is the axle's z, R_33 */
    double nn = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
    out->lean[i] = acos(1 - 2 * (p[1] * p[1] + p[2] * p[2]) / nn) - pi / 2;
    out->steer[i] = qs[bk->cH];
  }
  if (out->rc != AP_OK) fprintf(stderr, "ride (mode %d): %s\n", (int)mode, msg);
  if (sim) ap_sim_get_stats(sim, &out->st);
  ap_sim_free(sim);
  ap_data_free(d);
}

static double ride_diff(const ride *a, const ride *b) {
  double e = 0;
  for (int i = 0; i <= RIDE_OUT; i++)
    e = fmax(e, fmax(fabs(a->lean[i] - b->lean[i]), fabs(a->steer[i] - b->steer[i])));
  return e;
}

static void test_ride(const bike *bk) {
  static ride r[3], tight;
  const double rtol = 1e-10;
  const char *names[3] = {"minimal", "projected", "dae"};
  ride_run(bk, AP_MODE_MINIMAL, 1e-13, &tight);
  AP_CHECK_EQ_INT(tight.rc, AP_OK);
  for (int mo = 0; mo < 3; mo++) {
    ride_run(bk, (ap_mode)mo, rtol, &r[mo]);
    AP_CHECK_EQ_INT(r[mo].rc, AP_OK);
    printf("ride 10 s, %-9s rtol %.0e: energy drift %.1e relative, contact rows rear %.1e "
           "front %.1e m, max |A v| %.1e, steps %ld; lean and steer vs rtol 1e-13: %.1e rad\n",
           names[mo], rtol, r[mo].drift, r[mo].rear, r[mo].front, r[mo].resid, r[mo].st.steps,
           ride_diff(&r[mo], &tight));
    /* The bound on the energy; the trajectories within 100 rtol of the tight run. */
    AP_CHECK_LE(r[mo].drift, 1e-10);
    AP_CHECK_LE(ride_diff(&r[mo], &tight), 100 * rtol);
    /* Appell modes: A v = 0 by construction (round-off), the contact rows held below the
     * projection tolerance 1e-12 x the model's length scale (1.0025 m here); IDA holds them
     * to its own tolerance. */
    AP_CHECK_LE(r[mo].resid, mo == 2 ? 100 * rtol : 1e-13);
    AP_CHECK_LE(fmax(r[mo].front, r[mo].rear), mo == 2 ? 100 * rtol : 1.0025e-12);
  }
  printf("  lean at 0.5 s %.6f rad, steer %.6f rad; at 10 s %.2e, %.2e (the weave decays)\n",
         tight.lean[50], tight.steer[50], tight.lean[RIDE_OUT], tight.steer[RIDE_OUT]);
}

/* ---- small motions: Meijaard's linearized equations ------------------------------------------ */

/* M q'' + v C1 q' + (g K0 + v^2 K2) q = 0, q = (roll, steer), the benchmark's matrices. */
static void linear_rates(double v, const double x[4], double xd[4]) {
  static const double M[2][2] = {{80.81722, 2.31941332208709}, {2.31941332208709, 0.29784188199686}};
  static const double C1[2][2] = {{0, 33.86641391492494}, {-0.85035641456978, 1.68540397397560}};
  static const double K0[2][2] = {{-80.95, -2.59951685249872}, {-2.59951685249872, -0.80329488458618}};
  static const double K2[2][2] = {{0, 76.59734589573222}, {0, 2.65431523794604}};
  double f[2], det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
  for (int i = 0; i < 2; i++)
    f[i] = -v * (C1[i][0] * x[2] + C1[i][1] * x[3]) -
           (grav * K0[i][0] + v * v * K2[i][0]) * x[0] - (grav * K0[i][1] + v * v * K2[i][1]) * x[1];
  xd[0] = x[2], xd[1] = x[3];
  xd[2] = (M[1][1] * f[0] - M[0][1] * f[1]) / det;
  xd[3] = (M[0][0] * f[1] - M[1][0] * f[0]) / det;
}

/* A roll rate of eps at 4.6 m/s: the body model's lean (tilt - pi/2) and steer
 * (front_frame.angle) follow the linearized benchmark to higher order in eps, which confirms that
 * they are Meijaard's roll and steer with his signs. The linear solution by RK4, h = 1e-3. */
static void test_linear(void) {
  const double eps = 1e-4, v = 4.6;
  const char *set = "initial.rear_frame.tilt_rate=1e-4";
  bike bk;
  if (!bike_load(&bk, &set, 1)) return;
  static ride r;
  ride_run(&bk, AP_MODE_MINIMAL, 1e-12, &r);
  AP_CHECK_EQ_INT(r.rc, AP_OK);
  double x[4] = {0, 0, eps, 0}, err = 0, amp = 0;
  const double h = 1e-3;
  for (int i = 0; i <= RIDE_OUT; i++) {
    err = fmax(err, fmax(fabs(r.lean[i] - x[0]), fabs(r.steer[i] - x[1])));
    amp = fmax(amp, fmax(fabs(x[0]), fabs(x[1])));
    for (int s = 0; s < 10; s++) {
      double k[4][4], y[4];
      linear_rates(v, x, k[0]);
      for (int j = 0; j < 4; j++) y[j] = x[j] + 0.5 * h * k[0][j];
      linear_rates(v, y, k[1]);
      for (int j = 0; j < 4; j++) y[j] = x[j] + 0.5 * h * k[1][j];
      linear_rates(v, y, k[2]);
      for (int j = 0; j < 4; j++) y[j] = x[j] + h * k[2][j];
      linear_rates(v, y, k[3]);
      for (int j = 0; j < 4; j++) x[j] += h / 6 * (k[0][j] + 2 * k[1][j] + 2 * k[2][j] + k[3][j]);
    }
  }
  printf("roll rate %.0e rad/s at %.1f m/s: lean and steer follow Meijaard's linearized "
         "equations to %.1e of their amplitude %.2e rad over 10 s\n", eps, v, err / amp, amp);
  /* The bicycle is symmetric: the first neglected terms are cubic, relative size amp^2
   * (~1e-9) times O(1) constants; the integration errors (rtol 1e-12, RK4 h^4) are smaller. */
  AP_CHECK_LE(err / amp, 1e-7);
  ap_scene_free(bk.sc);
}
int main(void) {
  bike bk;
  if (!bike_load(&bk, NULL, 0)) return ap_check_finish("bicycle_ride");
  test_ride(&bk);
  test_linear();
  ap_scene_free(bk.sc);
  return ap_check_finish("bicycle_ride");
}
