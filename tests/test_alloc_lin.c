/* Allocation failures in the linearizer's eigenvalue solve (ap_lin_eigen): LAPACKE_dgeevx
 * allocates its workspace itself, and an allocation failure there was reported as "the QR
 * algorithm did not converge" (AP_ERR_SINGULAR). Each allocation ap_lin_eigen makes on the
 * heavy top (examples/scenes/heavy_top.yaml, its linearize: section) fails in turn in a child
 * process (tests/alloc.h): every call must end in AP_OK (the allocation was not needed) or
 * AP_ERR_NOMEM with a message about memory, never another status or a crash. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "alloc.h"
#include "appell/appell.h"
#include "check.h"

static ap_lin *L;

/* 0: AP_OK or AP_ERR_NOMEM about memory; 3: another outcome (printed). */
static int one(long i) {
  ap_alloc_fail_at(i);
  int rc = ap_lin_eigen(L, NULL, 0, 1);
  ap_alloc_fail_at(-1);
  if (rc == AP_OK || (rc == AP_ERR_NOMEM && strstr(ap_lin_message(L), "memory"))) return 0;
  printf("allocation %ld: status %d: %s\n", i, rc, ap_lin_message(L));
  fflush(stdout);
  return 3;
}

int main(int argc, char **argv) {
  char path[4096];
  snprintf(path, sizeof path, "%s/examples/scenes/heavy_top.yaml", argc > 1 ? argv[1] : ".");
  ap_scene_lin_guess g;
  char msg[1024];
  int rc = ap_scene_lin_guess_load(path, NULL, 0, NULL, 0, &g, msg, sizeof msg);
  if (rc != AP_OK) printf("%s\n", msg);
  AP_CHECK_EQ_INT(rc, AP_OK);
  ap_lin_def def = ap_scene_lin_def(&g);
  if (rc == AP_OK) rc = ap_scene_lin_create(&g, &def, &L);
  AP_CHECK_EQ_INT(rc, AP_OK);
  if (rc == AP_OK) rc = ap_lin_operating_point(L, g.speed);
  if (rc == AP_OK) rc = ap_lin_linearize(L);
  if (rc != AP_OK) printf("%s\n", ap_lin_message(L));
  AP_CHECK_EQ_INT(rc, AP_OK);
  long n0 = n_alloc;
  AP_CHECK_EQ_INT(ap_lin_eigen(L, NULL, 0, 1), AP_OK);
  long count = n_alloc - n0, nomem_or_ok = 0, other = 0, crash = 0;
  AP_CHECK(count >= 2);   /* at least dgeevx's work and iwork */
  for (long i = 0; i < count; i++) {
    fflush(stdout);
    pid_t pid = fork();
    if (pid == 0) _exit(one(i));
    int st = 0;
    waitpid(pid, &st, 0);
    if (WIFEXITED(st) && WEXITSTATUS(st) == 0) nomem_or_ok++;
    else if (WIFEXITED(st) && WEXITSTATUS(st) == 3) other++;
    else crash++;
  }
  printf("ap_lin_eigen: %ld allocations failed one at a time: %ld AP_OK or AP_ERR_NOMEM, %ld "
         "other, %ld crashed\n", count, nomem_or_ok, other, crash);
  AP_CHECK_EQ_INT(other, 0);
  AP_CHECK_EQ_INT(crash, 0);
  ap_lin_free(L);
  ap_scene_lin_guess_free(&g);
  return ap_check_finish("alloc_lin");
}
