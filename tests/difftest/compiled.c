/* The differential tester's compiled-model check (difftest --compiled, docs/testing.md): the
 * scene on the dense path loaded twice, interpreted (simulation.compile = never) and compiled
 * (always, docs/compiled.md), and compared:
 *
 *   initial       q0, v0 (ap_scene_initial_state) and, after ap_partition and ap_forward at
 *                 them, v' and q' within 1e-13 relative (max |a - b| <= 1e-13 max |a|): the
 *                 compiled code performs the interpreted code's operations, so they agree to
 *                 the last bit up to the sign of a zero;
 *   runs          minimal, projected and DAE mode with each stepper of the options at their
 *                 rtol, atol: the same status, the same step count and partition switches,
 *                 and the states at t_end/4 ... t_end within the tester's trajectory bound with
 *                 no growth (both start from the same state): AMP sqrt(N) s (rtol X_i + atol),
 *                 s the accepted steps, X_i the largest |x_i| at the compared times.
 *
 * A model the generator does not take stays interpreted (its notice is counted, not a
 * disagreement); a compile that fails where the compiler works is a disagreement. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "appell/appell.h"
#include "compiled.h"

#define NT 4
#define AMP 10.0
#define RTOL_EXACT 1e-13

__attribute__((format(printf, 2, 3))) static void note(dt_cresult *r, const char *fmt, ...) {
  size_t used = strlen(r->what);
  if (used + 2 >= sizeof r->what) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(r->what + used, sizeof r->what - used, fmt, ap);
  va_end(ap);
}

/* max |a - b| / max |a| (0 when both are all zero). */
static double rel_diff(const double *a, const double *b, int n) {
  double d = 0.0, s = 0.0;
  for (int i = 0; i < n; i++) {
    if (isnan(a[i]) != isnan(b[i])) return INFINITY;
    if (!isnan(a[i])) d = fmax(d, fabs(a[i] - b[i])), s = fmax(s, fabs(a[i]));
  }
  return d == 0.0 ? 0.0 : s > 0.0 ? d / s : INFINITY;
}

static void exact(dt_cresult *r, const char *what, const double *a, const double *b, int n) {
  double d = rel_diff(a, b, n);
  r->worst_exact = fmax(r->worst_exact, d);
  if (!(d <= RTOL_EXACT))
    r->disagree = 1, note(r, "compiled: %s differs by %.3g relative (bound %g)\n", what, d,
                          RTOL_EXACT);
}

/* v', q' after ap_partition and ap_forward at (t0, q0, v0). */
static int forward(const ap_model *m, double t0, const double *q0, const double *v0,
                   double *out) {
  int n = ap_model_n(m), k = ap_model_k(m);
  ap_data *d = NULL;
  if (ap_data_create(m, &d) != AP_OK) return AP_ERR_NOMEM;
  memcpy(d->q, q0, sizeof(double) * (size_t)n), memcpy(d->v, v0, sizeof(double) * (size_t)k);
  d->t = t0;
  int rc = ap_partition(m, d);
  if (rc == AP_OK) rc = ap_forward(m, d);
  if (rc == AP_OK)
    memcpy(out, d->vdot, sizeof(double) * (size_t)k),
        memcpy(out + k, d->qdot, sizeof(double) * (size_t)n);
  ap_data_free(d);
  return rc;
}

typedef struct crun {
  int rc;
  long steps, switches;
  double t;
  double *x;          /* NT x N states */
  double *xmax;       /* N: max |x_i| at the compared times */
} crun;

static void run(ap_scene *sc, ap_mode mode, const char *method, const dt_opts *o,
                const double *q0, const double *v0, int N, crun *u) {
  const ap_model *m = ap_scene_model(sc);
  int n = ap_model_n(m);
  ap_scene_run sr;
  ap_scene_get_run(sc, &sr);
  ap_sim_def def = sr.sim;
  def.mode = mode, def.method = method, def.rtol = o->rtol, def.atol = o->atol;
  def.max_steps = 5000;
  ap_sim *s = NULL;
  u->x = calloc((size_t)N * (NT + 1), sizeof(double)), u->xmax = u->x + (size_t)N * NT;
  u->rc = ap_sim_create(m, &def, sr.t0, q0, v0, &s, NULL, 0);
  for (int j = 0; j < NT && u->rc == AP_OK; j++) {
    u->rc = ap_sim_advance(s, sr.t0 + (sr.t_end - sr.t0) * (j + 1) / NT);
    double *x = u->x + (size_t)j * N;
    memcpy(x, ap_sim_q(s), sizeof(double) * (size_t)n);
    memcpy(x + n, ap_sim_v(s), sizeof(double) * (size_t)(N - n));
    for (int i = 0; i < N; i++) u->xmax[i] = fmax(u->xmax[i], fabs(x[i]));
  }
  if (s) {
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    u->steps = st.steps, u->switches = st.partition_switches, u->t = ap_sim_time(s);
  }
  ap_sim_free(s);
}

static void compare_runs(dt_cresult *r, const char *label, const crun *a, const crun *b,
                         const dt_opts *o, int N) {
  r->runs += 2;
  if (a->rc != b->rc || a->t != b->t) {
    r->disagree = 1;
    note(r, "compiled: %s: status %d at t = %.17g interpreted, %d at t = %.17g compiled\n",
         label, a->rc, a->t, b->rc, b->t);
    return;
  }
  if (a->steps != b->steps || a->switches != b->switches) {
    r->disagree = 1;
    note(r, "compiled: %s: %ld steps, %ld partition switches interpreted; %ld, %ld compiled\n",
         label, a->steps, a->switches, b->steps, b->switches);
  }
  if (a->rc != AP_OK) return;   /* both stopped at the same time: compared up to there */
  for (int j = 0; j < NT; j++) {
    const double *x = a->x + (size_t)j * N, *y = b->x + (size_t)j * N;
    r->worst_run_rel = fmax(r->worst_run_rel, rel_diff(x, y, N));
    for (int i = 0; i < N; i++) {
      double bound = AMP * sqrt((double)N) * (double)a->steps * (o->rtol * a->xmax[i] + o->atol);
      double ratio = fabs(x[i] - y[i]) / bound;
      if (!(ratio <= r->worst_run)) r->worst_run = isnan(ratio) ? INFINITY : ratio;
      if (!(ratio <= 1.0)) {
        r->disagree = 1;
        note(r, "compiled: %s: x[%d] at t_end*%d/4 differs by %.3g, bound %.3g\n", label, i,
             j + 1, fabs(x[i] - y[i]), bound);
      }
    }
  }
}

void dt_check_compiled(const char *text, const dt_opts *o, dt_cresult *r) {
  static const char *const sets[2][2] = {{"simulation.path=dense", "simulation.compile=never"},
                                         {"simulation.path=dense", "simulation.compile=always"}};
  memset(r, 0, sizeof *r);
  ap_scene *sc[2] = {NULL, NULL};
  char msg[2][600];
  int rc[2];
  for (int p = 0; p < 2; p++)
    rc[p] = ap_scene_load_string(text, strlen(text), "difftest", sets[p], 2, &sc[p], msg[p],
                                 sizeof msg[p]);
  if (rc[0] != rc[1]) {
    r->disagree = 1;
    note(r, "compiled: loads with status %d interpreted (%s), %d compiled (%s)\n", rc[0],
         rc[0] ? msg[0] : "", rc[1], rc[1] ? msg[1] : "");
  } else if (rc[0] == AP_OK && !ap_model_is_compiled(ap_scene_model(sc[1]))) {
    r->interpreted = 1;
    snprintf(r->notice, sizeof r->notice, "%s", ap_scene_compile_notice(sc[1]));
  } else if (rc[0] == AP_OK) {
    r->compiled = 1;
    const ap_model *m = ap_scene_model(sc[0]);
    int n = ap_model_n(m), k = ap_model_k(m), N = n + k;
    double *x = calloc(4 * (size_t)N + 2, sizeof *x), *y = x + N, *f = y + N, *g = f + N;
    ap_scene_run sr;
    ap_scene_get_run(sc[0], &sr);
    rc[0] = ap_scene_initial_state(sc[0], x, x + n, NULL, 0, msg[0], sizeof msg[0]);
    rc[1] = ap_scene_initial_state(sc[1], y, y + n, NULL, 0, msg[1], sizeof msg[1]);
    if (rc[0] != rc[1]) {
      r->disagree = 1;
      note(r, "compiled: initial state status %d interpreted, %d compiled\n", rc[0], rc[1]);
    } else if (rc[0] == AP_OK) {
      exact(r, "initial state (q0, v0)", x, y, N);
      rc[0] = forward(m, sr.t0, x, x + n, f);
      rc[1] = forward(ap_scene_model(sc[1]), sr.t0, x, x + n, g);
      if (rc[0] != rc[1]) {
        r->disagree = 1;
        note(r, "compiled: ap_forward status %d interpreted, %d compiled\n", rc[0], rc[1]);
      } else if (rc[0] == AP_OK) {
        exact(r, "initial derivative (v', q')", f, g, N);
      }
      static const ap_mode modes[3] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE};
      static const char *const mname[3] = {"minimal", "projected", "dae"};
      for (int mo = 0; mo < 3; mo++)
        for (int me = 0; me < (mo == 2 ? 1 : o->nmethods); me++) {
          crun a = {0}, b = {0};
          char label[64];
          snprintf(label, sizeof label, "%s %s", mname[mo], mo == 2 ? "ida" : o->methods[me]);
          run(sc[0], modes[mo], o->methods[me], o, x, x + n, N, &a);
          run(sc[1], modes[mo], o->methods[me], o, x, x + n, N, &b);
          compare_runs(r, label, &a, &b, o, N);
          free(a.x), free(b.x);
        }
    }
    free(x);
  }
  ap_scene_free(sc[0]), ap_scene_free(sc[1]);
}

int dt_compiler_works(char *why, size_t len) {
  static const char scene[] =
      "bodies:\n  disk: {mass: 1.0, shape: {kind: disk, radius: 0.5}}\n"
      "joints:\n  disk: {kind: plane_contact}\n"
      "constraints:\n  roll: {kind: rolling, body: disk}\n"
      "effects:\n  gravity: {kind: gravity}\n"
      "initial:\n  disk: {tilt: 70*deg, spin_rate: -6}\n";
  const char *sets[1] = {"simulation.compile=always"};
  ap_scene *sc = NULL;
  char msg[600];
  int ok = ap_scene_load_string(scene, strlen(scene), "probe", sets, 1, &sc, msg,
                                sizeof msg) == AP_OK &&
           ap_model_is_compiled(ap_scene_model(sc));
  snprintf(why, len, "%s", ok ? "" : sc ? ap_scene_compile_notice(sc) : msg);
  ap_scene_free(sc);
  return ok;
}

void dt_compiled_merge(const dt_cresult *c, dt_result *r) {
  r->runs += c->runs;
  if (!c->disagree) return;
  if (r->verdict != DT_DISAGREE) r->what[0] = 0;
  r->verdict = DT_DISAGREE;
  size_t used = strlen(r->what);
  snprintf(r->what + used, sizeof r->what - used, "%s", c->what);
}

void dt_compiled_add(dt_ctally *t, const dt_cresult *c) {
  t->compiled += c->compiled, t->interpreted += c->interpreted, t->disagree += c->disagree;
  t->runs += c->runs;
  if (c->interpreted && !t->notice[0]) snprintf(t->notice, sizeof t->notice, "%s", c->notice);
  if (c->disagree) return;
  t->worst_exact = fmax(t->worst_exact, c->worst_exact);
  t->worst_run = fmax(t->worst_run, c->worst_run);
  t->worst_run_rel = fmax(t->worst_run_rel, c->worst_run_rel);
}

void dt_compiled_print(const dt_ctally *t) {
  printf("difftest --compiled: %ld models compiled and compared (%ld simulations), %ld stayed "
         "interpreted, %ld disagree; largest relative difference of the initial state and "
         "derivative %.3g (bound %g), of the compared states %.3g (%.3g of the trajectory "
         "bound)\n", t->compiled, t->runs, t->interpreted, t->disagree, t->worst_exact,
         RTOL_EXACT, t->worst_run_rel, t->worst_run);
  if (t->notice[0]) printf("difftest --compiled: e.g. %s\n", t->notice);
}
