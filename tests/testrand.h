/* The tests' random numbers: Vigna's xorshift64* (shifts 12, 25, 27, multiplier
 * 2685821657736338717), the 53 high bits of each output as a double. The state is the caller's
 * (any non-zero seed), so each test keeps its own fixed seed and sequence, and a test that
 * needs the same matrices again sets its state back. Written once for every test. */
#ifndef AP_TESTS_TESTRAND_H
#define AP_TESTS_TESTRAND_H

#include <stdint.h>

/* Advances *state; uniform in [0, 1) with 53 random bits. */
static inline double ap_test_urand(uint64_t *state) {
  uint64_t x = *state;
  x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
  *state = x;
  return (double)((x * 2685821657736338717ull) >> 11) * 0x1.0p-53;
}

/* Uniform in [-1, 1): 2 ap_test_urand - 1 (exact in binary floating point). */
static inline double ap_test_srand(uint64_t *state) { return 2.0 * ap_test_urand(state) - 1.0; }

#endif
