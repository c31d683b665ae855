/* libFuzzer harness: appell sweep --merge (tools/sweep_merge.c) on shard files. The input is
 * split at the byte 0x1e into up to 4 files, written to a private temporary directory, and
 * merged into a file there (quiet); every outcome must be a clean exit code with a message,
 * never a crash, and a refused merge must leave no output file. Seeds: tests/fuzz/seeds/merge
 * (shards of a small sweep, scripts/fuzz). */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "sweep.h"

#define MAXFILES 4

static char dir[64];

static int setup(void) {
  if (dir[0]) return 0;
  FILE *null = fopen("/dev/null", "w");   /* the merge's messages; fd 2 stays for ASan */
  if (null) stderr = null;
  snprintf(dir, sizeof dir, "/tmp/appell-fuzz-merge-XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (setup() != 0) return 0;
  char names[MAXFILES][128], out_path[128];
  const char *inputs[MAXFILES];
  int n = 0;
  size_t start = 0;
  for (size_t i = 0; i <= size && n < MAXFILES; i++) {
    if (i < size && data[i] != 0x1e) continue;
    snprintf(names[n], sizeof names[n], "%s/shard%d.csv", dir, n);
    FILE *f = fopen(names[n], "wb");
    if (!f) return 0;
    fwrite(data + start, 1, i - start, f);
    fclose(f);
    inputs[n] = names[n], n++;
    start = i + 1;
  }
  snprintf(out_path, sizeof out_path, "%s/merged.csv", dir);
  remove(out_path);
  cli_out out;
  cli_out_command("sweep");
  if (cli_out_check(&out, out_path, NULL) != 0) return 0;
  int code = sweep_merge(&out, inputs, n, 1);
  if (code != 0 && access(out_path, F_OK) == 0) __builtin_trap();   /* a refused merge wrote */
  for (int i = 0; i < n; i++) remove(names[i]);
  remove(out_path);
  return 0;
}
