/* The generated code's shared object: cached by the hash of its source under the user's cache
 * directory, compiled by the system C compiler when missing or invalid, loaded with dlopen.
 *
 * Cache: $XDG_CACHE_HOME/appell, else $HOME/.cache/appell (created 0700, and used only when
 * it is a directory owned by the user and not writable by others), one file
 * model-<hash>.so per model (FNV-1a 64 of the source and the compiler flags). A cached file
 * is used only when it is a regular file owned by the user, dlopen takes it, and its
 * apc_hash matches; otherwise it is rebuilt. Writes are atomic: the compiler writes a file
 * named after the process, a per-process sequence number and the hash, renamed over the final
 * name when complete.
 * The compiler (`cc`, or $APPELL_CC) runs by posix_spawnp with an argument vector, never a
 * shell; its output goes to /dev/null (the notice says that it failed and how). */
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "codegen/codegen.h"

extern char **environ;

#define CG_FLAGS "-O1 -fPIC -shared -ffp-contract=off -fno-fast-math"

static uint64_t fnv1a(const char *s, uint64_t h) {
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
  return h;
}

/* The cache directory into dir (created 0700 when missing). */
static int cache_dir(char *dir, size_t len, char *why, size_t wlen) {
  const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
  int n;
  if (xdg && xdg[0] == '/') n = snprintf(dir, len, "%s/appell", xdg);
  else if (home && home[0] == '/') n = snprintf(dir, len, "%s/.cache/appell", home);
  else return snprintf(why, wlen, "no cache directory (neither XDG_CACHE_HOME nor HOME set)"), -1;
  if (n < 0 || (size_t)n >= len) return snprintf(why, wlen, "cache directory name too long"), -1;
  if (mkdir(dir, 0700) != 0 && errno == ENOENT) {   /* ~/.cache itself may be missing */
    char parent[4096];
    snprintf(parent, sizeof parent, "%.*s", (int)(strrchr(dir, '/') - dir), dir);
    if (mkdir(parent, 0700) == 0 || errno == EEXIST) (void)mkdir(dir, 0700);
  }
  struct stat st;
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
    return snprintf(why, wlen, "cannot create the cache directory %s", dir), -1;
  if (st.st_uid != geteuid() || (st.st_mode & 0022))
    return snprintf(why, wlen, "the cache directory %s is not owned by the user or is writable "
                    "by others", dir), -1;
  return 0;
}

/* dlopen path when it is a regular file owned by the user, with the expected hash. */
static int try_open(const char *path, const char *hash, cg_lib *out) {
  struct stat st;
  if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != geteuid() ||
      (st.st_mode & 0022))
    return -1;
  void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!h) return -1;
  const char *got = dlsym(h, "apc_hash");
  out->position = (cg_pos_fn)(uintptr_t)dlsym(h, "apc_position");
  out->velocity = (cg_vel_fn)(uintptr_t)dlsym(h, "apc_velocity");
  out->acceleration = (cg_acc_fn)(uintptr_t)dlsym(h, "apc_acceleration");
  out->finite_pos = (cg_finite_fn)(uintptr_t)dlsym(h, "apc_finite_pos");
  out->finite_vel = (cg_finite_fn)(uintptr_t)dlsym(h, "apc_finite_vel");
  out->basis = (cg_basis_fn)(uintptr_t)dlsym(h, "apc_basis");   /* optional */
  out->particular = (cg_part_fn)(uintptr_t)dlsym(h, "apc_particular");
  if (!got || strcmp(got, hash) != 0 || !out->position || !out->velocity ||
      !out->acceleration || !out->finite_pos || !out->finite_vel ||
      !out->basis != !out->particular) {
    dlclose(h);
    return -1;
  }
  out->handle = h;
  return 0;
}

static int write_file(const char *path, const char *text) {
  int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW, 0600);
  if (fd < 0) return -1;
  size_t len = strlen(text), done = 0;
  while (done < len) {
    ssize_t w = write(fd, text + done, len - done);
    if (w <= 0) break;
    done += (size_t)w;
  }
  return close(fd) == 0 && done == len ? 0 : -1;
}

/* Run the compiler on src into so; 0, or -1 with the reason. */
static int run_cc(const char *src, const char *so, char *why, size_t len) {
  const char *cc = getenv("APPELL_CC");
  if (!cc || !cc[0]) cc = "cc";
  char *argv[] = {(char *)cc, "-O1", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math",
                  "-o", (char *)so, (char *)src, "-lm", NULL};
  posix_spawn_file_actions_t fa;
  if (posix_spawn_file_actions_init(&fa) != 0) return snprintf(why, len, "out of memory"), -1;
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid;
  int rc = posix_spawnp(&pid, cc, &fa, NULL, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    return snprintf(why, len, "no C compiler '%s' on PATH (%s)", cc, strerror(rc)), -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return snprintf(why, len, "waiting for '%s' failed", cc), -1;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    return snprintf(why, len, "no C compiler '%s' on PATH", cc), -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return snprintf(why, len, "the C compiler '%s' failed (status %d)", cc,
                    WIFEXITED(status) ? WEXITSTATUS(status) : -1), -1;
  return 0;
}

int cg_load(const char *src, cg_lib *out, char *why, size_t len) {
  memset(out, 0, sizeof *out);
  char dir[4096], hash[32], path[4200], tmp_c[4300], tmp_so[4300];
  snprintf(hash, sizeof hash, "%016llx",
           (unsigned long long)fnv1a(CG_FLAGS, fnv1a(src, 14695981039346656037ULL)));
  if (cache_dir(dir, sizeof dir, why, len) != 0) return -1;
  snprintf(path, sizeof path, "%s/model-%s.so", dir, hash);
  if (try_open(path, hash, out) == 0) return out->from_cache = 1, 0;
  static _Atomic unsigned seq;   /* threads of one process compile under their own names */
  unsigned me = seq++;
  snprintf(tmp_c, sizeof tmp_c, "%s/tmp-%ld-%u-%s.c", dir, (long)getpid(), me, hash);
  snprintf(tmp_so, sizeof tmp_so, "%s/tmp-%ld-%u-%s.so", dir, (long)getpid(), me, hash);
  size_t n = strlen(src) + 128;
  char *text = malloc(n);
  if (!text) return snprintf(why, len, "out of memory"), -1;
  snprintf(text, n, "%sconst char apc_hash[] = \"%s\";\n", src, hash);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  int rc = write_file(tmp_c, text);
  free(text);
  if (rc != 0) snprintf(why, len, "cannot write %s", tmp_c);
  else rc = run_cc(tmp_c, tmp_so, why, len);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  unlink(tmp_c);
  if (rc == 0 && rename(tmp_so, path) != 0) {
    snprintf(why, len, "cannot rename into %s", path);
    rc = -1;
  }
  if (rc != 0) {
    unlink(tmp_so);
    return -1;
  }
  out->ms_compile =
      (double)(t1.tv_sec - t0.tv_sec) * 1e3 + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-6;
  if (try_open(path, hash, out) != 0)
    return snprintf(why, len, "the compiled %s does not load", path), -1;
  return 0;
}
