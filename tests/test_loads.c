/* Wheel loads (docs/vehicles.md "Wheel loads"): the normal force of every wheel of the shipped
 * vehicles, in both chassis forms (planar, and free: --set joints.chassis.kind=free).
 *
 *  at rest on level ground (drives and motors at zero): the loads sum to m g and balance the
 *    moments of the weight about the contacts' centroid (statics); with three contacts
 *    (diff_drive_caster) each load against the lever rule, with two (diff_drive,
 *    diff_drive_motors: the planar joint keeps the pitch) m g / 2 each, with four rigid ones
 *    (car_ackermann) labelled statically indeterminate, and with the suspension
 *    (car_suspension) each load against the closed form of its scene (spring preload plus
 *    unsprung weight), labelled unique;
 *  driving (the scenes as given, 2 s): the robot with a caster and the car give the same loads
 *    on a planar and on a free chassis (the same motion written two ways) at every output,
 *    within the integrator's error (rtol 1e-10). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#ifndef AP_SRCDIR
#define AP_SRCDIR "."
#endif

#define G 9.81
#define MAXC 8

typedef struct loads {
  int n;
  double N[MAXC], x[MAXC], y[MAXC];
  ap_load_kind kind;
  int rc;
} loads;

/* The normal loads of the rolling contacts at the simulation's state. */
static loads get_loads(runner *r) {
  loads L;
  memset(&L, 0, sizeof L);
  const ap_model *m = ap_scene_model(r->sc);
  const double *lambda = NULL;
  L.rc = ap_sim_reactions(r->sim, &lambda);
  for (int i = 0; L.rc == AP_OK && i < ap_scene_count(r->sc, AP_SCENE_CONSTRAINTS); i++) {
    if (strcmp(ap_scene_element_kind(r->sc, AP_SCENE_CONSTRAINTS, i), "rolling") != 0) continue;
    ap_contact_force f;
    L.rc = ap_body_contact_force(m, ap_sim_data(r->sim), lambda, i, &f);
    if (L.rc != AP_OK || L.n >= MAXC) break;
    L.N[L.n] = f.normal, L.x[L.n] = f.point[0], L.y[L.n] = f.point[1], L.kind = f.load;
    L.n++;
  }
  return L;
}

/* Sum and moment balance of the loads against the weight W at (xc, yc). */
static void check_statics(const char *what, const loads *L, double W, double xc, double yc,
                          double tol) {
  double F = 0, Mx = 0, My = 0;
  for (int i = 0; i < L->n; i++) {
    F += L->N[i];
    Mx += L->N[i] * (L->y[i] - yc), My += L->N[i] * (L->x[i] - xc);
  }
  printf("  %-34s sum %.12g N (m g %.12g), moments %.2e %.2e N m\n", what, F, W, Mx, My);
  AP_CHECK_NEAR(F, W, tol * W);
  AP_CHECK_LE(fabs(Mx), tol * W);
  AP_CHECK_LE(fabs(My), tol * W);
}

static const char *const rest_sets[] = {"constraints.drive_l.value=0",
                                        "constraints.drive_r.value=0"};
static const char *const rest_free[] = {"constraints.drive_l.value=0",
                                        "constraints.drive_r.value=0", "joints.chassis.kind=free"};
static const char *const motors_rest[] = {"effects.motor_l.rate=0", "effects.motor_r.rate=0"};

/* Two wheels on the axle, com on the centre line: m g / 2 each; the planar joint keeps the
 * pitch moment (AP_LOAD_JOINT). */
static void test_two_wheels(const char *file, const char *const *sets) {
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, file, sets, 2, 0), AP_OK);
  loads L = get_loads(&r);
  double W = 11.0 * G;
  AP_CHECK_EQ_INT(L.rc, AP_OK);
  AP_CHECK_EQ_INT(L.n, 2);
  AP_CHECK_EQ_INT((int)L.kind, AP_LOAD_JOINT);
  for (int i = 0; i < L.n; i++) AP_CHECK_NEAR(L.N[i], W / 2, 1e-12 * W);
  double F = L.N[0] + L.N[1], Mx = L.N[0] * L.y[0] + L.N[1] * L.y[1];
  printf("  %-34s %.12g %.12g N (m g / 2 = %.12g), roll moment %.1e N m\n", file, L.N[0],
         L.N[1], W / 2, Mx);
  AP_CHECK_NEAR(F, W, 1e-12 * W);
  runner_stop(&r);
}

/* The loads at rest of a scene in one chassis form (1: free), with n contacts of kind. */
static loads rest_loads(const char *file, int form, int n, ap_load_kind kind) {
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, file, form ? rest_free : rest_sets, 2 + form, 0), AP_OK);
  loads L = get_loads(&r);
  AP_CHECK_EQ_INT(L.rc, AP_OK);
  AP_CHECK_EQ_INT(L.n, n);
  AP_CHECK_EQ_INT((int)L.kind, kind);
  runner_stop(&r);
  return L;
}

/* Three contacts: the caster at x = -0.34 m behind the axle (fork straight), the drive wheels
 * at y = +-0.25 m: the lever rule N_c = W (-x_com) / 0.34, N_l = N_r = (W - N_c) / 2. */
static void test_caster_rest(void) {
  double m = 11.3, W = m * G;
  double xcom = (10.0 * -0.08 + 0.2 * -0.32 + 0.1 * -0.34) / m;
  double Nc = W * -xcom / 0.34, Nw = (W - Nc) / 2;
  for (int form = 0; form < 2; form++) {
    loads L = rest_loads("diff_drive_caster.yaml", form, 3, AP_LOAD_UNIQUE);
    printf("  caster robot, %s chassis: %.12g %.12g %.12g N (lever rule %.12g %.12g %.12g)\n",
           form ? "free" : "planar", L.N[0], L.N[1], L.N[2], Nw, Nw, Nc);
    AP_CHECK_NEAR(L.N[0], Nw, 1e-12 * W);
    AP_CHECK_NEAR(L.N[1], Nw, 1e-12 * W);
    AP_CHECK_NEAR(L.N[2], Nc, 1e-12 * W);
    check_statics(form ? "diff_drive_caster (free)" : "diff_drive_caster (planar)", &L, W, xcom,
                  0.0, 1e-12);
  }
}

/* Four rigid wheels: indeterminate, the minimum-norm loads (still in equilibrium). */
static void test_car_rest(void) {
  double m = 24.6, W = m * G;
  double xcom = (20.0 * 0.6 + 0.6 * 1.2 + 2.0 * 1.2) / m;
  for (int form = 0; form < 2; form++) {
    loads L = rest_loads("car_ackermann.yaml", form, 4, AP_LOAD_MIN_NORM);
    check_statics(form ? "car_ackermann (free)" : "car_ackermann (planar)", &L, W, xcom, 0.0,
                  1e-12);
  }
}

/* The suspension: front 5.9667 g, rear 7.3333 g (the scene's closed form), unique; still so
 * after 1 s at rest, where the speeds are zero only to the stepper's tolerance (atol 1e-12
 * m/s): the dampers (1 kN s/m) then add up to 1e-9 N, hence 1e-11 W there. */
static void test_suspension(void) {
  runner r;
  double front = (4.466666666666667 + 1.5) * G, rear = (5.833333333333333 + 1.5) * G;
  double W = 26.6 * G;
  AP_CHECK_EQ_INT(runner_start(&r, "car_suspension.yaml", NULL, 0, 0), AP_OK);
  for (int pass = 0; pass < 2; pass++) {
    if (pass) AP_CHECK_EQ_INT(ap_sim_advance(r.sim, 1.0), AP_OK);
    loads L = get_loads(&r);
    AP_CHECK_EQ_INT(L.rc, AP_OK);
    AP_CHECK_EQ_INT(L.n, 4);
    AP_CHECK_EQ_INT((int)L.kind, AP_LOAD_UNIQUE);
    printf("  car_suspension at t = %g: rear %.12g %.12g, front %.12g %.12g N (closed form "
           "%.12g, %.12g)\n", pass ? 1.0 : 0.0, L.N[0], L.N[1], L.N[2], L.N[3], rear, front);
    double tol = pass ? 1e-11 : 1e-13;
    for (int i = 0; i < 4; i++) AP_CHECK_NEAR(L.N[i], i < 2 ? rear : front, tol * W);
    check_statics("car_suspension", &L, W, (20.0 * 0.5 + 0.6 * 1.2 + 3.0 * 1.2) / 26.6, 0.0,
                  pass ? 1e-11 : 1e-13);
  }
  runner_stop(&r);
}

/* The same motion on a planar and on a free chassis: the same loads at every output. */
static void test_forms_agree(const char *file, double W) {
  static const char *const free_set[] = {"joints.chassis.kind=free"};
  runner a, b;
  AP_CHECK_EQ_INT(runner_start(&a, file, NULL, 0, 0), AP_OK);
  AP_CHECK_EQ_INT(runner_start(&b, file, free_set, 1, 0), AP_OK);
  double worst = 0.0;
  for (int i = 0; i <= 40 && a.sim && b.sim; i++) {
    double t = 0.05 * i;
    if (i) AP_CHECK_EQ_INT(ap_sim_advance(a.sim, t), AP_OK);
    if (i) AP_CHECK_EQ_INT(ap_sim_advance(b.sim, t), AP_OK);
    loads La = get_loads(&a), Lb = get_loads(&b);
    AP_CHECK(La.rc == AP_OK && Lb.rc == AP_OK && La.n == Lb.n);
    for (int c = 0; c < La.n; c++) worst = fmax(worst, fabs(La.N[c] - Lb.N[c]));
  }
  printf("  %-34s planar vs free chassis over 2 s: loads differ by %.2e N (m g %.4g N)\n", file,
         worst, W);
  AP_CHECK_LE(worst, 1e-9 * W);
  runner_stop(&a), runner_stop(&b);
}

int main(void) {
  printf("wheel loads at rest on level ground:\n");
  test_two_wheels("diff_drive.yaml", rest_sets);
  test_two_wheels("diff_drive_motors.yaml", motors_rest);
  test_caster_rest();
  test_car_rest();
  test_suspension();
  printf("wheel loads driving, both chassis forms:\n");
  test_forms_agree("diff_drive_caster.yaml", 11.3 * G);
  test_forms_agree("car_ackermann.yaml", 24.6 * G);
  return ap_check_finish("test_loads");
}
