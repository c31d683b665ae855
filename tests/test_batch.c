/* test_batch: the batch API (include/appell/batch.h) in process.
 *
 * Plans: ranges against their closed form (A + m (B - A)/(N - 1), B exactly at the end), lists
 * with words, the product order, counter-based random values (the same from any slice; the
 * moments of normal and uniform samples within 5 standard errors), and every malformed spec
 * refused with a message. Batches: bad input refused once at creation (scene, override,
 * channel, time); each row equals `appell run`'s state for the same overrides (ap_scene + ap_sim
 * by hand here); failures are rows; a progress callback that cancels leaves the runs never
 * started as AP_BATCH_NOT_RUN rows and the one under way interrupted; NULL arguments are
 * refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

static char scene_path[1200];

static void find_scene(void) {
  char dir[1024];
  ct_find_source(dir, sizeof dir);
  snprintf(scene_path, sizeof scene_path, "%s/examples/scenes/rolling_disk.yaml", dir);
}

/* ---- plans -------------------------------------------------------------------------------- */

static void plan_grids(void) {
  ap_plan *p = NULL;
  char msg[512], buf[256];
  AP_CHECK_EQ_INT(ap_plan_create(&p), AP_OK);
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "initial.disk.tilt=70*deg:89*deg:4", msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "simulation.method=dopri5, 2*pi ,verner6", msg, sizeof msg),
                  AP_OK);
  AP_CHECK_EQ_INT(ap_plan_count(p), 12);
  AP_CHECK_EQ_INT(ap_plan_nparams(p), 2);
  AP_CHECK(strcmp(ap_plan_path(p, 1), "simulation.method") == 0);
  double a = 70 * (3.14159265358979323846 / 180), b = 89 * (3.14159265358979323846 / 180), x;
  for (long i = 0; i < 12; i++) {   /* the first grid varies slowest */
    AP_CHECK_EQ_INT(ap_plan_value(p, i, 0, &x, buf, sizeof buf), AP_OK);
    long m = i / 3;
    double want = m == 3 ? b : a + (double)m * ((b - a) / 3.0);
    AP_CHECK(x == want);
    AP_CHECK(strtod(strchr(buf, '=') + 1, NULL) == x);   /* 17 digits read back exactly */
  }
  AP_CHECK_EQ_INT(ap_plan_value(p, 4, 1, &x, buf, sizeof buf), AP_OK);
  AP_CHECK(x == 2 * 3.14159265358979323846 && strcmp(buf, "simulation.method=6.2831853071795862") == 0);
  AP_CHECK_EQ_INT(ap_plan_value(p, 5, 1, &x, buf, sizeof buf), AP_OK);
  AP_CHECK(isnan(x) && strcmp(buf, "simulation.method=verner6") == 0);
  AP_CHECK_EQ_INT(ap_plan_value(p, 12, 0, &x, buf, sizeof buf), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_plan_value(p, 0, 2, &x, buf, sizeof buf), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_plan_value(p, 0, 0, &x, buf, 8), AP_ERR_ARG);   /* too short */
  AP_CHECK_EQ_INT(ap_plan_typical(p, 1, buf, sizeof buf), AP_OK);
  AP_CHECK(strcmp(buf, "simulation.method=dopri5") == 0);
  ap_plan_free(p);
}

static void plan_errors(void) {
  static const char *const grids[][2] = {
      {"bodies.disk.mass", "expected PATH=VALUES"},
      {"=1:2:3", "expected PATH=VALUES"},
      {"bodies.disk mass=1", "blank in the path"},
      {"bodies.disk.mass=1:2", "expected PATH=A:B:N"},
      {"bodies.disk.mass=1:2:3:4", "expected PATH=A:B:N"},
      {"bodies.disk.mass=1:2:0", "N must be a whole number"},
      {"bodies.disk.mass=1:2:2.5", "N must be a whole number"},
      {"bodies.disk.mass=1*:2:3", "cannot parse"},
      {"bodies.disk.mass=1,,2", "an empty value"},
      {"bodies.disk.mass=1,2*(3", "cannot parse"},
      {"bodies.disk.mass=1:1e400:3", "finite number"},
  };
  static const char *const randoms[][2] = {
      {"bodies.disk.mass=gauss(1,2)", "expected PATH=normal(MU,SIGMA)"},
      {"bodies.disk.mass=normal(1)", "two arguments"},
      {"bodies.disk.mass=normal(1,2,3)", "two arguments"},
      {"bodies.disk.mass=normal(1,-2)", "must not be negative"},
      {"bodies.disk.mass=uniform(2,1)", "needs A <= B"},
      {"bodies.disk.mass=normal(1,x)", "unknown name"},
  };
  ap_plan *p = NULL;
  char msg[512];
  ap_plan_create(&p);
  for (size_t i = 0; i < sizeof grids / sizeof grids[0]; i++) {
    msg[0] = '\0';
    AP_CHECK_EQ_INT(ap_plan_add_grid(p, grids[i][0], msg, sizeof msg), AP_ERR_ARG);
    if (!strstr(msg, grids[i][1])) fprintf(stderr, "grid '%s': message '%s'\n", grids[i][0], msg);
    AP_CHECK(strstr(msg, grids[i][1]) != NULL);
  }
  for (size_t i = 0; i < sizeof randoms / sizeof randoms[0]; i++) {
    msg[0] = '\0';
    AP_CHECK_EQ_INT(ap_plan_add_random(p, randoms[i][0], msg, sizeof msg), AP_ERR_ARG);
    if (!strstr(msg, randoms[i][1])) fprintf(stderr, "random '%s': '%s'\n", randoms[i][0], msg);
    AP_CHECK(strstr(msg, randoms[i][1]) != NULL);
  }
  AP_CHECK_EQ_INT(ap_plan_nparams(p), 0);   /* refused specs leave nothing behind */
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "a=1:2:100000", msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "b=1:2:100000", msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "c=1:2:1000000", msg, sizeof msg), AP_ERR_ARG);   /* > 2^53 */
  /* A path varied twice: the later value won in the runs while the table listed both. */
  msg[0] = '\0';
  AP_CHECK_EQ_INT(ap_plan_add_grid(p, "a=3,4", msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "'a' is varied twice") != NULL);
  msg[0] = '\0';
  AP_CHECK_EQ_INT(ap_plan_add_random(p, "b=uniform(1,2)", msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "'b' is varied twice") != NULL);
  AP_CHECK_EQ_INT(ap_plan_nparams(p), 2);
  AP_CHECK_EQ_INT(ap_plan_add_grid(NULL, "a=1", msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_plan_add_random(p, NULL, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_plan_set_samples(p, 0, 1), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_plan_create(NULL), AP_ERR_ARG);
  ap_plan_free(p);
  ap_plan_free(NULL);
}

static void plan_random(void) {
  ap_plan *p = NULL, *q = NULL;
  char msg[256];
  ap_plan_create(&p);
  ap_plan_add_random(p, "m=normal(2,0.5)", msg, sizeof msg);
  ap_plan_add_random(p, "r=uniform(-1,3)", msg, sizeof msg);
  ap_plan_add_grid(p, "g=1,2", msg, sizeof msg);   /* grids go first */
  const long n = 20000;
  AP_CHECK_EQ_INT(ap_plan_set_samples(p, n, 42), AP_OK);
  AP_CHECK_EQ_INT(ap_plan_count(p), 2 * n);
  AP_CHECK(strcmp(ap_plan_path(p, 0), "g") == 0 && strcmp(ap_plan_path(p, 2), "r") == 0);
  double s1 = 0, s2 = 0, u1 = 0, umin = 1e9, umax = -1e9, x, y;
  long differ = 0;
  for (long j = 0; j < n; j++) {
    ap_plan_value(p, j, 1, &x, NULL, 0);
    ap_plan_value(p, n + j, 1, &y, NULL, 0);
    differ += x != y;   /* sample j has the same value at every grid point */
    s1 += x, s2 += x * x;
    ap_plan_value(p, j, 2, &x, NULL, 0);
    u1 += x, umin = fmin(umin, x), umax = fmax(umax, x);
  }
  AP_CHECK_EQ_INT(differ, 0);
  double mean = s1 / n, sd = sqrt(s2 / n - mean * mean);
  AP_CHECK_NEAR(mean, 2.0, 5 * 0.5 / sqrt((double)n));
  AP_CHECK_NEAR(sd, 0.5, 5 * 0.5 / sqrt(2.0 * n));
  AP_CHECK_NEAR(u1 / n, 1.0, 5 * 4.0 / sqrt(12.0 * n));
  AP_CHECK(umin >= -1 && umax < 3 && umin < -0.99 && umax > 2.99);
  /* the same seed gives the same numbers in another plan; another seed others */
  ap_plan_create(&q);
  ap_plan_add_grid(q, "g=1,2", msg, sizeof msg);
  ap_plan_add_random(q, "m=normal(2,0.5)", msg, sizeof msg);
  ap_plan_add_random(q, "r=uniform(-1,3)", msg, sizeof msg);
  ap_plan_set_samples(q, n, 42);
  ap_plan_value(p, 12345, 2, &x, NULL, 0);
  ap_plan_value(q, 12345, 2, &y, NULL, 0);
  AP_CHECK(x == y);
  ap_plan_set_samples(q, n, 43);
  ap_plan_value(q, 12345, 2, &y, NULL, 0);
  AP_CHECK(x != y);
  ap_plan_free(p);
  ap_plan_free(q);
}

/* ---- batches ------------------------------------------------------------------------------ */

static void batch_errors(void) {
  char msg[1024];
  ap_batch *b = NULL;
  ap_batch_def def = ap_batch_def_default();
  const char *bad_set[] = {"bodies.disk.mas=2"};
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, bad_set, 1, &def, &b, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(b == NULL && strstr(msg, "did you mean 'mass'"));
  const char *ch[] = {"disk.tlit"};
  def.channels = ch, def.nchannels = 1;
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, NULL, 0, &def, &b, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "channel 'disk.tlit': no output column of that name in the scene "
                      "(did you mean 'disk.tilt'?") != NULL);
  double t[] = {NAN};
  def = ap_batch_def_default();
  def.times = t, def.ntimes = 1;
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, NULL, 0, &def, &b, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "not finite") != NULL);
  AP_CHECK_EQ_INT(ap_batch_load("no/such.yaml", NULL, 0, NULL, &b, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK(strstr(msg, "cannot open") != NULL);
  AP_CHECK_EQ_INT(ap_batch_create("bodies: [", 9, "x.yaml", NULL, 0, NULL, &b, msg, sizeof msg),
                  AP_ERR_ARG);
  AP_CHECK(strncmp(msg, "x.yaml:", 7) == 0);
  AP_CHECK_EQ_INT(ap_batch_create(NULL, 0, "x", NULL, 0, NULL, &b, msg, sizeof msg), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_batch_create("a: 1", 4, "x", NULL, 0, NULL, NULL, msg, sizeof msg),
                  AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_batch_run(NULL, 1, 0, NULL, NULL, NULL, NULL), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_batch_ncols(NULL), 0);
  AP_CHECK(ap_batch_col_name(NULL, 0) == NULL);
  ap_batch_free(NULL);
}

/* The state where `appell run` ends with these overrides: scene, initial state, sim. */
static int reference_end(const char *const *sets, int nsets, double *qv, int *n, int *k) {
  char msg[1024];
  ap_scene *sc = NULL;
  int rc = ap_scene_load(scene_path, sets, nsets, &sc, msg, sizeof msg);
  if (rc != AP_OK) return rc;
  const ap_model *m = ap_scene_model(sc);
  *n = ap_model_n(m), *k = ap_model_k(m);
  double q0[16], v0[16];
  ap_scene_run run;
  ap_sim *sim = NULL;
  ap_scene_get_run(sc, &run);
  rc = ap_scene_initial_state(sc, q0, v0, NULL, 0, msg, sizeof msg);
  if (rc == AP_OK) rc = ap_sim_create(m, &run.sim, run.t0, q0, v0, &sim, msg, sizeof msg);
  long rows = (long)ceil((run.t_end - run.t0) / run.interval - 1e-9);
  for (long i = 1; rc == AP_OK && i <= rows; i++)
    rc = ap_sim_advance(sim, i == rows ? run.t_end : run.t0 + (double)i * run.interval);
  if (rc == AP_OK) {
    memcpy(qv, ap_sim_q(sim), sizeof(double) * (size_t)*n);
    memcpy(qv + *n, ap_sim_v(sim), sizeof(double) * (size_t)*k);
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
  return rc;
}

static void batch_rows(void) {
  char msg[1024];
  const char *base[] = {"simulation.t_end=0.5"};
  ap_batch *b = NULL;
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, base, 1, NULL, &b, msg, sizeof msg), AP_OK);
  if (!b) return;
  int nc = ap_batch_ncols(b);
  AP_CHECK_EQ_INT(nc, 6 + 6 + 5);
  AP_CHECK(strcmp(ap_batch_col_name(b, 6), "disk.x@end") == 0);
  AP_CHECK(strcmp(ap_batch_col_name(b, 16), "disk.wz@end") == 0);
  const char *sets[] = {"bodies.disk.mass=2", "bodies.disk.mass=0", "initial.disk.tilt=80*deg",
                        "simulation.max_steps=3"};
  double values[4 * 17];
  int status[4];
  char *messages[4];
  AP_CHECK_EQ_INT(ap_batch_run(b, 4, 1, sets, values, status, messages), AP_OK);
  int expect[4] = {AP_OK, AP_ERR_ARG, AP_OK, AP_ERR_SOLVER};
  for (int i = 0; i < 4; i++) {
    AP_CHECK_EQ_INT(status[i], expect[i]);
    double ref[16];
    int n = 0, k = 0;
    const char *all[] = {base[0], sets[i]};
    if (expect[i] == AP_OK && reference_end(all, 2, ref, &n, &k) == AP_OK)
      AP_CHECK(memcmp(values + i * nc + 6, ref, sizeof(double) * (size_t)(n + k)) == 0);
  }
  AP_CHECK(messages[1] && strstr(messages[1], "rolling_disk.yaml:") &&
           strstr(messages[1], "bodies.disk.mass"));
  AP_CHECK(isnan(values[1 * nc]));   /* never started: no time reached */
  AP_CHECK(messages[3] && strstr(messages[3], "the simulation failed at t = "));
  AP_CHECK(values[3 * nc] < 0.5 && values[3 * nc + 1] >= 3);   /* failed on the way */
  AP_CHECK(!messages[0] && !messages[2]);
  ap_batch_messages_free(4, messages);
  AP_CHECK(messages[1] == NULL);
  ap_batch_free(b);
}

/* An output interval past t_end by more than 1e9 still runs to t_end (a row count of
 * ceil(T / dt - 1e-9) = 0 made the run stop at t0 with status 0 and no step). */
static void batch_long_interval(void) {
  char msg[1024];
  const char *base[] = {"simulation.t_end=0.5", "output.interval=1e9"};
  ap_batch *b = NULL;
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, base, 2, NULL, &b, msg, sizeof msg), AP_OK);
  if (!b) return;
  double values[17];
  int status = -99;
  AP_CHECK_EQ_INT(ap_batch_run(b, 1, 0, NULL, values, &status, NULL), AP_OK);
  AP_CHECK_EQ_INT(status, AP_OK);
  AP_CHECK_NEAR(values[0], 0.5, 0.0);   /* t reached */
  AP_CHECK(values[1] > 0);              /* steps */
  ap_batch_free(b);
}

static int cancel_after_first(long done, long total, void *user) {
  (void)total;
  int *calls = user;
  ++*calls;
  return done >= 1;
}

static void batch_cancel(void) {
  char msg[1024];
  ap_plan *p = NULL;
  ap_plan_create(&p);
  ap_plan_add_grid(p, "initial.disk.spin_rate=-8:-4:200", msg, sizeof msg);
  const char *base[] = {"simulation.t_end=2", "simulation.rtol=1e-10"};
  int calls = 0;
  ap_batch_def def = ap_batch_def_default();
  def.progress = cancel_after_first, def.user = &calls;
  ap_batch *b = NULL;
  AP_CHECK_EQ_INT(ap_batch_load(scene_path, base, 2, &def, &b, msg, sizeof msg), AP_OK);
  long count = ap_plan_count(p);
  int nc = ap_batch_ncols(b), *status = calloc((size_t)count, sizeof *status);
  double *values = calloc((size_t)(count * nc), sizeof *values);
  AP_CHECK_EQ_INT(ap_batch_check_plan(b, p, msg, sizeof msg), AP_OK);
  AP_CHECK_EQ_INT(ap_batch_run_plan(b, p, 0, count + 1, values, status, NULL), AP_ERR_ARG);
  AP_CHECK_EQ_INT(ap_batch_run_plan(b, p, 0, count, values, status, NULL), AP_BATCH_CANCELLED);
  long ok = 0, not_run = 0, stopped = 0;
  for (long i = 0; i < count; i++) {
    ok += status[i] == AP_OK, not_run += status[i] == AP_BATCH_NOT_RUN;
    stopped += status[i] == AP_ERR_INTERRUPTED;
    if (status[i] == AP_BATCH_NOT_RUN) AP_CHECK(isnan(values[i * nc]));
    if (status[i] == AP_ERR_INTERRUPTED) AP_CHECK(values[i * nc] < 2.0);   /* stopped on the way */
  }
  AP_CHECK(calls >= 1 && ok >= 1 && not_run >= 1 && ok + not_run + stopped == count);
  printf("cancelled after %ld of %ld runs (%ld interrupted)\n", ok, count, stopped);
  free(status);
  free(values);
  ap_batch_free(b);
  ap_plan_free(p);
}

int main(void) {
  find_scene();
  plan_grids();
  plan_errors();
  plan_random();
  batch_errors();
  batch_rows();
  batch_long_interval();
  batch_cancel();
  return ap_check_finish("test_batch");
}
