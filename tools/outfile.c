/* Atomic output files for the appell command (tools/outfile.h): a temporary file in the
 * target's directory (so the rename stays on one file system and is atomic), renamed over the
 * target only when everything was written. Invariant: a file at the target path is complete. */
#include "outfile.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

int cli_outfile_open(cli_outfile *o, const char *cmd, const char *target) {
  memset(o, 0, sizeof *o);
  if (!target || strcmp(target, "-") == 0) {
    o->f = stdout;
    return EXIT_OK;
  }
  o->target = target;
  if (snprintf(o->tmp, sizeof o->tmp, "%s.tmp.XXXXXX", target) >= (int)sizeof o->tmp)
    return fprintf(stderr, "appell %s: --out: path too long\n", cmd), EXIT_INPUT;
  int fd = mkstemp(o->tmp);
  o->f = fd >= 0 ? fdopen(fd, "w") : NULL;
  if (!o->f) {
    fprintf(stderr, "appell %s: cannot create %s: %s\n", cmd, o->tmp, strerror(errno));
    if (fd >= 0) close(fd), unlink(o->tmp);
    o->tmp[0] = '\0';
    return EXIT_INPUT;
  }
  return EXIT_OK;
}

int cli_outfile_close(cli_outfile *o, const char *cmd, int code) {
  if (!o->f) return code;
  if (!o->target) {
    o->f = NULL;
    return fflush(stdout) != 0 && code == EXIT_OK ? EXIT_INTERNAL : code;
  }
  int bad = ferror(o->f) | (fclose(o->f) != 0);
  o->f = NULL;
  if (code == EXIT_OK && bad) {
    fprintf(stderr, "appell %s: writing %s failed\n", cmd, o->tmp);
    code = EXIT_INTERNAL;
  }
  if (code == EXIT_OK && rename(o->tmp, o->target) != 0) {
    fprintf(stderr, "appell %s: cannot rename %s to %s: %s\n", cmd, o->tmp, o->target,
            strerror(errno));
    code = EXIT_INTERNAL;
  }
  if (code != EXIT_OK) unlink(o->tmp);
  return code;
}
