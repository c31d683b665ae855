/* Layout tables of one-allocation blocks (the data's scalars and ints, the body model's
 * scratch): a list of named arrays with their element counts, from which each array's offset
 * and the block's size follow, so no size formula is written twice. With guards (meson
 * -Dguards=true, AP_GUARDS) every array is followed by AP_ARENA_GUARD elements of a NaN pattern
 * that the pipeline checks after each stage: a write past an array inside the block is caught
 * and named (docs/architecture.md "Layout tables and guard words"). */
#ifndef AP_CORE_ARENA_H
#define AP_CORE_ARENA_H

#include <stddef.h>

#ifndef AP_GUARDS
#define AP_GUARDS 0
#endif

#define AP_ARENA_MAX 48      /* arrays per block */
#define AP_ARENA_GUARD 16    /* guard elements after each array in the guard build */

typedef struct ap_arena_entry {
  const char *name;          /* the field it is carved into, e.g. "d->N" */
  size_t count;              /* elements */
  size_t offset;             /* elements from the start of the block */
} ap_arena_entry;

typedef struct ap_arena {
  const char *block;         /* the block's name in messages, e.g. "data doubles" */
  size_t elsize;             /* bytes per element; a multiple or divisor of 8 */
  size_t guard;              /* guard elements after each array (0 or AP_ARENA_GUARD) */
  int n;                     /* arrays added (more than AP_ARENA_MAX: the check fails) */
  size_t total;              /* elements of the block: sum of counts and guards */
  ap_arena_entry e[AP_ARENA_MAX];
} ap_arena;

/* An empty table with guard elements after each array (AP_ARENA_GUARDS: AP_ARENA_GUARD in the
 * guard build, else 0). */
#define AP_ARENA_GUARDS (AP_GUARDS ? (size_t)AP_ARENA_GUARD : 0)
void ap_arena_init(ap_arena *a, const char *block, size_t elsize, size_t guard);
/* Append an array of count elements at the end of the block; its index in the table. */
int ap_arena_add(ap_arena *a, const char *name, size_t count);
/* Offsets ascending, each array with its guard inside the block, total = sum of the counts and
 * guards, at most AP_ARENA_MAX arrays. 0, or -1 with a message naming the array. */
int ap_arena_check(const ap_arena *a, char *msg, size_t len);
/* Write the guard pattern after every array of the block at base. */
void ap_arena_fill_guards(const ap_arena *a, void *base);
/* The first array whose guard is not intact (and in *word the guard element hit), or -1. */
int ap_arena_guard_hit(const ap_arena *a, const void *base, size_t *word);
/* ap_arena_guard_hit as a message naming the block, the array, its extent and the stage: 0
 * when every guard is intact, else -1. */
int ap_arena_guard_msg(const ap_arena *a, const void *base, const char *stage, char *msg,
                       size_t len);

#endif
