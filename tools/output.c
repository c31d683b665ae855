/* appell run: where the CSV goes, and what a signal does to it (docs/cli.md, "Output files and
 * signals").
 *
 * The target is checked before anything is simulated: standard output ("-" or no --out), a
 * FIFO or a device (a symbolic link is followed) are written in place; a directory, a dangling
 * link or the scene file itself (same device and inode, whatever the name) are refused; a
 * regular file (new, or an existing one, through a link too) is written as a temporary file
 * beside it, named FILE.appell-tmp.PID.XXXXXX, and renamed over it after the last row. The
 * new file gets the permissions of the file it replaces, or 0666 minus the umask.
 *
 * Signals: every signal whose default action ends the process and that can be caught gets a
 * handler through sigaction (never reset on delivery). The first one of those that arrive
 * asynchronously (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGXFSZ, ...) is recorded, the run
 * stops at the next internal step (cli_interrupted, polled by the library through
 * ap_sim_set_poll) and removes its temporary file; a second one removes the temporary file at
 * once and exits 128 + the signal (repeats of SIGXFSZ and SIGPIPE, which failed writes raise,
 * do not count: the failed write is reported instead). A fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP,
 * SIGSYS) removes the temporary file and re-raises with the handler that was there before.
 * SIGKILL cannot be caught: its temporary file stays, and the next run to the same target
 * removes it when the process named in it no longer exists (and the file is a regular file
 * of this user). Invariant: a file at the target path is always complete. */
#define _XOPEN_SOURCE 700   /* realpath */

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"

#define TMP_TAG ".appell-tmp."

/* ---- signals ------------------------------------------------------------------------------ */

static volatile sig_atomic_t caught = 0;    /* the first terminating signal, or 0 */
static volatile sig_atomic_t armed = 0;     /* cleanup_path names a file to remove */
static char cleanup_path[sizeof ((cli_out *)0)->tmp];
static struct sigaction previous[65];       /* the actions replaced for faults */

/* SIGXFSZ and SIGPIPE come from our own writes, once per failed write (a file size limit, a
 * reader gone): the failed write is reported, and their repeats do not count as a second
 * signal. */
static int from_writes(int sig) {
#ifdef SIGXFSZ
  if (sig == SIGXFSZ) return 1;
#endif
  return sig == SIGPIPE;
}

static void on_signal(int sig) {
  if (caught && !from_writes(sig) && !from_writes(caught)) {
    if (armed) unlink(cleanup_path);   /* the second one: do not wait for the run to notice */
    _exit(128 + sig);
  }
  if (!caught) caught = sig;
}

static void on_fault(int sig) {
  if (armed) unlink(cleanup_path);
  if (sig > 0 && sig < 65) sigaction(sig, &previous[sig], NULL);
  raise(sig);   /* delivered when this handler returns, with the previous action */
}

static const int async_signals[] = {
    SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGPIPE, SIGALRM, SIGUSR1, SIGUSR2,
#ifdef SIGXCPU
    SIGXCPU,
#endif
#ifdef SIGXFSZ
    SIGXFSZ,
#endif
#ifdef SIGVTALRM
    SIGVTALRM,
#endif
#ifdef SIGPROF
    SIGPROF,
#endif
#ifdef SIGPOLL
    SIGPOLL,
#endif
#ifdef SIGSTKFLT
    SIGSTKFLT,
#endif
#ifdef SIGPWR
    SIGPWR,
#endif
};

static const int fault_signals[] = {
    SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT,
#ifdef SIGTRAP
    SIGTRAP,
#endif
#ifdef SIGSYS
    SIGSYS,
#endif
};

void cli_signals_install(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sigfillset(&sa.sa_mask);   /* one handler at a time */
  sa.sa_flags = SA_RESTART;  /* a write to a slow reader goes on; the run stops at its poll */
  sa.sa_handler = on_signal;
  for (size_t i = 0; i < sizeof async_signals / sizeof async_signals[0]; i++)
    sigaction(async_signals[i], &sa, NULL);
#if defined(SIGRTMIN) && defined(SIGRTMAX)
  for (int s = SIGRTMIN; s <= SIGRTMAX; s++) sigaction(s, &sa, NULL);
#endif
  sa.sa_flags = 0;
  sa.sa_handler = on_fault;
  for (size_t i = 0; i < sizeof fault_signals / sizeof fault_signals[0]; i++)
    if (fault_signals[i] < 65) sigaction(fault_signals[i], &sa, &previous[fault_signals[i]]);
}

int cli_interrupted(void) { return caught; }

const char *cli_signal_name(int sig) {
  static const struct {
    int sig;
    const char *name;
  } names[] = {{SIGHUP, "SIGHUP"},   {SIGINT, "SIGINT"},   {SIGQUIT, "SIGQUIT"},
               {SIGTERM, "SIGTERM"}, {SIGPIPE, "SIGPIPE"}, {SIGALRM, "SIGALRM"},
               {SIGUSR1, "SIGUSR1"}, {SIGUSR2, "SIGUSR2"},
#ifdef SIGXCPU
               {SIGXCPU, "SIGXCPU"},
#endif
#ifdef SIGXFSZ
               {SIGXFSZ, "SIGXFSZ"},
#endif
  };
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
    if (names[i].sig == sig) return names[i].name;
  static char other[32];
  snprintf(other, sizeof other, "signal %d", sig);
  return other;
}

/* ---- the target --------------------------------------------------------------------------- */

static int fail(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/* The subcommand named in messages (appell sweep writes its table through these too). */
static const char *command = "run";

void cli_out_command(const char *name) { command = name; }

static int fail(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "appell %s: ", command);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
  return EXIT_INPUT;
}

/* The directory part of path ("." when there is none). */
static void dir_of(const char *path, char *dir, size_t len) {
  const char *slash = strrchr(path, '/');
  if (!slash) snprintf(dir, len, ".");
  else if (slash == path) snprintf(dir, len, "/");
  else snprintf(dir, len, "%.*s", (int)(slash - path), path);
}

int cli_out_check(cli_out *o, const char *target, const char *scene) {
  memset(o, 0, sizeof *o);
  mode_t mask = umask(0);
  umask(mask);
  o->mode = 0666 & ~mask;
  if (!target || strcmp(target, "-") == 0) return o->kind = CLI_OUT_STDOUT, EXIT_OK;
  o->target = target;
  struct stat st, sc;
  if (strlen(target) >= PATH_MAX) return fail("--out %s: the path is too long", target);
  snprintf(o->path, sizeof o->path, "%s", target);
  if (lstat(target, &st) != 0) {
    char dir[PATH_MAX];
    dir_of(target, dir, sizeof dir);
    if (errno != ENOENT || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
      return fail("--out %s: %s", target, errno == ENOENT ? "its directory does not exist"
                                                           : strerror(errno));
    return o->kind = CLI_OUT_FILE, EXIT_OK;
  }
  int link = S_ISLNK(st.st_mode);
  if (link && stat(target, &st) != 0)
    return fail("--out %s: a symbolic link to a file that cannot be reached (%s)", target,
                strerror(errno));
  if (S_ISDIR(st.st_mode)) return fail("--out %s: is a directory; name a file", target);
  if (scene && stat(scene, &sc) == 0 && sc.st_dev == st.st_dev && sc.st_ino == st.st_ino)
    return fail("--out %s: is the scene file %s; refusing to overwrite it", target, scene);
  if (!S_ISREG(st.st_mode)) return o->kind = CLI_OUT_DIRECT, EXIT_OK;
  if (link && !realpath(target, o->path))
    return fail("--out %s: cannot resolve the link: %s", target, strerror(errno));
  o->mode = st.st_mode & 07777;
  return o->kind = CLI_OUT_FILE, EXIT_OK;
}

/* Remove temporary files of earlier runs to the same path whose process is gone. */
static void remove_stale(const cli_out *o) {
  char dir[PATH_MAX], file[PATH_MAX + 300];
  dir_of(o->path, dir, sizeof dir);
  const char *base = strrchr(o->path, '/') ? strrchr(o->path, '/') + 1 : o->path;
  size_t blen = strlen(base), tlen = strlen(TMP_TAG);
  DIR *d = opendir(dir);
  for (struct dirent *e; d && (e = readdir(d));) {
    const char *n = e->d_name, *p = n + blen + tlen;
    if (strncmp(n, base, blen) != 0 || strncmp(n + blen, TMP_TAG, tlen) != 0) continue;
    char *end = NULL;
    long pid = strtol(p, &end, 10);
    if (end == p || pid <= 0 || *end != '.' || strlen(end + 1) != 6 || pid == (long)getpid())
      continue;
    if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;   /* alive, or not ours to ask */
    struct stat st;
    snprintf(file, sizeof file, "%s/%s", dir, n);
    if (lstat(file, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != geteuid()) continue;
    if (unlink(file) == 0)
      fprintf(stderr, "appell %s: removed %s, left by an earlier run (process %ld) that was "
              "killed\n", command, file, pid);
  }
  if (d) closedir(d);
}

int cli_out_open(cli_out *o) {
  if (o->kind == CLI_OUT_STDOUT) return o->f = stdout, EXIT_OK;
  if (o->kind == CLI_OUT_DIRECT) {
    int fd = open(o->path, O_WRONLY | O_NOCTTY);
    o->f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!o->f) {
      if (fd >= 0) close(fd);
      return fail("cannot open %s for writing: %s", o->path, strerror(errno)), EXIT_INTERNAL;
    }
    return EXIT_OK;
  }
  remove_stale(o);
  int n = snprintf(o->tmp, sizeof o->tmp, "%s" TMP_TAG "%ld.XXXXXX", o->path, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof o->tmp) return fail("--out %s: path too long", o->target);
  memcpy(cleanup_path, o->tmp, (size_t)n + 1);
  armed = 1;
  int fd = mkstemp(cleanup_path);   /* the name is complete before the file exists */
  memcpy(o->tmp, cleanup_path, (size_t)n + 1);
  o->f = fd >= 0 && fchmod(fd, o->mode) == 0 ? fdopen(fd, "w") : NULL;
  if (!o->f) {
    int err = errno;
    if (fd >= 0) close(fd), unlink(o->tmp);
    armed = 0;
    return fail("cannot create %s: %s", o->tmp, strerror(err)), EXIT_INTERNAL;
  }
  return EXIT_OK;
}

const char *cli_out_name(const cli_out *o) {
  return o->kind == CLI_OUT_STDOUT ? "standard output" : o->path;
}

int cli_out_failed(cli_out *o) {
  if (!o->err && o->f && ferror(o->f)) o->err = errno ? errno : EIO;
  return o->err;
}

int cli_out_close(cli_out *o, int code) {
  if (!o->f) return code;
  cli_out_failed(o);
  int rc = o->kind == CLI_OUT_STDOUT ? fflush(stdout) : fclose(o->f);
  if (rc != 0 && !o->err) o->err = errno ? errno : EIO;
  o->f = NULL;
  if (o->kind == CLI_OUT_STDOUT) clearerr(stdout);   /* reported here, not again at exit */
  if (o->err && o->err != EPIPE)
    fprintf(stderr, "appell %s: writing %s failed: %s%s\n", command, cli_out_name(o), strerror(o->err),
            o->kind == CLI_OUT_FILE ? " (the partial file is removed)" : "");
  if (o->err && code == EXIT_OK) code = o->err == EPIPE ? 128 + SIGPIPE : EXIT_INTERNAL;
  if (o->kind != CLI_OUT_FILE) return code;
  if (code == EXIT_OK && rename(o->tmp, o->path) != 0) {
    fprintf(stderr, "appell %s: cannot rename %s to %s: %s\n", command, o->tmp, o->path,
            strerror(errno));
    code = EXIT_INTERNAL;
  }
  if (code != EXIT_OK) unlink(o->tmp);
  armed = 0;
  return code;
}
