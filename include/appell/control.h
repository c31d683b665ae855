/* Appell: inputs and controllers in the loop (docs/control.md).
 *
 * An input is a generalized force on one model speed, named by the speed (a revolute joint's
 * "steer.angle_dot": a torque about its axis, N m; a prescribed joint's rate: a force, N; a
 * free body's "frame.wx": a torque about the world x axis): exactly the columns of the
 * linearizer's input matrix B (ap_lin_def.inputs, docs/linearize.md), so that a gain K
 * computed from the linearization applies to the same inputs here. The scene's `inputs:`
 * section declares them (ap_scene_add_inputs). An input may also be a motor's set-point, named
 * "MOTOR.setpoint" (a motor effect of a body model whose set-point is a constant, rad/s, rad or
 * m): it replaces the motor's set-point, starting at it, and the motor's law makes the torque.
 *
 * Values are held constant between changes (zero-order hold). The right-hand side jumps
 * where a value changes, so the stepper is restarted there (at the current state, q and v put
 * back on the constraints to round-off, the step size kept): a change costs a restart.
 *
 * A controller is a function called every `period` seconds of simulated time, at
 * t_c = t_set + j period (t_set the time of ap_sim_set_controller), first at t_set: the
 * stepper stops exactly at each t_c, the function reads the state there (q, v; ap_sim_data,
 * ap_sim_time, ap_sim_q and ap_sim_v of the simulation describe it too) and writes the new
 * input values, held until the next call. It returns 0 to go on, non-zero to stop the advance
 * with AP_ERR_CALLBACK. An input value that is not finite stops it with AP_ERR_NAN; the
 * message names the input and the time. */
#ifndef APPELL_CONTROL_H
#define APPELL_CONTROL_H

#include "appell/export.h"
#include "appell/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Declare the inputs: names is a NULL-terminated list of model speed names (as
 * ap_model_speed_name gives them; at most one input per speed) or MOTOR.setpoint names. The
 * values start at 0 (a set-point: at the motor's own). A new
 * declaration replaces the old one (and removes a controller). AP_ERR_ARG for a name that is
 * not a speed (the message has the closest one) or a repeated name; s NULL: AP_ERR_ARG. */
AP_API int ap_sim_declare_inputs(ap_sim *s, const char *const *names);
/* Inputs declared (0 for s NULL); name of input j (NULL when out of range); index of the
 * input called name (-1 when none). */
AP_API int ap_sim_input_count(const ap_sim *s);
AP_API const char *ap_sim_input_name(const ap_sim *s, int j);
AP_API int ap_sim_find_input(const ap_sim *s, const char *name);
/* The values now (input_count entries; NULL when there are none or s is NULL). */
AP_API const double *ap_sim_inputs(const ap_sim *s);
/* Set one input by name, or all of them (u: input_count values), from the current time on.
 * AP_ERR_ARG for an unknown name (the message has the closest input) or a value that is not
 * finite (the message names the input). */
AP_API int ap_sim_set_input(ap_sim *s, const char *name, double value);
AP_API int ap_sim_set_inputs(ap_sim *s, const double *u);

/* The controller: u (input_count entries) holds the values in force and receives the new
 * ones. */
typedef int (*ap_sim_controller_fn)(double t, const double *q, const double *v, double *u,
                                    void *user);
/* Call fn every period seconds (finite, > 0) from the current time, the first time at the
 * next ap_sim_advance. fn NULL removes the controller (the inputs keep their values).
 * AP_ERR_ARG without declared inputs or for a bad period. */
AP_API int ap_sim_set_controller(ap_sim *s, ap_sim_controller_fn fn, double period,
                                 void *user);

#ifdef __cplusplus
}
#endif
#endif
