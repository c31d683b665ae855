/* Appell: many runs of one scene (parameter sweeps, Monte Carlo, tolerance studies).
 *
 * A plan (ap_plan) says which scene values vary and how: grids (equally spaced values or a
 * list) and random samples (normal, uniform) drawn reproducibly from a seed. Run i of a plan is
 * a list of overrides in the --set path syntax ("initial.disk.tilt=1.2217304763960306").
 *
 * A batch (ap_batch) is one scene prepared for many runs: its text is read once, and each run
 * loads it with the batch's own overrides followed by the run's, simulates it from its initial
 * state to t_end exactly as `appell run` does (same output times, same stops), and leaves one
 * row of summaries: where it ended (q and v), the output channels asked for at the times asked
 * for, the energy drift over the output times, the largest constraint residual, step counts,
 * and a status with its message. A run that fails is a row with its status and message; the
 * other runs go on. Runs are spread over a pool of threads; each run owns its scene, model,
 * data and simulation, and the rows do not depend on the number of threads, on the order in
 * which runs finish, or on how a plan is split into slices.
 *
 * docs/sweeps.md describes `appell sweep` and the Python and Dask front ends built on this.
 * NULL or out-of-range arguments: AP_ERR_ARG from the functions that return a status (a NULL
 * among the overrides included), 0 or NULL from the counts and names. */
#ifndef APPELL_BATCH_H
#define APPELL_BATCH_H

#include <stddef.h>
#include <stdint.h>

#include "appell/export.h"
#include "appell/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- plans ------------------------------------------------------------------------------ */

typedef struct ap_plan ap_plan;

AP_API int ap_plan_create(ap_plan **out);
AP_API void ap_plan_free(ap_plan *p);

/* A grid over one path: "PATH=A:B:N" (N values from A to B, equally spaced, both ends
 * included; A and B may be constant expressions such as 70*deg; B - A must be finite) or
 * "PATH=V1,V2,..." (the values as written: numbers, expressions or words such as verner6).
 * Grids combine as a product, the first one varying slowest. */
AP_API int ap_plan_add_grid(ap_plan *p, const char *spec, char *msg, size_t msg_len);
/* A random value for one path: "PATH=normal(MU,SIGMA)" or "PATH=uniform(A,B)" (A <= x < B);
 * parameters may be constant expressions. Needs ap_plan_set_samples. */
AP_API int ap_plan_add_random(ap_plan *p, const char *spec, char *msg, size_t msg_len);
/* samples random draws per grid point (1 to 10^9, as a grid's N; common random numbers:
 * sample j has the same values at every grid point), from seed. Draw j of parameter r
 * depends only on (seed, j, r), so any slice of a plan draws the same numbers as the whole. */
AP_API int ap_plan_set_samples(ap_plan *p, long samples, uint64_t seed);

/* Runs in the plan: the product of the grid sizes times the samples (1 without random ones);
 * -1 when that exceeds 2^53. Run i = g * samples + j for grid point g and sample j. */
AP_API long ap_plan_count(const ap_plan *p);
AP_API int ap_plan_nparams(const ap_plan *p);
/* Parameter r's path (grids first, in the order added, then random ones). */
AP_API const char *ap_plan_path(const ap_plan *p, int r);
/* Parameter r of run i: the number in *x (NaN for a word) and the override "PATH=VALUE" in
 * buf (numbers written with 17 significant digits, which read back to the same double).
 * AP_ERR_ARG when i or r is out of range or buf is too short. */
AP_API int ap_plan_value(const ap_plan *p, long i, int r, double *x, char *buf, size_t len);
/* A typical value of parameter r (the first grid value, the mean of a normal, the middle of
 * a uniform), for checking the overrides once before a sweep. */
AP_API int ap_plan_typical(const ap_plan *p, int r, char *buf, size_t len);

/* ---- batches ---------------------------------------------------------------------------- */

/* The status of a row whose run was never started because the batch was cancelled. */
#define AP_BATCH_NOT_RUN 100
/* ap_batch_run's return when the progress callback cancelled the batch. */
#define AP_BATCH_CANCELLED 101

typedef struct ap_batch_def {
  int threads;                    /* worker threads; default 1; 0 = one per online processor */
  const char *const *channels;    /* output columns to sample, named as in appell run's CSV
                                     header (e.g. "disk.tilt"); may be NULL when nchannels = 0 */
  int nchannels;
  const double *times;            /* times (s) at which the channels are sampled; a time that
                                     is not an output time adds a stop; NaN in a run that does
                                     not reach it. None (ntimes = 0) with channels: t_end of
                                     the scene as loaded by ap_batch_create */
  int ntimes;
  int final_state;                /* 1 (default): q and v where each run ends */
  /* Called about every 0.2 s and once at the end, from the thread that called ap_batch_run,
   * with the number of runs finished. A non-zero return cancels the batch: no further run
   * starts, and those running stop at their next internal step (status AP_ERR_INTERRUPTED).
   * May be NULL. */
  int (*progress)(long done, long total, void *user);
  void *user;
  int internal_check;       /* set by ap_batch_def_default(), never by hand: a definition that
                              function did not make is refused with AP_ERR_ARG */
} ap_batch_def;

AP_API ap_batch_def ap_batch_def_default(void);

typedef struct ap_batch ap_batch;

/* Prepare a scene given as text (len bytes; name stands for the file name in messages) with
 * nsets overrides that every run applies first. The scene is loaded once here, so bad input
 * (the scene, the overrides, an unknown channel, a time that is not finite) fails here with
 * AP_ERR_ARG and the message. */
AP_API int ap_batch_create(const char *text, size_t len, const char *name,
                           const char *const *sets, int nsets, const ap_batch_def *def,
                           ap_batch **out, char *msg, size_t msg_len);
/* The same from a file. */
AP_API int ap_batch_load(const char *path, const char *const *sets, int nsets,
                         const ap_batch_def *def, ap_batch **out, char *msg, size_t msg_len);
AP_API void ap_batch_free(ap_batch *b);

/* Columns of a row of values, the same for every run:
 *   t             time reached (t_end, or where the run failed; NaN when it never started)
 *   steps, rhs_evals, err_fails       accepted steps, right-hand sides, rejected steps
 *   max_residual  largest |A v + a0| at step ends
 *   energy_drift  largest |E(t) - E(t0)| over the output times (docs/cli.md, summary)
 *   NAME@end      each coordinate, then each speed, where the run ended (with final_state)
 *   CHANNEL@T     each channel at each time, times outer (T printed with %.10g) */
AP_API int ap_batch_ncols(const ap_batch *b);
AP_API const char *ap_batch_col_name(const ap_batch *b, int j);

/* The identity of a sweep of plan p on batch b: 16 hex digits and a NUL in id (len >= 17),
 * a hash of the scene text, the batch's overrides (as a set of PATH=VALUE, numbers by value),
 * its channels, times and final_state, and the plan's parameters, values, samples and seed.
 * Slices of one sweep share it wherever they run; `appell sweep --merge` refuses shards whose
 * identities differ. AP_ERR_ARG for NULL arguments or len < 17. */
AP_API int ap_batch_plan_id(const ap_batch *b, const ap_plan *p, char *id, size_t len);

/* Load the scene once with these overrides after the batch's own, without running it: the
 * overrides' paths and values are checked (AP_ERR_ARG and the scene's message otherwise). */
AP_API int ap_batch_check(const ap_batch *b, const char *const *sets, int nsets, char *msg,
                          size_t msg_len);
/* The same with every parameter of the plan at its typical value (ap_plan_typical). */
AP_API int ap_batch_check_plan(const ap_batch *b, const ap_plan *p, char *msg, size_t msg_len);

/* Run count variants: variant i applies sets[i * nper + j], j < nper, after the batch's own
 * overrides. Row i goes to values + i * ncols, status[i] (AP_OK, AP_STOPPED when a stop event
 * of the scene ended the run, the failure's status, or AP_BATCH_NOT_RUN) and messages[i] (may be NULL: then no messages): NULL, or a malloc'd
 * text for a failed run (the scene's message with file:line:column, or the simulation's) or
 * a successful run with a warning; free them with ap_batch_messages_free. Returns AP_OK when
 * every run was attempted, AP_BATCH_CANCELLED, AP_ERR_NOMEM when a worker thread could not
 * allocate its own buffers (the runs it took have status AP_ERR_NOMEM and an "out of memory"
 * message; a run that ran out of memory itself is only its row's status), or AP_ERR_ARG /
 * AP_ERR_NOMEM before any run (AP_ERR_NOMEM: the SUNDIALS contexts of the worker threads,
 * made before the first run, could not be; every row AP_BATCH_NOT_RUN, messages[0] says so). */
AP_API int ap_batch_run(ap_batch *b, long count, int nper, const char *const *sets,
                        double *values, int *status, char **messages);
/* Runs first .. first + count - 1 of a plan (its overrides generated in the workers). */
AP_API int ap_batch_run_plan(ap_batch *b, const ap_plan *p, long first, long count,
                             double *values, int *status, char **messages);
/* The same, with each run's events: the scene's events (its events: section, the bodies'
 * collide: keys, and the implicit kink and saturation events) are added to every run, a run
 * that a stop event ended has status AP_STOPPED (its row ends at the event time, its message
 * names the event), and events[i] (events may be NULL) gets NULL when run i recorded no event,
 * else a malloc'd "NAME@T;NAME@T" (T with %.17g; the last 64 events of the run, in the order
 * they happened); free them with ap_batch_messages_free. ap_batch_run and ap_batch_run_plan
 * add the scene's events too and return the same statuses. */
AP_API int ap_batch_run_plan_events(ap_batch *b, const ap_plan *p, long first, long count,
                                    double *values, int *status, char **messages,
                                    char **events);
AP_API void ap_batch_messages_free(long count, char **messages);

#ifdef __cplusplus
}
#endif
#endif
