/* Motor set-points as inputs (docs/control.md "Inputs"): a motor of a body model whose
 * set-point a simulation or the linearizer treats as an input, named "MOTOR.setpoint".
 * The override itself is the data's ap_scratch.setpoint_in (core/core.h), which ap_act_force
 * reads in place of the motor's own value (double build only; actuator.c). */
#ifndef AP_MODEL_SETPOINT_H
#define AP_MODEL_SETPOINT_H

#include "appell/system.h"

/* The effect index of the motor named by "MOTOR.setpoint" when that motor holds a constant
 * set-point (a number, not a function of time or state); else -1 (also for m NULL or not a
 * body model). */
int ap_act_find_setpoint(const ap_model *m, const char *name);
/* Number of effects of a body model (0 otherwise); the constant set-point of effect e. */
int ap_act_effect_count(const ap_model *m);
double ap_act_setpoint_value(const ap_model *m, int e);
/* d(generalized force)/d(set-point) of motor e at the data's state (d->t, d->q, d->v): g =
 * kd (rate motor) or kp (angle motor), 0 while its limit saturates it; *col the speed it acts
 * on. AP_ERR_ARG for an effect that is not a motor. */
int ap_act_setpoint_gain(const ap_model *m, ap_data *d, int e, int *col, double *g);

#endif
