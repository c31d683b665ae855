/* Slip that starts at zero and stays small, with mu_kinetic = mu (docs/vehicles.md "After the
 * break", docs/scenes.md "Slip direction"): the friction of a sliding contact at a slip near 0
 * follows the sticking force, and CVODE bdf's Jacobian is differenced below the slip speed.
 *
 *  The car of car_breakaway.yaml with mu_kinetic = mu = 0.5: the inner front tyre slips at
 *    3.6307 s and its slip hovers near 0 (before: bdf stalled at steps of 1e-11 s 5e-7 s after
 *    the slip, dop853 crawled 4e-6 s in 3 s of CPU). bdf runs to 4 s in minimal mode at rtol
 *    1e-8 and 1e-10 and in projected mode at 1e-8: the slip times agree within 1e3 rtol t, the
 *    states at 4 s within 1e3 rtol max(1, |x|) (the bound of the other DAE and cross-mode
 *    checks of vehicles), each run within 5000 steps from t = 0 (600 to 1400 now); the sliding tyre's
 *    |F_t| / F_n is mu_kinetic to 1e-12 (Coulomb's law, not a regularized one).
 *  The bicycle of bicycle_turn.yaml with 0.3 N m of steer torque and mu = 0.8 on both tyres
 *    (mu_kinetic = mu): the tyres slip at 8.798 s (before: bdf stalled 3.5e-5 s after it,
 *    dop853 reached 8.79858 in 120 s); bdf runs to 8.85 s in minimal and projected mode,
 *    within 5000 steps each from t = 0 (about 750 now), a tyre slides there at |F_t| / F_n = 0.8 to 1e-12, and projected
 *    mode is within 1e3 rtol max(1, |x|) of minimal mode at 8.85 s. (DAE mode runs there too,
 *    but takes 1e5 steps and ends 5e-5 off: docs/vehicles.md; not asserted.)
 *  The 0.15 N m steady turn with mu = 0.8 holds in projected and DAE mode as in minimal mode
 *    (test_bicycle_friction.c): no event in 10 s, the frictionless run of the same mode. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

typedef struct run_def {
  const char *file, *mode;
  const char *const *sets;
  int nsets;
  double rtol, atol, t_end;
} run_def;

typedef struct run_out {
  int ok, n, k, nev, rolling;   /* events; every contact with modes rolling at the end */
  long steps;
  double t_slip, x[128], ratio_sliding;   /* x: q then v; the sliding contact's |F_t| / F_n */
  char first[96];
} run_out;

/* Counts the internal steps (ap_sim_set_poll: called before each). */
static int count_step(double t, void *user) {
  (void)t;
  ++*(long *)user;
  return 0;
}

/* The scene with bdf at (rtol, atol) in mode to t_end: its first event, the state there, and
 * the friction ratio of a sliding contact (NAN when none slides). */
static void run(const run_def *rd, run_out *o) {
  char path[1200], msg[1024] = "";
  ap_scene *sc = NULL;
  ap_sim *sim = NULL;
  memset(o, 0, sizeof *o);
  o->t_slip = o->ratio_sliding = NAN;
  snprintf(path, sizeof path, "%s/examples/scenes/%s", AP_SRCDIR, rd->file);
  if (ap_scene_load(path, rd->sets, rd->nsets, &sc, msg, sizeof msg) != AP_OK) {
    printf("  %s: %s\n", rd->file, msg);
    return;
  }
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  double x0[128];
  ap_scene_run sr;
  ap_scene_get_run(sc, &sr);
  sr.sim.method = "bdf", sr.sim.rtol = rd->rtol, sr.sim.atol = rd->atol;
  sr.sim.mode = strcmp(rd->mode, "dae") == 0         ? AP_MODE_DAE
                : strcmp(rd->mode, "projected") == 0 ? AP_MODE_PROJECTED
                                                     : AP_MODE_MINIMAL;
  int rc = n + k <= 128 ? ap_scene_initial_state(sc, x0, x0 + n, NULL, 0, msg, sizeof msg)
                        : AP_ERR_ARG;
  if (rc == AP_OK) rc = ap_sim_create(m, &sr.sim, sr.t0, x0, x0 + n, &sim, msg, sizeof msg);
  long polls = 0;
  if (rc == AP_OK) ap_sim_set_poll(sim, count_step, &polls);
  if (rc == AP_OK) rc = ap_sim_advance(sim, rd->t_end);
  if (rc != AP_OK) printf("  %s %s: %s\n", rd->file, rd->mode, sim ? ap_sim_message(sim) : msg);
  if (rc == AP_OK) {
    ap_event_record rec;
    const double *lam = NULL;
    o->ok = 1, o->n = n, o->k = k;
    o->nev = runner_event(sim, 0, &rec);
    if (o->nev > 0) o->t_slip = rec.t;
    o->rolling = 1;
    for (int c = 0; c < ap_scene_count(sc, AP_SCENE_CONSTRAINTS); c++)
      if (ap_sim_contact_mode(sim, c) >= 0) o->rolling &= ap_sim_contact_mode(sim, c) == 0;
    snprintf(o->first, sizeof o->first, "%s", rec.name);
    o->steps = polls;
    memcpy(o->x, ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(o->x + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
    AP_CHECK_EQ_INT(ap_sim_reactions(sim, &lam), AP_OK);
    for (int c = 0; lam && c < ap_scene_count(sc, AP_SCENE_CONSTRAINTS); c++) {
      ap_contact_force f;
      if (ap_sim_contact_mode(sim, c) != AP_CONTACT_SLIDING) continue;
      if (ap_body_contact_force(m, ap_sim_data(sim), lam, c, &f) == AP_OK)
        o->ratio_sliding = f.friction_ratio;
    }
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
}

/* Largest |a - b| / max(1, |b|) over the state. */
static double state_diff(const run_out *a, const run_out *b) {
  double e = 0.0;
  for (int i = 0; i < a->n + a->k; i++)
    e = fmax(e, fabs(a->x[i] - b->x[i]) / fmax(1.0, fabs(b->x[i])));
  return e;
}

static void report(const run_def *rd, const run_out *o, double mu_k, long max_steps) {
  printf("  %s, %s, rtol %g: to t = %g: %d, first event %s at %.12g, %ld steps, sliding "
         "|F_t| / F_n = %.15g (mu_kinetic %g)\n", rd->file, rd->mode, rd->rtol, rd->t_end, o->ok,
         o->first, o->t_slip, o->steps, o->ratio_sliding, mu_k);
  AP_CHECK(o->ok && strstr(o->first, ".slip") != NULL);
  AP_CHECK(o->steps > 0 && o->steps <= max_steps);
  AP_CHECK_LE(fabs(o->ratio_sliding - mu_k), 1e-12);
}

/* Run o (rd) against the reference run (minimal mode, rtol 1e-8): slips within 1e3 rtol t,
 * states at the end within 1e3 rtol max(1, |x|). */
static void agree(const run_def *rd, const run_out *o, const run_out *ref) {
  if (!o->ok || !ref->ok) return;
  double dt = fabs(o->t_slip - ref->t_slip), dx = state_diff(o, ref);
  printf("    %s rtol %g against minimal rtol 1e-8: slip %.2g s apart (bound %.2g), state at "
         "%g s %.2g (bound %.2g)\n", rd->mode, rd->rtol, dt, 1e3 * 1e-8 * ref->t_slip,
         rd->t_end, dx, 1e3 * 1e-8);
  AP_CHECK_LE(dt, 1e3 * 1e-8 * ref->t_slip);
  AP_CHECK_LE(dx, 1e3 * 1e-8);
}

static void test_car(void) {
  const char *sets[] = {"parameters.mu_k=0.5"};
  run_def rd[3] = {{"car_breakaway.yaml", "minimal", sets, 1, 1e-8, 1e-12, 4.0},
                   {"car_breakaway.yaml", "minimal", sets, 1, 1e-10, 1e-12, 4.0},
                   {"car_breakaway.yaml", "projected", sets, 1, 1e-8, 1e-12, 4.0}};
  run_out o[3];
  for (int i = 0; i < 3; i++) run(&rd[i], &o[i]), report(&rd[i], &o[i], 0.5, 5000);
  for (int i = 1; i < 3; i++) agree(&rd[i], &o[i], &o[0]);
}

static void test_bicycle(void) {
  const char *sets[] = {"effects.steer.torque=0.3", "constraints.rear_contact.friction={mu: 0.8}",
                        "constraints.front_contact.friction={mu: 0.8}"};
  const char *modes[2] = {"minimal", "projected"};
  run_def rd[2];
  run_out o[2];
  for (int i = 0; i < 2; i++) {
    rd[i] = (run_def){"bicycle_turn.yaml", modes[i], sets, 3, 1e-8, 1e-10, 8.85};
    run(&rd[i], &o[i]);
    report(&rd[i], &o[i], 0.8, 5000);
  }
  agree(&rd[1], &o[1], &o[0]);
}

/* The 0.15 N m steady turn with mu = 0.8 in projected and DAE mode (bdf, rtol 1e-8, 10 s):
 * no event, both tyres rolling, the state within 1e3 rtol max(1, |x|) of the frictionless run
 * of the same mode (the tyres hold: the run is the frictionless one). */
static void test_holds(void) {
  const char *fr[] = {"effects.steer.torque=0.15", "constraints.rear_contact.friction={mu: 0.8}",
                      "constraints.front_contact.friction={mu: 0.8}"};
  const char *modes[2] = {"projected", "dae"};
  for (int i = 0; i < 2; i++) {
    run_def a = {"bicycle_turn.yaml", modes[i], fr, 3, 1e-8, 1e-10, 10.0};
    run_def b = {"bicycle_turn.yaml", modes[i], fr, 1, 1e-8, 1e-10, 10.0};
    run_out oa, ob;
    run(&a, &oa), run(&b, &ob);
    double dx = oa.ok && ob.ok ? state_diff(&oa, &ob) : INFINITY;
    printf("  steady turn, mu 0.8, %s: %d events, both rolling %d, state after 10 s %.2g from "
           "the frictionless run (bound %.2g)\n", modes[i], oa.nev, oa.rolling, dx, 1e3 * 1e-8);
    AP_CHECK(oa.ok && ob.ok && oa.nev == 0 && oa.rolling);
    AP_CHECK_LE(dx, 1e3 * 1e-8);
  }
}

int main(void) {
  printf("slip near zero with mu_kinetic = mu:\n");
  test_car();
  test_bicycle();
  test_holds();
  return ap_check_finish("test_stick_slip");
}
