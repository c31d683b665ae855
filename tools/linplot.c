/* appell linearize: CSV files and the eigenvalue figure.
 *
 * CSV files are written to a temporary file and renamed over the target only when complete;
 * a FIFO or a device (/dev/null) is written in place, and a link to a regular file keeps being
 * a link (the file it names is replaced), as appell run --out does.
 * Sweep CSV: the parameter, then re_i and im_i of each tracked eigenvalue (row i of the sweep
 * follows one eigenvalue by continuity). The figure (gnuplot, pngcairo or svg by the extension;
 * the data go to gnuplot inline, so no side file is written; checked by lin_check_plot before
 * any work, drawn into a temporary file renamed over the figure when complete) draws every
 * real part as a solid line and every non-zero imaginary part, as |im|, dashed in the same
 * colour, with a vertical line at each characteristic point: the classic picture of
 * eigenvalues against speed. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <appell/outfile.h>

#include "cli.h"
#include "linearize.h"

/* Output files follow appell run --out's rules (include/appell/outfile.h, lib/io/outfile.c):
 * a regular file is written to FILE.appell-tmp.PID.XXXXXX and renamed over FILE only when
 * complete, so that no partial file is left as if it were whole; a target that exists and is
 * not a regular file is written in place (renaming over /dev/null, run as root, would replace
 * the device with a regular file); a link to a regular file stays a link. */
typedef struct out_file {
  ap_outfile o;
  FILE *f;
} out_file;

int lin_check_target(const char *opt, const char *file, const char *scene) {
  ap_outfile o;
  char msg[AP_OUT_PATH_MAX + 300];
  const char *keep[1] = {scene};
  if (ap_out_check(&o, file, keep, 1, msg, sizeof msg) == AP_OK) return 0;
  if (strstr(msg, ": is the input file "))
    return fprintf(stderr, "appell linearize: %s %s: is the scene file; refusing to overwrite "
                   "it\n", opt, file), -1;
  return fprintf(stderr, "appell linearize: %s %s\n", opt, msg), -1;
}

static FILE *open_out(out_file *o, const char *file) {
  char msg[AP_OUT_PATH_MAX + 300];
  o->f = NULL;
  if (ap_out_check(&o->o, file, NULL, 0, msg, sizeof msg) != AP_OK ||
      ap_out_open(&o->o, msg, sizeof msg) != AP_OK) {
    fprintf(stderr, "appell linearize: %s\n", msg);
    return NULL;
  }
  o->f = fdopen(o->o.fd, "w");
  if (!o->f) {
    fprintf(stderr, "appell linearize: cannot write %s: %s\n", file, CLI_STRERROR(errno));
    ap_out_finish(&o->o, 0, NULL, 0);
  }
  return o->f;
}

static int close_out(out_file *o) {
  int bad = ferror(o->f) != 0;
  int err = bad ? errno : 0;
  if (fclose(o->f) != 0 && !bad) bad = 1, err = errno;
  o->o.fd = -1;   /* closed with the FILE */
  char msg[2 * AP_OUT_PATH_MAX + 300];
  if (bad) snprintf(msg, sizeof msg, "%s: %s", o->o.path, CLI_STRERROR(err ? err : EIO));
  if (ap_out_finish(&o->o, !bad, msg, sizeof msg) == AP_OK && !bad) return 0;
  fprintf(stderr, "appell linearize: cannot write %s\n", msg);
  return -1;
}

/* The rows of a sweep: the parameter, then re_i, im_i of each tracked eigenvalue. */
static void sweep_rows(FILE *f, const ap_lin_sweep *sw) {
  for (int c = 0; c < sw->count; c++) {
    fprintf(f, "%.17g", sw->p[c]);
    for (int i = 0; i < sw->n; i++)
      fprintf(f, ",%.17g,%.17g", sw->re[i + (size_t)c * sw->n], sw->im[i + (size_t)c * sw->n]);
    fprintf(f, "\n");
  }
}

int lin_write_sweep_csv(const char *file, const char *param, const ap_lin_sweep *sw) {
  out_file o;
  FILE *f = open_out(&o, file);
  if (!f) return -1;
  fprintf(f, "%s", param);
  for (int i = 0; i < sw->n; i++) fprintf(f, ",re%d,im%d", i, i);
  fprintf(f, "\n");
  sweep_rows(f, sw);
  return close_out(&o);
}

int lin_write_point_csv(const char *file, const ap_lin_eig *e) {
  out_file o;
  FILE *f = open_out(&o, file);
  if (!f) return -1;
  fprintf(f, "index,re,im,rcond,rcondv,error\n");
  for (int i = 0; i < e->n; i++)
    fprintf(f, "%d,%.17g,%.17g,%.6g,%.6g,%.6g\n", i, e->re[i], e->im[i], e->rcond[i],
            e->rcondv[i], e->err[i]);
  return close_out(&o);
}

/* The sweep as gnuplot's inline data block $eig (no side file): p, re_i, im_i per row. */
static void data_block(FILE *g, const ap_lin_sweep *sw) {
  fprintf(g, "$eig << EOD\n");
  sweep_rows(g, sw);
  fprintf(g, "EOD\n");
}

static void script(FILE *g, const char *fig, const char *param, const ap_lin_sweep *sw,
                   const char *title, const lin_opts *o) {
  const char *ext = strrchr(o->plot, '.');
  fprintf(g, "set terminal %s size 900,600 noenhanced\n",
          ext && strcmp(ext, ".svg") == 0 ? "svg" : "pngcairo");
  fprintf(g, "set output '%s'\nset datafile separator ','\nset grid\n", fig);
  fprintf(g, "set xlabel '%s'\nset ylabel 'eigenvalues (1/s)'\n", param);
  fprintf(g, "set title '%s: real parts (solid), imaginary parts (dashed)'\n", title);
  fprintf(g, "set key off\nset xzeroaxis lt -1\n");
  if (o->has_yrange) fprintf(g, "set yrange [%.17g:%.17g]\n", o->ymin, o->ymax);
  for (int i = 0; i < sw->npoints; i++)
    fprintf(g, "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 3 lc rgb 'gray40'\n",
            sw->points[i].p, sw->points[i].p);
  data_block(g, sw);
  fprintf(g, "plot ");
  for (int i = 0; i < sw->n; i++) {
    int cplx = 0;
    for (int c = 0; c < sw->count && !cplx; c++) cplx = sw->im[i + (size_t)c * sw->n] != 0.0;
    fprintf(g, "%s$eig using 1:%d with lines lw 2 lc %d", i ? ", " : "", 2 + 2 * i, i % 8 + 1);
    if (cplx)
      fprintf(g, ", $eig using 1:(abs($%d)) with lines lw 1.5 dt 2 lc %d", 3 + 2 * i,
              i % 8 + 1);
  }
  fprintf(g, "\nset output\n");
}

typedef struct lin_job {
  const char *fig, *param;
  const ap_lin_sweep *sw;
  const char *title;
  const lin_opts *o;
} lin_job;

static void lin_script(FILE *g, const void *user) {
  const lin_job *j = user;
  script(g, j->fig, j->param, j->sw, j->title, j->o);
}

int lin_check_plot(const char *fig, const char *scene) {
  const char *ext = strrchr(fig, '.');
  if (!ext || (strcmp(ext, ".png") != 0 && strcmp(ext, ".svg") != 0))
    return fprintf(stderr, "appell linearize: --plot %s: the figure must end in .png or .svg\n",
                   fig), -1;
  if (!cli_safe_name(fig))
    return fprintf(stderr, "appell linearize: --plot %s: the name must not contain quotes, "
                   "backslashes or newlines\n", fig), -1;
  if (lin_check_target("--plot", fig, scene)) return -1;
  char dir[4200];
  snprintf(dir, sizeof dir, "%s", fig);
  char *slash = strrchr(dir, '/');
  if (!slash) snprintf(dir, sizeof dir, ".");
  else if (slash == dir) dir[1] = '\0';
  else *slash = '\0';
  struct stat st;
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
    return fprintf(stderr, "appell linearize: --plot %s: the directory %s does not exist\n", fig,
                   dir), -1;
  if (access(dir, W_OK) != 0)
    return fprintf(stderr, "appell linearize: --plot %s: cannot write in %s: %s\n", fig, dir,
                   CLI_STRERROR(errno)), -1;
  return 0;
}

/* gnuplot draws into FIG.appell-tmp.PID.EXT, renamed over FIG when it succeeded. */
int lin_plot(const char *fig, const char *param, const ap_lin_sweep *sw, const char *title,
             const lin_opts *o) {
  if (!cli_safe_name(param) || !cli_safe_name(title))
    return fprintf(stderr, "appell linearize: the parameter and scene names must not contain "
                   "quotes, backslashes or newlines\n"), -1;
  char tmp[4300];
  snprintf(tmp, sizeof tmp, "%s.appell-tmp.%ld%s", fig, (long)getpid(), strrchr(fig, '.'));
  lin_job job = {tmp, param, sw, title, o};
  int rc = cli_gnuplot("linearize", lin_script, &job);
  if (rc == 0 && rename(tmp, fig) != 0) {
    fprintf(stderr, "appell linearize: cannot write %s: %s\n", fig, CLI_STRERROR(errno));
    rc = -1;
  }
  if (rc != 0) remove(tmp);
  return rc;
}
