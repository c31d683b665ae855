/* Helpers of the tests that run the appell binary (tests/clitest.h). */
#include "clitest.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

char ct_src[1024], ct_bin[1024], ct_tmp[64], ct_log[1200];

void ct_find_source(char *out, size_t len) {
  const char *env = getenv("APPELL_SOURCE_DIR");
  snprintf(out, len, "%s", env ? env : __FILE__);
  if (env) return;
  char *slash = strrchr(out, '/');
  if (slash) *slash = '\0', slash = strrchr(out, '/');
  if (slash) *slash = '\0';
  else snprintf(out, len, ".");
}

int ct_init(const char *test) {
  ct_find_source(ct_src, sizeof ct_src);
  const char *env = getenv("APPELL_BIN");
  snprintf(ct_bin, sizeof ct_bin, "%s", env ? env : "tools/appell");
  snprintf(ct_tmp, sizeof ct_tmp, "/tmp/appell_cli_XXXXXX");
  if (!mkdtemp(ct_tmp) || access(ct_bin, X_OK) != 0) {
    fprintf(stderr, "%s: no binary at %s (run from the build directory)\n", test, ct_bin);
    return 1;
  }
  snprintf(ct_log, sizeof ct_log, "%s/log.txt", ct_tmp);
  return 0;
}

void ct_finish(void) {
  unlink(ct_log);
  rmdir(ct_tmp);
}

void ct_source(char *out, size_t len, const char *dir, const char *name) {
  snprintf(out, len, "%s/%s/%s", ct_src, dir, name);
}

pid_t ct_spawn(const char *const *argv, const char *out_file, ct_setup_fn setup, void *user) {
  pid_t pid = fork();
  if (pid == 0) {
    int fd = open(ct_log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) dup2(fd, 1), dup2(fd, 2), close(fd);
    if (out_file && (fd = open(out_file, O_WRONLY)) >= 0) dup2(fd, 1), close(fd);
    if (setup) setup(user);
    execv(argv[0], (char *const *)argv);
    _exit(126);
  }
  return pid;
}

int ct_wait(pid_t pid) {
  int st = 0;
  if (pid < 0 || waitpid(pid, &st, 0) < 0) return -1;
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

int ct_run(const char *const *argv) { return ct_wait(ct_spawn(argv, NULL, NULL, NULL)); }

int ct_file_has(const char *path, const char *what) {
  static char buf[1 << 16];
  FILE *f = fopen(path, "r");
  size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[n] = '\0';
  return f && strstr(buf, what) != NULL;
}

int ct_log_has(const char *what) { return ct_file_has(ct_log, what); }

int ct_record_has(const char *csv, const char *what) {
  char path[1300];
  snprintf(path, sizeof path, "%s.run.json", csv);
  return ct_file_has(path, what);
}

void ct_remove_run(const char *csv) {
  char path[1300];
  snprintf(path, sizeof path, "%s.run.json", csv);
  unlink(csv);
  unlink(path);
}
