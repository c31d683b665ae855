/* test_cli_output: where `appell run` writes, and what signals do to it (docs/cli.md).
 *
 * Signals: the built binary runs the rolling disk for a long time as a child; once its
 * temporary output file exists, it gets SIGHUP, SIGQUIT, SIGTERM twice, SIGXFSZ (sent), or
 * SIGINT during one long output interval whose steps would run into max_steps. Each must end
 * the run with exit 128 + the signal and "interrupted by SIG..." (SIGINT: 130, not the
 * max_steps failure), leave no temporary file, and keep the rows so far (the row at t0) with
 * a run record saying "interrupted"; a second signal (SIGTERM twice) leaves nothing. A real
 * SIGXFSZ (a file size limit) is a failed write: exit 1, "File too large", nothing left. SIGKILL leaves its temporary file;
 * the next run to the same target removes it and says so, and keeps one whose process lives.
 *
 * Targets: a directory is refused before anything is simulated (a scene that would fail
 * numerically still gets exit 2); the scene itself (through a hard link) is refused and left
 * as it was; a link to a file keeps being a link and the file gets the rows; a link to
 * /dev/zero stays a link; a FIFO stays a FIFO and its reader gets the rows; standard output
 * or --out on /dev/full exits 1 with "No space left on device"; new files get 0666 minus the
 * umask, a replaced file keeps its permissions. */
#include <dirent.h>
#include <fcntl.h>
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

static char scene[1200], out[1200];

static void pause_ms(long ms) {
  struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
  nanosleep(&ts, NULL);
}

/* Files in the scratch directory whose name starts with prefix. */
static int files_like(const char *prefix) {
  DIR *d = opendir(ct_tmp);
  int n = 0;
  for (struct dirent *e; d && (e = readdir(d));)
    n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
  if (d) closedir(d);
  return n;
}

/* Wait (up to 60 s) until out's temporary file exists; 1 when it does. */
static int wait_for_tmp(pid_t pid) {
  for (int i = 0; i < 6000; i++) {
    if (files_like("long.csv.") > 0) return 1;
    int st;
    if (waitpid(pid, &st, WNOHANG) == pid) return 0;
    pause_ms(10);
  }
  return 0;
}

/* A run that takes minutes: one output interval of 2000 s at rtol 1e-12. */
static pid_t start_long(long max_steps) {
  static char steps[64];
  snprintf(steps, sizeof steps, "simulation.max_steps=%ld", max_steps);
  const char *argv[] = {ct_bin, "run", scene, "--quiet", "--out", out, "--t-end", "2000",
                        "--interval", "2000", "--rtol", "1e-12", "--atol", "1e-14", "--set",
                        steps, NULL};
  return ct_spawn(argv, NULL, NULL, NULL);
}

static void test_signal(int sig, int twice, const char *name) {
  pid_t pid = start_long(sig == SIGINT ? 200000 : 100000000);
  AP_CHECK(wait_for_tmp(pid));
  pause_ms(100);
  kill(pid, sig);
  if (twice) kill(pid, sig);
  int code = ct_wait(pid);
  AP_CHECK_EQ_INT(code, 128 + sig);
  char what[64];
  snprintf(what, sizeof what, "interrupted by %s", name);
  AP_CHECK(twice || ct_log_has(what));
  if (code != 128 + sig) fprintf(stderr, "  %s: exit %d\n", name, code);
  AP_CHECK_EQ_INT(files_like("long.csv.appell-tmp."), 0);
  if (!twice) {   /* the rows so far: at t0 and where it stopped; the record says why */
    AP_CHECK(ct_file_has(out, "t,disk.x,") && ct_record_has(out, "\"status\": \"interrupted\"") &&
             ct_record_has(out, what) && ct_record_has(out, "\"rows\": 2,"));
    char code_text[32];
    snprintf(code_text, sizeof code_text, "\"exit_code\": %d,", 128 + sig);
    AP_CHECK(ct_record_has(out, code_text));
  }
  ct_remove_run(out);
  AP_CHECK_EQ_INT(files_like("long.csv"), 0);
}

static void file_limit(void *user) {
  struct rlimit r = {(rlim_t)(size_t)user, (rlim_t)(size_t)user};
  setrlimit(RLIMIT_FSIZE, &r);
}

static void test_signals(void) {
  test_signal(SIGHUP, 0, "SIGHUP");
  test_signal(SIGQUIT, 0, "SIGQUIT");
  test_signal(SIGTERM, 1, "SIGTERM");
  test_signal(SIGXFSZ, 0, "SIGXFSZ");
  test_signal(SIGINT, 0, "SIGINT");
  /* A file size limit of 20 kB: the rolling disk writes 60 kB in 2 s. */
  const char *argv[] = {ct_bin, "run", scene, "--quiet", "--out", out, "--t-end", "2", NULL};
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, NULL, file_limit, (void *)(size_t)20000)), 1);
  AP_CHECK(ct_log_has("File too large"));
  AP_CHECK_EQ_INT(files_like("long.csv"), 0);
  /* SIGKILL: the temporary file stays; the next run removes it (not one of a live process). */
  pid_t pid = start_long(100000000);
  AP_CHECK(wait_for_tmp(pid));
  kill(pid, SIGKILL);
  AP_CHECK_EQ_INT(ct_wait(pid), 128 + SIGKILL);
  AP_CHECK_EQ_INT(files_like("long.csv.appell-tmp."), 1);
  char live[1300];
  snprintf(live, sizeof live, "%s.appell-tmp.%ld.abcdef", out, (long)getpid());
  FILE *f = fopen(live, "w");
  if (f) fclose(f);
  const char *again[] = {ct_bin, "run", scene, "--quiet", "--out", out, "--t-end", "0.1", NULL};
  AP_CHECK_EQ_INT(ct_run(again), 0);
  AP_CHECK(ct_log_has("left by an earlier run (process") && ct_log_has("that was killed"));
  AP_CHECK_EQ_INT(files_like("long.csv.appell-tmp."), 1);   /* the live one */
  AP_CHECK_EQ_INT(access(live, F_OK), 0);
  unlink(live);
  ct_remove_run(out);
}

/* ---- targets -------------------------------------------------------------------------------- */

/* The first line of path, "" when it cannot be read. */
static const char *first_line(const char *path) {
  static char line[256];
  line[0] = '\0';
  FILE *f = fopen(path, "r");
  if (f && !fgets(line, sizeof line, f)) line[0] = '\0';
  if (f) fclose(f);
  return line;
}

static void test_targets(void) {
  char path[1300], alias[1300];
  const char *fail3[] = {ct_bin, "run", scene, "--quiet", "--out", ct_tmp, "--set",
                         "simulation.max_steps=3", NULL};
  AP_CHECK_EQ_INT(ct_run(fail3), 2);   /* refused before the run that would fail (exit 3) */
  AP_CHECK(ct_log_has("is a directory"));
  /* The scene, reached through a hard link. */
  snprintf(path, sizeof path, "%s/scene.yaml", ct_tmp);
  snprintf(alias, sizeof alias, "%s/same.yaml", ct_tmp);
  FILE *from = fopen(scene, "rb"), *to = fopen(path, "wb");
  for (int ch; from && to && (ch = fgetc(from)) != EOF;) fputc(ch, to);
  if (from) fclose(from);
  if (to) fclose(to);
  AP_CHECK_EQ_INT(link(path, alias), 0);
  const char *self[] = {ct_bin, "run", path, "--quiet", "--t-end", "0.1", "--out", alias, NULL};
  AP_CHECK_EQ_INT(ct_run(self), 2);
  AP_CHECK(ct_log_has("is the scene file"));
  AP_CHECK_EQ_INT(strncmp(first_line(path), "# A thin disk rolling", 21), 0);
  unlink(alias), unlink(path);
  /* A link to a file: the file gets the rows, the link stays. */
  snprintf(alias, sizeof alias, "%s/link.csv", ct_tmp);
  FILE *old = fopen(out, "w");
  if (old) fputs("old\n", old), fclose(old);
  AP_CHECK_EQ_INT(symlink("long.csv", alias), 0);
  const char *via[] = {ct_bin, "run", scene, "--quiet", "--t-end", "0.1", "--out", alias, NULL};
  AP_CHECK_EQ_INT(ct_run(via), 0);
  struct stat st;
  AP_CHECK(lstat(alias, &st) == 0 && S_ISLNK(st.st_mode));
  AP_CHECK_EQ_INT(strncmp(first_line(out), "t,disk.x,", 9), 0);
  AP_CHECK(ct_record_has(alias, "\"status\": \"ok\""));   /* beside the name given */
  ct_remove_run(alias), unlink(out);
  /* A link to a device, and a FIFO: written in place. (/dev/zero rather than /dev/null,
   * which other programs on a shared machine use: its identity is checked before and after.) */
  struct stat dev;
  AP_CHECK(stat("/dev/zero", &dev) == 0 && S_ISCHR(dev.st_mode));
  AP_CHECK_EQ_INT(symlink("/dev/zero", alias), 0);
  AP_CHECK_EQ_INT(ct_run(via), 0);
  AP_CHECK(lstat(alias, &st) == 0 && S_ISLNK(st.st_mode) && stat("/dev/zero", &st) == 0 &&
           S_ISCHR(st.st_mode) && st.st_ino == dev.st_ino && st.st_rdev == dev.st_rdev);
  unlink(alias);
  AP_CHECK_EQ_INT(mkfifo(alias, 0600), 0);
  int fd = open(alias, O_RDONLY | O_NONBLOCK);
  AP_CHECK_EQ_INT(ct_run(via), 0);
  char buf[16] = "";
  AP_CHECK(fd >= 0 && read(fd, buf, 9) == 9 && strncmp(buf, "t,disk.x,", 9) == 0);
  AP_CHECK(lstat(alias, &st) == 0 && S_ISFIFO(st.st_mode));
  if (fd >= 0) close(fd);
  unlink(alias);
  AP_CHECK_EQ_INT(files_like("link.csv"), 0);
}

/* appell linearize --csv to a FIFO is written in place (the eigenvalue table reaches the
 * reader), and to a link to a regular file through the link: its temporary file renamed over
 * the target replaced the FIFO (and, run as root, /dev/null or /dev/full) with a regular
 * file, and the link with a file. */
static void test_linearize_targets(void) {
  char disk[1200], fifo[1300], file[1300], link[1300];
  ct_source(disk, sizeof disk, "examples/scenes", "rolling_disk.yaml");
  snprintf(fifo, sizeof fifo, "%s/eig.fifo", ct_tmp);
  snprintf(file, sizeof file, "%s/eig.csv", ct_tmp);
  snprintf(link, sizeof link, "%s/eig-link.csv", ct_tmp);
  AP_CHECK_EQ_INT(mkfifo(fifo, 0600), 0);
  int fd = open(fifo, O_RDONLY | O_NONBLOCK);
  const char *to_fifo[] = {ct_bin, "linearize", disk, "--csv", fifo, NULL};
  AP_CHECK_EQ_INT(ct_run(to_fifo), 0);
  char buf[32] = "";
  AP_CHECK(fd >= 0 && read(fd, buf, 17) == 17 && strncmp(buf, "index,re,im,rcond", 17) == 0);
  struct stat st;
  AP_CHECK(lstat(fifo, &st) == 0 && S_ISFIFO(st.st_mode));
  if (fd >= 0) close(fd);
  unlink(fifo);
  FILE *old = fopen(file, "w");
  if (old) fputs("old\n", old), fclose(old);
  AP_CHECK_EQ_INT(symlink("eig.csv", link), 0);
  const char *to_link[] = {ct_bin, "linearize", disk, "--csv", link, NULL};
  AP_CHECK_EQ_INT(ct_run(to_link), 0);
  AP_CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode));
  AP_CHECK_EQ_INT(strncmp(first_line(file), "index,re,im,", 12), 0);
  unlink(link), unlink(file);
}

static void set_umask(void *user) { umask((mode_t)(size_t)user); }

static void test_full_and_modes(void) {
  const char *to_stdout[] = {ct_bin, "run", scene, "--quiet", "--t-end", "0.1", NULL};
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(to_stdout, "/dev/full", NULL, NULL)), 1);
  AP_CHECK(ct_log_has("writing standard output failed: No space left on device"));
  char hoffmann[1200];
  ct_source(hoffmann, sizeof hoffmann, "examples/scenes", "hoffmann.yaml");
  const char *check[] = {ct_bin, "check", hoffmann, NULL};
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(check, "/dev/full", NULL, NULL)), 1);
  AP_CHECK(ct_log_has("appell: writing standard output failed: No space left on device"));
  char link[1300];
  snprintf(link, sizeof link, "%s/full.csv", ct_tmp);
  AP_CHECK_EQ_INT(symlink("/dev/full", link), 0);
  const char *to_full[] = {ct_bin, "run", scene, "--quiet", "--t-end", "0.1", "--out", link,
                           NULL};
  AP_CHECK_EQ_INT(ct_run(to_full), 1);
  AP_CHECK(ct_log_has("No space left on device"));
  unlink(link);
  const char *argv[] = {ct_bin, "run", scene, "--quiet", "--t-end", "0.1", "--out", out, NULL};
  struct stat st;
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, NULL, set_umask, (void *)(size_t)022)), 0);
  AP_CHECK(stat(out, &st) == 0 && (st.st_mode & 0777) == 0644);
  chmod(out, 0640);   /* a file that exists keeps its permissions */
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, NULL, set_umask, (void *)(size_t)0)), 0);
  AP_CHECK(stat(out, &st) == 0 && (st.st_mode & 0777) == 0640);
  ct_remove_run(out);
  AP_CHECK_EQ_INT(ct_wait(ct_spawn(argv, NULL, set_umask, (void *)(size_t)077)), 0);
  AP_CHECK(stat(out, &st) == 0 && (st.st_mode & 0777) == 0600);
  ct_remove_run(out);
}

int main(void) {
  if (ct_init("test_cli_output") != 0) return 1;
  ct_source(scene, sizeof scene, "examples/scenes", "rolling_disk.yaml");
  snprintf(out, sizeof out, "%s/long.csv", ct_tmp);
  test_targets();
  test_full_and_modes();
  test_linearize_targets();
  test_signals();
  ct_finish();
  return ap_check_finish("test_cli_output");
}
