/* The complex-step build of constraint.c (model/model.h): rows, gamma, loop rows and ground
 * motion on double _Complex (ap_con_*_cs). */
#define AP_SC_COMPLEX 1
#include "model/constraint.c"
