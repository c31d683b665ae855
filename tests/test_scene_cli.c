/* test_scene_cli: the appell binary (build/tools/appell) end to end.
 *
 * Runs the binary as a user would: --help on every subcommand; a good run writes a complete
 * CSV (header "t,...", one row per interval) and leaves no temporary file; bad scenes exit 2,
 * a numerical failure exits 3, and neither creates the output file nor touches an existing
 * one; check prints the structure; plot draws a PNG (when gnuplot is installed) and refuses
 * unknown columns; a few mutated scenes through `appell check` never crash the binary.
 * Meson runs tests in the build root, so the binary is tools/appell there ($APPELL_BIN
 * overrides) and the sources are found from __FILE__ ($APPELL_SOURCE_DIR overrides). */
#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"

static char src[1024], bin[1024], tmp[] = "/tmp/appell_cli_XXXXXX", out_log[1200];

/* Run argv with stdout and stderr into out_log; exit code, or 128 + signal when killed. */
static int run(const char *const *argv) {
  pid_t pid = fork();
  if (pid == 0) {
    int fd = open(out_log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) dup2(fd, 1), dup2(fd, 2), close(fd);
    execv(argv[0], (char *const *)argv);
    _exit(126);
  }
  int st = 0;
  if (pid < 0 || waitpid(pid, &st, 0) < 0) return -1;
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

static int log_has(const char *what) {
  static char buf[1 << 16];
  FILE *f = fopen(out_log, "r");
  size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[n] = '\0';
  return strstr(buf, what) != NULL;
}

static int exists(const char *p) { return access(p, F_OK) == 0; }

/* Files in the temporary directory other than the log and those named. */
static int stray_files(void) {
  DIR *d = opendir(tmp);
  int n = 0;
  for (struct dirent *e; d && (e = readdir(d));)
    n += strstr(e->d_name, ".tmp.") != NULL;
  if (d) closedir(d);
  return n;
}

static void scene_path(char *out, size_t len, const char *dir, const char *name) {
  snprintf(out, len, "%s/%s/%s", src, dir, name);
}

static void test_help(void) {
  const char *cmds[] = {"run", "check", "plot"};
  const char *top[] = {bin, "--help", NULL};
  AP_CHECK_EQ_INT(run(top), 0);
  AP_CHECK(log_has("usage: appell COMMAND"));
  for (int i = 0; i < 3; i++) {
    const char *argv[] = {bin, cmds[i], "--help", NULL};
    AP_CHECK_EQ_INT(run(argv), 0);
    AP_CHECK(log_has("usage: appell"));
  }
  const char *bad[] = {bin, "runn", NULL}, *opt[] = {bin, "run", "x.yaml", "--rtoll", "1", NULL};
  AP_CHECK_EQ_INT(run(bad), 2);
  AP_CHECK(log_has("did you mean 'run'?"));
  AP_CHECK_EQ_INT(run(opt), 2);
  AP_CHECK(log_has("did you mean '--rtol'?"));
}

static void test_good_run(const char *csv) {
  char scene[1200];
  scene_path(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  const char *argv[] = {bin, "run", scene, "--t-end", "0.5", "--out", csv,
                        "--set", "bodies.disk.mass=2", "--method", "verner6", NULL};
  AP_CHECK_EQ_INT(run(argv), 0);
  AP_CHECK(log_has("steps") && log_has("energy drift") && log_has("max constraint residual"));
  FILE *f = fopen(csv, "r");
  AP_CHECK(f != NULL);
  if (!f) return;
  char line[8192];
  int rows = 0, header = fgets(line, sizeof line, f) && strncmp(line, "t,disk.x,", 9) == 0;
  while (fgets(line, sizeof line, f)) rows++;
  fclose(f);
  AP_CHECK(header);
  AP_CHECK_EQ_INT(rows, 51);       /* t = 0, 0.01, ..., 0.5 */
  AP_CHECK_EQ_INT(stray_files(), 0);
}

static void expect_failure(const char *scene, const char *extra, int code, const char *csv) {
  const char *argv[] = {bin, "run", scene, "--out", csv, "--quiet", extra ? "--set" : NULL,
                        extra, NULL};
  AP_CHECK_EQ_INT(run(argv), code);
  AP_CHECK(!exists(csv));
  AP_CHECK_EQ_INT(stray_files(), 0);
}

static void test_failures(void) {
  static const char *const bad[] = {"malformed.yaml", "unknown_key.yaml", "negative_mass.yaml",
                                    "inertia_not_pd.yaml", "missing_body.yaml",
                                    "bad_expression.yaml", "disk_flat.yaml",
                                    "inconsistent_constraints.yaml"};
  char scene[1200], csv[1200], keep[1200];
  snprintf(csv, sizeof csv, "%s/bad.csv", tmp);
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    scene_path(scene, sizeof scene, "tests/scenes", bad[i]);
    expect_failure(scene, NULL, 2, csv);
    AP_CHECK(log_has(bad[i]));
  }
  /* A numerical failure: too few steps allowed. Exit 3, no file, an existing file kept. */
  scene_path(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  expect_failure(scene, "simulation.max_steps=3", 3, csv);
  AP_CHECK(log_has("max_steps"));
  snprintf(keep, sizeof keep, "%s/keep.csv", tmp);
  FILE *f = fopen(keep, "w");
  if (f) fputs("old\n", f), fclose(f);
  const char *argv[] = {bin, "run", scene, "--out", keep, "--set", "simulation.max_steps=3",
                        NULL};
  AP_CHECK_EQ_INT(run(argv), 3);
  char line[16] = "";
  f = fopen(keep, "r");
  if (f && fgets(line, sizeof line, f)) AP_CHECK_EQ_INT(strcmp(line, "old\n"), 0);
  else AP_CHECK(0);
  if (f) fclose(f);
  unlink(keep);
  const char *num[] = {bin, "run", scene, "--t-end", "soon", NULL};
  AP_CHECK_EQ_INT(run(num), 2);
  const char *missing[] = {bin, "run", "/nonexistent/scene.yaml", NULL};
  AP_CHECK_EQ_INT(run(missing), 2);
}

static void test_check(void) {
  char scene[1200];
  scene_path(scene, sizeof scene, "examples/scenes", "hoffmann.yaml");
  const char *argv[] = {bin, "check", scene, NULL};
  AP_CHECK_EQ_INT(run(argv), 0);
  AP_CHECK(log_has("n = 4") && log_has("k = 4") && log_has("b = 2"));
  AP_CHECK(log_has("free speeds  l = 2") && log_has("push (applied)"));
  AP_CHECK(log_has("coordinates corrected"));   /* the loop is assembled */
  scene_path(scene, sizeof scene, "tests/scenes", "unknown_key.yaml");
  const char *bad[] = {bin, "check", scene, NULL};
  AP_CHECK_EQ_INT(run(bad), 2);
  AP_CHECK(log_has("unknown_key.yaml:3:5: bodies.disk.mas: unknown key 'mas' (did you mean "
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
      {"drive_abs.yaml", "drive_abs.yaml:11:20: joints.wheel.drive.angle: '2 + abs(t)' has no "
                         "finite first time derivative at t = 0"},
      {"initial_overflow.yaml", "initial_overflow.yaml:13:53: initial.disk.heading_rate: the "
                                "equations of motion cannot be evaluated at the initial state"}};
  char scene[1200], csv[1200];
  snprintf(csv, sizeof csv, "%s/bad.csv", tmp);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    scene_path(scene, sizeof scene, "tests/scenes", cases[i][0]);
    const char *check[] = {bin, "check", scene, NULL};
    AP_CHECK_EQ_INT(run(check), 2);
    AP_CHECK(log_has(cases[i][1]));
    expect_failure(scene, NULL, 2, csv);
    AP_CHECK(log_has(cases[i][1]));
  }
  /* Fine at t0, a kink at t = 0.05 inside the run: exit 3, the expression located. */
  scene_path(scene, sizeof scene, "tests/scenes", "drive_abs.yaml");
  const char *argv[] = {bin, "run", scene, "--out", csv, "--quiet", "--t-end", "0.1",
                        "--set", "joints.wheel.drive.angle=abs(t - 0.05)", NULL};
  AP_CHECK_EQ_INT(run(argv), 3);
  AP_CHECK(log_has("drive_abs.yaml:11:20: joints.wheel.drive.angle (set by --set "
                   "joints.wheel.drive.angle=abs(t - 0.05)): 'abs(t - 0.05)' has no finite first "
                   "time derivative at t = 0.05"));
  AP_CHECK(!exists(csv));
}

static void test_plot(const char *csv) {
  char png[1200];
  snprintf(png, sizeof png, "%s/path.png", tmp);
  const char *bad[] = {bin, "plot", csv, "--x", "disk.contact.x", "--y", "disk.contact.z",
                       "-o", png, NULL};
  AP_CHECK_EQ_INT(run(bad), 2);
  AP_CHECK(log_has("did you mean 'disk.contact.x'?") || log_has("did you mean 'disk.contact.y'?"));
  const char *ext[] = {bin, "plot", csv, "--y", "energy", "-o", "fig.jpg", NULL};
  AP_CHECK_EQ_INT(run(ext), 2);
  if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
    printf("gnuplot not installed: plot drawing not tested\n");
    return;
  }
  const char *ok[] = {bin, "plot", csv, "--x", "disk.contact.x", "--y", "disk.contact.y",
                      "--equal", "-o", png, NULL};
  AP_CHECK_EQ_INT(run(ok), 0);
  struct stat st;
  AP_CHECK(stat(png, &st) == 0 && st.st_size > 1000);
  unlink(png);
}

/* A few byte-mutated scenes through the binary: exit 0 or 2, never a crash. */
static void test_mutants(void) {
  char scene[1200], path[1200];
  scene_path(scene, sizeof scene, "examples/scenes", "turntable_ball.yaml");
  FILE *f = fopen(scene, "rb");
  static char text[1 << 16];
  size_t len = f ? fread(text, 1, sizeof text, f) : 0;
  if (f) fclose(f);
  snprintf(path, sizeof path, "%s/mutant.yaml", tmp);
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
    const char *argv[] = {bin, "check", path, NULL};
    int rc = run(argv);
    AP_CHECK(rc == 0 || rc == 2);
  }
  unlink(path);
}

static void locate(void) {
  const char *env = getenv("APPELL_SOURCE_DIR");
  snprintf(src, sizeof src, "%s", env ? env : __FILE__);
  if (!env) {
    char *slash = strrchr(src, '/');
    if (slash) *slash = '\0', slash = strrchr(src, '/');
    if (slash) *slash = '\0';
    else snprintf(src, sizeof src, ".");
  }
  env = getenv("APPELL_BIN");
  snprintf(bin, sizeof bin, "%s", env ? env : "tools/appell");
}

int main(void) {
  locate();
  if (!mkdtemp(tmp) || access(bin, X_OK) != 0) {
    fprintf(stderr, "test_scene_cli: no binary at %s (run from the build directory)\n", bin);
    return 1;
  }
  snprintf(out_log, sizeof out_log, "%s/log.txt", tmp);
  char csv[1200];
  snprintf(csv, sizeof csv, "%s/disk.csv", tmp);
  test_help();
  test_good_run(csv);
  test_failures();
  test_check();
  test_not_finite();
  test_plot(csv);
  test_mutants();
  unlink(csv);
  unlink(out_log);
  rmdir(tmp);
  return ap_check_finish("test_scene_cli");
}
