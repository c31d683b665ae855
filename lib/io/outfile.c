/* Output files that are complete or absent (include/appell/outfile.h, docs/cli.md "Output
 * files and signals").
 *
 * ap_out_check classifies the target once, before anything is computed (lstat, then stat
 * through a link); ap_out_open creates PATH.appell-tmp.PID.XXXXXX with mkstemp beside a
 * regular file (the name is written into o->tmp before the file exists, so a signal handler
 * that unlinks o->tmp never misses it) or opens a FIFO or device in place; ap_out_finish
 * renames the temporary file over PATH or removes it. Invariant: a file at PATH is always
 * complete; a FIFO, a device, a directory, a link or an input named in `keep` is never
 * replaced by a regular file. No signal handler, no printing, no global state. */
#define _XOPEN_SOURCE 700   /* realpath */

#include "appell/outfile.h"

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

#define TMP_TAG ".appell-tmp."

static int say(char *msg, size_t len, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int say(char *msg, size_t len, const char *fmt, ...) {
  if (msg && len) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, len, fmt, ap);
    va_end(ap);
  }
  return 0;
}

/* A refusal (AP_ERR_ARG) or an I/O failure (AP_ERR_IO) with errno value err. */
static int refuse(ap_outfile *o, int err, int status) {
  if (o) o->err = err;
  return status;
}

/* The directory part of path ("." when there is none). */
static void dir_of(const char *path, char *dir, size_t len) {
  const char *slash = strrchr(path, '/');
  if (!slash) snprintf(dir, len, ".");
  else if (slash == path) snprintf(dir, len, "/");
  else snprintf(dir, len, "%.*s", (int)(slash - path), path);
}

/* The first of keep[0 .. nkeep-1] that is the file st describes, or NULL. */
static const char *kept(const struct stat *st, const char *const *keep, int nkeep) {
  struct stat k;
  for (int i = 0; keep && i < nkeep; i++)
    if (keep[i] && stat(keep[i], &k) == 0 && k.st_dev == st->st_dev && k.st_ino == st->st_ino)
      return keep[i];
  return NULL;
}

/* A target that does not exist: its directory must. */
static int check_new(ap_outfile *o, const char *target, char *msg, size_t len) {
  char dir[AP_OUT_PATH_MAX];
  struct stat st;
  int err = errno;
  dir_of(target, dir, sizeof dir);
  if (err != ENOENT || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
    say(msg, len, "%s: %s", target, err == ENOENT ? "its directory does not exist"
                                                   : strerror(err));
    return refuse(o, err == ENOENT ? ENOENT : err, AP_ERR_ARG);
  }
  o->kind = AP_OUT_FILE;
  return AP_OK;
}

int ap_out_check(ap_outfile *o, const char *target, const char *const *keep, int nkeep,
                 char *msg, size_t len) {
  if (!o || !target || !target[0] || nkeep < 0 || (nkeep > 0 && !keep)) {
    say(msg, len, "ap_out_check: %s", !o ? "o is NULL" : !target || !target[0]
                                          ? "no file name" : "keep is NULL or nkeep < 0");
    return refuse(o, EINVAL, AP_ERR_ARG);
  }
  memset(o, 0, sizeof *o);
  o->fd = -1;
  mode_t mask = umask(0);
  umask(mask);
  o->mode = 0666 & ~(unsigned)mask;
  if (strlen(target) >= sizeof o->path)
    return say(msg, len, "%.200s...: the path is too long", target),
           refuse(o, ENAMETOOLONG, AP_ERR_ARG);
  snprintf(o->path, sizeof o->path, "%s", target);
  struct stat st;
  if (lstat(target, &st) != 0) return check_new(o, target, msg, len);
  int link = S_ISLNK(st.st_mode);
  if (link && stat(target, &st) != 0)
    return say(msg, len, "%s: a symbolic link to a file that cannot be reached (%s)", target,
               strerror(errno)), refuse(o, errno, AP_ERR_ARG);
  if (S_ISDIR(st.st_mode))
    return say(msg, len, "%s: is a directory; name a file", target),
           refuse(o, EISDIR, AP_ERR_ARG);
  const char *input = kept(&st, keep, nkeep);
  if (input)
    return say(msg, len, "%s: is the input file %s; refusing to overwrite it", target, input),
           refuse(o, EEXIST, AP_ERR_ARG);
  if (!S_ISREG(st.st_mode)) return o->kind = AP_OUT_DIRECT, AP_OK;
  char real[PATH_MAX];
  if (link && !realpath(target, real))
    return say(msg, len, "%s: cannot resolve the link: %s", target, strerror(errno)),
           refuse(o, errno, AP_ERR_ARG);
  if (link) snprintf(o->path, sizeof o->path, "%s", real);
  o->mode = (unsigned)st.st_mode & 07777;
  o->kind = AP_OUT_FILE;
  return AP_OK;
}

/* Remove temporary files of earlier writers to the same path whose process is gone. */
static void remove_stale(ap_outfile *o) {
  char dir[AP_OUT_PATH_MAX], file[AP_OUT_PATH_MAX + 300];
  dir_of(o->path, dir, sizeof dir);
  const char *base = strrchr(o->path, '/') ? strrchr(o->path, '/') + 1 : o->path;
  size_t blen = strlen(base), tlen = strlen(TMP_TAG), used = 0;
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
    if (unlink(file) != 0 || used >= sizeof o->note - 1) continue;
    int w = snprintf(o->note + used, sizeof o->note - used, "%sremoved %s, left by an earlier "
                     "run (process %ld) that was killed", used ? "; " : "", file, pid);
    used = w > 0 ? used + (size_t)w : used;
  }
  if (d) closedir(d);
}

int ap_out_open(ap_outfile *o, char *msg, size_t len) {
  if (!o || (o->kind != AP_OUT_FILE && o->kind != AP_OUT_DIRECT) || o->fd >= 0) {
    say(msg, len, "ap_out_open: %s", !o ? "o is NULL" : o->fd >= 0 ? "already open"
                                                                    : "not checked");
    return refuse(o, EINVAL, AP_ERR_ARG);
  }
  o->tmp[0] = '\0';
  if (o->kind == AP_OUT_DIRECT) {
    o->fd = open(o->path, O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (o->fd < 0)
      return say(msg, len, "cannot open %s for writing: %s", o->path, strerror(errno)),
             refuse(o, errno, AP_ERR_IO);
    return AP_OK;
  }
  remove_stale(o);
  char name[sizeof o->tmp];
  int n = snprintf(name, sizeof name, "%s" TMP_TAG "%ld.XXXXXX", o->path, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof name)
    return say(msg, len, "%s: the path is too long", o->path), refuse(o, ENAMETOOLONG, AP_ERR_IO);
  memcpy(o->tmp, name, (size_t)n + 1);
  int fd = mkstemp(o->tmp);   /* fills the name in o->tmp before the file exists */
  if (fd < 0 || fchmod(fd, (mode_t)o->mode) != 0) {
    int err = errno;
    if (fd >= 0) close(fd), unlink(o->tmp);
    say(msg, len, "cannot create %s: %s", fd >= 0 ? o->tmp : name, strerror(err));
    o->tmp[0] = '\0';
    return refuse(o, err, AP_ERR_IO);
  }
  o->fd = fd;
  return AP_OK;
}

int ap_out_finish(ap_outfile *o, int keep, char *msg, size_t len) {
  if (!o) return say(msg, len, "ap_out_finish: o is NULL"), AP_ERR_ARG;
  int rc = AP_OK;
  if (o->fd >= 0 && close(o->fd) != 0 && keep) {
    say(msg, len, "writing %s failed: %s", o->path, strerror(errno));
    rc = refuse(o, errno, AP_ERR_IO);
  }
  o->fd = -1;
  if (o->kind != AP_OUT_FILE || !o->tmp[0]) return rc;
  if (rc == AP_OK && keep && rename(o->tmp, o->path) != 0) {
    say(msg, len, "cannot rename %s to %s: %s", o->tmp, o->path, strerror(errno));
    rc = refuse(o, errno, AP_ERR_IO);
  }
  if (rc != AP_OK || !keep) unlink(o->tmp);
  o->tmp[0] = '\0';
  return rc;
}

/* Every byte of data to fd (retrying short writes and EINTR); 0, or the errno value. */
static int write_all(int fd, const char *data, size_t len) {
  while (len > 0) {
    ssize_t w = write(fd, data, len);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return w < 0 ? errno : EIO;
    data += w, len -= (size_t)w;
  }
  return 0;
}

int ap_out_write_file(const char *target, const void *data, size_t len,
                      const char *const *keep, int nkeep, int *err, char *msg, size_t msg_len) {
  ap_outfile *o = calloc(1, sizeof *o);
  if (err) *err = ENOMEM;
  if (!o) return say(msg, msg_len, "out of memory"), AP_ERR_NOMEM;
  int rc = !data && len ? (say(msg, msg_len, "ap_out_write_file: data is NULL"), AP_ERR_ARG)
                        : ap_out_check(o, target, keep, nkeep, msg, msg_len);
  if (rc == AP_OK) rc = ap_out_open(o, msg, msg_len);
  if (rc == AP_OK) {
    int e = write_all(o->fd, data, len);
    if (e) say(msg, msg_len, "writing %s failed: %s", o->path, strerror(e)), o->err = e;
    int fin = ap_out_finish(o, !e, e ? NULL : msg, msg_len);
    rc = e ? AP_ERR_IO : fin;
  }
  if (err) *err = rc == AP_OK ? 0 : o->err ? o->err : EINVAL;
  free(o);
  return rc;
}
