/* Test helper: this program's malloc, calloc, realloc and free wrap glibc's, to count heap
 * allocations (n_alloc: every call of malloc, calloc or realloc; n_live: blocks allocated and
 * not yet freed, for leak checks) and to make one of them fail (ap_alloc_fail_at(i): the i-th
 * allocation from now returns NULL, i = 0 the next one; -1 switches injection off).
 * Include it in one source file of a test program: it defines malloc and friends.
 * AddressSanitizer owns malloc itself: under it AP_COUNT_ALLOC is 0 and nothing is counted
 * or injected (the plain build of scripts/test runs these checks). */
#ifndef AP_TEST_ALLOC_H
#define AP_TEST_ALLOC_H

#include <stddef.h>

#if defined(__GNUC__)
#define AP_ALLOC_UNUSED __attribute__((unused))
#else
#define AP_ALLOC_UNUSED
#endif

static long n_alloc AP_ALLOC_UNUSED = 0, n_live AP_ALLOC_UNUSED = 0;
static long ap_alloc_countdown AP_ALLOC_UNUSED = -1;   /* allocations before the failing one */
static int ap_alloc_failed AP_ALLOC_UNUSED = 0;        /* an allocation was made to fail */

#if defined(__SANITIZE_ADDRESS__)
#define AP_COUNT_ALLOC 0
#else
#define AP_COUNT_ALLOC 1
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);

static int ap_alloc_inject(void) {
  if (ap_alloc_countdown < 0) return 0;
  if (ap_alloc_countdown-- > 0) return 0;
  ap_alloc_failed = 1;
  return 1;
}

void *malloc(size_t size) {
  if (ap_alloc_inject()) return NULL;
  void *p = __libc_malloc(size);
  n_alloc++, n_live += p != NULL;
  return p;
}
void *calloc(size_t a, size_t b) {
  if (ap_alloc_inject()) return NULL;
  void *p = __libc_calloc(a, b);
  n_alloc++, n_live += p != NULL;
  return p;
}
void *realloc(void *p, size_t size) {
  if (ap_alloc_inject()) return NULL;
  void *q = __libc_realloc(p, size);
  n_alloc++, n_live += !p && q;
  return q;
}
void free(void *p) {
  n_live -= p != NULL;
  __libc_free(p);
}
#endif

/* Make the i-th allocation from now fail (i >= 0), or stop failing (i < 0). */
static inline void ap_alloc_fail_at(long i) {
  ap_alloc_countdown = i;
  ap_alloc_failed = 0;
}

#endif
