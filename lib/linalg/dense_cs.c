/* The complex-step build of dense.c (linalg/scalar.h): ap_la_chol_cs, ap_la_chol_solve_cs,
 * ap_la_congruence_cs, ap_la_gemv_cs, ap_la_gemv_t_cs on double _Complex, native kernels only. */
#define AP_SC_COMPLEX 1
#include "linalg/dense.c"
