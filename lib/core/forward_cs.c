/* The complex-step build of forward.c (linalg/scalar.h): ap_fwd_position_cs,
 * ap_fwd_velocity_cs, ap_fwd_acceleration_cs, ap_forward_cs on the mirror ap_data_cs
 * (core/core.h), for exact derivatives of the Appell solve. */
#define AP_SC_COMPLEX 1
#include "core/forward.c"
