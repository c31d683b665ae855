/* Appell test assertions: explicit tolerances, a count of failures, a closing line.
 * Each test program includes this, calls AP_CHECK* and returns ap_check_finish(). */
#ifndef AP_TEST_CHECK_H
#define AP_TEST_CHECK_H

#include <math.h>
#include <stdio.h>

/* One pair of counters per program: every file that includes this (the test and its shared
 * helpers, fdcheck.c, linalg_problems.c) counts into them, so a helper's failed check fails
 * the program. Weak definitions: the linker keeps one of the identical copies. */
extern int ap_check_failed, ap_check_passed;
__attribute__((weak)) int ap_check_failed = 0;
__attribute__((weak)) int ap_check_passed = 0;

#define AP_CHECK(cond)                                                                   \
  do {                                                                                   \
    if (cond) {                                                                          \
      ap_check_passed++;                                                                 \
    } else {                                                                             \
      ap_check_failed++;                                                                 \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);           \
    }                                                                                    \
  } while (0)

/* |x - ref| <= tol, and both finite. */
#define AP_CHECK_NEAR(x, ref, tol)                                                       \
  do {                                                                                   \
    double ap_x_ = (x), ap_r_ = (ref), ap_t_ = (tol);                                    \
    if (isfinite(ap_x_) && isfinite(ap_r_) && fabs(ap_x_ - ap_r_) <= ap_t_) {            \
      ap_check_passed++;                                                                 \
    } else {                                                                             \
      ap_check_failed++;                                                                 \
      fprintf(stderr, "%s:%d: %s = %.17g, expected %s = %.17g within %.3g (off by %.3g)\n", \
              __FILE__, __LINE__, #x, ap_x_, #ref, ap_r_, ap_t_, fabs(ap_x_ - ap_r_));   \
    }                                                                                    \
  } while (0)

/* x <= bound, and x finite. */
#define AP_CHECK_LE(x, bound)                                                            \
  do {                                                                                   \
    double ap_x_ = (x), ap_b_ = (bound);                                                 \
    if (isfinite(ap_x_) && ap_x_ <= ap_b_) {                                             \
      ap_check_passed++;                                                                 \
    } else {                                                                             \
      ap_check_failed++;                                                                 \
      fprintf(stderr, "%s:%d: %s = %.6g, expected <= %s = %.6g\n", __FILE__, __LINE__,   \
              #x, ap_x_, #bound, ap_b_);                                                 \
    }                                                                                    \
  } while (0)

#define AP_CHECK_EQ_INT(x, ref)                                                          \
  do {                                                                                   \
    long ap_x_ = (long)(x), ap_r_ = (long)(ref);                                         \
    if (ap_x_ == ap_r_) {                                                                \
      ap_check_passed++;                                                                 \
    } else {                                                                             \
      ap_check_failed++;                                                                 \
      fprintf(stderr, "%s:%d: %s = %ld, expected %ld\n", __FILE__, __LINE__, #x, ap_x_,  \
              ap_r_);                                                                    \
    }                                                                                    \
  } while (0)

static inline int ap_check_finish(const char *name) {
  printf("%s: %d checks passed, %d failed\n", name, ap_check_passed, ap_check_failed);
  return ap_check_failed == 0 ? 0 : 1;
}

#endif
