/* appell view: one self-contained HTML page that shows a run in 3-D (docs/viewer.md).
 *
 *   appell view SCENE --run FILE.csv --out FILE.html     a run written before
 *   appell view SCENE [run options] --out FILE.html       runs the scene first (appell run) and
 *                                                         keeps its CSV as FILE.csv
 *
 * The poses come from the CSV's coordinates through the scene's model (view_frames.c); the run
 * record FILE.run.json next to the CSV (events, status), when present, goes into the page. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "view.h"

#define VIEW_MAX_ARGS 64

typedef struct view_opts {
  const char *scene, *run, *out, *title, *record;
  const char *sets[VIEW_MAX_ARGS];
  int nsets;
  const char *plots[VIEW_MAX_ARGS];
  int nplots;
  char *run_args[2 * VIEW_MAX_ARGS + 16];   /* the options passed on to appell run */
  int nrun;
  int forces;
} view_opts;

static const char usage[] =
    "usage: appell view SCENE [--run FILE.csv | RUN OPTIONS] --out FILE.html [options]\n"
    "\n"
    "Write one self-contained HTML page (three.js inlined, the run embedded, no network) that\n"
    "plays the run in 3-D with plots beside it. Without --run the scene is run first (as by\n"
    "appell run, with the same run options) and its CSV kept as FILE.csv.\n"
    "\n"
    "options:\n"
    "  --run FILE.csv   a CSV of appell run with the coordinates channel\n"
    "  --out FILE.html  the page to write (required)\n"
    "  --plot NAME      a CSV column to plot beside the 3-D view (repeatable, or a,b,c);\n"
    "                   default energy_error and the tilt angles when present\n"
    "  --forces         draw the contact forces as arrows (needs the contact_forces channel)\n"
    "  --record FILE    the run record (default FILE.run.json next to the CSV, if present)\n"
    "  --title TEXT     the page's title (default the scene's name)\n"
    "  --set PATH=VALUE scene override (as appell run)\n"
    "  --mode, --method, --rtol, --atol, --t-end, --interval, --path: run options (no --run)\n";

static const char *const run_opts_known[] = {"--mode", "--method", "--rtol", "--atol",
                                             "--t-end", "--interval", "--path", NULL};

static int add_list(const char **list, int *n, const char *v) {
  if (*n >= VIEW_MAX_ARGS) {
    fprintf(stderr, "appell view: at most %d values of an option\n", VIEW_MAX_ARGS);
    return -1;
  }
  list[(*n)++] = v;
  return 0;
}

static int run_opt(int argc, char **argv, int *i, view_opts *o) {
  for (int k = 0; run_opts_known[k]; k++) {
    const char *v = NULL;
    int r = cli_opt(argc, argv, i, run_opts_known[k], &v);
    if (r == 0) continue;
    if (r < 0) return cli_need("view", run_opts_known[k], NULL);
    o->run_args[o->nrun++] = (char *)run_opts_known[k];
    o->run_args[o->nrun++] = (char *)v;
    return 1;
  }
  return 0;
}

static int value_opt(int argc, char **argv, int *i, view_opts *o) {
  static const char *const names[] = {"--run", "--out", "--title", "--record", "--set", "--plot"};
  for (int k = 0; k < 6; k++) {
    const char *v = NULL;
    int r = cli_opt(argc, argv, i, names[k], &v);
    if (r == 0) continue;
    if (r < 0) return cli_need("view", names[k], NULL);
    const char **dst[] = {&o->run, &o->out, &o->title, &o->record};
    if (k < 4) *dst[k] = v;
    else if (k == 4) return add_list(o->sets, &o->nsets, v) ? -1 : 1;
    else   /* "a,b,c": split in place (argv is writable) */
      for (char *save = NULL, *tok = strtok_r((char *)v, ",", &save); tok;
           tok = strtok_r(NULL, ",", &save))
        if (add_list(o->plots, &o->nplots, tok)) return -1;
    return 1;
  }
  return 0;
}

static int parse(int argc, char **argv, view_opts *o) {
  static const char *const known[] = {"--run", "--out", "--plot", "--forces", "--record",
                                      "--title", "--set", "--mode", "--method", "--rtol",
                                      "--atol", "--t-end", "--interval", "--path", "--help",
                                      NULL};
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      fputs(usage, stdout);
      return 1;
    }
    if (strcmp(argv[i], "--forces") == 0) {
      o->forces = 1;
      continue;
    }
    int r = value_opt(argc, argv, &i, o);
    if (r == 0) r = run_opt(argc, argv, &i, o);
    if (r < 0) return -1;
    if (r > 0) continue;
    if (argv[i][0] == '-' && argv[i][1]) return cli_unknown("view", argv[i], known), -1;
    if (o->scene) {
      fprintf(stderr, "appell view: one scene only (got '%s' and '%s')\n", o->scene, argv[i]);
      return -1;
    }
    o->scene = argv[i];
  }
  if (!o->scene || !o->out) {
    fprintf(stderr, "appell view: %s\n%s", !o->scene ? "no scene given" : "--out is required",
            usage);
    return -1;
  }
  if (o->run && o->nrun) {
    fprintf(stderr, "appell view: %s is a run option: give it to appell run, or drop --run\n",
            o->run_args[0]);
    return -1;
  }
  return 0;
}

/* FILE.EXT -> FILE + suffix (the extension replaced), malloc'd. */
static char *view_sibling(const char *path, const char *suffix) {
  const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
  size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - path) : strlen(path);
  char *s = malloc(stem + strlen(suffix) + 1);
  if (s) memcpy(s, path, stem), strcpy(s + stem, suffix);
  return s;
}

/* Run the scene through appell run into csv, with the coordinates channel added. */
static int run_scene(ap_scene *sc, view_opts *o, const char *csv) {
  char channels[1024] = "output.channels=[coordinates";
  for (int i = 0; i < ap_scene_count(sc, AP_SCENE_CHANNELS); i++) {
    const char *ch = ap_scene_element_name(sc, AP_SCENE_CHANNELS, i);
    if (strcmp(ch, "coordinates") != 0 && strlen(channels) + strlen(ch) + 4 < sizeof channels)
      strcat(strcat(channels, ", "), ch);
  }
  strcat(channels, "]");
  char *argv[2 * VIEW_MAX_ARGS + 64];
  int argc = 0;
  argv[argc++] = "run";
  argv[argc++] = (char *)o->scene;
  for (int i = 0; i < o->nsets; i++) argv[argc++] = "--set", argv[argc++] = (char *)o->sets[i];
  for (int i = 0; i < o->nrun; i++) argv[argc++] = o->run_args[i];
  argv[argc++] = "--set", argv[argc++] = channels;
  argv[argc++] = "--out", argv[argc++] = (char *)csv;
  argv[argc++] = "--quiet";
  argv[argc] = NULL;
  return cmd_run(argc, argv);
}

/* The whole text of a file, or NULL (quietly: the record is optional). */
static char *view_slurp(const char *path) {
  FILE *f = path ? fopen(path, "rb") : NULL;
  if (!f) return NULL;
  size_t cap = 4096, len = 0, got;
  char *s = malloc(cap);
  while (s && (got = fread(s + len, 1, cap - len - 1, f)) > 0) {
    len += got;
    char *t = len + 1 >= cap ? realloc(s, cap *= 2) : s;
    if (!t) free(s);
    s = t;
  }
  fclose(f);
  if (s) s[len] = '\0';
  return s;
}

static int check_plots(const view_opts *o, const view_csv *csv) {
  for (int i = 0; i < o->nplots; i++)
    if (view_csv_column(csv, o->plots[i]) < 0) {
      const char *s = cli_suggest(o->plots[i], (const char *const *)csv->names, csv->ncols);
      fprintf(stderr, "appell view: --plot %s: no such column in the CSV%s%s%s\n", o->plots[i],
              s ? " (did you mean '" : "", s ? s : "", s ? "'?)" : "");
      return EXIT_INPUT;
    }
  return EXIT_OK;
}

/* Default plots: energy_error and each BODY.tilt column (at most 4 in all). */
static void default_plots(view_opts *o, const view_csv *csv) {
  for (int i = 0; i < csv->ncols && o->nplots < 4; i++) {
    const char *n = csv->names[i];
    size_t len = strlen(n);
    if (strcmp(n, "energy_error") == 0 || (len > 5 && strcmp(n + len - 5, ".tilt") == 0))
      o->plots[o->nplots++] = n;
  }
}

static int write_page(const view_opts *o, const view_frames *f, const view_csv *csv,
                      const char *record) {
  view_page p = {o->title, o->plots, o->nplots, record, o->forces};
  cli_out out;
  cli_out_command("view");
  int rc = cli_out_check(&out, o->out, o->scene);
  if (rc == EXIT_OK) rc = cli_out_open(&out);
  if (rc != EXIT_OK) return rc;
  if (view_write_page(out.f, f, csv, &p) != 0 && !out.err) out.err = EIO;
  return cli_out_close(&out, EXIT_OK);
}

static int view_run(view_opts *o, ap_scene *sc) {
  char *csv_path = o->run ? NULL : view_sibling(o->out, ".csv");
  const char *csv_name = o->run ? o->run : csv_path;
  int rc = csv_name ? EXIT_OK : EXIT_INTERNAL;
  if (rc == EXIT_OK && !o->run) rc = run_scene(sc, o, csv_name);
  view_csv csv = {0};
  view_frames f = {0};
  if (rc == EXIT_OK) rc = view_csv_read("view", csv_name, &csv);
  if (rc == EXIT_OK) rc = view_frames_build("view", sc, &csv, &f);
  if (rc == EXIT_OK) rc = check_plots(o, &csv);
  if (rc == EXIT_OK && o->nplots == 0) default_plots(o, &csv);
  char *rec_path = o->record ? NULL : view_sibling(csv_name, ".run.json");
  char *record = view_slurp(o->record ? o->record : rec_path);
  if (o->record && !record && rc == EXIT_OK) {
    fprintf(stderr, "appell view: cannot read the run record %s\n", o->record);
    rc = EXIT_INPUT;
  }
  if (rc == EXIT_OK) rc = write_page(o, &f, &csv, record);
  if (rc == EXIT_OK)
    fprintf(stderr, "appell view: wrote %s (%ld frames, %d bodies); open it in a browser\n",
            o->out, f.nf, f.nb);
  free(record);
  free(rec_path);
  view_frames_free(&f);
  view_csv_free(&csv);
  free(csv_path);
  return rc;
}

int cmd_view(int argc, char **argv) {
  view_opts o;
  memset(&o, 0, sizeof o);
  int r = parse(argc, argv, &o);
  if (r) return r > 0 ? EXIT_OK : EXIT_INPUT;
  char msg[1024] = "";
  ap_scene *sc = NULL;
  int st = ap_scene_load(o.scene, o.sets, o.nsets, &sc, msg, sizeof msg);
  if (st != AP_OK) {
    fprintf(stderr, "appell view: %s\n", msg);
    return cli_exit_code(st);
  }
  int rc = view_run(&o, sc);
  ap_scene_free(sc);
  return rc;
}
