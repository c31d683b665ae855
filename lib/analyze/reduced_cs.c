/* The complex-step build of reduced.c (linalg/scalar.h): ap_an_rates_cs, the reduced equations
 * on complex-step states with the model's complex-step build, for exact Jacobian columns. */
#define AP_SC_COMPLEX 1
#include "analyze/reduced.c"
