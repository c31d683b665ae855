/* appell sweep's checkpoint (docs/sweeps.md "Interrupted sweeps"): the rows of a shard are
 * appended to OUT.partial as runs finish, a batch at a time, each batch flushed and synced, so
 * an interrupted or killed sweep keeps every finished batch. sweep_checkpoint_rows reads one
 * back for --resume: the header must be the sweep's, and the rows a prefix of the shard's
 * runs in order, each starting run,runs,plan with this sweep's plan identity; a torn last line
 * (a kill in the middle of a write) is cut off. The file is truncated after the last good row
 * and the number of rows kept is returned. Memory does not depend on the number of rows. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "sweep.h"

/* Row k (run first + k) of the sweep total runs with identity id at the start of line? */
static int row_ok(const char *line, long run, long total, const char *id) {
  char want[128];
  int n = snprintf(want, sizeof want, "%ld,%ld,%s,", run, total, id);
  return n > 0 && strncmp(line, want, (size_t)n) == 0;
}

long sweep_checkpoint_rows(const char *path, const char *header, const char *id, long first,
                           long total, long count) {
  FILE *f = fopen(path, "r+");
  if (!f)
    return fprintf(stderr, "appell sweep: --resume: %s: cannot open the checkpoint: %s\n", path,
                   CLI_STRERROR(errno)), -1;
  char *line = NULL;
  size_t cap = 0;
  ssize_t len = getline(&line, &cap, f);
  long kept = 0, bad = 0;
  if (len < 0 && !ferror(f)) {   /* killed before its header reached the disk: start it */
    free(line);
    bad = fputs(header, f) < 0 || fclose(f) != 0;
    if (bad) fprintf(stderr, "appell sweep: --resume: %s: %s\n", path, CLI_STRERROR(errno));
    return bad ? -1 : 0;
  }
  if (len < 0 || strcmp(line, header) != 0) {
    fprintf(stderr, "appell sweep: --resume: %s:1: the header differs from this sweep's "
            "(another scene, other parameters or columns)\n", path);
    bad = 1;
  }
  long pos = ftell(f);
  while (!bad && kept < count && (len = getline(&line, &cap, f)) > 0) {
    if (line[len - 1] != '\n') break;   /* torn by a kill: dropped */
    if (!row_ok(line, first + kept, total, id)) {
      fprintf(stderr, "appell sweep: --resume: %s:%ld: expected run %ld of this sweep (%ld runs, "
              "plan %s): another sweep's or shard's checkpoint\n", path, kept + 2, first + kept,
              total, id);
      bad = 1;
      break;
    }
    kept++, pos = ftell(f);
  }
  free(line);
  if (!bad && (fflush(f) != 0 || ftruncate(fileno(f), pos) != 0)) {
    fprintf(stderr, "appell sweep: --resume: %s: %s\n", path, CLI_STRERROR(errno));
    bad = 1;
  }
  fclose(f);
  return bad ? -1 : kept;
}
