/* SUNDIALS contexts, created once and reused by the integrators that follow.
 *
 * SUNDIALS 6.4.1's SUNContext_Create does not check two of its logger's allocations: one
 * failing crashes inside SUNLogger_Create, the other leaves a logger that crashes later inside
 * SUNContext_Free (SUNLogger_Destroy). A context is therefore never freed here: an integrator
 * takes an idle one (ap_ctx_take) and gives it back when it is freed (ap_ctx_give), so only the
 * first integrators of a process, as many as exist at the same time, create one. A sweep
 * reserves one per worker before its first run (ap_ctx_reserve), so its runs never create one.
 * SUNDIALS allows a context to serve one simulation at a time and to be reused once all of the
 * previous one's objects are freed ("Implications for task-based programming and
 * multi-threading" in the SUNDIALS documentation of SUNContext): a context is idle, or owned
 * by exactly one integrator, whatever thread it runs on.
 * Lifetime: idle contexts are kept for the life of the process (reachable from this file, so
 * not a leak for LeakSanitizer), at most AP_CTX_KEEP of them; beyond that a context given back
 * is freed. The mutex orders every hand-over between threads. */
#include <pthread.h>

#include "appell/status.h"
#include "integrate/sunctx.h"

#define AP_CTX_KEEP 512

static pthread_mutex_t ctx_mu = PTHREAD_MUTEX_INITIALIZER;
static SUNContext idle[AP_CTX_KEEP];
static int nidle = 0;

int ap_ctx_take(SUNContext *out) {
  *out = NULL;
  pthread_mutex_lock(&ctx_mu);
  if (nidle > 0) *out = idle[--nidle];
  pthread_mutex_unlock(&ctx_mu);
  if (!*out && SUNContext_Create(NULL, out) != 0) *out = NULL;
  return *out ? AP_OK : AP_ERR_NOMEM;
}

void ap_ctx_give(SUNContext ctx) {
  if (!ctx) return;
  pthread_mutex_lock(&ctx_mu);
  int kept = nidle < AP_CTX_KEEP;
  if (kept) idle[nidle++] = ctx;
  pthread_mutex_unlock(&ctx_mu);
  if (!kept) SUNContext_Free(&ctx);
}

int ap_ctx_reserve(int n) {
  if (n > AP_CTX_KEEP) n = AP_CTX_KEEP;
  int rc = AP_OK;
  pthread_mutex_lock(&ctx_mu);
  while (rc == AP_OK && nidle < n) {
    SUNContext ctx = NULL;
    if (SUNContext_Create(NULL, &ctx) == 0 && ctx) idle[nidle++] = ctx;
    else rc = AP_ERR_NOMEM;
  }
  pthread_mutex_unlock(&ctx_mu);
  return rc;
}
