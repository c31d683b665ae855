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
  ap_sim *ref;               /* the reference simulation (--error-estimate), or NULL */
  ap_sim_def ref_def;
  ap_scene_out *out;         /* its outputs */
  int nc;                    /* output columns (column 0 is t) */
  double *row, *ref_row, *err, *scale;   /* (nc) each: |difference|, reference row, maxima */
  double error;              /* the estimate so far (ap_error_norm over the columns after t) */
  long rows;
  FILE *csv;                 /* OUT.error.csv.part while running, or NULL */
  char path[AP_OUT_PATH_MAX + 16], part[AP_OUT_PATH_MAX + 24];
  char failure[1024];        /* why the reference stopped, or "" */
};
typedef struct cli_acc cli_acc;

/* --accuracy: choose the method and tolerance (run->sim replaced); a message on failure. */
int cli_acc_pick(cli_acc *a, ap_scene *sc, ap_scene_run *run, const double *q0,
                 const double *v0, int quiet);
/* Leave the coordinates that nothing and no output depends on out of sim's error control. */
int cli_acc_control(cli_acc *a, ap_scene *sc, const ap_scene_run *run, ap_sim *sim,
                    const double *q0, const double *v0);
/* --error-estimate: the reference simulation, and OUT.error.csv.part when out_path is a file. */
int cli_acc_estimate_start(cli_acc *a, ap_scene *sc, const ap_scene_run *run,
                           const double *q0, const double *v0, const char *out_path);
/* After each row of the run: the reference advanced to the run's time, then the row folded
 * into the estimate (and written to the error CSV). */
int cli_acc_estimate_row(cli_acc *a, ap_sim *sim);
void cli_acc_estimate_fold(cli_acc *a, const double *row);
/* Rename the error CSV into place when keep (and the reference reached the end). */
void cli_acc_finish(cli_acc *a, int keep);
/* The summary lines: the estimate, the coordinates left uncontrolled. */
void cli_acc_summary(const cli_acc *a, const ap_model *m);
void cli_acc_free(cli_acc *a);
/* The record's "accuracy" member (tools/runrecord.c): the estimate, the pick, the coordinates
 * left uncontrolled. */
void cli_acc_record(FILE *f, const cli_acc *a, const ap_model *m);

#endif
