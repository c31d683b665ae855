/* appell linearize: the run (operating point, linearization, eigenvalues, sweeps) and the
 * text report. Public API only. See linearize.c for the flow. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "linearize.h"

typedef struct run {
  lin_opts *o;
  ap_scene_lin_guess g;    /* the scene, its linearize: section, the guess */
  double s_point;          /* the speed parameter of one point (NaN: none) */
  ap_lin_def def;
  ap_lin *L;
  int *sel, ns;
  char msg[1024];
} run;

/* ---- loading ------------------------------------------------------------------------------ */

static int prepare(run *r) {
  lin_opts *o = r->o;
  int rc = ap_scene_lin_guess_load(o->scene, NULL, 0, o->sets, o->nsets, &r->g, r->msg,
                                   sizeof r->msg);
  if (rc != AP_OK) return rc;
  if ((o->has_speed || !strcmp(o->sweep_path, "speed")) && r->g.sec.nspeed == 0) {
    snprintf(r->msg, sizeof r->msg, "%s: the speed parameter needs linearize.speed (the "
             "initial rates proportional to it) in the scene", o->scene);
    return AP_ERR_ARG;
  }
  r->s_point = r->g.sec.nspeed == 0 ? NAN : o->has_speed ? o->speed : r->g.speed;
  return AP_OK;
}

static int create(run *r) {
  lin_opts *o = r->o;
  r->def = ap_scene_lin_def(&r->g);
  if (o->about >= 0) r->def.about = (ap_lin_about)o->about;
  if (o->free) r->def.free = (const char *const *)o->free;
  if (o->inputs) r->def.inputs = (const char *const *)o->inputs;
  r->def.method = (ap_lin_method)o->method;
  int rc = ap_scene_lin_create(&r->g, &r->def, &r->L);
  const char *m = ap_lin_message(r->L);
  if (rc != AP_OK && o->free && strncmp(m, "free: ", 6) == 0)   /* a name given by --free */
    snprintf(r->msg, sizeof r->msg, "%s: --free: %s", o->scene, m + 6);
  else if (rc != AP_OK)
    snprintf(r->msg, sizeof r->msg, "%s", m);
  return rc;
}

/* The subsystem's states from --states or linearize.states (after the partition). */
static int select_states(run *r) {
  char **names = r->o->states ? r->o->states : r->g.sec.states;
  r->ns = 0;
  if (!names) return AP_OK;
  int count = 0;
  while (names[count]) count++;
  free(r->sel);
  r->sel = calloc((size_t)count + 1, sizeof *r->sel);
  if (!r->sel) return AP_ERR_NOMEM;
  for (int i = 0; i < count; i++) {
    int s = ap_lin_find_state(r->L, names[i]);
    if (s < 0) {
      int len = snprintf(r->msg, sizeof r->msg, "%s: no state named '%s'; the states are:",
                         r->o->scene, names[i]);
      for (int j = 0; j < ap_lin_nx(r->L) && len > 0 && (size_t)len < sizeof r->msg; j++)
        len += snprintf(r->msg + len, sizeof r->msg - (size_t)len, " %s",
                        ap_lin_state_name(r->L, j));
      return AP_ERR_ARG;
    }
    r->sel[r->ns++] = s;
  }
  return AP_OK;
}

/* ---- one point ---------------------------------------------------------------------------- */

static double max_abs(const double *x, size_t n) {
  double m = 0.0;
  for (size_t i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

static void print_point(const run *r) {
  const ap_model *m = ap_scene_model(r->g.scene);
  const ap_lin *L = r->L;
  int nx = ap_lin_nx(L), nu = ap_lin_nu(L);
  const double *q = ap_lin_q(L), *v = ap_lin_v(L), *A = ap_lin_A(L), *E = ap_lin_A_error(L);
  const double *B = ap_lin_B(L), *F = ap_lin_rates(L);
  printf("scene        %s (%s)\n", ap_scene_name(r->g.scene), r->o->scene);
  printf("about        %s", r->def.about == AP_LIN_EQUILIBRIUM ? "equilibrium" : "steady motion");
  if (isfinite(r->s_point)) printf(" at speed %.10g", r->s_point);
  printf("\ncoordinates ");
  for (int i = 0; i < ap_model_n(m); i++) printf(" %s=%.12g", ap_model_coord_name(m, i), q[i]);
  printf("\nspeeds      ");
  for (int i = 0; i < ap_model_k(m); i++) printf(" %s=%.12g", ap_model_speed_name(m, i), v[i]);
  printf("\nstates       %d:", nx);
  for (int i = 0; i < nx; i++)
    printf(" %s%s", ap_lin_state_name(L, i), ap_lin_is_cyclic(L, i) ? " (cyclic)" : "");
  printf("\nrates        (non-zero only for cyclic coordinates at a steady motion)\n");
  for (int i = 0; i < nx; i++) printf("  %-24s %14.6g\n", ap_lin_state_name(L, i), F[i]);
  if (ap_lin_method_used(L) == AP_LIN_COMPLEX_STEP)
    printf("derivatives  complex step (exact to round-off)\n");
  else if (ap_lin_fallback(L)[0])
    printf("derivatives  Ridders' extrapolated differences: no complex step, %s\n",
           ap_lin_fallback(L));
  else
    printf("derivatives  Ridders' extrapolated differences\n");
  printf("state matrix A = dF/dx (row: rate of the state, column: the state); largest error "
         "estimate %.3g (largest entry %.3g)\n", max_abs(E, (size_t)nx * nx),
         max_abs(A, (size_t)nx * nx));
  for (int i = 0; i < nx; i++) {
    printf("  %-24s", ap_lin_state_name(L, i));
    for (int j = 0; j < nx; j++) printf(" %12.6g", A[i + (size_t)j * nx]);
    printf("\n");
  }
  if (nu > 0) {
    printf("input matrix B (columns:");
    for (int j = 0; j < nu; j++) printf(" %s", ap_lin_input_name(L, j));
    printf("; exact)\n");
    for (int i = 0; i < nx; i++) {
      printf("  %-24s", ap_lin_state_name(L, i));
      for (int j = 0; j < nu; j++) printf(" %12.6g", B[i + (size_t)j * nx]);
      printf("\n");
    }
  }
}

static void print_eigen(const ap_lin *L) {
  ap_lin_eig e;
  ap_lin_get_eigen(L, &e);
  if (e.n == 0) {
    printf("eigenvalues: none: every state is cyclic (the constraints prescribe the motion); "
           "--keep-cyclic lists the cyclic states' own, zero, eigenvalues\n");
    return;
  }
  printf("eigenvalues of the subsystem of %d states:", e.n);
  for (int i = 0; i < e.n; i++) printf(" %s", ap_lin_state_name(L, e.states[i]));
  printf("\n  %25s %25s %11s %11s %11s\n", "real", "imaginary", "rcond", "rcond(vec)",
         "error");
  for (int i = 0; i < e.n; i++)
    printf("  %25.16g %25.16g %11.3g %11.3g %11.3g\n", e.re[i], e.im[i], e.rcond[i],
           e.rcondv[i], e.err[i]);
}

static int one_point(run *r) {
  int rc = ap_lin_operating_point(r->L, r->s_point);
  if (rc == AP_OK) rc = ap_lin_linearize(r->L);
  if (rc == AP_OK) rc = select_states(r);
  else snprintf(r->msg, sizeof r->msg, "%s: %s", r->o->scene, ap_lin_message(r->L));
  if (rc == AP_OK) rc = ap_lin_eigen(r->L, r->ns ? r->sel : NULL, r->ns, !r->o->keep_cyclic &&
                                     r->g.sec.drop_cyclic);
  if (rc != AP_OK) {
    if (!r->msg[0]) snprintf(r->msg, sizeof r->msg, "%s: %s", r->o->scene, ap_lin_message(r->L));
    return rc;
  }
  print_point(r);
  print_eigen(r->L);
  if (r->o->csv) {
    ap_lin_eig e;
    ap_lin_get_eigen(r->L, &e);
    if (lin_write_point_csv(r->o->csv, &e)) return AP_ERR_INTERNAL;
  }
  return AP_OK;
}

/* ---- sweeps ------------------------------------------------------------------------------- */

/* A scene parameter at p: reload, fresh linearizer, eigenvalues of the same subsystem. */
typedef struct param_ctx {
  run *r;
  int n0;
} param_ctx;

static int param_eig(double p, int n, double *re, double *im, void *user) {
  run *r = ((param_ctx *)user)->r;
  char set[512];
  snprintf(set, sizeof set, "%s=%.17g", r->o->sweep_path, p);
  const char *sets[LIN_MAX_SETS + 1];
  memcpy(sets, r->o->sets, sizeof *sets * (size_t)r->o->nsets);
  sets[r->o->nsets] = set;
  ap_scene_lin_guess g;
  ap_lin *L = NULL;
  int rc = ap_scene_lin_guess_load(r->o->scene, NULL, 0, sets, r->o->nsets + 1, &g, r->msg,
                                   sizeof r->msg);
  if (rc == AP_OK) {
    ap_lin_def def = r->def;
    def.speed_dir = g.dir;
    rc = ap_scene_lin_create(&g, &def, &L);
  }
  ap_lin *keep = r->L;
  r->L = L;
  if (rc == AP_OK) rc = ap_lin_operating_point(L, r->s_point);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc == AP_OK) rc = select_states(r);
  if (rc == AP_OK) rc = ap_lin_eigen(L, r->ns ? r->sel : NULL, r->ns, !r->o->keep_cyclic &&
                                     r->g.sec.drop_cyclic);
  ap_lin_eig e;
  if (rc == AP_OK) ap_lin_get_eigen(L, &e);
  if (rc == AP_OK && e.n != n && n > 0) rc = AP_ERR_INCONSISTENT;
  if (rc == AP_OK && n > 0)
    memcpy(re, e.re, sizeof *re * (size_t)n), memcpy(im, e.im, sizeof *im * (size_t)n);
  if (rc == AP_OK) ((param_ctx *)user)->n0 = e.n;
  else if (L && !r->msg[0]) snprintf(r->msg, sizeof r->msg, "%s at %s: %s", r->o->scene, set,
                                     ap_lin_message(L));
  r->L = keep;
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
  return rc;
}

static void print_sweep(const run *r, const ap_lin_sweep *sw) {
  const char *param = r->o->sweep_path;
  printf("sweep        %s from %g to %g, %d values; %d eigenvalues tracked\n", param, r->o->from,
         r->o->to, r->o->count, sw->n);
  printf("characteristic points: %d\n", sw->npoints);
  for (int i = 0; i < sw->npoints; i++) {
    const ap_lin_point *p = &sw->points[i];
    const char *what = p->kind == AP_LIN_CROSSING
                           ? (p->im != 0.0 ? (p->rising ? "a complex pair becomes unstable"
                                                        : "a complex pair becomes stable")
                                           : (p->rising ? "a real eigenvalue becomes unstable"
                                                        : "a real eigenvalue becomes stable"))
                           : (p->rising ? "two real eigenvalues meet and become a pair"
                                        : "a pair splits into two real eigenvalues");
    printf("  %s = %.15g (+- %.2g): %s at %.6g %+.6gi\n", param, p->p, p->p_err, what, p->re,
           p->im);
  }
}

static int sweep(run *r) {
  lin_opts *o = r->o;
  int speed = strcmp(o->sweep_path, "speed") == 0, rc;
  double *p = malloc(sizeof *p * (size_t)o->count);
  if (!p) return AP_ERR_NOMEM;
  for (int i = 0; i < o->count; i++) p[i] = o->from + (o->to - o->from) * i / (o->count - 1);
  ap_lin_sweep sw;
  double ptol = 1e-14 * fmax(1.0, fmax(fabs(o->from), fabs(o->to)));
  if (speed) {
    rc = ap_lin_operating_point(r->L, p[0]);   /* fixes the partition: states have names */
    if (rc == AP_OK) rc = select_states(r);
    if (rc == AP_OK)
      rc = ap_lin_sweep_speed(r->L, p, o->count, r->ns ? r->sel : NULL, r->ns,
                              !o->keep_cyclic && r->g.sec.drop_cyclic, ptol, &sw);
    if (rc != AP_OK && !r->msg[0])
      snprintf(r->msg, sizeof r->msg, "%s: %s", o->scene, ap_lin_message(r->L));
  } else {
    param_ctx c = {r, 0};
    double re, im;
    rc = param_eig(p[0], 0, &re, &im, &c);   /* the size of the subsystem */
    char msg[512] = "";
    if (rc == AP_OK)
      rc = ap_lin_sweep_run(param_eig, &c, c.n0, p, o->count, ptol, 1e-6, &sw, msg, sizeof msg);
    if (rc != AP_OK && !r->msg[0]) snprintf(r->msg, sizeof r->msg, "%s: %s", o->scene, msg);
  }
  free(p);
  if (rc != AP_OK) return rc;
  print_sweep(r, &sw);
  if (o->csv && lin_write_sweep_csv(o->csv, o->sweep_path, &sw)) rc = AP_ERR_INTERNAL;
  if (rc == AP_OK && o->plot &&
      lin_plot(o->plot, o->sweep_path, &sw, ap_scene_name(r->g.scene), o) != 0)
    rc = AP_ERR_INTERNAL;
  if (rc == AP_OK && o->plot) printf("%s\n", o->plot);
  ap_lin_sweep_free(&sw);
  return rc;
}

int lin_run(lin_opts *o) {
  if ((o->csv && lin_check_target("--csv", o->csv, o->scene)) ||
      (o->plot && lin_check_plot(o->plot, o->scene)))
    return EXIT_INPUT;
  run r;
  memset(&r, 0, sizeof r);
  r.o = o;
  int rc = prepare(&r);
  if (rc == AP_OK) rc = create(&r);
  if (rc == AP_OK) rc = o->count ? sweep(&r) : one_point(&r);
  if (rc != AP_OK && rc != AP_ERR_INTERNAL)
    fprintf(stderr, "appell linearize: %s\n", r.msg[0] ? r.msg : ap_strerror(rc));
  int code = rc == AP_ERR_INTERNAL ? EXIT_INTERNAL : cli_exit_code(rc);
  ap_lin_free(r.L);
  ap_scene_lin_guess_free(&r.g);
  free(r.sel);
  return code;
}
