/* Friction under a planar chassis (docs/vehicles.md "Skidding and breaking away"): the wheels'
 * friction limits and sliding forces use their true loads (model/loads.c), solved with the
 * accelerations. The same robot is run on a planar and on a free chassis (where the loads are
 * the contact rows' multipliers) and against closed forms.
 *
 * diff_drive_skid.yaml with mu_kinetic = 0.4 (every load stays positive: the caster keeps
 * 7.2 N): locked wheels slide, the three loads sum to M g whatever the load transfer, so
 * v = v0 - mu_k g t until t* = v0 / (mu_k g), where the contacts stick. The speed and position
 * halfway to t* against the closed form (1e-9, rtol 1e-12 over a few hundred steps), each load
 * planar vs free (1e-9 M g: two integrations of the same motion), the stick events against t*
 * (1e-9 s, as in test_vehicle_slip).
 * diff_drive_brake.yaml on a planar chassis (the gentle brake that never slips: in
 * test_vehicle_slip). With the scene's mu_kinetic = 0.6 the caster's load is
 * negative from the start (braking at 5.9 m/s^2 tips the robot nose down), and T = 20 N m
 * lifts the caster too: a planar chassis cannot tip, the run stops saying so. Refused: friction
 * under a planar chassis on a tilted plane, a sliding wheel of the four-wheeled car.
 * A brake torque growing with time: the drive wheels slip where the never-slipping run's
 * friction_ratio (its true load below) reaches mu (1e-9 relative); growing faster, it tips
 * the robot: the planar run stops where the free chassis' caster lifts off (1e-9). DAE mode:
 * tests/test_planar_dae.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define G 9.81

static const char *const SKID[] = {
    "constraints.roll_l.friction={mu: 0.8, mu_kinetic: 0.4}",
    "constraints.roll_r.friction={mu: 0.8, mu_kinetic: 0.4}",
    "constraints.roll_c.friction={mu: 0.8, mu_kinetic: 0.4}", "simulation.mode=minimal",
    "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};
/* The same with mu_kinetic 0.6: the braking would tip the robot (the caster's load -2.1 N). */
static const char *const TIP[] = {
    "constraints.roll_l.friction={mu: 0.8, mu_kinetic: 0.6}",
    "constraints.roll_r.friction={mu: 0.8, mu_kinetic: 0.6}",
    "constraints.roll_c.friction={mu: 0.8, mu_kinetic: 0.6}", "simulation.mode=minimal",
    "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};

/* The three wheels' normal loads (roll_l, roll_r, roll_c are constraints 0, 1, 2). */
static int wheel_loads(runner *r, double *N) {
  const double *lambda = NULL;
  int rc = ap_sim_reactions(r->sim, &lambda);
  for (int i = 0; rc == AP_OK && i < 3; i++) {
    ap_contact_force f;
    rc = ap_body_contact_force(ap_scene_model(r->sc), ap_sim_data(r->sim), lambda, i, &f);
    N[i] = f.normal;
  }
  return rc;
}

static void test_skid(const char *mode) {
  const double v0 = 1.0, muk = 0.4, ts = v0 / (muk * G), t1 = 0.5 * ts, W = 11.3 * G;
  const char *sets[6];
  memcpy(sets, SKID, sizeof sets);
  sets[3] = mode;
  runner a, b;
  AP_CHECK_EQ_INT(runner_start(&a, "diff_drive_skid.yaml", sets, 6, 1e-12), AP_OK);
  AP_CHECK_EQ_INT(runner_start(&b, "diff_drive_skid.yaml", sets, 4, 1e-12), AP_OK);
  if (!a.sim || !b.sim) return runner_stop(&a), runner_stop(&b);
  int slide = 1;
  for (int c = 0; c < 3; c++) slide &= ap_sim_contact_mode(a.sim, c) == 1;
  AP_CHECK(slide);
  AP_CHECK_EQ_INT(ap_sim_advance(a.sim, t1), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(b.sim, t1), AP_OK);
  const double *q = ap_sim_q(a.sim), *v = ap_sim_v(a.sim);
  double ev = fabs(v[0] - (v0 - muk * G * t1));
  double ex = fabs(q[0] - (v0 * t1 - 0.5 * muk * G * t1 * t1));
  double Na[3], Nb[3], dN = 0.0, sum = 0.0;
  AP_CHECK_EQ_INT(wheel_loads(&a, Na), AP_OK);
  AP_CHECK_EQ_INT(wheel_loads(&b, Nb), AP_OK);
  for (int c = 0; c < 3; c++) dN = fmax(dN, fabs(Na[c] - Nb[c])), sum += Na[c];
  printf("  %s: planar, sliding at t = %.6g: |vx - (v0 - mu_k g t)| = %.2g m/s, |x - ...| = "
         "%.2g m; loads %.10g %.10g %.10g N, sum - M g = %.2g N, vs free chassis %.2g N\n",
         mode + 16, t1, ev, ex, Na[0], Na[1], Na[2], sum - W, dN);
  AP_CHECK(ev < 1e-9 && ex < 1e-9);
  AP_CHECK(dN < 1e-9 * W && fabs(sum - W) < 1e-9 * W && Na[2] > 1.0);
  AP_CHECK_EQ_INT(ap_sim_event_count(a.sim), 3);   /* the three contacts' slip at t0 */
  AP_CHECK_EQ_INT(ap_sim_advance(a.sim, 0.4), AP_OK);
  int ne = 0;
  double et = 0.0;
  for (int i = 0; i < ap_sim_event_count(a.sim); i++) {
    ap_event_record rec;
    AP_CHECK_EQ_INT(ap_sim_event_get(a.sim, i, &rec), AP_OK);
    if (strstr(rec.name, ".stick")) et = fmax(et, fabs(rec.t - ts)), ne++;
    else AP_CHECK(strstr(rec.name, ".slip") && rec.t == 0.0);
  }
  v = ap_sim_v(a.sim), q = ap_sim_q(a.sim);
  int roll = 1;
  for (int c = 0; c < 3; c++) roll &= ap_sim_contact_mode(a.sim, c) == 0;
  printf("  %s: planar, %d stick events, largest |t - v0 / (mu_k g)| = %.2g s; at t = 0.4 "
         "|vx| = %.2g m/s, x - v0^2 / (2 mu_k g) = %.2g m, all rolling %d\n", mode + 16, ne, et,
         fabs(v[0]), q[0] - v0 * v0 / (2 * muk * G), roll);
  AP_CHECK(ne == 3 && et < 1e-9 && roll);
  AP_CHECK(fabs(v[0]) < 1e-9 && fabs(q[0] - v0 * v0 / (2 * muk * G)) < 1e-9);
  runner_stop(&a), runner_stop(&b);
}

static const char *const PLANAR[] = {"simulation.mode=minimal", "joints.chassis.kind=planar",
                                     "initial.chassis={vx: 1}", "effects.brake_l.torque=-20",
                                     "effects.brake_r.torque=-20"};

/* The hard brake (20 N m per wheel) and the locked wheels with mu_kinetic 0.6 tip the robot
 * at once: refused at the start. (The gentle brake: test_vehicle_slip.) */
static void test_tips(const char *mode) {
  const char *sets[5];
  memcpy(sets, PLANAR, sizeof sets);
  sets[0] = mode;
  runner r;
  AP_CHECK(runner_start(&r, "diff_drive_brake.yaml", sets, 5, 1e-12) != AP_OK);
  runner_stop(&r);
  AP_CHECK(runner_start(&r, "diff_drive_skid.yaml", TIP, 6, 1e-12) != AP_OK);
  runner_stop(&r);
}

/* The message of a run that tips (mu_kinetic 0.6). */
static void test_tip_message(void) {
  char path[1200], msg[1024] = "";
  snprintf(path, sizeof path, "%s/examples/scenes/diff_drive_skid.yaml", AP_SRCDIR);
  ap_scene *sc = NULL;
  AP_CHECK_EQ_INT(ap_scene_load(path, TIP, 6, &sc, msg, sizeof msg), AP_OK);
  if (!sc) return;
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  double *x0 = calloc((size_t)(n + ap_model_k(m)), sizeof *x0);
  ap_sim *sim = NULL;
  int rc = ap_scene_initial_state(sc, x0, x0 + n, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_create(m, &run.sim, run.t0, x0, x0 + n, &sim, msg, sizeof msg);
  printf("  planar, mu_k 0.6: %s\n", msg);
  AP_CHECK(rc == AP_ERR_UNSUPPORTED && strstr(msg, "contact 'roll_c'") &&
           strstr(msg, "planar chassis cannot"));
  ap_sim_free(sim);
  free(x0);
  ap_scene_free(sc);
}

/* A brake torque growing as 4 t N m per drive wheel on the planar robot: the wheels slip where
 * the run that never slips (mu = 100) needs mu = 0.3, i.e. where its friction_ratio of roll_l
 * (the true load in the denominator) reaches 0.3: t* located by an event on ratio - mu. */
static int ratio_l(double t, const double *q, const double *v, const ap_data *d, void *user,
                   double *out) {
  ap_contact_force f;
  (void)t, (void)q, (void)v;
  if (ap_body_contact_force(user, d, d->lambda, 0, &f) != AP_OK) return -1;
  *out = f.friction_ratio - 0.3;
  return 0;
}

static void test_growing_brake(void) {
  const char *sets[] = {"joints.chassis.kind=planar", "initial.chassis={vx: 1}",
                        "effects.brake_l.torque=-4*t", "effects.brake_r.torque=-4*t",
                        "constraints.roll_l.friction={mu: 100}",
                        "constraints.roll_r.friction={mu: 100}",
                        "constraints.roll_c.friction={mu: 100}"};
  runner a, b;
  double ts = NAN;
  AP_CHECK_EQ_INT(runner_start(&a, "diff_drive_brake.yaml", sets, 7, 1e-12), AP_OK);
  if (a.sim) {
    ap_event_def def = ap_event_def_default();
    def.name = "ratio", def.fn = ratio_l, def.user = (void *)ap_scene_model(a.sc);
    def.direction = AP_EVENT_RISING, def.action = AP_EVENT_STOP, def.stage = AP_EVENT_REACTIONS;
    AP_CHECK_EQ_INT(ap_sim_add_event(a.sim, &def), AP_OK);
    if (ap_sim_advance(a.sim, 1.0) == AP_STOPPED) ts = ap_sim_time(a.sim);
  }
  sets[4] = "constraints.roll_l.friction={mu: 0.3}";
  sets[5] = "constraints.roll_r.friction={mu: 0.3}";
  sets[6] = "constraints.roll_c.friction={mu: 0.3}";
  AP_CHECK_EQ_INT(runner_start(&b, "diff_drive_brake.yaml", sets, 7, 1e-12), AP_OK);
  if (b.sim && isfinite(ts)) {
    AP_CHECK_EQ_INT(ap_sim_advance(b.sim, ts + 1e-9), AP_OK);
    ap_event_record rec;
    memset(&rec, 0, sizeof rec);
    int n = ap_sim_event_count(b.sim);
    if (n > 0) AP_CHECK_EQ_INT(ap_sim_event_get(b.sim, 0, &rec), AP_OK);
    printf("  planar, brake 4 t N m, mu 0.3: the never-slipping run needs mu at t* = %.15g; "
           "first event %s at %.15g (|t - t*| / t* = %.2g)\n", ts, n ? rec.name : "none", rec.t,
           fabs(rec.t - ts) / ts);
    AP_CHECK(n >= 1 && strstr(rec.name, ".slip") != NULL);
    AP_CHECK_LE(fabs(rec.t - ts), 1e-9 * ts);
  }
  AP_CHECK(isfinite(ts));
  runner_stop(&a), runner_stop(&b);
}

/* Brakes growing as 8 t N m: the braking tips the robot nose down, the caster's load falls to
 * 0. On a planar chassis the run stops there with the tipping message; on the free chassis the
 * caster lifts off (roll_c.lift_off) at the same time (the same motion and loads until then). */
static void test_tip_mid_run(void) {
  const char *sets[] = {"effects.brake_l.torque=-8*t", "effects.brake_r.torque=-8*t",
                        "joints.chassis.kind=planar", "initial.chassis={vx: 1}"};
  runner a, b;
  double tp = NAN, tf = NAN;
  AP_CHECK_EQ_INT(runner_start(&a, "diff_drive_brake.yaml", sets, 4, 1e-12), AP_OK);
  if (a.sim) {
    int rc = ap_sim_advance(a.sim, 1.0);
    const char *msg = ap_sim_message(a.sim), *at = strstr(msg, "at t = ");
    if (at) tp = atof(at + 7);
    printf("  planar, brakes 8 t N m: %s\n", msg);
    AP_CHECK(rc == AP_ERR_UNSUPPORTED && strstr(msg, "contact 'roll_c'") &&
             strstr(msg, "planar chassis cannot"));
  }
  AP_CHECK_EQ_INT(runner_start(&b, "diff_drive_brake.yaml", sets, 2, 1e-12), AP_OK);
  if (b.sim) {
    AP_CHECK_EQ_INT(ap_sim_advance(b.sim, 0.395), AP_OK);
    for (int i = 0; i < ap_sim_event_count(b.sim); i++) {
      ap_event_record rec;
      AP_CHECK_EQ_INT(ap_sim_event_get(b.sim, i, &rec), AP_OK);
      if (strcmp(rec.name, "roll_c.lift_off") == 0 && isnan(tf)) tf = rec.t;
    }
  }
  printf("  the caster's load vanishes at t = %.15g (planar, stopped), %.15g (free, lift-off): "
         "%.2g apart\n", tp, tf, fabs(tp - tf));
  AP_CHECK_LE(fabs(tp - tf), 1e-9 * tf);
  runner_stop(&a), runner_stop(&b);
}

/* Refused under a planar chassis: friction on a tilted plane (the loads assume z = 0), and a
 * sliding wheel of the four-wheeled car (statically indeterminate loads), as on a free one.
 * All four wheels have friction: with perfectly rough ones beside it, those would carry the
 * sideways force that the wheel's row repeats (contact_share.c), and the wheel, needing no
 * longitudinal force, would roll on. */
static void test_refusals(void) {
  char path[1200], msg[1024] = "";
  snprintf(path, sizeof path, "%s/examples/scenes/diff_drive_skid.yaml", AP_SRCDIR);
  const char *tilt[] = {"joints.chassis.kind=planar", "initial.chassis={vx: 1}",
                        "constraints.roll_l.ground={normal: [0, 0.1, 1]}"};
  ap_scene *sc = NULL;
  int rc = ap_scene_load(path, tilt, 3, &sc, msg, sizeof msg);
  printf("  tilted plane: %s\n", msg);
  AP_CHECK(rc != AP_OK && strstr(msg, "'roll_l'") && strstr(msg, "level ground"));
  ap_scene_free(sc);
  const char *car[] = {"constraints.roll_rl.friction={mu: 0.01}",
                       "constraints.roll_rr.friction={mu: 0.01}",
                       "constraints.roll_fl.friction={mu: 0.01}",
                       "constraints.roll_fr.friction={mu: 0.01}"};
  runner r;
  rc = runner_start(&r, "car_ackermann.yaml", car, 4, 1e-10);
  AP_CHECK(rc == AP_ERR_SINGULAR);
  runner_stop(&r);
}

int main(void) {
  printf("friction under a planar chassis:\n");
  test_skid("simulation.mode=minimal");
  test_skid("simulation.mode=projected");
  test_tips("simulation.mode=minimal");
  test_tips("simulation.mode=projected");
  test_tip_message();
  test_refusals();
  test_growing_brake();
  test_tip_mid_run();
  return ap_check_finish("test_planar_friction");
}
