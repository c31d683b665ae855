/* Vehicles that skid (docs/vehicles.md "Skidding and breaking away"): wheel contacts with
 * friction on a free chassis, against closed forms.
 *
 * diff_drive_skid.yaml: the robot with a caster (total mass M = 11.3 kg) runs at v0 = 1 m/s
 * along x with every wheel locked. Each contact point slips at the chassis velocity, so each
 * contact slides with friction -mu_k N_i e_x; the three normal forces hold the chassis up and
 * sum to M g whatever the load transfer (no vertical acceleration), so
 * M v' = -mu_k M g: v = v0 - mu_k g t, x = v0 t - mu_k g t^2 / 2 until t* = v0 / (mu_k g),
 * where the slip speeds reach 0 and the contacts stick (the robot stands). Checked to 1e-9
 * (the integrator's rtol 1e-12 over a few hundred steps).
 *
 * diff_drive_brake.yaml: the same robot, wheels free, a braking torque T on each drive wheel,
 * caster rolling. Power: d/dt (M_eff v^2 / 2) = -2 T v / r with M_eff = M + 2 I_w / r^2 +
 * I_c / r_c^2 (wheel axle inertias m r^2 / 2: M_eff = 11.85 kg), so v' = -2 T / (r M_eff).
 * With T = 1 N m the wheels need far less friction than mu N: no slip event, the deceleration
 * against the closed form to 1e-9; with T = 20 N m (friction T / r = 200 N per wheel against
 * mu N of about 35 N) the drive wheels slide from the start, and the caster lifts off: the
 * brakes' reaction on the chassis, 2 T = 40 N m nose down, exceeds the weights' moment about
 * the axle that holds the tail down (9.81 (10 * 0.08 + 0.2 * 0.32 + 0.1 * 0.34) = 8.8 N m).
 *
 * Tolerances: the sliding motion to 1e-9 (rtol 1e-12, a few hundred steps). The stick events
 * to 1e-9 s: the first wheel's is located to 1e-11 relative like any event; each stick
 * restarts on the new rows, which leaves the others' slip speeds at round-off (1e-10 m/s),
 * and their crossings follow from those residuals at mu_k g, up to 1e-10 s later. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define G 9.81

static const char *MODES[] = {"simulation.mode=minimal", "simulation.mode=projected"};

/* Locked wheels: sliding at mu_k g, sticking at t* = v0 / (mu_k g). */
static void test_skid(int im) {
  const double v0 = 1.0, muk = 0.4, ts = v0 / (muk * G);
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_skid.yaml", &MODES[im], 1, 1e-12), AP_OK);
  if (!r.sim) return runner_stop(&r);
  int slide = 1;
  for (int c = 0; c < 3; c++) slide &= ap_sim_contact_mode(r.sim, c) == 1;
  AP_CHECK(slide);
  double t1 = 0.5 * ts;
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, t1), AP_OK);
  const double *q = ap_sim_q(r.sim), *v = ap_sim_v(r.sim);
  double ev = fabs(v[0] - (v0 - muk * G * t1)), ex = fabs(q[0] - (v0 * t1 - 0.5 * muk * G * t1 * t1));
  printf("  %s: sliding at t = %.6g: |vx - (v0 - mu_k g t)| = %.2g m/s, |x - ...| = %.2g m, "
         "|vy| %.2g, |wz| %.2g, events %d\n", MODES[im] + 16, t1, ev, ex, fabs(v[1]),
         fabs(v[5]), ap_sim_event_count(r.sim));
  AP_CHECK(ev < 1e-9 && ex < 1e-9 && fabs(v[1]) < 1e-9 && fabs(v[5]) < 1e-9);
  AP_CHECK_EQ_INT(ap_sim_event_count(r.sim), 3);   /* the three contacts' slip at t0 */
  int rc = ap_sim_advance(r.sim, 0.3);
  if (rc != AP_OK) printf("  advance to 0.3: %s (t = %.17g)\n", ap_sim_message(r.sim), ap_sim_time(r.sim));
  AP_CHECK_EQ_INT(rc, AP_OK);
  int ne = ap_sim_event_count(r.sim), nst = 0;
  double et = 0.0;
  for (int i = 0; i < ne; i++) {
    ap_event_record rec;
    AP_CHECK_EQ_INT(ap_sim_event_get(r.sim, i, &rec), AP_OK);
    printf("    event %s at t = %.15g (t* = %.15g)\n", rec.name, rec.t, ts);
    if (strstr(rec.name, ".stick")) et = fmax(et, fabs(rec.t - ts)), nst++;
    else AP_CHECK(strstr(rec.name, ".slip") && rec.t == 0.0);
  }
  v = ap_sim_v(r.sim), q = ap_sim_q(r.sim);
  int roll = 1;
  for (int c = 0; c < 3; c++) roll &= ap_sim_contact_mode(r.sim, c) == 0;
  printf("  %s: %d stick events, largest |t - t*| = %.2g s; at t = 0.3: |vx| = %.2g m/s, "
         "x - v0^2 / (2 mu_k g) = %.2g m, all rolling: %d\n", MODES[im] + 16, nst, et, fabs(v[0]),
         q[0] - v0 * v0 / (2 * muk * G), roll);
  AP_CHECK(nst >= 1 && et < 1e-9);
  AP_CHECK(fabs(v[0]) < 1e-9 && fabs(q[0] - v0 * v0 / (2 * muk * G)) < 1e-9 && roll);
  runner_stop(&r);
}

/* A braking torque T per drive wheel: gentle (no slip, closed-form deceleration; on the free
 * chassis as shipped and on a planar one, whose friction limits use the wheels' true loads)
 * or hard (the drive wheels slide at once). */
static void test_brake(int im, int planar) {
  const double v0 = 1.0, T = 1.0, r_w = 0.1, Meff = 11.3 + 2 * 0.25 + 0.05;
  const double a = -2 * T / (r_w * Meff), t1 = 0.4;
  const char *form[] = {MODES[im], "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_brake.yaml", form, planar ? 3 : 1, 1e-12), AP_OK);
  if (!r.sim) return runner_stop(&r);
  AP_CHECK_EQ_INT(ap_sim_advance(r.sim, t1), AP_OK);
  const double *q = ap_sim_q(r.sim), *v = ap_sim_v(r.sim);
  double ev = fabs(v[0] - (v0 + a * t1)), ex = fabs(q[0] - (v0 * t1 + 0.5 * a * t1 * t1));
  int roll = 1;
  for (int c = 0; c < 3; c++) roll &= ap_sim_contact_mode(r.sim, c) == 0;
  printf("  %s, %s chassis: T = 1 N m: a = %.6g m/s^2, after %.2g s |vx - (v0 + a t)| = %.2g "
         "m/s, |x - ...| = %.2g m, events %d, all rolling %d\n", MODES[im] + 16,
         planar ? "planar" : "free", a, t1, ev, ex, ap_sim_event_count(r.sim), roll);
  AP_CHECK(ev < 1e-9 && ex < 1e-9 && roll);
  AP_CHECK_EQ_INT(ap_sim_event_count(r.sim), 0);
  runner_stop(&r);
  if (planar) return;   /* T = 20 N m tips it: test_planar_friction */
  const char *sets[] = {MODES[im], "effects.brake_l.torque=-20", "effects.brake_r.torque=-20"};
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_brake.yaml", sets, 3, 1e-12), AP_OK);
  if (!r.sim) return runner_stop(&r);
  int ml = ap_sim_contact_mode(r.sim, 0), mr = ap_sim_contact_mode(r.sim, 1);
  int mc = ap_sim_contact_mode(r.sim, 2);
  printf("  %s: T = 20 N m: modes at t0 %d %d %d (1 sliding, 2 airborne)\n", MODES[im] + 16,
         ml, mr, mc);
  AP_CHECK(ml == 1 && mr == 1 && mc == 2);
  runner_stop(&r);
}

/* Locked wheels with mu_k 0.6: braking at 0.6 g would pull the caster down (its load -2.1 N),
 * so the caster lifts off at t0 (a contact sliding from the start is judged by its normal force
 * too) while the drive wheels slide; the robot tips nose down. */
static void test_skid_tips(int im) {
  const char *sets[] = {MODES[im], "constraints.roll_l.friction={mu: 0.8, mu_kinetic: 0.6}",
                        "constraints.roll_r.friction={mu: 0.8, mu_kinetic: 0.6}",
                        "constraints.roll_c.friction={mu: 0.8, mu_kinetic: 0.6}"};
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_skid.yaml", sets, 4, 1e-12), AP_OK);
  if (!r.sim) return runner_stop(&r);
  AP_CHECK_EQ_INT(ap_sim_contact_mode(r.sim, 2), AP_CONTACT_AIRBORNE);
  AP_CHECK(ap_sim_contact_mode(r.sim, 0) == AP_CONTACT_SLIDING &&
           ap_sim_contact_mode(r.sim, 1) == AP_CONTACT_SLIDING);
  int lifted = 0;
  for (int i = 0; i < ap_sim_event_count(r.sim); i++) {
    ap_event_record rec;
    AP_CHECK_EQ_INT(ap_sim_event_get(r.sim, i, &rec), AP_OK);
    lifted |= strcmp(rec.name, "roll_c.lift_off") == 0 && rec.t == 0.0;
  }
  printf("  %s: mu_k 0.6: caster airborne at t0 %d, lift-off event %d\n", MODES[im] + 16,
         ap_sim_contact_mode(r.sim, 2) == AP_CONTACT_AIRBORNE, lifted);
  AP_CHECK(lifted);
  runner_stop(&r);
}

/* CVODE with contact modes runs without a warning (its Jacobian is made again as a slip
 * grows: tests/test_cvode_contacts.c checks bdf and adams against closed forms). */
static void test_cvode_no_warning(void) {
  const char *bdf[] = {"simulation.method=bdf"};
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_skid.yaml", bdf, 1, 0), AP_OK);
  AP_CHECK(r.sim && !strstr(ap_sim_warning(r.sim), "not verified"));
  runner_stop(&r);
}

int main(void) {
  printf("vehicle slip:\n");
  for (int im = 0; im < 2; im++)
    test_skid(im), test_skid_tips(im), test_brake(im, 0), test_brake(im, 1);
  test_cvode_no_warning();
  return ap_check_finish("test_vehicle_slip");
}
