/* The batch's thread pool: `threads` POSIX threads take run indices from a shared counter in
 * increasing order, run them (batch_run.c) and write row i, status[i], messages[i] and events[i]
 * only;
 * the calling thread waits, reporting progress about every 0.2 s. Rows are therefore the same
 * whatever the number of threads and the order in which runs finish.
 * Cancelling (the progress callback returns non-zero) stops the handing out of indices and
 * interrupts the runs under way at their next internal step (ap_sim_set_poll; their rows say
 * AP_ERR_INTERRUPTED); rows never started keep status AP_BATCH_NOT_RUN and NaN values.
 * When no thread can be created the calling thread runs everything itself. A worker that
 * cannot allocate its buffers still takes runs, and marks each AP_ERR_NOMEM with the message
 * "out of memory ..." (never AP_BATCH_NOT_RUN, which means cancelled); ap_bat_pool then returns
 * AP_ERR_NOMEM. Before the first run one idle SUNDIALS context per worker is made
 * (integrate/sunctx.c), so that no run creates one; when that fails nothing runs (every row
 * AP_BATCH_NOT_RUN, messages[0] says why) and ap_bat_pool returns AP_ERR_NOMEM.
 * Progress is timed on the monotonic clock (the condition variable waits on CLOCK_MONOTONIC
 * too), so a change of the wall clock neither stalls nor floods it. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "batch/batch_int.h"
#include "integrate/sunctx.h"

#define POOL_MAX_THREADS 256
#define POOL_MSG 1024
#define POOL_SET 512
#define POOL_EVENTS (AP_BAT_MAX_EVENTS * 160)   /* names of up to 127 bytes, times */

typedef struct pool {
  const ap_batch *b;
  const ap_bat_source *src;
  long count;
  double *values;
  int *status;
  char **messages;
  char **events;           /* may be NULL */
  pthread_mutex_t mu;
  pthread_cond_t cv;
  long next, done;         /* next index to hand out; runs finished */
  int cancel;
  int nomem;               /* a worker could not allocate its buffers */
  atomic_int stop;         /* = cancel, read by the simulations' poll without the mutex */
  int active;              /* workers still running */
} pool;

/* The overrides of run i: pointers into the explicit list, or written from the plan. */
static const char *const *run_sets(const pool *p, long i, char (*buf)[POOL_SET],
                                   const char **sets) {
  const ap_bat_source *s = p->src;
  if (!s->plan) return s->sets ? s->sets + (size_t)i * (size_t)s->nper : NULL;
  for (int r = 0; r < s->nper; r++) {
    if (ap_plan_value(s->plan, s->first + i, r, NULL, buf[r], POOL_SET) != AP_OK)
      snprintf(buf[r], POOL_SET, "%s", "plan: no value");   /* checked before the pool */
    sets[r] = buf[r];
  }
  return sets;
}

static void *worker(void *arg) {
  pool *p = arg;
  int nper = p->src->nper;
  char msg[POOL_MSG], ev[POOL_EVENTS], (*buf)[POOL_SET] = calloc((size_t)nper + 1, sizeof *buf);
  const char **sets = calloc((size_t)nper + 1, sizeof *sets);
  for (;;) {
    pthread_mutex_lock(&p->mu);
    long i = p->cancel ? p->count : p->next;
    if (i < p->count) p->next++;
    if (i < p->count && (!buf || !sets)) p->nomem = 1;
    pthread_mutex_unlock(&p->mu);
    if (i >= p->count) break;
    int rc;
    ev[0] = '\0';
    if (!buf || !sets) {   /* the run is reported, as out of memory, not left "not run" */
      rc = AP_ERR_NOMEM;
      snprintf(msg, sizeof msg, "out of memory: the batch worker could not allocate the "
               "overrides of run %ld", i);
    } else {
      const char *const *vs = run_sets(p, i, buf, sets);
      rc = ap_bat_run_one(p->b, vs, nper, p->values + (size_t)i * (size_t)p->b->ncols, msg,
                          sizeof msg, p->events ? ev : NULL, sizeof ev, &p->stop);
    }
    p->status[i] = rc;
    if (p->messages) p->messages[i] = msg[0] ? strdup(msg) : NULL;
    if (p->events) p->events[i] = ev[0] ? strdup(ev) : NULL;
    pthread_mutex_lock(&p->mu);
    p->done++;
    pthread_cond_signal(&p->cv);
    pthread_mutex_unlock(&p->mu);
  }
  free(buf);
  free(sets);
  pthread_mutex_lock(&p->mu);
  p->active--;
  pthread_cond_signal(&p->cv);
  pthread_mutex_unlock(&p->mu);
  return NULL;
}

static int progress(pool *p, long done) {
  const ap_batch_def *d = &p->b->def;
  return d->progress ? d->progress(done, p->count, d->user) : 0;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Wait for the workers, calling the progress callback about every 0.2 s. */
static void wait_done(pool *p) {
  double last = now();
  pthread_mutex_lock(&p->mu);
  while (p->active > 0 && p->done < p->count && !p->cancel) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);   /* the clock of p->cv (pool_init) */
    ts.tv_nsec += 200000000L;
    if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
    pthread_cond_timedwait(&p->cv, &p->mu, &ts);
    if (p->done >= p->count || now() - last < 0.2) continue;
    long done = p->done;
    pthread_mutex_unlock(&p->mu);
    int stop = progress(p, done);
    last = now();
    pthread_mutex_lock(&p->mu);
    if (stop) p->cancel = 1, atomic_store(&p->stop, 1);
  }
  pthread_mutex_unlock(&p->mu);
}

static int thread_count(const ap_batch *b, long count) {
  long t = b->def.threads > 0 ? b->def.threads : sysconf(_SC_NPROCESSORS_ONLN);
  if (t < 1) t = 1;
  if (t > POOL_MAX_THREADS) t = POOL_MAX_THREADS;
  return (int)(t < count ? t : count);
}

/* The condition variable waits with deadlines on CLOCK_MONOTONIC. */
static int pool_init(pool *p) {
  pthread_condattr_t ca;
  if (pthread_condattr_init(&ca) != 0) return AP_ERR_NOMEM;
  int rc = pthread_condattr_setclock(&ca, CLOCK_MONOTONIC) == 0 &&
           pthread_cond_init(&p->cv, &ca) == 0 ? AP_OK : AP_ERR_NOMEM;
  pthread_condattr_destroy(&ca);
  if (rc == AP_OK && pthread_mutex_init(&p->mu, NULL) != 0)
    rc = AP_ERR_NOMEM, pthread_cond_destroy(&p->cv);
  atomic_init(&p->stop, 0);
  return rc;
}

int ap_bat_pool(ap_batch *b, const ap_bat_source *src, long count, double *values, int *status,
                char **messages, char **events) {
  pool p;
  memset(&p, 0, sizeof p);
  p.b = b, p.src = src, p.count = count, p.values = values, p.status = status;
  p.messages = messages, p.events = events;
  for (long i = 0; i < count; i++) {
    status[i] = AP_BATCH_NOT_RUN;
    if (messages) messages[i] = NULL;
    if (events) events[i] = NULL;
    for (int j = 0; j < b->ncols; j++) values[(size_t)i * (size_t)b->ncols + (size_t)j] = NAN;
  }
  int nt = thread_count(b, count), started = 0;
  if (nt > 0 && ap_ctx_reserve(nt) != AP_OK) {   /* before any run: nothing is lost */
    if (messages)
      messages[0] = strdup("out of memory: the SUNDIALS contexts of the batch's workers "
                           "could not be created; no run was started");
    return AP_ERR_NOMEM;
  }
  if (pool_init(&p) != AP_OK) return AP_ERR_NOMEM;
  pthread_t tid[POOL_MAX_THREADS];
  p.active = nt;
  while (started < nt && pthread_create(&tid[started], NULL, worker, &p) == 0) started++;
  pthread_mutex_lock(&p.mu);
  p.active -= nt - started;   /* threads that could not be created */
  pthread_mutex_unlock(&p.mu);
  if (started == 0) p.active = 1, worker(&p);
  else wait_done(&p);
  for (int t = 0; t < started; t++) pthread_join(tid[t], NULL);
  int cancelled = p.cancel || p.done < count;
  if (!cancelled) progress(&p, p.done);
  pthread_cond_destroy(&p.cv);
  pthread_mutex_destroy(&p.mu);
  return cancelled ? AP_BATCH_CANCELLED : p.nomem ? AP_ERR_NOMEM : AP_OK;
}
