/* Size limits of the dense path: LAPACK (LP64: 32-bit lapack_int, as Debian's LAPACKE and
 * OpenBLAS) indexes a matrix with int products of its dimensions, so every dense array the data
 * of a model holds must have at most INT_MAX entries. */
#ifndef AP_CORE_SIZES_H
#define AP_CORE_SIZES_H

#include <stddef.h>

/* AP_OK when the dense arrays of a model with n coordinates, k speeds and b constraint rows
 * (and, with christoffel, the n blocks of k x k of dg/dq) each have at most INT_MAX entries:
 * k x k (g, B, G), n x k (N), b x (k + 1) (A with its free column), n k^2 (dg). Otherwise
 * AP_ERR_ARG and a message naming the model, the array and the numbers. */
int ap_core_check_sizes(const char *model, int n, int k, int b, int christoffel, char *msg,
                        size_t len);

#endif
