/* The differential tester's comparer (docs/testing.md, "Modes must agree").
 *
 * A scene is loaded twice through the public API, with simulation.path = dense and = tree, and
 * each path runs from its own consistent initial state (ap_scene_initial_state) in minimal,
 * projected and plain mode with each stepper of the options, and the dense path in DAE mode
 * (IDA). The reference is the projected mode, dense path, dop853 at the tighter rtol_ref; the
 * sensitivity run is the reference from an initial state moved by DELTA (relative), whose
 * distance from it over DELTA is the measured growth G >= 1 of a perturbation. With eps the
 * machine epsilon, k the speeds, N = n + k the state size, kappa the condition estimate of
 * G = B^T g B (squared ratio of its Cholesky factor's extreme diagonal entries, dense runs),
 * s the accepted steps of a run up to the compared time and X_i the largest |x_i| up to then,
 * each run must satisfy:
 *
 *   creation      refused by every run or by none (besides the documented refusal: plain mode
 *                 with rows redundant only on the manifold); the tree path takes the model
 *                 exactly when each constraint acts on one body (when the generator knows);
 *   initial       q0, v0 of both paths, and v and v' after ap_sim_create, equal to the
 *                 reference's within C_R k eps K (1 + |v|) and C_R k eps K (1 + |v'| + |v|^2)
 *                 (C_R = 64: round-off of the solves), K = max(kappa, ||M|| max(max |A_ij|,
 *                 lscale)): kappa for the free speeds, and for the constrained ones the
 *                 round-off of forming A (terms up to a direction times a lever arm) carried
 *                 by M = g^-1 A^T (A g^-1 A^T)^+ (cond.c);
 *   trajectory    |x_i - x_ref,i| <= AMP G sqrt(N) (s (rtol X_i + atol) + s_ref (rtol_ref X_i
 *                 + atol_ref)) at t_end/4, t_end/2, 3 t_end/4, t_end: each accepted step adds
 *                 at most one tolerance unit per component (the weighted RMS error test allows
 *                 sqrt(N)), grown by G, AMP = 10 for other directions than the one perturbed;
 *                 plain mode's speeds add ||M|| sqrt(b) max |A v + a0| (its drift r = A dv,
 *                 which the exact flow keeps constant, moves v by M r);
 *   energy        when the scene conserves it: |E - E0| <= AMP G sqrt(N) s (rtol + atol / X)
 *                 max(2 T + |V|) (a relative error rtol of v costs 2 rtol of T), plus AMP
 *                 t_end max ||lambda||_1 max |A v + a0| (the multipliers' work on the drift);
 *   residual      max |A v + a0| (its channel, sampled 16 times, and the driver's own) within
 *                 C_R k eps max(1, ||A|| ||M||) (1 + X_q)(1 + X_v) for minimal and explicit
 *                 projected runs (the basis and projection solved to A's conditioning);
 *                 AMP (rtol X_v + atol)(1 + X_q) for BDF projected (CVODE projects past a
 *                 tenth of its tolerance) and DAE; AMP G sqrt(N) s (rtol X_v + atol)(1 + X_q)
 *                 for plain mode, which drifts. ||M||, ||A|| are the largest over the
 *                 reference's samples up to the compared time, and X_i counts the initial state.
 *
 * A run that stops mid-way is a disagreement unless the reference stopped too (a disk that
 * falls flat): the model then counts as stopped; so is a reference that stops where another
 * run goes through, unless it gave up on a stiff model (MAX_STEPS per sample). */
#include "compare.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "cond.h"
#include "switches.h"

#define NT 4          /* compared times */
#define NS 16         /* samples (max |x|, energy, residual) */
#define C_R 64.0
#define AMP 10.0
#define DELTA 1e-7    /* relative perturbation of the sensitivity run */
#define MAX_STEPS 5000 /* per sample (t_end / 16): a stiff model stops the reference instead of
                          taking minutes */

typedef struct run {
  char label[48];
  int path;           /* 0 dense, 1 tree */
  ap_mode mode;
  const char *method;
  double rtol, atol;
  int rc;             /* AP_OK, or the failing status */
  int stage;          /* 0 created and ran, 1 refused at creation, 2 stopped mid-run */
  char msg[600];
  double t_fail;
  double *v_init, *a_init; /* (k) after creation */
  double *x[NT];      /* (n + k) at the compared times */
  long steps[NT];
  double *xmax[NT];   /* (n + k) max |x| up to each compared time */
  double kappa;       /* condition estimate of G at creation (dense); 0 unknown */
  int perturb;        /* the sensitivity run: initial state moved by DELTA */
  double e_err, e_scale, res, res_driver;
  double res_at[NT];  /* max |A v + a0| up to each compared time (samples and the driver's) */
  double lam1;        /* max ||lambda||_1 over the samples */
  double e_rise;      /* max over samples of E - min E before it (contact modes: >= 0 only
                         within the tolerance) */
  dt_events ev;       /* contact-mode switches (switches.c) */
} run;

typedef struct ctx {
  const dt_opts *o;
  dt_result *r;
  ap_scene *sc[2];
  int n, k, conserves;
  int modes;          /* the scene has contact modes */
  int passive;        /* ... and conserves energy without them: its energy may only fall */
  double *q0[2], *v0[2];
  int cols[4];        /* output columns: kinetic, potential, energy_error, residual */
  run *runs;
  int nruns;
  double growth[NT];  /* measured growth of a perturbation up to each compared time, >= 1 */
  double span, t0;    /* t_end - t0, t0 (s) */
  ap_data *dc;        /* the dense model's data for the conditioning (cond.c) */
  dt_cond c0;         /* at the initial state */
  double pinv[NT], krows[NT]; /* max over the reference's samples up to each compared time of
                                 ||M|| and ||A|| ||M|| (cond.h) */
} ctx;

dt_opts dt_opts_default(void) {
  dt_opts o = {3, {"dopri5", "dop853", "bdf", NULL}, 1e-8, 1e-10, 1e-12, 1e-14, -1, 0};
  return o;
}

__attribute__((format(printf, 2, 3))) static void note(ctx *c, const char *fmt, ...) {
  size_t used = strlen(c->r->what);
  if (used + 2 >= sizeof c->r->what) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(c->r->what + used, sizeof c->r->what - used, fmt, ap);
  va_end(ap);
}

__attribute__((format(printf, 2, 3))) static void disagree(ctx *c, const char *fmt,
                                                            ...) {
  char line[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  if (c->r->verdict != DT_DISAGREE) c->r->what[0] = 0;
  c->r->verdict = DT_DISAGREE;
  note(c, "%s\n", line);
}

const char *const dt_check_names[DT_NCHECK] = {"initial v", "initial v'", "trajectory",
                                               "energy", "residual", "switch time"};

static int check_kind(const char *what) {
  if (!strcmp(what, "initial v'")) return 1;
  if (!strcmp(what, "initial v") || !strcmp(what, "v0") || !strcmp(what, "q0")) return 0;
  if (what[0] == 'x') return 2;
  if (!strcmp(what, "switch time")) return 5;
  return strstr(what, "energy") ? 3 : 4;
}

/* Record diff / bound; a disagreement when it exceeds 1. */
static void check(ctx *c, const run *u, const char *what, int i, double diff, double bound) {
  double ratio = diff / bound, *wk = &c->r->worst_by[check_kind(what)];
  if (!(ratio <= *wk)) *wk = isnan(ratio) ? INFINITY : ratio;
  if (!(ratio <= c->r->worst)) {
    c->r->worst = isnan(ratio) ? INFINITY : ratio;
    snprintf(c->r->worst_what, sizeof c->r->worst_what, "%s %s[%d]", u->label, what, i);
  }
  if (!(ratio <= 1.0))
    disagree(c, "%s: %s[%d] differs by %.3g, bound %.3g", u->label, what, i, diff, bound);
}

static double norm_inf(int n, const double *x) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* Condition estimate of G from its Cholesky factor (dense data after ap_forward). */
static double kappa_of(const ap_data *d) {
  if (!d->G || d->l <= 0) return 0;
  double lo = INFINITY, hi = 0;
  for (int i = 0; i < d->l; i++) {
    double x = fabs(d->G[i + i * d->l]);
    lo = fmin(lo, x), hi = fmax(hi, x);
  }
  return lo > 0 ? (hi / lo) * (hi / lo) : INFINITY;
}

static int documented_refusal(const run *u) {
  return strstr(u->msg, "plain mode cannot run it") != NULL ||
         (u->mode == AP_MODE_DAE && strstr(u->msg, "not yet in DAE mode") != NULL);
}

static void out_values(ctx *c, ap_scene_out *o, ap_sim *s, double *row, double *T, double *V,
                       double *dE, double *res) {
  if (ap_scene_out_row(o, s, row) != AP_OK) row[0] = NAN;
  *T = c->cols[0] >= 0 ? row[c->cols[0]] : 0;
  *V = c->cols[1] >= 0 ? row[c->cols[1]] : 0;
  *dE = c->cols[2] >= 0 ? row[c->cols[2]] : 0;
  *res = c->cols[3] >= 0 ? row[c->cols[3]] : 0;
}

/* At a sample before compared time jt: the multipliers' size; on the reference, the rows'
 * conditioning there (cond.c). */
static void sample_extra(ctx *c, run *u, ap_sim *s, int jt) {
  const double *lam = NULL;
  int b = ap_model_b(ap_scene_model(c->sc[u->path]));
  if (b > 0 && ap_sim_reactions(s, &lam) == AP_OK && lam) {
    double l1 = 0;
    for (int r = 0; r < b; r++) l1 += fabs(lam[r]);
    u->lam1 = fmax(u->lam1, l1);
  }
  if (u != &c->runs[0] || !c->dc) return;
  const ap_model *m = ap_scene_model(c->sc[0]);
  dt_cond cd;
  double t = ap_sim_time(s);
  if (dt_cond_at(m, c->dc, t, ap_sim_q(s), &cd) != AP_OK) cd.pinv = 0;
  for (int j = jt; j < NT; j++)
    c->pinv[j] = fmax(c->pinv[j], cd.pinv), c->krows[j] = fmax(c->krows[j], cd.pinv * cd.anorm);
}

/* Advance one run through the samples, recording what the checks need. */
static void advance(ctx *c, run *u, ap_sim *s, double t0, double t1) {
  ap_scene *sc = c->sc[u->path];
  int N = c->n + c->k;
  double *row = calloc((size_t)ap_scene_output_count(sc) + 1, sizeof *row), *mx = calloc(
         (size_t)N, sizeof *mx), T, V, dE, res;
  ap_scene_out *o = NULL;
  if (ap_scene_out_create(sc, &o) != AP_OK) u->rc = AP_ERR_NOMEM;
  else out_values(c, o, s, row, &T, &V, &dE, &res);
  double e_min = 0;
  for (int i = 0; i < N; i++)   /* "seen so far" includes the initial state */
    mx[i] = fabs(i < c->n ? ap_sim_q(s)[i] : ap_sim_v(s)[i - c->n]);
  for (int j = 0; j < NS && u->rc == AP_OK; j++) {
    u->rc = ap_sim_advance(s, t0 + (t1 - t0) * (j + 1) / NS);
    const double *q = ap_sim_q(s), *v = ap_sim_v(s);
    for (int i = 0; i < N; i++) mx[i] = fmax(mx[i], fabs(i < c->n ? q[i] : v[i - c->n]));
    if (u->rc != AP_OK) {
      u->stage = 2, u->t_fail = ap_sim_time(s);
      snprintf(u->msg, sizeof u->msg, "%s", ap_sim_message(s));
      break;
    }
    out_values(c, o, s, row, &T, &V, &dE, &res);
    u->e_err = fmax(u->e_err, fabs(dE)), u->e_scale = fmax(u->e_scale, 2 * T + fabs(V));
    u->res = fmax(u->res, res);
    e_min = fmin(e_min, dE), u->e_rise = fmax(u->e_rise, dE - e_min);
    dt_events_read(&u->ev, s);
    sample_extra(c, u, s, j / (NS / NT));
    if ((j + 1) % (NS / NT) == 0) {
      int jt = (j + 1) / (NS / NT) - 1;
      ap_sim_stats st;
      ap_sim_get_stats(s, &st);
      u->steps[jt] = st.steps;
      u->x[jt] = malloc(sizeof(double) * (size_t)N);
      u->xmax[jt] = malloc(sizeof(double) * (size_t)N);
      memcpy(u->x[jt], q, sizeof(double) * (size_t)c->n);
      memcpy(u->x[jt] + c->n, v, sizeof(double) * (size_t)c->k);
      memcpy(u->xmax[jt], mx, sizeof(double) * (size_t)N);
      u->res_driver = st.max_residual;
      u->res_at[jt] = fmax(u->res, u->res_driver);
    }
  }
  ap_scene_out_free(o);
  free(row), free(mx);
}

static void do_run(ctx *c, run *u) {
  ap_scene_run sr;
  ap_scene_get_run(c->sc[u->path], &sr);
  ap_sim_def def = sr.sim;
  def.mode = u->mode, def.method = u->method, def.rtol = u->rtol, def.atol = u->atol;
  def.max_steps = c->modes ? MAX_STEPS / 10 : MAX_STEPS;   /* contact modes: costlier steps */
  ap_sim *s = NULL;
  c->r->runs++;
  double *q0 = c->q0[u->path], *v0 = c->v0[u->path];   /* each path's own initial state */
  if (u->perturb) {   /* x0 + DELTA max(1, |x0|) (+-1, alternating) */
    q0 = malloc(sizeof(double) * (size_t)(c->n + c->k + 1)), v0 = q0 + c->n;
    for (int i = 0; i < c->n; i++) q0[i] = c->q0[0][i] + (i % 2 ? -DELTA : DELTA) *
                                           fmax(1, fabs(c->q0[0][i]));
    for (int i = 0; i < c->k; i++) v0[i] = c->v0[0][i] + (i % 3 ? DELTA : -DELTA) *
                                           fmax(1, fabs(c->v0[0][i]));
  }
  u->rc = ap_sim_create(ap_scene_model(c->sc[u->path]), &def, sr.t0, q0, v0, &s, u->msg,
                        sizeof u->msg);
  if (u->perturb) free(q0);
  if (u->rc != AP_OK) {
    u->stage = 1;
    return;
  }
  const ap_data *d = ap_sim_data(s);
  u->v_init = malloc(sizeof(double) * (size_t)c->k);
  u->a_init = malloc(sizeof(double) * (size_t)c->k);
  memcpy(u->v_init, ap_sim_v(s), sizeof(double) * (size_t)c->k);
  memcpy(u->a_init, d->vdot, sizeof(double) * (size_t)c->k);
  u->kappa = kappa_of(d);
  advance(c, u, s, sr.t0, sr.t_end);
  ap_sim_free(s);
}

static void free_run(run *u) {
  free(u->v_init), free(u->a_init);
  for (int j = 0; j < NT; j++) free(u->x[j]), free(u->xmax[j]);
}

/* The runs: reference first, then every path x mode x method (DAE once, dense). */
static void plan(ctx *c) {
  static const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_PLAIN};
  static const char *const mname[4] = {"minimal", "projected", "dae", "plain"};
  const dt_opts *o = c->o;
  c->runs = calloc((size_t)(3 + 2 * 3 * o->nmethods), sizeof(run));
  run *u = &c->runs[c->nruns++];
  *u = (run){.path = 0, .mode = AP_MODE_PROJECTED, .method = "dop853", .rtol = o->rtol_ref,
             .atol = o->atol_ref};
  snprintf(u->label, sizeof u->label, "reference (projected dense dop853)");
  u = &c->runs[c->nruns++];
  *u = c->runs[0], u->perturb = 1;
  snprintf(u->label, sizeof u->label, "sensitivity (reference, perturbed)");
  for (int p = 0; p < 2; p++) {
    if (!c->sc[p]) continue;
    for (int mo = 0; mo < 3; mo++)
      for (int me = 0; me < o->nmethods; me++) {
        if (c->modes && modes[mo] == AP_MODE_PLAIN)
          continue;   /* contact modes: minimal and projected (docs/testing.md) */
        u = &c->runs[c->nruns++];
        *u = (run){.path = p, .mode = modes[mo], .method = o->methods[me], .rtol = o->rtol,
                   .atol = o->atol};
        snprintf(u->label, sizeof u->label, "%s %s %s", mname[modes[mo]], p ? "tree" : "dense",
                 o->methods[me]);
      }
  }
  u = &c->runs[c->nruns++];
  *u = (run){.path = 0, .mode = AP_MODE_DAE, .method = "dopri5", .rtol = o->rtol, .atol = o->atol};
  snprintf(u->label, sizeof u->label, "dae dense ida");
}

static double kappa_max(const ctx *c) {
  double k = 1;
  for (int i = 0; i < c->nruns; i++)
    if (c->runs[i].stage != 1) k = fmax(k, c->runs[i].kappa);
  return isfinite(k) ? k : 1e16;
}

/* Initial states: both paths' q0, v0 and every run's v, v' after creation. */
static void check_initial(ctx *c, const run *ref) {
  /* kappa of G for the free speeds; for the constrained ones the round-off of forming A,
   * whose terms are up to max(max |A_ij|, lscale) (a direction, or one times a lever arm;
   * cond.h), carried through M */
  double eps = DBL_EPSILON, kap = fmax(kappa_max(c), c->c0.pinv * fmax(c->c0.amax,
                                                                        c->c0.lscale));
  double vs = norm_inf(c->k, ref->v_init);
  double as = norm_inf(c->k, ref->a_init);
  double bv = C_R * c->k * eps * kap * (1 + vs), ba = C_R * c->k * eps * kap * (1 + as + vs * vs);
  run tree0 = {.path = 1};
  snprintf(tree0.label, sizeof tree0.label, "the tree path's ap_scene_initial_state");
  for (int i = 0; c->sc[1] && i < c->n; i++)
    check(c, &tree0, "q0", i, fabs(c->q0[1][i] - c->q0[0][i]), C_R * eps * (1 + fabs(c->q0[0][i])));
  for (int i = 0; c->sc[1] && i < c->k; i++)
    check(c, &tree0, "v0", i, fabs(c->v0[1][i] - c->v0[0][i]), bv);
  for (int r = 2; r < c->nruns; r++) {
    const run *u = &c->runs[r];
    if (u->stage == 1) continue;
    for (int i = 0; i < c->k; i++) {
      check(c, u, "initial v", i, fabs(u->v_init[i] - ref->v_init[i]), bv);
      check(c, u, "initial v'", i, fabs(u->a_init[i] - ref->a_init[i]), ba);
    }
  }
}

/* The growth of the perturbation of the sensitivity run (runs[1]) relative to its size,
 * at least 1, non-decreasing over the compared times; 1/DELTA where it did not get there. */
static void measure_growth(ctx *c, const run *ref) {
  const run *p = &c->runs[1];
  double g = 1;
  for (int j = 0; j < NT; j++) {
    for (int i = 0; ref->x[j] && i < c->n + c->k; i++) {
      double x0 = i < c->n ? c->q0[0][i] : c->v0[0][i - c->n];
      double dx = p->x[j] ? fabs(p->x[j][i] - ref->x[j][i]) : INFINITY;
      g = fmax(g, dx / (DELTA * fmax(1, fabs(x0))));
    }
    c->growth[j] = fmin(g, 1 / DELTA);
  }
}

/* The tolerance bound of component i at compared time j (docs/testing.md). */
static double tol_bound(const ctx *c, const run *ref, const run *u, int j, int i) {
  double X = fmax(ref->xmax[j][i], u->xmax[j][i]);
  return AMP * c->growth[j] * sqrt((double)(c->n + c->k)) *
         ((double)u->steps[j] * (u->rtol * X + u->atol) +
          (double)ref->steps[j] * (ref->rtol * X + ref->atol));
}

/* Plain mode keeps the drift r = A v + a0 in its state (the exact flow keeps r constant), and
 * r = A dv moves the speeds normal to the constraints by M r (cond.h), |M r|_2 <= ||M||_2
 * sqrt(b) max |r|; the other modes project v, so r is round-off there. */
static double drift_bound(const ctx *c, const run *u, int j) {
  int b = ap_model_b(ap_scene_model(c->sc[0]));
  return u->mode == AP_MODE_PLAIN ? c->pinv[j] * sqrt((double)b) * u->res_at[j] : 0;
}

/* Contact modes: the same switches as the reference's, up to where both ran, each time
 * within AMP G sqrt(N) (s (rtol + atol / X) + s_ref (...)) of the time since the last one
 * (switches.c). */
static void check_switches(ctx *c, const run *ref, const run *u) {
  if (!c->modes || u->stage == 1) return;
  int j = NT - 1;
  while (j > 0 && (!u->x[j] || !ref->x[j])) j--;
  double X = fmax(norm_inf(c->n + c->k, ref->xmax[j] ? ref->xmax[j] : ref->v_init), 1e-300);
  double s = (double)u->steps[j], sr = (double)ref->steps[j];
  double tol = AMP * c->growth[j] * sqrt((double)(c->n + c->k)) *
               (s * (u->rtol + u->atol / X) + sr * (ref->rtol + ref->atol / X));
  double t_upto = u->stage == 2 ? u->t_fail : INFINITY, worst;
  if (ref->stage == 2) t_upto = fmin(t_upto, ref->t_fail);
  char msg[300];
  if (dt_events_compare(&ref->ev, &u->ev, c->t0, t_upto, tol, &worst, msg, sizeof msg))
    disagree(c, "%s: %s", u->label, msg);
  else check(c, u, "switch time", 0, worst, 1);
}

static void check_trajectory(ctx *c, const run *ref, const run *u) {
  int N = c->n + c->k;
  for (int j = 0; j < NT; j++) {
    if (!u->x[j] || !ref->x[j]) break;
    char what[32];
    snprintf(what, sizeof what, "x(t%d)", j + 1);
    double bn = drift_bound(c, u, j);
    for (int i = 0; i < N; i++)
      check(c, u, what, i, fabs(u->x[j][i] - ref->x[j][i]),
            tol_bound(c, ref, u, j, i) + (i >= c->n ? bn : 0));
  }
}

static void check_invariants(ctx *c, const run *ref, const run *u) {
  if (!u->x[NT - 1] || !ref->xmax[NT - 1]) return;   /* stopped: the trajectory says it */
  int N = c->n + c->k;
  double sq = sqrt((double)N), s = (double)u->steps[NT - 1];
  double Xq = norm_inf(c->n, ref->xmax[NT - 1]), Xv = norm_inf(c->k, ref->xmax[NT - 1] + c->n);
  double X = fmax(Xq, Xv), G = c->growth[NT - 1];
  /* the multipliers' work on the drift A v + a0: t_end max ||lambda||_1 max |A v + a0| */
  double work = c->span * u->lam1 * fmax(u->res, u->res_driver);
  double be = AMP * G * sq * fmax(s, 1) * (u->rtol + u->atol / fmax(X, 1e-300)) * u->e_scale +
              AMP * work + DBL_MIN;
  if (c->conserves && u->e_scale > 1e-20)   /* not a mechanism locked at rest (l = 0) */
    check(c, u, "energy error", 0, u->e_err, be);
  if (c->passive) check(c, u, "energy rise (dissipation < 0)", 0, u->e_rise, be);
  double b;
  int erk = strcmp(u->method, "bdf") != 0 && strcmp(u->method, "adams") != 0;
  if (u->mode == AP_MODE_PLAIN) b = AMP * G * sq * s * (u->rtol * Xv + u->atol) * (1 + Xq);
  else if (u->mode == AP_MODE_DAE || (u->mode == AP_MODE_PROJECTED && !erk))
    b = AMP * (u->rtol * Xv + u->atol) * (1 + Xq);
  else b = C_R * c->k * DBL_EPSILON * fmax(1, c->krows[NT - 1]) * (1 + Xq) * (1 + Xv);
  b = fmax(b, DBL_MIN);
  check(c, u, "residual", 0, u->res, b);
  check(c, u, "driver residual", 0, u->res_driver, b);
}

/* Creation and stops: refusals must agree; a run stopping mid-way needs a stopped reference. */
static int check_status(ctx *c, const run *ref) {
  if (ref->stage == 1) {
    for (int r = 2; r < c->nruns; r++)
      if (c->runs[r].stage != 1)
        disagree(c, "the reference is refused (%s) but %s runs", ref->msg, c->runs[r].label);
    if (c->r->verdict != DT_DISAGREE) {
      c->r->verdict = DT_REFUSED;
      note(c, "refused at creation: %s\n", ref->msg);
    }
    return 0;
  }
  const run *gave_up = NULL;
  for (int r = 2; r < c->nruns; r++) {
    const run *u = &c->runs[r];
    if (u->stage == 1 && documented_refusal(u)) {
      c->r->refused_runs++;
      continue;
    }
    if (u->stage == 1) disagree(c, "%s refused (%s) where the reference runs", u->label, u->msg);
    if (u->stage == 2 && ref->stage != 2 && c->modes && strstr(u->msg, "max_steps")) {
      gave_up = u;   /* Coulomb friction near sticking is stiff for explicit methods */
      continue;
    }
    if (u->stage == 2 && ref->stage != 2)
      disagree(c, "%s stopped at t = %.6g (%s) where the reference runs through", u->label,
               u->t_fail, u->msg);
  }
  /* A stop of the reference is the model's (a disk falling flat: every run stops) unless
   * another run gets through; an explicit method giving up on a stiff model is no verdict. */
  int stiff = strstr(ref->msg, "gave up") || strstr(ref->msg, "too much work") ||
              strstr(ref->msg, "max_steps");
  for (int r = 2; r < c->nruns && ref->stage == 2 && !stiff; r++)
    if (c->runs[r].stage == 0)
      disagree(c, "the reference stopped at t = %.6g (%s) where %s runs through", ref->t_fail,
               ref->msg, c->runs[r].label);
  if (ref->stage == 2 && c->r->verdict != DT_DISAGREE) {
    c->r->verdict = DT_STOPPED;
    note(c, "the reference stopped at t = %.6g: %s\n", ref->t_fail, ref->msg);
  } else if (gave_up && c->r->verdict != DT_DISAGREE) {
    c->r->verdict = DT_STOPPED;
    note(c, "%s gave up at t = %.6g (contact modes, stiff): %s\n", gave_up->label,
         gave_up->t_fail, gave_up->msg);
    return 0;
  }
  return 1;
}

/* Contact modes: whether the scene has them, and whether without them it conserves energy
 * (then only friction and impacts act besides conservative forces: its energy may only
 * fall). */
static void modes_of(ctx *c, const char *text) {
  char *plain = dt_without_modes(text), msg[300];
  ap_scene *sc = NULL;
  c->modes = plain != NULL;
  if (plain && ap_scene_load_string(plain, strlen(plain), "difftest", NULL, 0, &sc, msg,
                                    sizeof msg) == AP_OK)
    c->passive = ap_scene_conserves_energy(sc);
  ap_scene_free(sc);
  free(plain);
}

/* Load both paths and the initial state; 0 when the runs can start. */
static int load(ctx *c, const char *text) {
  static const char *const sets[2][1] = {{"simulation.path=dense"}, {"simulation.path=tree"}};
  char msg[2][600];
  int rc[2];
  size_t len = strlen(text);
  for (int p = 0; p < 2; p++)
    rc[p] = ap_scene_load_string(text, len, "difftest", sets[p], 1, &c->sc[p], msg[p], 600);
  if (rc[0] != AP_OK) {
    if (rc[1] == AP_OK) disagree(c, "the dense path refuses (%s), the tree path loads", msg[0]);
    else c->r->verdict = DT_REFUSED, note(c, "refused at load: %s\n", msg[0]);
    return -1;
  }
  if (c->o->expect_tree == 1 && rc[1] != AP_OK)
    disagree(c, "the tree path refuses a model whose constraints each act on one body: %s",
             msg[1]);
  if (c->o->expect_tree == 0 && rc[1] == AP_OK)
    disagree(c, "the tree path takes a model with loop closures or wheel contacts");
  const ap_model *m = ap_scene_model(c->sc[0]);
  ap_scene_run sr;
  ap_scene_get_run(c->sc[0], &sr);
  c->span = sr.t_end - sr.t0, c->t0 = sr.t0;
  modes_of(c, text);
  c->n = ap_model_n(m), c->k = ap_model_k(m), c->conserves = ap_scene_conserves_energy(c->sc[0]);
  static const char *const names[4] = {"kinetic", "potential", "energy_error", "residual"};
  for (int j = 0; j < 4; j++) {
    c->cols[j] = -1;
    for (int i = 0; i < ap_scene_output_count(c->sc[0]); i++)
      if (!strcmp(ap_scene_output_name(c->sc[0], i), names[j])) c->cols[j] = i;
  }
  for (int p = 0; p < 2; p++) {
    if (!c->sc[p]) continue;
    c->q0[p] = calloc((size_t)c->n + 1, sizeof(double));
    c->v0[p] = calloc((size_t)c->k + 1, sizeof(double));
    rc[p] = ap_scene_initial_state(c->sc[p], c->q0[p], c->v0[p], NULL, 0, msg[p], 600);
  }
  if (rc[0] != AP_OK) {
    if (c->sc[1] && rc[1] == AP_OK)
      disagree(c, "the dense path refuses the initial state (%s), the tree path takes it", msg[0]);
    else if (c->r->verdict != DT_DISAGREE)
      c->r->verdict = DT_REFUSED, note(c, "initial state refused: %s\n", msg[0]);
    return -1;
  }
  if (c->sc[1] && rc[1] != AP_OK) {
    disagree(c, "the tree path refuses the initial state (%s), the dense path takes it", msg[1]);
    ap_scene_free(c->sc[1]), c->sc[1] = NULL;
  }
  return 0;
}

/* The rows' conditioning at the initial state (cond.c); the running maxima start there. */
static void start_cond(ctx *c) {
  const ap_model *m = ap_scene_model(c->sc[0]);
  ap_scene_run sr;
  ap_scene_get_run(c->sc[0], &sr);
  if (ap_data_create(m, &c->dc) != AP_OK) c->dc = NULL;
  if (!c->dc || dt_cond_at(m, c->dc, sr.t0, c->q0[0], &c->c0) != AP_OK) c->c0.pinv = 0;   /* no term: strict */
  for (int j = 0; j < NT; j++) c->pinv[j] = c->c0.pinv, c->krows[j] = c->c0.pinv * c->c0.anorm;
}

void dt_check(const char *text, const dt_opts *o, dt_result *r) {
  memset(r, 0, sizeof *r);
  ctx c = {.o = o, .r = r};
  if (load(&c, text) == 0) {
    start_cond(&c);
    plan(&c);
    for (int i = 0; i < c.nruns; i++) do_run(&c, &c.runs[i]);
    const run *ref = &c.runs[0];
    if (check_status(&c, ref)) {
      check_initial(&c, ref);
      measure_growth(&c, ref);
      for (int i = 2; i < c.nruns; i++) {
        check_trajectory(&c, ref, &c.runs[i]);
        check_switches(&c, ref, &c.runs[i]);
        check_invariants(&c, ref, &c.runs[i]);
      }
      check_invariants(&c, ref, ref);
    }
    for (int i = 0; i < c.nruns; i++) free_run(&c.runs[i]);
    free(c.runs);
  }
  ap_data_free(c.dc);
  for (int p = 0; p < 2; p++) ap_scene_free(c.sc[p]), free(c.q0[p]), free(c.v0[p]);
}
