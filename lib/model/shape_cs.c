/* The complex-step build of shape.c (model/model.h): ap_shape_support_cs. */
#define AP_SC_COMPLEX 1
#include "model/shape.c"
