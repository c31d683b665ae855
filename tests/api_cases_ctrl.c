/* tests/test_api's cases for inputs and controllers (appell/control.h, ap_scene_add_inputs):
 * NULL simulations, unknown names, values and periods out of range. S is the rolling disk
 * (speeds disk.vx ...); each case runs in its own child, so declaring inputs on S is local. */
#include <math.h>

#include "api_case.h"

static int ctrl_ok(double t, const double *q, const double *v, double *u, void *user) {
  (void)t, (void)q, (void)v, (void)u, (void)user;
  return 0;
}

static int declare_first(void) {
  const char *names[] = {ap_model_speed_name(BM, 0), NULL};
  return ap_sim_declare_inputs(S, names);
}

void api_cases_ctrl(void) {
  const char *none[] = {NULL}, *bad[] = {"no_such_speed", NULL};
  CASE(ap_sim_declare_inputs, "s NULL", ap_sim_declare_inputs(NULL, none) == AP_ERR_ARG);
  CASE(ap_sim_declare_inputs, "names NULL", ap_sim_declare_inputs(S, NULL) == AP_ERR_ARG);
  CASE(ap_sim_declare_inputs, "not a speed", ap_sim_declare_inputs(S, bad) == AP_ERR_ARG);
  CASE(ap_sim_input_count, "s NULL", ap_sim_input_count(NULL) == 0);
  CASE(ap_sim_input_count, "none declared", ap_sim_input_count(S) == 0);
  CASE(ap_sim_input_name, "s NULL", ap_sim_input_name(NULL, 0) == NULL);
  CASE(ap_sim_input_name, "j out of range",
       declare_first() == AP_OK && ap_sim_input_name(S, 1) == NULL &&
           ap_sim_input_name(S, -1) == NULL);
  CASE(ap_sim_find_input, "s NULL", ap_sim_find_input(NULL, "x") == -1);
  CASE(ap_sim_find_input, "name NULL", declare_first() == AP_OK && ap_sim_find_input(S, NULL) == -1);
  CASE(ap_sim_inputs, "s NULL", ap_sim_inputs(NULL) == NULL);
  CASE(ap_sim_inputs, "none declared", ap_sim_inputs(S) == NULL);
  CASE(ap_sim_set_input, "s NULL", ap_sim_set_input(NULL, "x", 1.0) == AP_ERR_ARG);
  CASE(ap_sim_set_input, "name NULL", declare_first() == AP_OK &&
                                          ap_sim_set_input(S, NULL, 1.0) == AP_ERR_ARG);
  CASE(ap_sim_set_input, "unknown name", declare_first() == AP_OK &&
                                             ap_sim_set_input(S, "nope", 1.0) == AP_ERR_ARG);
  CASE(ap_sim_set_input, "NaN", declare_first() == AP_OK &&
                                    ap_sim_set_input(S, ap_model_speed_name(BM, 0), NAN) ==
                                        AP_ERR_NAN);
  CASE(ap_sim_set_inputs, "s NULL", ap_sim_set_inputs(NULL, w) == AP_ERR_ARG);
  CASE(ap_sim_set_inputs, "u NULL", ap_sim_set_inputs(S, NULL) == AP_ERR_ARG);
  CASE(ap_sim_set_controller, "s NULL", ap_sim_set_controller(NULL, ctrl_ok, 0.01, NULL) ==
                                            AP_ERR_ARG);
  CASE(ap_sim_set_controller, "no inputs", ap_sim_set_controller(S, ctrl_ok, 0.01, NULL) ==
                                               AP_ERR_ARG);
  CASE(ap_sim_set_controller, "period 0", declare_first() == AP_OK &&
                                              ap_sim_set_controller(S, ctrl_ok, 0.0, NULL) ==
                                                  AP_ERR_ARG);
  CASE(ap_sim_set_controller, "period NaN", declare_first() == AP_OK &&
                                                ap_sim_set_controller(S, ctrl_ok, NAN, NULL) ==
                                                    AP_ERR_ARG);
  CASE(ap_sim_set_controller, "fn NULL (removes it)",
       ap_sim_set_controller(S, NULL, 0.0, NULL) == AP_OK);
  CASE(ap_scene_add_inputs, "s NULL", ap_scene_add_inputs(NULL, S, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_add_inputs, "sim NULL", ap_scene_add_inputs(SC, NULL, msg, 1) == AP_ERR_ARG);
  CASE(ap_scene_add_inputs, "sim of another model",
       ap_scene_add_inputs(SC, S, NULL, 0) == AP_ERR_ARG);
}
