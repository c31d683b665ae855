/* The complex-step build of data.c (linalg/scalar.h): ap_data_create_cs, ap_data_free_cs and
 * ap_core_msg_cs on the mirror ap_data_cs (core/core.h). */
#define AP_SC_COMPLEX 1
#include "core/data.c"
