/* appell sweep --merge: join the CSV files of the shards of one sweep (docs/sweeps.md).
 *
 * Every file must have the same header (starting run,runs), every row must end with a line
 * break, and together the rows must hold each run 0 .. runs - 1 of the plan exactly once
 * (runs is the plan's size, written in every row). The rows are copied byte for byte in run
 * order into the output, which is written atomically; anything missing, duplicated or
 * inconsistent is reported with the file and the runs concerned, and nothing is written. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "sweep.h"

typedef struct shard_file {
  const char *name;
  char *text;
  size_t len;
} shard_file;

typedef struct merge_state {
  shard_file *files;
  int nfiles;
  const char **rows;       /* (runs) the start of each run's line, or NULL */
  int *owner;              /* (runs) the file index of each row */
  long runs;
} merge_state;

void sweep_csv_quote(FILE *f, const char *text) {
  fputc('"', f);
  for (const char *c = text; *c; c++) {
    if (*c == '"') fputc('"', f);
    fputc(*c == '\n' || *c == '\r' ? ' ' : *c, f);
  }
  fputc('"', f);
}

static int read_file(shard_file *sf) {
  FILE *f = fopen(sf->name, "rb");
  if (!f) return fprintf(stderr, "appell sweep: %s: cannot open: %s\n", sf->name, strerror(errno)), -1;
  size_t cap = 1 << 16;
  sf->text = malloc(cap + 1);
  while (sf->text) {
    sf->len += fread(sf->text + sf->len, 1, cap - sf->len, f);
    if (sf->len < cap) break;
    char *t = realloc(sf->text, 2 * cap + 1);
    if (!t) free(sf->text);
    sf->text = t, cap *= 2;
  }
  int bad = ferror(f);
  fclose(f);
  if (!sf->text || bad)
    return fprintf(stderr, "appell sweep: %s: %s\n", sf->name, bad ? "read error" : "out of memory"), -1;
  sf->text[sf->len] = '\0';
  if (sf->len && sf->text[sf->len - 1] != '\n')
    return fprintf(stderr, "appell sweep: %s: the last line is incomplete\n", sf->name), -1;
  return 0;
}

static size_t line_len(const char *s) { return strcspn(s, "\n"); }

/* The header of every file must equal the first file's. */
static int check_header(const merge_state *m) {
  const char *h0 = m->files[0].text;
  size_t l0 = line_len(h0);
  if (strncmp(h0, "run,runs,", 9) != 0)
    return fprintf(stderr, "appell sweep: %s: not a table of appell sweep (the header starts "
                   "with run,runs)\n", m->files[0].name), -1;
  for (int i = 1; i < m->nfiles; i++) {
    const char *h = m->files[i].text;
    if (line_len(h) != l0 || strncmp(h, h0, l0) != 0)
      return fprintf(stderr, "appell sweep: %s: its header differs from %s's (another scene or "
                     "other parameters)\n", m->files[i].name, m->files[0].name), -1;
  }
  return 0;
}

/* Place the rows of file i by their run index. */
static int place_rows(merge_state *m, int i) {
  const shard_file *sf = &m->files[i];
  const char *s = sf->text + line_len(sf->text) + 1;
  for (long line = 2; s < sf->text + sf->len; line++, s += line_len(s) + 1) {
    char *end = NULL, *end2 = NULL;
    long run = strtol(s, &end, 10), runs = *end == ',' ? strtol(end + 1, &end2, 10) : -1;
    if (end == s || !end2 || *end2 != ',' || runs < 1 || run < 0 || run >= runs)
      return fprintf(stderr, "appell sweep: %s:%ld: expected run,runs,... at the start of the "
                     "row\n", sf->name, line), -1;
    if (!m->rows) {
      m->runs = runs;
      m->rows = calloc((size_t)runs, sizeof *m->rows);
      m->owner = calloc((size_t)runs, sizeof *m->owner);
      if (!m->rows || !m->owner) return fprintf(stderr, "appell sweep: out of memory\n"), -1;
    }
    if (runs != m->runs)
      return fprintf(stderr, "appell sweep: %s:%ld: a sweep of %ld runs, but the others have %ld "
                     "(another plan)\n", sf->name, line, runs, m->runs), -1;
    if (m->rows[run])
      return fprintf(stderr, "appell sweep: run %ld is in %s and in %s\n", run,
                     m->files[m->owner[run]].name, sf->name), -1;
    m->rows[run] = s, m->owner[run] = i;
  }
  return 0;
}

/* Every run present; otherwise list the first missing ranges. */
static int check_complete(const merge_state *m) {
  long missing = 0;
  for (long r = 0; r < m->runs; r++) missing += !m->rows[r];
  if (!missing) return 0;
  fprintf(stderr, "appell sweep: %ld of %ld runs are missing:", missing, m->runs);
  int shown = 0;
  for (long r = 0; r < m->runs && shown < 5; r++) {
    if (m->rows[r]) continue;
    long e = r;
    while (e + 1 < m->runs && !m->rows[e + 1]) e++;
    fprintf(stderr, e > r ? " %ld..%ld" : " %ld", r, e);
    shown++, r = e;
  }
  fprintf(stderr, "%s (a shard not run, failed or not given?)\n", shown == 5 ? " ..." : "");
  return -1;
}

static int write_merged(const merge_state *m, cli_out *out) {
  int code = cli_out_open(out);
  if (code != EXIT_OK) return code;
  fwrite(m->files[0].text, 1, line_len(m->files[0].text) + 1, out->f);
  for (long r = 0; r < m->runs; r++) fwrite(m->rows[r], 1, line_len(m->rows[r]) + 1, out->f);
  return cli_out_close(out, code);
}

int sweep_merge(cli_out *out, const char *const *inputs, int n, int quiet) {
  merge_state m;
  memset(&m, 0, sizeof m);
  m.files = calloc((size_t)n, sizeof *m.files);
  int code = m.files ? EXIT_OK : EXIT_INTERNAL;
  for (int i = 0; code == EXIT_OK && i < n; i++) {
    m.files[i].name = inputs[i];
    m.nfiles++;
    if (read_file(&m.files[i]) != 0) code = EXIT_INPUT;
  }
  if (code == EXIT_OK && check_header(&m) != 0) code = EXIT_INPUT;
  for (int i = 0; code == EXIT_OK && i < n; i++)
    if (place_rows(&m, i) != 0) code = EXIT_INPUT;
  if (code == EXIT_OK && check_complete(&m) != 0) code = EXIT_INPUT;
  if (code == EXIT_OK) code = write_merged(&m, out);
  if (code == EXIT_OK && !quiet)
    fprintf(stderr, "appell sweep: merged %d files, %ld runs -> %s\n", n, m.runs,
            cli_out_name(out));
  for (int i = 0; i < m.nfiles; i++) free(m.files[i].text);
  free(m.files);
  free(m.rows);
  free(m.owner);
  return code;
}
