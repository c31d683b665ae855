/* Batches (include/appell/batch.h): one scene prepared for many runs.
 *
 * ap_batch_create copies the scene text, the overrides, the channels and the times, loads the
 * scene once (so bad input fails here, once, not in every run), checks that the channels exist
 * and fixes the result columns: AP_BAT_FIXED_COLS summaries, then NAME@end for every
 * coordinate and speed (with final_state), then CHANNEL@T for every time and channel.
 * Runs load their scenes in parallel: the scene layer keeps no state between calls (its
 * expression evaluator is thread-safe; test_threads checks loads under ThreadSanitizer). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/scene.h"
#include "batch/batch_int.h"
#include "core/defcheck.h"
#include "core/text.h"

ap_batch_def ap_batch_def_default(void) {
  ap_batch_def d;
  memset(&d, 0, sizeof d);
  d.threads = 1;
  d.final_state = 1;
  d.internal_check = AP_DEF_CHECK;
  return d;
}

int ap_bat_load(const ap_batch *b, const char *const *vsets, int nv, ap_scene **out, char *msg,
                size_t msg_len) {
  const char **all = malloc(sizeof *all * (size_t)(b->nsets + nv + 1));
  if (!all) {
    if (msg && msg_len) snprintf(msg, msg_len, "out of memory");
    return AP_ERR_NOMEM;
  }
  for (int i = 0; i < b->nsets; i++) all[i] = b->sets[i];
  for (int i = 0; i < nv; i++) all[b->nsets + i] = vsets[i];
  int rc = ap_scene_load_string(b->text, b->len, b->name, all, b->nsets + nv, out, msg, msg_len);
  free(all);
  return rc;
}

static void free_strings(char **s, int n) {
  for (int i = 0; s && i < n; i++) free(s[i]);
  free(s);
}

void ap_batch_free(ap_batch *b) {
  if (!b) return;
  free(b->text);
  free(b->name);
  free_strings(b->sets, b->nsets);
  free_strings(b->channels, b->def.nchannels);
  free(b->times);
  free(b->order);
  free_strings(b->cols, b->ncols);
  free(b);
}

static char **copy_strings(const char *const *s, int n) {
  char **d = calloc((size_t)n + 1, sizeof *d);
  for (int i = 0; d && i < n; i++)
    if (!(d[i] = strdup(s[i]))) return free_strings(d, i), NULL;
  return d;
}

#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static int say(char *msg, size_t len, int rc, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (msg && len) vsnprintf(msg, len, fmt, ap);
  va_end(ap);
  return rc;
}

/* printf into a string of exactly the length needed (a column name is never cut). */
static char *fmt_dup(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static char *fmt_dup(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  char *s = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!s) return NULL;
  va_start(ap, fmt);
  vsnprintf(s, (size_t)n + 1, fmt, ap);
  va_end(ap);
  return s;
}

/* "channel 'X': no output column ... (did you mean 'Y'?)". */
static int unknown_channel(const ap_scene *sc, const char *name, char *msg, size_t len) {
  int nc = ap_scene_output_count(sc);
  const char **names = malloc(sizeof *names * (size_t)(nc + 1));
  for (int i = 0; names && i < nc; i++) names[i] = ap_scene_output_name(sc, i);
  const char *near = names ? ap_suggest(name, names, nc) : NULL;
  char hint[300] = "";
  if (near) snprintf(hint, sizeof hint, "did you mean '%s'? ", near);
  free(names);
  return say(msg, len, AP_ERR_ARG, "channel '%s': no output column of that name in the scene "
             "(%sthe columns are those of appell run's CSV header; output.channels chooses "
             "them)", name, hint);
}

/* The result columns; the channels must be columns of the scene. */
static int make_cols(ap_batch *b, const ap_scene *sc, char *msg, size_t len) {
  static const char *const fixed[AP_BAT_FIXED_COLS] = {"t", "steps", "rhs_evals", "err_fails",
                                                       "max_residual", "energy_drift"};
  const ap_model *m = ap_scene_model(sc);
  int nfinal = b->def.final_state ? b->n + b->k : 0;
  b->ncols = AP_BAT_FIXED_COLS + nfinal + b->def.ntimes * b->def.nchannels;
  b->cols = calloc((size_t)b->ncols, sizeof *b->cols);
  if (!b->cols) return AP_ERR_NOMEM;
  for (int j = 0; j < b->ncols; j++) {
    int f = j - AP_BAT_FIXED_COLS, s = f - nfinal;
    if (j < AP_BAT_FIXED_COLS) b->cols[j] = fmt_dup("%s", fixed[j]);
    else if (f < nfinal)
      b->cols[j] = fmt_dup("%s@end", f < b->n ? ap_model_coord_name(m, f)
                                              : ap_model_speed_name(m, f - b->n));
    else
      b->cols[j] = fmt_dup("%s@%.10g", b->channels[s % b->def.nchannels],
                           b->times[s / b->def.nchannels]);
    if (!b->cols[j]) return AP_ERR_NOMEM;
  }
  for (int c = 0; c < b->def.nchannels; c++) {
    int found = 0;
    for (int i = 0; i < ap_scene_output_count(sc) && !found; i++)
      found = strcmp(ap_scene_output_name(sc, i), b->channels[c]) == 0;
    if (!found) return unknown_channel(sc, b->channels[c], msg, len);
  }
  return AP_OK;
}

static int copy_def(ap_batch *b, const ap_batch_def *def, char *msg, size_t len) {
  if (def && def->internal_check != AP_DEF_CHECK)
    return say(msg, len, AP_ERR_ARG, "ap_batch_def " AP_DEF_NOT_DEFAULT("ap_batch_def"));
  b->def = def ? *def : ap_batch_def_default();
  if (b->def.threads < 0)
    return say(msg, len, AP_ERR_ARG, "invalid batch definition: threads %d (need >= 0; 0: one "
               "per processor)", b->def.threads);
  if (b->def.nchannels < 0 || b->def.ntimes < 0 || (b->def.nchannels && !b->def.channels) ||
      (b->def.ntimes && !b->def.times))
    return say(msg, len, AP_ERR_ARG, "invalid batch definition: nchannels %d, ntimes %d (need "
               ">= 0, and the arrays when positive)", b->def.nchannels, b->def.ntimes);
  for (int c = 0; c < b->def.nchannels; c++)
    if (!b->def.channels[c])
      return say(msg, len, AP_ERR_ARG, "invalid batch definition: channel %d of %d is NULL", c,
                 b->def.nchannels);
  b->channels = copy_strings(b->def.channels, b->def.nchannels);
  b->times = malloc(sizeof *b->times * (size_t)(b->def.ntimes + 1));
  b->order = malloc(sizeof *b->order * (size_t)(b->def.ntimes + 1));
  if (!b->channels || !b->times || !b->order) return AP_ERR_NOMEM;
  for (int i = 0; i < b->def.ntimes; i++) {
    if (!isfinite(b->def.times[i]))
      return say(msg, len, AP_ERR_ARG, "sample time %g is not finite", b->def.times[i]);
    b->times[i] = b->def.times[i];
    int at = i;   /* insertion sort of the indices by time */
    while (at > 0 && b->times[b->order[at - 1]] > b->times[i]) b->order[at] = b->order[at - 1], at--;
    b->order[at] = i;
  }
  b->def.channels = (const char *const *)b->channels;
  b->def.times = b->times;
  return AP_OK;
}

int ap_batch_create(const char *text, size_t len, const char *name, const char *const *sets,
                    int nsets, const ap_batch_def *def, ap_batch **out, char *msg,
                    size_t msg_len) {
  if (msg && msg_len) msg[0] = '\0';
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  int null_set = 0;
  for (int i = 0; sets && i < nsets; i++) null_set |= !sets[i];
  if (!text || nsets < 0 || (nsets && !sets) || null_set)
    return say(msg, msg_len, AP_ERR_ARG, "NULL scene text or overrides");
  ap_batch *b = calloc(1, sizeof *b);
  if (!b) return say(msg, msg_len, AP_ERR_NOMEM, "out of memory");
  b->text = malloc(len + 1);
  b->name = strdup(name ? name : "scene");
  b->sets = copy_strings(sets, nsets);
  b->nsets = nsets, b->len = len;
  int rc = b->text && b->name && b->sets ? copy_def(b, def, msg, msg_len) : AP_ERR_NOMEM;
  ap_scene *sc = NULL;
  if (rc == AP_OK) {
    memcpy(b->text, text, len);
    b->text[len] = '\0';
    rc = ap_bat_load(b, NULL, 0, &sc, msg, msg_len);
  }
  if (rc == AP_OK) {
    b->n = ap_model_n(ap_scene_model(sc)), b->k = ap_model_k(ap_scene_model(sc));
    if (b->def.nchannels > 0 && b->def.ntimes == 0) {   /* channels at t_end */
      ap_scene_run run;
      ap_scene_get_run(sc, &run);
      b->times[0] = run.t_end, b->order[0] = 0, b->def.ntimes = 1;
    }
    rc = make_cols(b, sc, msg, msg_len);
  }
  ap_scene_free(sc);
  if (rc == AP_ERR_NOMEM) say(msg, msg_len, rc, "out of memory");
  if (rc != AP_OK) return ap_batch_free(b), rc;
  *out = b;
  return AP_OK;
}

int ap_batch_load(const char *path, const char *const *sets, int nsets, const ap_batch_def *def,
                  ap_batch **out, char *msg, size_t msg_len) {
  if (out) *out = NULL;
  char *buf = NULL;
  size_t len = 0;
  int rc = ap_scene_read(path, &buf, &len, msg, msg_len);
  if (rc == AP_OK) rc = ap_batch_create(buf, len, path, sets, nsets, def, out, msg, msg_len);
  ap_scene_text_free(buf);
  return rc;
}

int ap_batch_ncols(const ap_batch *b) { return b ? b->ncols : 0; }

const char *ap_batch_col_name(const ap_batch *b, int j) {
  return b && j >= 0 && j < b->ncols ? b->cols[j] : NULL;
}

int ap_batch_check(const ap_batch *b, const char *const *sets, int nsets, char *msg,
                   size_t msg_len) {
  if (!b || nsets < 0 || (nsets && !sets)) return AP_ERR_ARG;
  ap_scene *sc = NULL;
  int rc = ap_bat_load(b, sets, nsets, &sc, msg, msg_len);
  ap_scene_free(sc);
  return rc;
}

int ap_batch_check_plan(const ap_batch *b, const ap_plan *p, char *msg, size_t msg_len) {
  int np = ap_plan_nparams(p), rc = b && p ? AP_OK : AP_ERR_ARG;
  char (*buf)[512] = calloc((size_t)np + 1, sizeof *buf);
  const char **sets = calloc((size_t)np + 1, sizeof *sets);
  if (rc == AP_OK && (!buf || !sets)) rc = AP_ERR_NOMEM;
  for (int r = 0; rc == AP_OK && r < np; r++) {
    rc = ap_plan_typical(p, r, buf[r], sizeof buf[r]);
    sets[r] = buf[r];
  }
  if (rc == AP_OK) rc = ap_batch_check(b, sets, np, msg, msg_len);
  free(buf);
  free(sets);
  return rc;
}

int ap_batch_run(ap_batch *b, long count, int nper, const char *const *sets, double *values,
                 int *status, char **messages) {
  if (!b || count < 0 || nper < 0 || (count && nper && !sets) || (count && (!values || !status)))
    return AP_ERR_ARG;
  ap_bat_source src = {sets, nper, NULL, 0};
  return ap_bat_pool(b, &src, count, values, status, messages, NULL);
}

int ap_batch_run_plan(ap_batch *b, const ap_plan *p, long first, long count, double *values,
                      int *status, char **messages) {
  return ap_batch_run_plan_events(b, p, first, count, values, status, messages, NULL);
}

int ap_batch_run_plan_events(ap_batch *b, const ap_plan *p, long first, long count,
                             double *values, int *status, char **messages, char **events) {
  if (!b || !p || first < 0 || count < 0 || first + count > ap_plan_count(p) ||
      (count && (!values || !status)))
    return AP_ERR_ARG;
  char buf[512];
  for (int r = 0; count && r < ap_plan_nparams(p); r++)   /* e.g. random values need samples */
    if (ap_plan_value(p, first, r, NULL, buf, sizeof buf) != AP_OK) return AP_ERR_ARG;
  ap_bat_source src = {NULL, ap_plan_nparams(p), p, first};
  return ap_bat_pool(b, &src, count, values, status, messages, events);
}

void ap_batch_messages_free(long count, char **messages) {
  for (long i = 0; messages && i < count; i++) {
    free(messages[i]);
    messages[i] = NULL;
  }
}
