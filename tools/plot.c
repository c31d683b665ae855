/* appell plot: draw columns of an appell CSV file with gnuplot (docs/cli.md).
 *
 * Reads the header row, checks every requested column (with "did you mean"), writes a gnuplot
 * script to gnuplot's standard input (pngcairo or svg terminal, chosen by the extension of
 * -o) and waits for it. Columns are addressed by number in the script, so names need no
 * quoting; file names are refused if they contain a quote or a newline, and a figure whose
 * directory is missing, or that is a directory, before gnuplot runs (gnuplot would go on and
 * write the figure to its standard output, which is sent to /dev/null in any case). When the
 * CSV has a run record beside it (FILE.csv.run.json, tools/runrecord.h) saying the run did
 * not reach its end, the figure says so: a title "failed at t = ...: MESSAGE" (unless --title
 * is given) and, against t, a dashed vertical line where it stopped and one at each event.
 * Exit 2 for bad input, 1 when gnuplot is missing or fails. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"
#include "runrecord.h"

#define MAX_COLS 4096
#define MAX_Y 16

static const char help[] =
    "usage: appell plot FILE.csv [--x COL] --y COL [--y COL]... -o FIG.png|FIG.svg\n"
    "\n"
    "Draw columns of a CSV file written by appell run with gnuplot (package gnuplot-nox).\n"
    "\n"
    "options:\n"
    "  --x COL         the column on the horizontal axis (default t)\n"
    "  --y COL         a column to draw against it (repeatable, at most 16)\n"
    "  -o, --output F  the figure: F.png (pngcairo) or F.svg\n"
    "  --title TEXT    a title above the plot\n"
    "  --equal         the same scale on both axes (for paths in the plane)\n"
    "  --logy          logarithmic vertical axis (absolute values are not taken)\n"
    "  --error         draw the estimated global error of the --y columns instead, from\n"
    "                  FILE.csv.error.csv (appell run --error-estimate; log scale)\n"
    "  -h, --help      this help\n"
    "\n"
    "Exit codes: 0 success, 2 bad input (file, columns, options), 1 gnuplot missing or failed.\n";

typedef struct plot_opts {
  const char *csv, *x, *y[MAX_Y], *out, *title;
  int ny, equal, logy, error;
  char error_csv[4200];    /* --error: FILE.csv.error.csv */
  int has_record;          /* rec read from CSV.run.json */
  cli_record_info rec;
} plot_opts;

static int parse(int argc, char **argv, plot_opts *o) {
  static const char *const known[] = {"--x", "--y", "--output", "--title", "--equal", "--logy",
                                      "--help", "--error", NULL};
  for (int i = 1; i < argc; i++) {
    const char *v = NULL;
    int r = 0;
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) return 1;
    if (strcmp(argv[i], "--equal") == 0) o->equal = 1;
    else if (strcmp(argv[i], "--logy") == 0) o->logy = 1;
    else if (strcmp(argv[i], "--error") == 0) o->error = o->logy = 1;
    else if ((r = cli_opt(argc, argv, &i, "--x", &v)) != 0) o->x = v;
    else if ((r = cli_opt(argc, argv, &i, "--y", &v)) != 0) {
      if (r > 0 && o->ny >= MAX_Y)
        return fprintf(stderr, "appell plot: at most %d --y\n", MAX_Y), -1;
      if (r > 0) o->y[o->ny++] = v;
    } else if ((r = cli_opt(argc, argv, &i, "-o", &v)) != 0 ||
               (r = cli_opt(argc, argv, &i, "--output", &v)) != 0) o->out = v;
    else if ((r = cli_opt(argc, argv, &i, "--title", &v)) != 0) o->title = v;
    else if (argv[i][0] == '-' && argv[i][1]) return cli_unknown("plot", argv[i], known), -1;
    else if (!o->csv) o->csv = argv[i];
    else return fprintf(stderr, "appell plot: one CSV file at a time\n"), -1;
    if (r < 0) return cli_need("plot", argv[i], NULL);
  }
  if (!o->csv || !o->ny || !o->out)
    return fprintf(stderr, "appell plot: need FILE.csv, at least one --y and -o FIG.png|svg "
                   "(see --help)\n"), -1;
  return 0;
}

typedef struct header {
  char *line;
  const char *cols[MAX_COLS];
  int n;
} header;

static int read_header(const char *csv, header *h) {
  FILE *f = fopen(csv, "r");
  if (!f) return fprintf(stderr, "appell plot: cannot open %s: %s\n", csv, CLI_STRERROR(errno)), -1;
  size_t cap = 0, cap2 = 0;
  char *row = NULL;
  ssize_t len = getline(&h->line, &cap, f), len2 = len > 0 ? getline(&row, &cap2, f) : -1;
  int data = len2 > 0 && row[strspn(row, " \t\r\n")] != '\0';   /* a non-blank second line */
  free(row);
  fclose(f);
  if (len <= 0) return fprintf(stderr, "appell plot: %s is empty (0 bytes)\n", csv), -1;
  if (!data)   /* gnuplot would fail on it and leave an empty figure */
    return fprintf(stderr, "appell plot: %s has a header but no data rows: nothing to draw\n",
                   csv), -1;
  h->line[strcspn(h->line, "\r\n")] = '\0';
  for (char *p = strtok(h->line, ","); p && h->n < MAX_COLS; p = strtok(NULL, ","))
    h->cols[h->n++] = p;
  return 0;
}

/* 1-based column number of name, or 0 with a message. */
static int column(const header *h, const char *csv, const char *name) {
  for (int i = 0; i < h->n; i++)
    if (strcmp(h->cols[i], name) == 0) return i + 1;
  const char *s = cli_suggest(name, h->cols, h->n);
  fprintf(stderr, "appell plot: %s has no column '%s'%s%s%s\n", csv, name,
          s ? " (did you mean '" : "", s ? s : "", s ? "'?)" : "");
  return 0;
}

/* text (at most max bytes) as a gnuplot string in double quotes: a double quote becomes a
 * single one, a backslash or a control character a space. */
static void quoted(FILE *g, const char *text, size_t max) {
  fputc('"', g);
  for (size_t i = 0; text[i] && i < max; i++)
    fputc(text[i] == '"' ? '\'' : text[i] == '\\' || (unsigned char)text[i] < 0x20 ? ' '
                                                                                   : text[i], g);
  fputs(max < strlen(text) ? "...\"" : "\"", g);
}

/* What the run record adds: how a run that did not reach t_end ended, and its events. */
static void record_marks(FILE *g, const plot_opts *o) {
  const cli_record_info *r = &o->rec;
  int stopped = strcmp(r->status, CLI_STATUS_OK) != 0, against_t = strcmp(o->x, "t") == 0;
  if (stopped && !o->title) {   /* "failed at t = 4.12715", then the cause on a second line */
    const char *m = strncmp(r->message, "appell run: ", 12) == 0 ? r->message + 12 : r->message;
    const char *at = strstr(m, " at t = "), *cause = at ? strstr(at, ": ") : NULL;
    m = cause ? cause + 2 : m;
    fprintf(g, "set title \"%s at t = %.6g\\n\" . ", r->status, r->t);
    quoted(g, m, 100);
    fputs(" font ',10'\n", g);
  }
  if (stopped && against_t)
    fprintf(g, "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 2 lw 2 lc rgb "
            "'#c00000'\n", r->t, r->t);
  for (int i = 0; against_t && i < r->nevents; i++) {
    fprintf(g, "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 3 lc rgb '#606060'\n",
            r->event_t[i], r->event_t[i]);
    fprintf(g, "set label %d ", i + 1);
    quoted(g, r->event_name[i], 40);
    fprintf(g, " at %.17g, graph 0.97 rotate by 90 right font ',9'\n", r->event_t[i]);
  }
}

static void script(FILE *g, const plot_opts *o, int xc, const int *yc) {
  const char *ext = strrchr(o->out, '.');
  int svg = ext && strcmp(ext, ".svg") == 0;
  fprintf(g, "set terminal %s size 900,600 noenhanced\n", svg ? "svg" : "pngcairo");
  fprintf(g, "set output '%s'\nset datafile separator ','\nset grid\nset key outside bottom "
          "center horizontal\n", o->out);
  fprintf(g, "set xlabel '%s'\n", o->x);
  if (o->ny == 1) fprintf(g, "set ylabel '%s'\nset key off\n", o->y[0]);
  if (o->title) fprintf(g, "set title '%s'\n", o->title);
  else if (o->error) fprintf(g, "set title 'estimated global error (appell run --error-estimate)'\n");
  if (o->equal) fprintf(g, "set size ratio -1\n");
  if (o->logy) fprintf(g, "set logscale y\nset format y '%%.0e'\n");
  if (o->has_record) record_marks(g, o);
  fprintf(g, "plot ");
  for (int i = 0; i < o->ny; i++)
    fprintf(g, "%s'%s' skip 1 using %d:%d with lines lw 2 title '%s'", i ? ", " : "", o->csv, xc,
            yc[i], o->y[i]);
  fprintf(g, "\n");
}

typedef struct plot_job {
  const plot_opts *o;
  int xc;
  const int *yc;
} plot_job;

static void plot_script(FILE *g, const void *user) {
  const plot_job *j = user;
  script(g, j->o, j->xc, j->yc);
}

/* The figure's directory exists and the figure is not a directory; else a message, exit 2. */
static int check_figure(const char *out) {
  struct stat st;
  if (stat(out, &st) == 0 && S_ISDIR(st.st_mode))
    return fprintf(stderr, "appell plot: -o %s: is a directory\n", out), EXIT_INPUT;
  char dir[4096];
  const char *slash = strrchr(out, '/');
  size_t len = slash ? (size_t)(slash - out) : 0;
  if (len >= sizeof dir) return EXIT_OK;
  snprintf(dir, sizeof dir, "%.*s", (int)len, out);
  if (slash && len == 0) snprintf(dir, sizeof dir, "/");
  if (slash && (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)))
    return fprintf(stderr, "appell plot: -o %s: no such directory '%s'\n", out, dir),
           EXIT_INPUT;
  return EXIT_OK;
}

/* --error: the columns of FILE.csv.error.csv (same header as FILE.csv) instead. */
static int use_error_csv(plot_opts *o, header *h) {
  if ((size_t)snprintf(o->error_csv, sizeof o->error_csv, "%s.error.csv", o->csv) >=
      sizeof o->error_csv)
    return fprintf(stderr, "appell plot: %s: the path is too long\n", o->csv), EXIT_INPUT;
  if (access(o->error_csv, R_OK) != 0)
    return fprintf(stderr, "appell plot: --error: no %s: run appell run SCENE --out %s "
                   "--error-estimate first\n", o->error_csv, o->csv), EXIT_INPUT;
  free(h->line);
  *h = (header){0};
  o->csv = o->error_csv;
  return read_header(o->csv, h) == 0 ? EXIT_OK : EXIT_INPUT;
}

int cmd_plot(int argc, char **argv) {
  plot_opts o = {.x = "t"};
  int rc = parse(argc, argv, &o);
  if (rc != 0) return rc > 0 ? (fputs(help, stdout), EXIT_OK) : EXIT_INPUT;
  const char *ext = strrchr(o.out, '.');
  if (!ext || (strcmp(ext, ".png") != 0 && strcmp(ext, ".svg") != 0))
    return fprintf(stderr, "appell plot: -o %s: the figure must end in .png or .svg\n", o.out),
           EXIT_INPUT;
  if (!cli_safe_name(o.csv) || !cli_safe_name(o.out) || (o.title && !cli_safe_name(o.title)))
    return fprintf(stderr, "appell plot: file names and titles must not contain quotes, "
                   "backslashes or newlines\n"), EXIT_INPUT;
  if (check_figure(o.out) != EXIT_OK) return EXIT_INPUT;
  header h = {0};
  int code = read_header(o.csv, &h) == 0 ? EXIT_OK : EXIT_INPUT;
  char record[4200];
  if ((size_t)snprintf(record, sizeof record, "%s.run.json", o.csv) < sizeof record)
    o.has_record = cli_record_read(record, &o.rec) == 0;
  if (code == EXIT_OK && o.error) code = use_error_csv(&o, &h);
  int xc = code == EXIT_OK ? column(&h, o.csv, o.x) : 0, yc[MAX_Y];
  if (code == EXIT_OK && !xc) code = EXIT_INPUT;
  for (int i = 0; code == EXIT_OK && i < o.ny; i++)
    if (!(yc[i] = column(&h, o.csv, o.y[i]))) code = EXIT_INPUT;
  plot_job job = {&o, xc, yc};
  if (code == EXIT_OK && cli_gnuplot("plot", plot_script, &job) != 0) code = EXIT_INTERNAL;
  if (code == EXIT_OK) printf("%s\n", o.out);
  free(h.line);
  return code;
}
