/* appell: the command-line tool. `appell run`, `check`, `plot` and `bench` (docs/cli.md).
 *
 * This file dispatches to the subcommands and holds their shared helpers: option matching
 * ("--opt VALUE" and "--opt=VALUE"), numbers, "did you mean" for unknown options, and the map
 * from library status codes to exit codes. Public API only (<appell/appell.h>). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "cli.h"

int cmd_bench(int argc, char **argv);   /* tools/bench.c */
int cmd_linearize(int argc, char **argv);   /* tools/linearize.c */
int cmd_sweep(int argc, char **argv);   /* tools/sweep.c */
int cmd_view(int argc, char **argv);   /* tools/view.c */
int cmd_export(int argc, char **argv);   /* tools/export_gltf.c */
int cmd_import(int argc, char **argv);   /* tools/import.c */

static const char usage[] =
    "usage: appell COMMAND [OPTIONS]\n"
    "\n"
    "Simulate mechanical systems with nonholonomic constraints described in scene files.\n"
    "\n"
    "commands:\n"
    "  run SCENE     simulate a scene and write its outputs as CSV\n"
    "  check SCENE   validate a scene and print its structure (n, k, b, rank, l, ...)\n"
    "  plot CSV      draw columns of a CSV file with gnuplot into a PNG or SVG file\n"
    "  bench SCENE   work-precision sweep of a scene against its own tight reference\n"
    "  linearize SCENE  operating point, linearization, eigenvalues, speed sweeps\n"
    "  sweep SCENE   run a scene over grids or random samples of its values, one CSV row a run\n"
    "  view SCENE    write a self-contained HTML page that plays a run in 3-D, with plots\n"
    "  export SCENE  write a run as a glTF 2.0 binary (.glb): meshes and their animation\n"
    "  import URDF   convert a URDF robot description into a scene file\n"
    "\n"
    "`appell COMMAND --help` describes each command. Exit codes: 0 success, 2 bad input,\n"
    "3 numerical failure, 1 internal error or failed write, 128 + N stopped by signal N.\n"
    "Scenes: docs/scenes.md; the tool: docs/cli.md.\n";

int cli_exit_code(int status) {
  switch (status) {
    case AP_OK: return EXIT_OK;
    case AP_ERR_ARG:
    case AP_ERR_INCONSISTENT:
    case AP_ERR_RANK:
    case AP_ERR_UNSUPPORTED: return EXIT_INPUT;
    case AP_ERR_CALLBACK:
    case AP_ERR_NAN:
    case AP_ERR_SINGULAR:
    case AP_ERR_SOLVER:
    case AP_RECOVERABLE: return EXIT_NUMERIC;
    default: return EXIT_INTERNAL;
  }
}

/* The separate value that cli_opt refused because it looked like an option, or NULL. */
static const char *refused_value;

/* "-o", "--out": a word that starts with '-' and is not "-" (standard output) or a number
 * ("-1", "-.5", "-2*pi"). */
static int looks_like_option(const char *v) {
  return v[0] == '-' && v[1] != '\0' && !(v[1] >= '0' && v[1] <= '9') && v[1] != '.';
}

int cli_opt(int argc, char **argv, int *i, const char *name, const char **value) {
  size_t len = strlen(name);
  const char *a = argv[*i];
  if (strncmp(a, name, len) != 0) return 0;
  refused_value = NULL;
  if (a[len] == '=') {
    *value = a + len + 1;
    return 1;
  }
  if (a[len] != '\0') return 0;
  if (*i + 1 >= argc) return -1;
  if (looks_like_option(argv[*i + 1])) {   /* "--mode -o out.csv": -o is not the mode */
    refused_value = argv[*i + 1];
    return -1;
  }
  *value = argv[++*i];
  return 1;
}

int cli_need(const char *cmd, const char *opt, const char *what) {
  if (refused_value)
    fprintf(stderr, "appell %s: %s needs %s; got the option %s (write %s=%s if that is the "
            "value)\n", cmd, opt, what ? what : "a value", refused_value, opt, refused_value);
  else
    fprintf(stderr, "appell %s: %s needs %s (see appell %s --help)\n", cmd, opt,
            what ? what : "a value", cmd);
  return -1;
}

int cli_number(const char *cmd, const char *opt, const char *text, double *out) {
  char *end = NULL;
  double x = strtod(text, &end);
  if (end == text || *end != '\0' || !isfinite(x)) {
    fprintf(stderr, "appell %s: %s: expected a number, got '%s'\n", cmd, opt, text);
    return -1;
  }
  *out = x;
  return 0;
}

const char *cli_suggest(const char *word, const char *const *words, int count) {
  return ap_suggest(word, words, count);
}

int cli_unknown(const char *cmd, const char *arg, const char *const *known) {
  char opt[64];
  snprintf(opt, sizeof opt, "%.*s", (int)strcspn(arg, "="), arg);
  int count = 0;
  while (known[count]) count++;
  const char *s = cli_suggest(opt, known, count);
  if (s)
    fprintf(stderr, "appell %s: unknown option '%s' (did you mean '%s'?)\n", cmd, opt, s);
  else
    fprintf(stderr, "appell %s: unknown option '%s' (see appell %s --help)\n", cmd, opt, cmd);
  return EXIT_INPUT;
}

/* What the command printed must have reached standard output: a full disk or a closed pipe
 * is an I/O failure (exit 1), not a silent success. */
static int finish(int code) {
  if (fflush(stdout) == 0 && !ferror(stdout)) return code;
  if (errno != EPIPE) fprintf(stderr, "appell: writing standard output failed: %s\n",
                              CLI_STRERROR(errno ? errno : EIO));
  return code == EXIT_OK ? EXIT_INTERNAL : code;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fputs(usage, stderr);
    return EXIT_INPUT;
  }
  const char *cmd = argv[1];
  if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
    fputs(usage, stdout);
    return finish(EXIT_OK);
  }
  if (strcmp(cmd, "--version") == 0) {
    printf("appell %s\n", AP_VERSION_STRING);
    return finish(EXIT_OK);
  }
  if (strcmp(cmd, "run") == 0) return finish(cmd_run(argc - 1, argv + 1));
  if (strcmp(cmd, "check") == 0) return finish(cmd_check(argc - 1, argv + 1));
  if (strcmp(cmd, "plot") == 0) return finish(cmd_plot(argc - 1, argv + 1));
  if (strcmp(cmd, "bench") == 0) return finish(cmd_bench(argc - 1, argv + 1));
  if (strcmp(cmd, "linearize") == 0) return finish(cmd_linearize(argc - 1, argv + 1));
  if (strcmp(cmd, "sweep") == 0) return finish(cmd_sweep(argc - 1, argv + 1));
  if (strcmp(cmd, "view") == 0) return finish(cmd_view(argc - 1, argv + 1));
  if (strcmp(cmd, "export") == 0) return finish(cmd_export(argc - 1, argv + 1));
  if (strcmp(cmd, "import") == 0) return finish(cmd_import(argc - 1, argv + 1));
  static const char *const cmds[] = {"run", "check", "plot", "bench", "linearize", "sweep", "view",
                                     "export", "import"};
  const char *s = cli_suggest(cmd, cmds, 9);
  fprintf(stderr, "appell: unknown command '%s'%s%s%s (see appell --help)\n", cmd,
          s ? " (did you mean '" : "", s ? s : "", s ? "'?)" : "");
  return EXIT_INPUT;
}
