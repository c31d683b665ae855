/* appell linearize: the run (operating point, linearization, eigenvalues, sweeps) and the
 * text report. Public API only. See linearize.c for the flow. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "linearize.h"

#define MAX_LOAD_SETS (LIN_MAX_SETS + 512)

typedef struct run {
  lin_opts *o;
  ap_scene_lin sec;        /* the linearize: section */
  ap_scene *sc;            /* the scene of the operating point guess */
  const char *sets[MAX_LOAD_SETS];
  int nsets;               /* user sets + linearize.initial */
  char (*buf)[128];        /* speed-key sets written here */
  double *q, *v, *v0, *dir, s_point;
  ap_lin_def def;
  ap_lin *L;
  int *sel, ns;
  char msg[1024];
} run;

/* ---- loading ------------------------------------------------------------------------------ */

/* Load the scene with r->sets plus the speed keys at coef * s (NaN: leave them) and one more
 * set (or NULL); its initial state into q, v. The scene goes to *out (may be NULL: freed). */
static int load(run *r, double s, const char *extra, ap_scene **out, double *q, double *v) {
  const char *sets[MAX_LOAD_SETS + 2];
  int n = r->nsets;
  memcpy(sets, r->sets, sizeof *sets * (size_t)n);
  for (int i = 0; isfinite(s) && i < r->sec.nspeed && i < 256; i++) {
    snprintf(r->buf[i], sizeof r->buf[i], "%.100s=%.17g", r->sec.speed_keys[i],
             r->sec.speed_coef[i] * s);
    sets[n++] = r->buf[i];
  }
  if (extra) sets[n++] = extra;
  ap_scene *sc = NULL;
  int rc = ap_scene_load(r->o->scene, sets, n, &sc, r->msg, sizeof r->msg);
  if (rc == AP_OK && q)
    rc = ap_scene_initial_state(sc, q, v, NULL, 0, r->msg, sizeof r->msg);
  if (rc != AP_OK || !out) ap_scene_free(sc);
  else *out = sc;
  return rc;
}

static int prepare(run *r) {
  lin_opts *o = r->o;
  ap_scene *sc0 = NULL;
  int rc = ap_scene_load(o->scene, o->sets, o->nsets, &sc0, r->msg, sizeof r->msg);
  if (rc == AP_OK) rc = ap_scene_get_linearize(sc0, &r->sec, r->msg, sizeof r->msg);
  ap_scene_free(sc0);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < o->nsets; i++) r->sets[r->nsets++] = o->sets[i];
  for (int i = 0; i < r->sec.nsets && r->nsets < MAX_LOAD_SETS; i++)
    r->sets[r->nsets++] = r->sec.sets[i];
  if ((o->has_speed || !strcmp(o->sweep_path, "speed")) && r->sec.nspeed == 0) {
    snprintf(r->msg, sizeof r->msg, "%s: the speed parameter needs linearize.speed (the "
             "initial rates proportional to it) in the scene", o->scene);
    return AP_ERR_ARG;
  }
  r->buf = calloc(256, sizeof *r->buf);
  if (!r->buf) return AP_ERR_NOMEM;
  return load(r, NAN, NULL, &r->sc, NULL, NULL);
}

/* q and v of the guess; with speed keys, v0 (speed 0), dir and the scene's own speed. */
static int guess(run *r) {
  const ap_model *m = ap_scene_model(r->sc);
  int n = ap_model_n(m), k = ap_model_k(m);
  r->q = calloc((size_t)(n + 4 * k) + 1, sizeof *r->q);
  if (!r->q) return AP_ERR_NOMEM;
  r->v = r->q + n, r->v0 = r->v + k, r->dir = r->v0 + k;
  int rc = ap_scene_initial_state(r->sc, r->q, r->v, NULL, 0, r->msg, sizeof r->msg);
  r->s_point = NAN;
  if (rc != AP_OK || r->sec.nspeed == 0) return rc;
  double *qt = r->dir + k, num = 0.0, den = 0.0;
  rc = load(r, 0.0, NULL, NULL, qt, r->v0);
  if (rc == AP_OK) rc = load(r, 1.0, NULL, NULL, qt, r->dir);
  for (int i = 0; rc == AP_OK && i < k; i++) {
    r->dir[i] -= r->v0[i];
    num += (r->v[i] - r->v0[i]) * r->dir[i], den += r->dir[i] * r->dir[i];
  }
  r->s_point = r->o->has_speed ? r->o->speed : den > 0 ? num / den : 0.0;
  return rc;
}

static int create(run *r) {
  lin_opts *o = r->o;
  ap_scene_run sr;
  ap_scene_get_run(r->sc, &sr);
  r->def = ap_lin_def_default();
  r->def.about = o->about >= 0 ? (ap_lin_about)o->about : r->sec.about;
  r->def.free = (const char *const *)(o->free ? o->free : r->sec.free);
  r->def.independent = (const char *const *)r->sec.independent;
  r->def.inputs = (const char *const *)(o->inputs ? o->inputs : r->sec.inputs);
  r->def.speed_dir = r->sec.nspeed ? r->dir : NULL;
  r->def.method = (ap_lin_method)o->method;
  int rc = ap_lin_create(ap_scene_model(r->sc), &r->def, sr.t0, r->q,
                         r->sec.nspeed ? r->v0 : r->v, &r->L);
  if (rc != AP_OK) snprintf(r->msg, sizeof r->msg, "%s", ap_lin_message(r->L));
  return rc;
}

/* The subsystem's states from --states or linearize.states (after the partition). */
static int select_states(run *r) {
  char **names = r->o->states ? r->o->states : r->sec.states;
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
  const ap_model *m = ap_scene_model(r->sc);
  const ap_lin *L = r->L;
  int nx = ap_lin_nx(L), nu = ap_lin_nu(L);
  const double *q = ap_lin_q(L), *v = ap_lin_v(L), *A = ap_lin_A(L), *E = ap_lin_A_error(L);
  const double *B = ap_lin_B(L), *F = ap_lin_rates(L);
  printf("scene        %s (%s)\n", ap_scene_name(r->sc), r->o->scene);
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
                                     r->sec.drop_cyclic);
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
  ap_scene *sc = NULL;
  ap_lin *L = NULL;
  const ap_model *m = NULL;
  ap_scene_run sr;
  double *q = NULL;
  int rc = load(r, r->s_point, set, &sc, NULL, NULL);
  if (rc == AP_OK) {
    m = ap_scene_model(sc);
    q = calloc((size_t)(ap_model_n(m) + ap_model_k(m)) + 1, sizeof *q);
    rc = q ? ap_scene_initial_state(sc, q, q + ap_model_n(m), NULL, 0, r->msg, sizeof r->msg)
           : AP_ERR_NOMEM;
  }
  if (rc == AP_OK) {
    ap_scene_get_run(sc, &sr);
    ap_lin_def def = r->def;
    def.speed_dir = NULL;
    rc = ap_lin_create(m, &def, sr.t0, q, q + ap_model_n(m), &L);
  }
  ap_lin *keep = r->L;
  r->L = L;
  if (rc == AP_OK) rc = ap_lin_operating_point(L, NAN);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc == AP_OK) rc = select_states(r);
  if (rc == AP_OK) rc = ap_lin_eigen(L, r->ns ? r->sel : NULL, r->ns, !r->o->keep_cyclic &&
                                     r->sec.drop_cyclic);
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
  ap_scene_free(sc);
  free(q);
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
                              !o->keep_cyclic && r->sec.drop_cyclic, ptol, &sw);
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
  const char *csv = o->csv;
  char tmp[1100];
  if (!csv && o->plot) snprintf(tmp, sizeof tmp, "%s.csv", o->plot), csv = tmp;
  if (csv && lin_write_sweep_csv(csv, o->sweep_path, &sw)) rc = AP_ERR_INTERNAL;
  if (rc == AP_OK && o->plot &&
      lin_plot(o->plot, csv, o->sweep_path, &sw, ap_scene_name(r->sc)) != 0)
    rc = AP_ERR_INTERNAL;
  if (rc == AP_OK && o->plot) printf("%s\n", o->plot);
  ap_lin_sweep_free(&sw);
  return rc;
}

int lin_run(lin_opts *o) {
  if ((o->csv && lin_check_target("--csv", o->csv, o->scene)) ||
      (o->plot && lin_check_target("--plot", o->plot, o->scene)))
    return EXIT_INPUT;
  run r;
  memset(&r, 0, sizeof r);
  r.o = o;
  int rc = prepare(&r);
  if (rc == AP_OK) rc = guess(&r);
  if (rc == AP_OK) rc = create(&r);
  if (rc == AP_OK) rc = o->count ? sweep(&r) : one_point(&r);
  if (rc != AP_OK && rc != AP_ERR_INTERNAL)
    fprintf(stderr, "appell linearize: %s\n", r.msg[0] ? r.msg : ap_strerror(rc));
  int code = rc == AP_ERR_INTERNAL ? EXIT_INTERNAL : cli_exit_code(rc);
  ap_lin_free(r.L);
  ap_scene_free(r.sc);
  ap_scene_lin_free(&r.sec);
  free(r.q), free(r.sel), free(r.buf);
  return code;
}
