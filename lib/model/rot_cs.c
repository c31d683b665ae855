/* The complex-step build of rot.c (model/model.h): m3_mul_cs, ap_rot_axis_angle_cs,
 * ap_quat_normalized_matrix_cs, ap_quat_N_cs and the products with a double operand. */
#define AP_SC_COMPLEX 1
#include "model/rot.c"
