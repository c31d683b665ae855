/* Helpers of the tests that run the appell binary as a user would (test_scene_cli,
 * test_cli_output): where the binary and the sources are, a scratch directory, and running a
 * child with its standard output and error in a log file.
 *
 * Meson runs tests in the build root, so the binary is tools/appell there ($APPELL_BIN
 * overrides) and the sources are found from __FILE__ ($APPELL_SOURCE_DIR overrides). */
#ifndef AP_TESTS_CLITEST_H
#define AP_TESTS_CLITEST_H

#include <stddef.h>
#include <sys/types.h>

extern char ct_src[1024];   /* the source tree */
extern char ct_bin[1024];   /* the appell binary */
extern char ct_tmp[64];     /* a scratch directory of this run */
extern char ct_log[1200];   /* the children's stdout and stderr */

/* The source tree into out: $APPELL_SOURCE_DIR, else two levels up from this file's __FILE__
 * (tests/clitest.c), else ".". For tests that read example scenes without running the binary. */
void ct_find_source(char *out, size_t len);
/* Find the binary and the sources, make the scratch directory; 0 on success. */
int ct_init(const char *test);
/* Remove the log and the scratch directory (which must be empty by then). */
void ct_finish(void);
/* A path in the source tree: SRC/dir/name. */
void ct_source(char *out, size_t len, const char *dir, const char *name);

/* Start argv with stdout and stderr into the log (stdout into out_file when not NULL); setup
 * runs in the child before exec (umask, limits). */
typedef void (*ct_setup_fn)(void *user);
pid_t ct_spawn(const char *const *argv, const char *out_file, ct_setup_fn setup, void *user);
/* Wait for pid: its exit code, or 128 + the signal that killed it; -1 on error. */
int ct_wait(pid_t pid);
/* ct_spawn + ct_wait. */
int ct_run(const char *const *argv);
/* Does the log contain what? Does the file at path (the first 64 kB)? */
int ct_log_has(const char *what);
int ct_file_has(const char *path, const char *what);
/* Does the run record of `appell run --out csv` (csv.run.json) contain what? */
int ct_record_has(const char *csv, const char *what);
/* Remove csv and its run record. */
void ct_remove_run(const char *csv);

#endif
