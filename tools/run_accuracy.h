/* appell run's accuracy options (tools/run_accuracy.c, docs/accuracy.md): --accuracy,
 * --error-estimate and the error control where it matters (--error-control). */
#ifndef APPELL_RUN_ACCURACY_H
#define APPELL_RUN_ACCURACY_H

#include <stdio.h>

#include <appell/appell.h>

#include "cli.h"

struct cli_acc {
  int estimate;              /* --error-estimate */
  double accuracy;           /* --accuracy (0: not asked) */
  int control_all;           /* --error-control all: every coordinate controlled */
  int picked;                /* 1 after cli_acc_pick chose pick.def */
  ap_pick_report pick;
  int *unc, nunc;            /* (n) coordinates left out of the error control, their number */
  double *kept;              /* (rows x nc) the run's rows, for the estimate */
  long rows, cap;
  int nc, too_many;          /* columns (column 0 is t); 1 when the rows were not all kept */
  int done;                  /* 1 when rep holds the estimate */
  ap_error_report rep;
  char path[AP_OUT_PATH_MAX + 16];   /* OUT.error.csv once written, else "" */
  char failure[1024];        /* why there is no estimate, or "" */
};
typedef struct cli_acc cli_acc;

/* --accuracy: choose the method and tolerance (run->sim replaced); a message on failure. */
int cli_acc_pick(cli_acc *a, ap_scene *sc, ap_scene_run *run, const double *q0,
                 const double *v0, int quiet);
/* Leave the coordinates that nothing and no output depends on out of sim's error control. */
int cli_acc_control(cli_acc *a, ap_scene *sc, const ap_scene_run *run, ap_sim *sim,
                    const double *q0, const double *v0);
/* --error-estimate: keep a row of the run (nc columns, column 0 = t). */
int cli_acc_keep_row(cli_acc *a, const double *row, int nc);
/* After the run: when keep (it reached t_end or a stop event), the estimate of the rows kept
 * (a reference run from q0, v0) and OUT.error.csv beside out_path (a regular file, or NULL);
 * an older OUT.error.csv is removed in any case. */
void cli_acc_finish(cli_acc *a, ap_scene *sc, const ap_scene_run *run, const double *q0,
                    const double *v0, int keep, const char *out_path);
/* The summary lines: the estimate, the coordinates left uncontrolled. */
void cli_acc_summary(const cli_acc *a, const ap_model *m);
void cli_acc_free(cli_acc *a);
/* The record's "accuracy" member (tools/runrecord.c): the estimate, the pick, the coordinates
 * left uncontrolled. */
void cli_acc_record(FILE *f, const cli_acc *a, const ap_model *m);

#endif
