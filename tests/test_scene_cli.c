/* test_scene_cli: the appell binary (build/tools/appell) end to end.
 *
 * Runs the binary as a user would: --help on every subcommand; a good run writes a complete
 * CSV (header "t,...", one row per interval) and leaves no temporary file; bad scenes exit 2
 * and neither create the output file nor touch an existing one; a numerical failure exits 3
 * and replaces the file with the rows up to the failure, its run record saying "failed"; check prints the structure; plot draws a PNG (when gnuplot is installed) and refuses
 * unknown columns; a few mutated scenes through `appell check` never crash the binary; a
 * scene that is an alias bomb is refused with exit 2 under a memory limit (the output files
 * and signals of `appell run` are in test_cli_output). tests/clitest.h runs the binary. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "clitest.h"

static int exists(const char *p) { return access(p, F_OK) == 0; }

/* Temporary output files left in the scratch directory. */
static int stray_files(void) {
  DIR *d = opendir(ct_tmp);
  int n = 0;
  for (struct dirent *e; d && (e = readdir(d));)
    n += strstr(e->d_name, ".tmp.") != NULL || strstr(e->d_name, ".appell-tmp.") != NULL;
  if (d) closedir(d);
  return n;
}

static void test_help(void) {
  const char *cmds[] = {"run", "check", "plot"};
  const char *top[] = {ct_bin, "--help", NULL};
  AP_CHECK_EQ_INT(ct_run(top), 0);
  AP_CHECK(ct_log_has("usage: appell COMMAND"));
  for (int i = 0; i < 3; i++) {
    const char *argv[] = {ct_bin, cmds[i], "--help", NULL};
    AP_CHECK_EQ_INT(ct_run(argv), 0);
    AP_CHECK(ct_log_has("usage: appell"));
  }
  const char *bad[] = {ct_bin, "runn", NULL}, *opt[] = {ct_bin, "run", "x.yaml", "--rtoll", "1", NULL};
  AP_CHECK_EQ_INT(ct_run(bad), 2);
  AP_CHECK(ct_log_has("did you mean 'run'?"));
  AP_CHECK_EQ_INT(ct_run(opt), 2);
  AP_CHECK(ct_log_has("did you mean '--rtol'?"));
}

static void test_good_run(const char *csv) {
  char scene[1200];
  ct_source(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  const char *argv[] = {ct_bin, "run", scene, "--t-end", "0.5", "--out", csv,
                        "--set", "bodies.disk.mass=2", "--method", "verner6", NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_log_has("steps") && ct_log_has("energy drift") && ct_log_has("max constraint residual"));
  FILE *f = fopen(csv, "r");
  AP_CHECK(f != NULL);
  if (!f) return;
  char line[8192];
  int rows = 0, header = fgets(line, sizeof line, f) && strncmp(line, "t,disk.x,", 9) == 0;
  while (fgets(line, sizeof line, f)) rows++;
  fclose(f);
  AP_CHECK(header);
  AP_CHECK_EQ_INT(rows, 51);       /* t = 0, 0.01, ..., 0.5 */
  AP_CHECK(ct_record_has(csv, "\"status\": \"ok\"") && ct_record_has(csv, "\"rows\": 51,"));
  AP_CHECK_EQ_INT(stray_files(), 0);
}

/* An output interval longer than t_end - t0 by more than 1e9: the rows are t0 and t_end, and
 * the run goes to t_end (a row count of ceil(T / dt - 1e-9) = 0 wrote the t0 row only and
 * reported success without simulating). */
static void test_long_interval(const char *csv) {
  char scene[1200];
  ct_source(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  const char *argv[] = {ct_bin, "run", scene, "--t-end", "0.5", "--interval", "1e9", "--out",
                        csv, NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_log_has("t = 0 .. 0.5, 2 rows"));
  FILE *f = fopen(csv, "r");
  AP_CHECK(f != NULL);
  if (!f) return;
  char line[8192], last[8192] = "";
  int rows = -1;
  while (fgets(line, sizeof line, f)) rows++, memcpy(last, line, sizeof last);
  fclose(f);
  AP_CHECK_EQ_INT(rows, 2);
  AP_CHECK(strncmp(last, "0.5,", 4) == 0);
}

static void expect_failure(const char *scene, const char *extra, int code, const char *csv) {
  const char *argv[] = {ct_bin, "run", scene, "--out", csv, "--quiet", extra ? "--set" : NULL,
                        extra, NULL};
  AP_CHECK_EQ_INT(ct_run(argv), code);
  if (code == 3)   /* the rows up to the failure, and the run record saying so */
    AP_CHECK(exists(csv) && ct_record_has(csv, "\"status\": \"failed\"") &&
             ct_record_has(csv, "\"exit_code\": 3"));
  else
    AP_CHECK(!exists(csv));
  ct_remove_run(csv);
  AP_CHECK_EQ_INT(stray_files(), 0);
}

static void test_failures(void) {
  static const char *const bad[] = {"malformed.yaml", "unknown_key.yaml", "negative_mass.yaml",
                                    "inertia_not_pd.yaml", "missing_body.yaml",
                                    "bad_expression.yaml", "disk_flat.yaml",
                                    "inconsistent_constraints.yaml"};
  char scene[1200], csv[1200], keep[1200];
  snprintf(csv, sizeof csv, "%s/bad.csv", ct_tmp);
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    ct_source(scene, sizeof scene, "tests/scenes", bad[i]);
    expect_failure(scene, NULL, 2, csv);
    AP_CHECK(ct_log_has(bad[i]));
  }
  /* A numerical failure: too few steps allowed. Exit 3, the rows up to it replace a file. */
  ct_source(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  expect_failure(scene, "simulation.max_steps=3", 3, csv);
  AP_CHECK(ct_log_has("max_steps"));
  snprintf(keep, sizeof keep, "%s/keep.csv", ct_tmp);
  FILE *f = fopen(keep, "w");
  if (f) fputs("old\n", f), fclose(f);
  const char *argv[] = {ct_bin, "run", scene, "--out", keep, "--set", "simulation.max_steps=3",
                        NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 3);
  char line[16] = "";
  f = fopen(keep, "r");
  if (f && fgets(line, sizeof line, f)) AP_CHECK_EQ_INT(strncmp(line, "t,disk.x,", 9), 0);
  else AP_CHECK(0);
  if (f) fclose(f);
  ct_remove_run(keep);
  const char *num[] = {ct_bin, "run", scene, "--t-end", "soon", NULL};
  AP_CHECK_EQ_INT(ct_run(num), 2);
  const char *missing[] = {ct_bin, "run", "/nonexistent/scene.yaml", NULL};
  AP_CHECK_EQ_INT(ct_run(missing), 2);
}

static void test_check(void) {
  char scene[1200];
  ct_source(scene, sizeof scene, "examples/scenes", "hoffmann.yaml");
  const char *argv[] = {ct_bin, "check", scene, NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_log_has("n = 4") && ct_log_has("k = 4") && ct_log_has("b = 2"));
  AP_CHECK(ct_log_has("free speeds  l = 2") && ct_log_has("push (applied)"));
  AP_CHECK(ct_log_has("coordinates corrected"));   /* the loop is assembled */
  AP_CHECK(!ct_log_has("(null)"));
  ct_source(scene, sizeof scene, "tests/scenes", "unknown_key.yaml");
  const char *bad[] = {ct_bin, "check", scene, NULL};
  AP_CHECK_EQ_INT(ct_run(bad), 2);
  AP_CHECK(ct_log_has("unknown_key.yaml:3:5: bodies.disk.mas: unknown key 'mas' (did you mean "
                   "'mass'?)"));
}

/* Expressions that are not finite where they are evaluated: check and run name the
 * expression's FILE:LINE:COLUMN, at t0 (exit 2, both) and later in a run (exit 3). */
static void test_not_finite(void) {
  static const char *const cases[][2] = {
      {"drive_inverse.yaml", "drive_inverse.yaml:11:20: joints.wheel.drive.angle: '1/t' is not "
                             "finite at t = 0: 1 / 0 = inf (column 2 of the expression)"},
      {"drive_log.yaml", "drive_log.yaml:11:20: joints.wheel.drive.angle: '0.5*log(t - 1)' is "
                         "not finite at t = 0: log(-1) = nan (column 5 of the expression)"},
      {"initial_overflow.yaml", "initial_overflow.yaml:13:53: initial.disk.heading_rate: the "
                                "equations of motion cannot be evaluated at the initial state"}};
  char scene[1200], csv[1200];
  snprintf(csv, sizeof csv, "%s/bad.csv", ct_tmp);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    ct_source(scene, sizeof scene, "tests/scenes", cases[i][0]);
    const char *check[] = {ct_bin, "check", scene, NULL};
    AP_CHECK_EQ_INT(ct_run(check), 2);
    AP_CHECK(ct_log_has(cases[i][1]));
    expect_failure(scene, NULL, 2, csv);
    AP_CHECK(ct_log_has(cases[i][1]));
  }
  /* A kink at t0 and one at an output time inside the run: the run stops exactly there and
   * goes on (docs/scenes.md "Kinks"), where these were refused before (exit 2 and 3). */
  ct_source(scene, sizeof scene, "tests/scenes", "drive_abs.yaml");
  const char *ok[] = {ct_bin, "run", scene, "--out", csv, "--t-end", "0.1", NULL};
  AP_CHECK_EQ_INT(ct_run(ok), 0);
  const char *argv[] = {ct_bin, "run", scene, "--out", csv, "--t-end", "0.1",
                        "--set", "joints.wheel.drive.angle=abs(t - 0.05)", NULL};
  AP_CHECK_EQ_INT(ct_run(argv), 0);
  AP_CHECK(ct_log_has("event 'kink 1 of joints.wheel.drive.angle' at t = 0.05 (rising, switch)"));
  AP_CHECK(exists(csv));
  ct_remove_run(csv);
}

static void test_plot(const char *csv) {
  char png[1200];
  snprintf(png, sizeof png, "%s/path.png", ct_tmp);
  const char *bad[] = {ct_bin, "plot", csv, "--x", "disk.contact.x", "--y", "disk.contact.z",
                       "-o", png, NULL};
  AP_CHECK_EQ_INT(ct_run(bad), 2);
  AP_CHECK(ct_log_has("did you mean 'disk.contact.x'?") || ct_log_has("did you mean 'disk.contact.y'?"));
  const char *ext[] = {ct_bin, "plot", csv, "--y", "energy", "-o", "fig.jpg", NULL};
  AP_CHECK_EQ_INT(ct_run(ext), 2);
  /* A figure in a missing directory, or a directory: refused before gnuplot runs (gnuplot
   * could not open it and wrote the PNG to standard output, onto the terminal, exit 1). */
  char nodir[1200], isdir[1200];
  snprintf(nodir, sizeof nodir, "%s/no/such/dir/x.png", ct_tmp);
  snprintf(isdir, sizeof isdir, "%s/d.png", ct_tmp);
  const char *missing[] = {ct_bin, "plot", csv, "--y", "energy", "-o", nodir, NULL};
  AP_CHECK_EQ_INT(ct_run(missing), 2);
  AP_CHECK(ct_log_has("no such directory") && !ct_log_has("PNG"));
  AP_CHECK(mkdir(isdir, 0700) == 0);
  const char *dir[] = {ct_bin, "plot", csv, "--y", "energy", "-o", isdir, NULL};
  AP_CHECK_EQ_INT(ct_run(dir), 2);
  AP_CHECK(ct_log_has("is a directory"));
  rmdir(isdir);
  if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
    printf("gnuplot not installed: plot drawing not tested\n");
    return;
  }
  const char *ok[] = {ct_bin, "plot", csv, "--x", "disk.contact.x", "--y", "disk.contact.y",
                      "--equal", "-o", png, NULL};
  AP_CHECK_EQ_INT(ct_run(ok), 0);
  struct stat st;
  AP_CHECK(stat(png, &st) == 0 && st.st_size > 1000);
  unlink(png);
}

/* A few byte-mutated scenes through the binary: exit 0 or 2, never a crash. */
/* A memory limit for a child: 1 GiB of address space, or of resident memory under
 * AddressSanitizer (which reserves terabytes of address space and has its own limit). */
static void limit_memory(void *user) {
  (void)user;
#if defined(__SANITIZE_ADDRESS__)
  setenv("ASAN_OPTIONS", "hard_rss_limit_mb=1024", 1);
#else
  struct rlimit r = {1L << 30, 1L << 30};
  setrlimit(RLIMIT_AS, &r);
#endif
}

/* An explicit key of keylen characters whose value is an alias tree of 10^5 nodes: every node
 * carries the key in its key path (main reached 3.9 GB with a 20 KB file of this kind). */
static void write_bomb(const char *path, size_t keylen) {
  FILE *f = fopen(path, "w");
  if (!f) return;
  fputs("? ", f);
  for (size_t i = 0; i < keylen; i++) fputc('k', f);
  fputs("\n: [&a [x, x, x, x, x, x, x, x, x, x]", f);
  for (int level = 1; level < 5; level++) {
    fprintf(f, ", &%c [", 'a' + level);
    for (int i = 0; i < 10; i++) fprintf(f, "%s*%c", i ? ", " : "", 'a' + level - 1);
    fputs("]", f);
  }
  for (int i = 0; i < 7; i++) fputs(", *d", f);
  fputs("]\n", f);
  fclose(f);
}

/* Bombs of 20 KB and 2 MB: refused with exit 2 and a located message, within the limit. */
static void test_memory(void) {
  const size_t keys[] = {20000, 2000000};
  for (int i = 0; i < 2; i++) {
    char path[200];
    snprintf(path, sizeof path, "%s/bomb%d.yaml", ct_tmp, i);
    write_bomb(path, keys[i]);
    const char *argv[] = {ct_bin, "check", path, NULL};
    AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, NULL, limit_memory, NULL)), 2);
    snprintf(path, sizeof path, "bomb%d.yaml:2:", i);
    AP_CHECK(ct_log_has(path) && ct_log_has("grows past 64 MiB"));
    snprintf(path, sizeof path, "%s/bomb%d.yaml", ct_tmp, i);
    unlink(path);
  }
}

static void test_mutants(void) {
  char scene[1200], path[1200];
  ct_source(scene, sizeof scene, "examples/scenes", "turntable_ball.yaml");
  FILE *f = fopen(scene, "rb");
  static char text[1 << 16];
  size_t len = f ? fread(text, 1, sizeof text, f) : 0;
  if (f) fclose(f);
  snprintf(path, sizeof path, "%s/mutant.yaml", ct_tmp);
  unsigned seed = 12345;
  for (int i = 0; i < 8 && len > 0; i++) {
    static char buf[1 << 16];
    memcpy(buf, text, len);
    for (int e = 0; e < 3; e++) {
      seed = seed * 1103515245u + 12345u;
      buf[(seed >> 8) % len] = ":[{}&*'\"\n-#9"[(seed >> 20) % 13];
    }
    f = fopen(path, "wb");
    if (f) fwrite(buf, 1, i == 7 ? len / 2 : len, f), fclose(f);
    const char *argv[] = {ct_bin, "check", path, NULL};
    int rc = ct_run(argv);
    AP_CHECK(rc == 0 || rc == 2);
  }
  unlink(path);
}

int main(void) {
  if (ct_init("test_scene_cli") != 0) return 1;
  char csv[1200];
  snprintf(csv, sizeof csv, "%s/disk.csv", ct_tmp);
  test_help();
  test_good_run(csv);
  test_long_interval(csv);
  test_failures();
  test_check();
  test_not_finite();
  test_plot(csv);
  test_mutants();
  test_memory();
  ct_remove_run(csv);
  ct_finish();
  return ap_check_finish("test_scene_cli");
}
