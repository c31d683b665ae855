/* test_api's cases, second half (api_case.h): body queries, scenes and their runs, batches,
 * the linearizer. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_case.h"

static int load_string(const char *text, size_t len, const char *const *sets, int nsets,
                       ap_scene **out, char *m, size_t mlen) {
  return ap_scene_load_string(text, len, "api.yaml", sets, nsets, out, m, mlen);
}
static const char *const no_sets[1] = {NULL};
static const char *const good_sets[1] = {"bodies.sleigh.mass=2"};

static void cases_body_queries(void) {
  CASE(ap_model_is_body_model, "NULL", ap_model_is_body_model(NULL) == 0);
  CASE(ap_model_body_count, "NULL", ap_model_body_count(NULL) == AP_ERR_ARG);
  CASE(ap_model_body_count, "math-level model", ap_model_body_count(SM) == AP_ERR_ARG);
  CASE(ap_model_find_body, "m NULL", ap_model_find_body(NULL, "disk") == -1);
  CASE(ap_model_find_body, "name NULL", ap_model_find_body(BM, NULL) == -1);
  CASE(ap_model_body_name, "m NULL", ap_model_body_name(NULL, 0) == NULL);
  CASE(ap_model_body_name, "math-level model", ap_model_body_name(SM, 0) == NULL);
  CASE(ap_model_body_name, "b out of range", ap_model_body_name(BM, 1) == NULL);
  CASE(ap_model_body_shape, "m NULL", ap_model_body_shape(NULL, 0, &(ap_shape){0}) == AP_ERR_ARG);
  CASE(ap_model_body_shape, "out NULL", ap_model_body_shape(BM, 0, NULL) == AP_ERR_ARG);
  CASE(ap_model_body_shape, "b < 0", ap_model_body_shape(BM, -1, &(ap_shape){0}) == AP_ERR_ARG);
  CASE(ap_model_find_coord, "m NULL", ap_model_find_coord(NULL, "x") == -1);
  CASE(ap_model_find_coord, "name NULL", ap_model_find_coord(BM, NULL) == -1);
  CASE(ap_model_find_speed, "m NULL", ap_model_find_speed(NULL, "x") == -1);
  CASE(ap_model_find_speed, "name NULL", ap_model_find_speed(BM, NULL) == -1);
  CASE(ap_joint_coord_index, "m NULL", ap_joint_coord_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "joint -1", ap_joint_coord_index(BM, -1) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "joint 99", ap_joint_coord_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_joint_coord_index, "math-level model", ap_joint_coord_index(SM, 0) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "m NULL", ap_joint_speed_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "joint 99", ap_joint_speed_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_joint_speed_index, "math-level model", ap_joint_speed_index(SM, 0) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "m NULL", ap_constraint_row_index(NULL, 0) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "constraint -1", ap_constraint_row_index(BM, -1) == AP_ERR_ARG);
  CASE(ap_constraint_row_index, "constraint 99", ap_constraint_row_index(BM, 99) == AP_ERR_ARG);
  CASE(ap_body_eval, "m NULL", ap_body_eval(NULL, BD) == AP_ERR_ARG);
  CASE(ap_body_eval, "d NULL", ap_body_eval(BM, NULL) == AP_ERR_ARG);
  CASE(ap_body_eval, "math-level model", ap_body_eval(SM, SD) == AP_ERR_ARG);
  CASE(ap_body_eval, "d of another model", ap_body_eval(BM, TD) == AP_ERR_ARG);
  CASE(ap_body_get_state, "m NULL", ap_body_get_state(NULL, BD, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "d NULL", ap_body_get_state(BM, NULL, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "body -1", ap_body_get_state(BM, BD, -1, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "body 99", ap_body_get_state(BM, BD, 99, &bst) == AP_ERR_ARG);
  CASE(ap_body_get_state, "out NULL", ap_body_get_state(BM, BD, 0, NULL) == AP_ERR_ARG);
  CASE(ap_body_get_state, "d of another model", ap_body_get_state(BM, TD, 0, &bst) == AP_ERR_ARG);
  CASE(ap_body_quantity, "m NULL", ap_body_quantity(NULL, BD, 0, 0, &T) == AP_ERR_ARG);
  CASE(ap_body_quantity, "d NULL", ap_body_quantity(BM, NULL, 0, 0, &T) == AP_ERR_ARG);
  CASE(ap_body_quantity, "body -1", ap_body_quantity(BM, BD, -1, 0, &T) == AP_ERR_ARG);
  CASE(ap_body_quantity, "which -1", ap_body_quantity(BM, BD, 0, -1, &T) == AP_ERR_ARG);
  CASE(ap_body_quantity, "which 99", ap_body_quantity(BM, BD, 0, 99, &T) == AP_ERR_ARG);
  CASE(ap_body_quantity, "value NULL", ap_body_quantity(BM, BD, 0, 0, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "m NULL",
       ap_body_point_jacobian(NULL, BD, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "d NULL",
       ap_body_point_jacobian(BM, NULL, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "body -1",
       ap_body_point_jacobian(BM, BD, -1, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "body 99",
       ap_body_point_jacobian(BM, BD, 99, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "p NULL",
       ap_body_point_jacobian(BM, BD, 0, NULL, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_point_jacobian, "outputs NULL (optional)",
       ap_body_point_jacobian(BM, BD, 0, axis, NULL, NULL, NULL, NULL, NULL, NULL) == AP_OK);
  CASE(ap_body_point_jacobian, "d of another model",
       ap_body_point_jacobian(BM, TD, 0, axis, w, w, NULL, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_energy, "m NULL", ap_body_energy(NULL, BD, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_energy, "d NULL", ap_body_energy(BM, NULL, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_energy, "outputs NULL (optional)", ap_body_energy(BM, BD, NULL, NULL) == AP_OK);
  CASE(ap_body_contact_modes, "m NULL", ap_body_contact_modes(NULL, BD, NULL, 1e-6) == AP_ERR_ARG);
  CASE(ap_body_contact_modes, "d NULL", ap_body_contact_modes(BM, NULL, NULL, 1e-6) == AP_ERR_ARG);
  CASE(ap_body_contact_modes, "tol 0", ap_body_contact_modes(BM, BD, NULL, 0.0) == AP_ERR_ARG);
  CASE(ap_body_energy, "d of another model", ap_body_energy(BM, TD, &T, &V) == AP_ERR_ARG);
  CASE(ap_body_effect_count, "m NULL", ap_body_effect_count(NULL, BD, 0) == -1);
  CASE(ap_body_effect_count, "d NULL", ap_body_effect_count(BM, NULL, 0) == -1);
  CASE(ap_body_effect_count, "effect -1", ap_body_effect_count(BM, BD, -1) == -1);
  CASE(ap_body_effect_count, "effect 99", ap_body_effect_count(BM, BD, 99) == -1);
  CASE(ap_body_effect_count, "d of another model", ap_body_effect_count(BM, TD, 0) == -1);
  CASE(ap_body_project_q, "m NULL", ap_body_project_q(NULL, BD, q, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "d NULL", ap_body_project_q(BM, NULL, q, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "q NULL", ap_body_project_q(BM, BD, NULL, &T) == AP_ERR_ARG);
  CASE(ap_body_project_q, "change NULL (optional)", ap_body_project_q(BM, BD, q, NULL) == AP_OK);
  CASE(ap_body_project_q, "d of another model", ap_body_project_q(BM, TD, q, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "m NULL", ap_body_loop_residual(NULL, BD, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "d NULL", ap_body_loop_residual(BM, NULL, &T) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "phi_max NULL", ap_body_loop_residual(BM, BD, NULL) == AP_ERR_ARG);
  CASE(ap_body_loop_residual, "d of another model",
       ap_body_loop_residual(BM, TD, &T) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "m NULL",
       ap_body_complete_speeds(NULL, BD, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "d NULL",
       ap_body_complete_speeds(BM, NULL, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "q NULL",
       ap_body_complete_speeds(BM, BD, NULL, given, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "given NULL",
       ap_body_complete_speeds(BM, BD, q, NULL, v) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "v NULL",
       ap_body_complete_speeds(BM, BD, q, given, NULL) == AP_ERR_ARG);
  CASE(ap_body_complete_speeds, "d of another model",
       ap_body_complete_speeds(BM, TD, q, given, v) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "m NULL",
       ap_body_contact_force(NULL, BD, NULL, 0, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "d NULL",
       ap_body_contact_force(BM, NULL, NULL, 0, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "constraint -1",
       ap_body_contact_force(BM, BD, NULL, -1, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "constraint 99",
       ap_body_contact_force(BM, BD, NULL, 99, &cf) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "out NULL",
       ap_body_contact_force(BM, BD, NULL, 0, NULL) == AP_ERR_ARG);
  CASE(ap_body_contact_force, "d of another model",
       ap_body_contact_force(BM, TD, NULL, 0, &cf) == AP_ERR_ARG);
  double out[9] = {0};
  CASE(ap_quat_from_axis_angle, "axis NULL: q untouched",
       (ap_quat_from_axis_angle(NULL, 1.0, out), all_zero(out, sizeof out)));
  CASE(ap_quat_from_axis_angle, "q NULL", (ap_quat_from_axis_angle(axis, 1.0, NULL), 1));
  CASE(ap_quat_mul, "a NULL: out untouched",
       (ap_quat_mul(NULL, qa, out), all_zero(out, sizeof out)));
  CASE(ap_quat_mul, "b NULL: out untouched",
       (ap_quat_mul(qa, NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_mul, "out NULL", (ap_quat_mul(qa, qa, NULL), 1));
  CASE(ap_quat_to_matrix, "q NULL: R untouched",
       (ap_quat_to_matrix(NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_to_matrix, "R NULL", (ap_quat_to_matrix(qa, NULL), 1));
  CASE(ap_quat_from_matrix, "R NULL: q untouched",
       (ap_quat_from_matrix(NULL, out), all_zero(out, sizeof out)));
  CASE(ap_quat_from_matrix, "q NULL", (ap_quat_from_matrix(out, NULL), 1));
}

static void cases_scene(void) {
  size_t n = strlen(SCENE);
  CASE(ap_scene_load, "path NULL",
       ap_scene_load(NULL, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "out NULL",
       ap_scene_load(SCENE_PATH, NULL, 0, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_load, "sets NULL, nsets 1",
       ap_scene_load(SCENE_PATH, NULL, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "nsets -1",
       ap_scene_load(SCENE_PATH, good_sets, -1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "sets[0] NULL",
       ap_scene_load(SCENE_PATH, no_sets, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "msg NULL, length > 0",
       ap_scene_load(NULL, NULL, 0, &osc, NULL, 100) == AP_ERR_ARG);
  CASE(ap_scene_load, "path is a directory",
       ap_scene_load("/", NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load, "sets NULL, nsets 0 (no overrides)",
       ap_scene_load(SCENE_PATH, NULL, 0, &osc, msg, sizeof msg) == AP_OK);
  CASE(ap_scene_load_string, "text NULL",
       load_string(NULL, 10, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "out NULL",
       load_string(SCENE, n, NULL, 0, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "sets NULL, nsets 1",
       load_string(SCENE, n, NULL, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "nsets -1",
       load_string(SCENE, n, good_sets, -1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "sets[0] NULL",
       load_string(SCENE, n, no_sets, 1, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_load_string, "msg NULL, length > 0",
       load_string(NULL, 10, NULL, 0, &osc, NULL, 100) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "msg_len 0",
       load_string(SCENE, n, no_sets, 1, &osc, msg, 0) == AP_ERR_ARG);
  CASE(ap_scene_load_string, "name NULL (optional)",
       ap_scene_load_string(SCENE, n, NULL, NULL, 0, &osc, msg, sizeof msg) == AP_OK);
  CASE(ap_scene_load_string, "length 0",
       load_string(SCENE, 0, NULL, 0, &osc, msg, sizeof msg) == AP_ERR_ARG && !osc);
  CASE(ap_scene_free, "NULL", (ap_scene_free(NULL), 1));
  CASE(ap_scene_model, "NULL", ap_scene_model(NULL) == NULL);
  CASE(ap_scene_get_run, "s NULL: zeroed",
       (memset(&run, 1, sizeof run), ap_scene_get_run(NULL, &run), all_zero(&run, sizeof run)));
  CASE(ap_scene_get_run, "run NULL", (ap_scene_get_run(SC, NULL), 1));
  CASE(ap_scene_add_events, "s NULL", ap_scene_add_events(NULL, S, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_add_events, "sim NULL", ap_scene_add_events(SC, NULL, msg, 1) == AP_ERR_ARG);
  CASE(ap_scene_add_events, "sim of another model",
       ap_scene_add_events(SC, S, NULL, 0) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "s NULL",
       ap_scene_initial_state(NULL, q, v, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "q0 NULL",
       ap_scene_initial_state(SC, NULL, v, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "v0 NULL",
       ap_scene_initial_state(SC, q, NULL, msg, sizeof msg, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_initial_state, "report, msg NULL (optional)",
       ap_scene_initial_state(SC, q, v, NULL, 100, NULL, 100) == AP_OK);
  CASE(ap_scene_check_time, "s NULL",
       ap_scene_check_time(NULL, 0.0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_check_time, "msg NULL, length > 0 (optional)",
       ap_scene_check_time(SC, 0.0, NULL, 100) == AP_OK);
  CASE(ap_scene_output_count, "NULL", ap_scene_output_count(NULL) == 0);
  CASE(ap_scene_output_name, "s NULL", ap_scene_output_name(NULL, 0) == NULL);
  CASE(ap_scene_output_name, "i -1", ap_scene_output_name(SC, -1) == NULL);
  CASE(ap_scene_output_name, "i = count",
       ap_scene_output_name(SC, ap_scene_output_count(SC)) == NULL);
  CASE(ap_scene_output_row, "s NULL", ap_scene_output_row(NULL, S, row) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "sim NULL", ap_scene_output_row(SC, NULL, row) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "row NULL", ap_scene_output_row(SC, S, NULL) == AP_ERR_ARG);
  CASE(ap_scene_output_row, "sim of another model", ap_scene_output_row(SC, S, row) == AP_ERR_ARG);
  CASE(ap_scene_energy, "s NULL", ap_scene_energy(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "q NULL", ap_scene_energy(SC, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "v NULL", ap_scene_energy(SC, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_energy, "E NULL", ap_scene_energy(SC, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_residual, "s NULL", ap_scene_residual(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "q NULL", ap_scene_residual(SC, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "v NULL", ap_scene_residual(SC, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_residual, "resid NULL", ap_scene_residual(SC, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_conserves_energy, "NULL", ap_scene_conserves_energy(NULL) == 0);
  CASE(ap_scene_count, "s NULL", ap_scene_count(NULL, AP_SCENE_BODIES) == 0);
  CASE(ap_scene_count, "section 99", ap_scene_count(SC, (ap_scene_section)99) == 0);
  CASE(ap_scene_count, "section -1", ap_scene_count(SC, (ap_scene_section)-1) == 0);
  CASE(ap_scene_element_name, "s NULL", ap_scene_element_name(NULL, AP_SCENE_BODIES, 0) == NULL);
  CASE(ap_scene_element_name, "section 99",
       ap_scene_element_name(SC, (ap_scene_section)99, 0) == NULL);
  CASE(ap_scene_element_name, "i -1", ap_scene_element_name(SC, AP_SCENE_BODIES, -1) == NULL);
  CASE(ap_scene_element_name, "i 99", ap_scene_element_name(SC, AP_SCENE_CHANNELS, 99) == NULL);
  CASE(ap_scene_element_kind, "s NULL", ap_scene_element_kind(NULL, AP_SCENE_BODIES, 0) == NULL);
  CASE(ap_scene_element_kind, "section 99",
       ap_scene_element_kind(SC, (ap_scene_section)99, 0) == NULL);
  CASE(ap_scene_element_kind, "i -1", ap_scene_element_kind(SC, AP_SCENE_EFFECTS, -1) == NULL);
  CASE(ap_scene_element_kind, "i 99", ap_scene_element_kind(SC, AP_SCENE_CONSTRAINTS, 99) == NULL);
  CASE(ap_scene_name, "NULL", ap_scene_name(NULL) == NULL);
  CASE(ap_scene_body_visual, "s NULL",
       ap_scene_body_visual(NULL, 0, &(ap_scene_visual){0}) == AP_ERR_ARG);
  CASE(ap_scene_body_visual, "out NULL", ap_scene_body_visual(SC, 0, NULL) == AP_ERR_ARG);
  CASE(ap_scene_body_visual, "body out of range",
       ap_scene_body_visual(SC, 99, &(ap_scene_visual){0}) == AP_ERR_ARG);
  CASE(ap_scene_parameter_count, "s NULL", ap_scene_parameter_count(NULL) == 0);
  const char *pname = NULL;
  double pvalue = 0.0;
  CASE(ap_scene_parameter, "s NULL", ap_scene_parameter(NULL, 0, &pname, &pvalue) == AP_ERR_ARG);
  CASE(ap_scene_parameter, "i -1", ap_scene_parameter(SC, -1, &pname, &pvalue) == AP_ERR_ARG);
  CASE(ap_scene_parameter, "i 99", ap_scene_parameter(SC, 99, &pname, &pvalue) == AP_ERR_ARG);
  CASE(ap_scene_parameter, "name NULL", ap_scene_parameter(SC, 0, NULL, &pvalue) == AP_ERR_ARG);
}

static int eig_fn(double p_, int n, double *re, double *im, void *user) {
  (void)user;
  for (int i = 0; i < n; i++) re[i] = p_ - 1.0 - i, im[i] = 0.0;
  return 0;
}

static void cases_scene_runs(void) {
  CASE(ap_scene_out_create, "s NULL", ap_scene_out_create(NULL, &oo) == AP_ERR_ARG && !oo);
  CASE(ap_scene_out_create, "out NULL", ap_scene_out_create(SC, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "o NULL", ap_scene_out_row(NULL, S, row) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "sim NULL", ap_scene_out_row(O, NULL, row) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "row NULL", ap_scene_out_row(O, S, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_row, "sim of another model", ap_scene_out_row(O, S, row) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "o NULL", ap_scene_out_energy(NULL, 0, q, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "q NULL", ap_scene_out_energy(O, 0, NULL, v, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "v NULL", ap_scene_out_energy(O, 0, q, NULL, &E) == AP_ERR_ARG);
  CASE(ap_scene_out_energy, "E NULL", ap_scene_out_energy(O, 0, q, v, NULL) == AP_ERR_ARG);
  CASE(ap_scene_out_free, "NULL", (ap_scene_out_free(NULL), 1));
  CASE(ap_scene_constant, "text NULL", ap_scene_constant(NULL, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_constant, "x NULL", ap_scene_constant("2", NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_constant, "not an expression",
       ap_scene_constant("1 +", &E, msg, sizeof msg) == AP_ERR_ARG && msg[0]);
  CASE(ap_scene_constant, "msg NULL, length > 0 (optional)",
       ap_scene_constant("70*deg", &E, NULL, 100) == AP_OK);
  CASE(ap_scene_get_linearize, "s NULL",
       ap_scene_get_linearize(NULL, &sl, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_get_linearize, "out NULL",
       ap_scene_get_linearize(SC, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_lin_free, "NULL", (ap_scene_lin_free(NULL), 1));
  CASE(ap_scene_lin_guess_load, "path NULL",
       ap_scene_lin_guess_load(NULL, NULL, 0, NULL, 0, &lg, msg, sizeof msg) == AP_ERR_ARG &&
           msg[0] && !lg.scene);
  CASE(ap_scene_lin_guess_load, "out NULL",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, 0, NULL, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_scene_lin_guess_load, "nsets -1",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, -1, &lg, msg, sizeof msg) ==
           AP_ERR_ARG && !lg.scene);
  CASE(ap_scene_lin_guess_load, "sets NULL, nsets 1",
       ap_scene_lin_guess_load(SCENE_PATH, NULL, 0, NULL, 1, &lg, msg, sizeof msg) ==
           AP_ERR_ARG && !lg.scene);
  CASE(ap_scene_lin_guess_load, "a missing file",
       ap_scene_lin_guess_load("/nonexistent/x.yaml", NULL, 0, NULL, 0, &lg, msg, sizeof msg) !=
           AP_OK && msg[0] && !lg.scene && !lg.q);
  CASE(ap_scene_lin_guess_load, "msg NULL (optional)",
       ap_scene_lin_guess_load(NULL, NULL, 0, NULL, 0, &lg, NULL, 0) == AP_ERR_ARG);
  CASE(ap_scene_lin_guess_free, "NULL", (ap_scene_lin_guess_free(NULL), 1));
  CASE(ap_scene_lin_guess_free, "zeroed", (ap_scene_lin_guess_free(&lg), isnan(lg.speed)));
  CASE(ap_scene_lin_def, "NULL: the defaults",
       ap_scene_lin_def(NULL).about == AP_LIN_STEADY && !ap_scene_lin_def(NULL).speed_dir);
  CASE(ap_scene_lin_create, "g NULL", ap_scene_lin_create(NULL, NULL, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_scene_lin_create, "g without a scene",
       ap_scene_lin_create(&lg, NULL, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_scene_lin_create, "out NULL", ap_scene_lin_create(&lg, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "m NULL",
       ap_body_actuator_partials(NULL, BD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "d NULL",
       ap_body_actuator_partials(BM, NULL, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "d of another model",
       ap_body_actuator_partials(BM, TD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "effect -1",
       ap_body_actuator_partials(BM, BD, -1, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "effect 99",
       ap_body_actuator_partials(BM, BD, 99, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_body_actuator_partials, "gravity, not an actuator",
       ap_body_actuator_partials(BM, BD, 0, &id, &T, NULL, NULL, NULL) == AP_ERR_ARG);
}

static void cases_batch(void) {
  double vals[64];
  const char *const one[1] = {"bodies.sleigh.mass=2"};
  size_t n = strlen(SCENE);
  ap_batch_def bd = ap_batch_def_default();
  CASE(ap_plan_create, "out NULL", ap_plan_create(NULL) == AP_ERR_ARG);
  CASE(ap_plan_free, "NULL", (ap_plan_free(NULL), 1));
  CASE(ap_plan_add_grid, "p NULL",
       ap_plan_add_grid(NULL, "a=1:2:3", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "spec NULL", ap_plan_add_grid(PL, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "spec without '='",
       ap_plan_add_grid(PL, "nonsense", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_grid, "msg NULL, length > 0",
       ap_plan_add_grid(PL, "x", NULL, 100) == AP_ERR_ARG);
  CASE(ap_plan_add_random, "p NULL",
       ap_plan_add_random(NULL, "a=uniform(0,1)", msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_add_random, "spec NULL",
       ap_plan_add_random(PL, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "p NULL", ap_plan_set_samples(NULL, 4, 1) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "samples 0", ap_plan_set_samples(PL, 0, 1) == AP_ERR_ARG);
  CASE(ap_plan_set_samples, "samples -5", ap_plan_set_samples(PL, -5, 1) == AP_ERR_ARG);
  CASE(ap_plan_count, "NULL", ap_plan_count(NULL) == 0);
  CASE(ap_plan_nparams, "NULL", ap_plan_nparams(NULL) == 0);
  CASE(ap_plan_path, "p NULL", ap_plan_path(NULL, 0) == NULL);
  CASE(ap_plan_path, "r -1", ap_plan_path(PL, -1) == NULL);
  CASE(ap_plan_path, "r 99", ap_plan_path(PL, 99) == NULL);
  CASE(ap_plan_value, "p NULL", ap_plan_value(NULL, 0, 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "i -1", ap_plan_value(PL, -1, 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "i = count",
       ap_plan_value(PL, ap_plan_count(PL), 0, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "r 5", ap_plan_value(PL, 0, 5, &E, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_value, "buf too short", ap_plan_value(PL, 0, 0, &E, msg, 3) == AP_ERR_ARG);
  CASE(ap_plan_value, "x, buf NULL (optional)", ap_plan_value(PL, 0, 0, NULL, NULL, 0) == AP_OK);
  CASE(ap_plan_typical, "p NULL", ap_plan_typical(NULL, 0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_typical, "r 5", ap_plan_typical(PL, 5, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_plan_typical, "buf NULL", ap_plan_typical(PL, 0, NULL, 10) == AP_ERR_ARG);
  CASE(ap_batch_def_default, "no arguments", ap_batch_def_default().threads >= 1);
  CASE(ap_batch_create, "def zeroed, not from ap_batch_def_default",
       ap_batch_create(SCENE, n, "b", NULL, 0, &(ap_batch_def){.threads = 1}, &obt, msg,
                       sizeof msg) == AP_ERR_ARG &&
           !obt && not_default_msg(msg, "ap_batch_def", NULL));
  CASE(ap_batch_create, "text NULL",
       ap_batch_create(NULL, 9, "b", NULL, 0, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "out NULL",
       ap_batch_create(SCENE, n, "b", NULL, 0, &bd, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_create, "sets NULL, nsets 1",
       ap_batch_create(SCENE, n, "b", NULL, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "nsets -1",
       ap_batch_create(SCENE, n, "b", one, -1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_create, "sets[0] NULL",
       ap_batch_create(SCENE, n, "b", no_sets, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG &&
           !obt);
  const char *const no_channel[1] = {NULL};
  ap_batch_def bn = bd;
  bn.channels = no_channel, bn.nchannels = 1;
  CASE(ap_batch_create, "def.channels[0] NULL",
       ap_batch_create(SCENE, n, "b", NULL, 0, &bn, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  bn.channels = NULL;
  CASE(ap_batch_create, "def.channels NULL, nchannels 1",
       ap_batch_create(SCENE, n, "b", NULL, 0, &bn, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_plan_id, "b NULL", ap_batch_plan_id(NULL, PL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_plan_id, "p NULL", ap_batch_plan_id(BT, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_plan_id, "id NULL", ap_batch_plan_id(BT, PL, NULL, 17) == AP_ERR_ARG);
  CASE(ap_batch_plan_id, "len 16", ap_batch_plan_id(BT, PL, msg, 16) == AP_ERR_ARG);
  char *txt = (char *)1;
  size_t tlen = 1;
  CASE(ap_scene_read, "path NULL",
       ap_scene_read(NULL, &txt, &tlen, msg, sizeof msg) == AP_ERR_ARG && !txt && !tlen);
  CASE(ap_scene_read, "text NULL",
       ap_scene_read(SCENE_PATH, NULL, &tlen, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_read, "len NULL",
       ap_scene_read(SCENE_PATH, &txt, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_read, "a directory",
       ap_scene_read("/", &txt, &tlen, msg, sizeof msg) == AP_ERR_ARG && !txt);
  CASE(ap_scene_read, "/dev/zero (larger than 16 MiB)",
       ap_scene_read("/dev/zero", &txt, &tlen, msg, sizeof msg) == AP_ERR_ARG && !txt &&
           strstr(msg, "larger than 16 MiB"));
  CASE(ap_scene_locate_failure, "sc NULL",
       ap_scene_locate_failure(NULL, S, 1.0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_locate_failure, "sim NULL",
       ap_scene_locate_failure(SC, NULL, 1.0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_scene_locate_failure, "another scene's simulation, msg NULL",
       ap_scene_locate_failure(SC, S, NAN, NULL, 0) == AP_OK);
  CASE(ap_scene_text_free, "NULL", (ap_scene_text_free(NULL), 1));
  CASE(ap_batch_load, "path NULL",
       ap_batch_load(NULL, NULL, 0, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_load, "sets NULL, nsets 1",
       ap_batch_load(SCENE_PATH, NULL, 1, &bd, &obt, msg, sizeof msg) == AP_ERR_ARG && !obt);
  CASE(ap_batch_load, "out NULL",
       ap_batch_load(SCENE_PATH, NULL, 0, &bd, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_free, "NULL", (ap_batch_free(NULL), 1));
  CASE(ap_batch_ncols, "NULL", ap_batch_ncols(NULL) == 0);
  CASE(ap_batch_col_name, "b NULL", ap_batch_col_name(NULL, 0) == NULL);
  CASE(ap_batch_col_name, "j -1", ap_batch_col_name(BT, -1) == NULL);
  CASE(ap_batch_col_name, "j = ncols", ap_batch_col_name(BT, ap_batch_ncols(BT)) == NULL);
  CASE(ap_batch_check, "b NULL", ap_batch_check(NULL, one, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "sets NULL, nsets 1",
       ap_batch_check(BT, NULL, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "nsets -1", ap_batch_check(BT, one, -1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check, "sets[0] NULL",
       ap_batch_check(BT, no_sets, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check_plan, "b NULL", ap_batch_check_plan(NULL, PL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_check_plan, "p NULL", ap_batch_check_plan(BT, NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_batch_run, "b NULL", ap_batch_run(NULL, 1, 1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "count -1", ap_batch_run(BT, -1, 1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "nper -1", ap_batch_run(BT, 1, -1, one, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "sets NULL", ap_batch_run(BT, 1, 1, NULL, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "values NULL", ap_batch_run(BT, 1, 1, one, NULL, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "status NULL", ap_batch_run(BT, 1, 1, one, vals, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run, "sets[0] NULL", ap_batch_run(BT, 1, 1, no_sets, vals, stat_, msgs) == AP_OK &&
       stat_[0] == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "b NULL",
       ap_batch_run_plan(NULL, PL, 0, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "p NULL",
       ap_batch_run_plan(BT, NULL, 0, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "first -1",
       ap_batch_run_plan(BT, PL, -1, 1, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "past the plan",
       ap_batch_run_plan(BT, PL, 2, 5, vals, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan, "values NULL",
       ap_batch_run_plan(BT, PL, 0, 1, NULL, stat_, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan_events, "b NULL",
       ap_batch_run_plan_events(NULL, PL, 0, 1, vals, stat_, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan_events, "p NULL",
       ap_batch_run_plan_events(BT, NULL, 0, 1, vals, stat_, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_batch_run_plan_events, "status NULL",
       ap_batch_run_plan_events(BT, PL, 0, 1, vals, NULL, NULL, NULL) == AP_ERR_ARG);
  CASE(ap_batch_messages_free, "messages NULL", (ap_batch_messages_free(3, NULL), 1));
  CASE(ap_batch_messages_free, "count -1", (ap_batch_messages_free(-1, msgs), 1));
}

static void cases_lin(void) {
  double tq[4], tw[3], sv[2] = {0.0, 1.0};
  int sel[1] = {0};
  bs_top_initial(tq, tw);
  CASE(ap_lin_def_default, "no arguments", ap_lin_def_default().about == AP_LIN_STEADY);
  CASE(ap_lin_create, "m NULL", ap_lin_create(NULL, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "q NULL", ap_lin_create(TM, NULL, 0.0, NULL, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "t NaN", ap_lin_create(TM, NULL, NAN, tq, tw, &oln) == AP_ERR_ARG && !oln);
  CASE(ap_lin_create, "out NULL", ap_lin_create(TM, NULL, 0.0, tq, tw, NULL) == AP_ERR_ARG);
  CASE(ap_lin_create, "q NaN (a message in the linearizer)",
       (tq[1] = NAN, ap_lin_create(TM, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && oln &&
                         strstr(ap_lin_message(oln), "nan")));
  CASE(ap_lin_create, "v Inf (a message in the linearizer)",
       (tw[0] = INFINITY, ap_lin_create(TM, NULL, 0.0, tq, tw, &oln) == AP_ERR_ARG && oln &&
                              strstr(ap_lin_message(oln), "inf")));
  CASE(ap_lin_create, "def, v NULL (defaults, zero speeds)",
       (ap_lin_create(TM, NULL, 0.0, tq, NULL, &oln), oln != NULL));
  CASE(ap_lin_create, "def zeroed, not from ap_lin_def_default (message in the linearizer)",
       ap_lin_create(TM, &(ap_lin_def){0}, 0.0, tq, NULL, &oln) == AP_ERR_ARG && oln &&
           not_default_msg(ap_lin_message(oln), "ap_lin_def", NULL));
  CASE(ap_lin_free, "NULL", (ap_lin_free(NULL), 1));
  CASE(ap_lin_message, "NULL: a fixed text", ap_lin_message(NULL) && ap_lin_message(NULL)[0]);
  CASE(ap_lin_operating_point, "L NULL", ap_lin_operating_point(NULL, 0.0) == AP_ERR_ARG);
  CASE(ap_lin_operating_point, "s Inf (a message naming the speed)",
       ap_lin_operating_point(LN, INFINITY) == AP_ERR_ARG &&
           strstr(ap_lin_message(LN), "speed parameter is inf"));
  CASE(ap_lin_q, "NULL", ap_lin_q(NULL) == NULL);
  CASE(ap_lin_v, "NULL", ap_lin_v(NULL) == NULL);
  CASE(ap_lin_linearize, "NULL", ap_lin_linearize(NULL) == AP_ERR_ARG);
  CASE(ap_lin_nx, "NULL", ap_lin_nx(NULL) == 0);
  CASE(ap_lin_nu, "NULL", ap_lin_nu(NULL) == 0);
  CASE(ap_lin_state_name, "L NULL", ap_lin_state_name(NULL, 0) == NULL);
  CASE(ap_lin_state_name, "i -1", ap_lin_state_name(LN, -1) == NULL);
  CASE(ap_lin_state_name, "i 999", ap_lin_state_name(LN, 999) == NULL);
  CASE(ap_lin_input_name, "L NULL", ap_lin_input_name(NULL, 0) == NULL);
  CASE(ap_lin_input_name, "j 999", ap_lin_input_name(LN, 999) == NULL);
  CASE(ap_lin_is_cyclic, "L NULL", ap_lin_is_cyclic(NULL, 0) == 0);
  CASE(ap_lin_is_cyclic, "i 999", ap_lin_is_cyclic(LN, 999) == 0);
  CASE(ap_lin_find_state, "L NULL", ap_lin_find_state(NULL, "x") == -1);
  CASE(ap_lin_find_state, "name NULL", ap_lin_find_state(LN, NULL) == -1);
  CASE(ap_lin_A, "NULL", ap_lin_A(NULL) == NULL);
  CASE(ap_lin_A_error, "NULL", ap_lin_A_error(NULL) == NULL);
  CASE(ap_lin_B, "NULL", ap_lin_B(NULL) == NULL);
  CASE(ap_lin_rates, "NULL", ap_lin_rates(NULL) == NULL);
  CASE(ap_lin_method_used, "NULL", ap_lin_method_used(NULL) == AP_LIN_AUTO);
  CASE(ap_lin_fallback, "NULL", ap_lin_fallback(NULL) && !ap_lin_fallback(NULL)[0]);
  CASE(ap_lin_eigen, "L NULL", ap_lin_eigen(NULL, sel, 1, 0) == AP_ERR_ARG);
  CASE(ap_lin_eigen, "not linearized", ap_lin_eigen(LN, sel, 1, 0) == AP_ERR_ARG);
  CASE(ap_lin_get_eigen, "L NULL", ap_lin_get_eigen(NULL, &eg) == AP_ERR_ARG);
  CASE(ap_lin_get_eigen, "out NULL", ap_lin_get_eigen(LN, NULL) == AP_ERR_ARG);
  CASE(ap_lin_set_poll, "L NULL", (ap_lin_set_poll(NULL, NULL, NULL), 1));
  CASE(ap_lin_sweep_run, "fn NULL",
       ap_lin_sweep_run(NULL, NULL, 2, sweep_p, 3, 1e-6, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "n 0",
       ap_lin_sweep_run(eig_fn, NULL, 0, sweep_p, 3, 1e-6, 0.0, &sw, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "p NULL",
       ap_lin_sweep_run(eig_fn, NULL, 2, NULL, 3, 1e-6, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "count 0",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 0, 1e-6, 0.0, &sw, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "ptol NaN",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 3, NAN, 0.0, &sw, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_lin_sweep_run, "out NULL",
       ap_lin_sweep_run(eig_fn, NULL, 2, sweep_p, 3, 1e-6, 0.0, NULL, msg, sizeof msg) ==
           AP_ERR_ARG);
  CASE(ap_lin_sweep_free, "NULL", (ap_lin_sweep_free(NULL), 1));
  CASE(ap_lin_sweep_speed, "L NULL",
       ap_lin_sweep_speed(NULL, sv, 2, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "s NULL",
       ap_lin_sweep_speed(LN, NULL, 2, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "count 0",
       ap_lin_sweep_speed(LN, sv, 0, NULL, 0, 0, 1e-6, &sw) == AP_ERR_ARG);
  CASE(ap_lin_sweep_speed, "out NULL",
       ap_lin_sweep_speed(LN, sv, 2, NULL, 0, 0, 1e-6, NULL) == AP_ERR_ARG);
}

static int api_out(ap_sim *s, double *row, void *user) {
  (void)user;
  row[0] = ap_sim_q(s)[0];
  return AP_OK;
}

static void cases_accuracy(void) {
  ap_sim_def def = ap_sim_def_default(), ref;
  ap_error_report rep;
  ap_pick_report pk;
  double q0[8] = {0, 0, 1, 0, 0, 0, 0, 0}, v0[8] = {0}, tt[1] = {0.1}, e[1] = {1}, sc[1] = {0};
  int fl[8];
  char msg[256];
  CASE(ap_sim_free_coordinates, "s NULL", ap_sim_free_coordinates(NULL, fl) == AP_ERR_ARG);
  CASE(ap_sim_free_coordinates, "out NULL", ap_sim_free_coordinates(S, NULL) == AP_ERR_ARG);
  CASE(ap_sim_set_uncontrolled, "s NULL", ap_sim_set_uncontrolled(NULL, NULL) == AP_ERR_ARG);
  CASE(ap_sim_set_uncontrolled, "flags NULL (all controlled)",
       ap_sim_set_uncontrolled(S, NULL) == AP_OK && !ap_sim_uncontrolled(S, 0));
  CASE(ap_sim_uncontrolled, "s NULL", ap_sim_uncontrolled(NULL, 0) == 0);
  CASE(ap_sim_uncontrolled, "i 999", ap_sim_uncontrolled(S, 999) == 0);
  CASE(ap_error_reference_def, "dopri5 at 1e-8: dop853 at 1e-10",
       (ap_error_reference_def(&def, &ref), ref.rtol == 1e-10 && !strcmp(ref.method, "dop853")));
  CASE(ap_error_fold, "nc 0", (ap_error_fold(0, NULL, NULL, NULL, NULL), 1));
  CASE(ap_error_norm, "relative above 1", (sc[0] = 4, ap_error_norm(1, e, sc) == 0.25));
  CASE(ap_global_error, "out NULL",
       ap_global_error(SM, &def, 0, q0, v0, tt, 1, 1, NULL, NULL, NULL, NULL, NULL, NULL, &rep,
                       msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_global_error, "nt 0",
       ap_global_error(SM, &def, 0, q0, v0, tt, 0, 1, api_out, NULL, NULL, NULL, NULL, NULL,
                       &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_error_against, "rows NULL",
       ap_error_against(SM, &def, 0, q0, v0, tt, 1, 1, api_out, NULL, NULL, NULL, NULL, NULL,
                        NULL, &rep, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_accuracy_pick, "accuracy 0",
       ap_accuracy_pick(SM, &def, 0, q0, v0, tt, 1, 1, api_out, NULL, NULL, 0.0, &pk, msg,
                        sizeof msg) == AP_ERR_ARG);
  CASE(ap_accuracy_pick, "pick NULL",
       ap_accuracy_pick(SM, &def, 0, q0, v0, tt, 1, 1, api_out, NULL, NULL, 1e-6, NULL, msg,
                        sizeof msg) == AP_ERR_ARG);
}

/* Compiled models (compiled.h): no compiler is run by these cases. */
static void cases_compiled(void) {
  ap_compile_mode cm = AP_COMPILE_AUTO;
  CASE(ap_model_compile_native, "NULL model",
       ap_model_compile_native(NULL, AP_COMPILE_AUTO, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_model_compile_native, "mode out of range",
       ap_model_compile_native(BM, (ap_compile_mode)7, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_model_compile_native, "math-level model: interpreted, notice",
       ap_model_compile_native(SM, AP_COMPILE_ALWAYS, msg, sizeof msg) == 0 &&
           strstr(msg, "not a body model") != NULL);
  CASE(ap_model_compile_native, "never, NULL notice",
       ap_model_compile_native(BM, AP_COMPILE_NEVER, NULL, 0) == 0);
  CASE(ap_model_is_compiled, "NULL", ap_model_is_compiled(NULL) == 0);
  CASE(ap_model_is_compiled, "math-level model", ap_model_is_compiled(SM) == 0);
  CASE(ap_compile_mode_parse, "NULL name", ap_compile_mode_parse(NULL, &cm) == AP_ERR_ARG);
  CASE(ap_compile_mode_parse, "NULL mode", ap_compile_mode_parse("auto", NULL) == AP_ERR_ARG);
  CASE(ap_compile_mode_parse, "unknown", ap_compile_mode_parse("sometimes", &cm) == AP_ERR_ARG);
  CASE(ap_scene_compile_notice, "NULL", strcmp(ap_scene_compile_notice(NULL), "") == 0);
}

void api_cases_high(void) {
  cases_compiled();
  cases_body_queries();
  cases_scene();
  cases_scene_runs();
  cases_batch();
  cases_lin();
  cases_accuracy();
}
