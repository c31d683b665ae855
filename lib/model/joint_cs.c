/* The complex-step build of joint.c (model/model.h): ap_joint_column_cs,
 * ap_joint_transform_cs, ap_joint_fill_N_cs. */
#define AP_SC_COMPLEX 1
#include "model/joint.c"
