/* The complex-step build of nullspace.c (linalg/scalar.h): ap_la_pivot_select_cs,
 * ap_la_partition_basis_cs, ap_la_partition_particular_cs, ap_la_orth_basis_cs,
 * ap_la_orth_particular_cs, ap_la_lstsq_At_cs on double _Complex, native kernels only. */
#define AP_SC_COMPLEX 1
#include "linalg/nullspace.c"
