/* The complex-step build of hooks.c (model/model.h): ap_bm_position_cs, ap_bm_velocity_cs,
 * ap_bm_phi_cs. */
#define AP_SC_COMPLEX 1
#include "model/hooks.c"
