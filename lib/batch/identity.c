/* A sweep's identity (include/appell/batch.h, ap_batch_plan_id): 16 hex digits of a 64-bit
 * FNV-1a hash of what fixes its rows: the scene text (bytes), the batch's overrides, the
 * channels, times and final_state, and the plan (plan.c: values, not their spelling).
 *
 * The overrides are taken as a set of PATH=VALUE (the last of a path wins, as when a scene is
 * loaded; the order of different paths does not matter), VALUE as its number when it is a
 * constant expression (1e-8 and 1e-08 are the same) and as its text otherwise; each pair is
 * hashed alone and the hashes are summed, which does not depend on their order. Shards of one
 * sweep made by appell sweep and by appell.sweep therefore carry the same identity, and
 * `appell sweep --merge` refuses to join shards whose identities differ. */
#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "appell/scene.h"
#include "batch/batch_int.h"

uint64_t ap_bat_hash(uint64_t h, const void *data, size_t n) {
  const unsigned char *c = data;
  for (size_t i = 0; i < n; i++) h = (h ^ c[i]) * 0x100000001b3ULL;
  return h;
}

/* The length of the path of "PATH=VALUE" (up to '=' without trailing blanks). */
static size_t path_len(const char *set) {
  size_t n = strcspn(set, "=");
  while (n && isspace((unsigned char)set[n - 1])) n--;
  return n;
}

/* The hash of one override, or 0 when a later one sets the same path. */
static uint64_t set_hash(char *const *sets, int nsets, int i) {
  const char *s = sets[i];
  size_t n = path_len(s);
  for (int j = i + 1; j < nsets; j++)
    if (path_len(sets[j]) == n && strncmp(sets[j], s, n) == 0) return 0;
  uint64_t h = ap_bat_hash(AP_BAT_HASH0, s, n);
  const char *v = s + strcspn(s, "=");
  if (*v) v++;
  while (isspace((unsigned char)*v)) v++;
  double x;
  char why[64];
  if (ap_scene_constant(v, &x, why, sizeof why) == AP_OK) {
    x += 0.0;
    return ap_bat_hash(h ^ 1, &x, sizeof x);
  }
  size_t m = strlen(v);
  while (m && isspace((unsigned char)v[m - 1])) m--;
  return ap_bat_hash(h ^ 2, v, m);
}

int ap_batch_plan_id(const ap_batch *b, const ap_plan *p, char *id, size_t len) {
  if (!b || !p || !id || len < 17) return AP_ERR_ARG;
  uint64_t h = ap_bat_hash(AP_BAT_HASH0, "appell sweep 1", 14), sets = 0;
  h = ap_bat_hash(h, b->text, b->len);
  for (int i = 0; i < b->nsets; i++) sets += set_hash(b->sets, b->nsets, i);
  h = ap_bat_hash(h, &sets, sizeof sets);
  for (int c = 0; c < b->def.nchannels; c++)
    h = ap_bat_hash(h, b->channels[c], strlen(b->channels[c]) + 1);
  h = ap_bat_hash(h, b->times, sizeof *b->times * (size_t)b->def.ntimes);
  h = ap_bat_hash(h, &b->def.final_state, sizeof b->def.final_state);
  h = ap_bat_plan_hash(p, h);
  snprintf(id, len, "%016llx", (unsigned long long)h);
  return AP_OK;
}
