/* The complex-step build of body_qty.c (model/model.h): ap_bq_value_cs. */
#define AP_SC_COMPLEX 1
#include "model/body_qty.c"
