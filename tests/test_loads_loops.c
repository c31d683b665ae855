/* The wheel loads of diff_drive_loops.yaml (docs/vehicles.md "Wheel loads"): the robot of
 * diff_drive.yaml built from plane-contact wheels joined to a planar chassis by loop
 * closures. Each wheel keeps its own height on its plane-contact joint and the chassis its
 * height on its planar joint, so Newton's law for a wheel alone gives its own weight only
 * (4.905 N each: 1/11 of m g before the fix); the chassis' weight and tilting moments, which
 * its joint carries in the model, are the wheels' in reality. The loads are the vehicle's:
 * chassis and wheels together (loop forces cancel), shared between the two contacts, the
 * pitch about their line kept by the joint (AP_LOAD_JOINT, as for diff_drive.yaml).
 *
 * Statics (chassis 10 kg with its centre of mass on the axle midpoint at the axle height
 * h = 0.1 m, wheels 0.5 kg of radius 0.1 m, track 0.5 m; m = 11 kg):
 *   at rest          N_l = N_r = m g / 2 (the lever rule);
 *   on its circle    (R = 1.25 m at v = 1 m/s, yaw rate W = 0.8 rad/s, wheel spins w_l = 8,
 *                    w_r = 12 rad/s): the roll moment of the inertial forces and of the wheels'
 *                    gyroscopic moments moves load to the outer (right) wheel,
 *                    N_r - N_l = 2 [h (m_c v^2/R + m_w W^2 (R_l + R_r)) + I_a W (w_l + w_r)]
 *                    / track, R_l,r = R -+ track / 2, I_a = m_w r^2 / 2;
 * at the initial state (to 1e-12 of m g: round-off) and after 1 s of coasting (the same
 * circle: the run's error, rtol 1e-10, bound 1e-8 m g), minimal and projected mode. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define G 9.81
#define MC 10.0
#define MW 0.5
#define H 0.1
#define TRACK 0.5

static void loads(runner *r, double *N, int *kind) {
  const double *lambda = NULL;
  int n = 0;
  AP_CHECK_EQ_INT(ap_sim_reactions(r->sim, &lambda), AP_OK);
  for (int i = 0; lambda && i < ap_scene_count(r->sc, AP_SCENE_CONSTRAINTS); i++) {
    if (strcmp(ap_scene_element_kind(r->sc, AP_SCENE_CONSTRAINTS, i), "rolling") != 0) continue;
    ap_contact_force f;
    AP_CHECK_EQ_INT(ap_body_contact_force(ap_scene_model(r->sc), ap_sim_data(r->sim), lambda,
                                          i, &f), AP_OK);
    if (n < 2) N[n] = f.normal, kind[n] = (int)f.load;
    n++;
  }
  AP_CHECK_EQ_INT(n, 2);
}

static void check(const char *what, runner *r, double Nl, double Nr, double tol) {
  double N[2] = {NAN, NAN}, W = (MC + 2 * MW) * G;
  int kind[2] = {-1, -1};
  loads(r, N, kind);
  printf("  %s: roll_l %.13g N (statics %.13g), roll_r %.13g N (%.13g); sum %.13g of m g "
         "%.13g; worst %.1e of m g\n", what, N[0], Nl, N[1], Nr, N[0] + N[1], W,
         fmax(fabs(N[0] - Nl), fabs(N[1] - Nr)) / W);
  AP_CHECK_NEAR(N[0], Nl, tol * W);
  AP_CHECK_NEAR(N[1], Nr, tol * W);
  AP_CHECK_NEAR(N[0] + N[1], W, tol * W);
  AP_CHECK(kind[0] == AP_LOAD_JOINT && kind[1] == AP_LOAD_JOINT);
}

static void test_mode(const char *mode) {
  char sm[64];
  snprintf(sm, sizeof sm, "simulation.mode=%s", mode);
  const char *rest[] = {sm, "initial.chassis={vx: 0, heading_rate: 0}",
                        "initial.wheel_l={y: 0.25, tilt: 90*deg}",
                        "initial.wheel_r={y: -0.25, tilt: 90*deg}"};
  double W = (MC + 2 * MW) * G;
  runner r;
  printf(" %s mode:\n", mode);
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_loops.yaml", rest, 4, 0), AP_OK);
  if (r.sim) check("at rest", &r, W / 2, W / 2, 1e-12);
  runner_stop(&r);
  /* on the circle: R = 1.25, v = 1, W = 0.8, wheel spins 8 and 12 rad/s */
  double R = 1.25, v = 1.0, yaw = 0.8, Ia = MW * 0.1 * 0.1 / 2;
  double roll = H * (MC * v * v / R + MW * yaw * yaw * (2 * R)) + Ia * yaw * (8.0 + 12.0);
  double dN = roll / TRACK;
  const char *moving[] = {sm};
  AP_CHECK_EQ_INT(runner_start(&r, "diff_drive_loops.yaml", moving, 1, 0), AP_OK);
  if (r.sim) {
    check("on its circle, t = 0", &r, W / 2 - dN, W / 2 + dN, 1e-12);
    AP_CHECK_EQ_INT(ap_sim_advance(r.sim, 1.0), AP_OK);
    check("on its circle, t = 1 s", &r, W / 2 - dN, W / 2 + dN, 1e-8);
  }
  runner_stop(&r);
}

int main(void) {
  printf("the loads of the robot with an axle of loop closures:\n");
  test_mode("minimal");
  test_mode("projected");
  return ap_check_finish("test_loads_loops");
}
