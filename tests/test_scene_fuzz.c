/* test_scene_fuzz: truncated and byte-mutated versions of every example scene, in process.
 *
 * For each scene in examples/scenes: 25 truncations and 50 mutations (1 to 4 edits each:
 * replace a byte with one YAML cares about or a random byte, delete, duplicate a run, insert),
 * from a fixed seed. Each variant goes through ap_scene_load_string, and when that succeeds,
 * the initial state and a short simulation. Nothing may crash (the sanitizer build runs this
 * too); every failure must come with a message that names the scene. The count of variants
 * that still load is printed, to show the mutations are not all rejected at the first byte. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

#define TRUNCATIONS 25
#define MUTATIONS 50

static uint64_t rng = 0x9e3779b97f4a7c15ull;

static unsigned next(unsigned bound) {
  rng = rng * 6364136223846793005ull + 1442695040888963407ull;
  return (unsigned)((rng >> 33) % bound);
}

static char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *buf = malloc(1 << 20);
  *len = buf ? fread(buf, 1, (1 << 20) - 1, f) : 0;
  fclose(f);
  return buf;
}

/* One random edit of buf (capacity cap) in place; returns the new length. */
static size_t mutate(char *buf, size_t len, size_t cap) {
  static const char special[] = ":-[]{}&*!'\"\n #0.9e,|>%@`?";
  size_t at = len ? next((unsigned)len) : 0;
  switch (next(4)) {
    case 0:
      if (len) buf[at] = next(3) ? special[next(sizeof special - 1)] : (char)next(256);
      return len;
    case 1:
      if (len) memmove(buf + at, buf + at + 1, len - at - 1);
      return len ? len - 1 : 0;
    case 2: {
      size_t run = 1 + next(16);
      if (at + run > len || len + run > cap) return len;
      memmove(buf + at + run, buf + at, len - at);
      return len + run;
    }
    default:
      if (len + 1 > cap) return len;
      memmove(buf + at + 1, buf + at, len - at);
      buf[at] = special[next(sizeof special - 1)];
      return len + 1;
  }
}

/* Load, initialize and briefly run a variant. Returns 1 when it loaded. */
static int try_variant(const char *text, size_t len, const char *name) {
  char msg[1024] = "";
  ap_scene *sc = NULL;
  int rc = ap_scene_load_string(text, len, name, NULL, 0, &sc, msg, sizeof msg);
  if (rc != AP_OK) {
    AP_CHECK(strncmp(msg, name, strlen(name)) == 0 || rc == AP_ERR_NOMEM);
    return 0;
  }
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m), k = ap_model_k(m), nc = ap_scene_output_count(sc);
  double *x = calloc((size_t)(n + k + nc) + 1, sizeof *x);
  ap_scene_run run;
  ap_scene_get_run(sc, &run);
  run.sim.max_steps = 2000;
  ap_sim *sim = NULL;
  if (x && ap_scene_initial_state(sc, x, x + n, NULL, 0, msg, sizeof msg) == AP_OK &&
      ap_sim_create(m, &run.sim, run.t0, x, x + n, &sim, msg, sizeof msg) == AP_OK) {
    if (ap_sim_advance(sim, run.t0 + 1e-3) == AP_OK) ap_scene_output_row(sc, sim, x + n + k);
  }
  ap_sim_free(sim);
  free(x);
  ap_scene_free(sc);
  return 1;
}

static void fuzz_scene(const char *dir, const char *file) {
  char path[1200];
  size_t len = 0;
  snprintf(path, sizeof path, "%s/%s", dir, file);
  char *orig = read_file(path, &len), *buf = malloc(2 * len + 64);
  AP_CHECK(orig != NULL && buf != NULL);
  if (!orig || !buf) {
    free(orig), free(buf);
    return;
  }
  AP_CHECK_EQ_INT(try_variant(orig, len, file), 1);
  int loaded = 0;
  for (int i = 1; i <= TRUNCATIONS; i++)
    loaded += try_variant(orig, len * i / (TRUNCATIONS + 1), file);
  for (int i = 0; i < MUTATIONS; i++) {
    memcpy(buf, orig, len);
    size_t l = len;
    for (int e = 0, edits = 1 + (int)next(4); e < edits; e++) l = mutate(buf, l, 2 * len + 64);
    loaded += try_variant(buf, l, file);
  }
  printf("%-24s %d of %d variants loaded\n", file, loaded, TRUNCATIONS + MUTATIONS);
  free(orig);
  free(buf);
}

int main(void) {
  static const char *const scenes[] = {"rolling_disk.yaml", "skate_incline.yaml",
                                       "chaplygin_sleigh.yaml", "turntable_ball.yaml",
                                       "hoffmann.yaml", "rattleback.yaml", "heavy_top.yaml"};
  char dir[1024];
  ct_find_source(dir, sizeof dir);
  strncat(dir, "/examples/scenes", sizeof dir - strlen(dir) - 1);
  for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++) fuzz_scene(dir, scenes[i]);
  return ap_check_finish("test_scene_fuzz");
}
