/* Slip onset where the friction demand grows (docs/scenes.md "Friction, slip and lift-off"):
 * a run with `friction: {mu}` must start to slip exactly where the same run without friction
 * (perfectly rough) needs mu, i.e. where its friction_ratio |F_t| / F_n reaches mu.
 *
 * The speeding-up turn: the thin uniform disk of bs_disk_default (r 0.3 m, 1.5 kg) on a free
 * joint starts in the steady turn at lean 0.3 rad, heading rate 3 rad/s (friction ratio
 * 0.193), and a torque T = 0.05 N m about its axis (a user effect: T a, a the disk axis in
 * world axes) spins it up: it rolls faster and the friction it needs grows (0.287 at t = 1 s);
 * mu is set halfway, 0.2398, reached at t* = 0.775 s. The reference t* is located on the frictionless run by an event on
 * friction_ratio - mu (rising, at the reactions stage: the ratio from ap_body_contact_force at
 * the event machinery's states, located to its 1e-11 relative) and, independently, by the
 * secant method on the ratio at output times of fresh runs (ap_sim_advance to t lands on t).
 * The run with friction must record roll.slip at t* (1e-9 relative) and, before it, follow the
 * frictionless run bit for bit (a contact with modes in its rolling mode is the same model). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "bodysys.h"
#include "check.h"

#define G 9.81
static const double TORQUE = -0.05;   /* N m about the disk axis (speeds the rolling up) */

static int spin_up(double t, const double *q, const double *v, double *Q, void *user) {
  double R[9];
  (void)t, (void)v, (void)user;
  ap_quat_to_matrix(q + 3, R);
  for (int i = 0; i < 3; i++) Q[3 + i] += TORQUE * R[6 + i];   /* T a, a = R e_z */
  return 0;
}

/* The disk on a free joint, rolling (friction mu, or none for mu < 0), gravity, the torque. */
static ap_model *disk(double mu) {
  bs_disk p = bs_disk_default();
  const double g[3] = {0, 0, -G};
  ap_constraint_def c = ap_constraint_def_default();
  c.name = "roll", c.mu = mu;
  ap_effect_def e = ap_effect_def_default();
  e.kind = AP_EFFECT_USER, e.generalized = spin_up, e.name = "spin_up";
  return bs_free_ball_effect(AP_SHAPE_DISK, p.r, p.m, &c, g, &e);
}

static ap_sim *start(const ap_model *m, ap_mode mode) {
  bs_disk p = bs_disk_default();
  double q[7], v[6];
  bs_disk_turn_free(&p, 0.3, 3.0, 0.4, q, v);
  return bs_start(m, mode, "dop853", 1e-12, 1e-14, q, v);
}

typedef struct ratio_ev {
  const ap_model *m;
  double mu;
} ratio_ev;

static int ratio_minus_mu(double t, const double *q, const double *v, const ap_data *d,
                          void *user, double *out) {
  const ratio_ev *e = user;
  ap_contact_force f;
  (void)t, (void)q, (void)v;
  if (ap_body_contact_force(e->m, d, d->lambda, 0, &f) != AP_OK) return -1;
  *out = f.friction_ratio - e->mu;
  return 0;
}

/* The frictionless run's friction ratio at t (a fresh run advanced to t). */
static double ratio_at(const ap_model *m, ap_mode mode, double t) {
  ap_sim *s = start(m, mode);
  const double *lambda = NULL;
  ap_contact_force f;
  f.friction_ratio = NAN;
  if (s && ap_sim_advance(s, t) == AP_OK && ap_sim_reactions(s, &lambda) == AP_OK)
    ap_body_contact_force(m, ap_sim_data(s), lambda, 0, &f);
  ap_sim_free(s);
  return f.friction_ratio;
}

/* t* by the event on friction_ratio - mu of the frictionless run. */
static double crossing_by_event(const ap_model *m, ap_mode mode, double mu) {
  ap_sim *s = start(m, mode);
  if (!s) return NAN;
  ratio_ev e = {m, mu};
  ap_event_def def = ap_event_def_default();
  def.name = "ratio", def.fn = ratio_minus_mu, def.user = &e;
  def.direction = AP_EVENT_RISING, def.action = AP_EVENT_STOP, def.stage = AP_EVENT_REACTIONS;
  AP_CHECK_EQ_INT(ap_sim_add_event(s, &def), AP_OK);
  double t = NAN;
  if (ap_sim_advance(s, 5.0) == AP_STOPPED) t = ap_sim_time(s);
  ap_sim_free(s);
  return t;
}

/* t* by the secant method on the ratio at output times, from a bracket [a, b]. */
static double crossing_by_secant(const ap_model *m, ap_mode mode, double mu, double a,
                                 double b) {
  double fa = ratio_at(m, mode, a) - mu, fb = ratio_at(m, mode, b) - mu;
  for (int it = 0; it < 30 && fabs(b - a) > 1e-14 * b; it++) {
    double c = b - fb * (b - a) / (fb - fa);
    a = b, fa = fb, b = c, fb = ratio_at(m, mode, c) - mu;
  }
  return b;
}

static void test_speeding_turn(ap_mode mode) {
  const char *name = mode == AP_MODE_MINIMAL ? "minimal" : "projected";
  ap_model *m0 = disk(-1.0);
  double r0 = ratio_at(m0, mode, 0.0), r1 = ratio_at(m0, mode, 1.0), mu = 0.5 * (r0 + r1);
  double te = crossing_by_event(m0, mode, mu);
  double ts = crossing_by_secant(m0, mode, mu, 0.4 * te, 0.6 * te + 0.4);
  printf("  %s: frictionless ratio %.6g at t = 0, %.6g at t = 1; mu = %.9g reached at t* = "
         "%.15g (event), %.15g (secant on the ratio): %.2g apart\n", name, r0, r1, mu, te, ts,
         fabs(te - ts) / te);
  AP_CHECK(r1 > r0 * 1.3 && te > 0.1 && te < 1.0);
  AP_CHECK_LE(fabs(te - ts), 1e-9 * te);
  ap_model *m = disk(mu);
  ap_sim *s = start(m, mode), *s0 = start(m0, mode);
  if (m && s && s0) {
    double t1 = 0.9 * te;
    AP_CHECK_EQ_INT(ap_sim_advance(s, t1), AP_OK);
    AP_CHECK_EQ_INT(ap_sim_advance(s0, t1), AP_OK);
    int same = memcmp(ap_sim_v(s), ap_sim_v(s0), 6 * sizeof(double)) == 0 &&
               memcmp(ap_sim_q(s), ap_sim_q(s0), 7 * sizeof(double)) == 0;
    AP_CHECK_EQ_INT(ap_sim_advance(s, 1.0), AP_OK);
    ap_event_record rec;
    memset(&rec, 0, sizeof rec);
    int n = ap_sim_event_count(s);
    if (n > 0) AP_CHECK_EQ_INT(ap_sim_event_get(s, 0, &rec), AP_OK);
    printf("  %s: with friction mu: the same state as the frictionless run at 0.9 t* (bitwise "
           "%d); first event %s at t = %.15g, |t - t*| / t* = %.2g; sliding at t = 1: %d\n",
           name, same, n > 0 ? rec.name : "none", rec.t, fabs(rec.t - te) / te,
           ap_sim_contact_mode(s, 0) == AP_CONTACT_SLIDING);
    AP_CHECK(same && n >= 1 && strcmp(rec.name, "roll.slip") == 0);
    AP_CHECK_LE(fabs(rec.t - te), 1e-9 * te);
    AP_CHECK_EQ_INT(ap_sim_contact_mode(s, 0), AP_CONTACT_SLIDING);
  }
  ap_sim_free(s), ap_sim_free(s0);
  ap_model_free(m), ap_model_free(m0);
}

int main(void) {
  printf("slip onset where the friction demand grows:\n");
  test_speeding_turn(AP_MODE_MINIMAL);
  test_speeding_turn(AP_MODE_PROJECTED);
  return ap_check_finish("test_slip_onset");
}
