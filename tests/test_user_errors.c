/* test_user_errors: faults a new user met, each kept fixed (issue "Hardening").
 *
 * Library (ap_sim_create, ap_sim_advance): a NaN or Inf output time, a NaN start time and
 * max_steps give messages naming the value and the field; rank_rtol must lie in (0, 1) (a
 * scene with rank_rtol >= 1 is refused at its file:line:column); a stiff motor that makes an
 * explicit method give up or blow up gets the hint to try BDF, and a model without motors
 * does not. CLI: an option value that is another option ("--mode -o out.csv") is refused by
 * every subcommand with exit 2 and both names; `appell sweep --at T` outside the runs' time
 * range is refused before running; `appell plot` of a CSV with a header and no rows exits 2
 * and leaves no figure. tests/clitest.h runs the binary. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <appell/appell.h>

#include "check.h"
#include "clitest.h"

static char disk_scene[1200], motors_scene[1200];

/* Load path with the overrides, take the initial state and start a simulation at t0 (NULL
 * with the message in msg on failure). */
static ap_sim *start(const char *path, const char *const *sets, int nsets, double t0,
                     ap_scene **sc, char *msg, size_t len) {
  ap_sim *sim = NULL;
  *sc = NULL;
  if (ap_scene_load(path, sets, nsets, sc, msg, len) != AP_OK) return NULL;
  const ap_model *m = ap_scene_model(*sc);
  ap_scene_run run;
  ap_scene_get_run(*sc, &run);
  double *x = calloc((size_t)(ap_model_n(m) + ap_model_k(m)), sizeof *x);
  if (x && ap_scene_initial_state(*sc, x, x + ap_model_n(m), NULL, 0, msg, len) == AP_OK)
    ap_sim_create(m, &run.sim, t0, x, x + ap_model_n(m), &sim, msg, len);
  free(x);
  return sim;
}

static void test_times(void) {
  char msg[1024] = "";
  ap_scene *sc = NULL;
  /* was "the initial time t0 is -nan": neither the function nor what NaN means */
  ap_sim *sim = start(disk_scene, NULL, 0, NAN, &sc, msg, sizeof msg);
  AP_CHECK(sim == NULL);
  printf("t0 NaN: %s\n", msg);
  AP_CHECK(strstr(msg, "ap_sim_create: the initial time t0 is NaN; it must be a finite number"));
  ap_scene_free(sc);
  sim = start(disk_scene, NULL, 0, 0.0, &sc, msg, sizeof msg);
  AP_CHECK(sim != NULL);
  if (!sim) {
    ap_scene_free(sc);
    return;
  }
  /* was "tout = inf is not a finite time at or after t = 0" */
  const double bad[] = {NAN, INFINITY, -INFINITY};
  const char *says[] = {"the output time tout is NaN;", "the output time tout is +Inf;",
                        "the output time tout is -Inf;"};
  for (int i = 0; i < 3; i++) {
    AP_CHECK_EQ_INT(ap_sim_advance(sim, bad[i]), AP_ERR_ARG);
    printf("tout %g: %s\n", bad[i], ap_sim_message(sim));
    AP_CHECK(strstr(ap_sim_message(sim), says[i]) != NULL);
  }
  AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.01), AP_OK);
  AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.005), AP_ERR_ARG);
  AP_CHECK(strstr(ap_sim_message(sim), "tout = 0.005") &&
           strstr(ap_sim_message(sim), "is before the current time t = 0.01"));
  ap_sim_free(sim);
  ap_scene_free(sc);
}

/* max_steps: the message names the field, where the interval started and how far it got
 * (was "more than max_steps = 10 steps between t = <where it stopped> and 0.01"). */
static void test_max_steps(void) {
  const char *sets[] = {"simulation.max_steps=10"};
  char msg[1024] = "";
  ap_scene *sc = NULL;
  ap_sim *sim = start(disk_scene, sets, 1, 0.0, &sc, msg, sizeof msg);
  AP_CHECK(sim != NULL);
  if (sim) {
    AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.01), AP_ERR_SOLVER);
    const char *m = ap_sim_message(sim);
    printf("max_steps: %s\n", m);
    AP_CHECK(strstr(m, "max_steps = 10 steps from t = 0 reached only t = ") != NULL);
    AP_CHECK(strstr(m, "short of the output time 0.01") && strstr(m, "simulation.max_steps"));
    AP_CHECK(strstr(m, "--method bdf") == NULL);   /* no motor, spring or damper: no hint */
  }
  ap_sim_free(sim);
  ap_scene_free(sc);
}

/* kd = 1e5 N m s/rad on the wheel motors: dopri5 runs into max_steps and dop853 blows up in
 * its first steps; both messages point to BDF. */
static void test_stiff_hint(void) {
  const char *sets[] = {"effects.motor_l.kd=1e5", "effects.motor_r.kd=1e5",
                        "simulation.max_steps=2000", "simulation.method=dopri5"};
  const int want[] = {AP_ERR_SOLVER, AP_ERR_NAN};
  for (int i = 0; i < 2; i++) {
    if (i == 1) sets[3] = "simulation.method=dop853";
    char msg[1024] = "";
    ap_scene *sc = NULL;
    ap_sim *sim = start(motors_scene, sets, 4, 0.0, &sc, msg, sizeof msg);
    AP_CHECK(sim != NULL);
    if (sim) {
      AP_CHECK_EQ_INT(ap_sim_advance(sim, 0.05), want[i]);
      printf("%s: %s\n", sets[3], ap_sim_message(sim));
      AP_CHECK(strstr(ap_sim_message(sim), "the motor 'motor_l'") &&
               strstr(ap_sim_message(sim), "try --method bdf"));
    }
    ap_sim_free(sim);
    ap_scene_free(sc);
  }
}

static void test_rank_rtol(void) {
  /* ap_sim_def: rank_rtol >= 1 called every row after the first redundant (was accepted) */
  const char *sets[] = {"simulation.rank_rtol=0.5"};
  char msg[1024] = "";
  ap_scene *sc = NULL;
  ap_sim *sim = start(disk_scene, sets, 1, 0.0, &sc, msg, sizeof msg);
  AP_CHECK(sim != NULL);   /* 0.5 is a legal tolerance */
  ap_sim_free(sim);
  const ap_model *m = sc ? ap_scene_model(sc) : NULL;
  double x[64] = {0};
  const double bad[] = {1.0, 2.0, NAN, -1e-10, 0.0};
  for (int i = 0; m && i < 5; i++) {
    ap_sim_def def = ap_sim_def_default();
    def.rank_rtol = bad[i];
    AP_CHECK_EQ_INT(ap_sim_create(m, &def, 0.0, x, x + 32, &sim, msg, sizeof msg), AP_ERR_ARG);
    AP_CHECK(strstr(msg, "rank_rtol = ") && strstr(msg, "must lie in (0, 1)"));
  }
  printf("rank_rtol: %s\n", msg);
  ap_scene_free(sc);
  /* a scene: refused at the key, and through --set */
  char path[200];
  snprintf(path, sizeof path, "%s/rank.yaml", ct_tmp);
  FILE *in = fopen(disk_scene, "r"), *out = fopen(path, "w");
  char line[1024];
  int lines = 0, at = 0;
  while (in && out && fgets(line, sizeof line, in)) {
    fputs(line, out), lines++;
    if (strncmp(line, "simulation:", 11) == 0) fputs("  rank_rtol: 1.5\n", out), at = lines + 1;
  }
  if (in) fclose(in);
  if (out) fclose(out);
  char where[300];
  snprintf(where, sizeof where, "%s:%d:14: simulation.rank_rtol: must be below 1 (got 1.5",
           path, at);
  AP_CHECK_EQ_INT(ap_scene_load(path, NULL, 0, &sc, msg, sizeof msg), AP_ERR_ARG);
  printf("scene: %s\n", msg);
  AP_CHECK(strstr(msg, where) != NULL);
  unlink(path);
  const char *argv[] = {ct_bin, "check", disk_scene, "--set", "simulation.rank_rtol=1", NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 2);
  AP_CHECK(ct_log_has("--set simulation.rank_rtol=1: simulation.rank_rtol: must be below 1"));
}

/* "appell run scene.yaml --mode -o out.csv" took "-o" as the mode. */
static void test_option_as_value(void) {
  char csv[200];
  snprintf(csv, sizeof csv, "%s/out.csv", ct_tmp);
  const char *run[] = {ct_bin, "run", disk_scene, "--mode", "-o", csv, NULL};
  AP_CHECK_EQ_INT(ct_run(run), 2);
  AP_CHECK(ct_log_has("appell run: --mode needs a value; got the option -o"));
  AP_CHECK(access(csv, F_OK) != 0);
  const char *const cases[][7] = {
      {"run", "--out", "--quiet", "appell run: --out needs a file name; got the option --quiet"},
      {"run", "--set", "--quiet", "appell run: --set needs PATH=VALUE; got the option --quiet"},
      {"sweep", "--at", "-o", "appell sweep: --at needs a value; got the option -o"},
      {"sweep", "--jobs", "--quiet", "appell sweep: --jobs needs a value; got the option --quiet"},
      {"check", "--set", "--help", "appell check: --set needs PATH=VALUE; got the option --help"},
      {"linearize", "--csv", "--plot", "appell linearize: --csv needs a value; got the option "
                                       "--plot"},
      {"bench", "--csv", "-q", "appell bench: --csv needs a value; got the option -q"},
      {"plot", "--y", "-o", "appell plot: --y needs a value; got the option -o"}};
  for (int i = 0; i < 8; i++) {
    const char *argv[] = {ct_bin, cases[i][0], disk_scene, cases[i][1], cases[i][2], "x", NULL};
    AP_CHECK_EQ_INT(ct_run(argv), 2);
    if (!ct_log_has(cases[i][3])) fprintf(stderr, "missing: %s\n", cases[i][3]);
    AP_CHECK(ct_log_has(cases[i][3]));
  }
  /* a negative number and "-" (standard output) are values */
  const char *neg[] = {ct_bin, "run", disk_scene, "--t-end", "-1", NULL};
  AP_CHECK_EQ_INT(ct_run(neg), 2);
  AP_CHECK(ct_log_has("simulation.t_end (set by --set simulation.t_end=-1): must be after t0"));
  const char *dash[] = {ct_bin, "run", disk_scene, "--t-end", "0.02", "--out", "-", "--quiet",
                        NULL};
  AP_CHECK_EQ_INT(ct_run(dash), 0);
  AP_CHECK(ct_log_has("t,disk.x,"));
  const char *eq[] = {ct_bin, "run", disk_scene, "--mode=-o", NULL};   /* the = form passes */
  AP_CHECK_EQ_INT(ct_run(eq), 2);
  AP_CHECK(ct_log_has("unknown mode '-o'"));
}

/* appell sweep --at beyond t_end wrote a table of NaN samples and exited 0. */
static void test_sweep_at(void) {
  char csv[200];
  snprintf(csv, sizeof csv, "%s/sweep.csv", ct_tmp);
  const char *late[] = {ct_bin, "sweep", disk_scene, "--t-end", "0.1", "--channel", "disk.x",
                        "--at", "0.05,0.5", "--out", csv, "--quiet", NULL};
  AP_CHECK_EQ_INT(ct_run(late), 2);
  AP_CHECK(ct_log_has("appell sweep: --at 0.5 is outside the runs' time range t0 = 0 .. "
                      "t_end = 0.1"));
  AP_CHECK(access(csv, F_OK) != 0);
  const char *early[] = {ct_bin, "sweep", disk_scene, "--t-end", "0.1", "--at", "-1",
                         "--channel", "disk.x", "--out", csv, "--quiet", NULL};
  AP_CHECK_EQ_INT(ct_run(early), 2);
  AP_CHECK(ct_log_has("--at -1 is outside the runs' time range"));
  /* a grid over t_end: the shortest run sets the end of the range */
  const char *grid[] = {ct_bin, "sweep", disk_scene, "--grid", "simulation.t_end=0.1,0.02",
                        "--at", "0.05", "--channel", "disk.x", "--out", csv, "--quiet", NULL};
  AP_CHECK_EQ_INT(ct_run(grid), 2);
  AP_CHECK(ct_log_has("--at 0.05 is outside the runs' time range t0 = 0 .. t_end = 0.02"));
  /* --at without --channel spun for ever on the first time it reached (lib/batch) */
  const char *nochan[] = {ct_bin, "sweep", disk_scene, "--t-end", "0.1", "--at", "0.05",
                          "--out", csv, "--quiet", NULL};
  AP_CHECK_EQ_INT(ct_run(nochan), 2);
  AP_CHECK(ct_log_has("--at gives the times to sample the --channel columns at"));
  const char *good[] = {ct_bin, "sweep", disk_scene, "--t-end", "0.1", "--channel", "disk.x",
                        "--at", "0,0.05,0.1", "--out", csv, "--quiet", NULL};
  AP_CHECK_EQ_INT(ct_run(good), 0);
  AP_CHECK(access(csv, F_OK) == 0);
  unlink(csv);
}

/* The batch API with sample times and no channels: ap_batch_run returned only when killed.
 * The alarm turns a hang into a failure. */
static void test_batch_times_without_channels(void) {
  const char *sets[] = {"simulation.t_end=0.1"};
  const double times[] = {0.05, 0.033, 0.5};
  ap_batch_def def = ap_batch_def_default();
  def.times = times, def.ntimes = 3;
  ap_batch *b = NULL;
  char msg[1024] = "";
  AP_CHECK_EQ_INT(ap_batch_load(disk_scene, sets, 1, &def, &b, msg, sizeof msg), AP_OK);
  int nc = b ? ap_batch_ncols(b) : 0, status = -1;
  double *row = calloc((size_t)nc + 1, sizeof *row);
  alarm(20);
  if (b && row) AP_CHECK_EQ_INT(ap_batch_run(b, 1, 0, NULL, row, &status, NULL), AP_OK);
  alarm(0);
  AP_CHECK_EQ_INT(status, AP_OK);
  AP_CHECK(b && strcmp(ap_batch_col_name(b, 0), "t") == 0 && row[0] == 0.1);
  free(row);
  ap_batch_free(b);
}

/* appell plot of a header-only CSV ran gnuplot, which failed (exit 1) and left an empty PNG. */
static void test_plot_empty(void) {
  char csv[200], png[200];
  snprintf(csv, sizeof csv, "%s/empty.csv", ct_tmp);
  snprintf(png, sizeof png, "%s/fig.png", ct_tmp);
  const char *argv[] = {ct_bin, "plot", csv, "--y", "x", "-o", png, NULL};
  const char *text[] = {"t,x\n", ""}, *says[] = {"has a header but no data rows", "is empty"};
  for (int i = 0; i < 2; i++) {
    FILE *f = fopen(csv, "w");
    if (f) fputs(text[i], f), fclose(f);
    AP_CHECK_EQ_INT(ct_run(argv), 2);
    AP_CHECK(ct_log_has(says[i]));
    AP_CHECK(access(png, F_OK) != 0);
    unlink(png);
  }
  unlink(csv);
}

int main(void) {
  if (ct_init("test_user_errors") != 0) return 1;
  ct_source(disk_scene, sizeof disk_scene, "examples/scenes", "rolling_disk.yaml");
  ct_source(motors_scene, sizeof motors_scene, "examples/scenes", "diff_drive_motors.yaml");
  test_times();
  test_max_steps();
  test_stiff_hint();
  test_rank_rtol();
  test_option_as_value();
  test_sweep_at();
  test_batch_times_without_channels();
  test_plot_empty();
  ct_finish();
  return ap_check_finish("test_user_errors");
}
