/* appell sweep (tools/sweep.c) and its --merge of shard files (tools/sweep_merge.c). */
#ifndef APPELL_SWEEP_H
#define APPELL_SWEEP_H

#include <stdio.h>

#include "cli.h"

int cmd_sweep(int argc, char **argv);
/* Join the shard files inputs (n) into out (checked by cli_out_check): same header, every run
 * of the plan exactly once, rows in run order. Returns an exit code. */
int sweep_merge(cli_out *out, const char *const *inputs, int n, int quiet);
/* Write text as one CSV field in double quotes (quotes doubled, line breaks as spaces). */
void sweep_csv_quote(FILE *f, const char *text);

/* The checkpoint OUT.partial for --resume (tools/sweep_resume.c): checks its header (the text
 * of the header line, with its line break) and rows (runs first, first + 1, ... of total, with
 * identity id), truncates it after the last good row (at most count) and returns how many
 * rows it keeps, or -1 with a message. */
long sweep_checkpoint_rows(const char *path, const char *header, const char *id, long first,
                           long total, long count);

#endif
