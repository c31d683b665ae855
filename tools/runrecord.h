/* The run record of appell run (OUT.run.json beside --out OUT; docs/cli.md "The run record"),
 * the status words and events shared with appell sweep's rows, and the reader appell plot
 * uses. tools/runrecord.c writes (JSON by hand), tools/runrecord_read.c reads. */
#ifndef APPELL_RUNRECORD_H
#define APPELL_RUNRECORD_H

#include <stdio.h>

#include <appell/appell.h>

/* One event of a run: where it happened and what it did (docs/cli.md). */
typedef struct cli_event {
  const char *name;        /* the event's name in the scene */
  double t;                /* its time (s) */
  const char *action;      /* "stop", "log", ... */
  const char *direction;   /* "rising", "falling", "either" */
  const double *q, *v;     /* the state there: n coordinates, k speeds (may be NULL) */
} cli_event;

/* The events a run recorded (ap_sim_event_count / ap_sim_event_get), for the run record: the
 * last max of them into out (a stop event is the last), the count returned. */
int cli_run_events(const ap_sim *sim, cli_event *out, int max);

/* Status words of a run record and of a sweep row's outcome column. */
#define CLI_STATUS_OK "ok"                    /* reached t_end */
#define CLI_STATUS_EVENT "event"              /* a stop event ended it (exit 0) */
#define CLI_STATUS_FAILED "failed"            /* a numerical failure (exit 3) */
#define CLI_STATUS_INTERRUPTED "interrupted"  /* a signal (exit 128 + N) */

/* What a record says; strings are owned by the caller. */
typedef struct cli_record {
  const char *scene, *scene_name, *out;
  const char *const *sets;  /* the overrides in the order applied (--set, then shorthands) */
  int nsets;
  const ap_scene_run *run;  /* mode, method, tolerances, times */
  const ap_model *model;    /* for the path and the coordinate and speed names */
  const char *status;       /* CLI_STATUS_* */
  int exit_code;
  const char *error;        /* ap_strerror of the failure, or NULL */
  const char *message;      /* what stopped it (as on stderr), or the run's warning, or "" */
  double t;                 /* the time reached */
  long rows;                /* data rows in the CSV */
  const ap_sim *sim;        /* statistics and events (may be NULL) */
  double energy_drift, energy0, wall;
  int conserves_energy;
  const struct cli_acc *acc;   /* the accuracy options' results (tools/run_accuracy.h), or NULL */
} cli_record;

/* Write the record as JSON to f (UTF-8; strings escaped, invalid bytes as U+FFFD, numbers
 * with 17 significant digits, NaN and infinities as null). */
void cli_record_write(FILE *f, const cli_record *r);
/* A JSON number (the shortest of 15 to 17 digits that reads back; null for NaN, Inf). */
void cli_json_number(FILE *f, double x);
/* A JSON string (with its quotes) for s. */
void cli_json_string(FILE *f, const char *s);

/* The parts of a record appell plot uses. read returns 0 when path holds a record of this
 * format, -1 otherwise (missing, unreadable, not a record). */
#define CLI_RECORD_MAX_EVENTS 64
typedef struct cli_record_info {
  char status[32];
  char message[1024];
  double t;
  int nevents;
  double event_t[CLI_RECORD_MAX_EVENTS];
  char event_name[CLI_RECORD_MAX_EVENTS][64];
} cli_record_info;
int cli_record_read(const char *path, cli_record_info *info);

/* A sweep row's outcome word for a run's status (AP_OK: ok; AP_STOPPED: event; a failure:
 * failed). */
const char *cli_outcome(int status);
/* A sweep row's outcome and events cells (",ok,\"\"") after its status; events is the
 * batch's "NAME@T;NAME@T" of the run (or NULL), quoted like the message. */
void sweep_outcome_cells(FILE *f, int status, const char *events);

#endif
