/* appell sweep --merge: join the CSV files of the shards of one sweep (docs/sweeps.md).
 *
 * Every file must have the same header (starting run,runs,plan), every row must end with a
 * line break and parse: as many fields as the header has columns, each well formed (plain, or
 * quoted with "" inside), run, runs and status whole numbers, the plan the same identity in
 * every row of every file (ap_batch_plan_id: the same scene, overrides and plan), a value for
 * each parameter, a number in each result column (t, steps, ..., NAME@end, CHANNEL@T); and
 * together the rows must hold each run 0 .. runs - 1 of the plan exactly once (runs is the
 * plan's size, written in every row). The rows are copied byte for byte in run
 * order into the output, which is written atomically; anything missing, duplicated or
 * inconsistent is reported with the file and the runs concerned, and nothing is written. */
#include <ctype.h>
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
  int ncols;               /* columns of the header */
  int *kind;               /* (ncols) COL_* of each column */
  char plan[17];           /* the first row's plan identity, and where it is */
  int plan_file;
  long plan_line;
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
  if (!f) return fprintf(stderr, "appell sweep: %s: cannot open: %s\n", sf->name, CLI_STRERROR(errno)), -1;
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

/* The kind of a column, from its name in the header. */
enum { COL_RUN, COL_RUNS, COL_PLAN, COL_PARAM, COL_STATUS, COL_NUMBER, COL_TEXT };

static int column_kind(const char *name, size_t n, int after_status) {
  static const char *const fixed[] = {"t", "steps", "rhs_evals", "err_fails", "max_residual",
                                      "energy_drift"};
  if (!after_status) return n == 6 && strncmp(name, "status", 6) == 0 ? COL_STATUS : COL_PARAM;
  for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
    if (strlen(fixed[i]) == n && strncmp(name, fixed[i], n) == 0) return COL_NUMBER;
  return memchr(name, '@', n) ? COL_NUMBER : COL_TEXT;
}

/* The columns of the first file's header: run,runs,plan, parameters, status, the rest. */
static int header_columns(merge_state *m) {
  const char *h = m->files[0].text;
  size_t len = line_len(h);
  if (strncmp(h, "run,runs,plan,", 14) != 0)
    return fprintf(stderr, "appell sweep: %s:1: not a table of appell sweep (the header starts "
                   "with run,runs,plan; a table of an older appell has no plan column: rerun "
                   "that shard)\n", m->files[0].name), -1;
  m->ncols = 1;
  for (size_t i = 0; i < len; i++) m->ncols += h[i] == ',';
  m->kind = malloc(sizeof *m->kind * (size_t)m->ncols);
  if (!m->kind) return fprintf(stderr, "appell sweep: out of memory\n"), -1;
  int after = 0;
  for (int c = 0; c < m->ncols; c++) {
    size_t n = strcspn(h, ",\n");
    m->kind[c] = c < 3 ? c : column_kind(h, n, after);
    after |= m->kind[c] == COL_STATUS;
    h += n + 1;
  }
  if (!after)
    return fprintf(stderr, "appell sweep: %s:1: no status column in the header\n",
                   m->files[0].name), -1;
  return 0;
}

/* The header of every file must equal the first file's. */
static int check_header(merge_state *m) {
  if (header_columns(m) != 0) return -1;
  const char *h0 = m->files[0].text;
  size_t l0 = line_len(h0);
  for (int i = 1; i < m->nfiles; i++) {
    const char *h = m->files[i].text;
    if (line_len(h) != l0 || strncmp(h, h0, l0) != 0)
      return fprintf(stderr, "appell sweep: %s:1: its header differs from %s's (another scene or "
                     "other parameters)\n", m->files[i].name, m->files[0].name), -1;
  }
  return 0;
}

/* One field at *s (quoted: "..." with "" inside; or plain, without quotes): its end in *end,
 * or NULL when malformed. */
static const char *field_end(const char *s) {
  if (*s != '"') {
    size_t n = strcspn(s, ",\n\"");
    return s[n] == '"' ? NULL : s + n;
  }
  for (s++;; s++) {
    if (*s == '\n' || !*s) return NULL;
    if (*s == '"' && s[1] == '"') s++;
    else if (*s == '"') return s[1] == ',' || s[1] == '\n' ? s + 1 : NULL;
  }
}

/* A whole number of at most 2^53 in magnitude (run, runs, status) or any double (%.17g, nan,
 * inf) filling [s, e). */
static int parse_num(const char *s, const char *e, int whole, double *x) {
  char buf[64], *end = NULL;
  size_t n = (size_t)(e - s);
  if (n == 0 || n >= sizeof buf || *s == '"') return -1;
  memcpy(buf, s, n), buf[n] = '\0';
  errno = 0;
  if (whole) {
    long v = strtol(buf, &end, 10);
    if (errno == ERANGE || v > (1L << 53) || v < -(1L << 53)) return -1;   /* found by fuzz_merge */
    *x = (double)v;
  } else {
    *x = strtod(buf, &end);
  }
  return *end || isspace((unsigned char)buf[0]) ? -1 : 0;
}

static const char *col_name(const merge_state *m, int c, char *buf, size_t len) {
  const char *h = m->files[0].text;
  for (int i = 0; i < c; i++) h += strcspn(h, ",\n") + 1;
  snprintf(buf, len, "%.*s", (int)strcspn(h, ",\n"), h);
  return buf;
}

/* Parse the row at s (file f, line): every field well formed and of its column's kind, the
 * plan's identity the first file's; run and runs out. */
static int parse_row(merge_state *m, int f, long line, const char *s, long *run, long *runs) {
  const shard_file *sf = &m->files[f];
  char name[256];
  int c = 0;
  double x = 0.0;
  for (const char *e;; s = e + 1, c++) {
    if (!(e = field_end(s)))
      return fprintf(stderr, "appell sweep: %s:%ld: field %d: a malformed field (a quote inside "
                     "a plain field, or an unclosed quoted one)\n", sf->name, line, c + 1), -1;
    int k = c < m->ncols ? m->kind[c] : COL_TEXT, bad = 0;
    if (k == COL_PLAN) {
      if (e - s != 16 || strspn(s, "0123456789abcdef") < 16) bad = 1;
      else if (!m->plan[0]) memcpy(m->plan, s, 16), m->plan_file = f, m->plan_line = line;
      else if (memcmp(m->plan, s, 16) != 0)
        return fprintf(stderr, "appell sweep: %s:%ld: plan %.16s, but %s:%ld has plan %s: shards "
                       "of different sweeps (another scene, other overrides or another plan)\n",
                       sf->name, line, s, m->files[m->plan_file].name, m->plan_line, m->plan), -1;
    } else if (k == COL_PARAM) {
      bad = e == s;
    } else if (k != COL_TEXT) {
      bad = parse_num(s, e, k != COL_NUMBER, &x) != 0;
      if (k == COL_RUN) *run = (long)x;
      if (k == COL_RUNS) *runs = (long)x;
    }
    if (bad)
      return fprintf(stderr, "appell sweep: %s:%ld: column %s: '%.*s' is not %s\n", sf->name,
                     line, col_name(m, c, name, sizeof name), (int)(e - s > 40 ? 40 : e - s), s,
                     k == COL_PLAN ? "a plan identity (16 hex digits)"
                     : k == COL_NUMBER ? "a number" : k == COL_PARAM ? "a value"
                                                                      : "a whole number"), -1;
    if (*e == '\n') break;
  }
  if (c + 1 != m->ncols)
    return fprintf(stderr, "appell sweep: %s:%ld: %d fields, but the header has %d columns\n",
                   sf->name, line, c + 1, m->ncols), -1;
  return 0;
}

/* Place the rows of file i by their run index. */
static int place_rows(merge_state *m, int i) {
  const shard_file *sf = &m->files[i];
  const char *s = sf->text + line_len(sf->text) + 1;
  for (long line = 2; s < sf->text + sf->len; line++, s += line_len(s) + 1) {
    long run = -1, runs = -1;
    if (parse_row(m, i, line, s, &run, &runs) != 0) return -1;
    if (runs < 1 || run < 0 || run >= runs)
      return fprintf(stderr, "appell sweep: %s:%ld: run %ld of %ld runs is not in the plan\n",
                     sf->name, line, run, runs), -1;
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
      return fprintf(stderr, "appell sweep: run %ld is in %s and in %s:%ld\n", run,
                     m->files[m->owner[run]].name, sf->name, line), -1;
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
  free(m.kind);
  return code;
}
