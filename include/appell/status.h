/* Appell: status codes and messages.
 *
 * Every public function that can fail returns an int status: AP_OK (0) on success, a negative
 * AP_ERR_* code on failure. User callbacks follow the SUNDIALS rule: 0 = ok, > 0 = recoverable
 * (the integrator retries with a smaller step), < 0 = stop. The object that failed (model,
 * data, simulation) keeps a detailed message naming what failed, where, and the number. */
#ifndef APPELL_STATUS_H
#define APPELL_STATUS_H

#include "appell/export.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
  AP_OK = 0,
  AP_RECOVERABLE = 1,         /* a stage asks for a smaller step (positive on purpose) */
  AP_STOPPED = 2,             /* ap_sim_advance: a stop event fired (appell/event.h); the run
                                 is at the event time, not failed (positive on purpose) */
  AP_ERR_ARG = -1,            /* invalid argument or definition */
  AP_ERR_NOMEM = -2,          /* allocation failed */
  AP_ERR_CALLBACK = -3,       /* a user callback returned < 0 */
  AP_ERR_NAN = -4,            /* a callback or a step produced NaN, Inf or a value past 1e150 */
  AP_ERR_SINGULAR = -5,       /* singular or indefinite matrix (G, R11, g) */
  AP_ERR_INCONSISTENT = -6,   /* constraint rows that contradict each other */
  AP_ERR_RANK = -7,           /* the constraints leave no free speed, or the rank changed */
  AP_ERR_SOLVER = -8,         /* the integrator failed (too many steps, step too small, ...) */
  AP_ERR_UNSUPPORTED = -9,    /* method or option not available for this model */
  AP_ERR_INTERNAL = -10,      /* a bug in Appell: please report */
  AP_ERR_INTERRUPTED = -11,   /* the caller's poll function asked to stop (ap_sim_set_poll) */
  AP_ERR_IO = -12             /* a file could not be created, written, closed or renamed */
};

/* A short, static text for a status code ("unknown status" for any other int). */
AP_API const char *ap_strerror(int status);

/* The closest of words[0 .. count-1] (count < 0: up to a NULL entry) to a misspelt word, for
 * "did you mean" messages: optimal string alignment distance, case-insensitive, within 1 edit
 * for words of up to 4 letters, 2 up to 8, else 3; NULL when none is that close or an argument
 * is NULL. */
AP_API const char *ap_suggest(const char *word, const char *const *words, int count);

#ifdef __cplusplus
}
#endif
#endif
