/* appell linearize (internal to tools/): options and the pieces of the command, shared by
 * linearize.c (options), linrun.c (operating point, linearization, sweeps, text output) and
 * linplot.c (CSV and the gnuplot figure). */
#ifndef APPELL_TOOLS_LINEARIZE_H
#define APPELL_TOOLS_LINEARIZE_H

#include <appell/appell.h>

#define LIN_MAX_SETS 256

typedef struct lin_opts {
  const char *scene, *csv, *plot;
  const char *sets[LIN_MAX_SETS];
  int nsets;
  int about;               /* -1: the scene's choice, else ap_lin_about */
  int has_speed;
  double speed;
  char sweep_path[256];    /* "speed" or a scene key path; count 0: no sweep */
  double from, to;
  int count;
  char **states, **free, **inputs;   /* NULL-terminated, or NULL */
  int keep_cyclic;
  int has_yrange;          /* --yrange A:B: the plot's vertical range */
  double ymin, ymax;
  int method;              /* --derivatives: ap_lin_method; 0 = AP_LIN_AUTO (the default) */
} lin_opts;

int lin_run(lin_opts *o);
void lin_opts_free(lin_opts *o);

/* Eigenvalues of a sweep as CSV: the parameter, then re_i, im_i per tracked eigenvalue. */
int lin_write_sweep_csv(const char *file, const char *param, const ap_lin_sweep *sw);
/* Eigenvalues of one point as CSV: index, re, im, rcond, error. */
int lin_write_point_csv(const char *file, const ap_lin_eig *e);
/* Refuse an output target that is a directory or the scene itself (message; -1). */
int lin_check_target(const char *opt, const char *file, const char *scene);
/* --plot FIG before any work: .png or .svg, a name gnuplot can take, not a directory or the
 * scene, in a directory that exists and is writable (message; -1). */
int lin_check_plot(const char *fig, const char *scene);
/* Real and imaginary parts against the parameter (the data inline: no side file), drawn into
 * a temporary file renamed over fig when gnuplot succeeded. */
int lin_plot(const char *fig, const char *param, const ap_lin_sweep *sw, const char *title,
             const lin_opts *o);

#endif
