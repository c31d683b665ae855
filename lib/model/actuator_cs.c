/* The complex-step build of actuator.c (model/model.h): ap_act_force_cs, with a state
 * function's exact partials carried into the imaginary parts. */
#define AP_SC_COMPLEX 1
#include "model/actuator.c"
