/* test_run_record: a run that stops keeps its rows and says why (docs/cli.md "The run record").
 *
 * The built binary, as a user runs it:
 *  - a drive that is NaN after t = 1.005 (t^2 + 0/step(1.005 - t)) fails there: exit 3, the CSV
 *    holds every row up to the failure, byte for byte the rows of the same run to t_end = 1
 *    (which succeeds; the stepper stops at every output time, so both runs take the same steps
 *    up to there); its record says "failed", exit_code 3, the rows, the time reached (from the
 *    last row to 1.005) and the located expression; the
 *    successful run's record says "ok", exit_code 0, its rows, settings and overrides;
 *  - the bicycle at 2 m/s falls and fails when its rear wheel lies flat (t ~ 4.13 s): the
 *    message names the body, the constraint, the tilt from upright (90 degrees within the
 *    2 flat_tol band the check uses) and suggests `collide: stop`; the record says the same;
 *  - SIGINT in the middle of a long run: exit 130, the CSV holds the rows written so far, every
 *    one complete (as many fields as the header, t increasing), the record counts them and says
 *    "interrupted";
 *  - atomicity: a failing run whose write fails (a file size limit) leaves no CSV, no record
 *    and no temporary file; a record path that is a directory is refused before the run. */
#include <dirent.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "clitest.h"

static char drive[1200], disk[1200], bicycle[1200], pendulum[1200];

#define NAN_DRIVE "t*t + 0/step(1.005 - t)"   /* t^2 until t = 1.005, then NaN (0/0) */

/* Files in the scratch directory whose name contains part. */
static int files_with(const char *part) {
  DIR *d = opendir(ct_tmp);
  int n = 0;
  for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, part) != NULL;
  if (d) closedir(d);
  return n;
}

/* The lines of path (header included) into a malloc'd array; the count, -1 if unreadable. */
static int read_lines(const char *path, char ***out) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  char **lines = NULL, *line = NULL;
  size_t cap = 0;
  int n = 0;
  for (ssize_t len; (len = getline(&line, &cap, f)) > 0;) {
    char **grown = realloc(lines, sizeof *lines * (size_t)(n + 1));
    if (!grown) break;
    lines = grown;
    lines[n++] = strdup(line);
  }
  free(line);
  fclose(f);
  *out = lines;
  return n;
}

static void free_lines(char **lines, int n) {
  for (int i = 0; i < n; i++) free(lines[i]);
  free(lines);
}

static int fields(const char *line) {
  int n = 1;
  for (; *line; line++) n += *line == ',';
  return n;
}

/* The number after "key": in csv's record, NaN when absent. */
static double record_number(const char *csv, const char *key) {
  char path[1300], pat[80], buf[1 << 15];
  snprintf(path, sizeof path, "%s.run.json", csv);
  snprintf(pat, sizeof pat, "\"%s\": ", key);
  FILE *f = fopen(path, "r");
  size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[n] = '\0';
  const char *p = strstr(buf, pat);
  return p ? strtod(p + strlen(pat), NULL) : NAN;
}

static void test_failure_keeps_rows(void) {
  char fail_csv[1300], ok_csv[1300];
  snprintf(fail_csv, sizeof fail_csv, "%s/fail.csv", ct_tmp);
  snprintf(ok_csv, sizeof ok_csv, "%s/ok.csv", ct_tmp);
  const char *fail[] = {ct_bin, "run", drive, "--quiet", "--t-end", "2", "--out", fail_csv,
                        "--set", "joints.wheel.drive.angle=" NAN_DRIVE, NULL};
  const char *good[] = {ct_bin, "run", drive, "--quiet", "--t-end", "1", "--out", ok_csv,
                        "--set", "joints.wheel.drive.angle=" NAN_DRIVE, NULL};
  AP_CHECK_EQ_INT(ct_run(fail), 3);
  AP_CHECK(ct_log_has("'" NAN_DRIVE "' is not finite at t = ") && ct_log_has("0 / 0 = nan"));
  AP_CHECK_EQ_INT(ct_run(good), 0);
  char **a = NULL, **b = NULL;
  int na = read_lines(fail_csv, &a), nb = read_lines(ok_csv, &b);
  AP_CHECK_EQ_INT(nb, 102);   /* header + t = 0, 0.01, ..., 1 */
  AP_CHECK_EQ_INT(na, 102);   /* the same rows */
  for (int i = 0; i < nb && i < na; i++) AP_CHECK_EQ_INT(strcmp(a[i], b[i]), 0);
  double t_stop = record_number(fail_csv, "t");   /* where the integrator gave up */
  AP_CHECK(t_stop >= 1.0 && t_stop <= 1.005);
  AP_CHECK(ct_record_has(fail_csv, "\"status\": \"failed\"") &&
           ct_record_has(fail_csv, "\"exit_code\": 3,") &&
           ct_record_has(fail_csv, "\"error\": \"a user callback reported failure\"") &&
           ct_record_has(fail_csv, "drive_abs.yaml:13:20: joints.wheel.drive.angle") &&
           ct_record_has(fail_csv, "\"events\": [],"));
  AP_CHECK_EQ_INT((int)record_number(fail_csv, "rows"), na - 1);
  AP_CHECK(ct_record_has(ok_csv, "\"status\": \"ok\"") &&
           ct_record_has(ok_csv, "\"exit_code\": 0,") && ct_record_has(ok_csv, "\"error\": null") &&
           ct_record_has(ok_csv, "\"message\": \"\"") &&
           ct_record_has(ok_csv, "\"overrides\": [\"joints.wheel.drive.angle=" NAN_DRIVE "\", "
                                 "\"simulation.t_end=1\"]") &&
           ct_record_has(ok_csv, "\"method\": \"dopri5\""));
  AP_CHECK_EQ_INT((int)record_number(ok_csv, "rows"), 101);
  AP_CHECK(record_number(ok_csv, "t") == 1.0 && record_number(ok_csv, "steps") > 0 &&
           record_number(ok_csv, "evaluations") > record_number(ok_csv, "steps"));
  free_lines(a, na), free_lines(b, nb);
  ct_remove_run(fail_csv), ct_remove_run(ok_csv);
  AP_CHECK_EQ_INT(files_with(".appell-tmp."), 0);
}

static void test_bicycle_lying_flat(void) {
  char csv[1300];
  snprintf(csv, sizeof csv, "%s/bike.csv", ct_tmp);
  const char *argv[] = {ct_bin, "run", bicycle, "--quiet", "--out", csv, "--set",
                        "initial.rear_wheel.rate=2/0.3", NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 3);
  AP_CHECK(ct_log_has("body 'rear_wheel', constraint 'rear_contact': the disk reached lying flat"));
  AP_CHECK(ct_log_has("add `collide: stop` to the body that touches the ground first"));
  AP_CHECK(ct_record_has(csv, "constraint 'rear_contact'") &&
           ct_record_has(csv, "\"status\": \"failed\""));
  FILE *f = fopen(ct_log, "r");
  char buf[8192] = "";
  size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[n] = '\0';
  const char *p = strstr(buf, "tilted ");
  double tilt = p ? strtod(p + 7, NULL) : NAN;   /* degrees from upright */
  AP_CHECK_NEAR(tilt, 90.0, asin(2e-6) * 57.29577951308232 + 1e-4);   /* the band, %.6g printed */
  double t = record_number(csv, "t");
  AP_CHECK(t > 4.0 && t < 4.3);   /* it falls at about 4.13 s */
  AP_CHECK((int)record_number(csv, "rows") > 400);
  ct_remove_run(csv);
}

static void pause_ms(long ms) {
  struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
  nanosleep(&ts, NULL);
}

/* Size of the temporary file of target (0 when there is none). */
static long tmp_size(void) {
  DIR *d = opendir(ct_tmp);
  long size = 0;
  for (struct dirent *e; d && (e = readdir(d));) {
    if (!strstr(e->d_name, "long.csv.appell-tmp.")) continue;
    char path[1400];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", ct_tmp, e->d_name);
    if (stat(path, &st) == 0) size = (long)st.st_size;
  }
  if (d) closedir(d);
  return size;
}

static void test_sigint_keeps_rows(void) {
  char csv[1300];
  snprintf(csv, sizeof csv, "%s/long.csv", ct_tmp);
  const char *argv[] = {ct_bin, "run", disk, "--quiet", "--out", csv, "--t-end", "10000", NULL};
  pid_t pid = ct_spawn(argv, NULL, NULL, NULL);
  for (int i = 0; i < 6000 && tmp_size() < 300000; i++) pause_ms(10);
  kill(pid, SIGINT);
  AP_CHECK_EQ_INT(ct_wait(pid), 130);
  AP_CHECK(ct_log_has("interrupted by SIGINT at t = "));
  char **lines = NULL;
  int n = read_lines(csv, &lines), complete = n > 2, rising = 1;
  for (int i = 1; i < n; i++) {
    size_t len = strlen(lines[i]);
    complete &= len > 0 && lines[i][len - 1] == '\n' && fields(lines[i]) == fields(lines[0]);
    if (i > 1) rising &= strtod(lines[i], NULL) > strtod(lines[i - 1], NULL);
  }
  AP_CHECK(n > 500 && complete && rising);   /* 300 kB: some 700 rows of 24 columns */
  AP_CHECK_EQ_INT((int)record_number(csv, "rows"), n - 1);
  AP_CHECK_EQ_INT((int)record_number(csv, "exit_code"), 130);
  AP_CHECK(ct_record_has(csv, "\"status\": \"interrupted\""));
  double t_last = n > 1 ? strtod(lines[n - 1], NULL) : NAN;
  AP_CHECK(t_last < 10000 && fabs(record_number(csv, "t") - t_last) <= 1e-12 * t_last);
  free_lines(lines, n);
  ct_remove_run(csv);
  AP_CHECK_EQ_INT(files_with(".appell-tmp."), 0);
}

static void file_limit(void *user) {
  struct rlimit r = {(rlim_t)(size_t)user, (rlim_t)(size_t)user};
  signal(SIGXFSZ, SIG_IGN);   /* the write fails with EFBIG instead */
  setrlimit(RLIMIT_FSIZE, &r);
}

static void test_atomic(void) {
  char csv[1300], rec[1400];
  snprintf(csv, sizeof csv, "%s/limited.csv", ct_tmp);
  const char *fail[] = {ct_bin, "run", drive, "--quiet", "--t-end", "2", "--out", csv, "--set",
                        "joints.wheel.drive.angle=" NAN_DRIVE, NULL};
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(fail, NULL, file_limit, (void *)(size_t)3000)), 1);
  AP_CHECK(ct_log_has("File too large"));
  AP_CHECK_EQ_INT(files_with("limited.csv"), 0);   /* no CSV, no record, no temporary file */
  snprintf(rec, sizeof rec, "%s.run.json", csv);
  AP_CHECK_EQ_INT(mkdir(rec, 0700), 0);
  AP_CHECK_EQ_INT(ct_run(fail), 2);   /* refused before the run that would fail (exit 3) */
  AP_CHECK(ct_log_has("limited.csv.run.json: is a directory"));
  AP_CHECK_EQ_INT(access(csv, F_OK) != 0, 1);
  rmdir(rec);
}

/* A stop event (tests/scenes/pendulum_events.yaml: 'down' logged, 'back' stops the run): exit
 * 0, status "event", both events in the record, and the last row at the stop's time. */
static void test_stop_event(void) {
  char csv[1300];
  snprintf(csv, sizeof csv, "%s/pendulum.csv", ct_tmp);
  const char *argv[] = {ct_bin, "run", pendulum, "--quiet", "--out", csv, NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_record_has(csv, "\"status\": \"event\"") && ct_record_has(csv, "\"exit_code\": 0,"));
  AP_CHECK(ct_record_has(csv, "{\"name\": \"down\", \"t\": ") &&
           ct_record_has(csv, "\"action\": \"log\", \"direction\": \"falling\""));
  AP_CHECK(ct_record_has(csv, "{\"name\": \"back\", \"t\": ") &&
           ct_record_has(csv, "\"action\": \"stop\", \"direction\": \"falling\""));
  char **rows = NULL;
  int n = read_lines(csv, &rows);
  double t_last = n > 1 ? strtod(rows[n - 1], NULL) : NAN, t_rec = record_number(csv, "t");
  AP_CHECK(n > 2 && t_rec > 0.5 && t_rec < 5.0);     /* before t_end = 5 */
  AP_CHECK_NEAR(t_last, t_rec, 1e-14 * t_rec);        /* the CSV prints %.15g */
  free_lines(rows, n);
  ct_remove_run(csv);
}

int main(void) {
  if (ct_init("test_run_record") != 0) return 1;
  ct_source(drive, sizeof drive, "tests/scenes", "drive_abs.yaml");
  ct_source(disk, sizeof disk, "examples/scenes", "rolling_disk.yaml");
  ct_source(bicycle, sizeof bicycle, "examples/scenes", "bicycle.yaml");
  ct_source(pendulum, sizeof pendulum, "tests/scenes", "pendulum_events.yaml");
  test_failure_keeps_rows();
  test_bicycle_lying_flat();
  test_sigint_keeps_rows();
  test_atomic();
  test_stop_event();
  ct_finish();
  return ap_check_finish("test_run_record");
}
