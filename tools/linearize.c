/* appell linearize: operating point, linearization, eigenvalues and speed sweeps of a scene
 * (docs/linearize.md, docs/cli.md).
 *
 * Flow: load the scene (--set overrides), read its linearize: section; the guess of the
 * operating point is the scene's initial state with linearize.initial applied, and the speed
 * parameter's direction in the model speeds comes from two more loads with the speed keys at
 * 0 and at their coefficients (the scene's initial state is linear in the rates). One point:
 * Newton, A and B with Ridders' error estimates, cyclic states, eigenvalues of the subsystem.
 * --sweep speed=A:B:N: the same at N speeds (continuation) with eigenvalues tracked and the
 * characteristic speeds located; --sweep PATH=A:B:N sweeps a scalar of the scene instead (one
 * reload per value). Output: text on stdout; --csv the eigenvalues (one row per point);
 * --plot real and imaginary parts against the parameter with gnuplot (linplot.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "cli.h"
#include "linearize.h"

static const char help[] =
    "usage: appell linearize SCENE [OPTIONS]\n"
    "\n"
    "Find SCENE's operating point (an equilibrium or a steady motion), linearize its reduced\n"
    "equations there and print the state and input matrices, the cyclic coordinates and the\n"
    "eigenvalues with their condition numbers; with --sweep, follow the eigenvalues over the\n"
    "speed (or a scene parameter) and locate where a real part crosses zero and where two\n"
    "real eigenvalues meet. The scene's linearize: section says how (docs/linearize.md).\n"
    "\n"
    "options:\n"
    "  --about steady|equilibrium   the operating point (default: the scene's, else steady)\n"
    "  --speed V           the speed parameter (needs linearize.speed in the scene)\n"
    "  --sweep speed=A:B:N sweep the speed over N values from A to B (inclusive)\n"
    "  --sweep PATH=A:B:N  sweep a scalar of the scene instead, e.g. bodies.disk.mass=1:2:11\n"
    "  --sweep NAME=A:B:N  sweep a parameter of the scene (parameters.NAME), e.g. trail=0.05:0.15:21\n"
    "  --states A,B,...    report the subsystem of these states (it must be closed)\n"
    "  --free A,B,...      state variables the Newton may move (steady motions)\n"
    "  --inputs A,B,...    model speeds receiving an input force or torque (columns of B)\n"
    "  --keep-cyclic       keep the cyclic coordinates in the eigenvalue problem\n"
    "  --derivatives complex-step|ridders   how A is differentiated (default: complex step,\n"
    "                      exact to round-off, where the model allows it; else Ridders')\n"
    "  --csv FILE          write the eigenvalues as CSV (a sweep: one row per value)\n"
    "  --plot FIG.png|svg  draw real and imaginary parts against the swept parameter\n"
    "  --yrange A:B        the plot's vertical range (default: all eigenvalues)\n"
    "  --set PATH=VALUE    override a scalar of the scene (repeatable)\n"
    "  -h, --help          this help\n"
    "\n"
    "Exit codes: 0 success, 2 bad input or no operating point, 3 numerical failure,\n"
    "1 internal error.\n";

/* Split "a,b,c" into a NULL-terminated list (pointers into a copy). */
static char **split(const char *text) {
  size_t n = 1, len = strlen(text);
  for (const char *p = text; *p; p++) n += *p == ',';
  char **out = malloc((n + 1) * sizeof *out + len + 1);
  if (!out) return NULL;
  char *s = memcpy((char *)(out + n + 1), text, len + 1);
  size_t i = 0;
  for (char *t = strtok(s, ","); t; t = strtok(NULL, ",")) out[i++] = t;
  out[i] = NULL;
  return out;
}

static int parse_sweep(const char *v, lin_opts *o) {
  const char *eq = strchr(v, '=');
  if (!eq || eq == v) return -1;
  size_t len = (size_t)(eq - v);
  /* A bare name other than speed is a parameter: trail=A:B:N sweeps parameters.trail. */
  const char *pre = memchr(v, '.', len) || (len == 5 && !strncmp(v, "speed", 5))
                        ? "" : "parameters.";
  if (strlen(pre) + len >= sizeof o->sweep_path) return -1;
  snprintf(o->sweep_path, sizeof o->sweep_path, "%s%.*s", pre, (int)len, v);
  char *end = NULL;
  o->from = strtod(eq + 1, &end);
  if (*end != ':') return -1;
  o->to = strtod(end + 1, &end);
  if (*end != ':') return -1;
  long n = strtol(end + 1, &end, 10);
  if (*end || n < 2 || n > 100000 || !(o->to > o->from) || !isfinite(o->from) ||
      !isfinite(o->to))
    return -1;
  o->count = (int)n;
  return 0;
}

static int parse_yrange(const char *v, lin_opts *o) {
  char *end = NULL;
  o->ymin = strtod(v, &end);
  if (end == v || *end != ':') return -1;
  const char *b = end + 1;
  o->ymax = strtod(b, &end);
  if (end == b || *end || !isfinite(o->ymin) || !isfinite(o->ymax) || !(o->ymax > o->ymin))
    return -1;
  o->has_yrange = 1;
  return 0;
}

static int list_opt(char ***dst, const char *v) {
  free(*dst);
  *dst = split(v);
  return *dst ? 0 : (fprintf(stderr, "appell linearize: out of memory\n"), -1);
}

static int parse(int argc, char **argv, lin_opts *o) {
  static const char *const known[] = {"--about", "--speed", "--sweep", "--states", "--free",
                                      "--inputs", "--keep-cyclic", "--derivatives", "--csv",
                                      "--plot", "--yrange", "--set", "--help", NULL};
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r = 0;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) return 1;
    if (strcmp(argv[i], "--keep-cyclic") == 0) o->keep_cyclic = 1;
    else if ((r = cli_opt(argc, argv, &i, "--about", &v)) > 0) {
      if (strcmp(v, "steady") && strcmp(v, "equilibrium"))
        return fprintf(stderr, "appell linearize: --about steady or equilibrium, not '%s'\n",
                       v), -1;
      o->about = strcmp(v, "steady") == 0 ? 0 : 1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--speed", &v)) > 0) {
      if (cli_number("linearize", "--speed", v, &o->speed)) return -1;
      o->has_speed = 1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--sweep", &v)) > 0) {
      if (parse_sweep(v, o))
        return fprintf(stderr, "appell linearize: --sweep %s: expected NAME=FROM:TO:COUNT with "
                       "FROM < TO and 2 <= COUNT <= 100000, e.g. speed=0:10:101\n", v), -1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--states", &v)) > 0) {
      if (list_opt(&o->states, v)) return -1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--free", &v)) > 0) {
      if (list_opt(&o->free, v)) return -1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--inputs", &v)) > 0) {
      if (list_opt(&o->inputs, v)) return -1;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--derivatives", &v)) > 0) {
      if (strcmp(v, "complex-step") && strcmp(v, "ridders"))
        return fprintf(stderr, "appell linearize: --derivatives complex-step or ridders, not "
                       "'%s'\n", v), -1;
      o->method = strcmp(v, "ridders") == 0 ? AP_LIN_RIDDERS : AP_LIN_COMPLEX_STEP;
    } else if (r == 0 && (r = cli_opt(argc, argv, &i, "--csv", &v)) > 0) o->csv = v;
    else if (r == 0 && (r = cli_opt(argc, argv, &i, "--plot", &v)) > 0) o->plot = v;
    else if (r == 0 && (r = cli_opt(argc, argv, &i, "--yrange", &v)) > 0) {
      if (parse_yrange(v, o))
        return fprintf(stderr, "appell linearize: --yrange %s: expected A:B with A < B, e.g. "
                       "-10:10\n", v), -1;
    }
    else if (r == 0 && (r = cli_opt(argc, argv, &i, "--set", &v)) > 0) {
      if (o->nsets >= LIN_MAX_SETS)
        return fprintf(stderr, "appell linearize: at most %d --set\n", LIN_MAX_SETS), -1;
      o->sets[o->nsets++] = v;
    } else if (r == 0 && argv[i][0] == '-' && argv[i][1]) {
      return cli_unknown("linearize", argv[i], known), -1;
    } else if (r == 0 && !o->scene) {
      o->scene = argv[i];
    } else if (r == 0) {
      return fprintf(stderr, "appell linearize: one scene at a time\n"), -1;
    }
    if (r < 0) return cli_need("linearize", argv[i], NULL);
  }
  if (!o->scene) return fprintf(stderr, "appell linearize: no scene file (see --help)\n"), -1;
  if (o->plot && !o->count)
    return fprintf(stderr, "appell linearize: --plot draws a sweep: give --sweep\n"), -1;
  if (o->has_yrange && !o->plot)
    return fprintf(stderr, "appell linearize: --yrange sets the range of --plot's figure\n"), -1;
  return 0;
}

void lin_opts_free(lin_opts *o) {
  free(o->states), free(o->free), free(o->inputs);
}

int cmd_linearize(int argc, char **argv) {
  lin_opts o;
  memset(&o, 0, sizeof o);
  o.about = -1;
  int rc = parse(argc, argv, &o);
  if (rc != 0) {
    lin_opts_free(&o);
    return rc > 0 ? (fputs(help, stdout), EXIT_OK) : EXIT_INPUT;
  }
  int code = lin_run(&o);
  lin_opts_free(&o);
  return code;
}
