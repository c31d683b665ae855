/* Friction under a planar chassis in DAE mode (docs/vehicles.md "Skidding and breaking away";
 * lib/integrate/dae_loads.c): IDA solves each sliding wheel's true load (the chassis joint's
 * vertical reaction and tilting moments shared among the contacts) with the accelerations and
 * the multipliers. The braking robot of examples/scenes/diff_drive_skid.yaml and
 * diff_drive_brake.yaml on a planar chassis, in DAE mode against minimal mode (dop853), against
 * closed forms, and against the same robot on a free chassis (where the loads are the contact
 * rows' multipliers):
 *
 *   skid      every wheel locked at v0 = 1 m/s, the drive wheels' mu_kinetic 0.4, the caster's
 *             0.1: every contact slides along -x, and the deceleration depends on how the load
 *             is shared (the caster's share brakes less), which depends on the deceleration
 *             (load transfer): with the bodies' mass moments Sx = sum m x_com = -0.898 kg m and
 *             Sz = sum m z_com = 1.62 kg m about the drive axle's ground point, and the caster's
 *             contact at x_c = -0.34 m, pitch balance and M a = -(mu_d (M g - N_c) + mu_c N_c)
 *             give N_c = (g Sx - a Sz) / x_c and
 *                 a (M - (mu_c - mu_d) Sz / x_c) = -mu_d M g - (mu_c - mu_d) g Sx / x_c,
 *             a = -3.7048 m/s^2, N_c = 8.2578 N: every contact sticks at t* = v0 / |a| and the
 *             robot stands at x* = v0^2 / (2 |a|). (With equal mu_kinetic the loads' sum alone
 *             would decide the motion.)
 *   slip onset  brakes growing as 4 t N m per drive wheel, mu 0.3, mu_kinetic 0.25: the drive
 *             wheels slip where their friction demand reaches mu times their load (rolling:
 *             the slip event on IDA's multipliers and accelerations), then slide; the state at
 *             0.8 s;
 *   turn      brakes growing as 4 t (left) and 2 t N m (right) in a turn: the caster, not
 *             aligned, slips at t0 and sticks, then each drive wheel slips, with a sideways part
 *             of its friction that the two wheels of the axle share indeterminately (DAE mode
 *             splits IDA's multipliers by minimum norm, as the reactions do: without it the left
 *             wheel slipped 7.9e-3 s late);
 *   tipping   brakes growing as 8 t N m: the caster slips, then its load falls to 0 and the run
 *             stops with the tipping message (a planar chassis cannot tip) at the same time;
 *             20 N m brakes tip it at the start (refused);
 *   gentle    1 N m brakes: no slip, deceleration 2 T / (r M_eff) (closed form).
 *
 * Tolerances. rtol 1e-10, atol 1e-12 (the scenes'); IDA runs at rtol / 10 (AP_DAE_TOL_FACTOR).
 * Event times, positions and speeds of order 1 within TOLF = 10 rtol (times the value's size
 * when larger than 1, the wheels' angles), as the other DAE cross-checks
 * (tests/test_contact_dae.c); the turn's slip events, on IDA's multipliers (less accurate than
 * its states) while the demand varies with the state, within 1e3 rtol per second of motion, the
 * bound of the other vehicles' DAE slip events (tests/test_car_breakaway.c). The straight runs'
 * loads and demands are functions of t alone, so their switch times agree to round-off. All
 * bounds are far below what a wrong load gives (the
 * caster's share counted with the drive wheels' mu_kinetic moves t* by 4e-3 s; the loads left
 * out of DAE mode, as before, skid without friction). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define G 9.81
#define RTOL 1e-10
#define TOLF (10 * RTOL)

static const char *const MODES[] = {"simulation.mode=minimal", "simulation.mode=dae"};

/* Within TOLF of the reference, relative when |ref| > 1. */
static double bound(double ref) { return TOLF * fmax(1.0, fabs(ref)); }

/* dop853 at RTOL for minimal mode, IDA at the scene's RTOL for DAE mode. */
static int start(runner *r, const char *file, const char *const *sets, int n, int dae) {
  return runner_start(r, file, sets, n, dae ? 0.0 : RTOL);
}

/* The time of the last event whose name contains what (NaN when none), and their number. */
static double event_time(const ap_sim *s, const char *what, int *count) {
  double t = NAN;
  *count = 0;
  for (int i = 0; i < ap_sim_event_count(s); i++) {
    ap_event_record rec;
    if (ap_sim_event_get(s, i, &rec) == AP_OK && strstr(rec.name, what)) t = rec.t, (*count)++;
  }
  return t;
}

/* Skid with the caster's mu_kinetic 0.1: into out (vx and x at t* / 2, the stick time, x at
 * 0.4 s). */
static void skid(int dae, int planar, double *out) {
  const double M = 11.3, Sx = -0.898, Sz = 1.62, xc = -0.34, md = 0.4, mc = 0.1, v0 = 1.0;
  const double a = (-md * M * G - (mc - md) * G * Sx / xc) / (M - (mc - md) * Sz / xc);
  const double ts = v0 / -a, xs = v0 * v0 / (-2 * a), t1 = 0.5 * ts;
  const char *sets[] = {MODES[dae], "constraints.roll_c.friction={mu: 0.8, mu_kinetic: 0.1}",
                        "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};
  runner r;
  AP_CHECK_EQ_INT(start(&r, "diff_drive_skid.yaml", sets, planar ? 4 : 2, dae), AP_OK);
  if (!r.sim) return runner_stop(&r);
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, t1), AP_OK);
  out[0] = ap_sim_v(r.sim)[0], out[1] = ap_sim_q(r.sim)[0];
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, 0.4), AP_OK);
  int ns = 0, roll = 1;
  out[2] = event_time(r.sim, ".stick", &ns), out[3] = ap_sim_q(r.sim)[0];
  for (int c = 0; c < 3; c++) roll &= ap_sim_contact_mode(r.sim, c) == AP_CONTACT_ROLLING;
  printf("  skid, %s chassis (%s): at t*/2 vx - (v0 + a t) %.1e m/s, x - ... %.1e m; %d stick "
         "events, t - t* %.1e s; stands at x - x* %.1e m, rolling %d\n", planar ? "planar" : "free",
         MODES[dae] + 16, out[0] - (v0 + a * t1), out[1] - (v0 * t1 + 0.5 * a * t1 * t1), ns,
         out[2] - ts, out[3] - xs, roll);
  AP_CHECK_NEAR(out[0], v0 + a * t1, TOLF);
  AP_CHECK_NEAR(out[1], v0 * t1 + 0.5 * a * t1 * t1, TOLF);
  AP_CHECK_NEAR(out[2], ts, TOLF);
  AP_CHECK_NEAR(out[3], xs, TOLF);
  AP_CHECK(ns == 3 && roll);
  runner_stop(&r);
}

/* The skid with a yaw rate of 3 rad/s at the start: the slip directions turn, the load
 * transfer has a sideways part, and the left wheel sticks first (0.3911 s), the others later
 * (0.4424 s). Into out (the three contacts' stick times, then x, y at 0.5 s). */
static void spin(int dae, int planar, double *out) {
  const char *sets[] = {MODES[dae], "constraints.roll_c.friction={mu: 0.8, mu_kinetic: 0.1}",
                        "initial.chassis={z: 0, vx: 1, vy: 0, vz: 0, omega: [0, 0, 3]}",
                        "joints.chassis.kind=planar"};
  if (planar) sets[2] = "initial.chassis={vx: 1, heading_rate: 3}";
  runner r;
  AP_CHECK_EQ_INT(start(&r, "diff_drive_skid.yaml", sets, planar ? 4 : 3, dae), AP_OK);
  if (!r.sim) return runner_stop(&r);
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, 0.5), AP_OK);
  static const char *const name[] = {"roll_l.stick", "roll_r.stick", "roll_c.stick"};
  int n = 0, all = 1;
  for (int c = 0; c < 3; c++) out[c] = event_time(r.sim, name[c], &n), all &= n == 1;
  out[3] = ap_sim_q(r.sim)[0], out[4] = ap_sim_q(r.sim)[1];
  printf("  spinning skid, %s chassis (%s): sticks at %.15g (left), %.15g, %.15g; at 0.5 s "
         "x %.15g, y %.15g m\n", planar ? "planar" : "free", MODES[dae] + 16, out[0], out[1],
         out[2], out[3], out[4]);
  AP_CHECK(all && out[0] < out[1] - 0.01);
  runner_stop(&r);
}

/* diff_drive_brake.yaml on a planar chassis with mu 0.3, mu_kinetic 0.25 on every contact and
 * the n settings extra, run to 0.8 s. */
static int brake_run(runner *r, int dae, const char *const *extra, int n) {
  const char *sets[16] = {MODES[dae], "joints.chassis.kind=planar",
                          "constraints.roll_l.friction={mu: 0.3, mu_kinetic: 0.25}",
                          "constraints.roll_r.friction={mu: 0.3, mu_kinetic: 0.25}",
                          "constraints.roll_c.friction={mu: 0.3, mu_kinetic: 0.25}"};
  for (int i = 0; i < n && i < 11; i++) sets[5 + i] = extra[i];
  int rc = start(r, "diff_drive_brake.yaml", sets, 5 + n, dae);
  return rc == AP_OK ? ap_sim_advance(r->sim, 0.8) : rc;
}

/* Brakes growing as 4 t N m, mu 0.3, mu_kinetic 0.25: into out (the slip time, then x, heading,
 * both wheels' angles, vx and both wheels' rates at 0.8 s). */
static void slip_onset(int dae, double *out) {
  const char *extra[] = {"initial.chassis={vx: 1}", "effects.brake_l.torque=-4*t",
                         "effects.brake_r.torque=-4*t"};
  runner r;
  AP_CHECK_EQ_INT(brake_run(&r, dae, extra, 3), AP_OK);
  if (!r.sim) return runner_stop(&r);
  int ns = 0, nst = 0;
  out[0] = event_time(r.sim, ".slip", &ns);
  event_time(r.sim, ".stick", &nst);
  const double *q = ap_sim_q(r.sim), *v = ap_sim_v(r.sim);
  double x[] = {q[0], q[2], q[3], q[4], v[0], v[3], v[4]};
  memcpy(out + 1, x, sizeof x);
  int sl = ap_sim_contact_mode(r.sim, 0) == AP_CONTACT_SLIDING &&
           ap_sim_contact_mode(r.sim, 1) == AP_CONTACT_SLIDING &&
           ap_sim_contact_mode(r.sim, 2) == AP_CONTACT_ROLLING;
  printf("  brakes 4 t N m (%s): %d slip events, at t = %.15g; %d stick; at 0.8 s x %.15g m, "
         "vx %.15g m/s, drive wheels sliding, caster rolling: %d\n", MODES[dae] + 16, ns, out[0],
         nst, out[1], out[5], sl);
  AP_CHECK(ns == 2 && nst == 0 && sl);
  runner_stop(&r);
}

/* Brakes growing as 4 t (left) and 2 t N m (right) in a turn (heading rate 1 rad/s, the
 * wheels rolling at 7.5 and 12.5 rad/s): the caster, not aligned with its path, slips at t0
 * and sticks at 0.0119 s; the drive wheels' friction has a sideways part, which two wheels on
 * one axle share in a statically indeterminate way (their sideways rows repeat each other):
 * DAE mode's events split IDA's multipliers as the Appell modes' reactions do (minimum norm),
 * so the same wheel slips at the same time, the left at 0.3002 s, the right at 0.7193 s. Into
 * out (the caster's stick, the two slips; x, y, heading at 0.8 s). */
static void turn(int dae, double *out) {
  const char *extra[] = {"initial.chassis={vx: 1, heading_rate: 1}",
                         "initial.wheel_l={rate: 7.5}", "initial.wheel_r={rate: 12.5}",
                         "effects.brake_l.torque=-4*t", "effects.brake_r.torque=-2*t"};
  runner r;
  AP_CHECK_EQ_INT(brake_run(&r, dae, extra, 5), AP_OK);
  if (!r.sim) return runner_stop(&r);
  int nc = 0, nl = 0, nr = 0;
  out[0] = event_time(r.sim, "roll_c.stick", &nc);
  out[1] = event_time(r.sim, "roll_l.slip", &nl), out[2] = event_time(r.sim, "roll_r.slip", &nr);
  const double *q = ap_sim_q(r.sim);
  out[3] = q[0], out[4] = q[1], out[5] = q[2];
  printf("  brakes 4 t, 2 t N m in a turn (%s): %d events, the caster sticks at %.15g, roll_l "
         "slips at %.15g, roll_r at %.15g; at 0.8 s x %.15g, y %.15g, heading %.15g\n",
         MODES[dae] + 16, ap_sim_event_count(r.sim), out[0], out[1], out[2], out[3], out[4],
         out[5]);
  AP_CHECK(ap_sim_event_count(r.sim) == 4 && nc == 1 && nl == 1 && nr == 1);
  runner_stop(&r);
}

/* The turn in DAE mode at a coarse rtol (1e-6, 3e-6) against minimal mode's switch times at
 * RTOL (ref: the caster's stick, the two slips), within 1e3 rtol per second of motion. IDA holds
 * the rolling rows to its own tolerance: at the slip onsets the slip was 1e-11 m/s (not 0),
 * pointing against the slip to come, and became the stick event's reference; the stick fired
 * 4.8e-6 s after roll_l's slip, and the chatter made roll_r slip at 0.661 s instead of 0.719 s
 * (9 events by 0.8 s instead of 4). The remake at a slip onset now puts v on s = 0 first
 * (contact_dae.c). */
static void turn_coarse(const char *rtol, const double *ref) {
  const char *extra[] = {"initial.chassis={vx: 1, heading_rate: 1}",
                         "initial.wheel_l={rate: 7.5}", "initial.wheel_r={rate: 12.5}",
                         "effects.brake_l.torque=-4*t", "effects.brake_r.torque=-2*t", rtol};
  runner r;
  AP_CHECK_EQ_INT(brake_run(&r, 1, extra, 6), AP_OK);
  if (!r.sim) return runner_stop(&r);
  double tol = atof(strchr(rtol, '=') + 1), t[3];
  int nc = 0, nl = 0, nr = 0;
  t[0] = event_time(r.sim, "roll_c.stick", &nc);
  t[1] = event_time(r.sim, "roll_l.slip", &nl), t[2] = event_time(r.sim, "roll_r.slip", &nr);
  printf("  turn, DAE at %s: %d events; DAE - minimal (rtol %.0e): caster stick %.1e s, "
         "roll_l.slip %.1e s, roll_r.slip %.1e s (bound 1e3 rtol t)\n", rtol,
         ap_sim_event_count(r.sim), RTOL, t[0] - ref[0], t[1] - ref[1], t[2] - ref[2]);
  AP_CHECK(ap_sim_event_count(r.sim) == 4 && nc == 1 && nl == 1 && nr == 1);
  for (int i = 0; i < 3; i++) AP_CHECK_LE(fabs(t[i] - ref[i]), 1e3 * tol * fmax(ref[i], 0.01));
  runner_stop(&r);
}

/* Brakes growing as 8 t N m: the time the run stops with the tipping message (into *tp) and
 * the caster's slip time (into *tc); 20 N m brakes: refused at the start. */
static void tipping(int dae, double *tp, double *tc) {
  const char *sets[] = {MODES[dae], "joints.chassis.kind=planar", "initial.chassis={vx: 1}",
                        "effects.brake_l.torque=-8*t", "effects.brake_r.torque=-8*t"};
  runner r;
  *tp = *tc = NAN;
  AP_CHECK_EQ_INT(start(&r, "diff_drive_brake.yaml", sets, 5, dae), AP_OK);
  if (r.sim) {
    int rc = ap_sim_advance(r.sim, 1.0), n = 0;
    const char *msg = ap_sim_message(r.sim), *at = strstr(msg, "at t = ");
    if (at) *tp = atof(at + 7);
    *tc = event_time(r.sim, "roll_c.slip", &n);
    printf("  brakes 8 t N m (%s): caster slips at %.15g, the run stops at %.17g: %.60s...\n",
           MODES[dae] + 16, *tc, *tp, msg);
    AP_CHECK(rc == AP_ERR_UNSUPPORTED && strstr(msg, "contact 'roll_c'") &&
             strstr(msg, "planar chassis cannot") && n == 1);
  }
  runner_stop(&r);
  sets[3] = "effects.brake_l.torque=-20", sets[4] = "effects.brake_r.torque=-20";
  AP_CHECK(start(&r, "diff_drive_brake.yaml", sets, 5, dae) == AP_ERR_UNSUPPORTED);
  runner_stop(&r);
}

/* 1 N m brakes: no slip, v' = -2 T / (r M_eff). */
static void gentle(void) {
  const double T = 1.0, Meff = 11.3 + 2 * 0.25 + 0.05, a = -2 * T / (0.1 * Meff), t1 = 0.4;
  const char *sets[] = {MODES[1], "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};
  runner r;
  AP_CHECK_EQ_INT(start(&r, "diff_drive_brake.yaml", sets, 3, 1), AP_OK);
  if (!r.sim) return runner_stop(&r);
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, t1), AP_OK);
  double ev = ap_sim_v(r.sim)[0] - (1 + a * t1), ex = ap_sim_q(r.sim)[0] - (t1 + a * t1 * t1 / 2);
  printf("  brakes 1 N m (dae): vx - (v0 + a t) %.1e m/s, x - ... %.1e m, %d events\n", ev, ex,
         ap_sim_event_count(r.sim));
  AP_CHECK(fabs(ev) < TOLF && fabs(ex) < TOLF && ap_sim_event_count(r.sim) == 0);
  runner_stop(&r);
}

/* The DAE run against the minimal-mode run: each of n numbers within bound(). */
static void against(const char *what, const double *dae, const double *min, int n) {
  double worst = 0.0, rel = 0.0;
  for (int i = 0; i < n; i++) {
    double e = fabs(dae[i] - min[i]);
    if (!(e <= worst)) worst = e;   /* a NaN stays */
    if (!(e / bound(min[i]) <= rel)) rel = e / bound(min[i]);
  }
  printf("  %s: largest difference %.1e (%.2g of the bound)\n", what, worst, rel);
  AP_CHECK_LE(rel, 1.0);
}

int main(void) {
  printf("friction under a planar chassis in DAE mode (rtol %.0e):\n", RTOL);
  double sk[3][4], sp[3][5], on[2][8], tu[2][6], tp[2], tc[2];
  for (int i = 0; i < 3; i++) skid(i > 0, i < 2, sk[i]), spin(i > 0, i < 2, sp[i]);
  for (int dae = 0; dae < 2; dae++)
    slip_onset(dae, on[dae]), turn(dae, tu[dae]), tipping(dae, &tp[dae], &tc[dae]);
  gentle();
  turn_coarse("simulation.rtol=1e-6", tu[0]), turn_coarse("simulation.rtol=3e-6", tu[0]);
  against("skid, planar: DAE vs minimal (vx, x at t*/2, t*, x at 0.4 s)", sk[1], sk[0], 4);
  against("skid, DAE: planar vs free chassis", sk[1], sk[2], 4);
  against("spinning skid, planar: DAE vs minimal (stick times, x, y at 0.5 s)", sp[1], sp[0], 5);
  against("spinning skid, DAE: planar vs free chassis", sp[1], sp[2], 5);
  against("brakes 4 t: DAE vs minimal (slip time; x, heading, wheel angles, vx, wheel rates "
          "at 0.8 s)", on[1], on[0], 8);
  against("brakes 4 t, 2 t in a turn: DAE vs minimal (x, y, heading at 0.8 s)", tu[1] + 3,
          tu[0] + 3, 3);
  /* the switch times: the stick on the state (TOLF), the slips on IDA's multipliers, within the
   * DAE cross-checks' bound for those, 1e3 rtol per second of motion (test_car_breakaway.c) */
  for (int i = 0; i < 3; i++) {
    double b = i ? 1e3 * RTOL * tu[0][i] : TOLF;
    printf("  brakes 4 t, 2 t in a turn: %s, DAE - minimal %.1e s (bound %.1e)\n",
           i ? (i == 1 ? "roll_l.slip" : "roll_r.slip") : "roll_c.stick", tu[1][i] - tu[0][i], b);
    AP_CHECK_LE(fabs(tu[1][i] - tu[0][i]), b);
  }
  against("brakes 8 t: DAE vs minimal (caster slip, tipping stop)", (double[]){tc[1], tp[1]},
          (double[]){tc[0], tp[0]}, 2);
  return ap_check_finish("test_planar_dae");
}
