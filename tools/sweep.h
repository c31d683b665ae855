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

#endif
