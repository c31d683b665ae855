/* Layout tables (core/arena.h): offsets from counts, the checks of a layout, and the guard
 * words between arrays. The guard pattern is the 8-byte quiet NaN 0x7FFA55A5DEADBEEF repeated:
 * no stage writes a NaN with that payload (a NaN from a callback is refused before it is
 * stored), so any change of a guard is a write past the array before it. */
#include "core/arena.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

static const uint64_t PATTERN = 0x7FFA55A5DEADBEEFull;

void ap_arena_init(ap_arena *a, const char *block, size_t elsize, size_t guard) {
  memset(a, 0, sizeof *a);
  a->block = block;
  a->elsize = elsize;
  a->guard = guard;
}

int ap_arena_add(ap_arena *a, const char *name, size_t count) {
  int i = a->n++;
  if (i < AP_ARENA_MAX) a->e[i] = (ap_arena_entry){name, count, a->total};
  a->total += count + a->guard;
  return i;
}

int ap_arena_check(const ap_arena *a, char *msg, size_t len) {
  if (a->n > AP_ARENA_MAX) {
    snprintf(msg, len, "internal error: %s: %d arrays, more than the table's %d", a->block,
             a->n, AP_ARENA_MAX);
    return -1;
  }
  if ((a->guard * a->elsize) % 8 != 0) {
    snprintf(msg, len, "internal error: %s: guards of %zu elements of %zu bytes are not whole "
             "8-byte words", a->block, a->guard, a->elsize);
    return -1;
  }
  size_t sum = 0, end = 0;
  for (int i = 0; i < a->n; i++) {
    const ap_arena_entry *e = &a->e[i];
    sum += e->count + a->guard;
    if (e->offset < end || e->offset + e->count + a->guard > a->total) {
      snprintf(msg, len, "internal error: %s: array '%s' (%zu elements at offset %zu) %s",
               a->block, e->name, e->count, e->offset,
               e->offset < end ? "overlaps the array before it" : "ends past the block");
      return -1;
    }
    end = e->offset + e->count + a->guard;
  }
  if (sum != a->total) {
    snprintf(msg, len, "internal error: %s: %zu elements, but the arrays and guards sum to %zu",
             a->block, a->total, sum);
    return -1;
  }
  return 0;
}

void ap_arena_fill_guards(const ap_arena *a, void *base) {
  if (!a->guard || !base) return;
  for (int i = 0; i < a->n && i < AP_ARENA_MAX; i++) {
    unsigned char *g = (unsigned char *)base + (a->e[i].offset + a->e[i].count) * a->elsize;
    for (size_t b = 0; b < a->guard * a->elsize; b += sizeof PATTERN)
      memcpy(g + b, &PATTERN, sizeof PATTERN);
  }
}

int ap_arena_guard_hit(const ap_arena *a, const void *base, size_t *word) {
  if (!a->guard || !base) return -1;
  for (int i = 0; i < a->n && i < AP_ARENA_MAX; i++) {
    const unsigned char *g =
        (const unsigned char *)base + (a->e[i].offset + a->e[i].count) * a->elsize;
    for (size_t b = 0; b < a->guard * a->elsize; b += sizeof PATTERN)
      if (memcmp(g + b, &PATTERN, sizeof PATTERN) != 0) {
        if (word) *word = b / a->elsize;
        return i;
      }
  }
  return -1;
}

int ap_arena_guard_msg(const ap_arena *a, const void *base, const char *stage, char *msg,
                       size_t len) {
  size_t w = 0;
  int i = ap_arena_guard_hit(a, base, &w);
  if (i < 0) return 0;
  const ap_arena_entry *e = &a->e[i];
  snprintf(msg, len, "internal error: %s: a write past the end of array '%s' (%zu elements at "
           "offset %zu) changed its guard (element %zu after it), found after stage '%s'",
           a->block, e->name, e->count, e->offset, w, stage);
  return -1;
}
