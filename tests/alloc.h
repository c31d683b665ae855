/* Test helper: this program's malloc, calloc, realloc and free wrap the next definition (glibc's,
 * or AddressSanitizer's in the sanitizer build, found with dlsym(RTLD_NEXT)), to count heap
 * allocations (n_alloc: every call of malloc, calloc or realloc; n_live: blocks allocated and
 * not yet freed, for leak checks) and to make one of them fail (ap_alloc_fail_at(i): the i-th
 * allocation from now returns NULL with errno ENOMEM, i = 0 the next one; -1 switches
 * injection off). ap_alloc_on_fail, when set, is called at the failing call (tests/test_alloc.c
 * prints its stack there). Every allocation counts, whoever makes it: Appell, libyaml,
 * SUNDIALS, glibc (strdup, ...); ap_alloc_largest keeps the largest size asked for (bytes;
 * reset it to 0 to measure a phase); under AddressSanitizer its own strdup and the like allocate
 * without calling malloc and are not counted.
 * Include it in one source file of a test program: it defines malloc and friends. Link with
 * -ldl where dlsym is not in libc. */
#ifndef AP_TEST_ALLOC_H
#define AP_TEST_ALLOC_H

#ifndef _GNU_SOURCE
#define _GNU_SOURCE   /* RTLD_NEXT */
#endif
#include <dlfcn.h>
#include <errno.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifndef RTLD_NEXT
#define RTLD_NEXT ((void *)-1l)   /* glibc's value; hidden when _GNU_SOURCE came too late */
#endif

#if defined(__GNUC__)
#define AP_ALLOC_UNUSED __attribute__((unused))
#else
#define AP_ALLOC_UNUSED
#endif

/* Counting and injection work in every build. */
#define AP_COUNT_ALLOC 1

static long n_alloc AP_ALLOC_UNUSED = 0, n_live AP_ALLOC_UNUSED = 0;
static long ap_alloc_countdown AP_ALLOC_UNUSED = -1;   /* allocations before the failing one */
static int ap_alloc_failed AP_ALLOC_UNUSED = 0;        /* an allocation was made to fail */
static size_t ap_alloc_largest AP_ALLOC_UNUSED = 0;    /* the largest size asked for */
static void (*ap_alloc_on_fail)(void) AP_ALLOC_UNUSED = NULL;

static void *(*ap_next_malloc)(size_t);
static void *(*ap_next_calloc)(size_t, size_t);
static void *(*ap_next_realloc)(void *, size_t);
static void (*ap_next_free)(void *);

/* dlsym may allocate before the pointers are known: it is served from this buffer, whose
 * blocks are never freed. */
static _Alignas(16) unsigned char ap_alloc_boot[1 << 14];
static size_t ap_alloc_boot_used = 0;
static int ap_alloc_resolving = 0;

static void *ap_alloc_boot_block(size_t n) {
  n = (n + 15) & ~(size_t)15;
  if (ap_alloc_boot_used + n > sizeof ap_alloc_boot) return NULL;
  void *p = ap_alloc_boot + ap_alloc_boot_used;
  ap_alloc_boot_used += n;
  return memset(p, 0, n);
}

static int ap_alloc_in_boot(const void *p) {
  return (const unsigned char *)p >= ap_alloc_boot &&
         (const unsigned char *)p < ap_alloc_boot + sizeof ap_alloc_boot;
}

static void ap_alloc_resolve(void) {
  if (ap_next_malloc || ap_alloc_resolving) return;
  ap_alloc_resolving = 1;
  ap_next_calloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "calloc");
  ap_next_realloc = (void *(*)(void *, size_t))dlsym(RTLD_NEXT, "realloc");
  ap_next_free = (void (*)(void *))dlsym(RTLD_NEXT, "free");
  ap_next_malloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "malloc");
  ap_alloc_resolving = 0;
}

static int ap_alloc_inject(void) {
  if (ap_alloc_countdown < 0) return 0;
  if (ap_alloc_countdown-- > 0) return 0;
  ap_alloc_failed = 1;
  if (ap_alloc_on_fail) ap_alloc_on_fail();
  errno = ENOMEM;
  return 1;
}

void *malloc(size_t size) {
  ap_alloc_resolve();
  if (!ap_next_malloc) return ap_alloc_boot_block(size);
  if (size > ap_alloc_largest) ap_alloc_largest = size;
  if (ap_alloc_inject()) return NULL;
  void *p = ap_next_malloc(size);
  n_alloc++, n_live += p != NULL;
  return p;
}
void *calloc(size_t a, size_t b) {
  ap_alloc_resolve();
  if (!ap_next_calloc) return b && a > SIZE_MAX / b ? NULL : ap_alloc_boot_block(a * b);
  if (b && a <= SIZE_MAX / b && a * b > ap_alloc_largest) ap_alloc_largest = a * b;
  if (ap_alloc_inject()) return NULL;
  void *p = ap_next_calloc(a, b);
  n_alloc++, n_live += p != NULL;
  return p;
}
void *realloc(void *p, size_t size) {
  ap_alloc_resolve();
  if (!ap_next_realloc || ap_alloc_in_boot(p)) {   /* only while resolving: copy, keep p */
    void *q = ap_alloc_boot_block(size);
    size_t left = p ? (size_t)(ap_alloc_boot + sizeof ap_alloc_boot - (unsigned char *)p) : 0;
    if (q && p) memmove(q, p, size < left ? size : left);
    return q;
  }
  if (size > ap_alloc_largest) ap_alloc_largest = size;
  if (ap_alloc_inject()) return NULL;
  void *q = ap_next_realloc(p, size);
  n_alloc++, n_live += !p && q;
  return q;
}
void free(void *p) {
  if (!p || ap_alloc_in_boot(p)) return;
  ap_alloc_resolve();
  n_live--;
  if (ap_next_free) ap_next_free(p);
}

/* Make the i-th allocation from now fail (i >= 0), or stop failing (i < 0). */
static inline void ap_alloc_fail_at(long i) {
  ap_alloc_countdown = i;
  ap_alloc_failed = 0;
}

#endif
