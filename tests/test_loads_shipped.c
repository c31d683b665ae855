/* Wheel loads of every shipped vehicle (docs/vehicles.md "Wheel loads"): at rest on level
 * ground the normal loads of all its rolling contacts sum to m g (Newton, vertically: nothing
 * else holds the vehicle up), in each chassis form that is at rest there. test_loads.c checks
 * diff_drive, diff_drive_motors (planar), diff_drive_caster and car_ackermann (both forms)
 * and car_suspension (free) against the lever rule and statics; this adds the others:
 *
 *   diff_drive_control, diff_drive_servo    planar (two wheels, com 0.1 m ahead of the axle:
 *                                           on a free chassis it tips onto its nose, no rest)
 *   diff_drive_brake, diff_drive_skid       free (as shipped) and planar
 *   car_suspension                          planar (the struts' springs still carry the body)
 *   bicycle, bicycle_falling                free, upright at rest (a planar rear frame cannot
 *                                           lean: no bicycle)
 *
 * diff_drive_loops (wheels on their own plane-contact joints, joined to the chassis by loop
 * closures) is in test_loads_loops.c. m from the scenes' masses. Tolerance 1e-12 of m g: statics at one state, round-off only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "scene_runner.h"

#define G 9.81
#define MAXS 8

typedef struct shipped {
  const char *file, *form;
  double mass;
  int contacts;
  const char *sets[MAXS];
} shipped;

static const shipped CASES[] = {
    {"diff_drive_control.yaml", "planar", 11.0, 2, {NULL}},
    {"diff_drive_servo.yaml", "planar", 11.0, 2, {NULL}},
    {"diff_drive_brake.yaml", "free", 11.3, 3,
     {"initial.chassis={z: 0}", "initial.wheel_l={rate: 0}", "initial.wheel_r={rate: 0}",
      "initial.caster={rate: 0}", "effects.brake_l.torque=0", "effects.brake_r.torque=0",
      NULL}},
    {"diff_drive_brake.yaml", "planar", 11.3, 3,
     {"joints.chassis.kind=planar", "initial.chassis={x: 0}", "initial.wheel_l={rate: 0}",
      "initial.wheel_r={rate: 0}", "initial.caster={rate: 0}", "effects.brake_l.torque=0",
      "effects.brake_r.torque=0", NULL}},
    {"diff_drive_skid.yaml", "free", 11.3, 3, {"initial.chassis={z: 0}", NULL}},
    {"diff_drive_skid.yaml", "planar", 11.3, 3,
     {"joints.chassis.kind=planar", "initial.chassis={x: 0}", NULL}},
    {"car_suspension.yaml", "planar", 26.6, 4, {"joints.chassis.kind=planar", NULL}},
    {"bicycle.yaml", "free", 94.0, 2,
     {"initial.rear_frame.tilt_rate=0", "initial.rear_wheel.rate=0", NULL}},
    {"bicycle_falling.yaml", "free", 94.0, 2,
     {"initial.rear_frame.tilt_rate=0", "initial.rear_wheel.rate=0", NULL}},
};

static void check_case(const shipped *c) {
  int ns = 0;
  while (ns < MAXS && c->sets[ns]) ns++;
  runner r;
  AP_CHECK_EQ_INT(runner_start(&r, c->file, c->sets, ns, 0), AP_OK);
  if (!r.sim) return runner_stop(&r);
  const ap_model *m = ap_scene_model(r.sc);
  const double *lambda = NULL;
  double sum = 0.0, W = c->mass * G;
  int n = 0, rc = ap_sim_reactions(r.sim, &lambda);
  AP_CHECK_EQ_INT(rc, AP_OK);
  for (int i = 0; rc == AP_OK && i < ap_scene_count(r.sc, AP_SCENE_CONSTRAINTS); i++) {
    if (strncmp(ap_scene_element_kind(r.sc, AP_SCENE_CONSTRAINTS, i), "rolling", 7) != 0)
      continue;
    ap_contact_force f;
    AP_CHECK_EQ_INT(ap_body_contact_force(m, ap_sim_data(r.sim), lambda, i, &f), AP_OK);
    sum += f.normal, n++;
    AP_CHECK(f.normal > 0);
  }
  printf("  %-24s %-6s %d contacts, loads sum %.13g N, m g %.13g N (%.1e)\n", c->file, c->form,
         n, sum, W, fabs(sum - W) / W);
  AP_CHECK_EQ_INT(n, c->contacts);
  AP_CHECK_NEAR(sum, W, 1e-12 * W);
  runner_stop(&r);
}

int main(void) {
  printf("wheel loads of the shipped vehicles at rest on level ground:\n");
  for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) check_case(&CASES[i]);
  return ap_check_finish("test_loads_shipped");
}
