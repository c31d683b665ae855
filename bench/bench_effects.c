/* bench_effects: what switching on every output channel and effect costs (issue 5 "Effects":
 * the same scene with only what it needs vs. with every output and effect channel switched
 * on, same run, report the ratio).
 *
 * The scene is the rolling disk (examples/scenes/rolling_disk.yaml's disk and state: plane
 * contact, rolling, gravity), simulated in minimal mode with dopri5 at rtol 1e-9 with an
 * output row every `interval` seconds (ap_scene_output_row, as `appell run` writes rows).
 * Configurations (each a scene text; the trajectory is the same in all, since the extra
 * effects have zero strength):
 *   needs        gravity; channels [coordinates]
 *   outputs      + every channel: speeds, angles, com, contacts, energy, residual, reactions,
 *                contact_forces
 *   effects      + a spring (stiffness and damping 0), joint damping 0, an applied force 0
 *   all          outputs and effects
 *   all_timed    all, the applied force given as an expression of t that is 0 ("0*sin(t)"):
 *                the expression is evaluated at every evaluation
 * One repeat = ap_sim_create + advance through every output time + the rows + ap_sim_free
 * (the scene is loaded and its initial state computed once, outside the timing). The
 * configurations are timed in turn within each repeat, after one warm-up round; reported are
 * the median over the repeats (thread CPU time) with min..max, the ratio of medians to
 * "needs", and the work from the counters (steps, evaluations, effect evaluations, energy and
 * reaction evaluations). Usage: bench_effects [--csv FILE] [--repeats N] [--t-end T]
 * [--interval S]. Run with OPENBLAS_NUM_THREADS=1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "appell/appell.h"
#include "benchutil.h"
#include "scene/scene_int.h"

#define NCONF 5

static const char scene_head[] =
    "name: disk\n"
    "bodies:\n"
    "  disk: {mass: 1.0, shape: {kind: disk, radius: 0.5}, inertia: uniform}\n"
    "joints:\n"
    "  disk: {kind: plane_contact}\n"
    "constraints:\n"
    "  roll: {kind: rolling, body: disk}\n"
    "initial:\n"
    "  disk: {heading: 0, tilt: 60*deg, spin: 0, spin_rate: -6.0, heading_rate: 4.0}\n"
    "simulation: {mode: minimal, method: dopri5, rtol: 1e-9, atol: 1e-11, t_end: %g}\n"
    "output:\n"
    "  interval: %g\n"
    "  channels: %s\n"
    "effects:\n"
    "  gravity: {kind: gravity, g: [0, 0, -9.81]}\n";

static const char extra_effects[] =
    "  spring: {kind: spring, body: disk, point: [0.5, 0, 0], point2: [0, 0, 1], stiffness: 0, "
    "damping: 0}\n"
    "  damping: {kind: joint_damping, joint: disk, damping: 0}\n"
    "  push: {kind: applied, body: disk, point: [0, 0.5, 0], force: [0, 0, %s], torque: [0, 0, "
    "0]}\n";

static const char lean_channels[] = "[coordinates]";
static const char all_channels[] =
    "[coordinates, speeds, angles, com, contacts, energy, residual, reactions, contact_forces]";

typedef struct conf {
  const char *name;
  int outputs, effects;
  const char *force;           /* the applied force's z component */
  ap_scene *sc;
  double q0[16], v0[16];
  double *ns;                  /* one time per repeat */
  long steps, evals, velocity, effect_evals, energy, reactions, rows, ncols;
  double q_end[16];
} conf;

static void load(conf *c, double t_end, double interval) {
  char text[4096], effs[1024] = "", msg[1024] = "";
  int len = snprintf(text, sizeof text, scene_head, t_end, interval,
                     c->outputs ? all_channels : lean_channels);
  if (c->effects) snprintf(effs, sizeof effs, extra_effects, c->force);
  snprintf(text + len, sizeof text - (size_t)len, "%s", effs);
  if (ap_scene_load_string(text, strlen(text), c->name, NULL, 0, &c->sc, msg, sizeof msg) != AP_OK)
    bench_die(c->name, msg);
  if (ap_model_n(ap_scene_model(c->sc)) > 16 || ap_scene_output_count(c->sc) > 64)
    bench_die(c->name, "model or row too large");
  if (ap_scene_initial_state(c->sc, c->q0, c->v0, NULL, 0, msg, sizeof msg) != AP_OK)
    bench_die(c->name, msg);
}

/* One run: create, advance through every output time writing rows, free. With `record` the
 * counters of the run are kept. */
static void run_once(conf *c, int record) {
  const ap_model *m = ap_scene_model(c->sc);
  ap_scene_run sr;
  ap_scene_get_run(c->sc, &sr);
  char msg[512];
  double row[64];
  ap_sim *s = NULL;
  long rows = 0, nrows = lround((sr.t_end - sr.t0) / sr.interval);
  long e0 = sc_scene_output_data(c->sc)->cnt.energy;
  if (ap_sim_create(m, &sr.sim, sr.t0, c->q0, c->v0, &s, msg, sizeof msg) != AP_OK)
    bench_die(c->name, msg);
  for (long i = 0; i <= nrows; i++) {
    if (i > 0 && ap_sim_advance(s, sr.t0 + (double)i * sr.interval) != AP_OK)
      bench_die(c->name, ap_sim_message(s));
    if (ap_scene_output_row(c->sc, s, row) != AP_OK) bench_die(c->name, "output row failed");
    rows++;
  }
  if (record) {
    ap_sim_stats st;
    ap_sim_get_stats(s, &st);
    const ap_data *d = ap_sim_data(s);
    c->steps = st.steps, c->evals = st.rhs_evals, c->velocity = d->cnt.velocity;
    c->reactions = d->cnt.reactions, c->rows = rows, c->ncols = ap_scene_output_count(c->sc);
    c->energy = sc_scene_output_data(c->sc)->cnt.energy - e0;
    c->effect_evals = 0;
    for (int e = 0; e < ap_scene_count(c->sc, AP_SCENE_EFFECTS); e++)
      c->effect_evals += ap_body_effect_count(m, d, e);
    memcpy(c->q_end, ap_sim_q(s), sizeof(double) * (size_t)ap_model_n(m));
  }
  ap_sim_free(s);
}

int main(int argc, char **argv) {
  int repeats = 21;
  double t_end = 2.0, interval = 0.01;
  const char *csv = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!strcmp(argv[i], "--repeats") && i + 1 < argc) repeats = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--t-end") && i + 1 < argc) t_end = atof(argv[++i]);
    else if (!strcmp(argv[i], "--interval") && i + 1 < argc) interval = atof(argv[++i]);
    else {
      fprintf(stderr, "usage: bench_effects [--csv FILE] [--repeats N] [--t-end T] "
                      "[--interval S]\n");
      return 2;
    }
  }
  if (repeats < 1 || !(t_end > 0) || !(interval > 0) || interval > t_end) return 2;

  conf C[NCONF] = {{"needs", 0, 0, "0", NULL, {0}, {0}, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0}},
                   {"outputs", 1, 0, "0", NULL, {0}, {0}, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0}},
                   {"effects", 0, 1, "0", NULL, {0}, {0}, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0}},
                   {"all", 1, 1, "0", NULL, {0}, {0}, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0}},
                   {"all_timed", 1, 1, "\"0*sin(t)\"", NULL, {0}, {0}, NULL, 0, 0, 0, 0, 0, 0,
                    0, 0, {0}}};
  for (int c = 0; c < NCONF; c++) {
    load(&C[c], t_end, interval);
    C[c].ns = malloc(sizeof(double) * (size_t)repeats);
    if (!C[c].ns) bench_die("timing", "out of memory");
    run_once(&C[c], 1);   /* warm-up, and the counters of one run */
  }
  for (int r = 0; r < repeats; r++)
    for (int c = 0; c < NCONF; c++) {
      double t0 = bench_thread_ns();
      run_once(&C[c], 0);
      C[c].ns[r] = bench_thread_ns() - t0;
    }

  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (csv && !out) bench_die(csv, "cannot write");
  if (out)
    fprintf(out, "config,columns,effects,median_ms,min_ms,max_ms,ratio,steps,rhs_evals,"
                 "velocity_stages,effect_evals,energy_evals,reaction_solves,rows\n");
  printf("rolling disk, minimal dopri5 rtol 1e-9, t = 0 .. %g s, a row every %g s; median of %d "
         "runs\n\n", t_end, interval, repeats);
  printf("%-10s %4s %4s %9s %19s %6s %6s %6s %8s %8s %7s %7s %10s\n", "config", "cols", "effs",
         "ms", "(min..max)", "ratio", "steps", "evals", "vel.st", "eff.ev", "energy", "react",
         "max|dq|");
  double base = 0.0;
  for (int c = 0; c < NCONF; c++) {
    qsort(C[c].ns, (size_t)repeats, sizeof(double), bench_cmp_double);
    double med = C[c].ns[repeats / 2] * 1e-6, lo = C[c].ns[0] * 1e-6,
           hi = C[c].ns[repeats - 1] * 1e-6;
    if (c == 0) base = med;
    double dq = 0.0;
    for (int i = 0; i < ap_model_n(ap_scene_model(C[c].sc)); i++)
      dq = fmax(dq, fabs(C[c].q_end[i] - C[0].q_end[i]));
    int ne = ap_scene_count(C[c].sc, AP_SCENE_EFFECTS);
    printf("%-10s %4ld %4d %9.3f (%7.3f..%8.3f) %6.3f %6ld %6ld %6ld %8ld %8ld %7ld %10.1e\n",
           C[c].name, C[c].ncols, ne, med, lo, hi, med / base, C[c].steps, C[c].evals,
           C[c].velocity, C[c].effect_evals, C[c].energy, C[c].reactions, dq);
    if (out)
      fprintf(out, "%s,%ld,%d,%.4f,%.4f,%.4f,%.4f,%ld,%ld,%ld,%ld,%ld,%ld,%ld\n", C[c].name,
              C[c].ncols, ne, med, lo, hi, med / base, C[c].steps, C[c].evals, C[c].velocity,
              C[c].effect_evals, C[c].energy, C[c].reactions, C[c].rows);
  }
  if (out) fclose(out);
  for (int c = 0; c < NCONF; c++) {
    free(C[c].ns);
    ap_scene_free(C[c].sc);
  }
  return 0;
}
