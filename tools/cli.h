/* The appell command: shared declarations of its subcommands (tools/appell.c dispatches).
 *
 * Exit codes (docs/cli.md): 0 success, 2 bad input (scene, options, CSV columns), 3 numerical
 * failure (the integrator or a pipeline stage failed during the run), 1 internal error (out of
 * memory, a missing program, an I/O failure such as a failed write), 128 + N stopped by signal
 * N (EXIT_SIGNAL; 130 for SIGINT). Only the public API is used. */
#ifndef APPELL_CLI_H
#define APPELL_CLI_H

#include <stddef.h>

enum { EXIT_OK = 0, EXIT_INTERNAL = 1, EXIT_INPUT = 2, EXIT_NUMERIC = 3 };

/* Exit code of a run stopped by signal sig: 128 + sig (SIGINT 130, SIGTERM 143). */
#define EXIT_SIGNAL(sig) (128 + (sig))

int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
/* The simulation's recorded events, one line each on stderr (events.c). */
struct ap_sim;
void cli_print_events(const struct ap_sim *sim);
int cmd_plot(int argc, char **argv);

/* Exit code for a library status: bad input, numerical failure or internal error. */
int cli_exit_code(int status);
/* Option matching: "--name VALUE" or "--name=VALUE". Returns 1 and sets *value (advancing *i
 * past a separate value) when argv[*i] is the option; -1 when the value is missing or the next
 * word is another option ("--mode -o": a separate value starting with '-' must be "-" or a
 * number; "--name=-x" passes anything). Report -1 with cli_need. */
int cli_opt(int argc, char **argv, int *i, const char *name, const char **value);
/* After cli_opt returned -1 for opt: "appell CMD: OPT needs WHAT (a value when NULL)", naming
 * the option taken for the value if that was the cause. Returns -1. */
int cli_need(const char *cmd, const char *opt, const char *what);
/* Parse a finite number for an option; prints a message and returns -1 when it is not. */
int cli_number(const char *cmd, const char *opt, const char *text, double *out);
/* Report an unknown option with the closest known one. */
int cli_unknown(const char *cmd, const char *arg, const char *const *known);
/* The closest of words to word by edit distance, or NULL. */
const char *cli_suggest(const char *word, const char *const *words, int count);

/* The text of errno value err (strerror_r, thread-safe unlike strerror) in buf (len bytes);
 * "error N" when the C library has none (tools/errtext.c). CLI_STRERROR(err) gives it a
 * buffer that lives until the end of the enclosing block, for use inside one message call. */
const char *cli_errno_text(int err, char *buf, size_t len);
#define CLI_STRERROR(err) cli_errno_text((err), (char[128]){0}, 128)

/* ---- appell run's output target and signals (tools/output.c) ---- */

#include <stdio.h>

#include <appell/outfile.h>

typedef enum cli_out_kind {
  CLI_OUT_STDOUT,          /* no --out, or "-" */
  CLI_OUT_DIRECT,          /* a FIFO or a device: written in place */
  CLI_OUT_FILE             /* a regular file: a temporary file renamed over it at the end */
} cli_out_kind;

typedef struct cli_out {
  cli_out_kind kind;
  const char *target;      /* --out as given */
  ap_outfile file;         /* DIRECT, FILE: the library's rules (include/appell/outfile.h) */
  FILE *f;
  int err;                 /* errno of the first failed write, or 0 */
} cli_out;

/* Handlers for every catchable terminating signal (see tools/output.c). */
void cli_signals_install(void);
/* The first terminating signal received, or 0; and its name ("SIGINT"). */
int cli_interrupted(void);
const char *cli_signal_name(int sig);
/* Before simulating: what --out names (NULL or "-": standard output). Refuses a directory,
 * a dangling link and the scene itself with a message; returns an exit code. */
int cli_out_check(cli_out *o, const char *target, const char *scene);
/* Open the target (removing stale temporary files of killed runs first). */
int cli_out_open(cli_out *o);
/* Non-zero (an errno value) once a write has failed. */
int cli_out_failed(cli_out *o);
/* Finish: on code EXIT_OK rename the temporary file over the target, else remove it; a
 * failed write is reported. Returns the exit code. */
int cli_out_close(cli_out *o, int code);
/* The same, renaming the temporary file over the target also when code is not EXIT_OK but
 * keep is set (a run that failed or was interrupted keeps its rows); never after a failed
 * write (the partial file is removed, exit 1 when code was EXIT_OK). */
int cli_out_finish(cli_out *o, int code, int keep);
const char *cli_out_name(const cli_out *o);   /* the path, or "standard output" */
/* The subcommand its messages name ("run" unless set; appell sweep sets "sweep"). */
void cli_out_command(const char *name);

/* A file name gnuplot can take inside single quotes (no quotes, backslashes or newlines). */
int cli_safe_name(const char *s);
/* Run gnuplot on the script that script(g, user) writes; 0, or -1 with a message naming
 * `appell CMD` (gnuplot missing, failing, or the pipe or fork failing). tools/gnuplot.c. */
int cli_gnuplot(const char *cmd, void (*script)(FILE *g, const void *user), const void *user);

/* appell CMD: warning: when method is asked for an rtol below its rtol_floor (ap_method_info;
 * tools/tolerance.c); nothing in DAE mode (dae non-zero), whose integrator is IDA. */
void cli_warn_tolerance(const char *cmd, int dae, const char *method, double rtol);

#endif
