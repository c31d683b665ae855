/* The generated code's shared object: cached by the hash of its source under the user's cache
 * directory, compiled by the system C compiler when missing or invalid, loaded with dlopen.
 *
 * Cache: $XDG_CACHE_HOME/appell, else $HOME/.cache/appell (created 0700, and used only when
 * it is a directory owned by the user and not writable by others), one file
 * model-<hash>.so per model (FNV-1a 64 of the source, the compiler flags and the number of
 * units). A cached file is used only when it is a regular file owned by the user, dlopen takes
 * it, and its apc_hash matches; otherwise it is rebuilt. Writes are atomic: the compiler writes
 * files named after the process, a per-process sequence number and the hash; the shared object
 * is renamed over the final name when complete.
 * Compile: the source is split at its CG_TU_MARK lines into CG_MAX_TU translation units
 * (codegen.h), compiled side by side (cc -c, one process each) and linked into the shared
 * object; the compile time is that of the longest unit, about half the whole on two cores.
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
#if defined(__has_include)
#if __has_include(<gnu/lib-names.h>)
#include <gnu/lib-names.h>   /* LIBM_SO */
#endif
#endif

#include "codegen/codegen.h"

extern char **environ;

/* Compile (each unit, cc -c) and link flags. -ffp-contract=off: no fused multiply-adds (they
 * would change the roundings). The -fno-* passes of -O1 find nothing in code that the tracer
 * already folded, and cost the compiler about a tenth of its time; without them the generated
 * code is no longer (each was measured alone and all together: the instructions per evaluation
 * of the disk, robot and bicycle did not rise, docs/compiled.md). -nostdlib: the object needs no
 * start files and no C library of its own; its calls (sin, cos) resolve at dlopen from the
 * process's libm. A compiler that refuses the -fno-* flags (they are GCC's; clang stops on
 * some) gets a second run without them. */
static const char *const cflags[] = {"-O1", "-fPIC", "-ffp-contract=off", "-fno-fast-math",
                                     "-pipe", NULL};
static const char *const gcc_flags[] = {
    "-fno-tree-ccp", "-fno-tree-bit-ccp", "-fno-ssa-phiopt", "-fno-if-conversion",
    "-fno-forward-propagate", "-fno-split-wide-types", "-fno-tree-fre",
    "-fno-asynchronous-unwind-tables", "-fno-tree-dce", "-fno-tree-pta", "-fno-tree-slsr",
    "-fno-ipa-modref", "-fno-ipa-pure-const", "-fno-ipa-reference", "-fno-ipa-profile",
    "-fno-ipa-reference-addressable", "-fno-tree-ch", "-fno-tree-sra", "-fno-tree-copy-prop",
    "-fno-ssa-backprop", "-fno-tree-phiprop", "-fno-compare-elim", "-fno-tree-loop-optimize",
    NULL};
static const char *const ldflags[] = {"-shared", "-nostdlib", NULL};

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

/* The objects are linked without -lm (ld reading libm costs more than the rest of the link):
 * their calls to libm resolve in the global scope, which holds libm unless the library itself
 * was loaded RTLD_LOCAL (a Python extension); the already loaded libm is made global. */
static void libm_global(void) {
#ifdef LIBM_SO
  static _Atomic int done;
  if (!done++) (void)dlopen(LIBM_SO, RTLD_LAZY | RTLD_GLOBAL | RTLD_NOLOAD);
#endif
}

/* dlopen path when it is a regular file owned by the user, with the expected hash. */
static int try_open(const char *path, const char *hash, cg_lib *out) {
  struct stat st;
  if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != geteuid() ||
      (st.st_mode & 0022))
    return -1;
  libm_global();
  void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!h) return -1;
  const char *got = dlsym(h, "apc_hash");
  out->position = (cg_pos_fn)(uintptr_t)dlsym(h, "apc_position");
  out->velocity = (cg_vel_fn)(uintptr_t)dlsym(h, "apc_velocity");
  out->acceleration = (cg_acc_fn)(uintptr_t)dlsym(h, "apc_acceleration");
  cg_acc_fn part = (cg_acc_fn)(uintptr_t)dlsym(h, "apc_acc_part");   /* optional: the */
  if (part) out->acceleration = part;   /* expected partition's, calling the generic one */
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

/* Start argv (no shell), output to /dev/null; 0, or -1 with the reason. */
static int spawn(char *const argv[], pid_t *pid, char *why, size_t len) {
  posix_spawn_file_actions_t fa;
  if (posix_spawn_file_actions_init(&fa) != 0) return snprintf(why, len, "out of memory"), -1;
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  int rc = posix_spawnp(pid, argv[0], &fa, NULL, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    return snprintf(why, len, "no C compiler '%s' on PATH (%s)", argv[0], strerror(rc)), -1;
  return 0;
}

/* Wait for a compiler run; 0 when it succeeded, else -1 with the reason (when why is empty). */
static int reap(pid_t pid, const char *cc, char *why, size_t len) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return snprintf(why, len, "waiting for '%s' failed", cc), -1;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return 0;
  if (why[0]) return -1;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    return snprintf(why, len, "no C compiler '%s' on PATH", cc), -1;
  return snprintf(why, len, "the C compiler '%s' failed (status %d)", cc,
                  WIFEXITED(status) ? WEXITSTATUS(status) : -1), -1;
}

/* Append the NULL-terminated list to argv at a; the new count. */
static int push(char **argv, int a, const char *const *list) {
  for (int i = 0; list[i]; i++) argv[a++] = (char *)list[i];
  return a;
}

/* Compile the n units <stem>-<i>.c side by side (cc -c), then link their objects into so (one
 * unit: compiled and linked by one run); 0, or -1 with the reason. */
static int run_cc(const char *stem, int n, const char *so, int tuned, char *why, size_t len) {
  const char *cc = getenv("APPELL_CC");
  if (!cc || !cc[0]) cc = "cc";
  char src[CG_MAX_TU][4400], obj[CG_MAX_TU][4400], *argv[64] = {(char *)cc};
  pid_t pid[CG_MAX_TU];
  int started = 0, rc = 0;
  why[0] = '\0';
  for (int i = 0; i < n && rc == 0; i++) {
    snprintf(src[i], sizeof src[i], "%s-%d.c", stem, i);
    snprintf(obj[i], sizeof obj[i], "%s-%d.o", stem, i);
    const char *one[] = {"-o", so, src[i], NULL}, *part[] = {"-c", "-o", obj[i], src[i], NULL};
    int a = push(argv, 1, cflags);
    if (tuned) a = push(argv, a, gcc_flags);
    a = n == 1 ? push(argv, push(argv, a, ldflags), one) : push(argv, a, part);
    argv[a] = NULL;
    if ((rc = spawn(argv, &pid[i], why, len)) == 0) started++;
  }
  for (int i = 0; i < started; i++) rc |= reap(pid[i], cc, why, len);
  if (rc == 0 && n > 1) {
    const char *out[] = {"-o", so, NULL};
    int a = push(argv, push(argv, 1, ldflags), out);
    for (int i = 0; i < n; i++) argv[a++] = obj[i];
    argv[a] = NULL;
    pid_t p;
    if ((rc = spawn(argv, &p, why, len)) == 0) rc = reap(p, cc, why, len);
  }
  for (int i = 0; i < n && n > 1; i++) unlink(obj[i]);
  return rc;
}

/* The compiler's work on a piece, about: its statements, array accesses and arithmetic
 * operations. */
static size_t weight(const char *s, size_t n) {
  size_t w = 0;
  for (size_t i = 0; i < n; i++)
    w += s[i] == ';' || s[i] == '[' ||
         (i + 2 < n && s[i] == ' ' && strchr("+-*/", s[i + 1]) && s[i + 1] && s[i + 2] == ' ');
  return w;
}

/* The source split into at most CG_MAX_TU units at its CG_TU_MARK lines: each unit is the
 * prelude (the text before the first mark) and some of the pieces between the marks, in their
 * order, the pieces dealt heaviest first (statements) to the unit with the least work so far;
 * unit 0 also defines apc_hash. Returns the number of units (their texts malloc'ed into tu), or
 * -1. */
static int split_units(const char *src, const char *hash, char **tu) {
  size_t ml = strlen(CG_TU_MARK), start[256], end[256], w[256], load[CG_MAX_TU] = {0};
  size_t bytes[CG_MAX_TU] = {0};
  int np = 0, unit[256];
  const char *first = strstr(src, CG_TU_MARK), *p = first;
  size_t pre = first ? (size_t)(first - src) : strlen(src);
  while (p && np < 256) {
    const char *next = strstr(p + ml, CG_TU_MARK);
    start[np] = (size_t)(p + ml - src);
    end[np] = next ? (size_t)(next - src) : strlen(src);
    w[np] = weight(src + start[np], end[np] - start[np]);
    np++, p = next;
  }
  if (p) return -1;   /* more pieces than the table holds */
  int n = np < CG_MAX_TU ? (np ? np : 1) : CG_MAX_TU;
  for (int i = 0; i < np; i++) unit[i] = -1;
  for (int done = 0; done < np; done++) {   /* the largest piece not yet dealt */
    int big = -1;
    for (int i = 0; i < np; i++)
      if (unit[i] < 0 && (big < 0 || w[i] > w[big])) big = i;
    int to = 0;
    for (int u = 1; u < n; u++)
      if (load[u] < load[to]) to = u;
    unit[big] = to, load[to] += w[big], bytes[to] += end[big] - start[big];
  }
  for (int u = 0; u < n; u++) {
    size_t size = pre + bytes[u] + 128;
    char *t = tu[u] = malloc(size + 1);
    if (!t) {
      while (u-- > 0) free(tu[u]);
      return -1;
    }
    memcpy(t, src, pre);
    size_t at = pre;
    for (int i = 0; i < np; i++)
      if (unit[i] == u) memcpy(t + at, src + start[i], end[i] - start[i]), at += end[i] - start[i];
    if (u == 0) at += (size_t)snprintf(t + at, size - at, "const char apc_hash[] = \"%s\";\n", hash);
    t[at] = '\0';
  }
  return n;
}

/* The cache key: the source, the flags and the number of units. */
static uint64_t key(const char *src) {
  uint64_t h = fnv1a(src, 14695981039346656037ULL);
  for (int i = 0; cflags[i]; i++) h = fnv1a(cflags[i], h);
  for (int i = 0; gcc_flags[i]; i++) h = fnv1a(gcc_flags[i], h);
  for (int i = 0; ldflags[i]; i++) h = fnv1a(ldflags[i], h);
  return h * 1099511628211ULL + CG_MAX_TU;
}

int cg_load(const char *src, cg_lib *out, char *why, size_t len) {
  memset(out, 0, sizeof *out);
  char dir[4096], hash[32], path[4200], stem[4300], tmp_so[4400], name[CG_MAX_TU][4400];
  snprintf(hash, sizeof hash, "%016llx", (unsigned long long)key(src));
  if (cache_dir(dir, sizeof dir, why, len) != 0) return -1;
  snprintf(path, sizeof path, "%s/model-%s.so", dir, hash);
  if (try_open(path, hash, out) == 0) return out->from_cache = 1, 0;
  static _Atomic unsigned seq;   /* threads of one process compile under their own names */
  unsigned me = seq++;
  snprintf(stem, sizeof stem, "%s/tmp-%ld-%u-%s", dir, (long)getpid(), me, hash);
  snprintf(tmp_so, sizeof tmp_so, "%s.so", stem);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  char *tu[CG_MAX_TU];
  int n = split_units(src, hash, tu), rc = n > 0 ? 0 : -1;
  if (n <= 0) snprintf(why, len, "out of memory");
  for (int i = 0; i < n; i++) {
    snprintf(name[i], sizeof name[i], "%s-%d.c", stem, i);
    if (rc == 0 && write_file(name[i], tu[i]) != 0)
      rc = -1, snprintf(why, len, "cannot write %s", name[i]);
    free(tu[i]);
  }
  if (rc == 0) rc = run_cc(stem, n, tmp_so, 1, why, len);
  if (rc != 0 && strstr(why, "failed (status")) rc = run_cc(stem, n, tmp_so, 0, why, len);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  for (int i = 0; i < n; i++) unlink(name[i]);
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
