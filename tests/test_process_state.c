/* Process-wide state, system calls and size limits (issue 24, "other findings"):
 *   pool_nomem     the batch's worker thread cannot allocate its buffers: its runs say
 *                  AP_ERR_NOMEM and "out of memory" (never AP_BATCH_NOT_RUN, the mark of a
 *                  cancelled batch), and ap_batch_run returns AP_ERR_NOMEM, not
 *                  AP_BATCH_CANCELLED; each of the first allocations of a run fails in turn
 *   fstat_fails    fstat fails on an open scene file, leaving in its struct stat what garbage
 *                  could be there (a regular file of 12 MiB): the scene is read as a stream
 *                  (no allocation near 12 MiB from the unset st_size)
 *   errno_text     a file that cannot be opened: the message ends with the C library's text
 *                  for the errno (strerror_r, thread-safe)
 *   path_env_once  APPELL_PATH is read once, at the first body model compiled: a setenv after
 *                  it does not change the path of the next compile
 *   small_limit    the linalg small-size limit is per thread: moving it in one thread leaves
 *                  another's at its default
 *   names_cut      a scene file name longer than a model name: the name ends in "..."; the
 *                  text helpers cut with "..." (never inside a UTF-8 character) or not at all
 *   dense_limit    a body model on the dense path with k > 46340 speeds (k x k past INT_MAX,
 *                  what a 32-bit LAPACK integer indexes) is refused at compile with a message
 * malloc is interposed (tests/alloc.h) and so is fstat (below). */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "alloc.h"
#include "appell/appell.h"
#include "check.h"
#include "core/text.h"
#include "linalg/linalg.h"

/* ---- fstat, interposed ------------------------------------------------------------------- */

static int fstat_fails = 0;

/* With fstat_fails, fail with EIO after filling *st with a 12 MiB regular file: code that reads
 * st after a failed fstat sizes its buffer from that. */
int fstat(int fd, struct stat *st) {
  if (fstat_fails) {
    memset(st, 0, sizeof *st);
    st->st_mode = S_IFREG | 0644;
    st->st_size = 12 << 20;
    errno = EIO;
    return -1;
  }
  static int (*next)(int, struct stat *) = NULL;
  if (!next) next = (int (*)(int, struct stat *))dlsym(RTLD_NEXT, "fstat");
  return next ? next(fd, st) : (errno = ENOSYS, -1);
}

static const char SCENE[] =
    "name: slider\n"
    "bodies:\n"
    "  slider: {mass: 1, inertia: [0.1, 0.1, 0.1]}\n"
    "joints:\n"
    "  slider: {kind: prismatic, axis: z}\n"
    "effects:\n"
    "  gravity: {kind: gravity}\n"
    "initial:\n"
    "  slider: {position: 0.5}\n"
    "simulation: {t_end: 0.1}\n"
    "output: {interval: 0.05, channels: [coordinates]}\n";

/* ---- tests ---------------------------------------------------------------------------------- */

static void test_pool_nomem(void) {
#if defined(__SANITIZE_ADDRESS__)
  /* AddressSanitizer's thread start allocates (pthread_getattr_np) through the interposed
   * malloc and aborts when that fails: the normal build runs this test */
  printf("pool_nomem: skipped under AddressSanitizer\n");
  return;
#endif
  ap_batch_def def = ap_batch_def_default();
  def.threads = 1;
  ap_batch *b = NULL;
  char msg[512];
  AP_CHECK_EQ_INT(ap_batch_create(SCENE, strlen(SCENE), "slider", NULL, 0, &def, &b, msg,
                                  sizeof msg), AP_OK);
  if (!b) return;
  int nc = ap_batch_ncols(b), worker_nomem = 0, tried = 0;
  double *values = calloc((size_t)(2 * nc), sizeof *values);
  /* A batch first makes its workers' SUNDIALS contexts, kept for the runs after
   * (lib/integrate/sunctx.c; its failure, every row not run, is test_alloc's phase "first"):
   * one batch without failures makes them, so that the loop reaches the workers' buffers. */
  if (values) {
    int status[2];
    AP_CHECK_EQ_INT(ap_batch_run(b, 2, 0, NULL, values, status, NULL), AP_OK);
  }
  for (long i = 0; i < 48 && values; i++, tried++) {
    int status[2];
    char *messages[2] = {NULL, NULL};
    ap_alloc_failed = 0;
    ap_alloc_fail_at(i);
    int rc = ap_batch_run(b, 2, 0, NULL, values, status, messages);
    int failed = ap_alloc_failed;
    ap_alloc_fail_at(-1);
    AP_CHECK(rc != AP_BATCH_CANCELLED);   /* nothing cancelled this batch */
    for (int j = 0; j < 2; j++) {
      AP_CHECK(status[j] != AP_BATCH_NOT_RUN);
      AP_CHECK(status[j] == AP_OK || status[j] == AP_ERR_NOMEM);
      if (status[j] == AP_ERR_NOMEM && messages[j])
        AP_CHECK(strstr(messages[j], "out of memory") != NULL);
      if (messages[j] && strstr(messages[j], "batch worker")) {
        worker_nomem++;
        AP_CHECK_EQ_INT(rc, AP_ERR_NOMEM);
      }
    }
    ap_batch_messages_free(2, messages);
    if (!failed) break;   /* every allocation of the run has been failed once */
  }
  printf("pool_nomem: the first %d allocations of a batch run failed in turn; %d runs taken by "
         "a worker without its buffers, each reported out of memory\n", tried, worker_nomem);
  AP_CHECK(worker_nomem >= 2);   /* the worker's buffer path was reached */
  free(values);
  ap_batch_free(b);
}

static void test_fstat_fails(void) {
  char path[] = "/tmp/appell_fstat_XXXXXX";
  int fd = mkstemp(path);
  AP_CHECK(fd >= 0);
  if (fd < 0) return;
  AP_CHECK_EQ_INT(write(fd, SCENE, strlen(SCENE)), (long)strlen(SCENE));
  close(fd);
  ap_scene *sc = NULL;
  char msg[512] = "";
  fstat_fails = 1;
  ap_alloc_largest = 0;
  int rc = ap_scene_load(path, NULL, 0, &sc, msg, sizeof msg);
  fstat_fails = 0;
  printf("fstat_fails: the scene loaded with fstat failing; largest allocation %zu bytes\n",
         ap_alloc_largest);
  AP_CHECK(ap_alloc_largest < (1u << 20));
  if (rc != AP_OK) fprintf(stderr, "fstat_fails: %s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  AP_CHECK(sc && strcmp(ap_scene_name(sc), "slider") == 0);
  ap_scene_free(sc);
  unlink(path);
}

static void test_errno_text(void) {
  ap_scene *sc = NULL;
  char msg[512] = "";
  AP_CHECK_EQ_INT(ap_scene_load("/nonexistent/dir/x.yaml", NULL, 0, &sc, msg, sizeof msg),
                  AP_ERR_ARG);
  const char *want = strerror(ENOENT);   /* this thread alone: the reference */
  size_t lm = strlen(msg), lw = strlen(want);
  AP_CHECK(lm > lw && strcmp(msg + lm - lw, want) == 0);
  AP_CHECK(strstr(msg, "/nonexistent/dir/x.yaml: cannot open: ") == msg);
  ap_batch *b = NULL;
  AP_CHECK_EQ_INT(ap_batch_load("/nonexistent/dir/x.yaml", NULL, 0, NULL, &b, msg, sizeof msg),
                  AP_ERR_ARG);
  lm = strlen(msg);
  AP_CHECK(lm > lw && strcmp(msg + lm - lw, want) == 0);
}

static ap_model *one_revolute(ap_path path, int free_bodies) {
  ap_builder *b = NULL;
  ap_model *m = NULL;
  if (ap_builder_create("one", &b) != AP_OK) return NULL;
  ap_body_def d = ap_body_def_default();
  d.inertia[0] = d.inertia[4] = d.inertia[8] = 1.0;
  ap_joint_def j = ap_joint_def_default();
  j.kind = free_bodies ? AP_JOINT_FREE : AP_JOINT_REVOLUTE;
  int nb = free_bodies ? free_bodies : 1, rc = AP_OK;
  for (int i = 0; rc == AP_OK && i < nb; i++) {
    j.child = i;
    rc = ap_builder_add_body(b, &d, NULL);
    if (rc == AP_OK) rc = ap_builder_add_joint(b, &j, NULL);
  }
  ap_builder_set_path(b, path);
  rc = rc == AP_OK ? ap_builder_compile(b, &m) : rc;
  if (rc != AP_OK && free_bodies) {
    const char *why = ap_builder_message(b);
    printf("dense_limit: %d free bodies (k = %d) refused: %s\n", nb, 6 * nb, why);
    AP_CHECK(strstr(why, "32-bit LAPACK") && strstr(why, "k x k"));
  }
  ap_builder_free(b);
  return m;
}

static void test_path_env_once(void) {
  ap_model *m1 = one_revolute(AP_PATH_AUTO, 0);
  int p1 = m1 ? ap_model_path(m1) : -1;
  AP_CHECK(p1 == AP_PATH_DENSE || p1 == AP_PATH_TREE);
  setenv("APPELL_PATH", p1 == AP_PATH_DENSE ? "tree" : "dense", 1);   /* after the first */
  ap_model *m2 = one_revolute(AP_PATH_AUTO, 0);
  AP_CHECK_EQ_INT(m2 ? ap_model_path(m2) : -1, p1);
  unsetenv("APPELL_PATH");
  ap_model_free(m1), ap_model_free(m2);
}

static void *other_thread(void *arg) {
  int *seen = arg;
  seen[0] = ap_la_small_limit();
  seen[1] = ap_la_set_small_limit(0);
  seen[2] = ap_la_small_limit();
  return NULL;
}

static void test_small_limit(void) {
  int old = ap_la_set_small_limit(3), seen[3] = {-1, -1, -1};
  pthread_t t;
  AP_CHECK_EQ_INT(pthread_create(&t, NULL, other_thread, seen), 0);
  pthread_join(t, NULL);
  AP_CHECK_EQ_INT(seen[0], AP_LA_SMALL_LIMIT);   /* not this thread's 3 */
  AP_CHECK_EQ_INT(seen[1], AP_LA_SMALL_LIMIT);
  AP_CHECK_EQ_INT(seen[2], 0);
  AP_CHECK_EQ_INT(ap_la_small_limit(), 3);       /* not the other thread's 0 */
  ap_la_set_small_limit(old);
}

static void test_names_cut(void) {
  static const char body[] =
      "bodies:\n  p: {mass: 1, inertia: [1, 1, 1]}\njoints:\n  p: {kind: revolute}\n";
  char file[200];
  snprintf(file, sizeof file, "dir/%s.yaml",
           "a_scene_file_whose_name_is_much_longer_than_the_sixty_three_bytes_kept");
  ap_scene *sc = NULL;
  char msg[512];
  AP_CHECK_EQ_INT(ap_scene_load_string(body, strlen(body), file, NULL, 0, &sc, msg, sizeof msg),
                  AP_OK);
  const char *nm = sc ? ap_scene_name(sc) : "";
  size_t len = strlen(nm);
  AP_CHECK_EQ_INT(len, 63);
  AP_CHECK(len == 63 && strcmp(nm + 60, "...") == 0 && strncmp(nm, file + 4, 60) == 0);
  AP_CHECK(sc && strcmp(ap_model_name(ap_scene_model(sc)), nm) == 0);
  printf("names_cut: %s\n", nm);
  ap_scene_free(sc);
  char buf[8];
  AP_CHECK(ap_core_copy_name(buf, sizeof buf, "abcdefg") == 0 && strcmp(buf, "abcdefg") == 0);
  AP_CHECK(ap_core_copy_name(buf, sizeof buf, "abcdefgh") == 1 && strcmp(buf, "abcd...") == 0);
  AP_CHECK(ap_core_copy_name(buf, sizeof buf, "abc\xc3\xa9xyz") == 1 &&
           strcmp(buf, "abc...") == 0);   /* e-acute (2 bytes) not split */
  char m1[32] = "the message";
  ap_core_prefix(m1, sizeof m1, "dae mode: ");
  AP_CHECK(strcmp(m1, "dae mode: the message") == 0);
  char m2[16] = "a long message";
  ap_core_prefix(m2, sizeof m2, "dae mode: ");
  AP_CHECK(strcmp(m2, "dae mode: a ...") == 0 && strlen(m2) == 15);
}

static void test_dense_limit(void) {
  /* 7724 free bodies: k = 46344 > 46340 on the dense path; the tree path takes them */
  ap_model *m = one_revolute(AP_PATH_DENSE, 7724);
  AP_CHECK(m == NULL);
  ap_model_free(m);
  m = one_revolute(AP_PATH_TREE, 7724);
  AP_CHECK(m && ap_model_k(m) == 46344);
  ap_model_free(m);
}

int main(void) {
  test_path_env_once();   /* first: the first body model compiled reads APPELL_PATH */
  test_pool_nomem();
  test_fstat_fails();
  test_errno_text();
  test_small_limit();
  test_names_cut();
  test_dense_limit();
  return ap_check_finish("test_process_state");
}
