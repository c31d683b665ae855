/* The complex-step build of kinematics.c (model/model.h): positions, Jacobians, velocities,
 * bias accelerations, g and h on double _Complex (ap_kin_*_cs). */
#define AP_SC_COMPLEX 1
#include "model/kinematics.c"
