/* The appell command: shared declarations of its subcommands (tools/appell.c dispatches).
 *
 * Exit codes (docs/cli.md): 0 success, 2 bad input (scene, options, CSV columns), 3 numerical
 * failure (the integrator or a pipeline stage failed during the run), 1 internal error (out of
 * memory, a missing program, an I/O failure), 130 interrupted. Only the public API is used. */
#ifndef APPELL_CLI_H
#define APPELL_CLI_H

#include <stddef.h>

enum { EXIT_OK = 0, EXIT_INTERNAL = 1, EXIT_INPUT = 2, EXIT_NUMERIC = 3, EXIT_INTERRUPT = 130 };

int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_plot(int argc, char **argv);

/* Exit code for a library status: bad input, numerical failure or internal error. */
int cli_exit_code(int status);
/* Option matching: "--name VALUE" or "--name=VALUE". Returns 1 and sets *value (advancing *i
 * past a separate value) when argv[*i] is the option; -1 when the value is missing. */
int cli_opt(int argc, char **argv, int *i, const char *name, const char **value);
/* Parse a finite number for an option; prints a message and returns -1 when it is not. */
int cli_number(const char *cmd, const char *opt, const char *text, double *out);
/* Report an unknown option with the closest known one. */
int cli_unknown(const char *cmd, const char *arg, const char *const *known);
/* The closest of words to word by edit distance, or NULL. */
const char *cli_suggest(const char *word, const char *const *words, int count);

#endif
