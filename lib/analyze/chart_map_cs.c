/* The complex-step build of chart_map.c (linalg/scalar.h): ap_an_chart_apply_cs and the other
 * chart maps on double _Complex. */
#define AP_SC_COMPLEX 1
#include "analyze/chart_map.c"
