/* Appell: writing an output file without ever leaving a partial one, and without replacing
 * what must not be replaced. The rules of `appell run --out` (docs/cli.md "Output files and
 * signals"), in one place for every program that writes files: the appell command (CSV
 * tables, run records, sweep tables) and the Python package (appell.Table.to_csv).
 *
 *   target                          what happens
 *   a new file, an existing         written to a temporary file PATH.appell-tmp.PID.XXXXXX
 *   regular file                    beside it, renamed over PATH by ap_out_finish(keep = 1);
 *                                   removed by ap_out_finish(keep = 0) or a failure
 *   a symbolic link                 followed: to a regular file, the file it names is
 *                                   replaced as above (the link stays a link); to a FIFO or
 *                                   a device, written in place; to nothing: refused
 *   a FIFO or a device              written in place (never replaced: /dev/null stays a
 *                                   device, run as root too)
 *   a directory, a missing          refused (AP_ERR_ARG, err = EISDIR or ENOENT)
 *   directory
 *   one of the `keep` files (an     refused (AP_ERR_ARG, err = EEXIST); compared by device
 *   input such as the scene)        and inode, so through another name or a hard link too
 *
 * A new file gets the permissions 0666 minus the umask; a replaced file keeps its own.
 * Temporary files of earlier writers to the same PATH that were killed (SIGKILL) are removed
 * by ap_out_open when the process named in them no longer exists and the file is a regular
 * file of this user (o->note says so).
 *
 * Nothing here installs a signal handler or prints: a program that catches signals unlinks
 * o->tmp itself (the name is complete before the file exists, and "" when there is none).
 * Failures return AP_ERR_ARG (the target is refused) or AP_ERR_IO (a file could not be made,
 * written, closed or renamed), with o->err the errno value and msg naming the path. */
#ifndef APPELL_OUTFILE_H
#define APPELL_OUTFILE_H

#include <stddef.h>

#include "appell/export.h"
#include "appell/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AP_OUT_PATH_MAX 4096

typedef enum ap_out_kind {
  AP_OUT_FILE = 1,         /* a regular file (new or existing): temporary file + rename */
  AP_OUT_DIRECT = 2        /* a FIFO or a device (through a link too): written in place */
} ap_out_kind;

typedef struct ap_outfile {
  ap_out_kind kind;                  /* set by ap_out_check */
  char path[AP_OUT_PATH_MAX];        /* the file written: the target, a link to a regular
                                        file resolved to the file it names */
  char tmp[AP_OUT_PATH_MAX + 64];    /* AP_OUT_FILE, from ap_out_open to ap_out_finish: the
                                        temporary file; "" otherwise */
  unsigned mode;                     /* permission bits a new file gets */
  int fd;                            /* from ap_out_open: the descriptor to write; -1 */
  int err;                           /* errno of the last failure; 0 */
  char note[AP_OUT_PATH_MAX + 200];  /* what ap_out_open cleaned up ("" when nothing) */
} ap_outfile;

/* Decide where target goes, before anything is computed: fills *o (fd = -1). keep lists
 * nkeep files that must not be overwritten (NULL entries are skipped; keep may be NULL when
 * nkeep = 0). AP_ERR_ARG with a message "TARGET: is a directory; name a file" (and the like)
 * when refused or when an argument is NULL. */
AP_API int ap_out_check(ap_outfile *o, const char *target, const char *const *keep, int nkeep,
                        char *msg, size_t msg_len);
/* Open the file checked by ap_out_check: o->fd is then the descriptor to write (the
 * temporary file, or the FIFO or device). AP_ERR_IO when it cannot be created or opened. */
AP_API int ap_out_open(ap_outfile *o, char *msg, size_t msg_len);
/* Finish: close o->fd unless it is -1 (a caller that wrapped it in a FILE and closed that sets
 * o->fd = -1 first); then, for AP_OUT_FILE, rename the temporary file over o->path when keep
 * is non-zero, else remove it. AP_ERR_IO when the close or the rename fails (the temporary
 * file is removed then). o->tmp is "" afterwards. */
AP_API int ap_out_finish(ap_outfile *o, int keep, char *msg, size_t msg_len);
/* All of it for len bytes of data: check, open, write, finish. On any failure nothing is
 * left behind (no temporary file; a regular file at target is unchanged); *err (may be NULL)
 * gets the errno value. */
AP_API int ap_out_write_file(const char *target, const void *data, size_t len,
                             const char *const *keep, int nkeep, int *err, char *msg,
                             size_t msg_len);

#ifdef __cplusplus
}
#endif
#endif
