/* The guess of a scene's operating point (docs/linearize.md "Scene section"), shared by
 * appell linearize and the Python package.
 *
 * Loads: (1) the scene with the caller's overrides, to read its linearize: section; (2) again
 * with linearize.initial appended (later overrides win): the guess (q, v) is its initial state;
 * with a speed parameter (linearize.speed: initial rates equal to coef * s), (3) and (4) with
 * the speed keys at s = 0 and s = 1: the speeds v0 at speed 0 and dir = v(1) - v0 per unit.
 * The initial state is linear in the given rates (the dependent speeds solve A v + a0 = 0 at a
 * fixed q, and a projection is linear too), so the speeds at s are v0 + s dir, and the speed
 * of the scene's own rates is the least-squares s of v = v0 + s dir. The public API, and the
 * linearizer's record of a bad name in free: / independent: to locate it in the scene. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analyze/analyze_int.h"
#include "appell/scene.h"
#include "scene/scene_int.h"

#define MAX_KEY 512

typedef struct src {
  const char *path, *text;
  size_t len;
  const char **sets;       /* caller's sets, then the section's, then the speed keys */
  int nsets;
  char *msg;
  size_t msg_len;
} src;

static int load(const src *S, int nsets, ap_scene **out) {
  if (S->text)
    return ap_scene_load_string(S->text, S->len, S->path, S->sets, nsets, out, S->msg,
                                S->msg_len);
  return ap_scene_load(S->path, S->sets, nsets, out, S->msg, S->msg_len);
}

/* The speeds of the scene loaded with the speed keys at s (written into keys). */
static int speeds_at(src *S, const ap_scene_lin *sec, int n0, char (*keys)[MAX_KEY], double s,
                     double *q, double *v) {
  for (int i = 0; i < sec->nspeed; i++) {
    snprintf(keys[i], MAX_KEY, "%.400s=%.17g", sec->speed_keys[i], sec->speed_coef[i] * s);
    S->sets[n0 + i] = keys[i];
  }
  ap_scene *sc = NULL;
  int rc = load(S, n0 + sec->nspeed, &sc);
  if (rc == AP_OK) rc = ap_scene_initial_state(sc, q, v, NULL, 0, S->msg, S->msg_len);
  ap_scene_free(sc);
  return rc;
}

static int state(src *S, ap_scene_lin_guess *g, int n0) {
  const ap_model *m = ap_scene_model(g->scene);
  ap_scene_run run;
  ap_scene_get_run(g->scene, &run);
  g->t0 = run.t0, g->n = ap_model_n(m), g->k = ap_model_k(m);
  g->q = calloc((size_t)(2 * g->n + 3 * g->k) + 1, sizeof *g->q);
  if (!g->q) return AP_ERR_NOMEM;
  g->v = g->q + g->n;
  int rc = ap_scene_initial_state(g->scene, g->q, g->v, NULL, 0, S->msg, S->msg_len);
  if (rc != AP_OK || g->sec.nspeed == 0) return rc;
  g->v0 = g->v + g->k, g->dir = g->v0 + g->k;
  double *qt = g->dir + g->k, num = 0.0, den = 0.0;
  char (*keys)[MAX_KEY] = calloc((size_t)g->sec.nspeed, sizeof *keys);
  if (!keys) return AP_ERR_NOMEM;
  rc = speeds_at(S, &g->sec, n0, keys, 0.0, qt, g->v0);
  if (rc == AP_OK) rc = speeds_at(S, &g->sec, n0, keys, 1.0, qt, g->dir);
  free(keys);
  for (int i = 0; rc == AP_OK && i < g->k; i++) {
    g->dir[i] -= g->v0[i];
    num += (g->v[i] - g->v0[i]) * g->dir[i], den += g->dir[i] * g->dir[i];
  }
  g->speed = den > 0.0 ? num / den : 0.0;
  return rc;
}

int ap_scene_lin_guess_load(const char *path, const char *text, size_t len,
                            const char *const *sets, int nsets, ap_scene_lin_guess *out,
                            char *msg, size_t msg_len) {
  if (!out) return AP_ERR_ARG;
  memset(out, 0, sizeof *out);
  out->speed = NAN;
  if (msg && msg_len) msg[0] = '\0';
  if (!path || nsets < 0 || (nsets > 0 && !sets)) {
    if (msg && msg_len) snprintf(msg, msg_len, "ap_scene_lin_guess_load: no scene path or name");
    return AP_ERR_ARG;
  }
  char dummy[8];
  src S = {path, text, len, NULL, nsets, msg ? msg : dummy, msg ? msg_len : sizeof dummy};
  ap_scene *sc = NULL;
  S.sets = (const char **)sets;
  int rc = load(&S, nsets, &sc);
  if (rc == AP_OK) rc = ap_scene_get_linearize(sc, &out->sec, S.msg, S.msg_len);
  ap_scene_free(sc);
  if (rc != AP_OK) return rc;
  int n0 = nsets + out->sec.nsets;
  S.sets = calloc((size_t)(n0 + out->sec.nspeed) + 1, sizeof *S.sets);
  if (!S.sets) return ap_scene_lin_guess_free(out), AP_ERR_NOMEM;
  for (int i = 0; i < nsets; i++) S.sets[i] = sets[i];
  for (int i = 0; i < out->sec.nsets; i++) S.sets[nsets + i] = out->sec.sets[i];
  rc = load(&S, n0, &out->scene);
  if (rc == AP_OK) rc = state(&S, out, n0);
  free(S.sets);
  if (rc != AP_OK) ap_scene_lin_guess_free(out);
  return rc;
}

void ap_scene_lin_guess_free(ap_scene_lin_guess *g) {
  if (!g) return;
  ap_scene_lin_free(&g->sec);
  ap_scene_free(g->scene);
  free(g->q);
  memset(g, 0, sizeof *g);
  g->speed = NAN;
}

ap_lin_def ap_scene_lin_def(const ap_scene_lin_guess *g) {
  ap_lin_def def = ap_lin_def_default();
  if (!g) return def;
  def.about = g->sec.about;
  def.free = (const char *const *)g->sec.free;
  def.independent = (const char *const *)g->sec.independent;
  def.inputs = (const char *const *)g->sec.inputs;
  def.speed_dir = g->dir;
  return def;
}

/* A name of the section's free:, independent: or inputs: list that is not a state variable (a
 * speed, for inputs): the
 * message gets the entry's location in the scene (the linearizer's starts with "LIST: "). */
static void locate_name(const ap_scene_lin_guess *g, const ap_lin_def *d, ap_lin *L) {
  if (!L->bad_list) return;
  int list = strcmp(L->bad_list, "free") == 0 ? 0 : strcmp(L->bad_list, "inputs") == 0 ? 2 : 1;
  char *const *mine = list == 0 ? g->sec.free : list == 2 ? g->sec.inputs : g->sec.independent;
  const char *const *used = list == 0 ? d->free : list == 2 ? d->inputs : d->independent;
  char at[400], tail[512];
  size_t skip = strlen(L->bad_list) + 2;
  if (!mine || used != (const char *const *)mine || strlen(L->msg) < skip ||
      !sc_lin_entry_at(g->scene, L->bad_list, L->bad_index, at, sizeof at))
    return;
  snprintf(tail, sizeof tail, "%s", L->msg + skip);
  snprintf(L->msg, sizeof L->msg, "%.200s: %.300s", at, tail);
}

int ap_scene_lin_create(const ap_scene_lin_guess *g, const ap_lin_def *def, ap_lin **out) {
  if (!out) return AP_ERR_ARG;
  *out = NULL;
  if (!g || !g->scene) return AP_ERR_ARG;
  ap_lin_def d = def ? *def : ap_scene_lin_def(g);
  int rc = ap_lin_create(ap_scene_model(g->scene), &d, g->t0, g->q,
                         d.speed_dir && g->v0 ? g->v0 : g->v, out);
  if (rc == AP_ERR_ARG && *out) locate_name(g, &d, *out);
  return rc;
}
