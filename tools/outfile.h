/* Output files that appear only complete: rows go to FILE.tmp.XXXXXX beside the target, which
 * is renamed over the target after the last row and removed on any failure or interruption
 * (tools/outfile.c). "-" or NULL means standard output. */
#ifndef APPELL_OUTFILE_H
#define APPELL_OUTFILE_H

#include <stdio.h>

typedef struct cli_outfile {
  FILE *f;
  char tmp[4096];
  const char *target;      /* NULL for standard output */
} cli_outfile;

/* Open; prints a message (prefixed with cmd) and returns EXIT_INPUT on failure. */
int cli_outfile_open(cli_outfile *o, const char *cmd, const char *target);
/* Close: with code == EXIT_OK rename the temporary file to the target, otherwise remove it.
 * Returns code, or EXIT_INTERNAL when writing or renaming failed. */
int cli_outfile_close(cli_outfile *o, const char *cmd, int code);

#endif
