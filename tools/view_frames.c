/* appell view / export: read an appell CSV and rebuild every body's world pose at every row.
 *
 * The CSV must hold the coordinates channel (every q by its model name); the pose of body b at
 * row r is ap_body_get_state after ap_body_eval at (t_r, q_r) (speeds zero: poses do not depend
 * on them), stored as origin (x, y, z) and the unit quaternion (w, x, y, z) of ap_quat_from_matrix
 * of the body axes, sign chosen with w >= 0 (as the `poses` output channel). The CSV's 15
 * significant digits put q within 1e-15 relative of the run's, so the poses agree with the run's
 * to about 1e-14 m. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "view.h"

void view_csv_free(view_csv *c) {
  for (int i = 0; i < c->ncols; i++) free(c->names[i]);
  free(c->names);
  free(c->rows);
  memset(c, 0, sizeof *c);
}

int view_csv_column(const view_csv *c, const char *name) {
  for (int i = 0; i < c->ncols; i++)
    if (strcmp(c->names[i], name) == 0) return i;
  return -1;
}

static int read_header(view_csv *c, char *line) {
  line[strcspn(line, "\r\n")] = '\0';
  for (char *tok = strtok(line, ","); tok; tok = strtok(NULL, ",")) {
    char **nn = realloc(c->names, sizeof *nn * (size_t)(c->ncols + 1));
    if (!nn) return -1;
    c->names = nn;
    if (!(c->names[c->ncols] = strdup(tok))) return -1;
    c->ncols++;
  }
  return 0;
}

/* One data row into c->rows; 1 for a malformed row. */
static int read_row(view_csv *c, char *line, long *cap) {
  if (c->nrows == *cap) {
    long nc = *cap ? 2 * *cap : 256;
    double *r = realloc(c->rows, sizeof *r * (size_t)nc * (size_t)c->ncols);
    if (!r) return -1;
    c->rows = r, *cap = nc;
  }
  double *row = c->rows + (size_t)c->nrows * (size_t)c->ncols;
  char *p = line, *end;
  for (int i = 0; i < c->ncols; i++) {
    row[i] = strtod(p, &end);
    if (end == p || (i + 1 < c->ncols && *end != ',')) return 1;
    p = end + 1;
  }
  if (*end != '\0' && *end != '\n' && *end != '\r') return 1;
  c->nrows++;
  return 0;
}

int view_csv_read(const char *cmd, const char *path, view_csv *c) {
  memset(c, 0, sizeof *c);
  FILE *f = fopen(path, "r");
  if (!f) {
    fprintf(stderr, "appell %s: cannot read %s: %s\n", cmd, path, CLI_STRERROR(errno));
    return EXIT_INPUT;
  }
  size_t len = 0;
  char *line = NULL;
  long cap = 0, lineno = 1;
  int rc = getline(&line, &len, f) < 0 ? 1 : read_header(c, line);
  if (rc == 0 && (c->ncols < 1 || strcmp(c->names[0], "t") != 0)) rc = 1;
  while (rc == 0 && getline(&line, &len, f) >= 0) {
    lineno++;
    if (line[0] == '\n' || line[0] == '\0') continue;
    rc = read_row(c, line, &cap);
  }
  free(line);
  fclose(f);
  if (rc == 0 && c->nrows == 0) rc = 1, lineno = 2;
  if (rc > 0)
    fprintf(stderr, "appell %s: %s:%ld: not an appell CSV row (a header starting with t, then "
            "rows of %d numbers)\n", cmd, path, lineno, c->ncols);
  else if (rc < 0)
    fprintf(stderr, "appell %s: out of memory reading %s\n", cmd, path);
  if (rc) view_csv_free(c);
  return rc > 0 ? EXIT_INPUT : rc < 0 ? EXIT_INTERNAL : EXIT_OK;
}

void view_frames_free(view_frames *f) {
  free(f->bodies);
  free(f->t);
  free(f->pose);
  free(f->contact);
  memset(f, 0, sizeof *f);
}

static int setup_bodies(ap_scene *sc, const view_csv *csv, view_frames *f) {
  const ap_model *m = ap_scene_model(sc);
  f->nb = ap_model_body_count(m);
  if (!(f->bodies = calloc((size_t)f->nb + 1, sizeof *f->bodies))) return -1;
  static const char *const fc[] = {".contact.Fx", ".contact.Fy", ".contact.Fz"};
  for (int b = 0; b < f->nb; b++) {
    view_body *vb = &f->bodies[b];
    vb->name = ap_model_body_name(m, b);
    ap_model_body_shape(m, b, &vb->shape);
    int sb = -1;
    for (int i = 0; i < ap_scene_count(sc, AP_SCENE_BODIES); i++)
      if (strcmp(ap_scene_element_name(sc, AP_SCENE_BODIES, i), vb->name) == 0) sb = i;
    if (sb >= 0) ap_scene_body_visual(sc, sb, &vb->visual);
    for (int i = 0; i < 3; i++) {
      char name[128];
      snprintf(name, sizeof name, "%s%s", vb->name, fc[i]);
      vb->force_col[i] = view_csv_column(csv, name);
    }
  }
  return 0;
}

/* Column of every coordinate; an exit code when one is missing. */
static int coord_cols(const char *cmd, const ap_model *m, const view_csv *csv, int *col) {
  for (int i = 0; i < ap_model_n(m); i++) {
    col[i] = view_csv_column(csv, ap_model_coord_name(m, i));
    if (col[i] < 0) {
      fprintf(stderr, "appell %s: the CSV has no column %s: write it with the coordinates "
              "channel (output.channels in the scene, or --set 'output.channels=[coordinates]')"
              "\n", cmd, ap_model_coord_name(m, i));
      return EXIT_INPUT;
    }
  }
  return EXIT_OK;
}

static int frame(const ap_model *m, ap_data *d, const double *row, const int *col, long r,
                 view_frames *f) {
  d->t = f->t[r] = row[0];
  for (int i = 0; i < ap_model_n(m); i++) d->q[i] = row[col[i]];
  for (int i = 0; i < ap_model_k(m); i++) d->v[i] = 0.0;
  int rc = ap_body_eval(m, d);
  for (int b = 0; rc == AP_OK && b < f->nb; b++) {
    ap_body_state st;
    if ((rc = ap_body_get_state(m, d, b, &st)) != AP_OK) break;
    double *p = f->pose + ((size_t)r * (size_t)f->nb + (size_t)b) * 7;
    memcpy(p, st.pos, sizeof st.pos);
    ap_quat_from_matrix(st.R, p + 3);
    if (p[3] < 0)
      for (int i = 3; i < 7; i++) p[i] = -p[i];
    double *c = f->contact + ((size_t)r * (size_t)f->nb + (size_t)b) * 3;
    memcpy(c, st.contact, sizeof st.contact);
    f->bodies[b].contact |= st.has_contact;
  }
  return rc;
}

int view_frames_build(const char *cmd, ap_scene *sc, const view_csv *csv, view_frames *f) {
  memset(f, 0, sizeof *f);
  const ap_model *m = ap_scene_model(sc);
  f->scene = ap_scene_name(sc);
  if (!ap_model_is_body_model(m)) {
    fprintf(stderr, "appell %s: the scene has no bodies to draw\n", cmd);
    return EXIT_INPUT;
  }
  int *col = calloc((size_t)ap_model_n(m) + 1, sizeof *col);
  ap_data *d = NULL;
  int rc = col && setup_bodies(sc, csv, f) == 0 && ap_data_create(m, &d) == AP_OK ? EXIT_OK
                                                                                  : EXIT_INTERNAL;
  if (rc == EXIT_OK) rc = coord_cols(cmd, m, csv, col);
  size_t nfb = (size_t)csv->nrows * (size_t)f->nb;
  f->nf = csv->nrows;
  if (rc == EXIT_OK && (!(f->t = malloc(sizeof *f->t * (size_t)f->nf)) ||
                        !(f->pose = malloc(sizeof *f->pose * 7 * nfb + 1)) ||
                        !(f->contact = calloc(3 * nfb + 1, sizeof *f->contact))))
    rc = EXIT_INTERNAL;
  for (long r = 0; rc == EXIT_OK && r < f->nf; r++) {
    int st = frame(m, d, csv->rows + (size_t)r * (size_t)csv->ncols, col, r, f);
    if (st != AP_OK) {
      fprintf(stderr, "appell %s: the kinematics failed at row %ld (t = %.10g): %s\n", cmd, r + 2,
              f->t[r], ap_strerror(st));
      rc = cli_exit_code(st);
    }
  }
  if (rc == EXIT_OK) view_grounds(sc, f);
  if (rc == EXIT_INTERNAL) fprintf(stderr, "appell %s: out of memory\n", cmd);
  ap_data_free(d);
  free(col);
  if (rc != EXIT_OK) view_frames_free(f);
  return rc;
}
