/* libFuzzer harness: --set overrides (ap_scene_load_string's sets; docs/cli.md). The input's
 * first byte picks one of the example scenes (examples/scenes, read once at start); the rest,
 * split at newlines, is up to 8 overrides "dotted.path=value" applied to it. When the result
 * loads: its initial state. Seeds: tests/fuzz/seeds/set (scripts/fuzz). */
#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#ifndef AP_FUZZ_SCENES
#define AP_FUZZ_SCENES "examples/scenes"
#endif
#define MAXSCENE 32
#define MAXSET 8

static char *scene[MAXSCENE];
static size_t scene_len[MAXSCENE];
static int nscene = 0;

static int by_name(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The example scenes in name order (the first input byte picks one, the same everywhere). */
static void load_scenes(void) {
  DIR *d = opendir(AP_FUZZ_SCENES);
  struct dirent *e;
  char *names[MAXSCENE];
  int nn = 0;
  while (d && (e = readdir(d)) && nn < MAXSCENE) {
    size_t l = strlen(e->d_name);
    if (l >= 6 && strcmp(e->d_name + l - 5, ".yaml") == 0) names[nn++] = strdup(e->d_name);
  }
  if (d) closedir(d);
  qsort(names, (size_t)nn, sizeof *names, by_name);
  for (int i = 0; i < nn; i++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", AP_FUZZ_SCENES, names[i] ? names[i] : "");
    free(names[i]);
    FILE *f = fopen(path, "rb");
    char *buf = malloc(1 << 16);
    if (f && buf) {
      scene_len[nscene] = fread(buf, 1, (1 << 16) - 1, f);
      scene[nscene++] = buf;
    } else {
      free(buf);
    }
    if (f) fclose(f);
  }
  if (!nscene) {
    fprintf(stderr, "fuzz_set: no scenes in %s\n", AP_FUZZ_SCENES);
    abort();
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (!nscene) load_scenes();
  if (size < 1) return 0;
  int which = data[0] % nscene;
  char *text = malloc(size), *sets[MAXSET];
  if (!text) return 0;
  memcpy(text, data + 1, size - 1);
  text[size - 1] = '\0';
  int nsets = 0;
  for (char *s = text; s && nsets < MAXSET;) {   /* lines; a NUL in the input ends one too */
    char *nl = strchr(s, '\n');
    if (nl) *nl = '\0';
    sets[nsets++] = s;
    s = nl ? nl + 1 : NULL;
  }
  ap_scene *sc = NULL;
  char msg[1024];
  if (ap_scene_load_string(scene[which], scene_len[which], "fuzz.yaml",
                           (const char *const *)sets, nsets, &sc, msg, sizeof msg) == AP_OK) {
    const ap_model *m = ap_scene_model(sc);
    double *q = calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof *q);
    if (q) ap_scene_initial_state(sc, q, q + ap_model_n(m), NULL, 0, msg, sizeof msg);
    free(q);
  }
  ap_scene_free(sc);
  free(text);
  return 0;
}
