/* Appell batch layer (internal): the prepared scene shared by the workers, and one run.
 *
 *   plan.c       sweep plans: grids and random samples -> the overrides of run i
 *   batch.c      ap_batch: the scene text, the overrides, the result columns; checks
 *   batch_run.c  one run: load, initial state, simulate over the output times, summarize
 *   pool.c       the thread pool: workers take run indices in order; progress; cancel
 *   identity.c   a sweep's identity: a hash of the scene, the overrides and the plan
 *
 * Invariant: after ap_batch_create an ap_batch is only read, so any number of workers share
 * it; everything a run writes (scene, model, data, simulation, row) is its own. */
#ifndef AP_BATCH_INT_H
#define AP_BATCH_INT_H

#include <stdatomic.h>

#include "appell/batch.h"
#include "appell/scene.h"

#define AP_BAT_FIXED_COLS 6   /* t, steps, rhs_evals, err_fails, max_residual, energy_drift */

struct ap_batch {
  char *text;              /* the scene (len bytes) and its name in messages */
  size_t len;
  char *name;
  char **sets;             /* the batch's own overrides (nsets), applied before a run's */
  int nsets;
  ap_batch_def def;        /* channels and times point to the copies below */
  char **channels;         /* (nchannels) */
  double *times;           /* (ntimes), as given */
  int *order;              /* (ntimes) indices of times in increasing order */
  int n, k;                /* coordinates and speeds of the scene as loaded here */
  char **cols;             /* (ncols) column names */
  int ncols;
};

/* One run with the overrides vsets (nv) after the batch's own: row (ncols values, NaN where
 * nothing was reached) and the status (AP_STOPPED when a stop event of the scene ended it);
 * msg gets the failure's message, the stop event or the run's warning, and ev (may be NULL)
 * the run's events as "NAME@T;NAME@T" (the last AP_BAT_MAX_EVENTS of them, "" for none).
 * The simulation stops (AP_ERR_INTERRUPTED) at its next internal step once *stop is non-zero
 * (stop may be NULL). */
#define AP_BAT_MAX_EVENTS 64
int ap_bat_run_one(const ap_batch *b, const char *const *vsets, int nv, double *row, char *msg,
                   size_t msg_len, char *ev, size_t ev_len, const atomic_int *stop);

/* Load the batch's scene with its overrides and vsets (nv). */
int ap_bat_load(const ap_batch *b, const char *const *vsets, int nv, ap_scene **out, char *msg,
                size_t msg_len);

/* Where the overrides of run i come from: explicit lists or a plan. */
typedef struct ap_bat_source {
  const char *const *sets;  /* explicit: run i uses sets[i * nper ...] */
  int nper;
  const ap_plan *plan;      /* or the plan's run first + i */
  long first;
} ap_bat_source;

/* FNV-1a (64 bits) of n bytes, continuing from h (start: AP_BAT_HASH0). */
#define AP_BAT_HASH0 0xcbf29ce484222325ULL
uint64_t ap_bat_hash(uint64_t h, const void *data, size_t n);
/* The plan's part of a sweep's identity (plan.c). */
uint64_t ap_bat_plan_hash(const ap_plan *p, uint64_t h);

int ap_bat_pool(ap_batch *b, const ap_bat_source *src, long count, double *values, int *status,
                char **messages, char **events);

#endif
