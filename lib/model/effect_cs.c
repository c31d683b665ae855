/* The complex-step build of effect.c (model/model.h): ap_eff_forces_cs. */
#define AP_SC_COMPLEX 1
#include "model/effect.c"
