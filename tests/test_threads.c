/* test_threads: one compiled model shared by 8 threads gives, bit for bit, what serial runs
 * give; so does the batch API with 8 workers against 1. Built and run under ThreadSanitizer by
 * scripts/tsan (suite 'threads'), where any data race fails the test, and in the plain and
 * ASan builds as an ordinary test.
 *
 * Shared: the ap_scene (its model, parsed tree and settings) of the rolling disk and of
 * Hoffmann's loop; each thread makes its own initial state from it, its own simulation (mode
 * and method differ per thread: minimal, projected, plain and DAE; ARKODE, CVODE and IDA) and
 * its own output evaluator (ap_scene_out), and records every output row. Then the same with
 * functions of time evaluated by all threads at once (the turntable's Omega(t), Hoffmann's
 * push f(t)). Then ap_batch_run of 24 variants, including failing ones, with 8 threads and
 * with 1: the workers load their scenes in parallel (YAML, --set paths, expressions).
 * Last, one const ap_data of N rolling disks on the tree path queried by 8 threads at once with
 * ap_body_contact_force (it took a const data but wrote the tree's twist scratch): every
 * thread's forces equal the serial ones bit for bit, and TSan sees no race. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"
#include "treemodels.h"

#define NT 8
#define T_END 1.0
#define DT 0.05
#define NROWS 21   /* t = 0, 0.05, ..., 1 */

static char srcdir[1024];

static ap_scene *load(const char *name, const char *const *sets, int nsets) {
  char path[1200], msg[1024];
  snprintf(path, sizeof path, "%s/examples/scenes/%s", srcdir, name);
  ap_scene *sc = NULL;
  if (ap_scene_load(path, sets, nsets, &sc, msg, sizeof msg) != AP_OK)
    fprintf(stderr, "%s\n", msg);
  return sc;
}

/* One thread's run and what it recorded. */
typedef struct job {
  ap_scene *sc;            /* shared, read only */
  ap_mode mode;
  const char *method;
  double scale;            /* initial speeds times this (the constraints are homogeneous) */
  int status;
  double *rows;            /* (NROWS x ncols) */
  double final[64];
  long steps, evals;
} job;

static int run_job(job *j) {
  const ap_model *m = ap_scene_model(j->sc);
  int n = ap_model_n(m), k = ap_model_k(m), nc = ap_scene_output_count(j->sc);
  double q0[32], v0[32];
  char msg[1024];
  int rc = ap_scene_initial_state(j->sc, q0, v0, NULL, 0, msg, sizeof msg);
  if (rc != AP_OK) return rc;
  for (int i = 0; i < k; i++) v0[i] *= j->scale;
  ap_scene_run run;
  ap_scene_get_run(j->sc, &run);
  run.sim.mode = j->mode, run.sim.method = j->method;
  ap_sim *sim = NULL;
  ap_scene_out *out = NULL;
  rc = ap_sim_create(m, &run.sim, 0.0, q0, v0, &sim, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_scene_out_create(j->sc, &out);
  for (int r = 0; rc == AP_OK && r < NROWS; r++) {
    if (r > 0) rc = ap_sim_advance(sim, r == NROWS - 1 ? T_END : r * DT);
    if (rc == AP_OK) rc = ap_scene_out_row(out, sim, j->rows + (size_t)r * (size_t)nc);
  }
  if (sim) {
    ap_sim_stats st;
    ap_sim_get_stats(sim, &st);
    j->steps = st.steps, j->evals = st.rhs_evals;
    memcpy(j->final, ap_sim_q(sim), sizeof(double) * (size_t)n);
    memcpy(j->final + n, ap_sim_v(sim), sizeof(double) * (size_t)k);
  }
  ap_scene_out_free(out);
  ap_sim_free(sim);
  return rc;
}

static void *thread_main(void *arg) {
  job *j = arg;
  j->status = run_job(j);
  return NULL;
}

static void setup_jobs(job *jobs, ap_scene *sc) {
  static const ap_mode modes[NT] = {AP_MODE_MINIMAL, AP_MODE_PROJECTED, AP_MODE_DAE,
                                    AP_MODE_MINIMAL, AP_MODE_PLAIN, AP_MODE_MINIMAL,
                                    AP_MODE_PROJECTED, AP_MODE_MINIMAL};
  static const char *const methods[NT] = {"dopri5", "verner6", "dopri5", "bdf",
                                          "fehlberg8", "adams", "bs3", "dopri5"};
  size_t per = (size_t)NROWS * (size_t)ap_scene_output_count(sc);
  for (int i = 0; i < NT; i++) {
    memset(&jobs[i], 0, sizeof jobs[i]);
    jobs[i].sc = sc, jobs[i].mode = modes[i], jobs[i].method = methods[i];
    jobs[i].scale = 1.0 + 0.01 * i;
    jobs[i].rows = calloc(per, sizeof(double));
  }
}

/* Serial runs, then the same jobs in NT threads at once: every recorded number equal. */
static void shared_model(const char *scene, const char *set) {
  ap_scene *sc = load(scene, &set, set ? 1 : 0);
  AP_CHECK(sc != NULL);
  if (!sc) return;
  job serial[NT], par[NT];
  setup_jobs(serial, sc);
  setup_jobs(par, sc);
  for (int i = 0; i < NT; i++) serial[i].status = run_job(&serial[i]);
  pthread_t tid[NT];
  for (int i = 0; i < NT; i++) AP_CHECK(pthread_create(&tid[i], NULL, thread_main, &par[i]) == 0);
  for (int i = 0; i < NT; i++) pthread_join(tid[i], NULL);
  size_t per = (size_t)NROWS * (size_t)ap_scene_output_count(sc);
  for (int i = 0; i < NT; i++) {
    AP_CHECK_EQ_INT(serial[i].status, AP_OK);
    AP_CHECK_EQ_INT(par[i].status, serial[i].status);
    AP_CHECK(memcmp(par[i].rows, serial[i].rows, per * sizeof(double)) == 0);
    AP_CHECK(memcmp(par[i].final, serial[i].final, sizeof par[i].final) == 0);
    AP_CHECK_EQ_INT(par[i].steps, serial[i].steps);
    AP_CHECK_EQ_INT(par[i].evals, serial[i].evals);
    AP_CHECK(serial[i].steps > 10);
    free(serial[i].rows);
    free(par[i].rows);
  }
  printf("%s%s%s: %d threads sharing one model, rows equal to the serial runs bit for bit\n",
         scene, set ? " --set " : "", set ? set : "", NT);
  ap_scene_free(sc);
}

/* ---- the batch API ------------------------------------------------------------------------ */

#define NV 24

/* The batch of scene with NV variants of (a, b); returns the number that failed. */
static int batch_threads(const char *scene, const char *const *base, int nbase,
                         const char *const *channels, int nch, void (*variant)(int, char *, char *)) {
  char path[1200], msg[1024], set[NV][2][96];
  snprintf(path, sizeof path, "%s/examples/scenes/%s", srcdir, scene);
  const double times[] = {0.5, 0.25, 1.0, 0.333};
  const char *sets[NV * 2];
  for (int i = 0; i < NV; i++) {
    variant(i, set[i][0], set[i][1]);
    sets[2 * i] = set[i][0], sets[2 * i + 1] = set[i][1];
  }
  double *values[2];
  int status[2][NV], nc = 0, bad = 0;
  char *messages[2][NV];
  for (int pass = 0; pass < 2; pass++) {
    ap_batch_def def = ap_batch_def_default();
    def.threads = pass == 0 ? 1 : NT;
    def.channels = channels, def.nchannels = nch, def.times = times, def.ntimes = 4;
    ap_batch *b = NULL;
    int rc = ap_batch_load(path, base, nbase, &def, &b, msg, sizeof msg);
    AP_CHECK_EQ_INT(rc, AP_OK);
    if (rc != AP_OK) return fprintf(stderr, "%s\n", msg), -1;
    nc = ap_batch_ncols(b);
    values[pass] = calloc((size_t)NV * (size_t)nc, sizeof(double));
    AP_CHECK_EQ_INT(ap_batch_run(b, NV, 2, sets, values[pass], status[pass], messages[pass]),
                    AP_OK);
    ap_batch_free(b);
  }
  for (int i = 0; i < NV; i++) {
    AP_CHECK_EQ_INT(status[1][i], status[0][i]);
    AP_CHECK(!messages[0][i] == !messages[1][i]);
    if (messages[0][i] && messages[1][i]) AP_CHECK(strcmp(messages[0][i], messages[1][i]) == 0);
    if (status[0][i] != AP_OK) AP_CHECK(messages[0][i] && strstr(messages[0][i], scene));
    bad += status[0][i] != AP_OK;
  }
  AP_CHECK(memcmp(values[0], values[1], sizeof(double) * (size_t)NV * (size_t)nc) == 0);
  printf("batch of %s: %d variants (%d failing) with %d threads and with 1: equal rows\n", scene,
         NV, bad, NT);
  for (int p = 0; p < 2; p++) {
    ap_batch_messages_free(NV, messages[p]);
    free(values[p]);
  }
  return bad;
}

/* Rolling disk: tilts, modes, and failures (an unknown method, a negative mass). */
static void disk_variant(int i, char *a, char *b) {
  snprintf(a, 96, "initial.disk.tilt=%.17g", 0.9 + 0.02 * i);
  snprintf(b, 96, "%s", i % 7 == 3 ? "simulation.method=bogus"
                        : i % 7 == 5 ? "bodies.disk.mass=-1"
                        : i % 2 ? "simulation.mode=dae" : "simulation.mode=minimal");
}

/* Turntable: Omega(t) differs per run (each load parses it); one unknown name. */
static void table_variant(int i, char *a, char *b) {
  snprintf(a, 96, i == 7 ? "ground.omega=%d*tanh(w)" : "ground.omega=%d*tanh(t)+0.1*sin(3*t)",
           1 + i % 5);
  snprintf(b, 96, "initial.ball.vy=%.17g", 0.05 + 0.01 * i);
}

#define NDISK 6
typedef struct cq_par {
  const ap_model *m;
  const ap_data *d;
  const ap_contact_force *ref;   /* NDISK serial results */
  int mismatches, fails;
} cq_par;

static void *contact_queries(void *arg) {
  cq_par *p = arg;
  for (int rep = 0; rep < 50; rep++)
    for (int c = 0; c < NDISK; c++) {
      ap_contact_force f;
      if (ap_body_contact_force(p->m, p->d, NULL, c, &f) != AP_OK) {
        p->fails++;
        continue;
      }
      p->mismatches += memcmp(f.force, p->ref[c].force, sizeof f.force) != 0;
    }
  return NULL;
}

static void shared_contact_force(void) {
  ap_model *m = tm_disks(NDISK, AP_PATH_TREE);
  ap_data *d = NULL;
  AP_CHECK_EQ_INT(ap_data_create(m, &d), AP_OK);
  if (!d) return;
  tm_disks_state(m, NDISK, d->q, d->v);
  d->want_reactions = 1;
  AP_CHECK_EQ_INT(ap_partition(m, d), AP_OK);
  AP_CHECK_EQ_INT(ap_forward(m, d), AP_OK);
  ap_contact_force ref[NDISK];
  for (int c = 0; c < NDISK; c++) {
    AP_CHECK_EQ_INT(ap_body_contact_force(m, d, NULL, c, &ref[c]), AP_OK);
    AP_CHECK(ref[c].normal > 0);   /* disks resting on the ground: they push it */
  }
  pthread_t tid[NT];
  cq_par par[NT];
  for (int i = 0; i < NT; i++) par[i] = (cq_par){m, d, ref, 0, 0};
  for (int i = 0; i < NT; i++) AP_CHECK(pthread_create(&tid[i], NULL, contact_queries, &par[i]) == 0);
  for (int i = 0; i < NT; i++) {
    pthread_join(tid[i], NULL);
    AP_CHECK_EQ_INT(par[i].fails, 0);
    AP_CHECK_EQ_INT(par[i].mismatches, 0);
  }
  printf("contact forces of %d disks (tree path), %d threads x 50 queries of one const data: "
         "F_n[0] = %.6f N\n", NDISK, NT, ref[0].normal);
  ap_data_free(d);
  ap_model_free(m);
}

int main(void) {
  ct_find_source(srcdir, sizeof srcdir);
  shared_contact_force();
  shared_model("rolling_disk.yaml", NULL);
  shared_model("hoffmann.yaml", NULL);
  shared_model("turntable_ball.yaml", "ground.omega=2*tanh(t)+0.3*sin(5*t)");
  shared_model("hoffmann.yaml", "effects.push.force.1=2*cos(3*t)");
  const char *disk_base[] = {"simulation.t_end=1", "simulation.rtol=1e-8"};
  const char *disk_ch[] = {"disk.tilt", "energy_error"};
  AP_CHECK_EQ_INT(batch_threads("rolling_disk.yaml", disk_base, 2, disk_ch, 2, disk_variant), 6);
  const char *table_base[] = {"simulation.t_end=1", "simulation.rtol=1e-8"};
  const char *table_ch[] = {"ball.x", "ball.wz"};
  AP_CHECK_EQ_INT(batch_threads("turntable_ball.yaml", table_base, 2, table_ch, 2, table_variant),
                  1);
  return ap_check_finish("test_threads");
}
